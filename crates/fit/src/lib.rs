//! Stage 1: per-part rigid fit of the template onto every pose (paper §3.1, Eq. 1–2).
//!
//! For every pose X and body part k, [`fit_pose_set`] finds the transform that best maps
//! the template's part-k vertices onto pose X's in the least-squares sense, and measures
//! each vertex's residual distance `‖R v_T + t − v_X‖` (in mesh units). Stage 2 turns
//! those residuals into deformation saliency.
//!
//! - [`align`]: the reusable solvers ([`kabsch`], [`affine_fit`]).
//! - [`fit`]: the stage orchestrator, its config and result types.
//! - [`summary`]: per-part and per-pose residual statistics, worst first.
//!
//! **Invariant:** this crate knows no file, no format and no progress bar; it takes a
//! [`desal_mesh::PoseSet`] and [`desal_mesh::PartLabels`] and returns plain data.

pub mod align;
pub mod error;
pub mod fit;
pub mod part_fit;
pub mod summary;

pub use align::{
    AffineTransform, PairMoments, RigidTransform, affine_fit, kabsch, solve_affine, solve_rigid,
};
pub use error::FitError;
pub use fit::{FitConfig, FitModel, FitResult, PartFit, fit_pose_set};
pub use summary::{FitSummary, PartSummary, PoseSummary};

/// Version of this stage's output. The driver's cache key carries it, so bump it in the
/// same commit as any change that alters the output for the same input and config; the
/// golden test `tests/golden.rs` fails until you do.
pub const VERSION: u32 = 1;
