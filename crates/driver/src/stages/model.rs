//! `[dataset.model]`: a parametric body model (SMPL, SMPL-H, SMPL-X, MANO, FLAME; `.npz`
//! or a chumpy `.pkl`, `desal-bodymodel`) sampled over shapes and poses in place of pose
//! files. Ingest evaluates the model at the template (the mean shape in the zero pose)
//! and at `shapes × poses` random samples (`desal_bodymodel::Sampler`, seeded); the
//! labels are the skinning weights' dominant joints merged to about `parts` parts
//! (`desal_bodymodel::labels_from_weights`).
//!
//! Both stages are keyed by the model file's bytes (never its path) and every sampling
//! setting. Pose names are `template` and `s<shape>-p<pose>`, so a sample's shape (its
//! person) can be read from its name.
//!
//! A model dataset is simplified with subset placement ([`use_subset_placement`]: the
//! default for it, and `placement = "optimal"` is refused), so that every kept vertex is
//! a model vertex and the output folder can hold the smaller model itself:
//! [`simplified_model`] writes `model.npz` (`desal_bodymodel::subset_model`, in the
//! input's keys and dtypes; a `.pkl` input comes out as an npz of the same keys) and
//! `model.json`, what the joint regressor's solve and the landmarks did. The samples
//! simplified (`simplified/<pose>.ply`, one file per sample) are written only when
//! `write_poses = true` asks for them.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use desal_bodymodel::{
    BodyModel, SampleConfig, Sampler, SubsetConfig, SubsetReport, labels_from_weights, subset_model,
};
use desal_io::artifact::{ArtifactKind, ContentHash, LabelsV1, MapV1, PoseSetV2};
use desal_mesh::PoseSet;
use desal_mesh::math::{vec3_from_f32, vec3_to_f32};
use desal_simplify::Placement;
use serde::{Deserialize, Serialize};
use serde_json::json;

use crate::cache::{StageKey, canonical_json};
use crate::stages::ingest::{IngestSummary, LabelsSummary, hash_file};
use crate::stages::runner::StageOutput;
use crate::stages::simplify::SimplifyParams;

/// Version of what this module adds to `desal-bodymodel`: the pose names, the template,
/// the labels' checks. Bumped when the pose set or labels of a model change.
pub const MODEL_STAGE_VERSION: u32 = 1;

/// The most positions (samples × vertices) a model source makes: the rig's cap
/// ([`desal_rig::MAX_POSE_VERTICES`], 2^25). A model source's `desal run` with a
/// two-level hierarchy peaks near 36 bytes a position (the 2048-sample benchmark, 27.4 M
/// positions: 0.98 GB; BENCHMARKS.md "Issue 41, item 4"), so about 1.2 GB at the cap.
pub const MAX_POSITIONS: usize = desal_rig::MAX_POSE_VERTICES;

/// `[dataset.model]`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ModelParams {
    /// The model file (`.npz`, or a `.pkl` read without running pickled code), relative
    /// to the pipeline file.
    pub file: String,
    /// Random shape vectors (betas ~ N(0, 1) per component, clipped to ±2.5). Default 8.
    #[serde(default = "default_count")]
    pub shapes: usize,
    /// Random poses per shape (per joint an axis-angle ~ N(0, σ²) per axis, σ = 0.3 rad
    /// for body joints, 0.2 for hands, jaw and eyes, and a turn about the up axis).
    /// Default 8.
    #[serde(default = "default_count")]
    pub poses: usize,
    /// SMPL-X and FLAME: each pose also gets a random expression (N(0, 1) per component).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub expressions: bool,
    /// Seed of the one random stream.
    #[serde(default)]
    pub seed: u64,
    /// σ (rad) of every joint, replacing the body and hand spreads.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pose_sigma: Option<f64>,
    /// The labels: dominant skinning joints merged to about this many parts. Default 16.
    #[serde(default = "default_parts")]
    pub parts: usize,
    /// Also write every sample simplified, `simplified/<pose>.ply` (one file per sample,
    /// thousands for a large sampling). Default false: the output is the simplified
    /// model (`model.npz`), which makes any sample again. It shapes the output folder
    /// only, so no stage's key holds it; the folder's `outputs_key` does when it is set.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub write_poses: bool,
}

fn default_count() -> usize {
    SampleConfig::default().shapes
}

fn default_parts() -> usize {
    16
}

