//! Greedy least-distance mapping (Zhao, Ngan, Li, §3.2): pair every simplified template
//! vertex with a distinct original template vertex by repeatedly taking the globally
//! closest free (simplified, original) pair.
//!
//! The rule is the paper's; the tie-break is ours and total: pairs are ordered by
//! `(squared distance, simp_idx, orig_idx)`, squared distances being exact `f64` values
//! from [`squared_distance`]. Two implementations share that order:
//!
//! - [`greedy_map_brute_force`], the reference: it keeps, for every free simplified
//!   vertex, its best free original vertex found by a full scan, and rescans a vertex
//!   only when its best is taken. It reads as the rule and runs in about O(n·m).
//! - [`greedy_map`], the fast one: a k-d tree ([`crate::kdtree`]) gives every simplified
//!   vertex its k nearest original vertices in the same order (queried in parallel), a
//!   min-heap holds each simplified vertex's best still-free candidate, and a vertex whose
//!   candidates are all taken is re-queried with k doubled. About O(n log m + m log m) on
//!   meshes.
//!
//! Both return the same map, ties included; the tests check it on hundreds of random,
//! tied and clustered inputs.

use std::cmp::{Ordering, Reverse};
use std::collections::BinaryHeap;

use desal_mesh::Vec3;
use rayon::prelude::*;

use crate::MapConfig;
use crate::error::MapError;
use crate::kdtree::KdTree;
pub use crate::kdtree::squared_distance;
use crate::vertex_map::VertexMap;

/// A (simplified, original) pair with its squared distance, ordered by
/// `(dist2, simp_idx, orig_idx)`: the greedy rule takes the smallest free pair.
#[derive(Debug, Clone, Copy)]
struct Pair {
    dist2: f64,
    simp_idx: u32,
    orig_idx: u32,
}

impl Ord for Pair {
    fn cmp(&self, other: &Self) -> Ordering {
        self.dist2
            .total_cmp(&other.dist2)
            .then(self.simp_idx.cmp(&other.simp_idx))
            .then(self.orig_idx.cmp(&other.orig_idx))
    }
}

