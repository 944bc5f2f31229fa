//! Rig datasets (`[dataset.rig]`): a skinned glTF 2.0 file in place of pose files and a
//! labels file. Ingest reads the rig, samples its frames (the animations, seeded random
//! joint rotations, or both), poses the welded mesh by linear blend skinning and yields
//! the same `PoseSetV2` artifact as pose files do (pose 0, the template, is the bind
//! pose); the labels stage gives each welded vertex its heaviest joint, small parts
//! merged into the parent (`parts = "dominant-joint"`), as a `LabelsV1`. So fit,
//! saliency, simplify and map never know the poses came from a rig. `outputs.rs` then
//! writes `simplified.glb` through [`simplified_glb`].
//!
//! Keys: the rig file's bytes (never its path), `desal_rig::VERSION`, and every resolved
//! parameter below, destructured exhaustively.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use desal_io::ContentHash;
use desal_io::artifact::{ArtifactKind, LabelsV1, MapV1, PoseSetV2, Producer, SimplifiedV1};
use desal_rig::{EditedGlb, FrameConfig, PoseSource, PosedRig, ReadOptions, Rig, SourceDocument};
use serde::{Deserialize, Serialize};
use serde_json::json;

use crate::cache::{StageKey, canonical_json};
use crate::stages::ingest::{IngestSummary, LabelsSummary, hash_file};
use crate::stages::runner::StageOutput;

/// Version of the rig ingest and labels as the driver runs them (with `desal_rig::VERSION`).
pub const RIG_STAGE_VERSION: u32 = 1;

/// `poses = "animations" | "random" | "both"`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum PosesFrom {
    #[default]
    Animations,
    Random,
    Both,
}

/// `parts = "dominant-joint"` (the one labelling a rig has for now).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum RigParts {
    #[default]
    DominantJoint,
}

/// The `[dataset.rig]` table.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RigParams {
    /// The `.glb` or `.gltf` file (relative to the pipeline file).
    pub file: String,
    /// The meshes to simplify, `"A"` or `["A", "B"]`, each by mesh name, node name or
    /// mesh index (skinned, or below a bone); the others pass through unchanged. Unset:
    /// every skinned mesh of the file (a mesh carried by several nodes once) and every
    /// mesh below a bone. One name is written back as a string, so keys made before
    /// lists existed still match.
    #[serde(default, deserialize_with = "one_or_many", serialize_with = "one_or_many_out")]
    pub mesh: Option<Vec<String>>,
    /// Where the frames come from. Default `animations`.
    #[serde(default)]
    pub poses: PosesFrom,
    /// Frames to sample (per source with `both`). Default 60.
    #[serde(default = "default_frames")]
    pub frames: usize,
    /// Seed of the random joint rotations. Default 0.
    #[serde(default)]
    pub seed: u64,
    /// Largest random turn of a joint from its rest rotation, degrees. Default 30.
    #[serde(default = "default_max_degrees")]
    pub max_degrees: f64,
    /// How part labels are made. Default `dominant-joint`.
    #[serde(default)]
    pub parts: RigParts,
    /// Fewest vertices a joint's part may have before it joins its parent. Default 50.
    #[serde(default = "default_min_part_vertices")]
    pub min_part_vertices: usize,
    /// At most this many joint influences per vertex of `simplified.glb`, or `"all"`.
    /// Default 4 ([`DEFAULT_MAX_INFLUENCES`]: one `JOINTS_0` set, what Unity, three.js and
    /// most engines skin). Subset placement gives a vertex with more the ones of its own
    /// joints that skin it closest over the poses, renormalised; the refit fits at most
    /// this many. `"all"`: subset placement keeps the exact weights, the refit at most 4.
    /// Left out of the ingest key's parameters when unset, so that caches made before it
    /// existed still match (it shapes the output only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_influences: Option<MaxInfluences>,
    /// A LOD chain: each level's fraction of the original faces, strictly decreasing, in
    /// (0, 1] (`stages::lods`). Each level is simplified from the one before (subset
    /// placement, so they nest) and written as `simplified-lod<k>.glb`, all of them with
    /// the input as `simplified-lods.glb` (`MSFT_lod`). Unset: no chain. Left out of the
    /// key's parameters when unset, as `max_influences`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lods: Option<Vec<f64>>,
    /// `[dataset.rig.meshes."NAME"]`: a mesh's own ratio by mesh name, node name or mesh
    /// index (`ratio = 1.0` keeps it whole; `stages::meshes`). Left out of the key's
    /// parameters when empty.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub meshes: BTreeMap<String, crate::stages::meshes::MeshOverride>,
}

