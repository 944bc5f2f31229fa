//! The stages on arrays already in memory, for library callers and the Python package
//! (`crates/python`): the checks of ingest and the labels stage, and the one stage chain
//! and level loop of `desal run` over the [`Memory`] store, without files or the cache.
//!
//! **Invariant:** the same arrays give the same bytes as `desal run`. Positions pass
//! through the pose-set artifact's f32 (`PoseSetV2`), as `desal run`'s do, and the
//! stages are chained by the same functions (`stages::chain`, `stages::hierarchy::levels`).

use std::path::Path;

use anyhow::{Context, Result, bail};
use desal_io::artifact::{FitV1, LabelsV1, MapV1, PoseSetV2, SaliencyV1, SimplifiedV1};
use desal_io::npz::HierarchyArrays;
use desal_mesh::validate::clean_faces;
use desal_mesh::{FaceCleanup, PartLabels, PoseSet, Progress};

use crate::stages::chain::{Chain, ChainInput, ChainSettings, chain};
use crate::stages::fit::{FitParams, FitSummary};
use crate::stages::hierarchy::{self, HierarchyParams, LevelSettings, LevelSummary};
use crate::stages::ingest::{IngestSummary, LabelsSummary};
use crate::stages::lods::{LodSettings, lod_levels};
use crate::stages::map::{self, MapSummary};
use crate::stages::parts::{self, PartsParams, PartsSummary};
use crate::stages::rig::{RigInput, RigParams, SimplifiedRigSummary};
use crate::stages::runner::{Memory, StageOutput};
use crate::stages::saliency::{SaliencyParams, SaliencySummary};
use crate::stages::seams::SeamEdges;
use crate::stages::simplify::{SimplifyParams, SimplifySummary};

/// A pose set built from arrays: validated as ingest validates pose files.
#[derive(Debug, Clone)]
pub struct ArrayPoseSet {
    pub set: PoseSet,
    /// Degenerate and duplicate template faces that were removed (ingest warns of them).
    pub cleanup: FaceCleanup,
}

/// Builds a pose set from per-pose positions (`positions[pose][vertex]`), one triangle
/// list and the template index, with one group id per pose or none (held-out figures
/// then hold out whole groups). Names default to `pose000`, `pose001`, …. Positions are
/// stored at f32, the precision of the pose-set artifact `desal run` computes from.
/// Errors name the pose and vertex or face, as ingest's do.
pub fn pose_set(
    names: Option<Vec<String>>,
    positions: Vec<Vec<[f32; 3]>>,
    faces: Vec<[u32; 3]>,
    template: usize,
    groups: Option<Vec<u32>>,
) -> Result<ArrayPoseSet> {
    let poses = positions.len();
    if poses == 0 {
        bail!("the pose list is empty: give at least one pose");
    }
    let names = match names {
        Some(names) if names.len() != poses => {
            bail!("names has {} entries but there are {poses} poses", names.len())
        }
        Some(names) => names,
        None => (0..poses).map(|k| format!("pose{k:03}")).collect(),
    };
    if let Some((i, name)) = names.iter().enumerate().find(|(i, n)| names[..*i].contains(n)) {
        bail!("pose name '{name}' is used twice (pose {i}); poses need distinct names");
    }
    if template >= poses {
        bail!("template {template} is out of range for {poses} poses");
    }
    let vertices = positions[template].len();
    if vertices > 0 {
        desal_mesh::validate::check_face_indices(&faces, vertices).context("faces")?;
    }
    let (faces, cleanup) = clean_faces(&faces);
    if let Some(g) = &groups
        && g.len() != poses
    {
        bail!("groups has {} entries but there are {poses} poses; give one group id per pose", g.len());
    }
    let body =
        PoseSetV2 { names, template: template as u32, faces, positions, groups: groups.unwrap_or_default() };
    let set = body.to_pose_set().context("invalid pose set")?;
    Ok(ArrayPoseSet { set, cleanup })
}

