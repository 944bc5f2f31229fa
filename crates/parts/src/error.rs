//! The error type of part discovery. Variants name the offending option, part or vertex
//! count, so the driver can say what to change.

use thiserror::Error;

/// Why parts could not be discovered.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PartsError {
    /// A configuration value is outside its documented range.
    #[error("parts option `{option}` = {value} is out of range: {expected}")]
    BadOption { option: &'static str, value: f64, expected: &'static str },

    /// No connected piece of the mesh is large enough to be a part.
    #[error(
        "the mesh has {vertices} vertices in its largest connected piece, fewer than `min_part_vertices` = {min_part_vertices}; lower `min_part_vertices` or give labels"
    )]
    MeshTooSmall { vertices: usize, min_part_vertices: usize },

    /// A discovered part cannot carry a rigid fit (fewer than three vertices, or all
    /// collinear in the template or in some pose). Discovery dissolves such parts into
    /// a neighbour, so this means a connected piece of the mesh is itself degenerate.
    #[error(
        "discovered part {part} ({vertices} vertices) does not span a plane in every pose; a rigid fit needs 3 non-collinear vertices per part: the mesh has a degenerate connected piece"
    )]
    DegeneratePart { part: u32, vertices: usize },
}