/// `max_influences = N | "all"`.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(untagged)]
pub enum MaxInfluences {
    Count(usize),
    All(AllInfluences),
}

/// The word `"all"` of [`MaxInfluences`].
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum AllInfluences {
    All,
}

/// Influences per vertex of the simplified rig when `max_influences` is unset (issue 42,
/// item 5): engines skin 4.
pub const DEFAULT_MAX_INFLUENCES: usize = 4;

/// `mesh = "A"` or `mesh = ["A", "B"]`.
fn one_or_many<'de, D: serde::Deserializer<'de>>(
    deserializer: D,
) -> std::result::Result<Option<Vec<String>>, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum OneOrMany {
        One(String),
        Many(Vec<String>),
    }
    // `null` (a producer record of no `mesh`) is none.
    Ok(Option::<OneOrMany>::deserialize(deserializer)?.map(|names| match names {
        OneOrMany::One(name) => vec![name],
        OneOrMany::Many(names) => names,
    }))
}

/// [`RigParams::mesh`] as written: one name as a string, several as a list.
fn one_or_many_out<S: serde::Serializer>(
    mesh: &Option<Vec<String>>,
    serializer: S,
) -> std::result::Result<S::Ok, S::Error> {
    match mesh.as_deref() {
        Some([one]) => serializer.serialize_some(one),
        Some(many) => serializer.serialize_some(many),
        None => serializer.serialize_none(),
    }
}

fn default_frames() -> usize {
    FrameConfig::default().frames
}
fn default_max_degrees() -> f64 {
    FrameConfig::default().max_degrees
}
fn default_min_part_vertices() -> usize {
    desal_rig::PartsConfig::default().min_part_vertices
}

impl RigParams {
    /// The frame settings, validated.
    pub fn frame_config(&self) -> Result<FrameConfig> {
        if self.frames == 0 {
            bail!("rig.frames must be at least 1");
        }
        if self.frames > desal_rig::MAX_FRAMES {
            bail!(
                "rig.frames = {} is more than desal's limit of {} frames per source (desal_rig::MAX_FRAMES); \
                 the pose set's memory grows with frames x vertices",
                self.frames,
                desal_rig::MAX_FRAMES
            );
        }
        if !(self.max_degrees.is_finite() && (0.0..=180.0).contains(&self.max_degrees)) {
            bail!("rig.max_degrees = {} must lie in 0..=180", self.max_degrees);
        }
        let source = match self.poses {
            PosesFrom::Animations => PoseSource::Animations,
            PosesFrom::Random => PoseSource::Random,
            PosesFrom::Both => PoseSource::Both,
        };
        Ok(FrameConfig { source, frames: self.frames, seed: self.seed, max_degrees: self.max_degrees })
    }

    /// The weight settings of the simplified rig, validated.
    pub fn weight_options(&self) -> Result<desal_rig::WeightOptions> {
        let max_influences = match self.max_influences {
            None => Some(DEFAULT_MAX_INFLUENCES),
            Some(MaxInfluences::Count(0)) => {
                bail!("rig.max_influences must be at least 1 (a vertex needs a joint to follow), or \"all\"")
            }
            Some(MaxInfluences::Count(n)) => Some(n),
            Some(MaxInfluences::All(_)) => None,
        };
        Ok(desal_rig::WeightOptions { max_influences })
    }

    /// The LOD chain's fractions, checked (`stages::lods::check_fractions`); empty
    /// without `lods`.
    pub fn lod_fractions(&self) -> Result<&[f64]> {
        match &self.lods {
            Some(lods) => {
                check_fractions(lods)?;
                Ok(lods)
            }
            None => Ok(&[]),
        }
    }

    /// Checks every `[dataset.rig.meshes."NAME"]` (a ratio in (0, 1]); whether each
    /// names a mesh is known once the rig is read.
    pub fn check_mesh_overrides(&self) -> Result<()> {
        self.meshes.iter().try_for_each(|(name, o)| o.check(name))
    }

    pub fn parts_config(&self) -> Result<desal_rig::PartsConfig> {
        if self.min_part_vertices < 3 {
            bail!("rig.min_part_vertices must be at least 3 (a part needs a rigid fit)");
        }
        Ok(desal_rig::PartsConfig { min_part_vertices: self.min_part_vertices })
    }
}

/// A rig dataset's input: the resolved file and its table.
#[derive(Debug, Clone, Copy)]
pub struct RigInput<'a> {
    pub file: &'a Path,
    pub params: &'a RigParams,
}

