//! `EvalError`: everything that can go wrong when fitting or using the deformation
//! model. Variants carry the offending pose, part or face ids.

use thiserror::Error;

/// Errors of the deformation model. Metrics never fail (an empty mesh gives NaN, see
/// [`crate::metrics`]).
#[derive(Debug, Error, Clone, PartialEq)]
pub enum EvalError {
    /// The part labels do not cover the pose set's vertices one to one.
    #[error(
        "part labels cover {labels} vertices but the pose set has {vertices}; use the labels of this mesh"
    )]
    LabelCountMismatch { labels: usize, vertices: usize },

    /// `rotations` must hold one entry per pose of the pose set.
    #[error("part rotations given for {found} poses but the pose set has {expected}")]
    RotationPoseCount { expected: usize, found: usize },

    /// Every pose needs one rotation per part.
    #[error("pose {pose}: part rotations given for {found} parts but the labels have {expected}")]
    RotationPartCount { pose: usize, expected: usize, found: usize },

    /// A rotation contains NaN or infinity.
    #[error("pose {pose}, part {part}: the part rotation is not finite")]
    NonFiniteRotation { pose: usize, part: usize },

    /// A part transform (rotation or translation) contains NaN or infinity.
    #[error("pose {pose}, part {part}: the part transform is not finite")]
    NonFiniteTransform { pose: usize, part: usize },

    /// The model needs at least one training pose.
    #[error("no training poses given")]
    NoTrainingPoses,

    /// A training pose index is not a pose of the pose set.
    #[error("training pose {pose} is out of range (the pose set has {pose_count} poses)")]
    TrainingPoseOutOfRange { pose: usize, pose_count: usize },

    /// A training pose is listed twice (it would silently weigh double).
    #[error("training pose {pose} is listed more than once")]
    DuplicateTrainingPose { pose: usize },

    /// A template triangle has zero area, so its deformation gradient is undefined.
    /// Remove degenerate faces first (`desal_mesh::clean_faces`).
    #[error("template face {face} has zero area; its deformation gradient is undefined")]
    DegenerateTriangle { face: usize },

    /// The sparse factorisation of the Poisson system failed (it is positive definite by
    /// construction, so this signals non-finite input or a bug).
    #[error("sparse Cholesky factorisation of the Poisson system failed: {0}")]
    Factorisation(String),

    /// `synthesize_many` got a different number of rotation sets and centroids.
    #[error("{rotations} rotation sets but {centroids} target centroids")]
    TargetCountMismatch { rotations: usize, centroids: usize },
}