impl ModelParams {
    /// The sampler's configuration; the counts checked.
    pub fn config(&self) -> Result<SampleConfig> {
        if self.shapes == 0 || self.poses == 0 {
            bail!("model: shapes and poses must be at least 1 (got {} and {})", self.shapes, self.poses);
        }
        if self.parts == 0 {
            bail!("model: parts must be at least 1");
        }
        if let Some(sigma) = self.pose_sigma
            && !(sigma.is_finite() && sigma >= 0.0)
        {
            bail!("model: pose_sigma = {sigma} must be finite and not negative");
        }
        // Checked again with the model's vertex count when it is read; a sample has at
        // least one vertex, so this refuses a count no model can meet before any reading.
        let samples = self.shapes.checked_mul(self.poses).and_then(|n| n.checked_add(1));
        if samples.is_none_or(|n| n > MAX_POSITIONS) {
            bail!(
                "model: {} shapes × {} poses is more than desal's {MAX_POSITIONS} positions at any vertex count",
                self.shapes,
                self.poses
            );
        }
        Ok(SampleConfig {
            shapes: self.shapes,
            poses: self.poses,
            seed: self.seed,
            pose_sigma: self.pose_sigma,
            expressions: self.expressions,
            ..SampleConfig::default()
        })
    }
}

/// A model dataset's input: the file (absolute) and its table.
#[derive(Debug, Clone, Copy)]
pub struct ModelInput<'a> {
    pub file: &'a Path,
    pub params: &'a ModelParams,
}

impl ModelInput<'_> {
    fn file_hash(&self) -> Result<ContentHash> {
        hash_file(self.file)
    }

    /// The ingest key: the model's bytes and every setting of the sampler.
    pub fn ingest_key(&self) -> Result<StageKey> {
        let c = self.params.config()?;
        Ok(StageKey {
            stage: "model-ingest".into(),
            stage_version: MODEL_STAGE_VERSION,
            format_version: ArtifactKind::PoseSet.current_version(),
            parameters: canonical_json(&json!({
                "shapes": self.params.shapes,
                "poses": self.params.poses,
                "expressions": self.params.expressions,
                "seed": self.params.seed,
                "pose_sigma": self.params.pose_sigma,
            })),
            resolved: canonical_json(&json!({ "sampler": format!("{c:?}") })),
            inputs: vec![("model".into(), self.file_hash()?)],
        })
    }

    /// The labels key: the model's bytes, the pose set and the part count.
    pub fn labels_key(&self, poses: ContentHash) -> Result<StageKey> {
        Ok(StageKey {
            stage: "model-labels".into(),
            stage_version: MODEL_STAGE_VERSION,
            format_version: ArtifactKind::Labels.current_version(),
            parameters: canonical_json(&json!({ "parts": self.params.parts })),
            resolved: canonical_json(&json!({ "parts": "dominant-joint, merged by area" })),
            inputs: vec![("model".into(), self.file_hash()?), ("poses".into(), poses)],
        })
    }

    pub fn hints(&self) -> Vec<(String, String)> {
        vec![("model".into(), crate::stages::ingest::file_name(self.file))]
    }

    fn load(&self) -> Result<BodyModel> {
        Ok(BodyModel::read(self.file)?)
    }

    /// Ingest: the template and every sample, as a pose set (template first).
    pub fn compute_poses(&self) -> Result<StageOutput<PoseSetV2, IngestSummary>> {
        let model = self.load()?;
        let config = self.params.config()?;
        let samples = 1 + config.shapes * config.poses;
        if samples.saturating_mul(model.vertex_count()) > MAX_POSITIONS {
            bail!(
                "{}: {samples} samples of {} vertices is more than desal's {MAX_POSITIONS} positions; \
                 ask for fewer shapes or poses",
                self.file.display(),
                model.vertex_count()
            );
        }
        let per_shape = config.poses;
        let mut names = Vec::with_capacity(samples);
        let mut poses = Vec::with_capacity(samples);
        let mut groups = Vec::with_capacity(samples);
        for (k, (group, vertices)) in Sampler::new(&model, config)?.enumerate() {
            groups.push(group as u32);
            names.push(if group == 0 {
                "template".to_owned()
            } else {
                format!("s{:03}-p{:03}", group - 1, (k - 1) % per_shape)
            });
            // At the artifact's precision, so that the summary is the stored set's.
            poses.push(vertices.iter().map(|p| vec3_from_f32(vec3_to_f32(p))).collect());
        }
        let set = PoseSet::try_new(names, poses, model.faces.clone(), 0)
            .and_then(|set| set.with_groups(Some(groups)))
            .with_context(|| format!("{}", self.file.display()))?;
        let summary = IngestSummary::of(&set, desal_mesh::FaceCleanup::default());
        // The set is handed over pose by pose: never held at both precisions.
        let body = PoseSetV2::from_owned_pose_set(set);
        let note = format!(
            "{} model: {} vertices, {} joints; template + {} shapes × {per_shape} poses",
            model.kind.name(),
            model.vertex_count(),
            model.joint_count(),
            self.params.shapes
        );
        Ok(StageOutput { body, summary, note })
    }

    /// Labels: the skinning weights' dominant joints, merged to about `parts` parts.
    pub fn compute_labels(&self, set: &PoseSet) -> Result<StageOutput<LabelsV1, LabelsSummary>> {
        let model = self.load()?;
        if model.vertex_count() != set.vertex_count() {
            bail!("{}: the model has changed since its pose set was made", self.file.display());
        }
        let labels = labels_from_weights(&model, self.params.parts);
        labels
            .check_parts_fittable(set.template_positions())
            .with_context(|| format!("{}: parts from the skinning weights", self.file.display()))?;
        let sizes: Vec<usize> = labels.members().iter().map(Vec::len).collect();
        let note = format!(
            "{} parts from the skinning weights of {} joints, smallest has {} vertices",
            labels.part_count(),
            model.joint_count(),
            sizes.iter().min().unwrap_or(&0)
        );
        let summary = LabelsSummary { parts: labels.names.clone(), vertices_per_part: sizes };
        Ok(StageOutput { body: LabelsV1::from_labels(&labels), summary, note })
    }
}

