//! The stages, one file each: its parameters (typed, with their validation), its cache
//! key built from the resolved library configuration, its call into its crate and its
//! artifact conversion. [`run_stages`] is the pipeline's story in order; the runner
//! (`runner.rs`) serves each stage from the cache or computes it.
//!
//! Dependency order of the driver: `cache` ← `stages` ← `outputs` ← `pipeline` ←
//! `run` ← `commands`; no module imports a later one.

pub mod chain;
pub mod fit;
pub mod hierarchy;
pub mod ingest;
pub mod lods;
pub mod map;
pub mod meshes;
pub mod model;
pub mod parts;
pub mod rig;
pub mod runner;
pub mod saliency;
pub mod seams;
pub mod simplify;

use std::cell::{Cell, OnceCell};
use std::path::Path;

use anyhow::Result;
use desal_io::artifact::{
    ArtifactKind, FitV1, HierarchyLevelV1, LabelsV1, MapV1, PoseSetV2, SaliencyV1, SimplifiedV1,
};
use desal_mesh::{PartLabels, PoseSet, Progress};

use chain::{Chain, ChainInput, ChainSettings, chain};
use fit::{FitParams, FitSummary};
use hierarchy::{HierarchyParams, LevelSummary};
use ingest::{IngestParams, IngestSummary, LabelsSummary};
use map::MapSummary;
use parts::{PartsParams, PartsSummary};
use runner::{Stage, StageRunner, Staged, Store};
use saliency::{SaliencyParams, SaliencySummary};
use simplify::{SimplifyParams, SimplifySummary};

/// Everything the stages of one dataset read: files and parameters.
#[derive(Debug, Clone, Copy)]
pub struct DatasetInputs<'a> {
    pub ingest: IngestParams<'a>,
    pub labels: LabelsInput<'a>,
    pub fit: &'a FitParams,
    pub saliency: &'a SaliencyParams,
    pub simplify: &'a SimplifyParams,
    /// `[dataset.hierarchy]`, when the dataset asks for one.
    pub hierarchy: Option<&'a HierarchyParams>,
    /// `[dataset.rig]`: the poses and labels come from a skinned glTF instead of
    /// `ingest` and `labels`.
    pub rig: Option<rig::RigInput<'a>>,
    /// `[dataset.model]`: the poses and labels come from a body model, sampled.
    pub model: Option<model::ModelInput<'a>>,
}

/// Where a dataset's part labels come from: a labels file, or discovery from the poses.
#[derive(Debug, Clone, Copy)]
pub enum LabelsInput<'a> {
    File(&'a Path),
    Auto(&'a PartsParams),
    /// From the rig of [`DatasetInputs::rig`] (dominant joints).
    Rig,
    /// From the skinning weights of [`DatasetInputs::model`].
    Model,
}

/// The stages of one dataset, run or found in the cache. Bodies are decoded lazily, the
/// pose set and labels at most once.
#[derive(Debug)]
pub struct DatasetStages {
    pub poses: Staged<PoseSetV2, IngestSummary>,
    pub labels: Staged<LabelsV1, LabelsSummary>,
    /// The discovery's figures when the labels are `auto` (`parts.json`).
    pub parts: Option<PartsSummary>,
    pub fit: Staged<FitV1, FitSummary>,
    pub saliency: Staged<SaliencyV1, SaliencySummary>,
    pub simplified: Staged<SimplifiedV1, SimplifySummary>,
    pub map: Staged<MapV1, MapSummary>,
    /// One per coarse level, level 1 first (empty without `[dataset.hierarchy]`).
    pub hierarchy: Vec<Staged<HierarchyLevelV1, LevelSummary>>,
    /// A rig's LOD chain (`lods` in `[dataset.rig]`), level 1 first: each level's map
    /// into the pose set (empty without one).
    pub lods: Vec<Staged<desal_io::artifact::MapV1, lods::LodSummary>>,
    /// The rig the poses came from, for a `[dataset.rig]` dataset (`simplified.glb`).
    pub rig: Option<rig::RigSource>,
    /// The model the poses came from, for a `[dataset.model]` dataset (`model.npz`).
    pub model: Option<model::ModelSource>,
    pose_set: OnceCell<PoseSet>,
    part_labels: OnceCell<PartLabels>,
}

/// Vertex, face and pose counts of a pose set.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct Counts {
    pub vertices: usize,
    pub faces: usize,
    pub poses: usize,
}

