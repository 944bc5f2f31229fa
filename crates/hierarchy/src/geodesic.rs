//! k nearest coarse vertices along the fine mesh's edges (Dijkstra in the template
//! pose): the fitted upsampler's optional candidates. Unlike Euclidean neighbours they do
//! not jump across a gap to another body part (an arm to the torso, one thigh to the
//! other), whose vertices move differently in other poses.
//!
//! Ties are broken by vertex index, so the candidates do not depend on scheduling.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use desal_mesh::{Face, Real, Vec3};

/// The fine mesh's vertex graph with template-pose edge lengths, CSR.
#[derive(Debug, Clone)]
pub struct EdgeGraph {
    start: Vec<usize>,
    neighbour: Vec<u32>,
    length: Vec<Real>,
}

impl EdgeGraph {
    pub fn new(positions: &[Vec3], faces: &[Face]) -> Self {
        let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(faces.len() * 6);
        for f in faces {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                if a != b {
                    pairs.push((a, b));
                    pairs.push((b, a));
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let mut start = vec![0usize; positions.len() + 1];
        for &(a, _) in &pairs {
            start[a as usize + 1] += 1;
        }
        for v in 0..positions.len() {
            start[v + 1] += start[v];
        }
        let neighbour: Vec<u32> = pairs.iter().map(|&(_, b)| b).collect();
        let length =
            pairs.iter().map(|&(a, b)| (positions[a as usize] - positions[b as usize]).norm()).collect();
        Self { start, neighbour, length }
    }
}

/// Reusable per-thread buffers for [`nearest_marked`].
#[derive(Debug, Clone)]
pub struct Scratch {
    distance: Vec<Real>,
    touched: Vec<u32>,
    heap: BinaryHeap<Entry>,
}

impl Scratch {
    pub fn new(vertex_count: usize) -> Self {
        Self { distance: vec![Real::INFINITY; vertex_count], touched: Vec::new(), heap: BinaryHeap::new() }
    }
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct Entry {
    distance: Real,
    vertex: u32,
}

impl Eq for Entry {}

impl Ord for Entry {
    /// Reversed, so `BinaryHeap` pops the nearest first, lower index on ties.
    fn cmp(&self, other: &Self) -> Ordering {
        other.distance.total_cmp(&self.distance).then(other.vertex.cmp(&self.vertex))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// The first `k` vertices with `mark[v] != u32::MAX` reached from `source` along the
/// graph, nearest first, as `mark` values (`coarse_idx`); fewer when the source's
/// component holds fewer.
pub fn nearest_marked(
    graph: &EdgeGraph,
    mark: &[u32],
    source: u32,
    k: usize,
    scratch: &mut Scratch,
) -> Vec<u32> {
    let mut found = Vec::with_capacity(k);
    let heap = &mut scratch.heap;
    heap.clear();
    scratch.distance[source as usize] = 0.0;
    scratch.touched.push(source);
    heap.push(Entry { distance: 0.0, vertex: source });
    while let Some(Entry { distance, vertex }) = heap.pop() {
        if distance > scratch.distance[vertex as usize] {
            continue; // stale entry
        }
        if mark[vertex as usize] != u32::MAX {
            found.push(mark[vertex as usize]);
            if found.len() == k {
                break;
            }
        }
        let v = vertex as usize;
        for e in graph.start[v]..graph.start[v + 1] {
            let (w, d) = (graph.neighbour[e], distance + graph.length[e]);
            if d < scratch.distance[w as usize] {
                if scratch.distance[w as usize] == Real::INFINITY {
                    scratch.touched.push(w);
                }
                scratch.distance[w as usize] = d;
                heap.push(Entry { distance: d, vertex: w });
            }
        }
    }
    for &v in &scratch.touched {
        scratch.distance[v as usize] = Real::INFINITY;
    }
    scratch.touched.clear();
    found
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A path 0 – 1 – 2 – 3 – 4 with unit edges, marks on 0, 3 and 4: from vertex 2 the
    /// nearest marked are 3 (1 away), then 0 and 4 (2 away: the lower vertex first).
    #[test]
    fn path_order_with_ties_by_index() {
        let positions: Vec<Vec3> = (0..5).map(|i| Vec3::new(i as f64, 0.0, 0.0)).collect();
        let faces = vec![[0, 1, 1], [1, 2, 2], [2, 3, 3], [3, 4, 4]];
        let graph = EdgeGraph::new(&positions, &faces);
        let mark = vec![10, u32::MAX, u32::MAX, 13, 14];
        let mut scratch = Scratch::new(positions.len());
        assert_eq!(nearest_marked(&graph, &mark, 2, 3, &mut scratch), vec![13, 10, 14]);
        // The scratch is reset: a second query gives the same answer.
        assert_eq!(nearest_marked(&graph, &mark, 2, 2, &mut scratch), vec![13, 10]);
    }
}
