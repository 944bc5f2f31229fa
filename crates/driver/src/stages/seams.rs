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

#[cfg(test)]
mod tests {
    use super::*;

    /// The hash is of the edges: other edges give another hash, the same edges the same.
    #[test]
    fn the_hash_follows_the_edges() {
        let a = SeamEdges::new(vec![[0, 1], [1, 2]]);
        assert_eq!(a.hash, SeamEdges::new(vec![[0, 1], [1, 2]]).hash);
        assert_ne!(a.hash, SeamEdges::new(vec![[0, 1], [1, 3]]).hash);
        assert_ne!(a.hash, SeamEdges::new(vec![[0, 1]]).hash);
    }
}