/// A rig dataset's input, owned (kept with the stages' results for the outputs).
#[derive(Debug, Clone)]
pub struct RigSource {
    pub file: PathBuf,
    pub params: RigParams,
}

impl RigSource {
    /// `labels`, this rig's dominant-joint parts (as a labels artifact stores them),
    /// with their joints' tree (`desal_rig::with_part_tree`): a part a simplification
    /// leaves without three non-collinear vertices then joins its parent joint's part.
    pub fn with_part_tree(&self, labels: desal_mesh::PartLabels) -> Result<desal_mesh::PartLabels> {
        let rig = desal_rig::read_rig(&self.file, &ReadOptions { mesh: self.params.mesh.clone() })?;
        Ok(desal_rig::with_part_tree(&rig, labels))
    }
}

impl RigInput<'_> {
    pub fn to_owned(&self) -> RigSource {
        RigSource { file: self.file.to_owned(), params: self.params.clone() }
    }

    fn file_hash(&self) -> Result<ContentHash> {
        hash_file(self.file)
    }

    /// The ingest key: the rig's bytes and every setting that shapes the pose set.
    pub fn ingest_key(&self) -> Result<StageKey> {
        let FrameConfig { source, frames, seed, max_degrees } = self.params.frame_config()?;
        let resolved = canonical_json(&json!({
            "mesh": self.params.mesh,
            "source": format!("{source:?}"),
            "frames": frames,
            "seed": seed,
            "max_degrees": max_degrees,
            "rig_version": desal_rig::VERSION,
        }));
        Ok(StageKey {
            stage: "rig-ingest".into(),
            stage_version: RIG_STAGE_VERSION,
            format_version: ArtifactKind::PoseSet.current_version(),
            parameters: canonical_json(self.params),
            resolved,
            inputs: vec![("rig".into(), self.file_hash()?)],
        })
    }

    /// The labels key: the rig's bytes, the pose set, the part settings.
    pub fn labels_key(&self, poses: ContentHash) -> Result<StageKey> {
        let desal_rig::PartsConfig { min_part_vertices } = self.params.parts_config()?;
        Ok(StageKey {
            stage: "rig-labels".into(),
            stage_version: RIG_STAGE_VERSION,
            format_version: ArtifactKind::Labels.current_version(),
            parameters: canonical_json(
                &json!({"parts": self.params.parts, "min_part_vertices": min_part_vertices}),
            ),
            resolved: canonical_json(&json!({
                "parts": "dominant-joint",
                "min_part_vertices": min_part_vertices,
                "rig_version": desal_rig::VERSION,
            })),
            inputs: vec![("rig".into(), self.file_hash()?), ("poses".into(), poses)],
        })
    }

    pub fn hints(&self) -> Vec<(String, String)> {
        vec![("rig".into(), crate::stages::ingest::file_name(self.file))]
    }

    /// The plan of stage 3 over the rig's meshes (`stages::meshes::MeshPlan`) for `set`,
    /// its pose set, under `target`; `None` when stage 3 runs once. An override naming
    /// no mesh is refused, naming the file.
    pub fn mesh_plan(
        &self,
        set: &desal_mesh::PoseSet,
        target: desal_simplify::Target,
    ) -> Result<Option<crate::stages::meshes::MeshPlan>> {
        let rig = desal_rig::read_rig(self.file, &ReadOptions { mesh: self.params.mesh.clone() })?;
        let weld = desal_rig::Weld::new(&rig.mesh);
        if weld.welded_count() != set.vertex_count() {
            bail!("{}: the rig has changed since its pose set was made", self.file.display());
        }
        let welded_end = |split_end: u32| {
            (split_end as usize).checked_sub(1).map_or(0, |last| weld.split_to_welded[last] + 1)
        };
        let meshes: Vec<crate::stages::meshes::MeshOfRig> = rig
            .meshes
            .iter()
            .map(|part| {
                let mut aliases = vec![part.name.clone(), part.mesh.to_string()];
                aliases.extend(rig.nodes[part.node].name.clone());
                crate::stages::meshes::MeshOfRig {
                    name: part.name.clone(),
                    aliases,
                    vertices: [welded_end(part.vertices.start), welded_end(part.vertices.end)],
                }
            })
            .collect();
        crate::stages::meshes::MeshPlan::new(self.file, &meshes, set, target, &self.params.meshes)
    }

    /// Reads the rig, keeping its whole document, and poses it at its frames: what the
    /// simplified rig is written from.
    pub fn load_with_document(&self) -> Result<(Rig, SourceDocument, PosedRig)> {
        let config = self.params.frame_config()?;
        self.load_with_document_at(|_| config)
    }

    /// [`RigInput::load_with_document`], posed for fitting the written rig's capped
    /// weights ([`simplified_rig`]): at the dataset's frames and, when they hold no random
    /// turns (`poses = "animations"`), as many random turns of every joint (the dataset's
    /// seed and largest turn). An animation moves some joints only together, and weights
    /// fitted to its frames alone skin other poses worse than the largest weights do: the
    /// rig sample's LOD 1 at 4 influences had 3.2e-7 held-out v2f against 1.7e-7 for
    /// gltfpack's top 4, and 6.6e-8 with the turns (EVAL.md, "LOD levels").
    pub fn load_for_output(&self) -> Result<(Rig, SourceDocument, PosedRig)> {
        let config = self.params.frame_config()?;
        self.load_with_document_at(|rig| {
            // Within the limits the dataset's own frames are checked against.
            let frames = config.frames.saturating_mul(2);
            let fits = frames.saturating_mul(rig.nodes.len()) <= desal_rig::MAX_POSE_NODES
                && (frames + 1).saturating_mul(rig.mesh.vertex_count()) <= desal_rig::MAX_POSE_VERTICES;
            if config.source == PoseSource::Animations && fits {
                FrameConfig { source: PoseSource::Both, ..config }
            } else {
                config
            }
        })
    }

    /// Reads the rig and its document and poses it at the frames `config` gives for it.
    fn load_with_document_at(
        &self,
        config: impl FnOnce(&Rig) -> FrameConfig,
    ) -> Result<(Rig, SourceDocument, PosedRig)> {
        let options = ReadOptions { mesh: self.params.mesh.clone() };
        let bytes = desal_io::file::read_regular_file(self.file)?;
        let (rig, document) = desal_rig::read_rig_and_document(self.file, &bytes, &options)?;
        let frames = desal_rig::sample_frames(&rig, &config(&rig), self.file)?;
        let posed = desal_rig::pose_rig(&rig, &frames).with_context(|| format!("{}", self.file.display()))?;
        Ok((rig, document, posed))
    }

    /// Reads the rig and poses it at its frames.
    pub fn load(&self) -> Result<(Rig, PosedRig)> {
        let options = ReadOptions { mesh: self.params.mesh.clone() };
        let rig = desal_rig::read_rig(self.file, &options)?;
        let frames = desal_rig::sample_frames(&rig, &self.params.frame_config()?, self.file)?;
        let posed = desal_rig::pose_rig(&rig, &frames).with_context(|| format!("{}", self.file.display()))?;
        Ok((rig, posed))
    }

    /// Ingest: the posed, welded rig as a pose set.
    pub fn compute_poses(&self) -> Result<StageOutput<PoseSetV2, IngestSummary>> {
        let (rig, posed) = self.load()?;
        let set = &posed.poses;
        let summary = IngestSummary::of(set, desal_mesh::FaceCleanup::default());
        let note = format!(
            "rig '{}': {} split -> {} welded vertices, {} joints, {} poses (bind + {} frames)",
            rig.mesh.name,
            rig.mesh.vertex_count(),
            set.vertex_count(),
            rig.skin.joints.len(),
            set.pose_count(),
            set.pose_count() - 1
        );
        let note = match rig.weight_sums.note() {
            Some(renormalised) => format!("{note}; {renormalised}"),
            None => note,
        };
        Ok(StageOutput { body: PoseSetV2::from_pose_set(set), summary, note })
    }

    /// Labels: each welded vertex's heaviest joint, small parts merged into the parent.
    pub fn compute_labels(&self, set: &desal_mesh::PoseSet) -> Result<StageOutput<LabelsV1, LabelsSummary>> {
        let (rig, posed) = self.load()?;
        if posed.poses.vertex_count() != set.vertex_count() {
            bail!("{}: the rig has changed since its pose set was made", self.file.display());
        }
        let labels = desal_rig::dominant_joint_parts(&rig, &posed.influences, &self.params.parts_config()?);
        labels.check_parts_fittable(set.template_positions()).with_context(|| {
            format!("{}: dominant-joint parts (raise rig.min_part_vertices)", self.file.display())
        })?;
        let sizes: Vec<usize> = labels.members().iter().map(Vec::len).collect();
        let note = format!(
            "{} dominant-joint parts of {} joints, smallest has {} vertices",
            labels.part_count(),
            rig.skin.joints.len(),
            sizes.iter().min().unwrap_or(&0)
        );
        let summary = LabelsSummary { parts: labels.names.clone(), vertices_per_part: sizes };
        Ok(StageOutput { body: LabelsV1::from_labels(&labels), summary, note })
    }
}

