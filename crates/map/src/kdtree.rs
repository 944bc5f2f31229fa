//! A small static k-d tree over the original vertices answering exact k-nearest
//! queries: the k smallest `(squared_distance, orig_idx)` pairs, ties included.
//!
//! Why not kiddo (declared in the workspace): kiddo 4.2.1's trees fail on the inputs
//! this stage must handle. `ImmutableKdTree` construction underflows in `calc_pivot` on
//! duplicated or lattice points (sdd-org/kiddo#172), and the mutable `KdTree` panics when
//! more than a bucket of points share a coordinate on one axis (sdd-org/kiddo#78, #158);
//! registered meshes have duplicate vertices and symmetric synthetic bodies have whole
//! planes of equal coordinates. kiddo also breaks distance ties arbitrarily and computes
//! its own distances, so exactness needed a rounding margin. This tree splits by rank (not
//! by value), so any number of equal coordinates is fine; it compares with
//! [`squared_distance`] and orders by `(dist2, orig_idx)`, so its answer is exactly the
//! first k entries of the reference order.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use desal_mesh::Vec3;

/// The squared Euclidean distance both implementations compare, computed in one fixed
/// order so that equal inputs give bit-equal distances and ties are seen alike.
#[inline]
pub fn squared_distance(a: &Vec3, b: &Vec3) -> f64 {
    let (dx, dy, dz) = (a.x - b.x, a.y - b.y, a.z - b.z);
    dx * dx + dy * dy + dz * dz
}

/// Points per leaf. Small leaves keep k = 8 queries cheap; the value only affects speed.
const LEAF_SIZE: usize = 16;

/// A node owns the contiguous range `start..end` of `KdTree::order` and the bounding box
/// of those points. Inner nodes have two children; leaves have `children == None`.
#[derive(Debug, Clone)]
struct Node {
    lo: Vec3,
    hi: Vec3,
    start: u32,
    end: u32,
    children: Option<(u32, u32)>,
}

/// The tree. `order` is a permutation of `orig_idx` values, grouped by node.
#[derive(Debug)]
pub(crate) struct KdTree<'a> {
    points: &'a [Vec3],
    order: Vec<u32>,
    nodes: Vec<Node>,
}

/// A candidate neighbour ordered by `(dist2, orig_idx)`: the max-heap of a query keeps
/// the worst of the k best on top.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Neighbour {
    pub dist2: f64,
    pub orig_idx: u32,
}

impl Ord for Neighbour {
    fn cmp(&self, other: &Self) -> Ordering {
        self.dist2.total_cmp(&other.dist2).then(self.orig_idx.cmp(&other.orig_idx))
    }
}

impl PartialOrd for Neighbour {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl PartialEq for Neighbour {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Neighbour {}

impl<'a> KdTree<'a> {
    /// Builds the tree over `points` (indexed by `orig_idx`). O(m log m).
    pub(crate) fn new(points: &'a [Vec3]) -> Self {
        debug_assert!(points.len() <= u32::MAX as usize);
        let mut tree = Self { points, order: (0..points.len() as u32).collect(), nodes: Vec::new() };
        if !points.is_empty() {
            tree.build_node(0, points.len());
        }
        tree
    }

    /// Appends the node for `order[start..end]` (and its subtree); returns its index.
    fn build_node(&mut self, start: usize, end: usize) -> u32 {
        let (lo, hi) = self.bounding_box(start, end);
        let id = self.nodes.len() as u32;
        self.nodes.push(Node { lo, hi, start: start as u32, end: end as u32, children: None });
        if end - start <= LEAF_SIZE {
            return id;
        }
        // Split the widest axis at the median rank; equal coordinates are ordered by
        // index, so duplicates land on both sides without harm.
        let extent = hi - lo;
        let axis = (0..3).fold(0, |best, a| if extent[a] > extent[best] { a } else { best });
        let points = self.points;
        let mid = (end - start) / 2;
        self.order[start..end].select_nth_unstable_by(mid, |&a, &b| {
            points[a as usize][axis].total_cmp(&points[b as usize][axis]).then(a.cmp(&b))
        });
        let left = self.build_node(start, start + mid);
        let right = self.build_node(start + mid, end);
        self.nodes[id as usize].children = Some((left, right));
        id
    }

