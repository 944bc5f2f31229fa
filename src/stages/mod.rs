//! Stage adapters: for each stage, its cache key, the call into its crate, the
//! conversion to and from its artifact, and the files it leaves in the output folder.

pub mod fit;
pub mod map;
pub mod saliency;
pub mod simplify;

use anyhow::Result;
use desal_io::artifact::{ArtifactKind, FitV1, LabelsV1, MapV1, PoseSetV1, SaliencyV1, SimplifiedV1};
use serde_json::json;

use crate::cache::StageKey;
use crate::ingest;
use crate::pipeline::{Dataset, canonical_json};
use crate::progress::StepProgress;
use std::cell::OnceCell;

use desal_mesh::{PartLabels, PoseSet};

use crate::run::{Counts, DatasetOutputs, Stage, StageRunner, Staged};

/// Version of each stage's algorithm as the driver runs it; bump when the output for the
/// same input and parameters changes.
pub const INGEST_VERSION: u32 = 1;
pub const LABELS_VERSION: u32 = 1;

/// The stages of one dataset, run or found in the cache. Bodies are decoded lazily.
#[derive(Debug)]
pub struct DatasetStages {
    pub poses: Staged<PoseSetV1>,
    pub labels: Staged<LabelsV1>,
    pub fit: Staged<FitV1>,
    pub saliency: Staged<SaliencyV1>,
    pub simplified: Staged<SimplifiedV1>,
    pub map: Staged<MapV1>,
}

/// Runs (or finds in the cache) every stage of `dataset`.
pub fn run_stages(
    dataset: &Dataset,
    runner: &mut StageRunner,
    progress: &StepProgress,
) -> Result<DatasetStages> {
    let spec = &dataset.spec;
    // Ingest: keyed on the bytes of every pose file, never on their paths.
    let file_hashes = ingest::hash_files(&dataset.pose_files)?;
    let template = ingest::resolve_template(&dataset.pose_files, spec.template.as_ref())?;
    let names: Vec<String> = dataset.pose_files.iter().map(|f| ingest::pose_name(f)).collect();
    let key = StageKey {
        stage: "ingest".into(),
        stage_version: INGEST_VERSION,
        format_version: ArtifactKind::PoseSet.current_version(),
        parameters: canonical_json(&json!({
            "names": names,
            "template": template,
            "ignore_pose_faces": spec.ignore_pose_faces,
        })),
        inputs: file_hashes.iter().enumerate().map(|(k, h)| (format!("pose[{k}]"), *h)).collect(),
    };
    // Hints are file names only: the producer is hashed, and paths must not reach a key.
    let hints: Vec<(String, String)> =
        dataset.pose_files.iter().enumerate().map(|(k, f)| (format!("pose[{k}]"), file_name(f))).collect();
    let poses = runner.stage(Stage::Ingest, key, &hints, || {
        let (set, summary) =
            ingest::ingest_poses(&dataset.pose_files, template, spec.ignore_pose_faces, progress)?;
        let note = format!(
            "{} poses x {} vertices, {} faces, template {}",
            summary.poses, summary.vertices, summary.faces, summary.template
        );
        Ok((PoseSetV1::from_pose_set(&set), serde_json::to_value(&summary)?, note))
    })?;
    // Decoded once, and only if a later stage has to run.
    let set_cell = OnceCell::new();
    let set = || -> Result<&PoseSet> { get_or_try_init(&set_cell, || Ok(poses.body()?.to_pose_set()?)) };

    // Labels: validated against the pose set; keyed on the labels file's bytes.
    let labels_hash = ingest::hash_files(std::slice::from_ref(&dataset.labels_file))?[0];
    let key = StageKey {
        stage: "labels".into(),
        stage_version: LABELS_VERSION,
        format_version: ArtifactKind::Labels.current_version(),
        parameters: "{}".into(),
        inputs: vec![("poses".into(), poses.hash), ("labels_file".into(), labels_hash)],
    };
    let hints = vec![("labels_file".to_owned(), file_name(&dataset.labels_file))];
    let labels = runner.stage(Stage::Ingest, key, &hints, || {
        let labels = ingest::ingest_labels(&dataset.labels_file, set()?)?;
        let sizes: Vec<_> = labels.members().iter().map(Vec::len).collect();
        let summary = json!({ "parts": labels.names, "vertices_per_part": sizes });
        let note = format!(
            "{} parts, smallest has {} vertices",
            labels.part_count(),
            sizes.iter().min().unwrap_or(&0)
        );
        Ok((LabelsV1::from_labels(&labels), summary, note))
    })?;
    let labels_cell = OnceCell::new();
    let part_labels =
        || -> Result<&PartLabels> { get_or_try_init(&labels_cell, || Ok(labels.body()?.to_labels()?)) };

    // Stage 1: per-part rigid fit of the template onto every pose.
    let key = fit::key(&spec.fit, poses.hash, labels.hash);
    let fitted =
        runner.stage(Stage::Fit, key, &[], || fit::compute(&spec.fit, set()?, part_labels()?, progress))?;

    // Stage 2: deformation saliency from the residuals.
    let key = saliency::key(&spec.saliency, poses.hash, fitted.hash);
    let salient = runner.stage(Stage::Saliency, key, &[], || {
        saliency::compute(&spec.saliency, fitted.body()?, set()?.template_mesh().diagonal())
    })?;

    // Stage 3: saliency-weighted quadric simplification of the template.
    let key = simplify::key(&spec.simplify, poses.hash, salient.hash, labels.hash);
    let simplified = runner.stage(Stage::Simplify, key, &[], || {
        let weights = &salient.body()?.weights;
        simplify::compute(&spec.simplify, &set()?.template_mesh(), weights, part_labels()?, progress)
    })?;

    // Stage 4: map the simplified vertices to original ones.
    let key = map::key(poses.hash, simplified.hash);
    let mapped =
        runner.stage(Stage::Map, key, &[], || map::compute(simplified.body()?, set()?, part_labels()?))?;

    Ok(DatasetStages { poses, labels, fit: fitted, saliency: salient, simplified, map: mapped })
}