impl PartialOrd for Pair {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl PartialEq for Pair {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Pair {}

/// Maps simplified template vertices to distinct original template vertices by the
/// greedy least-distance rule, fast (k-d tree candidates + heap), with default options.
///
/// Input: `simplified[simp_idx]` and `original[orig_idx]`, in the same units (the pose
/// set's, metres for SCAPE). Output: `simp_to_orig` with one entry per simplified vertex.
/// Equal to [`greedy_map_brute_force`] on every input, ties included.
///
/// Errors: more simplified than original vertices, a non-finite coordinate, or more
/// than `u32::MAX` vertices.
pub fn greedy_map(simplified: &[Vec3], original: &[Vec3]) -> Result<VertexMap, MapError> {
    greedy_map_with(&MapConfig::default(), simplified, original)
}

/// [`greedy_map`] with explicit options.
pub fn greedy_map_with(
    config: &MapConfig,
    simplified: &[Vec3],
    original: &[Vec3],
) -> Result<VertexMap, MapError> {
    check_inputs(simplified, original)?;
    if simplified.is_empty() {
        return Ok(VertexMap { simp_to_orig: Vec::new() });
    }
    let search = CandidateSearch::new(simplified, original);
    let initial_k = config.initial_candidates.clamp(1, original.len());

    // The k-nearest queries are independent: run them in parallel, collected in
    // simp_idx order so the rest is deterministic.
    let mut candidates: Vec<Candidates> = (0..simplified.len() as u32)
        .into_par_iter()
        .map(|simp_idx| search.query(simp_idx, initial_k))
        .collect();

    let mut orig_taken = vec![false; original.len()];
    let mut heap = BinaryHeap::with_capacity(simplified.len());
    for simp_idx in 0..simplified.len() as u32 {
        push_best_free(&search, &mut candidates[simp_idx as usize], &orig_taken, &mut heap);
    }

    let simp_to_orig = assign_closest_pairs(&search, &mut candidates, &mut orig_taken, &mut heap);
    debug_assert!(VertexMap::try_new(simp_to_orig.clone(), original.len()).is_ok());
    Ok(VertexMap { simp_to_orig })
}

/// The reference implementation of the greedy rule, documented as such and used by the
/// tests and benchmarks to check [`greedy_map`].
///
/// It holds, for every free simplified vertex, its best free original vertex
/// (smallest `(dist2, orig_idx)`, found by scanning all original vertices); each step
/// takes the smallest `(dist2, simp_idx, orig_idx)` among those, which is the globally
/// closest free pair, records it, and rescans the simplified vertices whose best was
/// just taken. O(n·m) for the first scan plus the rescans; no tree, no pruning.
///
/// Same inputs, output and errors as [`greedy_map`].
pub fn greedy_map_brute_force(simplified: &[Vec3], original: &[Vec3]) -> Result<VertexMap, MapError> {
    check_inputs(simplified, original)?;
    let mut orig_taken = vec![false; original.len()];
    let best_free = |simp_idx: u32, orig_taken: &[bool]| -> Pair {
        let s = &simplified[simp_idx as usize];
        let mut best: Option<Pair> = None;
        for (orig_idx, o) in original.iter().enumerate() {
            if orig_taken[orig_idx] {
                continue;
            }
            let pair = Pair { dist2: squared_distance(s, o), simp_idx, orig_idx: orig_idx as u32 };
            if best.is_none_or(|b| pair < b) {
                best = Some(pair);
            }
        }
        best.expect("a free original vertex exists while simplified vertices are free")
    };

    // `best[simp_idx]` is `None` once the simplified vertex is mapped.
    let mut best: Vec<Option<Pair>> =
        (0..simplified.len() as u32).into_par_iter().map(|s| Some(best_free(s, &orig_taken))).collect();
    let mut simp_to_orig = vec![u32::MAX; simplified.len()];
    for _ in 0..simplified.len() {
        let closest = best.iter().flatten().min().copied().expect("a free simplified vertex remains");
        simp_to_orig[closest.simp_idx as usize] = closest.orig_idx;
        orig_taken[closest.orig_idx as usize] = true;
        best[closest.simp_idx as usize] = None;
        for entry in best.iter_mut().flatten() {
            if entry.orig_idx == closest.orig_idx {
                *entry = best_free(entry.simp_idx, &orig_taken);
            }
        }
    }
    Ok(VertexMap { simp_to_orig })
}

/// Rejects inputs the greedy rule cannot map: too few original vertices, indices past
/// `u32`, non-finite coordinates (they would make distances meaningless).
fn check_inputs(simplified: &[Vec3], original: &[Vec3]) -> Result<(), MapError> {
    if simplified.len() > original.len() {
        return Err(MapError::TooFewOriginalVertices {
            simplified: simplified.len(),
            original: original.len(),
        });
    }
    if original.len() > u32::MAX as usize {
        return Err(MapError::TooManyVertices { count: original.len() });
    }
    if let Some((i, p)) = first_non_finite(simplified) {
        return Err(MapError::NonFiniteSimplified { simp_idx: i as u32, x: p.x, y: p.y, z: p.z });
    }
    if let Some((i, p)) = first_non_finite(original) {
        return Err(MapError::NonFiniteOriginal { orig_idx: i as u32, x: p.x, y: p.y, z: p.z });
    }
    Ok(())
}

fn first_non_finite(points: &[Vec3]) -> Option<(usize, &Vec3)> {
    points.iter().enumerate().find(|(_, p)| !p.iter().all(|c| c.is_finite()))
}

/// The greedy loop: pop the smallest pair; if its original vertex is still free it is
/// the globally closest free pair (every other heap entry is a lower bound for its
/// simplified vertex), so record it; otherwise refresh that simplified vertex's entry.
fn assign_closest_pairs(
    search: &CandidateSearch,
    candidates: &mut [Candidates],
    orig_taken: &mut [bool],
    heap: &mut BinaryHeap<Reverse<Pair>>,
) -> Vec<u32> {
    let mut simp_to_orig = vec![u32::MAX; candidates.len()];
    while let Some(Reverse(pair)) = heap.pop() {
        if orig_taken[pair.orig_idx as usize] {
            push_best_free(search, &mut candidates[pair.simp_idx as usize], orig_taken, heap);
            continue;
        }
        simp_to_orig[pair.simp_idx as usize] = pair.orig_idx;
        orig_taken[pair.orig_idx as usize] = true;
    }
    debug_assert!(simp_to_orig.iter().all(|&o| o != u32::MAX));
    simp_to_orig
}

/// Pushes the simplified vertex's best free candidate onto the heap, widening its
/// candidate set (k doubled) until a free candidate exists. One always does:
/// fewer original vertices are taken than there are simplified vertices, so at k = m
/// some original vertex is free.
fn push_best_free(
    search: &CandidateSearch,
    cands: &mut Candidates,
    orig_taken: &[bool],
    heap: &mut BinaryHeap<Reverse<Pair>>,
) {
    loop {
        while let Some(pair) = cands.nearest.get(cands.cursor) {
            if !orig_taken[pair.orig_idx as usize] {
                heap.push(Reverse(*pair));
                return;
            }
            cands.cursor += 1;
        }
        debug_assert!(cands.k < search.original.len(), "at k = m every original vertex is a candidate");
        *cands = search.query(cands.simp_idx, (cands.k * 2).min(search.original.len()));
    }
}

/// The k nearest original vertices of one simplified vertex, sorted by
/// `(dist2, orig_idx)`: exactly the first k of that order over all original vertices,
/// so the first free entry is the vertex's best free original vertex.
#[derive(Debug)]
struct Candidates {
    simp_idx: u32,
    k: usize,
    nearest: Vec<Pair>,
    /// Entries before `cursor` are known to be taken.
    cursor: usize,
}

/// The k-d tree over the original vertices and the points it answers for.
#[derive(Debug)]
struct CandidateSearch<'a> {
    simplified: &'a [Vec3],
    original: &'a [Vec3],
    tree: KdTree<'a>,
}

impl<'a> CandidateSearch<'a> {
    fn new(simplified: &'a [Vec3], original: &'a [Vec3]) -> Self {
        Self { simplified, original, tree: KdTree::new(original) }
    }

