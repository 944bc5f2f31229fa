//! The surface being simplified, as the collapses so far left it: the flat per-slot arrays
//! (positions, quadrics, weights, flags, normals), the faces with every slot's face list,
//! and the seams. A *slot* is an input vertex index (`orig_idx`): a slot keeps its
//! index while it lives, and its arrays' entries are its vertex's.
//!
//! Phase 1 fills it ([`Surface::new`], with `classify.rs`'s functions); the costs
//! (`placement.rs`), the safeguards (`safeguards.rs`) and the edge listing (`edges.rs`)
//! only read it; a collapse (`collapse.rs`) is the one writer. It is the bundle of
//! explicit arrays that meshoptimizer's simplifier passes to each phase.

use desal_mesh::Vec3;

use crate::classify::{
    ClassifyInput, classify_vertices, compute_input_normals, compute_vertex_normals, fill_face_planes,
};
use crate::config::{Placement, SimplifyConfig};
use crate::face_lists::FaceLists;
use crate::quadric::Quadric;
use crate::seams::SeamGraph;
use crate::types::SimplifyInput;

/// The per-slot and per-face arrays every phase reads (see the module doc).
#[derive(Debug)]
pub(crate) struct Surface {
    /// Subtracted from every input position for precision; added back on output.
    pub(crate) center: Vec3,
    pub(crate) pose_count: usize,
    /// Current template positions, local coordinates, by slot.
    pub(crate) positions: Vec<Vec3>,
    /// Multi-pose only: local positions of every pose, `[pose][slot]` (never move).
    pub(crate) pose_positions: Vec<Vec<Vec3>>,
    /// `quadrics[slot * pose_count + pose]`.
    pub(crate) quadrics: Vec<Quadric>,
    /// Saliency weight per slot, when the saliency factor is on. A merged vertex takes
    /// the larger weight of the two, so salient detail is never diluted by absorbing a
    /// cheap neighbour.
    pub(crate) weights: Option<Vec<f64>>,
    /// Keep penalty per slot (subset placement; [`SimplifyInput::keep_penalty`]). A slot
    /// always holds the input vertex it started with, so the input's array serves.
    pub(crate) keep_penalty: Option<Vec<f64>>,
    /// The flags of `classify.rs` (`ALIVE`, `BOUNDARY`, `FROZEN`, `PINNED`, `SEAM`), by
    /// slot.
    pub(crate) flags: Vec<u8>,
    pub(crate) lists: FaceLists,
    /// The current seam edges, when the input has seams.
    pub(crate) seams: Option<SeamGraph>,
    /// Unnormalised normal of every input face in the template: a collapse may not
    /// turn a face past the threshold from it either, since small steps add up.
    pub(crate) input_normals: Vec<Vec3>,
    /// Unit area-weighted normal of every input vertex (template pose): the local
    /// surface orientation where a slot's vertex came from, whatever faces it has now.
    pub(crate) vertex_normals: Vec<Vec3>,
}

impl Surface {
    /// Phase 1: centre the positions, classify every vertex and fill its quadric from
    /// the face planes, then fill the input and vertex normals (`classify.rs`).
    /// `poses[p]` are the positions of pose `p`, `input.mesh` is pose `template`, and
    /// `faces` are its non-degenerate faces.
    pub(crate) fn new(
        poses: &[&[Vec3]],
        template: usize,
        input: &SimplifyInput<'_>,
        faces: Vec<[u32; 3]>,
        config: &SimplifyConfig,
    ) -> Self {
        let SimplifyInput { mesh, weights, part_labels, seams, keep_penalty } = *input;
        let n = mesh.positions.len();
        let pose_count = poses.len();
        let center = mesh.bounding_box().map_or(Vec3::zeros(), |(lo, hi)| (lo + hi) * 0.5);
        let local: Vec<Vec<Vec3>> = poses.iter().map(|p| p.iter().map(|x| x - center).collect()).collect();
        let lists = FaceLists::new(n, faces);
        let seams = seams.map(|edges| SeamGraph::new(n, edges));
        // Each face's plane quadric once (a vertex sums those of its faces). Several
        // poses would need one per face and pose: those are computed where summed.
        let face_planes = (pose_count == 1).then(|| fill_face_planes(lists.faces(), &local[0]));
        let (flags, quadrics) = classify_vertices(&ClassifyInput {
            lists: &lists,
            poses: &local,
            face_planes: face_planes.as_deref(),
            part_labels,
            seams: seams.as_ref(),
            config,
        });
        // The planes go before the normals come: the two are never in memory together
        // (on a million faces, 40 and 36 MB, the allocated heap's peak when they were).
        drop(face_planes);
        let input_normals = compute_input_normals(lists.faces(), &mesh.positions);
        let vertex_normals = compute_vertex_normals(&lists, &input_normals);
        let mut pose_positions = local;
        // One pose: the moving positions are the only copy; several: the template's
        // positions are copied out, since every pose's stay fixed for the cost.
        let positions = if pose_count == 1 {
            pose_positions.pop().expect("one pose")
        } else {
            pose_positions[template].clone()
        };
        Surface {
            center,
            pose_count,
            positions,
            pose_positions,
            quadrics,
            // `+ 0.0` turns a −0 weight into +0: costs are ranked by their bit patterns,
            // where −0 would sort after every positive cost.
            weights: weights.filter(|_| config.saliency).map(|w| w.iter().map(|&x| x + 0.0).collect()),
            keep_penalty: keep_penalty.filter(|_| config.placement == Placement::Subset).map(<[f64]>::to_vec),
            flags,
            lists,
            seams,
            input_normals,
            vertex_normals,
        }
    }
}
