//! The output folder: what `<out>/<dataset>` holds, the one writer of the registered
//! simplified pose set, and how a folder is replaced (whole, through
//! [`desal_io::replace_dir`], carrying `desal eval`'s `eval/` over).
//!
//! | file | from |
//! |---|---|
//! | `poses.dsa`, `labels.dsa`, `fit.dsa`, `saliency.dsa`, `simplified.dsa`, `map.dsa` | the stages' cache entries, copied (never linked: nothing done to the output folder reaches the cache) |
//! | `<stage>.json` | each stage's typed summary |
//! | `saliency.png`, `saliency.ply` | the saliency drawn on the template |
//! | `labels.txt`, `parts.png`, `parts.json` | with `labels = "auto"`: the discovered parts (text, drawn on the template, the discovery's figures) |
//! | `simplified-template-raw.ply` | stage 3's template before mapping |
//! | `simplified/<pose>.ply`, `simplified/parts.txt`, `vertex_map.txt` | the registered simplified pose set; a `[dataset.model]` writes the PLYs only with `write_poses = true` |
//! | `hierarchy-<k>.dsa`, `hierarchy.npz`, `hierarchy.json` | with `[dataset.hierarchy]`: each level's cache entry, the npz of every level (`stages::hierarchy::npz_arrays`), the levels' summaries |
//! | `hierarchy.png`, `upsampling-error.png`, `upsampling-error-<k>.ply` | with `[dataset.hierarchy]`: the levels side by side; the held-out per-vertex upsampling error of each level, fitted against barycentric (RMS, drawn and as PLY properties) |
//! | `simplified.glb` (`.vrm` for a `.vrm`), `simplified-rig.json`, the images it names by URI | with `[dataset.rig]`: the simplified rig, the input document edited (`stages::rig::simplified_glb`), its figures, and its external images under their relative paths |
//! | `simplified-lod<k>.glb`, `simplified-lods.glb` (`.vrm` for a `.vrm`) | with `lods` in `[dataset.rig]`: each LOD level's rig and the chain in one (`MSFT_lod`, `stages::rig::lod_glbs`); `simplified-rig.json`'s `lods` |
//! | `model.npz`, `model.json` | with `[dataset.model]`: the simplified model in the input's keys and dtypes (an npz also for a `.pkl` input), its joint regressor solved on the kept vertices (`stages::model::simplified_model`), and what the solve and the landmarks did |
//! | `view.html` | with `[dataset.rig]`: the input and the simplified rig side by side in three.js with their materials and textures, a level selector and morph-target sliders; three.js loaded from its pinned CDN URLs, or inlined from the package `DESAL_THREE` names (`viewer.rs`) |
//! | `report.json` | the run's report, with `outputs_key` |
//! | `eval/` | `desal eval`'s, kept across runs |

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use desal_io::artifact::{ContentHash, MapV1};
use desal_mesh::{PartLabels, PoseSet, TriMesh};
use serde::Serialize;

use crate::cache::canonical_json;
use crate::stages::runner::{StageRecord, Staged};
use crate::stages::{Counts, DatasetStages};

/// What the output writers write: part of [`outputs_key`], so that a folder written by
/// an older desal is rewritten, not kept as in place. Bump it whenever a writer here
/// adds, drops or changes a file. 2: the hierarchy figures and the rig viewer. 3: the
/// viewer's three.js from its CDN or `DESAL_THREE`, no `viewer/three/` copy. 4: a model
/// dataset's `model.npz` and `model.json`; the simplified rig is the input document
/// edited (every mesh, material, texture and extension kept; `simplified.vrm` for a
/// `.vrm`), its external images beside it. 5: `view.html` takes a list of levels, shows
/// the input file's own `.glb` with its materials and textures, frames the whole body,
/// has morph-target sliders. 6: a model dataset writes `simplified/<pose>.ply` only with
/// `write_poses = true`.
pub const OUTPUTS_VERSION: u32 = 6;

/// `desal eval`'s folder inside a dataset's output folder: kept when `desal run` replaces
/// the rest (it depends on the pipeline's inputs, not on the run's stage parameters).
pub const KEPT_SUBFOLDER: &str = "eval";

/// Writes one derived output file to the path it is given.
pub type FileWriter = Box<dyn FnOnce(&Path) -> Result<()> + Send>;

