//! COMA's upsampler (Ranjan et al. 2018, `mesh_sampling.py`,
//! `setup_deformation_transfer`): each fine vertex, in the template pose, is projected
//! onto the nearest coarse triangle, and its row of U holds the barycentric coordinates
//! of that projection over the triangle's three corners.
//!
//! COMA's three cases, and what this file does in each:
//! - projection inside the triangle: COMA solves `[a b c] x = q` by least squares, which
//!   for a triangle whose plane misses the origin *is* the barycentric coordinates;
//!   here they are computed from the Gram system, the same numbers without the origin
//!   caveat.
//! - projection on a vertex: weight 1 on that vertex, as COMA.
//! - projection on an edge: COMA solves `[a b] x = v` against the *fine vertex* `v`,
//!   unconstrained, so its two weights need not sum to 1 and move with the coordinate
//!   origin. Here the edge case takes the projection's coordinates along the edge, which
//!   sum to 1 — the rule COMA's comment ("closest surface point on edge") describes. It
//!   differs from COMA's numbers only for fine vertices whose projection is on an edge.
//!
//! The nearest triangle is the lowest-index one among equally near faces (desal-measures'
//! BVH order), so the matrix is deterministic.

use desal_measures::SurfaceIndex;
use desal_measures::closest_point::closest_point_on_triangle;
use desal_mesh::{Face, Real, TriMesh, Vec3};
use rayon::prelude::*;

/// One sparse row of U: `(coarse_idx, weight)`, weights summing to 1.
pub type Row = Vec<(u32, Real)>;

/// Barycentric rows for every point of `fine` against the coarse surface, in `fine`'s
/// order. `coarse` is the coarse level's template-pose mesh (`coarse_idx` space).
pub fn barycentric_rows(coarse: &TriMesh, fine: &[Vec3]) -> Vec<Row> {
    let surface = SurfaceIndex::new(coarse);
    fine.par_iter()
        .map(|p| {
            let (face, _) = surface.nearest(p).expect("the caller checked the coarse level has faces");
            projection_row(coarse, coarse.faces[face as usize], p)
        })
        .collect()
}

/// The barycentric row of `p`'s closest point on `face` of `coarse`.
pub fn projection_row(coarse: &TriMesh, face: Face, p: &Vec3) -> Row {
    let [a, b, c] = face.map(|v| coarse.positions[v as usize]);
    let q = closest_point_on_triangle(p, &a, &b, &c);
    let weights = barycentric(&q, &a, &b, &c);
    face.into_iter().zip(weights).filter(|&(_, w)| w != 0.0).collect()
}

/// Barycentric coordinates `(u, v, w)` of a point `q` on triangle `(a, b, c)`, summing
/// to one. A corner the point coincides with gets exactly one, and so does the nearest
/// corner of a zero-area triangle.
pub fn barycentric(q: &Vec3, a: &Vec3, b: &Vec3, c: &Vec3) -> [Real; 3] {
    // Exact corners first: Ericson's vertex regions return the corner itself, and COMA
    // puts weight 1 there; the Gram solve would leave rounding residue in the others.
    for (i, corner) in [a, b, c].into_iter().enumerate() {
        if q == corner {
            let mut w = [0.0; 3];
            w[i] = 1.0;
            return w;
        }
    }
    let (e0, e1, d) = (b - a, c - a, q - a);
    let (d00, d01, d11) = (e0.dot(&e0), e0.dot(&e1), e1.dot(&e1));
    let (d20, d21) = (d.dot(&e0), d.dot(&e1));
    let denom = d00 * d11 - d01 * d01;
    if denom <= Real::EPSILON * d00 * d11 || denom <= 0.0 {
        let nearest = [a, b, c]
            .iter()
            .enumerate()
            .min_by(|x, y| (q - *x.1).norm_squared().total_cmp(&(q - *y.1).norm_squared()))
            .map_or(0, |(i, _)| i);
        let mut w = [0.0; 3];
        w[nearest] = 1.0;
        return w;
    }
    let v = (d11 * d20 - d01 * d21) / denom;
    let w = (d00 * d21 - d01 * d20) / denom;
    [1.0 - v - w, v, w]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point inside the unit right triangle has the coordinates read off the axes.
    #[test]
    fn interior_point_coordinates() {
        let (a, b, c) = (Vec3::zeros(), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0));
        let w = barycentric(&Vec3::new(0.25, 0.5, 0.0), &a, &b, &c);
        assert_eq!(w, [0.25, 0.25, 0.5]);
    }

    /// A point above an edge projects onto it: two weights, summing to 1, the third 0.
    #[test]
    fn point_over_an_edge_gets_two_weights() {
        let tri = TriMesh {
            positions: vec![Vec3::zeros(), Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0)],
            faces: vec![[0, 1, 2]],
        };
        let row = projection_row(&tri, [0, 1, 2], &Vec3::new(0.5, -1.0, 3.0));
        assert_eq!(row, vec![(0, 0.75), (1, 0.25)]);
    }

    /// Beyond a corner the projection is the corner: weight exactly 1 (COMA's vertex case).
    #[test]
    fn point_beyond_a_corner_gets_the_corner() {
        let tri = TriMesh {
            positions: vec![Vec3::zeros(), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)],
            faces: vec![[0, 1, 2]],
        };
        assert_eq!(projection_row(&tri, [0, 1, 2], &Vec3::new(3.0, -1.0, 0.5)), vec![(1, 1.0)]);
    }

    /// A zero-area triangle does not divide by zero: the nearest corner takes it all.
    #[test]
    fn degenerate_triangle_falls_back_to_nearest_corner() {
        let (a, b, c) = (Vec3::zeros(), Vec3::new(1.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0));
        assert_eq!(barycentric(&Vec3::new(1.9, 0.0, 0.0), &a, &b, &c), [0.0, 0.0, 1.0]);
    }
}