impl DatasetStages {
    /// The ingested pose set, decoded on first use (its artifact body is not kept).
    pub fn pose_set(&self) -> Result<&PoseSet> {
        get_or_try_init(&self.pose_set, || Ok(self.poses.decode_entry()?.into_pose_set()?))
    }

    /// The part labels, decoded on first use; a rig's with its joints' tree
    /// ([`rig::RigSource::with_part_tree`]).
    pub fn part_labels(&self) -> Result<&PartLabels> {
        get_or_try_init(&self.part_labels, || {
            let labels = self.labels.body()?.to_labels()?;
            match &self.rig {
                Some(rig) => rig.with_part_tree(labels),
                None => Ok(labels),
            }
        })
    }

    /// Input and output counts, from the stages' summaries (no body is decoded).
    pub fn counts(&self) -> (Counts, Counts) {
        let i = &self.poses.summary;
        let m = &self.map.summary;
        let input = Counts { vertices: i.vertices, faces: i.faces, poses: i.poses };
        let output = Counts { vertices: m.simplified_vertices, faces: m.simplified_faces, poses: m.poses };
        (input, output)
    }
}

/// Runs (or finds in the cache) every stage of a dataset.
pub fn run_stages(
    inputs: &DatasetInputs,
    runner: &mut StageRunner,
    progress: &dyn Progress,
) -> Result<DatasetStages> {
    // Ingest: keyed on the bytes of every pose file (or of the rig or the model), never on
    // their paths.
    let mut poses = match (&inputs.rig, &inputs.model) {
        (Some(rig), _) => {
            runner.stage(Stage::Ingest, || rig.ingest_key(), &rig.hints(), || rig.compute_poses())?
        }
        (None, Some(model)) => {
            runner.stage(Stage::Ingest, || model.ingest_key(), &model.hints(), || model.compute_poses())?
        }
        (None, None) => {
            let (key, template) = inputs.ingest.key()?;
            runner.stage(
                Stage::Ingest,
                || Ok(key),
                &inputs.ingest.hints(),
                || inputs.ingest.compute(template, progress),
            )?
        }
    };
    // Decoded once, and only if a later stage has to run. The artifact body (f32) is
    // converted into the set, not kept beside it: a model source's is hundreds of MB.
    let held = Cell::new(poses.take_held_body());
    let set_cell = OnceCell::new();
    let set = || -> Result<&PoseSet> {
        get_or_try_init(&set_cell, || {
            let body = match held.take() {
                Some(body) => body,
                None => poses.decode_entry()?,
            };
            Ok(body.into_pose_set()?)
        })
    };

    // Labels: a file validated against the pose set and keyed on its bytes, or parts
    // discovered from the poses and keyed on their parameters and the poses' hash.
    let (labels, parts_summary) = match (&inputs.rig, &inputs.model, inputs.labels) {
        (None, Some(model), LabelsInput::Model) => {
            let key = || model.labels_key(poses.hash()?);
            (runner.stage(Stage::Ingest, key, &model.hints(), || model.compute_labels(set()?))?, None)
        }
        (Some(rig), None, LabelsInput::Rig) => {
            let key = || rig.labels_key(poses.hash()?);
            (runner.stage(Stage::Ingest, key, &rig.hints(), || rig.compute_labels(set()?))?, None)
        }
        (None, None, LabelsInput::File(file)) => {
            let key = || ingest::labels_key(file, poses.hash()?);
            let hints = vec![("labels_file".to_owned(), ingest::file_name(file))];
            (runner.stage(Stage::Ingest, key, &hints, || ingest::compute_labels(file, set()?))?, None)
        }
        (None, None, LabelsInput::Auto(params)) => {
            let key = || params.key(poses.hash()?);
            let found = runner.stage(Stage::Parts, key, &[], || parts::compute(params, set()?))?;
            let summary = found.summary.clone();
            (found.map_summary(|s| s.labels_summary()), Some(summary))
        }
        _ => anyhow::bail!(
            "a rig or model dataset takes its labels from its rig or model, and only such a dataset does"
        ),
    };
    let labels_cell = OnceCell::new();
    // A rig's labels carry its joints' tree, so that a part simplification leaves
    // unfittable joins its parent (issue 42, item 8).
    let part_labels = || -> Result<&PartLabels> {
        get_or_try_init(&labels_cell, || {
            let decoded = labels.body()?.to_labels()?;
            match &inputs.rig {
                Some(rig) => rig.to_owned().with_part_tree(decoded),
                None => Ok(decoded),
            }
        })
    };

    // Stages 1–4, written once (`chain.rs`); stage 3 keeps a rig's attribute seams as
    // polylines unless told to ignore them.
    let seam_edges = match &inputs.rig {
        Some(rig) if inputs.simplify.keeps_seams() => {
            Some(seams::rig_seam_edges(rig, poses.summary.vertices)?)
        }
        _ => None,
    };
    // A rig's meshes under one budget: their plan (`meshes.rs`), when they need one.
    let mesh_plan = match &inputs.rig {
        Some(rig) => rig.mesh_plan(set()?, inputs.simplify.target())?,
        None => None,
    };
    let input = ChainInput {
        set: &set,
        labels: &part_labels,
        hashes: Some((poses.hash()?, labels.hash()?)),
        seams: seam_edges.as_ref(),
        meshes: mesh_plan.as_ref(),
    };
    let settings = ChainSettings { fit: inputs.fit, saliency: inputs.saliency, simplify: inputs.simplify };
    let Chain { fit, saliency, simplified, map } = chain(runner, settings, &input, progress)?;

    // Hierarchy: one stage per coarse level, each from the level above.
    let hierarchy = match inputs.hierarchy {
        Some(h) => {
            h.check_levels(Some(poses.summary.vertices))?;
            let settings = hierarchy::LevelSettings { chain: settings, hierarchy: h };
            hierarchy::levels(runner, &settings, &input, progress)?
        }
        None => Vec::new(),
    };

    // A rig's LOD chain: one stage per level, each from the level before.
    let lod_levels = match &inputs.rig {
        Some(rig) if rig.params.lods.is_some() => {
            let settings = lods::LodSettings { chain: settings, fractions: rig.params.lod_fractions()? };
            lods::lod_levels(runner, &settings, &input, poses.summary.faces, progress)?
        }
        _ => Vec::new(),
    };

    Ok(DatasetStages {
        hierarchy,
        lods: lod_levels,
        rig: inputs.rig.map(|r| r.to_owned()),
        model: inputs.model.map(|m| m.to_owned()),
        poses,
        labels,
        parts: parts_summary,
        fit,
        saliency,
        simplified,
        map,
        pose_set: set_cell,
        part_labels: labels_cell,
    })
}