/// Everything a dataset run leaves in its output folder.
pub struct DatasetOutputs {
    /// `(file name in the output folder, cache artifact to copy)`.
    pub artifacts: Vec<(String, PathBuf)>,
    /// `(relative path, writer)` for derived files (PLY, PNG, text, JSON).
    pub files: Vec<(String, FileWriter)>,
}

impl std::fmt::Debug for DatasetOutputs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let files: Vec<&str> = self.files.iter().map(|(name, _)| name.as_str()).collect();
        f.debug_struct("DatasetOutputs").field("artifacts", &self.artifacts).field("files", &files).finish()
    }
}

impl DatasetOutputs {
    /// Every relative path the outputs write, in write order.
    pub fn names(&self) -> Vec<String> {
        self.artifacts
            .iter()
            .map(|(name, _)| name.clone())
            .chain(self.files.iter().map(|(n, _)| n.clone()))
            .collect()
    }

    /// Writes every output into `dir` (which exists).
    pub fn write_into(self, dir: &Path) -> Result<()> {
        for (file, source) in &self.artifacts {
            let dest = dir.join(file);
            // The source is a cache entry, which a shard sharing the cache may be replacing.
            crate::cache::read_entry_file(source, |source| std::fs::copy(source, &dest))
                .with_context(|| format!("cannot copy {} to {}", source.display(), dest.display()))?;
        }
        for (file, write) in self.files {
            let path = dir.join(&file);
            if let Some(parent) = path.parent() {
                std::fs::create_dir_all(parent)
                    .with_context(|| format!("cannot create {}", parent.display()))?;
            }
            write(&path).with_context(|| format!("cannot write {file}"))?;
        }
        Ok(())
    }
}

/// `report.json` of one dataset.
#[derive(Debug, Clone, Serialize)]
pub struct DatasetReport {
    pub dataset: String,
    pub pipeline: String,
    pub input: Counts,
    pub output: Counts,
    pub stages: Vec<StageRecord>,
    pub seconds: f64,
    pub out_dir: PathBuf,
    /// Identity of the output folder's content (see `outputs_key`).
    pub outputs_key: String,
    /// Every file the output folder holds besides report.json.
    pub files: Vec<String>,
}

/// Fills the output folder of `report`'s dataset from its `stages` and writes
/// `report.json`: a warm run (every stage cached, not `force`d) whose outputs are already
/// in place only refreshes `report.json`; otherwise the folder is built whole and swapped
/// in ([`write_outputs`]). Sets the report's `outputs_key`, `files` and `seconds`.
pub fn publish(
    report: &mut DatasetReport,
    stages: &DatasetStages,
    up_axis: Option<&str>,
    force: bool,
    start: std::time::Instant,
) -> Result<()> {
    report.outputs_key =
        outputs_key(&report.stages, up_axis, stages.model.as_ref().is_some_and(|m| m.write_poses));
    // When a stage ran (a corrupt entry recomputed, say), the folder is rewritten
    // regardless.
    if !force
        && report.stages.iter().all(|s| s.cached)
        && let Some(files) = outputs_in_place(&report.out_dir, &report.outputs_key)
    {
        report.files = files;
        report.seconds = start.elapsed().as_secs_f64();
        desal_io::write_json(&report.out_dir.join("report.json"), report)?;
        return Ok(());
    }
    let outputs = dataset_outputs(stages, up_axis)?;
    report.files = outputs.names();
    report.seconds = start.elapsed().as_secs_f64();
    write_outputs(&report.out_dir, outputs, report)
}

