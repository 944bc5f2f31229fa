//! Error quadrics (Garland and Heckbert 1997): `Q(x) = xᵀAx + 2bᵀx + c`, the weighted
//! sum of squared distances from `x` to a set of planes, stored as ten `f64` plus the
//! total face area it stands for, and its minimisers (free, on a segment).

use desal_mesh::Vec3;

use crate::lanes::{Lanes, Points, four};

/// A symmetric 4×4 quadric in its ten distinct coefficients, plus `area`: the total
/// area of the faces whose planes it sums (constraint planes add no area), so that
/// `eval(x) / area` is a mean squared distance in squared mesh units.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Quadric {
    a00: f64,
    a01: f64,
    a02: f64,
    a11: f64,
    a12: f64,
    a22: f64,
    b0: f64,
    b1: f64,
    b2: f64,
    c: f64,
    /// Total face area represented, in squared mesh units.
    pub area: f64,
}

/// `|det A| <= DET_EPSILON * (trace A / 3)³` counts as singular: the quadric does not pin
/// the point down in some direction (flat or cylindrical neighbourhood), and solving
/// would amplify noise into a placement far from the edge.
const DET_EPSILON: f64 = 1e-9;

impl Quadric {
    /// The plane `n·x + d = 0` (unit `n`) with weight `weight`, standing for `area`.
    #[inline]
    pub fn from_plane(n: &Vec3, d: f64, weight: f64, area: f64) -> Self {
        let (x, y, z) = (n.x * weight, n.y * weight, n.z * weight);
        Self {
            a00: x * n.x,
            a01: x * n.y,
            a02: x * n.z,
            a11: y * n.y,
            a12: y * n.z,
            a22: z * n.z,
            b0: x * d,
            b1: y * d,
            b2: z * d,
            c: weight * d * d,
            area,
        }
    }

    /// The area-weighted plane quadric of triangle `(p0, p1, p2)`; zero when degenerate.
    #[inline]
    pub fn from_triangle(p0: &Vec3, p1: &Vec3, p2: &Vec3) -> Self {
        FacePlane::of_triangle(p0, p1, p2).quadric()
    }

    /// The constraint quadric holding edge `(p0, p1)` of a face with normal direction
    /// `face_cross` (any length): the plane through the edge perpendicular to the face,
    /// with weight `weight * |p1 - p0|²`. Zero when degenerate.
    #[inline]
    pub fn edge_constraint(p0: &Vec3, p1: &Vec3, face_cross: &Vec3, weight: f64) -> Self {
        let edge = p1 - p0;
        let Some(n) = edge.cross(face_cross).try_normalize(0.0) else {
            return Self::default();
        };
        Self::from_plane(&n, -n.dot(p0), weight * edge.norm_squared(), 0.0)
    }

    /// `|d × (x − t)|²`: `|d|²` times the squared distance from `x` to the line through
    /// `t` along `d` (Lindstrom–Turk: four times the squared area of triangle
    /// `(x, t − d, t)`). Carries no area.
    #[inline]
    pub(crate) fn from_line(t: &Vec3, d: &Vec3) -> Self {
        let l = d.norm_squared();
        let mut q = Self {
            a00: l - d.x * d.x,
            a01: -d.x * d.y,
            a02: -d.x * d.z,
            a11: l - d.y * d.y,
            a12: -d.y * d.z,
            a22: l - d.z * d.z,
            ..Self::default()
        };
        let at = q.apply(t);
        (q.b0, q.b1, q.b2) = (-at.x, -at.y, -at.z);
        q.c = t.dot(&at);
        q
    }

    /// `|x − p|²`, the squared distance to one point. Carries no area.
    #[inline]
    pub(crate) fn from_point(p: &Vec3) -> Self {
        Self {
            a00: 1.0,
            a11: 1.0,
            a22: 1.0,
            b0: -p.x,
            b1: -p.y,
            b2: -p.z,
            c: p.norm_squared(),
            ..Self::default()
        }
    }

    /// The quadric times `w` (area included).
    #[inline]
    pub(crate) fn scaled(&self, w: f64) -> Self {
        Self {
            a00: self.a00 * w,
            a01: self.a01 * w,
            a02: self.a02 * w,
            a11: self.a11 * w,
            a12: self.a12 * w,
            a22: self.a22 * w,
            b0: self.b0 * w,
            b1: self.b1 * w,
            b2: self.b2 * w,
            c: self.c * w,
            area: self.area * w,
        }
    }

    /// The rows of `A` and the vector `b`: the minimiser solves `A x = −b`.
    #[inline]
    pub(crate) fn gradient_parts(&self) -> ([Vec3; 3], Vec3) {
        (
            [
                Vec3::new(self.a00, self.a01, self.a02),
                Vec3::new(self.a01, self.a11, self.a12),
                Vec3::new(self.a02, self.a12, self.a22),
            ],
            Vec3::new(self.b0, self.b1, self.b2),
        )
    }