/// The rig a pose set was ingested from, for writing its simplified rig outside `desal
/// run` (`desal map --glb`): the `[dataset.rig]` settings come from the pose set's
/// producer record, and `file` must hold the very bytes it records (the record keeps the
/// rig's content hash and file name, never its path).
pub fn source_of_pose_set(producer: &Producer, poses: &Path, file: &Path) -> Result<RigSource> {
    if producer.stage != "rig-ingest" {
        bail!(
            "{} was made by stage '{}', not from a skinned glTF rig: a simplified rig can only be \
             written for a pose set that `desal run` ingested from a [dataset.rig]",
            poses.display(),
            producer.stage
        );
    }
    if producer.stage_version != RIG_STAGE_VERSION {
        bail!(
            "{} was ingested by rig stage version {}, this desal has {}: re-run `desal run` to remake it",
            poses.display(),
            producer.stage_version,
            RIG_STAGE_VERSION
        );
    }
    let params: RigParams = serde_json::from_str(&producer.parameters)
        .with_context(|| format!("{}: its rig settings cannot be read", poses.display()))?;
    let recorded = producer
        .inputs
        .iter()
        .find(|i| i.role == "rig")
        .with_context(|| format!("{}: its producer record names no rig", poses.display()))?;
    let actual = hash_file(file)?;
    if actual != recorded.hash {
        bail!(
            "{} is not the rig {} was ingested from (that was '{}', with other bytes)",
            file.display(),
            poses.display(),
            recorded.hint
        );
    }
    Ok(RigSource { file: file.to_owned(), params })
}

