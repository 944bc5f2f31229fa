//! Stage adapters: for each stage, its cache key, the call into its crate, the
//! conversion to and from its artifact, and the files it leaves in the output folder.

pub mod fit;
pub mod saliency;

use anyhow::Result;
use desal_io::artifact::{ArtifactKind, FitV1, LabelsV1, PoseSetV1, SaliencyV1};
use serde_json::json;

use crate::cache::StageKey;
use crate::ingest;
use crate::pipeline::{Dataset, canonical_json};
use crate::progress::StepProgress;
use crate::run::{Counts, DatasetOutputs, Stage, StageRunner};

/// Version of each stage's algorithm as the driver runs it; bump when the output for the
/// same input and parameters changes.
pub const INGEST_VERSION: u32 = 1;
pub const LABELS_VERSION: u32 = 1;

/// Runs every stage of `dataset`; returns what goes into its output folder.
pub fn run_stages(
    dataset: &Dataset,
    runner: &mut StageRunner,
    progress: &StepProgress,
) -> Result<DatasetOutputs> {
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
    let set = poses.body.to_pose_set()?;

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
        let labels = ingest::ingest_labels(&dataset.labels_file, &set)?;
        let sizes: Vec<_> = labels.members().iter().map(Vec::len).collect();
        let summary = json!({ "parts": labels.names, "vertices_per_part": sizes });
        let note = format!(
            "{} parts, smallest has {} vertices",
            labels.part_count(),
            sizes.iter().min().unwrap_or(&0)
        );
        Ok((LabelsV1::from_labels(&labels), summary, note))
    })?;

    let part_labels = labels.body.to_labels()?;

    // Stage 1: per-part rigid fit of the template onto every pose.
    let key = fit::key(&spec.fit, poses.hash, labels.hash);
    let fitted =
        runner.stage(Stage::Fit, key, &[], || fit::compute(&spec.fit, &set, &part_labels, progress))?;

    // Stage 2: deformation saliency from the residuals.
    let diagonal = set.template_mesh().diagonal();
    let key = saliency::key(&spec.saliency, poses.hash, fitted.hash);
    let salient = runner
        .stage(Stage::Saliency, key, &[], || saliency::compute(&spec.saliency, &fitted.body, diagonal))?;

    let counts = Counts { vertices: set.vertex_count(), faces: set.face_count(), poses: set.pose_count() };
    let mut outputs =
        DatasetOutputs { input: counts.clone(), output: counts, artifacts: Vec::new(), files: Vec::new() };
    add_artifact(&mut outputs, "poses", poses.artifact_path, poses.summary);
    add_artifact(&mut outputs, "labels", labels.artifact_path, labels.summary);
    add_artifact(&mut outputs, "fit", fitted.artifact_path, fitted.summary);
    add_artifact(&mut outputs, "saliency", salient.artifact_path, salient.summary);
    add_saliency_pictures(
        &mut outputs,
        set.template_mesh(),
        salient.body.saliency.clone(),
        spec.up_axis.as_deref(),
    )?;
    Ok(outputs)
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
        _ => writeln!(out, "    ({kind} artifacts are summarised once their stage is wired in)")?,
    }
    Ok(())
}