    /// `xᵀAx + 2bᵀx + c`: the weighted sum of squared distances to the planes. Inlined
    /// by force into the engine's `try_collapse` clones (BENCHMARKS.md "Issue 40").
    #[inline(always)]
    pub fn eval(&self, p: &Vec3) -> f64 {
        let (x, y, z) = (p.x, p.y, p.z);
        x * (self.a00 * x + 2.0 * (self.a01 * y + self.a02 * z + self.b0))
            + y * (self.a11 * y + 2.0 * (self.a12 * z + self.b1))
            + z * (self.a22 * z + 2.0 * self.b2)
            + self.c
    }

    /// `A p` (the quadratic part applied to `p`).
    #[inline]
    fn apply(&self, p: &Vec3) -> Vec3 {
        Vec3::new(
            self.a00 * p.x + self.a01 * p.y + self.a02 * p.z,
            self.a01 * p.x + self.a11 * p.y + self.a12 * p.z,
            self.a02 * p.x + self.a12 * p.y + self.a22 * p.z,
        )
    }

    /// The point minimising the quadric, or `None` when `A` is near-singular (see
    /// `DET_EPSILON`).
    #[inline]
    pub fn minimiser(&self) -> Option<Vec3> {
        // Cofactors of the symmetric A; det by expansion along the first row.
        let c00 = self.a11 * self.a22 - self.a12 * self.a12;
        let c01 = self.a02 * self.a12 - self.a01 * self.a22;
        let c02 = self.a01 * self.a12 - self.a02 * self.a11;
        let det = self.a00 * c00 + self.a01 * c01 + self.a02 * c02;
        let scale = (self.a00 + self.a11 + self.a22) / 3.0;
        // `is_gt` is false for NaN too, so a poisoned quadric is treated as singular.
        if !det.abs().partial_cmp(&(DET_EPSILON * scale * scale * scale)).is_some_and(|o| o.is_gt()) {
            return None;
        }
        let c11 = self.a00 * self.a22 - self.a02 * self.a02;
        let c12 = self.a01 * self.a02 - self.a00 * self.a12;
        let c22 = self.a00 * self.a11 - self.a01 * self.a01;
        let inv = 1.0 / det;
        let (b0, b1, b2) = (-self.b0, -self.b1, -self.b2);
        let p = Vec3::new(
            (c00 * b0 + c01 * b1 + c02 * b2) * inv,
            (c01 * b0 + c11 * b1 + c12 * b2) * inv,
            (c02 * b0 + c12 * b1 + c22 * b2) * inv,
        );
        all_finite(&p).then_some(p)
    }

    /// The point of segment `[p0, p1]` minimising the quadric, or `None` when the
    /// quadric is flat along the segment (then the endpoints are equally good).
    #[inline]
    pub fn minimiser_on_segment(&self, p0: &Vec3, p1: &Vec3) -> Option<Vec3> {
        let d = p1 - p0;
        let curvature = d.dot(&self.apply(&d));
        // Along p0 + t d, Q is curvature t² + 2 slope t + Q(p0).
        let slope = d.dot(&self.apply(p0)) + self.b0 * d.x + self.b1 * d.y + self.b2 * d.z;
        let scale = (self.a00 + self.a11 + self.a22) * d.norm_squared();
        if !curvature.partial_cmp(&(1e-12 * scale)).is_some_and(|o| o.is_gt()) {
            return None;
        }
        let t = (-slope / curvature).clamp(0.0, 1.0);
        Some(p0 + d * t)
    }
}

/// Four quadrics, one per lane: the sums of four pairs, for costing four edges at once
/// with the arithmetic of [`Quadric::eval`] and [`Quadric::minimiser`] written in the same
/// order (each lane is bit for bit the scalar result; `placement.rs` asserts it in debug
/// builds). No `area`: the placement does not read it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Quadric4 {
    a00: Lanes,
    a01: Lanes,
    a02: Lanes,
    a11: Lanes,
    a12: Lanes,
    a22: Lanes,
    b0: Lanes,
    b1: Lanes,
    b2: Lanes,
    c: Lanes,
}

impl Quadric4 {
    /// Lane `l` is `pairs[l].0 + pairs[l].1`, added as `Quadric + Quadric` adds. Inlined
    /// by force into the listing's clones (BENCHMARKS.md "Issue 40").
    #[inline(always)]
    pub(crate) fn sums(pairs: [(&Quadric, &Quadric); 4]) -> Self {
        let sum = |f: fn(&Quadric) -> f64| Lanes::from_fn(|l| f(pairs[l].0) + f(pairs[l].1));
        Self {
            a00: sum(|q| q.a00),
            a01: sum(|q| q.a01),
            a02: sum(|q| q.a02),
            a11: sum(|q| q.a11),
            a12: sum(|q| q.a12),
            a22: sum(|q| q.a22),
            b0: sum(|q| q.b0),
            b1: sum(|q| q.b1),
            b2: sum(|q| q.b2),
            c: sum(|q| q.c),
        }
    }