    fn query(&self, simp_idx: u32, k: usize) -> Candidates {
        let nearest = self
            .tree
            .nearest(&self.simplified[simp_idx as usize], k)
            .into_iter()
            .map(|n| Pair { dist2: n.dist2, simp_idx, orig_idx: n.orig_idx })
            .collect();
        Candidates { simp_idx, k, nearest, cursor: 0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points(coords: &[[f64; 3]]) -> Vec<Vec3> {
        coords.iter().map(|c| Vec3::new(c[0], c[1], c[2])).collect()
    }

    /// The globally closest pair goes first, even when it steals another vertex's
    /// nearest: s1 takes o0 (0.1 away), so s0 (0.2 from o0) falls back to o1.
    #[test]
    fn closest_pair_goes_first() {
        let simplified = points(&[[0.2, 0.0, 0.0], [-0.1, 0.0, 0.0]]);
        let original = points(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [-5.0, 0.0, 0.0]]);
        for map in [greedy_map(&simplified, &original), greedy_map_brute_force(&simplified, &original)] {
            assert_eq!(map.unwrap().simp_to_orig, vec![1, 0]);
        }
    }

    /// Equal distances: the lower simp_idx picks first, and it picks the lower orig_idx.
    #[test]
    fn ties_go_to_the_lower_indices() {
        let simplified = points(&[[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]);
        let original = points(&[[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]);
        for map in [greedy_map(&simplified, &original), greedy_map_brute_force(&simplified, &original)] {
            assert_eq!(map.unwrap().simp_to_orig, vec![0, 1]);
        }
    }

    #[test]
    fn too_few_original_vertices_is_an_error() {
        let simplified = points(&[[0.0; 3], [1.0; 3]]);
        let original = points(&[[0.0; 3]]);
        let expected = MapError::TooFewOriginalVertices { simplified: 2, original: 1 };
        assert_eq!(greedy_map(&simplified, &original).unwrap_err(), expected);
        assert_eq!(greedy_map_brute_force(&simplified, &original).unwrap_err(), expected);
    }

    #[test]
    fn non_finite_coordinates_name_the_vertex() {
        let good = points(&[[0.0; 3], [1.0; 3], [2.0; 3]]);
        let mut bad = good.clone();
        bad[2].y = f64::NAN;
        assert!(matches!(greedy_map(&bad, &good), Err(MapError::NonFiniteSimplified { simp_idx: 2, .. })));
        bad[2].y = f64::INFINITY;
        assert!(matches!(
            greedy_map_brute_force(&good, &bad),
            Err(MapError::NonFiniteOriginal { orig_idx: 2, .. })
        ));
    }

    #[test]
    fn empty_simplified_maps_to_nothing() {
        assert!(greedy_map(&[], &points(&[[0.0; 3]])).unwrap().is_empty());
        assert!(greedy_map(&[], &[]).unwrap().is_empty());
    }
}
