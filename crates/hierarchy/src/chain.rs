//! A chain of levels refitted on a subset of poses: what held-out measurement needs. Per
//! fold, every level's U is rebuilt on the fold's training poses (the levels' vertices
//! and faces stay as they are) and the U's are composed to full resolution, so the
//! measured poses reach no upsampler of the chain.
//!
//! Index spaces: each level's `coarse_to_fine` indexes the level above it; level 0 is
//! `full`. The composed upsampler of level k is `n_0 × n_k`.

use std::borrow::Cow;

use desal_mesh::{Face, PoseSet};

use crate::error::HierarchyError;
use crate::fitted::FineLevel;
use crate::level::{Upsampler, build_levels, nest};
use crate::sparse::CsrMatrix;

/// One level of a chain: its vertices as vertices of the level above (`map{k+1}`) and
/// its faces.
#[derive(Debug, Clone, Copy)]
pub struct ChainLevel<'a> {
    pub coarse_to_fine: &'a [u32],
    pub coarse_faces: &'a [Face],
}

/// The registered pose set of a level: every pose of `full` at `coarse_to_orig`
/// (`orig{k}`), with the level's `faces`; names and template as `full`'s.
///
/// Errors: an index past `full`'s vertices, faces past the level's vertex count.
pub fn level_poses(
    full: &PoseSet,
    coarse_to_orig: &[u32],
    faces: &[Face],
) -> Result<PoseSet, HierarchyError> {
    let n0 = full.vertex_count();
    if let Some((coarse_idx, &fine_idx)) = coarse_to_orig.iter().enumerate().find(|&(_, &o)| o as usize >= n0)
    {
        return Err(HierarchyError::MapOutOfRange { coarse_idx, fine_idx, fine_count: n0 });
    }
    let gather = |v: &[desal_mesh::Vec3]| coarse_to_orig.iter().map(|&o| v[o as usize]).collect();
    Ok(PoseSet::try_new(
        full.names.clone(),
        full.poses.iter().map(|v| gather(v)).collect(),
        faces.to_vec(),
        full.template,
    )?
    .with_groups(full.groups.clone())?)
}

/// The composed upsamplers `U_0`, `U_0 · U_1`, …, one per level of `chain` (so entry k
/// is `n_0 × n_{k+1}`), every level's U built with `upsampler` on the poses of `full`
/// that `training` marks (one flag per pose).
///
/// Errors: those of [`build_level`](crate::build_level) for any level, an empty chain
/// (`EmptyCoarse`).
pub fn composed_upsamplers(
    full: &PoseSet,
    chain: &[ChainLevel],
    training: &[bool],
    upsampler: &Upsampler,
) -> Result<Vec<CsrMatrix>, HierarchyError> {
    Ok(composed_upsamplers_per_mask(full, chain, &[training], upsampler)?.pop().expect("one mask"))
}

/// [`composed_upsamplers`] once per training mask (`masks[k]` in place of `training`),
/// in order: one chain per fold of a held-out evaluation. Each level's fits share their
/// candidates and their sums over poses, so the folds cost about what one fit over every
/// pose costs; each fold's U equals [`composed_upsamplers`]' up to the rounding of those
/// sums (for one mask, bit for bit).
///
/// Errors: those of [`composed_upsamplers`] for any mask.
pub fn composed_upsamplers_per_mask(
    full: &PoseSet,
    chain: &[ChainLevel],
    masks: &[&[bool]],
    upsampler: &Upsampler,
) -> Result<Vec<Vec<CsrMatrix>>, HierarchyError> {
    upsamplers_per_mask(full, chain, masks, upsampler)?
        .into_iter()
        .map(|levels| {
            let mut composed: Vec<CsrMatrix> = Vec::with_capacity(levels.len());
            for up in levels {
                let next = match composed.last() {
                    None => up,
                    Some(c) => c.mul(&up)?,
                };
                composed.push(next);
            }
            Ok(composed)
        })
        .collect()
}

/// Every level's own U (level 1's first), not composed, once per training mask, built
/// as [`composed_upsamplers_per_mask`] builds them: what [`crate::Upsampled`] applies
/// level by level, without the composed matrices (whose rows hold the union of every
/// level's neighbourhoods).
///
/// Errors: those of [`composed_upsamplers`] for any mask.
pub fn upsamplers_per_mask(
    full: &PoseSet,
    chain: &[ChainLevel],
    masks: &[&[bool]],
    upsampler: &Upsampler,
) -> Result<Vec<Vec<CsrMatrix>>, HierarchyError> {
    if chain.is_empty() {
        return Err(HierarchyError::EmptyCoarse { vertices: 0, faces: 0 });
    }
    let mut per_mask: Vec<Vec<CsrMatrix>> = masks.iter().map(|_| Vec::with_capacity(chain.len())).collect();
    let full_template = full.template_positions();
    let mut fine_to_orig: Option<Vec<u32>> = None;
    let mut fine_faces: &[Face] = &full.faces;
    for level in chain {
        // Level 0 is `full` itself; a coarser level is read in place through its
        // `orig{k}`: a pose set of its own would add a copy of every pose. Its map and
        // faces were checked against the level above by `build_levels` on the way down.
        let template: Cow<[desal_mesh::Vec3]> = match &fine_to_orig {
            None => Cow::Borrowed(full_template),
            Some(orig) => Cow::Owned(orig.iter().map(|&o| full_template[o as usize]).collect()),
        };
        let fine =
            FineLevel { poses: full, orig: fine_to_orig.as_deref(), template: &template, faces: fine_faces };
        let built = build_levels(&fine, level.coarse_to_fine, level.coarse_faces, masks, upsampler)?;
        for (levels, built) in per_mask.iter_mut().zip(built) {
            levels.push(built.up);
        }
        fine_to_orig = Some(match &fine_to_orig {
            None => level.coarse_to_fine.to_vec(),
            Some(orig) => nest(orig, level.coarse_to_fine),
        });
        fine_faces = level.coarse_faces;
    }
    Ok(per_mask)
}