    /// [`Quadric::eval`], lane-wise.
    #[inline]
    pub(crate) fn eval(&self, p: &Points) -> Lanes {
        let (x, y, z) = (p.x, p.y, p.z);
        let two = Lanes::splat(2.0);
        x * (self.a00 * x + two * (self.a01 * y + self.a02 * z + self.b0))
            + y * (self.a11 * y + two * (self.a12 * z + self.b1))
            + z * (self.a22 * z + two * self.b2)
            + self.c
    }

    /// [`Quadric::minimiser`], lane-wise: the points, and which lanes have one (lanes
    /// without hold garbage). Inlined by force into the listing's clones
    /// (BENCHMARKS.md "Issue 40").
    #[inline(always)]
    pub(crate) fn minimiser(&self) -> (Points, [bool; 4]) {
        let c00 = self.a11 * self.a22 - self.a12 * self.a12;
        let c01 = self.a02 * self.a12 - self.a01 * self.a22;
        let c02 = self.a01 * self.a12 - self.a02 * self.a11;
        let det = self.a00 * c00 + self.a01 * c01 + self.a02 * c02;
        let scale = (self.a00 + self.a11 + self.a22) / Lanes::splat(3.0);
        let regular = det.abs().gt(Lanes::splat(DET_EPSILON) * scale * scale * scale);
        let c11 = self.a00 * self.a22 - self.a02 * self.a02;
        let c12 = self.a01 * self.a02 - self.a00 * self.a12;
        let c22 = self.a00 * self.a11 - self.a01 * self.a01;
        let inv = Lanes::splat(1.0) / det;
        let (b0, b1, b2) = (-self.b0, -self.b1, -self.b2);
        let p = Points {
            x: (c00 * b0 + c01 * b1 + c02 * b2) * inv,
            y: (c01 * b0 + c11 * b1 + c12 * b2) * inv,
            z: (c02 * b0 + c12 * b1 + c22 * b2) * inv,
        };
        // `all_finite`, lane-wise.
        #[expect(clippy::eq_op, reason = "`x - x` is the test")]
        let zero = (p.x - p.x) + (p.y - p.y) + (p.z - p.z);
        let valid = four(|l| regular[l] && zero.0[l] == 0.0);
        (p, valid)
    }
}

/// Whether all three coordinates are finite, in one comparison (three `is_finite` tests
/// cost three masks and branches): `x - x` is +0 for a finite `x` and NaN for an
/// infinite or NaN one, which makes the sum NaN.
#[inline]
#[expect(clippy::eq_op, reason = "`x - x` is the test")]
fn all_finite(p: &Vec3) -> bool {
    (p.x - p.x) + (p.y - p.y) + (p.z - p.z) == 0.0
}

/// The plane of a triangle, `n·x + offset = 0` (unit `n`), and its area: 40 bytes
/// against a quadric's 88, from which [`FacePlane::quadric`] rebuilds the triangle's
/// quadric exactly (the engine keeps one per input face while it fills the vertices').
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct FacePlane {
    normal: Vec3,
    offset: f64,
    /// In squared mesh units; 0 (with a zero normal) for a degenerate triangle.
    area: f64,
}

impl FacePlane {
    #[inline]
    pub(crate) fn of_triangle(p0: &Vec3, p1: &Vec3, p2: &Vec3) -> Self {
        let cross = (p1 - p0).cross(&(p2 - p0));
        let twice_area = cross.norm();
        if twice_area <= 0.0 || !twice_area.is_finite() {
            return Self::default();
        }
        let normal = cross / twice_area;
        Self { normal, offset: -normal.dot(p0), area: 0.5 * twice_area }
    }

    /// The area-weighted quadric of the plane. A degenerate triangle's (zero normal,
    /// offset and area) is `Quadric::default()`: every product is `+0`.
    #[inline]
    pub(crate) fn quadric(&self) -> Quadric {
        Quadric::from_plane(&self.normal, self.offset, self.area, self.area)
    }
}

impl std::ops::AddAssign<&Quadric> for Quadric {
    #[inline]
    fn add_assign(&mut self, o: &Quadric) {
        self.a00 += o.a00;
        self.a01 += o.a01;
        self.a02 += o.a02;
        self.a11 += o.a11;
        self.a12 += o.a12;
        self.a22 += o.a22;
        self.b0 += o.b0;
        self.b1 += o.b1;
        self.b2 += o.b2;
        self.c += o.c;
        self.area += o.area;
    }
}

