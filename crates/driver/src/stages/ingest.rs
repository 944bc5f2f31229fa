//! Ingest and labels, the stages before stage 1: pose files and a labels file in, a validated `PoseSet` and `PartLabels` out.
//! Every check that can fail on user input happens here, before anything is written.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use desal_io::ContentHash;
use desal_io::artifact::{ArtifactKind, LabelsV1, PoseSetV2};
use desal_mesh::validate::{check_same_faces, clean_faces};
use desal_mesh::{Face, FaceCleanup};
use desal_mesh::{PartLabels, PoseSet, Progress, TriMesh};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::json;

use crate::cache::{StageKey, canonical_json};
use crate::stages::runner::StageOutput;

/// Version of ingest (reading and validating the pose files) as the driver runs it;
/// bump when its output for the same files and parameters changes.
/// 2: the readers refuse what they once let through (issue 12: lying counts, extra ASCII
/// values, duplicate PLY properties), so entries made from such files are not served.
pub const INGEST_VERSION: u32 = 2;
/// Version of the labels stage (reading and validating the labels file).
/// 2: empty parts refused in text and JSON alike; parts checked at the fit's threshold.
pub const LABELS_VERSION: u32 = 2;

/// Which pose is the template: a pose file name or stem, or a 0-based index into the
/// sorted list.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum TemplateSpec {
    Index(usize),
    Name(String),
}

/// What ingest reads: the pose files and how to treat them.
#[derive(Debug, Clone, Copy)]
pub struct IngestParams<'a> {
    /// Pose files, in pose order.
    pub pose_files: &'a [PathBuf],
    pub template: Option<&'a TemplateSpec>,
    /// Use the template's triangles for every pose instead of requiring identical lists.
    pub ignore_pose_faces: bool,
    /// The group file (`groups`): one group id per pose.
    pub groups: Option<&'a Path>,
}

impl IngestParams<'_> {
    /// The cache key: the bytes of every pose file (never their paths), the pose names,
    /// the resolved template index, the group file's bytes.
    pub fn key(&self) -> Result<(StageKey, usize)> {
        let file_hashes = hash_files(self.pose_files)?;
        let groups = self.groups.map(hash_file).transpose()?;
        let template = resolve_template(self.pose_files, self.template)?;
        let names: Vec<String> = self.pose_files.iter().map(|f| pose_name(f)).collect();
        let parameters = canonical_json(&json!({
            "names": names,
            "template": template,
            "ignore_pose_faces": self.ignore_pose_faces,
        }));
        let key = StageKey {
            stage: "ingest".into(),
            stage_version: INGEST_VERSION,
            format_version: ArtifactKind::PoseSet.current_version(),
            resolved: parameters.clone(),
            parameters,
            inputs: file_hashes
                .iter()
                .enumerate()
                .map(|(k, h)| (format!("pose[{k}]"), *h))
                .chain(groups.map(|h| ("groups".to_owned(), h)))
                .collect(),
        };
        Ok((key, template))
    }

    /// Human-readable names of the key's inputs (file names only: paths never reach a key).
    pub fn hints(&self) -> Vec<(String, String)> {
        let poses = self.pose_files.iter().enumerate().map(|(k, f)| (format!("pose[{k}]"), file_name(f)));
        poses.chain(self.groups.map(|g| ("groups".to_owned(), file_name(g)))).collect()
    }

    /// Reads and validates the pose files as a stage output.
    pub fn compute(
        &self,
        template: usize,
        progress: &dyn Progress,
    ) -> Result<StageOutput<PoseSetV2, IngestSummary>> {
        let (set, summary) = ingest_poses(self.pose_files, template, self.ignore_pose_faces, progress)?;
        let (summary, set) = match self.groups {
            Some(file) => {
                let groups = desal_io::groups::read_groups(file, set.pose_count())?;
                let set = set.with_groups(Some(groups))?;
                (IngestSummary { groups: set.group_count(), ..summary }, set)
            }
            None => (summary, set),
        };
        let mut note = format!(
            "{} poses x {} vertices, {} faces, template {}",
            summary.poses, summary.vertices, summary.faces, summary.template
        );
        if let Some(groups) = summary.groups {
            note += &format!(", {groups} groups");
        }
        Ok(StageOutput { body: PoseSetV2::from_pose_set(&set), summary, note })
    }
}

