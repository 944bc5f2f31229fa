//! `HierarchyError`: every way building a level or measuring it can fail, with the
//! offending vertex, face, pose or matrix shape.

use thiserror::Error;

#[derive(Debug, Error)]
pub enum HierarchyError {
    /// A coarse vertex names a fine vertex that does not exist.
    #[error(
        "coarse vertex {coarse_idx} maps to fine vertex {fine_idx}, but the fine level has {fine_count} vertices"
    )]
    MapOutOfRange { coarse_idx: usize, fine_idx: u32, fine_count: usize },

    /// Two coarse vertices name the same fine vertex: a selection needs distinct ones.
    #[error("coarse vertices {first} and {second} both map to fine vertex {fine_idx}")]
    MapRepeated { first: usize, second: usize, fine_idx: u32 },

    /// A coarse face names a vertex past the coarse vertex count.
    #[error("coarse face {face} names vertex {vertex}, but the coarse level has {coarse_count} vertices")]
    FaceOutOfRange { face: usize, vertex: u32, coarse_count: usize },

    /// The coarse level has no vertex or no face, so nothing can be upsampled from it.
    #[error("the coarse level has {vertices} vertices and {faces} faces; it needs at least one of each")]
    EmptyCoarse { vertices: usize, faces: usize },

    /// The training mask does not have one entry per pose.
    #[error("the training mask has {mask} entries but the pose set has {poses} poses")]
    MaskLength { mask: usize, poses: usize },

    /// No pose is marked for training.
    #[error("no pose is marked for training (the fitted upsampler needs at least one)")]
    NoTrainingPose,

    /// An upsampler option is out of range.
    #[error("upsampler option {option} = {value} is out of range: {expected}")]
    BadOption { option: &'static str, value: String, expected: &'static str },

    /// A sparse row names a column past the matrix width.
    #[error("sparse row {row} names column {col}, but the matrix has {cols} columns")]
    ColumnOutOfRange { row: usize, col: u32, cols: usize },

    /// Matrix (or matrix and point set) shapes do not fit together.
    #[error("shapes {left:?} and {right:?} do not fit together")]
    ShapeMismatch { left: (usize, usize), right: (usize, usize) },

    /// A pose to measure is not in the pose set.
    #[error("pose {pose} is not in the pose set ({poses} poses)")]
    PoseOutOfRange { pose: usize, poses: usize },

    #[error(transparent)]
    Mesh(#[from] desal_mesh::MeshError),
}