/// `OnceCell::get_or_try_init`, which is not stable yet.
fn get_or_try_init<T>(cell: &OnceCell<T>, init: impl FnOnce() -> Result<T>) -> Result<&T> {
    if let Some(value) = cell.get() {
        return Ok(value);
    }
    let value = init()?;
    Ok(cell.get_or_init(|| value))
}

impl DatasetStages {
    /// Input and output counts, from the stages' summaries (no body is decoded).
    pub fn counts(&self) -> (Counts, Counts) {
        let get = |v: &serde_json::Value, k: &str| v.get(k).and_then(|x| x.as_u64()).unwrap_or(0) as usize;
        let i = &self.poses.summary;
        let m = &self.map.summary;
        let input = Counts { vertices: get(i, "vertices"), faces: get(i, "faces"), poses: get(i, "poses") };
        let output = Counts {
            vertices: get(m, "simplified_vertices"),
            faces: get(m, "simplified_faces"),
            poses: get(m, "poses"),
        };
        (input, output)
    }

    /// Everything the dataset's output folder holds (decodes the bodies it needs).
    pub fn outputs(self, spec: &crate::pipeline::DatasetToml) -> Result<DatasetOutputs> {
        let set = self.poses.body()?.to_pose_set()?;
        let part_labels = self.labels.body()?.to_labels()?;
        let (simple_set, simple_labels) = map::apply(self.map.body()?, &set, &part_labels)?;
        let (input, output) = self.counts();
        let mut outputs = DatasetOutputs { input, output, artifacts: Vec::new(), files: Vec::new() };
        add_saliency_pictures(
            &mut outputs,
            set.template_mesh(),
            self.saliency.body()?.saliency.clone(),
            spec.up_axis.as_deref(),
        )?;
        let raw = map::raw_template(self.simplified.body()?);
        add_simplified_pose_set(&mut outputs, raw, self.map.body()?, simple_set, simple_labels);
        add_artifact(&mut outputs, "poses", self.poses.artifact_path, self.poses.summary);
        add_artifact(&mut outputs, "labels", self.labels.artifact_path, self.labels.summary);
        add_artifact(&mut outputs, "fit", self.fit.artifact_path, self.fit.summary);
        add_artifact(&mut outputs, "saliency", self.saliency.artifact_path, self.saliency.summary);
        add_artifact(&mut outputs, "simplified", self.simplified.artifact_path, self.simplified.summary);
        add_artifact(&mut outputs, "map", self.map.artifact_path, self.map.summary);
        Ok(outputs)
    }
}