/// Part labels from one id per vertex (and the parts' names, else `part0`, `part1`, …),
/// checked as the labels stage checks a labels file: one per vertex, no empty part,
/// every part able to carry a rigid fit.
pub fn labels(ids: Vec<u32>, names: Option<Vec<String>>, set: &PoseSet) -> Result<PartLabels> {
    let labels = match names {
        Some(names) => PartLabels::try_new(ids, names)?,
        None => PartLabels::from_ids(ids),
    };
    labels.check_vertex_count(set.vertex_count())?;
    if let Some(part) = labels.first_empty_part() {
        bail!("part {part} ('{}') has no vertex", labels.names[part as usize]);
    }
    labels
        .check_parts_fittable(set.template_positions())
        .with_context(|| format!("part labels against the template '{}'", set.names[set.template]))?;
    Ok(labels)
}

/// Parts discovered from the poses (`labels = "auto"`).
pub fn discover_parts(params: &PartsParams, set: &PoseSet) -> Result<(PartLabels, PartsSummary)> {
    let out = parts::compute(params, set)?;
    Ok((out.body.to_labels()?, out.summary))
}

/// The stage parameters of one pose set, as a pipeline file's dataset table holds them.
#[derive(Debug, Clone, Default)]
pub struct StageParams {
    pub fit: FitParams,
    pub saliency: SaliencyParams,
    pub simplify: SimplifyParams,
}

impl StageParams {
    /// The chain's view of them.
    pub fn chain(&self) -> ChainSettings<'_> {
        ChainSettings { fit: &self.fit, saliency: &self.saliency, simplify: &self.simplify }
    }
}

/// Stages 1–4 of one pose set, computed.
#[derive(Debug, Clone)]
pub struct Simplification {
    pub fit: StageOutput<FitV1, FitSummary>,
    pub saliency: StageOutput<SaliencyV1, SaliencySummary>,
    pub simplified: StageOutput<SimplifiedV1, SimplifySummary>,
    pub map: StageOutput<MapV1, MapSummary>,
}

/// Stage 1.
pub fn fit(
    params: &FitParams,
    set: &PoseSet,
    labels: &PartLabels,
    progress: &dyn Progress,
) -> Result<StageOutput<FitV1, FitSummary>> {
    crate::stages::fit::compute(params, set, labels, progress)
}

/// Stage 2 from a stage-1 result of `set`.
pub fn saliency(
    params: &SaliencyParams,
    set: &PoseSet,
    fit: &FitV1,
) -> Result<StageOutput<SaliencyV1, SaliencySummary>> {
    crate::stages::saliency::compute(params, fit, set.template_mesh().diagonal())
}

/// Stages 1–4, in `desal run`'s order: the one chain (`stages::chain`), in memory.
pub fn simplify_pose_set(
    params: &StageParams,
    set: &PoseSet,
    labels: &PartLabels,
    progress: &dyn Progress,
) -> Result<Simplification> {
    simplify_with_seams(params, set, labels, None, None, progress)
}

/// [`simplify_pose_set`] with the template's attribute seams handed to stage 3 (a rig's,
/// as `desal run` hands them).
fn simplify_with_seams(
    params: &StageParams,
    set: &PoseSet,
    labels: &PartLabels,
    seams: Option<&SeamEdges>,
    meshes: Option<&crate::stages::meshes::MeshPlan>,
    progress: &dyn Progress,
) -> Result<Simplification> {
    let input = ChainInput { set: &|| Ok(set), labels: &|| Ok(labels), hashes: None, seams, meshes };
    let Chain { fit, saliency, simplified, map } = chain(&mut Memory, params.chain(), &input, progress)?;
    Ok(Simplification {
        fit: fit.into_output()?,
        saliency: saliency.into_output()?,
        simplified: simplified.into_output()?,
        map: map.into_output()?,
    })
}

/// A skinned glTF rig simplified as `desal run` simplifies a `[dataset.rig]`: the bytes of
/// its `simplified.glb` and every stage's result.
#[derive(Debug, Clone)]
pub struct RigSimplification {
    /// The simplified rig (`.glb`), the bytes `desal run` writes as `simplified.glb`.
    pub glb: Vec<u8>,
    /// The images it names by a relative URI, to be written beside it.
    pub images: Vec<desal_rig::ExternalImage>,
    pub rig: SimplifiedRigSummary,
    /// With `lods`: each level's rig and the chain in one (`simplified-lod<k>.glb`,
    /// `simplified-lods.glb`); their figures are `rig.lods`.
    pub lods: Option<crate::stages::rig::LodGlbs>,
    pub ingest: StageOutput<PoseSetV2, IngestSummary>,
    pub labels: StageOutput<LabelsV1, LabelsSummary>,
    pub stages: Simplification,
}