impl std::ops::Add for Quadric {
    type Output = Quadric;
    #[inline]
    fn add(mut self, o: Quadric) -> Quadric {
        self += &o;
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `all_finite` is three `is_finite` tests: any infinite or NaN coordinate fails it.
    #[test]
    fn all_finite_is_three_finiteness_tests() {
        let values = [0.0, -0.0, 1.5, -3e300, f64::MIN_POSITIVE, f64::INFINITY, f64::NEG_INFINITY, f64::NAN];
        for &x in &values {
            for &y in &values {
                for &z in &values {
                    let expected = x.is_finite() && y.is_finite() && z.is_finite();
                    assert_eq!(all_finite(&Vec3::new(x, y, z)), expected, "({x}, {y}, {z})");
                }
            }
        }
    }

    /// The plane z = 1 with weight 2: a point at z = 4 is 3 away, so the error is 2·9.
    #[test]
    fn plane_quadric_measures_weighted_squared_distance() {
        let q = Quadric::from_plane(&Vec3::z(), -1.0, 2.0, 0.5);
        assert!((q.eval(&Vec3::new(5.0, -7.0, 4.0)) - 18.0).abs() < 1e-12);
        assert_eq!(q.area, 0.5);
    }

    /// Three orthogonal planes meet in one point, which is the minimiser.
    #[test]
    fn three_planes_meet_at_minimiser() {
        let q = Quadric::from_plane(&Vec3::x(), -1.0, 1.0, 1.0)
            + Quadric::from_plane(&Vec3::y(), -2.0, 1.0, 1.0)
            + Quadric::from_plane(&Vec3::z(), 3.0, 1.0, 1.0);
        let p = q.minimiser().expect("well-conditioned");
        assert!((p - Vec3::new(1.0, 2.0, -3.0)).norm() < 1e-12);
        assert!(q.eval(&p).abs() < 1e-12);
    }

    /// One plane leaves two free directions: no unique minimiser; on a segment crossing
    /// the plane the minimiser is the crossing point.
    #[test]
    fn single_plane_is_singular_but_segment_minimiser_crosses_it() {
        let q = Quadric::from_plane(&Vec3::z(), 0.0, 1.0, 1.0);
        assert!(q.minimiser().is_none());
        let p = q.minimiser_on_segment(&Vec3::new(0.0, 0.0, -1.0), &Vec3::new(2.0, 0.0, 3.0)).unwrap();
        assert!((p - Vec3::new(0.5, 0.0, 0.0)).norm() < 1e-12);
        // A segment inside the plane: Q is flat along it.
        assert!(q.minimiser_on_segment(&Vec3::zeros(), &Vec3::x()).is_none());
    }

    /// The line quadric is |d|² times the squared distance to the line; the point
    /// quadric the squared distance to the point.
    #[test]
    fn line_and_point_quadrics_measure_squared_distances() {
        let q = Quadric::from_line(&Vec3::new(0.0, 1.0, 0.0), &Vec3::new(2.0, 0.0, 0.0));
        // (7, 4, 5) is at distance² 3² + 5² = 34 from the line y = 1, z = 0.
        assert!((q.eval(&Vec3::new(7.0, 4.0, 5.0)) - 4.0 * 34.0).abs() < 1e-9);
        let p = Quadric::from_point(&Vec3::new(1.0, 2.0, 3.0)).scaled(2.0);
        assert!((p.eval(&Vec3::new(2.0, 2.0, 1.0)) - 10.0).abs() < 1e-12);
    }

    /// A degenerate triangle (three collinear points) has the zero quadric, bit for bit:
    /// vertex sums must not change when a face plane stands for it.
    #[test]
    fn degenerate_triangle_has_the_zero_quadric() {
        let q = Quadric::from_triangle(&Vec3::zeros(), &Vec3::x(), &(Vec3::x() * 2.0));
        assert_eq!(format!("{q:?}"), format!("{:?}", Quadric::default()));
        assert!([q.a00, q.a01, q.b0, q.c, q.area].iter().all(|x| x.to_bits() == 0));
    }

    /// The boundary constraint of edge (0,0,0)-(1,0,0) on a face in the z = 0 plane is
    /// the plane y = 0, weighted by w·l².
    #[test]
    fn edge_constraint_is_perpendicular_to_face() {
        let q = Quadric::edge_constraint(&Vec3::zeros(), &Vec3::new(2.0, 0.0, 0.0), &Vec3::z(), 3.0);
        assert!((q.eval(&Vec3::new(9.0, 1.0, 5.0)) - 12.0).abs() < 1e-12);
        assert_eq!(q.area, 0.0);
    }
}
