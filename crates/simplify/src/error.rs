//! The one error type of stage 3. Every variant names the offending vertex (or count) so
//! the caller can point at the bad input.

use thiserror::Error;

/// Why a simplification could not start. Running out of valid collapses is *not* an
/// error: it is reported in [`crate::SimplifyReport::stop`].
#[derive(Debug, Clone, PartialEq, Error)]
pub enum SimplifyError {
    /// The mesh has no face (or no vertex); there is nothing to simplify.
    #[error("the mesh is empty ({vertices} vertices, {faces} faces)")]
    EmptyMesh { vertices: usize, faces: usize },
    /// A face refers to a vertex past the end of the position array.
    #[error("face {face} uses vertex {vertex}, but the mesh has only {vertex_count} vertices")]
    FaceIndexOutOfRange { face: usize, vertex: u32, vertex_count: usize },
    /// A vertex coordinate is NaN or infinite.
    #[error("vertex {vertex} has a non-finite coordinate")]
    NonFinitePosition { vertex: usize },
    /// The saliency weights are not one per vertex.
    #[error("{weights} saliency weights given for a mesh of {vertices} vertices (need one per vertex)")]
    WeightCountMismatch { weights: usize, vertices: usize },
    /// A saliency weight is negative, NaN or infinite.
    #[error("saliency weight of vertex {vertex} is {value}; weights must be finite and >= 0")]
    BadWeight { vertex: usize, value: f64 },
    /// The keep penalties are not one per vertex.
    #[error("{penalties} keep penalties given for a mesh of {vertices} vertices (need one per vertex)")]
    KeepPenaltyCountMismatch { penalties: usize, vertices: usize },
    /// A keep penalty is negative, NaN or infinite.
    #[error("keep penalty of vertex {vertex} is {value}; penalties must be finite and >= 0")]
    BadKeepPenalty { vertex: usize, value: f64 },
    /// The part labels are not one per vertex.
    #[error("{labels} part labels given for a mesh of {vertices} vertices (need one per vertex)")]
    LabelCountMismatch { labels: usize, vertices: usize },
    /// A seam edge names a vertex past the end of the position array.
    #[error("seam {seam} uses vertex {vertex}, but the mesh has only {vertex_count} vertices")]
    SeamIndexOutOfRange { seam: usize, vertex: u32, vertex_count: usize },
    /// A seam `[a, b]` is not an edge of the mesh (no face has both vertices, or `a == b`).
    #[error("seam {seam} ({a}, {b}) is not an edge of the mesh")]
    SeamNotAnEdge { seam: usize, a: u32, b: u32 },
    /// A ratio target outside `(0, 1]`.
    #[error("target ratio {ratio} is outside (0, 1]")]
    BadRatio { ratio: f64 },
    /// A configuration value outside its documented range.
    #[error("configuration field `{field}` = {value} is out of range: {expected}")]
    BadConfig { field: &'static str, value: f64, expected: &'static str },
}
