//! A uniform grid over primitive boxes, for exact nearest-primitive queries that start
//! from a good guess.
//!
//! `desal eval` measures meshes against meshes they nearly coincide with (a deformation
//! or an upsampling against its truth, with the same vertices), so every query comes
//! with a *seed*: a primitive already near it (a face of the corresponding vertex), whose
//! exact distance bounds the answer. What is left is proving that nothing else is
//! nearer, and for a small bound that is a handful of grid cells — where the
//! [`crate::bvh::Bvh`] walks a root-to-leaf path and scans whole leaves for the same
//! proof. A query whose bound spans too many cells is handed back to the caller (the
//! BVH answers it, from the same bound).
//!
//! Exactness: a primitive is skipped only when its box is strictly farther than the best
//! exact distance so far (the BVH's rule), and every primitive whose box is within the
//! bound is registered in a cell the query visits. Cell indices are a monotone function
//! of the coordinate (`floor((x − origin) · 1/h)`, clamped), so a box and the query's
//! cube that overlap share a cell; the cube is widened by a margin far above rounding.
//! Among equally near primitives the lowest index wins, as in the BVH, so both answer
//! the same `(index, distance)` bit for bit.

use desal_mesh::{Real, Vec3};

use crate::bvh::Aabb;

/// Most cells one query may visit before it is handed back to the BVH: beyond that the
/// bound is loose and the tree prunes better.
const MAX_CELLS: usize = 27;

/// Most cells per primitive the grid may hold (it grows its cell size until it fits):
/// bounds the memory of a grid over a few large primitives.
const MAX_CELLS_PER_PRIMITIVE: usize = 16;

/// A grid of cubic cells, each listing the primitives whose boxes overlap it.
#[derive(Debug, Clone)]
pub(crate) struct Grid {
    origin: Vec3,
    inv_cell: Real,
    dims: [usize; 3],
    /// Cell `c` holds `entries[starts[c]..starts[c + 1]]`, in primitive order.
    starts: Vec<u32>,
    entries: Vec<u32>,
    /// Primitive `i`'s box (each stored once, however many cells list it).
    boxes: Vec<Aabb>,
    /// Absolute widening of a query's cube, far above the rounding of its coordinates.
    margin: Real,
}

impl Grid {
    /// A grid over `boxes[i]`, the bounds of primitive `i`, with cells of about `cell`
    /// (grown when the grid would be too large). `None` when there is nothing to index
    /// or a box is not finite.
    pub(crate) fn build(boxes: &[Aabb], cell: Real) -> Option<Self> {
        let bounds = boxes.iter().fold(Aabb::empty(), |b, x| b.union(x));
        let finite = |v: &Vec3| v.iter().all(|c| c.is_finite());
        if boxes.is_empty() || !finite(&bounds.lo) || !finite(&bounds.hi) {
            return None;
        }
        let extent = bounds.hi - bounds.lo;
        let scale = bounds.lo.abs().sup(&bounds.hi.abs()).max();
        let mut cell = if cell.is_finite() && cell > 0.0 { cell } else { extent.max().max(scale).max(1.0) };
        let dims = loop {
            let dims = extent.map(|e| (e / cell).floor() as usize + 1);
            let total = dims[0].saturating_mul(dims[1]).saturating_mul(dims[2]);
            if total <= MAX_CELLS_PER_PRIMITIVE * boxes.len() + 1 {
                break [dims[0], dims[1], dims[2]];
            }
            cell *= 1.5;
        };
        let mut grid = Self {
            origin: bounds.lo,
            inv_cell: 1.0 / cell,
            dims,
            starts: Vec::new(),
            entries: Vec::new(),
            boxes: boxes.to_vec(),
            margin: 1e-12 * scale.max(Real::MIN_POSITIVE),
        };
        let cell_count = dims[0] * dims[1] * dims[2];
        let mut counts = vec![0u32; cell_count + 1];
        let ranges: Vec<[(usize, usize); 3]> = boxes.iter().map(|b| grid.cell_range(&b.lo, &b.hi)).collect();
        for r in &ranges {
            grid.for_cells(r, |c| counts[c + 1] += 1);
        }
        for c in 0..cell_count {
            counts[c + 1] += counts[c];
        }
        let total = counts[cell_count] as usize;
        let mut next = counts.clone();
        let mut entries = vec![0u32; total];
        // Primitives in increasing index, so each cell lists them in order.
        for (i, r) in ranges.iter().enumerate() {
            grid.for_cells(r, |c| {
                let k = next[c] as usize;
                entries[k] = i as u32;
                next[c] += 1;
            });
        }
        grid.starts = counts;
        grid.entries = entries;
        Some(grid)
    }

    /// The cell index of coordinate `x` along `axis`: monotone in `x`, clamped to the grid.
    fn cell_of(&self, x: Real, axis: usize) -> usize {
        let t = (x - self.origin[axis]) * self.inv_cell;
        // For t > 0 the cast truncates, which is the floor (and no libm call); through
        // i64, which x86 converts in one instruction where u64 takes a branchy sequence
        // (the same value: a positive t saturates at i64::MAX, then the clamp).
        if t <= 0.0 { 0 } else { (t as i64 as usize).min(self.dims[axis] - 1) }
    }

