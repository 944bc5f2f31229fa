//! The error type of stage 4. Variants name the offending simplified vertex (`simp_idx`),
//! original vertex (`orig_idx`) or simplified face, so the caller can say what to fix.

use desal_mesh::MeshError;
use thiserror::Error;

/// What is wrong with the inputs of a mapping or of applying a map.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MapError {
    /// The greedy mapping pairs every simplified vertex with a *distinct* original vertex,
    /// so it needs at least as many original vertices as simplified ones. Usually the
    /// simplified template and the pose set belong to different meshes.
    #[error(
        "the simplified template has {simplified} vertices but the original template only {original}; a one-to-one mapping needs at least as many original vertices"
    )]
    TooFewOriginalVertices { simplified: usize, original: usize },

    /// A simplified vertex has a NaN or infinite coordinate.
    #[error("simplified vertex {simp_idx} has a non-finite coordinate ({x}, {y}, {z})")]
    NonFiniteSimplified { simp_idx: u32, x: f64, y: f64, z: f64 },

    /// An original vertex has a NaN or infinite coordinate.
    #[error("original vertex {orig_idx} has a non-finite coordinate ({x}, {y}, {z})")]
    NonFiniteOriginal { orig_idx: u32, x: f64, y: f64, z: f64 },

    /// More vertices than `u32` indices can name.
    #[error("{count} vertices do not fit 32-bit vertex indices")]
    TooManyVertices { count: usize },

    /// A map entry names an original vertex that does not exist: the map was made for
    /// another mesh.
    #[error(
        "simplified vertex {simp_idx} maps to original vertex {orig_idx}, but the original mesh has only {original_count} vertices"
    )]
    OrigIndexOutOfRange { simp_idx: u32, orig_idx: u32, original_count: usize },

    /// Two simplified vertices map to the same original vertex, so the map is not
    /// one-to-one (a subset simplification kept a vertex twice, or the map is corrupt).
    #[error(
        "simplified vertices {first_simp_idx} and {second_simp_idx} both map to original vertex {orig_idx}; the map must be one-to-one"
    )]
    DuplicateOrigIndex { orig_idx: u32, first_simp_idx: u32, second_simp_idx: u32 },

    /// A simplified triangle names a simplified vertex the map does not cover.
    #[error(
        "simplified face {face} references simplified vertex {simp_idx}, but the map covers only {simplified_count} vertices"
    )]
    FaceIndexOutOfRange { face: usize, simp_idx: u32, simplified_count: usize },

    /// The simplified template's positions and the map disagree on the vertex count.
    #[error("the simplified template has {positions} vertices but the map has {map} entries")]
    MapLengthMismatch { positions: usize, map: usize },

    /// The pose set or labels are inconsistent, or the simplified pose set is empty.
    #[error(transparent)]
    Mesh(#[from] MeshError),
}