/// Everything the dataset's output folder holds (decodes the bodies it needs).
pub fn dataset_outputs(stages: &DatasetStages, up_axis: Option<&str>) -> Result<DatasetOutputs> {
    let set = stages.pose_set()?;
    let part_labels = stages.part_labels()?;
    let map = stages.map.body()?;
    // Built before anything is written, like the rig below, and before the simplified
    // pose set: reading the model takes a few times its file's size for a moment.
    let model_files = match &stages.model {
        Some(model) => simplified_model_files(model, map)?,
        None => Vec::new(),
    };
    // A model source's samples (thousands) are simplified only when asked for.
    let write_poses = stages.model.as_ref().is_none_or(|m| m.write_poses);
    let simplified_files = if write_poses {
        let (simple_set, simple_labels) = crate::stages::map::apply(map, set, part_labels)?;
        simplified_pose_set("simplified/", map, simple_set, simple_labels)
    } else {
        simplified_map_files("simplified/", map, crate::stages::map::labels(map, set, part_labels)?)
    };
    let mut outputs = DatasetOutputs { artifacts: Vec::new(), files: Vec::new() };
    add_saliency_pictures(
        &mut outputs,
        set.template_mesh(),
        stages.saliency.body()?.saliency.clone(),
        up_axis,
    )?;
    let raw = crate::stages::simplify::mesh(stages.simplified.body()?);
    outputs.files.push((
        "simplified-template-raw.ply".into(),
        Box::new(move |p| Ok(desal_io::ply::write_ply(p, &raw, &desal_io::ply::PlyWriteOptions::default())?)),
    ));
    outputs.files.extend(simplified_files);
    add_artifact(&mut outputs, "poses", &stages.poses)?;
    add_artifact(&mut outputs, "labels", &stages.labels)?;
    if let Some(parts) = &stages.parts {
        add_parts_files(&mut outputs, set.template_mesh(), part_labels, parts, up_axis)?;
    }
    add_artifact(&mut outputs, "fit", &stages.fit)?;
    add_artifact(&mut outputs, "saliency", &stages.saliency)?;
    add_artifact(&mut outputs, "simplified", &stages.simplified)?;
    add_artifact(&mut outputs, "map", &stages.map)?;
    if !stages.hierarchy.is_empty() {
        add_hierarchy(&mut outputs, stages, set, part_labels, up_axis)?;
    }
    outputs.files.extend(model_files);
    if let Some(rig) = &stages.rig {
        // Built before anything is written: a rig that cannot be written fails the run
        // with the output folder untouched.
        let (edited, mut summary) = crate::stages::rig::simplified_glb(rig, stages.simplified.body()?, map)?;
        // The page shows every LOD level too, under the level selector.
        let mut lod_pages: Vec<(String, Vec<u8>)> = Vec::new();
        if !stages.lods.is_empty() {
            let levels =
                stages.lods.iter().map(|l| Ok((l.body()?, &l.summary))).collect::<Result<Vec<_>>>()?;
            let lods = crate::stages::rig::lod_glbs(rig, &levels)?;
            for (k, level) in lods.levels.into_iter().enumerate() {
                let name = crate::stages::rig::lod_file_name(rig, Some(k + 1));
                let bytes = level.bytes;
                lod_pages.push((format!("LOD {}", k + 1), bytes.clone()));
                outputs.files.push((name, Box::new(move |p| Ok(desal_io::write_atomic(p, &bytes)?))));
            }
            let bytes = lods.combined.bytes;
            let name = crate::stages::rig::lod_file_name(rig, None);
            outputs.files.push((name, Box::new(move |p| Ok(desal_io::write_atomic(p, &bytes)?))));
            summary.lods = lods.figures;
        }
        for (name, page) in crate::viewer::view_files(rig, &edited.bytes, &lod_pages, &summary)? {
            outputs.files.push((name, Box::new(move |p| Ok(desal_io::write_atomic(p, &page)?))));
        }
        let bytes = edited.bytes;
        let name = crate::stages::rig::simplified_file_name(rig);
        outputs.files.push((name.into(), Box::new(move |p| Ok(desal_io::write_atomic(p, &bytes)?))));
        outputs
            .files
            .push(("simplified-rig.json".into(), Box::new(move |p| Ok(desal_io::write_json(p, &summary)?))));
        add_rig_images(&mut outputs, &rig.file, edited.images)?;
    }
    Ok(outputs)
}

/// `model.npz` and `model.json`: the model on the simplified vertices.
fn simplified_model_files(
    model: &crate::stages::model::ModelSource,
    map: &MapV1,
) -> Result<Vec<(String, FileWriter)>> {
    let (bytes, summary) = crate::stages::model::simplified_model(model, map)?;
    let summary = serde_json::to_value(&summary)?;
    Ok(vec![
        ("model.npz".into(), Box::new(move |p| Ok(desal_io::write_atomic(p, &bytes)?))),
        ("model.json".into(), Box::new(move |p| Ok(desal_io::write_json(p, &summary)?))),
    ])
}

