//! `PartTransform`: one part's rigid motion from the template to a pose (stage 1's fit),
//! the input both deformation models are driven by, and the checks of a pose's set of
//! them.

use desal_mesh::{Mat3, PartLabels, PoseSet, Vec3};

use crate::error::EvalError;
use crate::folds::check_training_poses;

/// The rigid motion `p ↦ rotation · p + translation` taking a part of the template onto
/// a pose, with `p` in template coordinates (mesh units, m for SCAPE). Stage 1
/// (`desal_fit::PartFit`: `linear`, `translation`) produces exactly this.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartTransform {
    /// A proper rotation.
    pub rotation: Mat3,
    /// Mesh units.
    pub translation: Vec3,
}

impl PartTransform {
    pub fn identity() -> Self {
        Self { rotation: Mat3::identity(), translation: Vec3::zeros() }
    }

    /// The image of template point `p`.
    #[inline]
    pub fn apply(&self, p: &Vec3) -> Vec3 {
        self.rotation * p + self.translation
    }
}

/// The rotations of one pose's part transforms, in part order.
pub fn rotations_of(transforms: &[PartTransform]) -> Vec<Mat3> {
    transforms.iter().map(|t| t.rotation).collect()
}

/// Checks one pose's transforms: one per part, all finite.
pub(crate) fn check_pose_transforms(
    transforms: &[PartTransform],
    part_count: usize,
    pose: usize,
) -> Result<(), EvalError> {
    if transforms.len() != part_count {
        return Err(EvalError::RotationPartCount { pose, expected: part_count, found: transforms.len() });
    }
    let finite = |t: &PartTransform| t.rotation.iter().chain(t.translation.iter()).all(|x| x.is_finite());
    if let Some(part) = transforms.iter().position(|t| !finite(t)) {
        return Err(EvalError::NonFiniteTransform { pose, part });
    }
    Ok(())
}

/// Checks one pose's rotations: one per part, all finite.
pub(crate) fn check_pose_rotations(
    rotations: &[Mat3],
    part_count: usize,
    pose: usize,
) -> Result<(), EvalError> {
    if rotations.len() != part_count {
        return Err(EvalError::RotationPartCount { pose, expected: part_count, found: rotations.len() });
    }
    if let Some(part) = rotations.iter().position(|r| !r.iter().all(|x| x.is_finite())) {
        return Err(EvalError::NonFiniteRotation { pose, part });
    }
    Ok(())
}

/// The inputs every model fit checks: labels for every vertex, per-pose part motions
/// for every pose (`check_pose` on each training pose's), valid training poses.
pub(crate) fn check_model_inputs<T>(
    poses: &PoseSet,
    labels: &PartLabels,
    per_pose: &[Vec<T>],
    training_poses: &[usize],
    check_pose: impl Fn(&[T], usize, usize) -> Result<(), EvalError>,
) -> Result<(), EvalError> {
    if labels.vertex_count() != poses.vertex_count() {
        return Err(EvalError::LabelCountMismatch {
            labels: labels.vertex_count(),
            vertices: poses.vertex_count(),
        });
    }
    if per_pose.len() != poses.pose_count() {
        return Err(EvalError::RotationPoseCount { expected: poses.pose_count(), found: per_pose.len() });
    }
    check_training_poses(poses.pose_count(), training_poses)?;
    for &pose in training_poses {
        check_pose(&per_pose[pose], labels.part_count(), pose)?;
    }
    Ok(())
}
