//! Near-rigid body parts discovered from a registered pose set, for pose sets that come
//! without part labels (`labels = "auto"`): vertices that one rigid motion per pose
//! explains are a part.
//!
//! - [`discover_parts`] ([`discover`]): the one entry point — pose set and
//!   [`PartsConfig`] in, [`desal_mesh::PartLabels`] (vertex index space of the pose set)
//!   and a [`PartsReport`] out, with the residual-against-part-count curve whose knee
//!   picks the count when none is given. [`refine_parts`] relaxes the borders of given
//!   parts by the same rule.
//! - `hierarchy`: the template cut into patches and their bottom-up merges.
//! - `motion`: per-part rigid fits onto every pose (stage 1's Kabsch solver from
//!   `desal-fit`) and the per-vertex residual they are judged by.
//! - `graph`: the vertex graph parts must be connected on, and its components.
//! - `knee`: the knee of the curve. [`compare`]: the adjusted Rand index.
//!
//! **Dependencies:** `desal-mesh`, rayon, and — a deliberate exception to "stage crates
//! depend on desal-mesh only" — `desal-fit`, so that parts are fitted and judged by
//! exactly stage 1's solver and objective. No file, format or progress bar.

pub mod compare;
pub mod config;
pub mod discover;
pub mod error;
pub(crate) mod graph;
pub(crate) mod hierarchy;
pub(crate) mod knee;
pub(crate) mod motion;
pub mod report;

pub use compare::adjusted_rand_index;
pub use config::PartsConfig;
pub use discover::{discover_parts, refine_parts};
pub use error::PartsError;
pub use report::{CurvePoint, PartsReport};

/// Version of this stage's output (the discovered labels). The driver's cache key carries
/// it, so bump it in the same commit as any change that alters the labels for the same
/// pose set and config.
pub const VERSION: u32 = 1;
