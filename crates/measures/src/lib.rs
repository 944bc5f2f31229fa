//! The paper's experiment (§4): SCAPE pose deformation of a (simplified or full) pose
//! set, and the v2f / v2v errors that measure it.
//!
//! - [`metrics`]: v2f (Eq. 6) and v2v (Eq. 7), their halves and per-vertex arrays, in
//!   squared input units (m² for SCAPE), exact distances through a BVH.
//! - [`fit_model`] / [`Model::synthesize`]: the SCAPE pose-deformation model (Anguelov et
//!   al. 2005) fitted on a registered pose set with per-pose part rotations (stage 1's
//!   fit), then driven by part rotations alone; built from [`skeleton`] (parts, joints,
//!   twists), [`gradient`] (deformation gradients) and [`poisson`] (sparse
//!   reconstruction).
//!   Placement by the centroid or, by default, part-anchored ([`Anchoring`]); ridge
//!   fixed or chosen by leave-one-out cross-validation ([`ridge`]).
//! - [`fit_lbs`] / [`LbsModel::synthesize`]: the second deformation model, linear blend
//!   skinning with the parts as bones ([`lbs`]).
//! - [`PoseModel`] / [`FittedModel`]: one interface over both, driven by the parts' rigid
//!   motions ([`PartTransform`], stage 1's fit); [`model_floor`] measures either model's
//!   own error in-sample and held out ([`floor`]).
//! - [`folds()`]: k-fold splits over poses for held-out evaluation.
//! - [`deform`]: the models by name (`desal eval --model`, [`deform::MODELS`]) and a
//!   whole pose set deformed by one, in-sample and per fold, driven by stage 1's fit
//!   (desal-fit): what `desal-refit` and `desal eval` share.
//!
//! **Invariant:** like every stage crate, this one knows no file, path or progress bar:
//! it takes meshes, labels and rotations, and returns positions and numbers. The method
//! comparison, tables and figures live in desal-experiment (`desal eval`).

mod bvh;
pub mod closest_point;
pub mod deform;
pub mod error;
pub mod floor;
pub mod folds;
pub mod gradient;
mod grid;
pub mod lbs;
pub mod metrics;
pub mod model;
pub mod poisson;
pub mod pose_model;
pub mod ridge;
pub mod skeleton;
pub mod transform;

/// A BLAKE3 hash of this crate's source (`build.rs`): `desal eval` caches the model's
/// floor under it, so a change to any model or metric measures the floor again.
pub const SOURCE: &str = env!("DESAL_EVAL_SOURCE");

pub use error::EvalError;
pub use floor::{MeanErrors, ModelFloor, model_floor, model_floor_indexed};
pub use folds::{folds, group_folds, pose_set_folds, tested_poses, training_poses};
pub use lbs::{LbsConfig, LbsModel, LbsReport, fit_lbs};
pub use metrics::{
    SurfaceIndex, V2fHalves, VertexErrors, VertexIndex, v2f, v2f_halves, v2f_halves_both_indexed,
    v2f_halves_indexed, v2f_halves_same_faces, v2v, vertex_errors, vertex_faces,
};
pub use model::{Anchoring, DEFAULT_ANCHOR_SCALE, Model, ModelConfig, ModelReport, Regression, fit_model};
pub use poisson::{AnchoredPoissonSolver, PoissonSolver};
pub use pose_model::{FittedModel, PoseModel};
pub use ridge::JointFeatures;
pub use skeleton::{Joint, Skeleton};
pub use transform::{PartTransform, rotations_of};