/// The labels stage's key: the labels file's bytes, and the pose set they label.
pub fn labels_key(labels_file: &Path, poses: ContentHash) -> Result<StageKey> {
    let labels_hash = hash_file(labels_file)?;
    Ok(StageKey {
        stage: "labels".into(),
        stage_version: LABELS_VERSION,
        format_version: ArtifactKind::Labels.current_version(),
        parameters: "{}".into(),
        resolved: "{}".into(),
        inputs: vec![("poses".into(), poses), ("labels_file".into(), labels_hash)],
    })
}

/// `labels.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LabelsSummary {
    pub parts: Vec<String>,
    pub vertices_per_part: Vec<usize>,
}

/// Reads and validates the labels of `set` as a stage output.
pub fn compute_labels(labels_file: &Path, set: &PoseSet) -> Result<StageOutput<LabelsV1, LabelsSummary>> {
    let labels = ingest_labels(labels_file, set)?;
    let sizes: Vec<_> = labels.members().iter().map(Vec::len).collect();
    let note =
        format!("{} parts, smallest has {} vertices", labels.part_count(), sizes.iter().min().unwrap_or(&0));
    let summary = LabelsSummary { parts: labels.names.clone(), vertices_per_part: sizes };
    Ok(StageOutput { body: LabelsV1::from_labels(&labels), summary, note })
}

/// A path's file name, for hints and messages.
pub fn file_name(path: &Path) -> String {
    path.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned())
}

/// Summary of an ingest, for the JSON sidecar and the run's log.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct IngestSummary {
    pub poses: usize,
    pub vertices: usize,
    pub faces: usize,
    pub template: String,
    /// Template faces removed because they repeat a vertex (original face indices).
    pub removed_degenerate_faces: Vec<usize>,
    /// Template faces removed because they repeat an earlier face (original indices).
    pub removed_duplicate_faces: Vec<usize>,
    pub bbox_min: [f64; 3],
    pub bbox_max: [f64; 3],
    pub diagonal: f64,
    /// How many groups the poses fall in, when they have groups.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub groups: Option<usize>,
}

impl IngestSummary {
    /// The summary of an ingested pose set, with the faces ingest removed from it.
    pub fn of(set: &PoseSet, cleanup: FaceCleanup) -> Self {
        let (lo, hi) = set.template_mesh().bounding_box().expect("a pose set is never empty");
        IngestSummary {
            poses: set.pose_count(),
            vertices: set.vertex_count(),
            faces: set.face_count(),
            template: set.names[set.template].clone(),
            removed_degenerate_faces: cleanup.degenerate,
            removed_duplicate_faces: cleanup.duplicate,
            bbox_min: lo.into(),
            bbox_max: hi.into(),
            diagonal: (hi - lo).norm(),
            groups: set.group_count(),
        }
    }
}

/// BLAKE3 of each file's bytes, in parallel.
pub fn hash_files(files: &[PathBuf]) -> Result<Vec<ContentHash>> {
    files.par_iter().map(|f| hash_file(f)).collect()
}

/// BLAKE3 of one file's bytes (read under the regular-file rule).
pub fn hash_file(file: &Path) -> Result<ContentHash> {
    Ok(ContentHash::of(&desal_io::file::read_regular_file(file)?))
}

/// The pose name of a file: its stem.
pub fn pose_name(path: &Path) -> String {
    path.file_stem().map_or_else(|| path.display().to_string(), |s| s.to_string_lossy().into_owned())
}

