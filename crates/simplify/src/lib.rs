//! Stage 3: saliency-weighted quadric edge collapse (paper §3.1, Eq. 3–5; Garland and
//! Heckbert 1997), and Mohr and Gleicher's multi-pose QEM (2003) for comparison.
//!
//! Entry points: [`simplify`] (one mesh, optional per-vertex weights, part labels and
//! attribute seams, which survive as polylines: meshoptimizer's seam rules)
//! and [`simplify_multipose`] (a registered pose set). Both return a [`Simplified`]:
//! the mesh in the `simp_idx` space, `simp_to_orig` (for each `simp_idx`, the
//! `orig_idx` whose exact position it kept, if any) and a [`SimplifyReport`].
//!
//! The cost of collapsing edge `(v1, v2)` is `E = d · (w1 + w2)/2 · v̄ᵀ(Q1 + Q2)v̄`
//! (Eq. 5), each factor switchable in [`SimplifyConfig`]: without saliency and balance
//! it is plain QSlim. Safeguards (link condition, fold-over, degeneracy, frozen
//! non-manifold input vertices) are always on; a target they prevent is reported in
//! [`SimplifyReport::stop`], not raised as an error.

mod api;
mod classify;
mod collapse;
mod config;
mod error;
mod face_lists;
mod lindstrom_turk;
mod marks;
mod names;
mod placement;
pub mod quadric;
mod report;
mod safeguards;
mod seams;
mod types;

pub use api::{simplify, simplify_multipose, simplify_with_progress};
pub use config::{Metric, PartBorders, Placement, SimplifyConfig, Target};
pub use error::SimplifyError;
pub use report::{Refusals, SimplifyReport, StopReason};
pub use types::{Simplified, SimplifyInput};

/// Version of this stage's output. The driver's cache key carries it, so bump it in the
/// same commit as any change that alters the output for the same input and
/// [`SimplifyConfig`] (a cost, a safeguard, a tie-break, a placement rule); the golden
/// test `tests/golden.rs` fails until you do.
/// 2: the corner-normal fold guard (`max_corner_normal_deg`).
pub const VERSION: u32 = 2;