/// A LOD chain's files: each level's rig (`simplified-lod<k>.glb`), all levels with the
/// input in one (`simplified-lods.glb`, `MSFT_lod`), and each level's figures.
#[derive(Debug, Clone)]
pub struct LodGlbs {
    pub levels: Vec<EditedGlb>,
    pub combined: EditedGlb,
    pub figures: Vec<LodFigures>,
}

/// One row of [`SimplifiedRigSummary::lods`]: the level's stage figures and its rig's.
#[derive(Debug, Clone, Serialize)]
pub struct LodFigures {
    #[serde(flatten)]
    pub level: LodSummary,
    /// `simplified-lod<k>.glb` (`.vrm` for a `.vrm`).
    pub file: String,
    /// Vertices and faces of the written primitives (seam copies included).
    pub output_vertices: usize,
    pub output_faces: usize,
    pub seam_vertices: usize,
    pub cross_chart_faces: usize,
    /// `MSFT_screencoverage` of the level in `simplified-lods.glb`.
    pub screen_coverage: f64,
}

/// The screen coverage (share of the screen) down to which each level of
/// `simplified-lods.glb` is shown, the input first: level `k` until the coverage falls
/// below half the next level's face fraction, so that the faces per screen area stay
/// about even; the coarsest level is never culled (0). A starting point for engines that
/// read `MSFT_screencoverage` (Babylon.js); they tune their own.
pub fn screen_coverage(fractions: &[f64]) -> Vec<f64> {
    let mut coverage: Vec<f64> = fractions.iter().map(|f| 0.5 * f).collect();
    coverage.push(0.0);
    coverage
}

/// The file name of LOD level `level` (`simplified-lod<k>`) or of the chain (`None`:
/// `simplified-lods`), with the input's extension (`.vrm` for a `.vrm`).
pub fn lod_file_name(source: &RigSource, level: Option<usize>) -> String {
    let extension = simplified_file_name(source).rsplit('.').next().unwrap_or("glb");
    match level {
        Some(k) => format!("simplified-lod{k}.{extension}"),
        None => format!("simplified-lods.{extension}"),
    }
}

