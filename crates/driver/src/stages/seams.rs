//! Stage 3's seam input: the attribute seams of a rig dataset's welded mesh
//! (`desal_rig::seam_edges`), which `[dataset.simplify] seams = "keep"` (the default)
//! hands to the simplifier so that every simplified face stays in one UV chart. Pose-file
//! datasets have no seams.
//!
//! The key of stage 3 takes the seams by content: the hash of the edge list, never the
//! rig's path, so a rig whose seams change re-runs stage 3 and one whose seams do not
//! (another file name, other animations) does not.

use anyhow::{Result, bail};
use desal_io::ContentHash;

use crate::stages::rig::RigInput;

/// A dataset's seam edges, in the pose set's (welded) vertex index space, and their hash.
#[derive(Debug, Clone, PartialEq)]
pub struct SeamEdges {
    /// `[lo, hi]` welded vertex pairs, ascending.
    pub edges: Vec<[u32; 2]>,
    /// The content hash of `edges` (little-endian `u32` pairs): stage 3's key input.
    pub hash: ContentHash,
}

impl SeamEdges {
    pub fn new(edges: Vec<[u32; 2]>) -> Self {
        let bytes: Vec<u8> = edges.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
        Self { hash: ContentHash::of(&bytes), edges }
    }
}

/// The seam edges of a rig dataset whose pose set has `vertices` vertices.
pub fn rig_seam_edges(rig: &RigInput, vertices: usize) -> Result<SeamEdges> {
    let (model, posed) = rig.load()?;
    if posed.weld.welded_count() != vertices {
        bail!("{}: the rig has changed since its pose set was made", rig.file.display());
    }
    Ok(SeamEdges::new(desal_rig::seam_edges(&model.mesh, &posed.weld)))
}

/// The seam edges of a subset simplification, in its own vertex index space: `seams` are
/// the full mesh's (`orig_idx` pairs), `kept_orig[simp_idx]` each kept vertex's original,
/// `faces` the simplified faces. Stage 3 removes a seam vertex only by collapsing it
/// along its seam, never a seam end or junction, so every simplified seam edge joins two
/// kept seam vertices through removed ones of degree 2 along one original seam; a walk
/// from each kept vertex along its seam finds them (only edges of `faces` are kept). What
/// a LOD level is simplified with, so that levels keep the seams as the first one did.
pub fn nested_seam_edges(seams: &[[u32; 2]], kept_orig: &[u32], faces: &[[u32; 3]]) -> Vec<[u32; 2]> {
    let mut neighbours: std::collections::HashMap<u32, Vec<u32>> = std::collections::HashMap::new();
    for &[a, b] in seams {
        neighbours.entry(a).or_default().push(b);
        neighbours.entry(b).or_default().push(a);
    }
    let simp_of: std::collections::HashMap<u32, u32> =
        kept_orig.iter().enumerate().map(|(simp, &orig)| (orig, simp as u32)).collect();
    let mut edges_of_faces = std::collections::BTreeSet::new();
    for f in faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            edges_of_faces.insert([a.min(b), a.max(b)]);
        }
    }
    let mut nested = std::collections::BTreeSet::new();
    for (simp, &orig) in kept_orig.iter().enumerate() {
        for &first in neighbours.get(&orig).into_iter().flatten() {
            let (mut previous, mut at) = (orig, first);
            // Bounded by the seam vertices: a walk through removed degree-2 vertices
            // cannot come back without passing a kept one.
            for _ in 0..=neighbours.len() {
                if let Some(&end) = simp_of.get(&at) {
                    let edge = [(simp as u32).min(end), (simp as u32).max(end)];
                    if edge[0] != edge[1] && edges_of_faces.contains(&edge) {
                        nested.insert(edge);
                    }
                    break;
                }
                match neighbours[&at].as_slice() {
                    &[x, y] => {
                        let next = if x == previous { y } else { x };
                        (previous, at) = (at, next);
                    }
                    _ => break,
                }
            }
        }
    }
    nested.into_iter().collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A seam 0-1-2-3 whose vertex 1 was removed: the simplified seam is 0-2-3 in the
    /// kept vertices' own numbers; an edge the faces do not have is not a seam.
    #[test]
    fn a_seam_through_removed_vertices_joins_the_kept_ones() {
        let seams = [[0, 1], [1, 2], [2, 3]];
        let kept_orig = [0, 2, 3, 7];
        let faces = [[0, 1, 3], [1, 2, 3]];
        assert_eq!(nested_seam_edges(&seams, &kept_orig, &faces), vec![[0, 1], [1, 2]]);
        assert_eq!(nested_seam_edges(&seams, &kept_orig, &[[1, 2, 3]]), vec![[1, 2]]);
    }

    /// The hash is of the edges: other edges give another hash, the same edges the same.
    #[test]
    fn the_hash_follows_the_edges() {
        let a = SeamEdges::new(vec![[0, 1], [1, 2]]);
        assert_eq!(a.hash, SeamEdges::new(vec![[0, 1], [1, 2]]).hash);
        assert_ne!(a.hash, SeamEdges::new(vec![[0, 1], [1, 3]]).hash);
        assert_ne!(a.hash, SeamEdges::new(vec![[0, 1]]).hash);
    }
}