/// Ingest and dominant-joint labels of the rig in `file` (read with the `[dataset.rig]`
/// settings `rig`), stages 1–4 as [`simplify_pose_set`] runs them, and the simplified
/// rig through the one rig writer (`stages::rig::simplified_glb`).
pub fn simplify_rig(
    file: &Path,
    rig: &RigParams,
    params: &StageParams,
    progress: &dyn Progress,
) -> Result<RigSimplification> {
    rig.weight_options()?;
    rig.lod_fractions()?;
    rig.check_mesh_overrides()?;
    let input = RigInput { file, params: rig };
    let ingest = input.compute_poses()?;
    let set = ingest.body.to_pose_set().with_context(|| format!("{}", file.display()))?;
    let labels = input.compute_labels(&set)?;
    let part_labels = labels.body.to_labels().with_context(|| format!("{}", file.display()))?;
    let part_labels = input.to_owned().with_part_tree(part_labels)?;
    let seams = if params.simplify.keeps_seams() {
        Some(crate::stages::seams::rig_seam_edges(&input, set.vertex_count())?)
    } else {
        None
    };
    let plan = input.mesh_plan(&set, params.simplify.target())?;
    let stages = simplify_with_seams(params, &set, &part_labels, seams.as_ref(), plan.as_ref(), progress)?;
    let (edited, mut summary) =
        crate::stages::rig::simplified_glb(&input.to_owned(), &stages.simplified.body, &stages.map.body)?;
    // The LOD chain, as `desal run` makes it (`stages::lods`), in memory.
    let fractions = rig.lod_fractions()?;
    let lods = if fractions.is_empty() {
        None
    } else {
        let chain_input = ChainInput {
            set: &|| Ok(&set),
            labels: &|| Ok(&part_labels),
            hashes: None,
            seams: seams.as_ref(),
            meshes: plan.as_ref(),
        };
        let settings = LodSettings { chain: params.chain(), fractions };
        let levels = lod_levels(&mut Memory, &settings, &chain_input, set.faces.len(), progress)?;
        let bodies = levels.iter().map(|l| Ok((l.body()?, &l.summary))).collect::<Result<Vec<_>>>()?;
        let files = crate::stages::rig::lod_glbs(&input.to_owned(), &bodies)?;
        summary.lods = files.figures.clone();
        Some(files)
    };
    Ok(RigSimplification {
        glb: edited.bytes,
        images: edited.images,
        rig: summary,
        lods,
        ingest,
        labels,
        stages,
    })
}

/// The simplified pose set and its labels: `map` applied to every pose of `set`.
pub fn apply_map(map: &MapV1, set: &PoseSet, labels: &PartLabels) -> Result<(PoseSet, PartLabels)> {
    map::apply(map, set, labels)
}

/// A hierarchy of `set` (level 0) and its coarse levels, as `desal run` writes it to
/// `hierarchy.npz`, with each level step's summary: the one level loop
/// (`stages::hierarchy::levels`), in memory.
pub fn hierarchy(
    params: &StageParams,
    hierarchy: &HierarchyParams,
    set: &PoseSet,
    labels: &PartLabels,
    progress: &dyn Progress,
) -> Result<(HierarchyArrays, Vec<LevelSummary>)> {
    hierarchy.check_levels(Some(set.vertex_count()))?;
    let settings = LevelSettings { chain: params.chain(), hierarchy };
    let input =
        ChainInput { set: &|| Ok(set), labels: &|| Ok(labels), hashes: None, seams: None, meshes: None };
    let levels = hierarchy::levels(&mut Memory, &settings, &input, progress)?;
    let bodies = levels.iter().map(|l| l.body()).collect::<Result<Vec<_>>>()?;
    let arrays = hierarchy::npz_arrays(set.vertex_count(), &set.faces, &bodies)?;
    Ok((arrays, levels.into_iter().map(|l| l.summary).collect()))
}
