//! Per-triangle deformation gradients, as in deformation transfer.
//!
//! Sumner & Popović 2004, "Deformation Transfer for Triangle Meshes", §3: a triangle
//! `(v1, v2, v3)` is given a frame `[v2 − v1, v3 − v1, n]` whose third column is the
//! normal scaled to `n = c / √‖c‖`, `c = (v2 − v1) × (v3 − v1)` — so the frame's third
//! column scales like the edges (its length is the square root of twice the area). The
//! deformation gradient from a template triangle to a posed one is then
//! `T = V V̂⁻¹`, the unique linear map taking the template's edges to the posed edges
//! and the template's scaled normal to the posed one.

use desal_mesh::{Mat3, Vec3};

/// The frame `[e2, e3, n]` of triangle `(a, b, c)`: edges from `a`, then the scaled
/// normal. Zero third column for a zero-area triangle.
pub fn triangle_frame(a: &Vec3, b: &Vec3, c: &Vec3) -> Mat3 {
    let e2 = b - a;
    let e3 = c - a;
    let cross = e2.cross(&e3);
    let len = cross.norm();
    let n = if len > 0.0 { cross / len.sqrt() } else { Vec3::zeros() };
    Mat3::from_columns(&[e2, e3, n])
}

/// Inverse of the template frame of triangle `(a, b, c)`; `None` for a zero-area
/// triangle (its frame is singular).
pub fn inverse_template_frame(a: &Vec3, b: &Vec3, c: &Vec3) -> Option<Mat3> {
    let frame = triangle_frame(a, b, c);
    // det = ‖c‖^{3/2} > 0 exactly when the triangle has area.
    if frame.column(2).norm_squared() == 0.0 {
        return None;
    }
    frame.try_inverse()
}

/// Deformation gradient `V V̂⁻¹` of a posed triangle, given the template's
/// [`inverse_template_frame`].
#[inline]
pub fn deformation_gradient(inverse_template: &Mat3, posed: [Vec3; 3]) -> Mat3 {
    triangle_frame(&posed[0], &posed[1], &posed[2]) * inverse_template
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rotated, uniformly scaled copy of a triangle has gradient `s R`; the normal
    /// column scales by `s` too thanks to the square-root normalisation.
    #[test]
    fn similarity_gives_scaled_rotation() {
        let (a, b, c) = (Vec3::new(0.1, 0.0, 0.2), Vec3::new(1.0, 0.3, 0.0), Vec3::new(0.2, 0.9, 0.4));
        let r = *nalgebra::Rotation3::from_scaled_axis(Vec3::new(0.3, -0.5, 0.8)).matrix();
        let s = 1.7;
        let t = Vec3::new(5.0, -2.0, 1.0);
        let posed = [s * r * a + t, s * r * b + t, s * r * c + t];
        let g = deformation_gradient(&inverse_template_frame(&a, &b, &c).unwrap(), posed);
        assert!((g - s * r).norm() < 1e-12, "{g}");
    }

    #[test]
    fn zero_area_template_has_no_inverse() {
        let a = Vec3::zeros();
        let b = Vec3::x();
        assert!(inverse_template_frame(&a, &b, &(2.0 * b)).is_none());
    }
}
