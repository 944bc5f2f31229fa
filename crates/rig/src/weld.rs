//! Welding split vertices for simplification. A rig's mesh repeats a vertex along every
//! UV and normal seam (the same position 2–4 times with different attributes). Left
//! split, each seam is a cut in the surface: boundary edges that pin the budget and open
//! cracks when the two sides collapse differently. So the pose set the pipeline runs on
//! has one vertex per (bind position, influences): split vertices with bit-identical
//! positions and bit-identical `(joint, weight)` lists are one welded vertex, and they
//! deform identically in every pose, so nothing is lost. The attributes come back in the
//! output (see [`crate::write`]): each corner takes the copy its side of the seam used.
//!
//! Welded vertices are numbered in order of their first split vertex, so a mesh without
//! seams welds to itself. Vertices of two glTF meshes of a rig never weld, so each mesh
//! is a run of welded vertices (meshes follow one another in [`crate::Rig::meshes`]).

use std::collections::HashMap;

use desal_mesh::Face;

use crate::model::SkinnedMesh;

/// The split ↔ welded vertex maps of a mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct Weld {
    /// `split_to_welded[split]`.
    pub split_to_welded: Vec<u32>,
    /// The split copies of welded vertex `w`: `copies[copy_offsets[w]..copy_offsets[w + 1]]`,
    /// ascending.
    pub copy_offsets: Vec<u32>,
    pub copies: Vec<u32>,
    /// The mesh's triangles over welded vertices, degenerate ones (two corners welded
    /// into one) dropped.
    pub faces: Vec<Face>,
    /// For each face of [`Weld::faces`], the index of its triangle in the mesh.
    pub face_source: Vec<u32>,
}

impl Weld {
    /// Welds `mesh`.
    pub fn new(mesh: &SkinnedMesh) -> Self {
        let mut index: HashMap<Vec<u32>, u32> = HashMap::with_capacity(mesh.vertex_count());
        let mut split_to_welded = Vec::with_capacity(mesh.vertex_count());
        let mut welded_count = 0u32;
        for (v, p) in mesh.positions.iter().enumerate() {
            let mut key: Vec<u32> = p.iter().map(|x| canonical_bits(*x)).collect();
            // Vertices of different glTF meshes never weld: each mesh is written back apart.
            key.push(mesh.primitive_of(v as u32).map_or(0, |s| mesh.primitives[s].mesh) as u32);
            for (j, w) in mesh.influences.of(v) {
                key.push(j as u32);
                key.push(w.to_bits());
            }
            let w = *index.entry(key).or_insert_with(|| {
                welded_count += 1;
                welded_count - 1
            });
            split_to_welded.push(w);
        }
        let (copy_offsets, copies) = invert(&split_to_welded, welded_count as usize);
        let mut faces = Vec::with_capacity(mesh.triangles.len());
        let mut face_source = Vec::with_capacity(mesh.triangles.len());
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let f = tri.map(|s| split_to_welded[s as usize]);
            if f[0] != f[1] && f[1] != f[2] && f[0] != f[2] {
                faces.push(f);
                face_source.push(t as u32);
            }
        }
        Self { split_to_welded, copy_offsets, copies, faces, face_source }
    }

    pub fn welded_count(&self) -> usize {
        self.copy_offsets.len() - 1
    }

    /// The split copies of welded vertex `w`.
    pub fn copies_of(&self, w: usize) -> &[u32] {
        &self.copies[self.copy_offsets[w] as usize..self.copy_offsets[w + 1] as usize]
    }

    /// The first split copy of every welded vertex (its representative).
    pub fn representatives(&self) -> Vec<u32> {
        (0..self.welded_count()).map(|w| self.copies_of(w)[0]).collect()
    }
}

/// `+0.0` for `-0.0`, so that the two zeros weld.
fn canonical_bits(x: f32) -> u32 {
    if x == 0.0 { 0 } else { x.to_bits() }
}

/// CSR inverse of a many-to-one map.
fn invert(map: &[u32], targets: usize) -> (Vec<u32>, Vec<u32>) {
    let mut offsets = vec![0u32; targets + 1];
    for &t in map {
        offsets[t as usize + 1] += 1;
    }
    for i in 0..targets {
        offsets[i + 1] += offsets[i];
    }
    let mut fill = offsets.clone();
    let mut items = vec![0u32; map.len()];
    for (s, &t) in map.iter().enumerate() {
        items[fill[t as usize] as usize] = s as u32;
        fill[t as usize] += 1;
    }
    (offsets, items)
}
