//! Exact closest point on a triangle to a query point.
//!
//! Ericson, "Real-Time Collision Detection" (2005), §5.1.5 `ClosestPtPointTriangle`: the
//! query is classified into one of the triangle's Voronoi regions (three vertices, three
//! edges, the face) with a handful of dot products, and the closest point is computed in
//! that region only. No square roots, no plane projection.

use desal_mesh::{Real, Vec3};

/// The point of triangle `(a, b, c)` closest to `p`.
///
/// Degenerate triangles (zero area) are handled: the answer is then the closest point on
/// the segments, which is what the triangle collapses to.
pub fn closest_point_on_triangle(p: &Vec3, a: &Vec3, b: &Vec3, c: &Vec3) -> Vec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return *a; // vertex region A
    }

    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return *b; // vertex region B
    }

    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        if d1 - d3 <= 0.0 {
            return closest_point_on_segments(p, a, b, c); // AB collapsed to a point
        }
        return a + ab * (d1 / (d1 - d3)); // edge region AB
    }

    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return *c; // vertex region C
    }

    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        if d2 - d6 <= 0.0 {
            return closest_point_on_segments(p, a, b, c); // AC collapsed to a point
        }
        return a + ac * (d2 / (d2 - d6)); // edge region AC
    }

    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let denominator = (d4 - d3) + (d5 - d6);
        if denominator <= 0.0 {
            return closest_point_on_segments(p, a, b, c); // BC collapsed to a point
        }
        return b + (c - b) * ((d4 - d3) / denominator); // edge region BC
    }

    let sum = va + vb + vc;
    if sum <= 0.0 {
        // Only a zero-area triangle reaches here with a zero sum (the three barycentric
        // numerators of a proper triangle sum to twice its squared area).
        return closest_point_on_segments(p, a, b, c);
    }
    let denom = 1.0 / sum;
    let v = vb * denom;
    let w = vc * denom;
    a + ab * v + ac * w // face region
}

/// Squared distance from `p` to triangle `(a, b, c)`.
#[inline]
pub fn point_triangle_distance_sq(p: &Vec3, a: &Vec3, b: &Vec3, c: &Vec3) -> Real {
    (p - closest_point_on_triangle(p, a, b, c)).norm_squared()
}

/// Closest point on the three edges of a degenerate triangle.
fn closest_point_on_segments(p: &Vec3, a: &Vec3, b: &Vec3, c: &Vec3) -> Vec3 {
    [closest_point_on_segment(p, a, b), closest_point_on_segment(p, b, c), closest_point_on_segment(p, c, a)]
        .into_iter()
        .min_by(|x, y| (p - x).norm_squared().total_cmp(&(p - y).norm_squared()))
        .expect("three candidates")
}

/// Closest point on segment `[a, b]` (a point when `a == b`).
fn closest_point_on_segment(p: &Vec3, a: &Vec3, b: &Vec3) -> Vec3 {
    let ab = b - a;
    let len_sq = ab.norm_squared();
    if len_sq == 0.0 {
        return *a;
    }
    let t = ((p - a).dot(&ab) / len_sq).clamp(0.0, 1.0);
    a + ab * t
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> Vec3 {
        Vec3::new(x, y, z)
    }

    /// Two coincident corners (a zero-length edge) must not give 0 / 0: the triangle is
    /// the segment from the double corner to the third, and each query point's distance
    /// to it is known. (Found by `desal eval`'s upsampling error, issue 13.)
    #[test]
    fn coincident_corners_give_the_distance_to_the_remaining_segment() {
        let (a, c) = (v(0.0, 0.0, 0.0), v(0.0, 1.0, 0.0));
        for (p, want) in [(v(0.0, 0.5, 1.0), 1.0), (v(2.0, 0.5, 0.0), 4.0), (v(0.0, -1.0, 0.0), 1.0)] {
            for (x, y, z) in [(a, a, c), (a, c, a), (c, a, a)] {
                let d = point_triangle_distance_sq(&p, &x, &y, &z);
                assert_eq!(d, want, "{p:?} against {x:?} {y:?} {z:?}");
            }
        }
    }

    /// The unit right triangle in the z = 0 plane, queried from each Voronoi region: the
    /// expected closest points are known by construction.
    #[test]
    fn each_voronoi_region_gives_the_known_closest_point() {
        let (a, b, c) = (v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0));
        let cases = [
            (v(0.25, 0.25, 2.0), v(0.25, 0.25, 0.0)), // face: straight down
            (v(-1.0, -1.0, 0.5), a),                  // vertex A
            (v(2.0, -0.5, 0.0), b),                   // vertex B
            (v(-0.5, 3.0, 1.0), c),                   // vertex C
            (v(0.5, -1.0, 1.0), v(0.5, 0.0, 0.0)),    // edge AB
            (v(-2.0, 0.5, 0.0), v(0.0, 0.5, 0.0)),    // edge AC
            (v(1.0, 1.0, 0.0), v(0.5, 0.5, 0.0)),     // edge BC
        ];
        for (p, expected) in cases {
            let q = closest_point_on_triangle(&p, &a, &b, &c);
            assert!((q - expected).norm() < 1e-15, "query {p:?}: got {q:?}, expected {expected:?}");
        }
    }

    /// A triangle collapsed onto a segment behaves like the segment.
    #[test]
    fn degenerate_triangle_is_its_segment() {
        let (a, b, c) = (v(0.0, 0.0, 0.0), v(2.0, 0.0, 0.0), v(1.0, 0.0, 0.0));
        let d = point_triangle_distance_sq(&v(1.5, 3.0, 4.0), &a, &b, &c);
        assert_eq!(d, 25.0);
        let d = point_triangle_distance_sq(&v(3.0, 0.0, 1.0), &a, &a, &a);
        assert_eq!(d, 10.0);
    }
}
