//! Parametric body models of the SMPL family — SMPL, SMPL-H, SMPL-X, MANO, FLAME — read
//! from their `.npz` or `.pkl` files, evaluated exactly as the official code does, and
//! sampled over shapes and poses as a stream of registered surfaces.
//!
//! References: Loper et al. 2015, "SMPL: A Skinned Multi-Person Linear Model" (the
//! evaluation, [`eval`]); Romero et al. 2017, "Embodied Hands" (MANO, SMPL+H); Pavlakos et
//! al. 2019, "Expressive Body Capture" (SMPL-X); Li et al. 2017, "Learning a model of
//! facial shape and expression from 4D scans" (FLAME).
//!
//! # The layout, per kind
//!
//! Every kind uses SMPL's keys; `V` vertices, `J` joints, `S` shape and `E` expression
//! components:
//!
//! | key | shape | meaning |
//! |---|---|---|
//! | `v_template` | `(V, 3)` | the mean shape in the zero pose |
//! | `f` | `(F, 3)` | triangles, vertex indices |
//! | `shapedirs` | `(V, 3, S)` — SMPL-X, FLAME: `(V, 3, S + E)` | shape (then expression) blend shapes |
//! | `posedirs` | `(V, 3, 9 (J − 1))` | pose correctives, by `vec(R_j − I)` of joints 1.. |
//! | `weights` | `(V, J)` | skinning weights |
//! | `kintree_table` | `(2, J)` | row 0: each joint's parent (joint 0 is the root, its entry ignored) |
//! | `J_regressor` | `(J, V)` | joints from vertices: dense in npz, a scipy CSC matrix in pkl |
//!
//! | kind | `J` | found by | `shapedirs` | also read |
//! |---|---|---|---|---|
//! | SMPL | 24 | 24 joints | all shape (10 in 1.0, 300 in 1.1) | |
//! | SMPL-H | 52 | 52 joints | all shape | `hands_meanl`, `hands_meanr` (45 each) |
//! | SMPL-X | 55 | 55 joints | 300 shape + the rest expression when wider than 300; 10 + 10 when 20 wide (1.0); else all shape | `hands_meanl`, `hands_meanr` |
//! | MANO | 16 | 16 joints | all shape (also accepted flattened, `(V·3·S,)`) | `hands_mean` |
//! | FLAME | 5 | 5 joints | 300 shape + the rest expression when wider than 300; else all shape | |
//!
//! In a `.pkl` (mostly Python 2 chumpy pickles) an array may be a chumpy `Ch` (its array
//! under `x` in its state), a `chumpy.reordering` object (`a` gathered at `idxs`, shaped by
//! `preferred_shape`) or a plain ndarray; desal-io's unpickler reads them without running
//! pickled code. Every other key (`J`, `bs_style`, `joint2num`, landmark arrays, …) is kept
//! in [`BodyModel::extras`] as it came — an npz entry's raw `.npy` bytes, a pickle's array
//! or value — so a writer can copy it unchanged.
//!
//! # Sampling ([`Sampler`])
//!
//! Sample 0 is the template: the mean shape in the zero pose (group 0). Then `shapes`
//! random shapes (groups 1..=shapes), each in `poses` random poses:
//! - **shape**: the first `shape_components` (default 10) betas ~ N(0, 1), each clipped to
//!   ±2.5 (`beta_clip`); the others zero;
//! - **pose**: per joint 1.., an axis-angle whose three components are ~ N(0, σ²): σ = 0.3
//!   rad for body joints, 0.2 for hand, jaw and eye joints ([`JointClass`]), or
//!   `pose_sigma` for all; added to the file's mean hand pose where it has one (as the
//!   official code does unless `flat_hand_mean`);
//! - **global rotation**: joint 0 turns about the up axis (`up`, default +Y) by an angle
//!   uniform in ±`max_turn` (default π), about the root joint;
//! - **expression** (SMPL-X, FLAME, when `expressions` is set): the first
//!   `expression_components` (default 10) coefficients ~ N(0, 1) per pose.
//!
//! The stream is deterministic for a `seed` (ChaCha8, `rand_distr`'s normal). Samples are
//! computed when asked for, up to 8 poses of a shape at a time ([`BodyModel::pose_batch`]
//! reads the pose correctives once for them, the same numbers as one by one); one shape's
//! rest surface is kept while its poses are made.
//!
//! # Part labels
//!
//! [`labels_from_weights`]: dominant joint per vertex, merged along the tree — smallest
//! surface first, mirror pairs together — to at most `target_parts` parts (16 gives
//! anatomical parts close to SCAPE's); the rule is in [`labels`].
//!
//! # A smaller model of the same format ([`subset_model`], [`BodyModel::to_npz`])
//!
//! For a simplification with subset placement (every kept vertex a model vertex):
//! [`subset_model`] keeps the per-vertex rows of the kept vertices, takes the new
//! triangles, solves `J_regressor` over the kept vertices so that the joints stay where
//! the full model puts them for every shape (and expression) its blend shapes span, and
//! moves SMPL-X's and FLAME's landmark embeddings onto the new triangles; every other key
//! is kept as it came (the rule is in [`mod@subset`]). [`BodyModel::to_npz`] writes a model
//! in its file's own keys, order and element types; a `.pkl` model comes out as an npz of
//! the same keys ([`mod@write`]).
//!
//! **Invariant:** no paths beyond the one file [`BodyModel::read`] is given; no pipeline,
//! cache or progress bar. Models are f64 throughout.

pub mod error;
pub mod eval;
pub mod labels;
pub mod model;
pub mod read;
pub mod sample;
pub mod subset;
pub mod write;

pub use error::BodyModelError;
pub use eval::{Params, PoseItem, Posed, Shaped, rodrigues};
pub use labels::{Skin, labels_from_skin, labels_from_weights};
pub use model::{BodyModel, ExtraEntry, FileLayout, JointClass, ModelKind, SparseRows};
pub use sample::{Sample, SampleConfig, Sampler};
pub use subset::{JointFit, LandmarkFit, SubsetConfig, SubsetReport, subset_model};
pub use write::NpzModel;
