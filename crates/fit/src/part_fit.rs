//! [`PartFit`]: the fit of one part onto one pose, which stage 1 computes and its summary
//! reads (below both, so neither imports the other's module for it).

use desal_mesh::math::{Mat3, Real, Vec3};

/// The fit of one part onto one pose, with its residual statistics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PartFit {
    /// The linear part: a proper rotation for [`FitModel::Rigid`].
    pub linear: Mat3,
    /// The translation, in mesh units.
    pub translation: Vec3,
    /// Root mean square of the part's vertex residuals, in mesh units.
    pub rms: Real,
    /// Mean of the part's vertex residuals, in mesh units.
    pub mean: Real,
    /// Largest of the part's vertex residuals, in mesh units.
    pub max: Real,
}

impl PartFit {
    /// The exact fit of a pose onto itself.
    pub(crate) fn identity() -> Self {
        Self { linear: Mat3::identity(), translation: Vec3::zeros(), rms: 0.0, mean: 0.0, max: 0.0 }
    }

    /// The image of template point `p`.
    #[inline]
    pub fn apply(&self, p: &Vec3) -> Vec3 {
        self.linear * p + self.translation
    }
}