/// `saliency.png` (the paper's Fig. 1) and `saliency.ply` (colours + a `saliency`
/// float property) of the template.
fn add_saliency_pictures(
    outputs: &mut DatasetOutputs,
    template: desal_mesh::TriMesh,
    saliency: Vec<f64>,
    up_axis: Option<&str>,
) -> Result<()> {
    let up = crate::pictures::parse_up_axis(up_axis)?;
    let png = crate::pictures::heatmap_png(
        &template,
        desal_viz::Scalar::PerVertex(&saliency),
        up,
        "deformation saliency",
        "0-1",
        Some((0.0, 1.0)),
    )?;
    outputs.files.push(("saliency.png".into(), Box::new(move |p| Ok(desal_io::write_atomic(p, &png)?))));
    outputs.files.push((
        "saliency.ply".into(),
        Box::new(move |p| crate::pictures::write_scalar_ply(p, &template, "saliency", &saliency)),
    ));
    Ok(())
}

/// Puts `<name>.dsa` (the cached artifact) and `<name>.json` (its summary) in the outputs.
fn add_artifact(
    outputs: &mut DatasetOutputs,
    name: &str,
    artifact: std::path::PathBuf,
    summary: serde_json::Value,
) {
    outputs.artifacts.push((format!("{name}.dsa"), artifact));
    outputs.files.push((format!("{name}.json"), Box::new(move |p| Ok(desal_io::write_json(p, &summary)?))));
}

fn file_name(path: &std::path::Path) -> String {
    path.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned())
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
        _ => writeln!(out, "    ({kind} artifacts are summarised once their stage is wired in)")?,
    }
    Ok(())
}

/// The registered simplified pose set: `simplified/<pose>.ply` for every pose,
/// `simplified/parts.txt`, `vertex_map.txt` (one original index per simplified vertex,
/// in simplified-vertex order) and `simplified-template-raw.ply` (stage 3's template
/// before mapping).
fn add_simplified_pose_set(
    outputs: &mut DatasetOutputs,
    raw: desal_mesh::TriMesh,
    map: &MapV1,
    set: desal_mesh::PoseSet,
    labels: desal_mesh::PartLabels,
) {
    use desal_io::ply::{PlyWriteOptions, write_ply};
    outputs.files.push((
        "simplified-template-raw.ply".into(),
        Box::new(move |p| Ok(write_ply(p, &raw, &PlyWriteOptions::default())?)),
    ));
    let text: String = map.simp_to_orig.iter().map(|i| format!("{i}\n")).collect();
    outputs
        .files
        .push(("vertex_map.txt".into(), Box::new(move |p| Ok(desal_io::write_atomic(p, text.as_bytes())?))));
    outputs.files.push((
        "simplified/parts.txt".into(),
        Box::new(move |p| Ok(desal_io::labels::write_labels_txt(p, &labels)?)),
    ));
    let set = std::sync::Arc::new(set);
    for pose in 0..set.pose_count() {
        let set = set.clone();
        outputs.files.push((
            format!("simplified/{}.ply", set.names[pose]),
            Box::new(move |p| Ok(write_ply(p, &set.pose_mesh(pose), &PlyWriteOptions::default())?)),
        ));
    }
}
