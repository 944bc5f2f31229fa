//! The error type of stage 1. Every variant names the part and, where it applies, the
//! pose, so a bad segmentation or a broken pose file can be found at once.

use desal_mesh::MeshError;
use thiserror::Error;

/// Why the per-part fit could not be computed.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum FitError {
    /// The labels do not match the pose set (wrong length, unknown part id).
    #[error("the part labels do not match the pose set")]
    Labels(#[source] MeshError),

    /// A part has fewer than three vertices, or all of them lie on a line in the named
    /// pose (the template), so no rotation is determined. Merge it into a neighbour.
    #[error(
        "part {part} ('{part_name}') has {vertices} vertices that do not span a plane in pose '{pose_name}' (index {pose}); a rigid fit needs at least 3 non-collinear vertices per part — merge it into a neighbouring part"
    )]
    DegeneratePart { part: u32, part_name: String, pose: usize, pose_name: String, vertices: usize },

    /// The fit of a part onto a pose is not unique: the part's vertices in that pose are
    /// (nearly) collinear or coincident, so the cross-covariance has rank < 2. Usually a
    /// broken pose file (a collapsed limb).
    #[error(
        "the fit of part {part} ('{part_name}') onto pose '{pose_name}' (index {pose}) is numerically degenerate: singular value ratio {ratio:.3e} is below {threshold:.1e} (the part collapses to a line or a point in that pose); check the pose file"
    )]
    DegenerateFit { part: u32, part_name: String, pose: usize, pose_name: String, ratio: f64, threshold: f64 },

    /// The solver produced a non-finite transform (non-finite or astronomically large input).
    #[error("the fit of part {part} ('{part_name}') onto pose '{pose_name}' (index {pose}) is not finite")]
    NonFinite { part: u32, part_name: String, pose: usize, pose_name: String },
}
