//! The error type of the renderer.

use thiserror::Error;

/// Why an image could not be rendered or encoded.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum VizError {
    /// The scalar field does not have one value per vertex (or per face).
    #[error("the {kind} scalar has {found} values but the mesh has {expected} {kind}s")]
    ScalarLength { kind: &'static str, expected: usize, found: usize },

    /// The mesh has no vertices or no faces: nothing to draw.
    #[error("cannot render an empty mesh ({vertices} vertices, {faces} faces)")]
    EmptyMesh { vertices: usize, faces: usize },

    /// The configured up and front directions are the same axis.
    #[error("the up direction {up:?} and the front direction {front:?} must be different axes")]
    ParallelAxes { up: crate::direction::Direction, front: crate::direction::Direction },

    /// A view size is zero or too large to allocate sensibly.
    #[error("view size {width} x {height} pixels is out of range (1..=8192 each)")]
    BadSize { width: u32, height: u32 },

    /// A line plot has no point it can draw (all non-finite, or y ≤ 0 on a log axis).
    #[error("nothing to plot: the {series} series have no finite point (y must be > 0 on a log axis)")]
    EmptyPlot { series: usize },

    /// The PNG encoder failed (should not happen for an in-memory image).
    #[error("PNG encoding failed: {0}")]
    Png(String),
}
