//! A compact bounding-volume hierarchy for exact nearest-primitive queries.
//!
//! One structure serves both metrics: over triangles (point-to-surface distance, v2f) and
//! over points (nearest vertex, v2v). It is built once per mesh by median splits of the
//! primitive centroids along the longest axis (leaves of at most [`LEAF_SIZE`]
//! primitives) and queried depth-first, nearer child first, pruning a node whose box is
//! farther than the best distance found so far, and in a leaf skipping a primitive whose
//! own box is. A tree built for one pose of a mesh can be refitted to another pose's
//! boxes instead of rebuilt. Pruning is strict (`>`), so among
//! primitives at exactly the same distance the lowest primitive index wins: results do
//! not depend on build order or thread count.

use desal_mesh::{Real, Vec3};

/// Primitives per leaf. Large, because a leaf is scanned through its primitives' boxes
/// (contiguous, a few flops each) while every inner node costs a stack entry and two
/// scattered boxes: v2f of a synthesised SCAPE pose against its truth (25 k queries into
/// 25 k triangles, `cargo bench -p desal-measures --bench eval`) took 65 ms with 4 per leaf
/// and 36 ms with 32, same load.
const LEAF_SIZE: usize = 32;

/// An axis-aligned box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Aabb {
    pub lo: Vec3,
    pub hi: Vec3,
}

impl Aabb {
    pub(crate) fn empty() -> Self {
        Self { lo: Vec3::repeat(Real::INFINITY), hi: Vec3::repeat(Real::NEG_INFINITY) }
    }

    pub(crate) fn of_points(points: &[Vec3]) -> Self {
        points.iter().fold(Self::empty(), |b, p| b.grown(p))
    }

    fn grown(self, p: &Vec3) -> Self {
        Self { lo: self.lo.inf(p), hi: self.hi.sup(p) }
    }

    pub(crate) fn union(self, other: &Self) -> Self {
        Self { lo: self.lo.inf(&other.lo), hi: self.hi.sup(&other.hi) }
    }

    fn centre(&self) -> Vec3 {
        (self.lo + self.hi) * 0.5
    }

    /// Squared distance from `p` to the box (0 inside): each axis's gap, squared and
    /// summed x, y, z, so for a point box it is the exact squared distance to the point.
    /// The hot loop of every search, written out: the maxima are comparisons, not
    /// `f64::max` (whose NaN rule costs instructions), the same for the finite
    /// coordinates the indices hold (a signed zero squares to the same 0).
    #[inline]
    pub(crate) fn distance_sq(&self, p: &Vec3) -> Real {
        let gap = |a: usize| {
            let (below, above) = (self.lo[a] - p[a], p[a] - self.hi[a]);
            let g = if below > above { below } else { above };
            if g > 0.0 { g } else { 0.0 }
        };
        let (x, y, z) = (gap(0), gap(1), gap(2));
        x * x + y * y + z * z
    }
}

/// A node: `count > 0` is a leaf holding `order[first..first + count]`; `count == 0` is
/// an inner node whose left child is the next node and whose right child is `first`.
#[derive(Debug, Clone, Copy)]
struct Node {
    bounds: Aabb,
    first: u32,
    count: u32,
}

/// A BVH over primitives given by their bounding boxes, indexed `0..n` in the caller's
/// primitive space.
#[derive(Debug, Clone)]
pub(crate) struct Bvh {
    nodes: Vec<Node>,
    /// Primitive indices, permuted so that every leaf is a contiguous range.
    order: Vec<u32>,
    /// `boxes[order[k]]`: each primitive's box in leaf order, tested before the exact
    /// distance; empty when every box is a point (its box distance *is* the exact one).
    leaf_boxes: Vec<Aabb>,
}

impl Bvh {
    /// Builds the hierarchy over `boxes[i]`, the bounds of primitive `i`.
    pub(crate) fn build(boxes: &[Aabb]) -> Self {
        let mut order: Vec<u32> = (0..boxes.len() as u32).collect();
        let centres: Vec<Vec3> = boxes.iter().map(Aabb::centre).collect();
        let mut nodes = Vec::with_capacity(2 * boxes.len().div_ceil(LEAF_SIZE) + 1);
        if !boxes.is_empty() {
            build_node(&mut nodes, &mut order, 0, boxes, &centres);
        }
        let leaf_boxes = leaf_boxes(&order, boxes);
        Self { nodes, order, leaf_boxes }
    }