/// The images the simplified rig names by URI, under the same relative paths as beside
/// the input; one that would go into a file or folder desal writes itself is refused (an
/// image named twice is written once).
fn add_rig_images(
    outputs: &mut DatasetOutputs,
    rig: &Path,
    images: Vec<desal_rig::ExternalImage>,
) -> Result<()> {
    let top = |name: &str| name.split('/').next().unwrap_or(name).to_owned();
    let mut ours: Vec<String> = outputs.names().iter().map(|n| top(n)).collect();
    ours.extend(["report.json".to_owned(), KEPT_SUBFOLDER.to_owned()]);
    let mut written = std::collections::BTreeSet::new();
    for image in images {
        let relative = image.path.to_string_lossy().replace('\\', "/");
        if let Some(other) = ours.iter().find(|&o| *o == top(&relative)) {
            bail!(
                "{}: image '{relative}' would be written beside the simplified rig as {relative}, in desal's \
                 own {other}; move the image into another folder (e.g. textures/)",
                rig.display()
            );
        }
        if written.insert(relative.clone()) {
            let bytes = image.bytes;
            outputs.files.push((relative, Box::new(move |p| Ok(desal_io::write_atomic(p, &bytes)?))));
        }
    }
    Ok(())
}

/// `hierarchy-<k>.dsa` per level, `hierarchy.npz`, `hierarchy.json`, and the figures:
/// `hierarchy.png` (the levels side by side) and `upsampling-error.png` and `upsampling-error-<k>.ply` (the
/// held-out per-vertex upsampling error, fitted against barycentric).
fn add_hierarchy(
    outputs: &mut DatasetOutputs,
    stages: &DatasetStages,
    set: &PoseSet,
    labels: &PartLabels,
    up_axis: Option<&str>,
) -> Result<()> {
    use crate::stages::hierarchy::{HierarchyReport, npz_arrays};
    let bodies = stages.hierarchy.iter().map(|l| l.body()).collect::<Result<Vec<_>>>()?;
    let arrays = npz_arrays(set.vertex_count(), &set.faces, &bodies)?;
    let summaries: Vec<_> = stages.hierarchy.iter().map(|l| &l.summary).collect();
    let report = HierarchyReport::new(
        arrays.levels.clone(),
        &bodies[0].upsampler,
        set.group_count(),
        summaries.iter().copied(),
    );
    let report = serde_json::to_value(&report)?;
    for (k, level) in stages.hierarchy.iter().enumerate() {
        outputs.artifacts.push((format!("hierarchy-{}.dsa", k + 1), level.artifact_path()?.to_owned()));
    }
    let up = crate::pictures::parse_up_axis(up_axis)?;
    let template = set.template_mesh();
    let levels_png = crate::pictures::hierarchy_levels_png(&template, labels, &bodies, up)?;
    let maps = crate::pictures::UpsamplingMaps::new(&summaries);
    let error_png = crate::pictures::upsampling_error_png(&template, &maps, up)?;
    outputs.files.push((
        "hierarchy.npz".into(),
        Box::new(move |p| Ok(desal_io::npz::write_hierarchy_npz(p, &arrays)?)),
    ));
    outputs.files.push(("hierarchy.json".into(), Box::new(move |p| Ok(desal_io::write_json(p, &report)?))));
    outputs
        .files
        .push(("hierarchy.png".into(), Box::new(move |p| Ok(desal_io::write_atomic(p, &levels_png)?))));
    outputs
        .files
        .push(("upsampling-error.png".into(), Box::new(move |p| Ok(desal_io::write_atomic(p, &error_png)?))));
    for k in 0..maps.levels.len() {
        let (template, columns) = (template.clone(), maps.columns(k));
        outputs.files.push((
            format!("upsampling-error-{}.ply", k + 1),
            Box::new(move |p| crate::pictures::write_scalars_ply(p, &template, columns)),
        ));
    }
    Ok(())
}