/// `OnceCell::get_or_try_init`, which is not stable yet.
fn get_or_try_init<T>(cell: &OnceCell<T>, init: impl FnOnce() -> Result<T>) -> Result<&T> {
    if let Some(value) = cell.get() {
        return Ok(value);
    }
    let value = init()?;
    Ok(cell.get_or_init(|| value))
}

/// Summary lines of a stage artifact for `desal inspect`.
pub fn describe_stage_artifact(path: &std::path::Path, kind: ArtifactKind, out: &mut String) -> Result<()> {
    use desal_io::artifact::read_artifact;
    use std::fmt::Write as _;
    match kind {
        ArtifactKind::Fit => fit::describe(&read_artifact::<FitV1>(path)?.1, out),
        ArtifactKind::Saliency => saliency::describe(&read_artifact::<SaliencyV1>(path)?.1, out),
        ArtifactKind::Simplified => simplify::describe(&read_artifact::<SimplifiedV1>(path)?.1, out),
        ArtifactKind::Map => map::describe(&read_artifact::<MapV1>(path)?.1, out),
        ArtifactKind::HierarchyLevel => hierarchy::describe(&read_artifact::<HierarchyLevelV1>(path)?.1, out),
        _ => writeln!(out, "    ({kind} artifacts are summarised once their stage is wired in)")?,
    }
    Ok(())
}
