//! The coarse-to-fine half of discovery: cut the template into many small patches
//! (farthest-point seeds, geodesic Voronoi cells along the mesh's edges), then merge
//! adjacent parts bottom-up, always the pair whose union adds the least to the summed
//! squared rigid-fit residual (Ward's criterion, with stage 1's rigid fit as the
//! "centroid"). Moments add up, so a merge's cost is exact and needs no per-vertex
//! work. Replaying the first merges gives the parts at every count.

use std::cmp::Reverse;
use std::collections::{BTreeSet, BinaryHeap};

use desal_mesh::math::{Real, Vec3};
use rayon::prelude::*;

use crate::graph::VertexGraph;
use crate::motion::{Moments, PoseData};

/// Patch id per vertex: `patches` farthest-point seeds (the first one of each initial
/// piece is its smallest vertex; each next one the vertex farthest along the edges from
/// every seed so far, ties by index), every vertex in the cell of its nearest seed.
/// Returns the patch ids and their count (fewer when the mesh has fewer vertices).
pub(crate) fn cut_patches(
    graph: &VertexGraph,
    positions: &[Vec3],
    pieces: &[u32],
    patches: usize,
) -> (Vec<u32>, usize) {
    let n = positions.len();
    let mut distance = vec![Real::INFINITY; n];
    let mut owner = vec![u32::MAX; n];
    let mut seeds = 0u32;
    let grow = |seed: usize, distance: &mut [Real], owner: &mut [u32], id: u32| {
        // Dijkstra from one seed, touching only vertices it brings closer.
        let mut heap = BinaryHeap::new();
        distance[seed] = 0.0;
        owner[seed] = id;
        heap.push(Reverse((0u64, seed as u32)));
        while let Some(Reverse((bits, v))) = heap.pop() {
            let d = Real::from_bits(bits);
            if d > distance[v as usize] {
                continue;
            }
            for &u in graph.around(v as usize) {
                let nd = d + (positions[u as usize] - positions[v as usize]).norm();
                if nd < distance[u as usize] {
                    distance[u as usize] = nd;
                    owner[u as usize] = id;
                    heap.push(Reverse((nd.to_bits(), u)));
                }
            }
        }
    };
    // One seed per piece first, so every piece has a patch.
    let mut first_of_piece = vec![usize::MAX; pieces.iter().map(|&p| p as usize + 1).max().unwrap_or(0)];
    for (v, &p) in pieces.iter().enumerate() {
        if first_of_piece[p as usize] == usize::MAX {
            first_of_piece[p as usize] = v;
        }
    }
    for &seed in &first_of_piece {
        grow(seed, &mut distance, &mut owner, seeds);
        seeds += 1;
    }
    while (seeds as usize) < patches.min(n) {
        let far = (0..n).fold(0, |best, v| if distance[v] > distance[best] { v } else { best });
        if distance[far] <= 0.0 {
            break;
        }
        grow(far, &mut distance, &mut owner, seeds);
        seeds += 1;
    }
    (owner, seeds as usize)
}

/// A candidate merge in the heap: (cost bits, a, b, a's version, b's version), `a < b`.
/// Non-negative costs order like their bits; a pair whose versions are stale is skipped.
type Candidate = (u64, u32, u32, u32, u32);

/// The bottom-up merge sequence of the patches: `merges[i] = (kept, absorbed)` patch
/// ids, cheapest first (ties by the id pair). Stops when no two parts are adjacent.
pub(crate) fn merge_sequence(
    data: &PoseData,
    graph: &VertexGraph,
    patch: &[u32],
    patch_count: usize,
) -> Vec<(u32, u32)> {
    let mut members = vec![Vec::new(); patch_count];
    for (v, &p) in patch.iter().enumerate() {
        members[p as usize].push(v as u32);
    }
    let mut moments: Vec<Moments> = members.par_iter().map(|m| Moments::of(data, m)).collect();
    let mut error: Vec<Real> = moments.par_iter().map(Moments::squared_error).collect();
    let mut neighbours: Vec<BTreeSet<u32>> = vec![BTreeSet::new(); patch_count];
    for v in 0..patch.len() {
        for &u in graph.around(v) {
            let (a, b) = (patch[v], patch[u as usize]);
            if a != b {
                neighbours[a as usize].insert(b);
            }
        }
    }
    let merge_cost = |moments: &[Moments], error: &[Real], a: u32, b: u32| {
        let mut union = moments[a as usize].clone();
        union.add(&moments[b as usize]);
        (union.squared_error() - error[a as usize] - error[b as usize]).max(0.0)
    };
    let pairs: Vec<(u32, u32)> = (0..patch_count as u32)
        .flat_map(|a| neighbours[a as usize].iter().filter(move |&&b| b > a).map(move |&b| (a, b)))
        .collect();
    let costs: Vec<Real> = pairs.par_iter().map(|&(a, b)| merge_cost(&moments, &error, a, b)).collect();
    let mut version = vec![0u32; patch_count];
    let mut heap: BinaryHeap<Reverse<Candidate>> =
        pairs.iter().zip(&costs).map(|(&(a, b), c)| Reverse((c.to_bits(), a, b, 0, 0))).collect();
    let mut alive = vec![true; patch_count];
    let mut merges = Vec::with_capacity(patch_count);
    while let Some(Reverse((_, a, b, va, vb))) = heap.pop() {
        if !(alive[a as usize] && alive[b as usize]) || version[a as usize] != va || version[b as usize] != vb
        {
            continue;
        }
        let absorbed = moments[b as usize].clone();
        moments[a as usize].add(&absorbed);
        error[a as usize] = moments[a as usize].squared_error();
        alive[b as usize] = false;
        version[a as usize] += 1;
        let moved = std::mem::take(&mut neighbours[b as usize]);
        for &c in &moved {
            neighbours[c as usize].remove(&b);
            if c != a {
                neighbours[c as usize].insert(a);
                neighbours[a as usize].insert(c);
            }
        }
        neighbours[a as usize].remove(&b);
        merges.push((a, b));
        let around: Vec<u32> = neighbours[a as usize].iter().copied().collect();
        let costs: Vec<Real> = around.par_iter().map(|&c| merge_cost(&moments, &error, a, c)).collect();
        for (&c, cost) in around.iter().zip(costs) {
            let (x, y) = if a < c { (a, c) } else { (c, a) };
            heap.push(Reverse((cost.to_bits(), x, y, version[x as usize], version[y as usize])));
        }
    }
    merges
}

/// Patch labels after the first `count` merges: each vertex's part is the surviving
/// patch id of its patch (not compacted).
pub(crate) fn replay(patch: &[u32], patch_count: usize, merges: &[(u32, u32)], count: usize) -> Vec<u32> {
    let mut root: Vec<u32> = (0..patch_count as u32).collect();
    fn find(root: &mut [u32], mut x: u32) -> u32 {
        while root[x as usize] != x {
            root[x as usize] = root[root[x as usize] as usize];
            x = root[x as usize];
        }
        x
    }
    for &(a, b) in &merges[..count] {
        let (ra, rb) = (find(&mut root, a), find(&mut root, b));
        root[rb as usize] = ra;
    }
    patch.iter().map(|&p| find(&mut root, p)).collect()
}