/// A model dataset's stage 3 keeps model vertices: subset placement unless a method sets
/// its own (all of desal's do: subset). `placement = "optimal"` is refused, because
/// `model.npz` is the model on the kept vertices and an optimal placement moves them off
/// the model.
pub fn use_subset_placement(simplify: &mut SimplifyParams) -> Result<()> {
    if simplify.given.contains(&"placement") && simplify.placement != Placement::Subset {
        bail!(
            "[simplify] placement = \"{}\": a [dataset.model] is simplified with subset placement, so that \
             every kept vertex is a model vertex and model.npz is the model on them; remove `placement` \
             or set it to \"subset\"",
            simplify.placement.name()
        );
    }
    simplify.placement = Placement::Subset;
    Ok(())
}

/// `model.json`: what [`simplified_model`] did.
#[derive(Debug, Clone, Serialize)]
pub struct SimplifiedModelSummary {
    /// `SMPL`, `SMPL-H`, `SMPL-X`, `MANO` or `FLAME`.
    pub kind: String,
    /// The input's file name; `model.npz` is an npz whatever the input was.
    pub source: String,
    pub vertices_in: usize,
    /// Keys of a `.pkl` with no plain numpy form (dicts, lists), left out, each with why.
    pub dropped: Vec<(String, String)>,
    #[serde(flatten)]
    pub subset: SubsetReport,
}

/// The model file a model dataset's outputs are made from, and whether they include
/// every sample simplified.
#[derive(Debug, Clone)]
pub struct ModelSource {
    pub file: PathBuf,
    /// [`ModelParams::write_poses`].
    pub write_poses: bool,
}

impl ModelInput<'_> {
    pub fn to_owned(&self) -> ModelSource {
        ModelSource { file: self.file.to_owned(), write_poses: self.params.write_poses }
    }
}

/// `model.npz` (its bytes) and `model.json`: the model restricted to the map's kept
/// vertices and triangles (`simp_to_orig`, subset placement), its joint regressor solved
/// on the kept vertices; see `desal_bodymodel::subset`.
pub fn simplified_model(source: &ModelSource, map: &MapV1) -> Result<(Vec<u8>, SimplifiedModelSummary)> {
    let file = &source.file;
    if map.mode != "subset" {
        bail!(
            "{}: model.npz needs a subset map (every kept vertex a model vertex), this one is '{}'",
            file.display(),
            map.mode
        );
    }
    let model = BodyModel::read(file)?;
    let (small, subset) = subset_model(&model, &map.simp_to_orig, &map.faces, &SubsetConfig::default())
        .with_context(|| format!("{}: the simplified model", file.display()))?;
    let written = small.to_npz().with_context(|| format!("{}: model.npz", file.display()))?;
    let summary = SimplifiedModelSummary {
        kind: model.kind.name().to_owned(),
        source: crate::stages::ingest::file_name(file),
        vertices_in: model.vertex_count(),
        dropped: written.dropped,
        subset,
    };
    Ok((written.bytes, summary))
}