/// The rigs of a LOD chain (`levels`: each level's map into the pose set, finest
/// first, with its summary): one edited document per level and the chain in one, each
/// level's weights exact (subset placement) and capped at `max_influences`.
pub fn lod_glbs(source: &RigSource, levels: &[(&MapV1, &LodSummary)]) -> Result<LodGlbs> {
    let input = RigInput { file: &source.file, params: &source.params };
    let options = source.params.weight_options()?;
    let (rig, document, posed) = input.load_for_output()?;
    let template = posed.poses.template_positions();
    let mut rigs = Vec::with_capacity(levels.len());
    let mut files = Vec::with_capacity(levels.len());
    let mut figures = Vec::with_capacity(levels.len());
    let fractions: Vec<f64> = levels.iter().map(|(_, s)| s.fraction).collect();
    let coverage = screen_coverage(&fractions);
    for (k, (map, summary)) in levels.iter().enumerate() {
        let simplified = SimplifiedV1 {
            positions: map.simp_to_orig.iter().map(|&o| template[o as usize].into()).collect(),
            faces: map.faces.clone(),
            simp_to_orig: map.simp_to_orig.iter().map(|&o| Some(o)).collect(),
            placement: "subset".into(),
            input_vertices: template.len() as u32,
            input_faces: posed.poses.faces.len() as u32,
            collapses: 0,
            stop: summary.stop.clone(),
            max_error: summary.max_error,
            mean_error: f64::NAN,
            edge_length_mean: f64::NAN,
            edge_length_variance: f64::NAN,
        };
        let (out, report) = simplified_rig(&rig, &posed, &simplified, map, &options)
            .with_context(|| format!("LOD level {}", k + 1))?;
        files.push(desal_rig::write_edited(&document, &rig, &out)?);
        figures.push(LodFigures {
            level: (*summary).clone(),
            file: lod_file_name(source, Some(k + 1)),
            output_vertices: report.output_vertices,
            output_faces: report.output_faces,
            seam_vertices: report.seam_vertices,
            cross_chart_faces: report.cross_chart_faces,
            screen_coverage: coverage[k + 1],
        });
        rigs.push(out);
    }
    let combined = desal_rig::write_lods(&document, &rig, &rigs, &coverage)?;
    Ok(LodGlbs { levels: files, combined, figures })
}

/// `simplified.glb`'s JSON sidecar (`simplified-rig.json`).
#[derive(Debug, Clone, Serialize)]
pub struct SimplifiedRigSummary {
    pub placement: String,
    pub weights: &'static str,
    pub simplified_vertices: usize,
    pub output_vertices: usize,
    pub output_faces: usize,
    pub seam_vertices: usize,
    pub cross_chart_faces: usize,
    pub refitted_vertices: usize,
    pub max_influences: usize,
    /// Each glTF mesh simplified, in node order: where its vertices are in the pose set
    /// (`poses.dsa`), the simplified pose set (`simplified/*.ply`, `vertex_map.txt`) and
    /// the written mesh, as `[first, end)` ranges.
    pub meshes: Vec<MeshRanges>,
    /// The LOD chain's levels (`lods`), finest first; absent without one.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub lods: Vec<LodFigures>,
}

/// One row of [`SimplifiedRigSummary::meshes`].
#[derive(Debug, Clone, Serialize)]
pub struct MeshRanges {
    pub name: String,
    pub node: usize,
    /// Welded vertices of the pose set.
    pub pose_set_vertices: [u32; 2],
    /// Vertices of the simplified pose set: stage 3 keeps each mesh's vertices apart and
    /// in order, so they follow one another.
    pub simplified_vertices: [u32; 2],
    /// Vertices of its primitives in the written rig (seam copies included).
    pub output_vertices: [u32; 2],
}

/// Each simplified mesh's vertex ranges: the pose set's from the weld, the simplified
/// pose set's through stage 4's map, the output's from the simplified rig.
fn mesh_ranges(input: &Rig, weld: &desal_rig::Weld, map: &MapV1, out: &Rig) -> Vec<MeshRanges> {
    let welded_end =
        |split_end: u32| (split_end as usize).checked_sub(1).map_or(0, |last| weld.split_to_welded[last] + 1);
    let mut simplified_start = 0u32;
    input
        .meshes
        .iter()
        .zip(&out.meshes)
        .map(|(part, written)| {
            let welded = [welded_end(part.vertices.start), welded_end(part.vertices.end)];
            let count =
                map.simp_to_orig.iter().filter(|&&w| (welded[0]..welded[1]).contains(&w)).count() as u32;
            let simplified = [simplified_start, simplified_start + count];
            simplified_start += count;
            MeshRanges {
                name: part.name.clone(),
                node: part.node,
                pose_set_vertices: welded,
                simplified_vertices: simplified,
                output_vertices: [written.vertices.start, written.vertices.end],
            }
        })
        .collect()
}

