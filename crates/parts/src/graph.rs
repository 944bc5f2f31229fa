//! The vertex graph parts live on: the mesh's edges, plus one bridge edge from every
//! small connected piece of the mesh (fewer than `min_part_vertices` vertices, such as
//! an unused vertex or a loose flap) to the nearest vertex of a large piece, so that
//! every vertex can join a part and "a part is connected" has one meaning everywhere.
//! Also the connected components of a labelling on that graph.

use std::collections::VecDeque;

use desal_mesh::math::{Real, Vec3};
use desal_mesh::{EdgeTopology, Face};

use crate::error::PartsError;

/// Adjacency in CSR form: the neighbours of `v` are `neighbours[offsets[v]..offsets[v + 1]]`,
/// ascending (vertex index space of the pose set).
#[derive(Debug, Clone)]
pub(crate) struct VertexGraph {
    offsets: Vec<u32>,
    neighbours: Vec<u32>,
}

impl VertexGraph {
    /// The mesh's vertex graph with small pieces bridged to large ones, and the initial
    /// labelling: one part per large piece, numbered by its smallest vertex.
    ///
    /// Errors when no piece has `min_part` vertices.
    pub(crate) fn build(
        faces: &[Face],
        positions: &[Vec3],
        min_part: usize,
    ) -> Result<(Self, Vec<u32>, usize), PartsError> {
        let n = positions.len();
        let (offsets, neighbours) = EdgeTopology::new(faces).vertex_neighbours(n);
        let mesh = Self { offsets, neighbours };
        let (piece, sizes) = mesh.components(&vec![0; n]);
        let largest = sizes.iter().copied().max().unwrap_or(0);
        if largest < min_part {
            return Err(PartsError::MeshTooSmall { vertices: largest, min_part_vertices: min_part });
        }
        let large: Vec<bool> = sizes.iter().map(|&s| s >= min_part).collect();
        let bridges = bridge_small_pieces(positions, &piece, &large);
        let graph = if bridges.is_empty() { mesh } else { mesh.with_edges(&bridges) };

        // Initial parts: the large pieces, each with the small pieces bridged to it.
        let (labels, sizes) = graph.components(&vec![0; n]);
        Ok((graph, labels, sizes.len()))
    }

    /// Neighbours of vertex `v`, ascending.
    #[inline]
    pub(crate) fn around(&self, v: usize) -> &[u32] {
        &self.neighbours[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }

    pub(crate) fn vertex_count(&self) -> usize {
        self.offsets.len() - 1
    }

    /// Connected components of the subgraphs of equal label: `component[v]` and the size
    /// of each component. Components are numbered in order of their smallest vertex, so
    /// the numbering is a pure function of the labels.
    pub(crate) fn components(&self, labels: &[u32]) -> (Vec<u32>, Vec<usize>) {
        let n = self.vertex_count();
        let mut component = vec![u32::MAX; n];
        let mut sizes = Vec::new();
        let mut queue = VecDeque::new();
        for start in 0..n {
            if component[start] != u32::MAX {
                continue;
            }
            let id = sizes.len() as u32;
            component[start] = id;
            queue.push_back(start);
            let mut size = 0;
            while let Some(v) = queue.pop_front() {
                size += 1;
                for &u in self.around(v) {
                    let u = u as usize;
                    if component[u] == u32::MAX && labels[u] == labels[start] {
                        component[u] = id;
                        queue.push_back(u);
                    }
                }
            }
            sizes.push(size);
        }
        (component, sizes)
    }

    /// This graph with the undirected `edges` added.
    fn with_edges(&self, edges: &[[u32; 2]]) -> Self {
        let n = self.vertex_count();
        let mut lists: Vec<Vec<u32>> = (0..n).map(|v| self.around(v).to_vec()).collect();
        for &[a, b] in edges {
            lists[a as usize].push(b);
            lists[b as usize].push(a);
        }
        let mut offsets = Vec::with_capacity(n + 1);
        let mut neighbours = Vec::with_capacity(self.neighbours.len() + 2 * edges.len());
        offsets.push(0);
        for mut list in lists {
            list.sort_unstable();
            list.dedup();
            neighbours.extend(list);
            offsets.push(neighbours.len() as u32);
        }
        Self { offsets, neighbours }
    }
}

/// One bridge per small piece: the closest (small-piece vertex, large-piece vertex)
/// pair in the template, ties by the smaller index pair. Brute force: small pieces are
/// rare and tiny, so this is `O(small vertices × vertices)`.
fn bridge_small_pieces(positions: &[Vec3], piece: &[u32], large: &[bool]) -> Vec<[u32; 2]> {
    let anchors: Vec<usize> = (0..positions.len()).filter(|&v| large[piece[v] as usize]).collect();
    let mut best: Vec<Option<(Real, u32, u32)>> = vec![None; large.len()];
    for v in (0..positions.len()).filter(|&v| !large[piece[v] as usize]) {
        for &u in &anchors {
            let d = (positions[v] - positions[u]).norm_squared();
            let slot = &mut best[piece[v] as usize];
            if slot.is_none_or(|(bd, _, _)| d < bd) {
                *slot = Some((d, v as u32, u as u32));
            }
        }
    }
    best.into_iter().flatten().map(|(_, v, u)| [v, u]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles sharing an edge (vertices 0–3) and a lone triangle far away (4–6)
    /// with `min_part = 4`: the lone triangle is small, so it is bridged to its nearest
    /// vertex (4 is nearest to 3) and everything is one initial part.
    #[test]
    fn small_pieces_are_bridged_to_the_nearest_large_vertex() {
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(3.0, 1.0, 0.0),
            Vec3::new(4.0, 1.0, 0.0),
            Vec3::new(3.0, 2.0, 0.0),
        ];
        let faces = [[0, 1, 2], [1, 3, 2], [4, 5, 6]];
        let (graph, labels, count) = VertexGraph::build(&faces, &positions, 4).unwrap();
        assert_eq!(count, 1);
        assert_eq!(labels, vec![0; 7]);
        assert_eq!(graph.around(3), &[1, 2, 4]);
        // With min_part = 3 both pieces are large: two initial parts, no bridge.
        let (graph, labels, count) = VertexGraph::build(&faces, &positions, 3).unwrap();
        assert_eq!((count, labels), (2, vec![0, 0, 0, 0, 1, 1, 1]));
        assert_eq!(graph.around(3), &[1, 2]);
    }

    /// A strip 0-1-2-3 labelled a, b, a, a: label a has two components, numbered by
    /// their smallest vertex.
    #[test]
    fn components_split_by_label() {
        let positions: Vec<Vec3> = (0..6).map(|i| Vec3::new((i / 2) as f64, (i % 2) as f64, 0.0)).collect();
        let faces = [[0, 2, 1], [1, 2, 3], [2, 4, 3], [3, 4, 5]];
        let (graph, _, _) = VertexGraph::build(&faces, &positions, 3).unwrap();
        let (component, sizes) = graph.components(&[0, 0, 1, 1, 0, 0]);
        assert_eq!(component, vec![0, 0, 1, 1, 2, 2]);
        assert_eq!(sizes, vec![2, 2, 2]);
    }

    #[test]
    fn too_small_a_mesh_is_an_error() {
        let positions = vec![Vec3::zeros(), Vec3::x(), Vec3::y()];
        let err = VertexGraph::build(&[[0, 1, 2]], &positions, 20).unwrap_err();
        assert_eq!(err, PartsError::MeshTooSmall { vertices: 3, min_part_vertices: 20 });
    }
}