/// `saliency.png` (the paper's Fig. 1) and `saliency.ply` (colours + a `saliency`
/// float property) of the template.
fn add_saliency_pictures(
    outputs: &mut DatasetOutputs,
    template: TriMesh,
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

/// `labels.txt`, `parts.png` and `parts.json` of discovered parts (`labels = "auto"`).
fn add_parts_files(
    outputs: &mut DatasetOutputs,
    template: TriMesh,
    labels: &PartLabels,
    summary: &crate::stages::parts::PartsSummary,
    up_axis: Option<&str>,
) -> Result<()> {
    let up = crate::pictures::parse_up_axis(up_axis)?;
    let png = crate::pictures::parts_png(&template, labels, up)?;
    let text = crate::stages::parts::labels_txt(labels);
    outputs
        .files
        .push(("labels.txt".into(), Box::new(move |p| Ok(desal_io::write_atomic(p, text.as_bytes())?))));
    outputs.files.push(("parts.png".into(), Box::new(move |p| Ok(desal_io::write_atomic(p, &png)?))));
    let summary = serde_json::to_value(summary).expect("summaries serialise");
    outputs.files.push(("parts.json".into(), Box::new(move |p| Ok(desal_io::write_json(p, &summary)?))));
    Ok(())
}

/// Puts `<name>.dsa` (the cached artifact) and `<name>.json` (its summary) in the outputs.
fn add_artifact<T, S: Serialize>(
    outputs: &mut DatasetOutputs,
    name: &str,
    stage: &Staged<T, S>,
) -> Result<()> {
    outputs.artifacts.push((format!("{name}.dsa"), stage.artifact_path()?.to_owned()));
    let summary = serde_json::to_value(&stage.summary)?;
    outputs.files.push((format!("{name}.json"), Box::new(move |p| Ok(desal_io::write_json(p, &summary)?))));
    Ok(())
}

/// The registered simplified pose set, the one writer of it: `<poses_dir><pose>.ply` for
/// every pose (the name through [`desal_io::confine::file_stems_for`]), `<poses_dir>parts.txt`, and `vertex_map.txt` (one original index per
/// simplified vertex, in simplified-vertex order).
pub fn simplified_pose_set(
    poses_dir: &str,
    map: &MapV1,
    set: PoseSet,
    labels: PartLabels,
) -> Vec<(String, FileWriter)> {
    use desal_io::ply::{PlyWriteOptions, write_ply};
    let mut files = simplified_map_files(poses_dir, map, labels);
    // Pose names come from files (a rig's animation names): one rule makes each a file
    // name inside `poses_dir`, ordinary names unchanged.
    let stems = desal_io::confine::file_stems_for(&set.names);
    let set = std::sync::Arc::new(set);
    for (pose, stem) in stems.into_iter().enumerate() {
        let set = set.clone();
        files.push((
            format!("{poses_dir}{stem}.ply"),
            Box::new(move |p| Ok(write_ply(p, &set.pose_mesh(pose), &PlyWriteOptions::default())?)),
        ));
    }
    files
}

/// The simplified pose set's files but its poses: `vertex_map.txt` and
/// `<poses_dir>parts.txt` (the labels of the simplified vertices), what a model source
/// writes without `write_poses`.
fn simplified_map_files(poses_dir: &str, map: &MapV1, labels: PartLabels) -> Vec<(String, FileWriter)> {
    let mut files: Vec<(String, FileWriter)> = Vec::new();
    let text: String = map.simp_to_orig.iter().map(|i| format!("{i}\n")).collect();
    files.push(("vertex_map.txt".into(), Box::new(move |p| Ok(desal_io::write_atomic(p, text.as_bytes())?))));
    files.push((
        format!("{poses_dir}parts.txt"),
        Box::new(move |p| Ok(desal_io::labels::write_labels_txt(p, &labels)?)),
    ));
    files
}

/// Writes loose output files (a single-stage command's artifact and pictures) all or
/// nothing: each goes to a temp name beside its destination first, and only when every
/// one is written are they renamed into place. A failure leaves none of them.
///
/// What may be replaced is [`desal_io::confine::write_target`]'s rule, checked for every
/// destination before anything is written: a character device (`-o /dev/null`) is
/// written through last, never renamed over; a folder, FIFO or socket is refused.
pub fn write_all_or_nothing(files: Vec<(PathBuf, FileWriter)>) -> Result<()> {
    use desal_io::confine::{WriteTarget, write_target};
    let pid = std::process::id();
    let partial = |dest: &Path| {
        let name = dest.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        dest.with_file_name(format!(".{name}.partial-{pid}"))
    };
    let mut targets = Vec::with_capacity(files.len());
    for (dest, write) in files {
        let target = write_target(&dest).with_context(|| format!("cannot write {}", dest.display()))?;
        targets.push((dest, write, target));
    }
    let mut written: Vec<(PathBuf, PathBuf)> = Vec::new();
    let mut devices: Vec<(PathBuf, FileWriter)> = Vec::new();
    let result = (|| -> Result<()> {
        for (dest, write, target) in targets {
            if target == WriteTarget::Device {
                devices.push((dest, write));
                continue;
            }
            let tmp = partial(&dest);
            written.push((tmp.clone(), dest.clone()));
            write(&tmp).with_context(|| format!("cannot write {}", dest.display()))?;
        }
        for (tmp, dest) in &written {
            std::fs::rename(tmp, dest).with_context(|| format!("cannot write {}", dest.display()))?;
        }
        Ok(())
    })();
    if result.is_err() {
        for (tmp, _) in &written {
            let _ = std::fs::remove_file(tmp);
        }
        return result;
    }
    for (dest, write) in devices {
        write(&dest).with_context(|| format!("cannot write {}", dest.display()))?;
    }
    Ok(())
}

/// Identifies a dataset's output folder content: every stage's cache key, plus what the
/// derived files depend on beyond them (the picture's up axis, the desal version,
/// whether `view.html` loads three.js from its CDN or inlines `DESAL_THREE`'s, and a
/// model source's `write_poses`, given as `model_poses`: left out when unset, as a
/// stage key leaves out a setting that is not given).
pub fn outputs_key(records: &[StageRecord], up_axis: Option<&str>, model_poses: bool) -> String {
    let keys: Vec<&str> = records.iter().map(|r| r.cache_key.as_str()).collect();
    let mut key = serde_json::json!({
        "stages": keys,
        "up_axis": up_axis,
        "desal": env!("CARGO_PKG_VERSION"),
        "outputs": OUTPUTS_VERSION,
        "three": desal_rig::viewer::three_key(desal_rig::viewer::three_dir_from_env().as_deref()),
    });
    if model_poses {
        key["model_poses"] = serde_json::Value::Bool(true);
    }
    ContentHash::of(canonical_json(&key).as_bytes()).to_hex()
}

/// The output folder's file list when its report.json carries `outputs_key` and every
/// listed file is present; `None` when the outputs must be written.
pub fn outputs_in_place(out_dir: &Path, outputs_key: &str) -> Option<Vec<String>> {
    let old: serde_json::Value = desal_io::atomic::read_json(&out_dir.join("report.json")).ok()?;
    if old.get("outputs_key")?.as_str()? != outputs_key {
        return None;
    }
    let files: Vec<String> =
        old.get("files")?.as_array()?.iter().map(|f| f.as_str().map(str::to_owned)).collect::<Option<_>>()?;
    files.iter().all(|f| out_dir.join(f).exists()).then_some(files)
}

/// Refuses to take over a folder that `desal run` did not write: the output folder is
/// replaced whole, so a non-empty folder without a `report.json` (someone's own files, or
/// a typo in `out` or `name`) would be lost.
pub fn check_output_folder(out_dir: &Path) -> Result<()> {
    if !out_dir.exists() {
        return Ok(());
    }
    if !out_dir.is_dir() {
        bail!(
            "output folder {} exists and is not a folder; remove it or change `out`/`name`",
            out_dir.display()
        );
    }
    let mut entries = std::fs::read_dir(out_dir)
        .with_context(|| format!("cannot read output folder {}", out_dir.display()))?;
    if entries.next().is_some() && !out_dir.join("report.json").is_file() {
        bail!(
            "output folder {} is not empty and holds no report.json, so desal did not write it; \
             desal replaces its output folder whole: move those files away or change `out`/`name`",
            out_dir.display()
        );
    }
    Ok(())
}

/// Replaces `out_dir` by a folder holding `outputs` and `report.json`, carrying `eval/`
/// over: the folder is the previous run's or this run's, never a mix.
pub fn write_outputs(out_dir: &Path, outputs: DatasetOutputs, report: &impl Serialize) -> Result<()> {
    // Checked again right before the swap: the caller checked before the stages ran, and
    // someone may have written into the folder since.
    check_output_folder(out_dir)?;
    desal_io::replace_dir(out_dir, &[KEPT_SUBFOLDER], |tmp| -> Result<()> {
        outputs.write_into(tmp)?;
        desal_io::write_json(&tmp.join("report.json"), report)?;
        Ok(())
    })
}
