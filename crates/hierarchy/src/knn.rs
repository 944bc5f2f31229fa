//! k nearest points by a uniform grid: the fitted upsampler's candidate coarse vertices.
//!
//! The grid's cells hold about two points each; a query visits rings of cells around its
//! own until the k-th best distance is no farther than the nearest cell it has not
//! visited. Results are exact and ordered by (squared distance, index), so ties go to the
//! lower index and the answer does not depend on the grid.

use desal_mesh::{Real, Vec3};

/// A point cloud bucketed into a uniform grid.
#[derive(Debug, Clone)]
pub struct PointGrid {
    points: Vec<Vec3>,
    lo: Vec3,
    cell: Real,
    dims: [usize; 3],
    /// CSR buckets: points of cell `c` are `order[start[c]..start[c + 1]]`, by index.
    start: Vec<usize>,
    order: Vec<u32>,
}

/// Points per cell the grid aims for: fewer cells to visit against fewer points per cell.
const POINTS_PER_CELL: Real = 2.0;

impl PointGrid {
    pub fn new(points: &[Vec3]) -> Self {
        let (lo, hi) = desal_mesh::math::bounding_box(points).unwrap_or((Vec3::zeros(), Vec3::zeros()));
        let extent = hi - lo;
        // A cube cell whose volume holds POINTS_PER_CELL points on average; flat or
        // degenerate clouds fall back to the largest extent so the cell is never zero.
        let volume = extent.iter().map(|e| e.max(extent.max() * 1e-3)).product::<Real>();
        let mut cell = (volume * POINTS_PER_CELL / points.len().max(1) as Real).cbrt();
        if !(cell.is_finite() && cell > 0.0) {
            cell = 1.0;
        }
        let dims = [0, 1, 2].map(|a| ((extent[a] / cell).floor() as usize + 1).min(1 << 20));
        let cell_of = |p: &Vec3| -> usize {
            let c = [0, 1, 2].map(|a| (((p[a] - lo[a]) / cell).floor().max(0.0) as usize).min(dims[a] - 1));
            (c[2] * dims[1] + c[1]) * dims[0] + c[0]
        };
        let cells = dims[0] * dims[1] * dims[2];
        let mut start = vec![0usize; cells + 1];
        for p in points {
            start[cell_of(p) + 1] += 1;
        }
        for c in 0..cells {
            start[c + 1] += start[c];
        }
        let mut fill = start.clone();
        let mut order = vec![0u32; points.len()];
        for (i, p) in points.iter().enumerate() {
            let c = cell_of(p);
            order[fill[c]] = i as u32;
            fill[c] += 1;
        }
        Self { points: points.to_vec(), lo, cell, dims, start, order }
    }

    /// The `k` points nearest to `q` as `(index, squared distance)`, nearest first, ties
    /// by index; fewer when the cloud has fewer points.
    pub fn nearest(&self, q: &Vec3, k: usize) -> Vec<(u32, Real)> {
        let k = k.min(self.points.len());
        if k == 0 {
            return Vec::new();
        }
        let home = [0, 1, 2].map(|a| {
            let c = ((q[a] - self.lo[a]) / self.cell).floor();
            c.clamp(0.0, (self.dims[a] - 1) as Real) as i64
        });
        let mut found: Vec<(u32, Real)> = Vec::new();
        for ring in 0i64.. {
            self.visit_ring(home, ring, q, &mut found);
            found.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
            found.truncate(k);
            let covered = (0..3).all(|a| home[a] - ring <= 0 && home[a] + ring >= self.dims[a] as i64 - 1);
            if covered || (found.len() == k && found[k - 1].1 <= self.unvisited_distance_sq(home, ring, q)) {
                return found;
            }
        }
        unreachable!("the rings cover the grid after finitely many steps")
    }

    /// Adds every point of the cells at Chebyshev distance exactly `ring` from `home`.
    fn visit_ring(&self, home: [i64; 3], ring: i64, q: &Vec3, found: &mut Vec<(u32, Real)>) {
        let range = |a: usize| (home[a] - ring).max(0)..=(home[a] + ring).min(self.dims[a] as i64 - 1);
        for z in range(2) {
            for y in range(1) {
                for x in range(0) {
                    let on_ring = (x - home[0]).abs() == ring
                        || (y - home[1]).abs() == ring
                        || (z - home[2]).abs() == ring;
                    if !on_ring {
                        continue;
                    }
                    let c = ((z as usize) * self.dims[1] + y as usize) * self.dims[0] + x as usize;
                    for &i in &self.order[self.start[c]..self.start[c + 1]] {
                        found.push((i, (self.points[i as usize] - q).norm_squared()));
                    }
                }
            }
        }
    }

    /// A lower bound on the squared distance from `q` to any cell outside the rings
    /// `0..=ring`: the gap to the nearest face of the visited box that has cells beyond it.
    fn unvisited_distance_sq(&self, home: [i64; 3], ring: i64, q: &Vec3) -> Real {
        let mut gap = Real::INFINITY;
        for a in 0..3 {
            if home[a] - ring > 0 {
                let face = self.lo[a] + (home[a] - ring) as Real * self.cell;
                gap = gap.min(q[a] - face);
            }
            if home[a] + ring < self.dims[a] as i64 - 1 {
                let face = self.lo[a] + (home[a] + ring + 1) as Real * self.cell;
                gap = gap.min(face - q[a]);
            }
        }
        if gap <= 0.0 { 0.0 } else { gap * gap }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn brute_force(points: &[Vec3], q: &Vec3, k: usize) -> Vec<(u32, Real)> {
        let mut all: Vec<(u32, Real)> =
            points.iter().enumerate().map(|(i, p)| (i as u32, (p - q).norm_squared())).collect();
        all.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        all.truncate(k);
        all
    }

    proptest! {
        /// The grid answer is the brute-force answer, including queries outside the
        /// cloud's box (fine vertices off the coarse surface) and flat clouds.
        #[test]
        fn grid_matches_brute_force(
            pts in prop::collection::vec((-1.0f64..1.0, -1.0f64..1.0, -0.01f64..0.01), 1..200),
            qs in prop::collection::vec((-2.0f64..2.0, -2.0f64..2.0, -2.0f64..2.0), 1..20),
            k in 1usize..15,
        ) {
            let points: Vec<Vec3> = pts.iter().map(|&(x, y, z)| Vec3::new(x, y, z)).collect();
            let grid = PointGrid::new(&points);
            for &(x, y, z) in &qs {
                let q = Vec3::new(x, y, z);
                prop_assert_eq!(grid.nearest(&q, k), brute_force(&points, &q, k));
            }
        }
    }

    /// Coincident points: the lowest indices win, in order.
    #[test]
    fn ties_go_to_lower_indices() {
        let points = vec![Vec3::new(1.0, 1.0, 1.0); 5];
        let got = PointGrid::new(&points).nearest(&Vec3::zeros(), 3);
        assert_eq!(got.iter().map(|&(i, _)| i).collect::<Vec<_>>(), vec![0, 1, 2]);
    }
}