    /// Per axis, the first and last cell overlapping `[lo, hi]`.
    fn cell_range(&self, lo: &Vec3, hi: &Vec3) -> [(usize, usize); 3] {
        let axis = |a: usize| (self.cell_of(lo[a], a), self.cell_of(hi[a], a));
        [axis(0), axis(1), axis(2)]
    }

    fn for_cells(&self, range: &[(usize, usize); 3], mut f: impl FnMut(usize)) {
        for z in range[2].0..=range[2].1 {
            for y in range[1].0..=range[1].1 {
                let row = (z * self.dims[1] + y) * self.dims[0];
                for x in range[0].0..=range[0].1 {
                    f(row + x);
                }
            }
        }
    }

    /// The primitive nearest to `p` as `(index, squared distance)`, starting from `best`
    /// (a primitive and its exact distance, e.g. a seed), where `distance_sq(i)` is the
    /// exact squared distance from `p` to primitive `i`; with `has_boxes` false every
    /// box is a point whose box distance is the exact one. `None` when the bound is too
    /// loose for the grid (the caller asks the BVH, from the same `best`).
    pub(crate) fn nearest(
        &self,
        p: &Vec3,
        best: (u32, Real),
        has_boxes: bool,
        distance_sq: impl Fn(u32) -> Real,
    ) -> Result<(u32, Real), (u32, Real)> {
        let mut best = best;
        if !best.1.is_finite() {
            return Err(best);
        }
        let scan = |c: usize, best: &mut (u32, Real)| {
            let (start, end) = (self.starts[c] as usize, self.starts[c + 1] as usize);
            for &prim in &self.entries[start..end] {
                let box_d = self.boxes[prim as usize].distance_sq(p);
                // Strictly farther than the best: it can neither win nor tie.
                if box_d > best.1 {
                    continue;
                }
                let d = if has_boxes { distance_sq(prim) } else { box_d };
                if d < best.1 || (d == best.1 && prim < best.0) {
                    *best = (prim, d);
                }
            }
        };
        // The cell holding `p` first: it usually holds the answer, and the bound it
        // leaves decides how many neighbours must be looked at.
        let own = [self.cell_of(p[0], 0), self.cell_of(p[1], 1), self.cell_of(p[2], 2)];
        let own_cell = (own[2] * self.dims[1] + own[1]) * self.dims[0] + own[0];
        scan(own_cell, &mut best);
        // The cube holds every box within the bound: widened relatively and absolutely,
        // far beyond the rounding of `p ± r`.
        let slack = self.margin + 1e-12 * p.abs().max();
        let r = best.1.sqrt() * (1.0 + 1e-9) + slack;
        let offset = Vec3::repeat(r);
        let range = self.cell_range(&(p - offset), &(p + offset));
        let cells: usize = range.iter().map(|(a, b)| b - a + 1).product();
        if cells > MAX_CELLS {
            return Err(best);
        }
        if cells == 1 {
            return Ok(best);
        }
        // A cell's gap to `p` along one axis, shrunk by the slack so that rounding can
        // only make it look nearer.
        let cell = 1.0 / self.inv_cell;
        let gap = |axis: usize, i: usize| {
            let lo = self.origin[axis] + i as Real * cell;
            let (below, above) = (lo - p[axis], p[axis] - (lo + cell));
            let g = if below > above { below } else { above } - slack;
            if g > 0.0 { g } else { 0.0 }
        };
        for z in range[2].0..=range[2].1 {
            let gz = gap(2, z);
            for y in range[1].0..=range[1].1 {
                let gy = gap(1, y);
                let row = (z * self.dims[1] + y) * self.dims[0];
                for x in range[0].0..=range[0].1 {
                    let c = row + x;
                    let gx = gap(0, x);
                    if c == own_cell || (gx * gx + gy * gy + gz * gz) * (1.0 - 1e-9) > best.1 {
                        continue;
                    }
                    scan(c, &mut best);
                }
            }
        }
        Ok(best)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// From any seed, the grid (when it answers) finds what a linear scan finds.
    #[test]
    fn seeded_nearest_matches_linear_scan() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut random =
            || Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
        let cloud: Vec<Vec3> = (0..800).map(|_| random()).collect();
        let boxes: Vec<Aabb> = cloud.iter().map(|p| Aabb { lo: *p, hi: *p }).collect();
        let grid = Grid::build(&boxes, 0.1).unwrap();
        let mut answered = 0;
        for k in 0..400 {
            let q = cloud[k] + random() * 0.05;
            let seed = (k as u32 + 1) % 800;
            let d = |i: u32| (cloud[i as usize] - q).norm_squared();
            let want = (0..cloud.len() as u32)
                .map(|i| (i, d(i)))
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
                .unwrap();
            let near_seed = (0..cloud.len() as u32).filter(|&i| (cloud[i as usize] - q).norm() < 0.02).min();
            for seed in [seed, near_seed.unwrap_or(seed)] {
                if let Ok(got) = grid.nearest(&q, (seed, d(seed)), false, d) {
                    assert_eq!(got, want);
                    answered += 1;
                }
            }
        }
        assert!(answered > 300, "the grid answered only {answered} queries");
    }
}
