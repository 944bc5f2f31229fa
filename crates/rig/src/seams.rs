//! The attribute seams of a welded rig mesh, for stage 3's seam-aware collapse.
//!
//! [`crate::weld`] joins the split copies of a vertex so that the simplifier sees one
//! surface; the seams it closed are still where the attributes (UV, normal) jump. A
//! welded edge is a *seam edge* when its two faces use different split copies at either
//! endpoint: the faces on each side read different attributes there. Stage 3 keeps these
//! edges as polylines (`desal_simplify::SimplifyInput::with_seams`), so every simplified
//! face stays on one side of every seam, and [`crate::simplified_rig`] finds copies of one
//! chart for its corners.
//!
//! Index space: `welded` (the pose set's vertices).

use crate::model::SkinnedMesh;
use crate::weld::Weld;

/// The seam edges of `weld` (the weld of `mesh`), as `[lo, hi]` welded vertex pairs,
/// ascending and without repeats. Only edges with exactly two faces can be seams: a
/// boundary edge has one side, and the simplifier never collapses at an edge with more
/// than two faces.
pub fn seam_edges(mesh: &SkinnedMesh, weld: &Weld) -> Vec<[u32; 2]> {
    // Every face's edges as (welded lo, welded hi, split copy at lo, split copy at hi).
    let mut sides: Vec<[u32; 4]> = Vec::with_capacity(3 * weld.faces.len());
    for (face, &source) in weld.faces.iter().zip(&weld.face_source) {
        let split = mesh.triangles[source as usize];
        for i in 0..3 {
            let j = (i + 1) % 3;
            let (a, b, sa, sb) = (face[i], face[j], split[i], split[j]);
            sides.push(if a < b { [a, b, sa, sb] } else { [b, a, sb, sa] });
        }
    }
    sides.sort_unstable();
    let mut seams = Vec::new();
    for edge in sides.chunk_by(|x, y| x[..2] == y[..2]) {
        if let [first, second] = edge
            && first[2..] != second[2..]
        {
            seams.push([first[0], first[1]]);
        }
    }
    seams
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Influences;

    /// A quad of two triangles whose diagonal is a UV seam: the split mesh repeats the
    /// diagonal's two vertices (4 and 5 copy 0 and 2), so the weld has one quad and the
    /// diagonal is its one seam edge; the quad's outer edges have one face each.
    #[test]
    fn the_split_diagonal_of_a_quad_is_its_seam() {
        let positions = vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
        let mut positions_split = positions.clone();
        positions_split.extend([positions[0], positions[2]]);
        let mut influences = Influences::new();
        for _ in 0..6 {
            influences.push_row([(0, 1.0)]);
        }
        let mesh = SkinnedMesh {
            name: "quad".into(),
            positions: positions_split,
            normals: None,
            uvs: None,
            influences,
            triangles: vec![[0, 1, 2], [4, 5, 3]],
            primitives: Vec::new(),
            sources: Vec::new(),
        };
        let weld = Weld::new(&mesh);
        assert_eq!(weld.welded_count(), 4);
        assert_eq!(seam_edges(&mesh, &weld), vec![[0, 2]]);
        // The same quad unsplit has no seam.
        let whole = SkinnedMesh { triangles: vec![[0, 1, 2], [0, 2, 3]], ..mesh };
        assert_eq!(seam_edges(&whole, &Weld::new(&whole)), Vec::<[u32; 2]>::new());
    }
}
