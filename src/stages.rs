//! Stage adapters: for each stage, its cache key, the call into its crate, the
//! conversion to and from its artifact, and the files it leaves in the output folder.

use anyhow::Result;
use desal_io::artifact::{ArtifactKind, LabelsV1, PoseSetV1};
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

    let counts = Counts { vertices: set.vertex_count(), faces: set.face_count(), poses: set.pose_count() };
    let ingest_summary = poses.summary.clone();
    let labels_summary = labels.summary.clone();
    Ok(DatasetOutputs {
        input: counts.clone(),
        output: counts,
        artifacts: vec![
            ("poses.dsa".into(), poses.artifact_path),
            ("labels.dsa".into(), labels.artifact_path),
        ],
        files: vec![
            ("poses.json".into(), Box::new(move |p| Ok(desal_io::write_json(p, &ingest_summary)?))),
            ("labels.json".into(), Box::new(move |p| Ok(desal_io::write_json(p, &labels_summary)?))),
        ],
    })
}

fn file_name(path: &std::path::Path) -> String {
    path.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned())
}

/// Summary lines of a stage artifact for `desal inspect`.
pub fn describe_stage_artifact(path: &std::path::Path, kind: ArtifactKind, out: &mut String) -> Result<()> {
    use std::fmt::Write as _;
    let _ = path;
    writeln!(out, "    ({kind} artifacts are summarised once their stage is wired in)")?;
    Ok(())
}