    /// The same tree over new bounds of the same primitives (`boxes[i]` of primitive `i`,
    /// as many as were built): every node's box is recomputed bottom up, nothing is
    /// sorted again. Queries stay exact whatever the new boxes, since the tree only groups
    /// primitive indices; they stay fast while the primitives keep their neighbours, as
    /// one mesh's triangles do from a pose to a nearby one.
    ///
    /// Panics when `boxes` has another length than the primitives built on.
    pub(crate) fn refitted(&self, boxes: &[Aabb]) -> Self {
        assert_eq!(boxes.len(), self.order.len(), "a refit keeps the primitive count");
        let mut nodes = self.nodes.clone();
        // Children come after their parent (left at `idx + 1`, right at `first`), so a
        // reverse sweep sees both children's new boxes before the parent.
        for idx in (0..nodes.len()).rev() {
            let Node { first, count, .. } = nodes[idx];
            nodes[idx].bounds = if count > 0 {
                let leaf = &self.order[first as usize..(first + count) as usize];
                leaf.iter().fold(Aabb::empty(), |b, &i| b.union(&boxes[i as usize]))
            } else {
                nodes[idx + 1].bounds.union(&nodes[first as usize].bounds)
            };
        }
        Self { nodes, leaf_boxes: leaf_boxes(&self.order, boxes), order: self.order.clone() }
    }

    /// The primitive nearest to `p` as `(index, squared distance)`, where
    /// `distance_sq(i)` is the exact squared distance from `p` to primitive `i`. `None`
    /// when there are no primitives.
    pub(crate) fn nearest(&self, p: &Vec3, distance_sq: impl Fn(u32) -> Real) -> Option<(u32, Real)> {
        self.nearest_from(p, None, distance_sq)
    }

    /// [`Bvh::nearest`] starting from `best`, a primitive and its exact distance (a seed):
    /// the same answer, since the search only ever keeps the nearer of two candidates.
    pub(crate) fn nearest_from(
        &self,
        p: &Vec3,
        mut best: Option<(u32, Real)>,
        distance_sq: impl Fn(u32) -> Real,
    ) -> Option<(u32, Real)> {
        let root = self.nodes.first()?;
        // A node or primitive is pruned only when strictly farther than the best, so
        // every primitive at the best distance is still compared (lowest index wins).
        let pruned = |best: Option<(u32, Real)>, d: Real| best.is_some_and(|(_, b)| d > b);
        // Median splits keep the depth at most ⌈log₂ n⌉ + 1 ≤ 33 for `u32` indices, and
        // the stack never holds more than one entry per level plus one.
        let mut stack = [(0u32, 0.0); STACK_DEPTH];
        stack[0] = (0, root.bounds.distance_sq(p));
        let mut len = 1;
        while len > 0 {
            len -= 1;
            let (node_idx, box_d2) = stack[len];
            if pruned(best, box_d2) {
                continue;
            }
            let node = &self.nodes[node_idx as usize];
            if node.count > 0 {
                let range = node.first as usize..(node.first + node.count) as usize;
                for k in range {
                    // A primitive's box is a lower bound of its distance and costs a
                    // fraction of the exact test.
                    if !self.leaf_boxes.is_empty() && pruned(best, self.leaf_boxes[k].distance_sq(p)) {
                        continue;
                    }
                    let prim = self.order[k];
                    let d = distance_sq(prim);
                    let better = match best {
                        None => true,
                        Some((best_prim, best_d)) => d < best_d || (d == best_d && prim < best_prim),
                    };
                    if better {
                        best = Some((prim, d));
                    }
                }
                continue;
            }
            let (left, right) = (node_idx + 1, node.first);
            let dl = self.nodes[left as usize].bounds.distance_sq(p);
            let dr = self.nodes[right as usize].bounds.distance_sq(p);
            // Push the farther child first so the nearer one is explored first; a child
            // already farther than the best is not pushed at all (it would be skipped).
            let (near, far) = if dl <= dr { ((left, dl), (right, dr)) } else { ((right, dr), (left, dl)) };
            for (child, d) in [far, near] {
                if !pruned(best, d) {
                    stack[len] = (child, d);
                    len += 1;
                }
            }
        }
        best
    }
}