    fn bounding_box(&self, start: usize, end: usize) -> (Vec3, Vec3) {
        let first = self.points[self.order[start] as usize];
        self.order[start..end].iter().fold((first, first), |(lo, hi), &o| {
            let p = &self.points[o as usize];
            (lo.inf(p), hi.sup(p))
        })
    }

    /// The `k` smallest `(squared_distance(query, point), orig_idx)` pairs, ascending.
    /// Returns every point when `k >= m`.
    pub(crate) fn nearest(&self, query: &Vec3, k: usize) -> Vec<Neighbour> {
        let mut best = BinaryHeap::with_capacity(k + 1);
        if k > 0 && !self.nodes.is_empty() {
            self.search(0, query, k, &mut best);
        }
        best.into_sorted_vec()
    }

    fn search(&self, node_id: u32, query: &Vec3, k: usize, best: &mut BinaryHeap<Neighbour>) {
        let node = &self.nodes[node_id as usize];
        match node.children {
            None => {
                for &orig_idx in &self.order[node.start as usize..node.end as usize] {
                    let candidate = Neighbour {
                        dist2: squared_distance(query, &self.points[orig_idx as usize]),
                        orig_idx,
                    };
                    if best.len() < k {
                        best.push(candidate);
                    } else if candidate < *best.peek().expect("k > 0") {
                        best.pop();
                        best.push(candidate);
                    }
                }
            }
            Some((left, right)) => {
                let left_bound = self.box_distance(left, query);
                let right_bound = self.box_distance(right, query);
                let (near, near_bound, far, far_bound) = if left_bound <= right_bound {
                    (left, left_bound, right, right_bound)
                } else {
                    (right, right_bound, left, left_bound)
                };
                for (child, bound) in [(near, near_bound), (far, far_bound)] {
                    // Visit a box that could hold a point at the current worst distance too:
                    // an equally far point with a lower index must win the tie.
                    if best.len() < k || bound <= best.peek().expect("k > 0").dist2 {
                        self.search(child, query, k, best);
                    }
                }
            }
        }
    }

    /// Squared distance from `query` to the node's box: a lower bound of
    /// [`squared_distance`] to every point inside, also in floating point, because each
    /// step (subtract, square, add) rounds monotonically.
    fn box_distance(&self, node_id: u32, query: &Vec3) -> f64 {
        let node = &self.nodes[node_id as usize];
        let gap = |a: usize| {
            if query[a] < node.lo[a] {
                node.lo[a] - query[a]
            } else if query[a] > node.hi[a] {
                query[a] - node.hi[a]
            } else {
                0.0
            }
        };
        let (gx, gy, gz) = (gap(0), gap(1), gap(2));
        gx * gx + gy * gy + gz * gz
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The k-nearest answer equals sorting all points by `(dist2, orig_idx)`, on points
    /// with many duplicates and equal coordinates.
    #[test]
    fn nearest_equals_a_full_sort() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for case in 0..100 {
            let m = rng.gen_range(1..300);
            let points: Vec<Vec3> = (0..m)
                .map(|_| {
                    Vec3::new(
                        rng.gen_range(0..3) as f64,
                        rng.gen_range(0..3) as f64,
                        rng.r#gen::<bool>() as u8 as f64,
                    )
                })
                .collect();
            let tree = KdTree::new(&points);
            let query = Vec3::new(rng.gen_range(-1.0..3.0), 1.0, rng.gen_range(0..2) as f64);
            let mut all: Vec<Neighbour> = (0..m as u32)
                .map(|o| Neighbour { dist2: squared_distance(&query, &points[o as usize]), orig_idx: o })
                .collect();
            all.sort();
            for k in [1, 2, 5, 17, m, m + 3] {
                let found = tree.nearest(&query, k);
                let expected = &all[..k.min(m)];
                assert!(
                    found.iter().zip(expected).all(|(a, b)| a.orig_idx == b.orig_idx)
                        && found.len() == expected.len(),
                    "case {case}, k = {k}"
                );
            }
        }
    }
}
