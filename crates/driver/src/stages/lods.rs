//! A rig's LOD chain (`lods = [0.5, 0.25, 0.1]` in `[dataset.rig]`, issue 42, item 6):
//! one cached stage per level, each simplified from the level before with the dataset's
//! stage-1–4 settings, except that the target is the level's fraction of the *original*
//! faces and placement is `subset`, so every vertex of a level is a vertex of the level
//! before (the levels nest) and every written vertex keeps its exact weights. The level
//! above's attribute seams come along (`seams::nested_seam_edges`), so each level keeps
//! the UV charts as the first does; a rig's labels keep their joint tree, so a part a
//! level leaves unfittable joins its parent (`PartLabels::merge_unfittable_parts`).
//!
//! A level's body is a `MapV1` into level 0 (the welded pose set): its kept vertices'
//! original numbers and its faces. `outputs.rs` writes `simplified-lod<k>.glb` per level
//! and `simplified-lods.glb` (`MSFT_lod`) from them through `stages::rig`.
//!
//! Index spaces: `orig_idx` (level 0, the pose set), `fine_idx` (level k), `coarse_idx`
//! (level k+1).

use anyhow::Result;
use desal_io::artifact::{ArtifactKind, ContentHash, MapV1};
use desal_mesh::{PartLabels, PoseSet, Progress};
use desal_simplify::Placement;
use serde_json::json;

use crate::cache::{StageKey, canonical_json};
use crate::stages::chain::{ChainInput, ChainSettings, chain};
use crate::stages::meshes::MeshPlan;
pub use crate::stages::rig::{LodSummary, check_fractions};
use crate::stages::runner::{Scratch, Stage, StageOutput, Staged, Store};
use crate::stages::seams::{SeamEdges, nested_seam_edges};
use crate::stages::simplify::SimplifyParams;

/// Version of the LOD level stage (with stage 3's own); 2: the levels are unspiked.
pub const LOD_STAGE_VERSION: u32 = 2;

/// What the levels are simplified with: the dataset's stages 1–3 and the fractions.
#[derive(Debug, Clone, Copy)]
pub struct LodSettings<'a> {
    pub chain: ChainSettings<'a>,
    pub fractions: &'a [f64],
}

impl LodSettings<'_> {
    /// Stage 3's parameters for level `step + 1` of a pose set with `faces` faces: the
    /// dataset's, with the level's face target and subset placement.
    fn simplify_params(&self, step: usize, faces: usize) -> SimplifyParams {
        SimplifyParams {
            target_vertices: None,
            target_faces: Some(target_faces(self.fractions[step], faces)),
            ratio: None,
            placement: Placement::Subset,
            ..self.chain.simplify.clone()
        }
    }

    /// The key of level `step + 1`: the pose set, labels and seams, the level above's
    /// artifact, the level's fraction and the resolved stage-1/2/3 settings.
    fn key(
        &self,
        step: usize,
        faces: usize,
        input: &ChainInput,
        parent: Option<ContentHash>,
    ) -> Result<StageKey> {
        let (poses, labels) = input.hashes()?;
        let seams = input.seams.map(|s| s.hash);
        let simplify = self.simplify_params(step, faces).key_with_seams(poses, poses, labels, seams)?;
        let fit = self.chain.fit.key(poses, labels);
        let saliency = self.chain.saliency.key(poses, poses)?;
        let mut inputs = vec![("poses".to_owned(), poses), ("labels".to_owned(), labels)];
        if let Some(seams) = seams {
            inputs.push(("seams".into(), seams));
        }
        if let Some(plan) = input.meshes {
            inputs.push(("meshes".into(), plan.hash()));
        }
        if let Some(parent) = parent {
            inputs.push(("parent".into(), parent));
        }
        Ok(StageKey {
            stage: format!("rig-lod-{}", step + 1),
            stage_version: LOD_STAGE_VERSION,
            format_version: ArtifactKind::Map.current_version(),
            parameters: canonical_json(&json!({"level": step + 1, "fraction": self.fractions[step]})),
            resolved: canonical_json(&json!({
                "level": step + 1,
                "target_faces": target_faces(self.fractions[step], faces),
                "fit": fit.resolved,
                "saliency": saliency.resolved,
                "simplify": simplify.resolved,
            })),
            inputs,
        })
    }
}

/// A level's face target: its fraction of the original `faces`, rounded, at least 1.
pub fn target_faces(fraction: f64, faces: usize) -> usize {
    ((fraction * faces as f64).round() as usize).max(1)
}

/// Every level of `settings.fractions`, level 1 first, each one stage of `store`
/// (`Stage::Hierarchy`'s place in `--from`: a level is a coarse level of the input)
/// simplified from the level before. `faces` is level 0's face count (known from the
/// ingest summary, so a warm run decodes nothing).
pub fn lod_levels(
    store: &mut impl Store,
    settings: &LodSettings,
    input: &ChainInput,
    faces: usize,
    progress: &dyn Progress,
) -> Result<Vec<Staged<MapV1, LodSummary>>> {
    check_fractions(settings.fractions)?;
    let mut levels: Vec<Staged<MapV1, LodSummary>> = Vec::new();
    for step in 0..settings.fractions.len() {
        let level = store.stage(
            Stage::Hierarchy,
            || settings.key(step, faces, input, levels.last().map(|l| l.hash()).transpose()?),
            &[],
            || {
                let parent = levels.last().map(|l| l.body()).transpose()?;
                let seams = input.seams.map(|s| s.edges.as_slice());
                let set = (input.set)()?;
                compute_level(settings, step, set, (input.labels)()?, seams, input.meshes, parent, progress)
            },
        )?;
        levels.push(level);
    }
    Ok(levels)
}

