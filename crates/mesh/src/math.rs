//! Math type aliases: the only file that names the linear-algebra library, so that a
//! change of library (or of precision) is a change here.

/// Scalar type for all geometry computed in memory.
pub type Real = f64;
/// A 3D point or vector.
pub type Vec3 = nalgebra::Vector3<f64>;
/// A 3x3 matrix (rotations, covariances, deformation gradients).
pub type Mat3 = nalgebra::Matrix3<f64>;
/// A 4x4 matrix (homogeneous transforms, quadrics).
pub type Mat4 = nalgebra::Matrix4<f64>;
/// A unit quaternion (rotations in the sample generator and the viewer).
pub type UnitQuat = nalgebra::UnitQuaternion<f64>;
/// A quaternion, not necessarily of unit length (as read from a file, before normalising).
pub type Quat = nalgebra::Quaternion<f64>;

/// Builds a `Vec3` from an `f32` triple as stored on disk.
#[inline]
pub fn vec3_from_f32(p: [f32; 3]) -> Vec3 {
    Vec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
}

/// Converts a `Vec3` to the `f32` triple stored on disk.
#[inline]
pub fn vec3_to_f32(p: &Vec3) -> [f32; 3] {
    [p.x as f32, p.y as f32, p.z as f32]
}

/// Unnormalised normal of triangle `(a, b, c)`: its length is twice the area.
#[inline]
pub fn triangle_cross(a: &Vec3, b: &Vec3, c: &Vec3) -> Vec3 {
    (b - a).cross(&(c - a))
}

/// Area of triangle `(a, b, c)`.
#[inline]
pub fn triangle_area(a: &Vec3, b: &Vec3, c: &Vec3) -> Real {
    0.5 * triangle_cross(a, b, c).norm()
}

/// Axis-aligned bounding box of `points` as `(min, max)`; `None` when empty.
pub fn bounding_box(points: &[Vec3]) -> Option<(Vec3, Vec3)> {
    let first = points.first()?;
    let mut lo = *first;
    let mut hi = *first;
    for p in points {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    Some((lo, hi))
}