/// The simplified rig: the input document with the simplified mesh's primitives in place
/// of its own (subset placement: exact weights; optimal: refitted), everything else the
/// input's (`desal_rig::edit`), and the external images it names.
pub fn simplified_glb(
    source: &RigSource,
    simplified: &SimplifiedV1,
    map: &MapV1,
) -> Result<(EditedGlb, SimplifiedRigSummary)> {
    let input = RigInput { file: &source.file, params: &source.params };
    let options = source.params.weight_options()?;
    let (rig, document, posed) = input.load_for_output()?;
    let (out, report) = simplified_rig(&rig, &posed, simplified, map, &options)?;
    let edited = desal_rig::write_edited(&document, &rig, &out)?;
    let subset = simplified.simp_to_orig.iter().all(Option::is_some);
    let summary = SimplifiedRigSummary {
        placement: simplified.placement.clone(),
        weights: match (subset, options.max_influences) {
            (true, None) => "exact (subset placement)",
            (true, Some(_)) => {
                "exact, capped at max_influences: of a vertex with more, the ones of its own joints that skin it \
                 closest over the poses (subset placement)"
            }
            (false, _) => "least-squares refit over the pose set",
        },
        simplified_vertices: report.simplified_vertices,
        output_vertices: report.output_vertices,
        output_faces: report.output_faces,
        seam_vertices: report.seam_vertices,
        cross_chart_faces: report.cross_chart_faces,
        refitted_vertices: report.refitted_vertices,
        max_influences: report.max_influences,
        meshes: mesh_ranges(&rig, &posed.weld, map, &out),
        lods: Vec::new(),
    };
    Ok((edited, summary))
}

/// The simplified rig's file name: `simplified.vrm` for a `.vrm` avatar, else
/// `simplified.glb`.
pub fn simplified_file_name(source: &RigSource) -> &'static str {
    let vrm = source.file.extension().is_some_and(|e| e.eq_ignore_ascii_case("vrm"));
    if vrm { "simplified.vrm" } else { "simplified.glb" }
}

/// The images a simplified rig written to `glb` names by URI, under the same relative
/// paths beside it (`desal_rig::ExternalImage::path` holds plain names only).
pub fn write_images_beside(glb: &Path, images: &[desal_rig::ExternalImage]) -> Result<()> {
    let folder = glb.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    for image in images {
        let to = folder.join(&image.path);
        if let Some(parent) = to.parent() {
            std::fs::create_dir_all(parent).with_context(|| format!("creating {}", parent.display()))?;
        }
        desal_io::write_atomic(&to, &image.bytes)?;
    }
    Ok(())
}

/// The simplified rig of a posed rig, stage 3's mesh and stage 4's map.
pub fn simplified_rig(
    rig: &Rig,
    posed: &PosedRig,
    simplified: &SimplifiedV1,
    map: &MapV1,
    options: &desal_rig::WeightOptions,
) -> Result<(Rig, desal_rig::SimplifiedReport)> {
    let positions: Vec<desal_mesh::Vec3> = simplified.positions.iter().map(|&p| p.into()).collect();
    let subset = simplified.simp_to_orig.iter().all(Option::is_some);
    let input = desal_rig::SimplifiedInput {
        positions: &positions,
        faces: &map.faces,
        simp_to_welded: &map.simp_to_orig,
        subset,
    };
    let targets = desal_rig::PoseTargets { joints: &posed.joints, positions: &posed.poses.poses };
    Ok(desal_rig::simplified_rig_with(rig, &posed.weld, &input, &targets, options)?)
}

// The LOD chain's settings check and figures, here (not in `lods.rs`) so that the rig
// stage, which checks and writes them, does not depend on the stage that makes them.

/// Checks `lods`: at least one level, each in (0, 1], strictly decreasing.
pub fn check_fractions(lods: &[f64]) -> Result<()> {
    if lods.is_empty() {
        bail!("rig.lods is empty: give the levels' fractions of the original faces, e.g. [0.5, 0.25, 0.1]");
    }
    if let Some((k, f)) = lods.iter().enumerate().find(|&(_, &f)| !(f > 0.0 && f <= 1.0)) {
        bail!("rig.lods[{k}] = {f} is not a fraction of the original faces in (0, 1]");
    }
    if let Some(k) = (1..lods.len()).find(|&k| lods[k] >= lods[k - 1]) {
        bail!(
            "rig.lods must be strictly decreasing (each level simplified from the one before): lods[{k}] = {} \
             follows {}",
            lods[k],
            lods[k - 1]
        );
    }
    Ok(())
}