/// Level `step + 1` from level `step` (`parent`, or the pose set itself for step 0):
/// stages 1–4 in memory on the level's registered pose set, its labels, seams and the
/// rig's mesh plan on it.
#[allow(clippy::too_many_arguments)]
fn compute_level(
    settings: &LodSettings,
    step: usize,
    full: &PoseSet,
    labels: &PartLabels,
    seams: Option<&[[u32; 2]]>,
    plan: Option<&MeshPlan>,
    parent: Option<&MapV1>,
    progress: &dyn Progress,
) -> Result<StageOutput<MapV1, LodSummary>> {
    let start = std::time::Instant::now();
    let fine_to_orig: Vec<u32> = match parent {
        Some(p) => p.simp_to_orig.clone(),
        None => (0..full.vertex_count() as u32).collect(),
    };
    let fine_faces = parent.map_or(&full.faces, |p| &p.faces);
    let fine = desal_hierarchy::level_poses(full, &fine_to_orig, fine_faces)?;
    let carried = PartLabels {
        labels: fine_to_orig.iter().map(|&o| labels.labels[o as usize]).collect(),
        names: labels.names.clone(),
        parents: labels.parents.clone(),
    };
    // Stage 1 fits every part of the level: one the level above left unfittable joins
    // its parent (a rig's labels have their tree; others are carried as they are).
    let (fine_labels, _) = carried.merge_unfittable_parts(fine.template_positions());
    let fine_seams = seams.map(|s| SeamEdges::new(nested_seam_edges(s, &fine_to_orig, fine_faces)));

    let params = settings.simplify_params(step, full.faces.len());
    // Meshes kept whole stay whole; the others share the level's target.
    let fine_plan = plan.and_then(|p| p.on_subset(&fine_to_orig));
    let chain_input = ChainInput {
        set: &|| Ok(&fine),
        labels: &|| Ok(&fine_labels),
        hashes: None,
        seams: fine_seams.as_ref(),
        meshes: fine_plan.as_ref(),
    };
    let stages =
        chain(&mut Scratch, ChainSettings { simplify: &params, ..settings.chain }, &chain_input, progress)?;
    let simplified = stages.simplified.body()?;
    let map = stages.map.body()?;
    let simp_to_orig = desal_hierarchy::nest(&fine_to_orig, &map.simp_to_orig);
    let mut faces = map.faces.clone();
    let flips = unspike(full, &simp_to_orig, &mut faces, seams, plan);
    let body = MapV1 {
        simp_to_orig,
        faces,
        mode: map.mode.clone(),
        displacement_mean: map.displacement_mean,
        displacement_max: map.displacement_max,
    };
    let summary = LodSummary {
        level: step + 1,
        fraction: settings.fractions[step],
        target_faces: target_faces(settings.fractions[step], full.faces.len()),
        vertices: body.simp_to_orig.len(),
        faces: body.faces.len(),
        stop: simplified.stop.clone(),
        max_error: simplified.max_error,
        seconds: start.elapsed().as_secs_f64(),
    };
    let note = format!(
        "LOD {}: {} -> {} faces (target {}, {} of the original {}), {} vertices, {flips} edges flipped against spikes",
        summary.level,
        fine_faces.len(),
        summary.faces,
        summary.target_faces,
        summary.fraction,
        full.faces.len(),
        summary.vertices
    );
    Ok(StageOutput { body, summary, note })
}

/// A level's last step (`desal_refit::flip::unspike`): the edges of faces that turn over
/// against the full surface in the pose set's frames flipped where fewer turn over,
/// seam vertices pinned, each face judged against its own mesh; the number of flips. On
/// the rig sample it took the held-out spikes of levels 2 and 3 from 19.6 and 26.3 a
/// frame to 16.0 and 18.7 (gltfpack: 19.3 and 27.1; EVAL.md, "LOD levels as written").
fn unspike(
    full: &PoseSet,
    simp_to_orig: &[u32],
    faces: &mut [[u32; 3]],
    seams: Option<&[[u32; 2]]>,
    plan: Option<&MeshPlan>,
) -> usize {
    let mut on_seam = vec![false; full.vertex_count()];
    for &v in seams.into_iter().flatten().flatten() {
        on_seam[v as usize] = true;
    }
    let pinned: Vec<bool> = simp_to_orig.iter().map(|&o| on_seam[o as usize]).collect();
    let mut mesh_of = Vec::new();
    if let Some(plan) = plan {
        mesh_of = vec![0u32; full.vertex_count()];
        for (m, slot) in plan.slots.iter().enumerate() {
            for v in slot.vertices[0]..slot.vertices[1] {
                mesh_of[v as usize] = m as u32;
            }
        }
    }
    let poses: Vec<usize> = (0..full.pose_count()).collect();
    desal_refit::flip::unspike(faces, simp_to_orig, full, &poses, &pinned, &mesh_of)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fractions_are_checked() {
        check_fractions(&[0.5, 0.25, 0.1]).unwrap();
        check_fractions(&[1.0]).unwrap();
        let message = |l: &[f64]| check_fractions(l).unwrap_err().to_string();
        assert!(message(&[]).contains("rig.lods is empty"));
        assert!(message(&[0.5, 0.5]).contains("strictly decreasing"), "{}", message(&[0.5, 0.5]));
        assert!(message(&[0.25, 0.5]).contains("lods[1] = 0.5"));
        assert!(message(&[1.5]).contains("rig.lods[0] = 1.5"));
        assert!(message(&[0.5, 0.0]).contains("rig.lods[1] = 0"));
        assert!(message(&[f64::NAN]).contains("(0, 1]"));
        assert_eq!(target_faces(0.1, 26756), 2676);
        assert_eq!(target_faces(1e-9, 10), 1, "at least one face");
    }
}
