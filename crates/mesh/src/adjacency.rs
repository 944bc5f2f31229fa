//! Compact adjacency in CSR form (offsets + flat arrays), built in O(F) passes with no
//! hash maps on the vertex path, so it stays cheap on million-face meshes.

use crate::mesh::Face;

/// For each vertex, the faces that use it: faces of vertex `v` are
/// `faces[offsets[v]..offsets[v + 1]]`, ascending.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VertexFaces {
    pub offsets: Vec<u32>,
    pub faces: Vec<u32>,
}

impl VertexFaces {
    pub fn new(vertex_count: usize, faces: &[Face]) -> Self {
        let mut offsets = vec![0u32; vertex_count + 1];
        for f in faces {
            for &v in f {
                offsets[v as usize + 1] += 1;
            }
        }
        for v in 0..vertex_count {
            offsets[v + 1] += offsets[v];
        }
        let mut fill = offsets.clone();
        let mut out = vec![0u32; faces.len() * 3];
        for (fi, f) in faces.iter().enumerate() {
            for &v in f {
                out[fill[v as usize] as usize] = fi as u32;
                fill[v as usize] += 1;
            }
        }
        Self { offsets, faces: out }
    }

    /// Faces incident to vertex `v`.
    #[inline]
    pub fn of(&self, v: u32) -> &[u32] {
        &self.faces[self.offsets[v as usize] as usize..self.offsets[v as usize + 1] as usize]
    }
}

/// The undirected edges of a triangle list, each with the number of faces using it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EdgeTopology {
    /// Edges as `(lo, hi)` vertex pairs, sorted ascending.
    pub edges: Vec<[u32; 2]>,
    /// Number of faces using each edge (1: boundary, 2: manifold interior, >2: non-manifold).
    pub face_counts: Vec<u32>,
}

impl EdgeTopology {
    pub fn new(faces: &[Face]) -> Self {
        let mut all: Vec<[u32; 2]> = faces
            .iter()
            .flat_map(|&[a, b, c]| [[a, b], [b, c], [c, a]])
            .map(|[x, y]| if x < y { [x, y] } else { [y, x] })
            .collect();
        all.sort_unstable();
        let mut edges = Vec::with_capacity(all.len() / 2 + 1);
        let mut face_counts = Vec::with_capacity(all.len() / 2 + 1);
        for e in all {
            if edges.last() == Some(&e) {
                *face_counts.last_mut().unwrap() += 1;
            } else {
                edges.push(e);
                face_counts.push(1);
            }
        }
        Self { edges, face_counts }
    }

    pub fn boundary_edge_count(&self) -> usize {
        self.face_counts.iter().filter(|&&c| c == 1).count()
    }

    pub fn non_manifold_edge_count(&self) -> usize {
        self.face_counts.iter().filter(|&&c| c > 2).count()
    }

    /// Vertex neighbours in CSR form: neighbours of `v` are
    /// `neighbours[offsets[v]..offsets[v + 1]]`, ascending.
    pub fn vertex_neighbours(&self, vertex_count: usize) -> (Vec<u32>, Vec<u32>) {
        let mut offsets = vec![0u32; vertex_count + 1];
        for &[a, b] in &self.edges {
            offsets[a as usize + 1] += 1;
            offsets[b as usize + 1] += 1;
        }
        for v in 0..vertex_count {
            offsets[v + 1] += offsets[v];
        }
        let mut fill = offsets.clone();
        let mut neighbours = vec![0u32; self.edges.len() * 2];
        for &[a, b] in &self.edges {
            neighbours[fill[a as usize] as usize] = b;
            fill[a as usize] += 1;
            neighbours[fill[b as usize] as usize] = a;
            fill[b as usize] += 1;
        }
        for v in 0..vertex_count {
            neighbours[offsets[v] as usize..offsets[v + 1] as usize].sort_unstable();
        }
        (offsets, neighbours)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tetrahedron: closed, every edge shared by exactly two faces.
    #[test]
    fn tetrahedron_is_closed_manifold() {
        let faces = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
        let topo = EdgeTopology::new(&faces);
        assert_eq!(topo.edges.len(), 6);
        assert_eq!(topo.boundary_edge_count(), 0);
        assert_eq!(topo.non_manifold_edge_count(), 0);
        let vf = VertexFaces::new(4, &faces);
        assert_eq!(vf.of(0), &[0, 1, 3]);
        let (off, nb) = topo.vertex_neighbours(4);
        assert_eq!(&nb[off[2] as usize..off[3] as usize], &[0, 1, 3]);
    }

    /// Two triangles sharing one edge: four boundary edges, one interior.
    #[test]
    fn quad_has_four_boundary_edges() {
        let topo = EdgeTopology::new(&[[0, 1, 2], [0, 2, 3]]);
        assert_eq!(topo.boundary_edge_count(), 4);
        assert_eq!(topo.face_counts.iter().filter(|&&c| c == 2).count(), 1);
    }
}