/// One level's figures (`simplified-rig.json`'s `lods`, with the written file's).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LodSummary {
    /// 1 for the first level below the input.
    pub level: usize,
    /// The level's `lods` entry: its target as a fraction of the original faces.
    pub fraction: f64,
    pub target_faces: usize,
    /// Welded vertices and faces of the level (the simplified pose set's).
    pub vertices: usize,
    pub faces: usize,
    /// Stage 3's stop reason on this level (`target` or `no valid collapse`).
    pub stop: String,
    /// Stage 3's largest collapse error on this level (mesh units).
    pub max_error: f64,
    pub seconds: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> RigParams {
        toml::from_str("file = \"a.glb\"").unwrap()
    }

    /// Every setting and the file's bytes reach the keys; the path does not.
    #[test]
    fn each_key_input_changes_the_key() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.glb"), dir.path().join("b.glb"));
        std::fs::write(&a, b"one").unwrap();
        std::fs::write(&b, b"one").unwrap();
        let base = params();
        let key = |file: &Path, p: &RigParams| RigInput { file, params: p }.ingest_key().unwrap().hash();
        let reference = key(&a, &base);
        assert_eq!(key(&b, &base), reference, "the same bytes under another name");
        let variants = [
            RigParams { mesh: Some(vec!["Body".into()]), ..base.clone() },
            RigParams { mesh: Some(vec!["Body".into(), "Eyes".into()]), ..base.clone() },
            RigParams { lods: Some(vec![0.5]), ..base.clone() },
            RigParams { poses: PosesFrom::Random, ..base.clone() },
            RigParams { frames: 61, ..base.clone() },
            RigParams { seed: 1, ..base.clone() },
            RigParams { max_degrees: 31.0, ..base.clone() },
            RigParams { max_influences: Some(MaxInfluences::Count(4)), ..base.clone() },
        ];
        for v in &variants {
            assert_ne!(key(&a, v), reference, "{v:?}");
        }
        std::fs::write(&b, b"two").unwrap();
        assert_ne!(key(&b, &base), reference, "other bytes");
        let poses = ContentHash::of(b"poses");
        let labels = |p: &RigParams| RigInput { file: &a, params: p }.labels_key(poses).unwrap().hash();
        assert_ne!(labels(&RigParams { min_part_vertices: 51, ..base.clone() }), labels(&base));
    }

    #[test]
    fn defaults_and_bad_settings() {
        let p = params();
        assert_eq!(
            (p.poses, p.frames, p.seed, p.max_degrees, p.min_part_vertices),
            (PosesFrom::Animations, 60, 0, 30.0, 50)
        );
        assert!(RigParams { frames: 0, ..p.clone() }.frame_config().is_err());
        assert!(RigParams { max_degrees: 200.0, ..p.clone() }.frame_config().is_err());
        assert!(RigParams { min_part_vertices: 2, ..p.clone() }.parts_config().is_err());
        assert!(
            RigParams { max_influences: Some(MaxInfluences::Count(0)), ..p.clone() }
                .weight_options()
                .is_err()
        );
        assert_eq!(p.weight_options().unwrap().max_influences, Some(4), "engines skin 4");
        let one: RigParams = toml::from_str("file = \"a.glb\"\nmesh = \"Body\"").unwrap();
        assert_eq!(one.mesh, Some(vec!["Body".to_owned()]));
        assert_eq!(
            serde_json::to_value(&one).unwrap()["mesh"],
            "Body",
            "one name is written as before lists"
        );
        let two: RigParams = toml::from_str("file = \"a.glb\"\nmesh = [\"Body\", \"2\"]").unwrap();
        assert_eq!(serde_json::to_value(&two).unwrap()["mesh"], serde_json::json!(["Body", "2"]));
        let none: RigParams = serde_json::from_str(r#"{"file": "a.glb", "mesh": null}"#).unwrap();
        assert_eq!(none.mesh, None, "a producer record without mesh");
        assert!(toml::from_str::<RigParams>("file = \"a.glb\"\nmesh = 3").is_err());
        let all: RigParams = toml::from_str("file = \"a.glb\"\nmax_influences = \"all\"").unwrap();
        assert_eq!(all.weight_options().unwrap().max_influences, None);
        let eight: RigParams = toml::from_str("file = \"a.glb\"\nmax_influences = 8").unwrap();
        assert_eq!(eight.weight_options().unwrap().max_influences, Some(8));
        assert!(toml::from_str::<RigParams>("file = \"a.glb\"\nmax_influences = \"some\"").is_err());
        let both: RigParams = toml::from_str("file = \"a.glb\"\nposes = \"both\"").unwrap();
        assert_eq!(both.poses, PosesFrom::Both);
        assert!(toml::from_str::<RigParams>("file = \"a.glb\"\nposes = \"all\"").is_err());
        assert!(toml::from_str::<RigParams>("file = \"a.glb\"\nparts = \"auto\"").is_err());
    }
}