/// Index of the template among `files`.
pub fn resolve_template(files: &[PathBuf], spec: Option<&TemplateSpec>) -> Result<usize> {
    match spec {
        None => Ok(0),
        Some(TemplateSpec::Index(i)) if *i < files.len() => Ok(*i),
        Some(TemplateSpec::Index(i)) => {
            bail!("template index {i} is out of range: there are {} poses", files.len())
        }
        Some(TemplateSpec::Name(name)) => files
            .iter()
            .position(|f| {
                pose_name(f) == *name
                    || f.file_name().is_some_and(|n| n.to_string_lossy() == *name)
                    || f.ends_with(name)
            })
            .with_context(|| format!("template '{name}' is not one of the {} pose files", files.len())),
    }
}

/// Reads every pose (in parallel), checks registration, cleans the template's faces
/// (with a warning per removal kind) and builds the pose set.
pub fn ingest_poses(
    files: &[PathBuf],
    template: usize,
    ignore_pose_faces: bool,
    progress: &dyn Progress,
) -> Result<(PoseSet, IngestSummary)> {
    if files.is_empty() {
        bail!("the pose list is empty: give at least one pose file");
    }
    progress.begin("read poses", files.len() as u64);
    let meshes: Vec<TriMesh> = files
        .par_iter()
        .map(|f| {
            let mesh = desal_io::read_mesh(f)?;
            progress.advance(1);
            Ok(mesh)
        })
        .collect::<Result<_, desal_io::IoError>>()?;
    progress.finish();

    let template_mesh = &meshes[template];
    let template_file = &files[template];
    for (file, mesh) in files.iter().zip(&meshes) {
        if mesh.vertex_count() != template_mesh.vertex_count() {
            bail!(
                "{}: has {} vertices but the template {} has {}; all poses must be registered (same vertex count and order)",
                file.display(),
                mesh.vertex_count(),
                template_file.display(),
                template_mesh.vertex_count()
            );
        }
        if !ignore_pose_faces {
            check_same_faces(&template_mesh.faces, &mesh.faces, &pose_name(file)).with_context(|| {
                format!(
                    "{}: triangle list differs from the template {}",
                    file.display(),
                    template_file.display()
                )
            })?;
        }
    }
    let (faces, cleanup) = clean_faces_with_warnings(template_file, &template_mesh.faces);
    let names: Vec<String> = files.iter().map(|f| pose_name(f)).collect();
    if let Some((i, name)) = names.iter().enumerate().find(|(i, n)| names[..*i].contains(n)) {
        bail!(
            "{}: pose name '{name}' is used twice (pose {i}); pose files need distinct stems",
            files[i].display()
        );
    }
    let poses = meshes.into_iter().map(|m| m.positions).collect();
    let set = PoseSet::try_new(names, poses, faces, template).context("invalid pose set")?;
    let summary = IngestSummary::of(&set, cleanup);
    Ok((set, summary))
}

/// Reads part labels and checks them against the pose set: one per vertex, every part
/// able to carry a rigid fit.
pub fn ingest_labels(path: &Path, set: &PoseSet) -> Result<PartLabels> {
    let labels = desal_io::labels::read_labels(path)?;
    labels.check_vertex_count(set.vertex_count()).with_context(|| format!("{}", path.display()))?;
    labels.check_parts_fittable(set.template_positions()).with_context(|| {
        format!("{}: part labels against the template '{}'", path.display(), set.names[set.template])
    })?;
    Ok(labels)
}

/// Removes degenerate (a repeated vertex) and duplicate (an earlier face's vertices)
/// faces, warning on stderr with the file and a face index: never silently.
pub fn clean_faces_with_warnings(file: &Path, faces: &[Face]) -> (Vec<Face>, FaceCleanup) {
    let (kept, cleanup) = clean_faces(faces);
    for (removed, what) in [
        (&cleanup.degenerate, "degenerate face(s) (a repeated vertex)"),
        (&cleanup.duplicate, "duplicate face(s) (same vertices as an earlier face)"),
    ] {
        if let Some(first) = removed.first() {
            eprintln!("warning: {}: removed {} {what}, e.g. face {first}", file.display(), removed.len());
        }
    }
    (kept, cleanup)
}
