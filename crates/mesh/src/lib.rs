//! Core in-memory types shared by every desal crate: triangle meshes, registered pose
//! sets, per-vertex part labels, adjacency and validation.
//!
//! Index spaces: every `u32` vertex index in this crate is an index into the mesh (or
//! pose set) it belongs to. Stage 4 is where two index spaces meet; it names them
//! `orig_idx` and `simp_idx`. Coordinates are `f64` in memory, in the units of the input
//! files (metres for SCAPE and the bundled sample).
//!
//! **Invariant:** this crate knows no file format, no path and no progress bar; it is
//! the one crate every stage depends on, so it stays small and dependency-light.

pub mod adjacency;
pub mod error;
pub mod labels;
pub mod math;
pub mod mesh;
pub mod pose_set;
pub mod progress;
pub mod validate;

pub use adjacency::{EdgeTopology, VertexFaces};
pub use error::MeshError;
pub use labels::PartLabels;
pub use math::{Mat3, Real, Vec3};
pub use mesh::{Face, LengthStats, TriMesh, edge_length_stats};
pub use pose_set::PoseSet;
pub use progress::{NoProgress, Progress};
pub use validate::{FaceCleanup, clean_faces, used_vertices};
