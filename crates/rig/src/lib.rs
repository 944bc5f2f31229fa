//! Skinned glTF 2.0 rigs in and out of desal.
//!
//! Engines, VR avatars and real-time trackers deform a body by linear blend skinning
//! (LBS): a skeleton, per-vertex joint weights and a glTF file. This crate turns such a
//! rig into what desal's stages run on — a registered pose set and part labels — and
//! turns the simplified mesh back into a rig that an engine loads:
//!
//! 1. [`read_rig`]: the node tree, every skinned mesh as one (with UVs and normals), their skins
//!    and the animations; the JSON parsed and validated by the `gltf` crate, every
//!    accessor checked against the glTF 2.0 specification and read by desal; bad or
//!    hostile input refused with the file and the element ([`RigError`]).
//! 2. [`Weld`]: split vertices of UV and normal seams welded by position and weights.
//! 3. [`sample_frames`] and [`pose_rig`]: frames of the animations and/or seeded random
//!    joint rotations, posed by LBS into a [`PoseSet`] over the welded vertices; the bind
//!    pose is the template (pose 0). Their size is capped ([`MAX_FRAMES`],
//!    [`MAX_POSE_NODES`], [`MAX_POSE_VERTICES`]) before anything is allocated.
//! 4. [`dominant_joint_parts`]: labels from each vertex's heaviest joint.
//! 5. [`simplified_rig`] then [`write_edited`]: the input document with the simplified
//!    primitives in place of its own — every other mesh, material, texture, animation and
//!    extension as it was —, seams kept, weights exact (subset placement) or refitted
//!    (optimal placement). [`write_glb`] writes a rig built in memory.
//! 6. [`viewer::view_html`]: a three.js page showing both rigs animated, loading the
//!    pinned three.js from its CDN, or inlining a local copy for offline use.
//!
//! Like `desal-sample`, this crate is not a stage: it knows a file format (glTF), the
//! one exception to "`desal-io` knows every format", because the `gltf` crate is the
//! whole reader and the writer's layout is tied to the rig model here.

mod accessor;
mod document;
pub mod edit;
pub mod error;
pub mod model;
pub mod morph;
pub mod parts;
pub mod pose;
pub mod read;
pub mod refit;
pub mod seams;
pub mod simplified;
mod structure;
pub mod viewer;
pub mod weld;
pub mod write;

use desal_mesh::math::Mat4;
use desal_mesh::{PoseSet, Vec3};

pub use edit::{EditedGlb, ExternalImage, MSFT_LOD, SourceDocument, write_edited, write_lods};
pub use error::RigError;
pub use model::{
    Animation, Channel, Influences, Interpolation, LocalTransform, Node, PrimitiveSpan, Rig, Skin,
    SkinnedMesh,
};
pub use morph::{MorphTarget, morph_targets};
pub use parts::{PartsConfig, dominant_joint_parts, with_part_tree};
pub use pose::{
    Frame, FrameConfig, MAX_FRAMES, MAX_POSE_NODES, MAX_POSE_VERTICES, PoseSource, joint_matrices,
    sample_frames, skin_points,
};
pub use read::{ReadOptions, read_rig, read_rig_and_document, read_rig_from};
pub use seams::seam_edges;
pub use simplified::{
    PoseTargets, SimplifiedInput, SimplifiedReport, WeightOptions, simplified_influences, simplified_rig,
    simplified_rig_with,
};
pub use weld::Weld;
pub use write::write_glb;

/// Version of what this crate makes of a rig (weld, frames, LBS, labels, output); bump
/// when the output for the same file and settings changes. 2: every skinned mesh and every
/// mesh below a bone is read (issue 42), so a file with a mesh below a bone gives another
/// pose set than before.
pub const VERSION: u32 = 2;

/// Name of the template pose: the mesh as bound (every skinning matrix the identity).
pub const BIND_POSE: &str = "bind";

/// A rig posed at its frames, over welded vertices.
#[derive(Debug, Clone)]
pub struct PosedRig {
    pub weld: Weld,
    /// Influences of each welded vertex (its first copy's).
    pub influences: Influences,
    /// Pose 0 is the bind pose (the template), then one pose per frame.
    pub poses: PoseSet,
    /// `joints[k][j]`: joint `j`'s skinning matrix in pose `k` (identities for the bind pose).
    pub joints: Vec<Vec<Mat4>>,
}

/// Poses the welded mesh of `rig` at `frames` by linear blend skinning. Refused: more
/// than [`MAX_POSE_VERTICES`] positions (before any is computed), and a posed position
/// that is not a finite `f32` ([`RigError::Posed`], naming the pose and welded vertex;
/// the caller adds the file). [`sample_frames`] has already refused frames whose joints
/// collapse or overflow.
pub fn pose_rig(rig: &Rig, frames: &[Frame]) -> Result<PosedRig, RigError> {
    let weld = Weld::new(&rig.mesh);
    let representatives = weld.representatives();
    let mut influences = Influences::new();
    for &s in &representatives {
        influences.push_row(rig.mesh.influences.of(s as usize).map(|(j, w)| (j as u16, w)));
    }
    let rest: Vec<Vec3> = representatives
        .iter()
        .map(|&s| {
            let p = rig.mesh.positions[s as usize];
            Vec3::new(p[0].into(), p[1].into(), p[2].into())
        })
        .collect();
    let positions_held = (frames.len() + 1).saturating_mul(rest.len());
    if positions_held > pose::MAX_POSE_VERTICES {
        return Err(RigError::Settings(format!(
            "{} poses of {} welded vertices are {positions_held} positions, more than desal's limit of {} \
             (desal_rig::MAX_POSE_VERTICES); lower frames",
            frames.len() + 1,
            rest.len(),
            pose::MAX_POSE_VERTICES
        )));
    }
    let mut names = vec![BIND_POSE.to_owned()];
    let mut positions = vec![rest.clone()];
    let mut joints = vec![vec![Mat4::identity(); rig.skin.joints.len()]];
    for frame in frames {
        let m = joint_matrices(rig, &frame.locals);
        positions.push(skin_points(&rest, &influences, &m));
        names.push(frame.name.clone());
        joints.push(m);
    }
    // The pose set is stored in f32: a position beyond its range would become infinite.
    let in_range = |q: &Vec3| q.iter().all(|c| c.is_finite() && c.abs() <= f64::from(f32::MAX));
    for (k, pose) in positions.iter().enumerate() {
        if let Some(v) = pose.iter().position(|q| !in_range(q)) {
            let j = influences.dominant_joint(v);
            return Err(RigError::Posed {
                pose: names[k].clone(),
                vertex: v,
                reason: format!(
                    "lands at {:?}, beyond the range of f32 in which desal stores poses; its heaviest joint is \
                     joint {j} ({}): check the translations and scales above it",
                    pose[v].as_slice(),
                    pose::node_label(rig, rig.skin.joints[j])
                ),
            });
        }
    }
    let poses = PoseSet::try_new(names, positions, weld.faces.clone(), 0)
        .map_err(|e| RigError::Settings(format!("the posed rig is not a valid pose set: {e}")))?;
    Ok(PosedRig { weld, influences, poses, joints })
}
