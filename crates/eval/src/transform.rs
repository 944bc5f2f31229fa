//! `PartTransform`: one part's rigid motion from the template to a pose (stage 1's fit),
//! the input both deformation models are driven by, and the checks of a pose's set of
//! them.

use desal_mesh::{Mat3, Vec3};

use crate::error::EvalError;

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
