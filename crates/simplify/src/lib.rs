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

/// Compiles the hot functions it wraps twice: for baseline x86-64 and for x86-64-v3's
/// features (AVX2, FMA, BMI; the `-C target-cpu=x86-64-v3` set less what stable Rust
/// cannot name), the clone chosen at run time on the first call (`multiversion`; the
/// generated `unsafe` dispatch is that crate's macro's, which the workspace's
/// `unsafe_code` lint does not see into). What a wrapped function inlines is compiled
/// with the features; what it calls is not. Results are the baseline's bit for bit:
/// Rust never contracts `a * b + c` into an FMA, and wider vectors change no arithmetic,
/// only how many lanes one instruction does. The one list of targets for the crate.
macro_rules! with_avx2_clone {
    ($($item:item)*) => {
        $(
            #[multiversion::multiversion(targets("x86_64+avx2+fma+bmi1+bmi2+lzcnt+popcnt+movbe+f16c"))]
            $item
        )*
    };
}

mod api;
mod classify;
mod collapse;
mod config;
mod edges;
mod error;
mod face_lists;
mod lanes;
mod lindstrom_turk;
mod marks;
mod names;
mod placement;
pub mod quadric;
mod report;
mod safeguards;
mod seams;
mod sort;
mod surface;
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