/// Each primitive's box in leaf order (`boxes[order[k]]`), or none when every box is a
/// point.
fn leaf_boxes(order: &[u32], boxes: &[Aabb]) -> Vec<Aabb> {
    if boxes.iter().all(|b| b.lo == b.hi) {
        return Vec::new();
    }
    order.iter().map(|&i| boxes[i as usize]).collect()
}

/// Capacity of [`Bvh::nearest`]'s traversal stack (see the comment there).
const STACK_DEPTH: usize = 64;

/// Builds the subtree over `order[offset..offset + len]` (the slice passed in), appending
/// nodes depth-first; returns the new node's index.
fn build_node(
    nodes: &mut Vec<Node>,
    order: &mut [u32],
    offset: usize,
    boxes: &[Aabb],
    centres: &[Vec3],
) -> u32 {
    let bounds = order.iter().fold(Aabb::empty(), |b, &i| b.union(&boxes[i as usize]));
    let node_idx = nodes.len() as u32;
    nodes.push(Node { bounds, first: offset as u32, count: order.len() as u32 });
    if order.len() <= LEAF_SIZE {
        return node_idx;
    }

    let spread = order.iter().fold(Aabb::empty(), |b, &i| b.grown(&centres[i as usize]));
    let extent = spread.hi - spread.lo;
    let axis = extent.imax();
    let mid = order.len() / 2;
    // Ties on the coordinate are broken by primitive index so the tree is a pure
    // function of the input.
    order.select_nth_unstable_by(mid, |&a, &b| {
        centres[a as usize][axis].total_cmp(&centres[b as usize][axis]).then(a.cmp(&b))
    });
    let (left, right) = order.split_at_mut(mid);
    build_node(nodes, left, offset, boxes, centres);
    let right_idx = build_node(nodes, right, offset + mid, boxes, centres);
    nodes[node_idx as usize].first = right_idx;
    nodes[node_idx as usize].count = 0;
    node_idx
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Nearest point of a random cloud, against a linear scan with the same tie rule.
    #[test]
    fn nearest_point_matches_linear_scan() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let mut random =
            || Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
        let cloud: Vec<Vec3> = (0..500).map(|_| random()).collect();
        let boxes: Vec<Aabb> = cloud.iter().map(|p| Aabb { lo: *p, hi: *p }).collect();
        let bvh = Bvh::build(&boxes);
        for _ in 0..200 {
            let q = random() * 1.5;
            let got = bvh.nearest(&q, |i| (cloud[i as usize] - q).norm_squared()).unwrap();
            let want = (0..cloud.len())
                .map(|i| (i as u32, (cloud[i] - q).norm_squared()))
                .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))
                .unwrap();
            assert_eq!(got, want);
        }
    }

    /// A tree refitted to moved points answers as a tree built on them.
    #[test]
    fn refitted_tree_matches_a_fresh_build() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut random =
            || Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
        let cloud: Vec<Vec3> = (0..300).map(|_| random()).collect();
        let moved: Vec<Vec3> =
            cloud.iter().map(|p| p.component_mul(&Vec3::new(2.0, -1.0, 0.5)) + random() * 0.3).collect();
        let boxes = |points: &[Vec3]| points.iter().map(|p| Aabb { lo: *p, hi: *p }).collect::<Vec<_>>();
        let refitted = Bvh::build(&boxes(&cloud)).refitted(&boxes(&moved));
        let fresh = Bvh::build(&boxes(&moved));
        for _ in 0..200 {
            let q = random() * 2.0;
            let d = |i: u32| (moved[i as usize] - q).norm_squared();
            assert_eq!(refitted.nearest(&q, d), fresh.nearest(&q, d));
        }
    }

    /// Many coincident points: the lowest index must win the tie.
    #[test]
    fn coincident_points_resolve_to_lowest_index() {
        let cloud = vec![Vec3::new(1.0, 2.0, 3.0); 37];
        let boxes: Vec<Aabb> = cloud.iter().map(|p| Aabb { lo: *p, hi: *p }).collect();
        let bvh = Bvh::build(&boxes);
        let q = Vec3::zeros();
        assert_eq!(bvh.nearest(&q, |i| (cloud[i as usize] - q).norm_squared()), Some((0, 14.0)));
    }

    #[test]
    fn empty_hierarchy_has_no_nearest() {
        let bvh = Bvh::build(&[]);
        assert_eq!(bvh.nearest(&Vec3::zeros(), |_| 0.0), None);
    }
}
