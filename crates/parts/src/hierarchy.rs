//! The bottom-up half of discovery: cut the template into many small patches
//! (farthest-point seeds, geodesic Voronoi cells along the mesh's edges), then merge
//! adjacent parts, always the pair whose union adds least to stage 1's residual (an
//! agglomerative clustering in the manner of Ward's, with a rigid fit per pose as the
//! "centroid"). Moments add up, so a union's fit needs no pass over its vertices; its
//! residual does. Replaying the first merges gives the parts at every count.

use std::cmp::Reverse;
use std::collections::{BTreeSet, BinaryHeap};

use desal_mesh::math::{Real, Vec3};
use rayon::prelude::*;

use crate::graph::VertexGraph;
use crate::motion::{Moments, PartMotion, PoseData};

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

/// The bottom-up merges of the patches, cheapest first.
#[derive(Debug, Clone)]
pub(crate) struct MergeSequence {
    /// `merges[i] = (kept, absorbed)` patch ids, in order.
    pub(crate) merges: Vec<(u32, u32)>,
    /// `residual[i]`: stage 1's summed residual (over every vertex and non-template
    /// pose, mesh units) with the parts left after the first `i` merges.
    pub(crate) residual: Vec<Real>,
}

/// Merges adjacent parts bottom-up, always the pair whose union adds least to stage
/// 1's summed residual `Σ_poses Σ_v ‖R v_T + t − v_X‖` (the union fitted from the
/// summed moments, its residual measured per vertex); ties by the id pair. Stops when
/// no two parts are adjacent.
///
/// The distance, not its square, is the criterion because it is the figure stage 1
/// reports and saliency sums: measured on SCAPE with K = 16, the squared criterion
/// (exact from moments alone, 3× cheaper) merges the hands into the forearms and
/// splits the chest in three instead (ARI 0.725 against the hand-made parts, 13.56 mm)
/// where the distance finds the hand-made structure part for part (0.767, 13.34 mm).
pub(crate) fn merge_sequence(
    data: &PoseData,
    graph: &VertexGraph,
    patch: &[u32],
    patch_count: usize,
) -> MergeSequence {
    let mut members = vec![Vec::new(); patch_count];
    for (v, &p) in patch.iter().enumerate() {
        members[p as usize].push(v as u32);
    }
    let residual_of = |moments: &Moments, vertices: &[u32]| -> Real {
        let motion = PartMotion::from_moments(moments);
        vertices.iter().map(|&v| motion.cost(data, v as usize)).sum()
    };
    let mut moments: Vec<Moments> = members.par_iter().map(|m| Moments::of(data, m)).collect();
    let mut error: Vec<Real> = moments.par_iter().zip(&members).map(|(m, v)| residual_of(m, v)).collect();
    let mut neighbours: Vec<BTreeSet<u32>> = vec![BTreeSet::new(); patch_count];
    for v in 0..patch.len() {
        for &u in graph.around(v) {
            let (a, b) = (patch[v], patch[u as usize]);
            if a != b {
                neighbours[a as usize].insert(b);
            }
        }
    }
    let merge_cost = |moments: &[Moments], members: &[Vec<u32>], error: &[Real], a: u32, b: u32| {
        let mut union = moments[a as usize].clone();
        union.add(&moments[b as usize]);
        let (ma, mb) = (&members[a as usize], &members[b as usize]);
        let motion = PartMotion::from_moments(&union);
        let joint: Real = ma.iter().chain(mb).map(|&v| motion.cost(data, v as usize)).sum();
        (joint - error[a as usize] - error[b as usize]).max(0.0)
    };
    let pairs: Vec<(u32, u32)> = (0..patch_count as u32)
        .flat_map(|a| neighbours[a as usize].iter().filter(move |&&b| b > a).map(move |&b| (a, b)))
        .collect();
    let costs: Vec<Real> =
        pairs.par_iter().map(|&(a, b)| merge_cost(&moments, &members, &error, a, b)).collect();
    let mut version = vec![0u32; patch_count];
    let mut heap: BinaryHeap<Reverse<Candidate>> =
        pairs.iter().zip(&costs).map(|(&(a, b), c)| Reverse((c.to_bits(), a, b, 0, 0))).collect();
    let mut alive = vec![true; patch_count];
    let total = |error: &[Real], alive: &[bool]| {
        (0..error.len()).filter(|&p| alive[p]).map(|p| error[p]).sum::<Real>()
    };
    let mut sequence =
        MergeSequence { merges: Vec::with_capacity(patch_count), residual: vec![total(&error, &alive)] };
    // Lazy re-evaluation: a merge leaves its neighbours' entries stale instead of
    // re-costing them at once; a stale entry that reaches the top is re-costed for the
    // parts that now hold its two ends and pushed back. A merge seldom makes a
    // neighbouring merge cheaper, so this keeps the greedy order in practice: on SCAPE
    // and the sample the merges, curve and parts are identical to re-costing every
    // neighbour after each merge, for 20 % less CPU. `absorber[p]`: the part that
    // absorbed dead part `p` (itself while alive).
    let mut absorber: Vec<u32> = (0..patch_count as u32).collect();
    let mut queued: BTreeSet<Candidate> = BTreeSet::new();
    while let Some(Reverse(entry)) = heap.pop() {
        let (_, a, b, va, vb) = entry;
        let current =
            alive[a as usize] && alive[b as usize] && version[a as usize] == va && version[b as usize] == vb;
        if !current {
            let root = |mut p: u32| {
                while absorber[p as usize] != p {
                    p = absorber[p as usize];
                }
                p
            };
            let (x, y) = (root(a).min(root(b)), root(a).max(root(b)));
            if x == y {
                continue;
            }
            // The same pair can come up stale from both of its former ends: cost it once.
            if !queued.insert((0, x, y, version[x as usize], version[y as usize])) {
                continue;
            }
            let cost = merge_cost(&moments, &members, &error, x, y);
            heap.push(Reverse((cost.to_bits(), x, y, version[x as usize], version[y as usize])));
            continue;
        }
        let absorbed = moments[b as usize].clone();
        moments[a as usize].add(&absorbed);
        let moved = std::mem::take(&mut members[b as usize]);
        members[a as usize].extend(moved);
        error[a as usize] = residual_of(&moments[a as usize], &members[a as usize]);
        alive[b as usize] = false;
        absorber[b as usize] = a;
        version[a as usize] += 1;
        for c in std::mem::take(&mut neighbours[b as usize]) {
            neighbours[c as usize].remove(&b);
            if c != a {
                neighbours[c as usize].insert(a);
                neighbours[a as usize].insert(c);
            }
        }
        sequence.merges.push((a, b));
        sequence.residual.push(total(&error, &alive));
    }
    sequence
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
