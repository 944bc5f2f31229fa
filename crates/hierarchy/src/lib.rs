//! Multi-level hierarchies of a registered pose set, in the layout body-reconstruction
//! networks load (COMA's `mesh_sampling.py`, GraphCMR's `mesh_downsampling.npz`): per
//! level step k → k+1 a selection D (`n_{k+1} × n_k`), an upsampler U (`n_k × n_{k+1}`)
//! and the coarse level's adjacency A.
//!
//! - [`build_level`]: one step, from the fine level's pose set, the coarse level's
//!   vertices as fine vertices (`coarse_to_fine`, i.e. `map{k+1}`) and faces, a training
//!   mask over poses and an [`Upsampler`]. Call it once per level; [`nest`] composes the
//!   maps into `orig{k+1}` (indices into level 0).
//! - [`Upsampler::Barycentric`] ([`barycentric`]): COMA's rule, the template pose only.
//! - [`Upsampler::Fitted`] ([`fitted`]): rows fitted by least squares over the training
//!   poses, affine (sum to 1), ridge toward the barycentric row.
//! - [`upsampling_error`] ([`measure`]): the composed U applied to the level-k ground
//!   truth against the full-resolution pose, mean squared vertex distance and v2f, m².
//! - [`CsrMatrix`] ([`sparse`]): the matrices, with a row-major COO export.
//!
//! Index spaces: `fine_idx` / `coarse_idx` within one step; `orig_idx` for level 0.
//! Units: the pose set's (metres for SCAPE); errors in squared units (m²).
//!
//! **Dependencies:** desal-mesh, plus — the one exception among stage crates —
//! desal-eval, for its BVH, exact closest point on a triangle and v2f, so that the
//! barycentric projection and the upsampling error use the same geometry as `desal eval`.
//! No file formats here: `desal-io::npz` writes `hierarchy.npz`.
//!
//! ## Choices, measured on SCAPE (levels [2500, 625], subset placement)
//!
//! `cargo run --release -p desal-hierarchy --example scape_upsampling [-- --tune]`.
//! The fitted upsampler's defaults (16 geodesic neighbours, relative ridge 3e-3) were
//! chosen without the odd poses: fitted on poses ≡ 0 (mod 4), validated on poses ≡ 2
//! (mod 4) of the paper's hierarchy. Held-out MSE ratio fitted / barycentric at 2500 |
//! at 625 composed, for geodesic candidates:
//!
//! | k \ ridge | 0 | 1e-3 | 3e-3 | 1e-2 | 3e-2 |
//! |---|---|---|---|---|---|
//! | 8 | 0.569 \| 0.343 | 0.549 \| 0.338 | 0.544 \| 0.344 | 0.556 \| 0.366 | 0.585 \| 0.406 |
//! | 12 | 0.581 \| 0.331 | 0.535 \| 0.315 | 0.524 \| 0.318 | 0.536 \| 0.336 | 0.563 \| 0.367 |
//! | 16 | 0.626 \| 0.344 | 0.537 \| 0.310 | **0.521 \| 0.311** | 0.531 \| 0.326 | 0.555 \| 0.352 |
//! | 24 | 0.774 \| 0.413 | 0.549 \| 0.311 | 0.525 \| 0.308 | 0.529 \| 0.319 | 0.549 \| 0.338 |
//! | 32 | 1.037 \| 0.575 | 0.561 \| 0.316 | 0.531 \| 0.311 | 0.532 \| 0.319 | 0.548 \| 0.334 |
//!
//! Without a ridge, many neighbours overfit (k = 32: worse than barycentric); with
//! it, k from 16 to 32 is a plateau and 16 is the cheapest point on it. Euclidean
//! candidates are within 0.003 of geodesic ones (k = 16, ridge 3e-3: 0.524 | 0.313); geodesic
//! is the default because it never reaches across a gap to another body part.
//!
//! With those defaults, fitted on the 36 even poses and measured on the 35 odd ones,
//! MSE fitted / barycentric is 0.481 at 2500 and 0.283 at 625 (composed) for the
//! paper's hierarchy (qslim's: 0.481, 0.295), and the paper's hierarchy with the fitted
//! U is 53.5 % below COMA's recipe (qslim + barycentric) at 2500 (71.1 % at 625).
//! Saliency for level 2 is recomputed on level 1's pose set rather than carried down
//! from level 0: with the fitted U it gives 10.73e-6 against 10.78e-6 m² at 625 (with the
//! barycentric U the order flips, 37.9e-6 against 37.2e-6), a small margin either way.
//!
//! Deterministic: rows are solved in parallel and collected in order; nearest-face and
//! nearest-vertex ties go to the lower index; the same input gives the same matrices
//! whatever the thread count.

pub mod barycentric;
pub mod error;
pub mod fitted;
mod geodesic;
mod knn;
pub mod level;
pub mod measure;
pub mod sparse;

pub use error::HierarchyError;
pub use fitted::{DEFAULT_NEIGHBOURS, DEFAULT_RIDGE, FitCounts, FittedConfig, Neighbourhood};
pub use level::{Level, LevelInput, LevelReport, Upsampler, adjacency, build_level, nest, selection};
pub use measure::{PoseError, UpsamplingError, upsampling_error, upsampling_mse};
pub use sparse::{Coo, CsrMatrix};
