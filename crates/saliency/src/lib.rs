//! Stage 2: per-vertex deformation saliency from the stage-1 fit residuals (paper §3.1).
//!
//! A vertex is salient when the rigid motion of its body part does not explain where it
//! goes: its saliency is the sum, over the poses, of its residual distance after the
//! per-part fit, normalised to `[0, 1]` ("normalize the total error", §3.1). Stage 3
//! weights edge-collapse costs with [`Saliency::weights`], which adds a floor so that a
//! perfectly rigid vertex is never free to collapse.
//!
//! - [`saliency`]: the config, the orchestrator [`compute_saliency`] and its result.
//! - [`error`]: the error type, [`SaliencyError`].
//!
//! **Invariant:** this crate does not depend on `desal-fit`: it reads the residual table
//! through the borrowed view [`ResidualTable`], so the two stages stay independent.

pub mod error;
pub mod saliency;

pub use error::SaliencyError;
pub use saliency::{
    DEFAULT_WEIGHT_FLOOR, Distance, Normalisation, ResidualTable, Saliency, SaliencyConfig, SaliencyReport,
    compute_saliency, weight,
};

/// Version of this stage's output. The driver's cache key carries it, so bump it in the
/// same commit as any change that alters the output for the same input and config; the
/// golden test `tests/golden.rs` fails until you do.
pub const VERSION: u32 = 1;
