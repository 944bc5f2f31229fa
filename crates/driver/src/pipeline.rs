//! Pipeline files (TOML, `schema = 1`): which datasets to run and with which stage
//! parameters. The format is documented in `pipelines/README.md`.
//!
//! Relative paths are resolved against the pipeline file's own folder, so a pipeline and
//! its data can be moved together. Parameters given under `[defaults]` apply to every
//! dataset; a dataset's own tables override them key by key.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};

use crate::stages::fit::FitParams;
use crate::stages::hierarchy::HierarchyParams;
use crate::stages::ingest::{IngestParams, TemplateSpec, pose_name};
use crate::stages::model::{ModelInput, ModelParams};
use crate::stages::parts::PartsParams;
use crate::stages::rig::{RigInput, RigParams};
use crate::stages::saliency::SaliencyParams;
use crate::stages::simplify::{Objective, SimplifyParams, TARGET_KEYS};
use crate::stages::{DatasetInputs, LabelsInput};

/// The pipeline file schema this build reads.
pub const SCHEMA: u32 = 1;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct PipelineToml {
    schema: u32,
    /// Output root; each dataset writes to `<out>/<dataset name>`.
    out: Option<String>,
    #[serde(default)]
    defaults: toml::Table,
    #[serde(rename = "dataset", default)]
    datasets: Vec<toml::Table>,
}

/// One dataset's inputs and stage parameters, with every path absolute.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct DatasetToml {
    /// Unique name; also the output sub-folder.
    pub name: String,
    /// A glob (`"scans/*.ply"`) or an explicit list of pose files (absent for a rig).
    #[serde(default)]
    pub poses: Option<PosesSpec>,
    /// The template: a pose file name or stem, or a 0-based index into the sorted list.
    #[serde(default)]
    pub template: Option<TemplateSpec>,
    /// Part labels file (text or JSON), or `"auto"`: parts discovered from the poses
    /// (absent for a rig).
    #[serde(default)]
    pub labels: Option<LabelsSpec>,
    /// `[dataset.rig]`: a skinned glTF in place of `poses` and `labels`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rig: Option<RigParams>,
    /// `[dataset.model]`: a body model (SMPL family), sampled, in place of `poses` and
    /// `labels`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<ModelParams>,
    /// Part discovery with `labels = "auto"`: `parts = K`, or a `[dataset.parts]` table.
    #[serde(default, deserialize_with = "crate::stages::parts::count_or_table")]
    pub parts: PartsParams,
    /// A group file (one group id per pose, in pose order: a person, a capture): held-out
    /// figures then hold out whole groups. A model source has one group per shape.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub groups: Option<String>,
    /// Use the template's triangles for every pose instead of requiring identical lists.
    #[serde(default)]
    pub ignore_pose_faces: bool,
    /// Up axis for pictures ("x", "y", "z"); detected from the bounding box when absent.
    #[serde(default)]
    pub up_axis: Option<String>,
    #[serde(default)]
    pub fit: FitParams,
    #[serde(default)]
    pub saliency: SaliencyParams,
    #[serde(default)]
    pub simplify: SimplifyParams,
    /// `[dataset.hierarchy]`: coarse levels for mesh networks (absent: none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hierarchy: Option<HierarchyParams>,
}

/// `labels = "auto"` or a labels file path (a file literally named `auto` is `./auto`).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(from = "String", into = "String")]
pub enum LabelsSpec {
    File(String),
    Auto,
}

impl From<String> for LabelsSpec {
    fn from(text: String) -> Self {
        if text == "auto" { LabelsSpec::Auto } else { LabelsSpec::File(text) }
    }
}

impl From<LabelsSpec> for String {
    fn from(spec: LabelsSpec) -> Self {
        match spec {
            LabelsSpec::File(path) => path,
            LabelsSpec::Auto => "auto".into(),
        }
    }
}

/// Where a dataset's labels come from, with the file's path absolute.
#[derive(Debug, Clone, PartialEq)]
pub enum LabelsSource {
    File(PathBuf),
    Auto,
    /// From the rig's dominant joints.
    Rig,
    /// From the model's skinning weights.
    Model,
}

#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(untagged)]
pub enum PosesSpec {
    Glob(String),
    List(Vec<String>),
}

/// A dataset ready to run: the parsed table plus resolved absolute paths.
#[derive(Debug, Clone)]
pub struct Dataset {
    pub spec: DatasetToml,
    /// Pose files, sorted (glob) or in the listed order.
    pub pose_files: Vec<PathBuf>,
    pub labels: LabelsSource,
    /// The file the poses are made from instead of pose files, absolute: the rig of a
    /// `[dataset.rig]` dataset, the model of a `[dataset.model]` one.
    pub source_file: Option<PathBuf>,
    /// The group file (`groups`), absolute.
    pub groups_file: Option<PathBuf>,
    /// Where this dataset's outputs go.
    pub out_dir: PathBuf,
}

impl Dataset {
    /// What the stages read.
    pub fn inputs(&self) -> DatasetInputs<'_> {
        DatasetInputs {
            ingest: IngestParams {
                pose_files: &self.pose_files,
                template: self.spec.template.as_ref(),
                ignore_pose_faces: self.spec.ignore_pose_faces,
                groups: self.groups_file.as_deref(),
            },
            labels: match &self.labels {
                LabelsSource::File(file) => LabelsInput::File(file),
                LabelsSource::Auto => LabelsInput::Auto(&self.spec.parts),
                LabelsSource::Rig => LabelsInput::Rig,
                LabelsSource::Model => LabelsInput::Model,
            },
            fit: &self.spec.fit,
            saliency: &self.spec.saliency,
            simplify: &self.spec.simplify,
            hierarchy: self.spec.hierarchy.as_ref(),
            rig: match (&self.source_file, &self.spec.rig) {
                (Some(file), Some(params)) => Some(RigInput { file, params }),
                _ => None,
            },
            model: match (&self.source_file, &self.spec.model) {
                (Some(file), Some(params)) => Some(ModelInput { file, params }),
                _ => None,
            },
        }
    }
}

/// A parsed pipeline file.
#[derive(Debug, Clone)]
pub struct Pipeline {
    pub path: PathBuf,
    pub out_root: PathBuf,
    pub datasets: Vec<Dataset>,
}

/// Reads and resolves a pipeline file. `out_override` replaces the file's `out`.
pub fn load(path: &Path, out_override: Option<&Path>) -> Result<Pipeline> {
    let text = desal_io::file::read_text_file(path).context("cannot read the pipeline file")?;
    parse(path, &text, out_override)
}

/// Parses pipeline text as if read from `path`.
pub fn parse(path: &Path, text: &str, out_override: Option<&Path>) -> Result<Pipeline> {
    let ctx = || format!("pipeline file {}", path.display());
    let raw: toml::Table = toml::from_str(text).with_context(ctx)?;
    match raw.get("schema").and_then(|v| v.as_integer()) {
        Some(s) if s == SCHEMA as i64 => {}
        Some(s) if s > SCHEMA as i64 => {
            bail!("{}: schema {s} is newer than this desal reads ({SCHEMA}); upgrade desal", path.display())
        }
        Some(s) => bail!("{}: unsupported schema {s} (this desal reads schema {SCHEMA})", path.display()),
        None => bail!("{}: missing `schema = {SCHEMA}` at the top", path.display()),
    }
    let file: PipelineToml = toml::from_str(text).with_context(ctx)?;
    debug_assert_eq!(file.schema, SCHEMA);
    let base = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new(".")).to_path_buf();
    let base = std::path::absolute(&base).with_context(|| format!("cannot resolve {}", base.display()))?;
    let out_root = match out_override {
        Some(o) => std::path::absolute(o)?,
        None => base.join(file.out.as_deref().unwrap_or("out")),
    };
    if file.datasets.is_empty() {
        bail!("{}: no [[dataset]] tables: nothing to run", path.display());
    }
    let mut datasets = Vec::new();
    for (k, table) in file.datasets.iter().enumerate() {
        let merged = merge(&file.defaults, table);
        let mut spec: DatasetToml = merged
            .try_into()
            .with_context(|| format!("{}: dataset #{} ({})", path.display(), k + 1, dataset_name(table)))?;
        check_dataset_name(&spec.name).with_context(|| format!("{}: dataset #{}", path.display(), k + 1))?;
        // Compared case-insensitively: "R" and "r" are one folder on macOS and Windows.
        if let Some(other) = datasets.iter().find(|d: &&Dataset| d.spec.name.eq_ignore_ascii_case(&spec.name))
        {
            bail!(
                "{}: two datasets are named '{}' and '{}'; names must be unique, ignoring case (they would share \
                 one output folder on a case-insensitive file system)",
                path.display(),
                other.spec.name,
                spec.name
            );
        }
        default_objective(&mut spec);
        let in_dataset = || format!("{}: dataset '{}'", path.display(), spec.name);
        if spec.model.is_some() {
            crate::stages::model::use_subset_placement(&mut spec.simplify).with_context(in_dataset)?;
        }
        let (pose_files, labels, source_file) = match (&spec.model, &spec.rig, &spec.poses, &spec.labels) {
            (Some(model), None, None, None) => {
                if spec.template.is_some() || spec.ignore_pose_faces || spec.parts != PartsParams::default() {
                    bail!(
                        "{}: a [dataset.model] takes its template (the mean shape in the zero pose) and \
                         parts (model.parts) from the model: remove `template`, `ignore_pose_faces` and `parts`",
                        in_dataset()
                    );
                }
                (Vec::new(), LabelsSource::Model, Some(base.join(&model.file)))
            }
            (Some(_), _, _, _) => {
                bail!(
                    "{}: a [dataset.model] replaces `poses`, `labels` and [dataset.rig]: give one of them",
                    in_dataset()
                )
            }
            (None, Some(rig), None, None) => {
                if spec.template.is_some() || spec.ignore_pose_faces || spec.parts != PartsParams::default() {
                    bail!(
                        "{}: a [dataset.rig] takes its template (the bind pose) and parts from the rig: \
                         remove `template`, `ignore_pose_faces` and `parts`",
                        in_dataset()
                    );
                }
                (Vec::new(), LabelsSource::Rig, Some(base.join(&rig.file)))
            }
            (None, Some(_), _, _) => {
                bail!(
                    "{}: a [dataset.rig] replaces `poses` and `labels`: give one or the other",
                    in_dataset()
                )
            }
            (None, None, Some(poses), Some(labels)) => {
                let pose_files = resolve_poses(&base, poses).with_context(in_dataset)?;
                let labels = match labels {
                    LabelsSpec::File(file) => LabelsSource::File(base.join(file)),
                    LabelsSpec::Auto => LabelsSource::Auto,
                };
                (pose_files, labels, None)
            }
            (None, None, _, _) => {
                bail!(
                    "{}: give `poses` and `labels`, a [dataset.rig] or a [dataset.model] table",
                    in_dataset()
                )
            }
        };
        if spec.groups.is_some() && source_file.is_some() {
            bail!(
                "{}: `groups` is for pose files; a [dataset.model] has one group per shape, a [dataset.rig] none: \
                 remove `groups`",
                in_dataset()
            );
        }
        let groups_file = spec.groups.as_ref().map(|g| base.join(g));
        // Every stage parameter is checked now, before any stage runs.
        check_parameters(&spec, &pose_files).with_context(in_dataset)?;
        let out_dir = out_root.join(&spec.name);
        datasets.push(Dataset { spec, pose_files, labels, source_file, groups_file, out_dir });
    }
    Ok(Pipeline { path: path.to_owned(), out_root, datasets })
}

/// A dataset kind's default use (issue 43), when its `[simplify]` names no `method`, no
/// `objective` and none of the settings a method sets: a rig is simplified for skinning,
/// a pose set with a `[dataset.hierarchy]` for its upsampler; any other keeps the paper's
/// stage 3 (its settings' defaults).
fn default_objective(spec: &mut DatasetToml) {
    let simplify = &mut spec.simplify;
    if simplify.method.is_some() || simplify.objective.is_some() || !simplify.given.is_empty() {
        return;
    }
    let objective = if spec.rig.is_some() {
        Objective::Skinning
    } else if spec.hierarchy.is_some() {
        Objective::Hierarchy
    } else {
        return;
    };
    simplify.objective = Some(objective);
    simplify.method = Some(objective.method());
}

/// The stage parameters that can be checked without reading a mesh: fit method,
/// saliency options and excluded pose names, simplify target and options, up axis.
fn check_parameters(spec: &DatasetToml, pose_files: &[PathBuf]) -> Result<()> {
    spec.saliency.config()?;
    let names: Vec<String> = pose_files.iter().map(|f| pose_name(f)).collect();
    if let Some(unknown) = spec.saliency.exclude.iter().find(|e| !names.contains(e)) {
        bail!(
            "saliency.exclude names pose '{unknown}', which is not in the pose list ({} poses)",
            names.len()
        );
    }
    spec.simplify.config()?;
    match &spec.labels {
        Some(LabelsSpec::Auto) => {
            spec.parts.config()?;
        }
        Some(LabelsSpec::File(_)) if spec.parts != PartsParams::default() => {
            bail!("`parts` applies to `labels = \"auto\"` only; this dataset reads its labels from a file")
        }
        Some(LabelsSpec::File(_)) | None => {}
    }
    if let Some(rig) = &spec.rig {
        rig.frame_config()?;
        rig.weight_options()?;
        rig.parts_config()?;
        rig.lod_fractions()?;
        rig.check_mesh_overrides()?;
    }
    if let Some(model) = &spec.model {
        model.config()?;
    }
    if let Some(h) = &spec.hierarchy {
        h.config()?;
    }
    crate::pictures::parse_up_axis(spec.up_axis.as_deref())?;
    Ok(())
}

/// The longest dataset name: the output folder's temp names (`.NAME.tmp-PID-N`) and the
/// cache's record file names must stay under the 255 bytes of a file name.
pub const MAX_DATASET_NAME: usize = 100;

/// A dataset's name is its output sub-folder, so it must stay one plain folder name:
/// letters, digits, `-`, `_` and `.`, not starting with `.` (no `..`, no hidden folder, no
/// path that escapes the output root), at most [`MAX_DATASET_NAME`] characters.
fn check_dataset_name(name: &str) -> Result<()> {
    let plain = |c: char| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.');
    if name.is_empty() || name.starts_with('.') || !name.chars().all(plain) {
        bail!(
            "dataset name {name:?} cannot be a folder name: use letters, digits, '-', '_' and '.', \
             not starting with '.'"
        );
    }
    // Folder names Windows cannot hold (a trailing dot is dropped there, so `a.` and `a`
    // would share a folder; CON, NUL, COM1 … are devices, with any extension).
    let stem = name.split('.').next().unwrap_or(name).to_ascii_uppercase();
    let device = matches!(stem.as_str(), "CON" | "PRN" | "AUX" | "NUL")
        || ((stem.starts_with("COM") || stem.starts_with("LPT"))
            && stem.len() == 4
            && stem.as_bytes()[3].is_ascii_digit());
    if name.ends_with('.') || device {
        bail!(
            "dataset name {name:?} cannot be a folder name on every system (a trailing '.' or a device name \
             like CON or COM1); choose another"
        );
    }
    if name.len() > MAX_DATASET_NAME {
        bail!(
            "dataset name '{name}' is {} characters long; at most {MAX_DATASET_NAME} are allowed",
            name.len()
        );
    }
    Ok(())
}

fn dataset_name(table: &toml::Table) -> String {
    table.get("name").and_then(|v| v.as_str()).unwrap_or("unnamed").to_owned()
}

/// `defaults` overlaid by `table`, merging nested tables key by key.
fn merge(defaults: &toml::Table, table: &toml::Table) -> toml::Table {
    let mut out = defaults.clone();
    // The three simplify targets are alternatives: a dataset's target replaces the
    // defaults' target, whichever key each uses.
    if TARGET_KEYS.iter().any(|k| table.contains_key(*k)) {
        out.retain(|k, _| !TARGET_KEYS.contains(&k));
    }
    for (key, value) in table {
        match (out.get_mut(key), value) {
            (Some(toml::Value::Table(base)), toml::Value::Table(over)) => {
                *base = merge(base, over);
            }
            _ => {
                out.insert(key.clone(), value.clone());
            }
        }
    }
    out
}

fn resolve_poses(base: &Path, spec: &PosesSpec) -> Result<Vec<PathBuf>> {
    let files = match spec {
        PosesSpec::List(list) => list.iter().map(|p| base.join(p)).collect::<Vec<_>>(),
        PosesSpec::Glob(pattern) => {
            let full = base.join(pattern);
            let full = full.to_string_lossy();
            let mut files: Vec<PathBuf> = glob::glob(&full)
                .with_context(|| format!("bad glob pattern '{pattern}'"))?
                .collect::<Result<_, _>>()
                .with_context(|| format!("cannot list '{pattern}'"))?;
            files.sort();
            if files.is_empty() {
                bail!(
                    "the pose pattern '{full}' matches no files: check the path (relative paths start at the pipeline file's folder)"
                );
            }
            files
        }
    };
    if files.is_empty() {
        bail!("the pose list is empty: give at least one pose file");
    }
    Ok(files)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pose set with a hierarchy is simplified for it, a rig for skinning, unless its
    /// `[simplify]` names a method, an objective or a setting a method makes; a plain
    /// pose set keeps the paper's stage 3.
    #[test]
    fn a_dataset_kind_has_its_default_objective() {
        use crate::stages::simplify::Method;
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("a.ply"), b"").unwrap();
        let path = dir.path().join("p.toml");
        let head = "schema = 1\n[[dataset]]\nname = 'a'\nposes = ['a.ply']\nlabels = 'l'\n";
        let parse = |extra: &str| parse(&path, &format!("{head}{extra}"), None).unwrap().datasets.remove(0);
        let levels = "[dataset.hierarchy]\nlevels = [10]\n";
        let plain = parse("");
        assert_eq!((plain.spec.simplify.objective, plain.spec.simplify.method), (None, None));
        let hierarchy = parse(levels);
        assert_eq!(hierarchy.spec.simplify.objective, Some(Objective::Hierarchy));
        assert_eq!(hierarchy.spec.simplify.method, Some(Method::DesalUpsample));
        let given = parse(&format!("{levels}[dataset.simplify]\nbalance = true\n"));
        assert_eq!((given.spec.simplify.objective, given.spec.simplify.method), (None, None));
        let named = parse(&format!("{levels}[dataset.simplify]\nmethod = \"multipose\"\n"));
        assert_eq!(
            (named.spec.simplify.objective, named.spec.simplify.method),
            (None, Some(Method::Multipose))
        );
        let rig = "schema = 1\n[[dataset]]\nname = 'r'\n[dataset.rig]\nfile = 'r.glb'\n";
        let rig = super::parse(&path, rig, None).unwrap().datasets.remove(0);
        assert_eq!(rig.spec.simplify.objective, Some(Objective::Skinning));
        assert_eq!(rig.spec.simplify.method, Some(Method::Desal));
    }

    #[test]
    fn defaults_merge_key_by_key_and_paths_resolve_against_the_file() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("a.ply"), b"").unwrap();
        let text = r#"
schema = 1
out = "results"
[defaults.simplify]
target_vertices = 100
placement = "subset"
[[dataset]]
name = "one"
poses = ["a.ply"]
labels = "labels.txt"
[dataset.simplify]
target_vertices = 50
"#;
        let p = parse(&dir.path().join("p.toml"), text, None).unwrap();
        let d = &p.datasets[0];
        assert_eq!(d.spec.simplify.target_vertices, Some(50));
        assert_eq!(d.spec.simplify.placement, desal_simplify::Placement::Subset);
        assert_eq!(
            d.spec.simplify.balance,
            SimplifyParams::default().balance,
            "unset keys keep their defaults"
        );
        assert_eq!(d.labels, LabelsSource::File(dir.path().join("labels.txt")));
        assert_eq!(d.out_dir, dir.path().join("results").join("one"));
    }

    #[test]
    fn schema_and_unknown_keys_are_checked() {
        let p = Path::new("x.toml");
        assert!(parse(p, "schema = 2\n", None).unwrap_err().to_string().contains("newer"));
        assert!(parse(p, "out = 'a'\n", None).unwrap_err().to_string().contains("missing `schema"));
        let bad = "schema = 1\n[[dataset]]\nname='a'\nposes=['x.ply']\nlabels='l'\ncolour='red'\n";
        let err = format!("{:#}", parse(p, bad, None).unwrap_err());
        assert!(err.contains("colour"), "{err}");
    }

    /// `labels = "auto"` with `parts = K` or a `[dataset.parts]` table; any other string
    /// is a labels file.
    #[test]
    fn auto_labels_take_a_count_or_a_table() {
        let p = Path::new("/data/x.toml");
        let head = "schema = 1\n[[dataset]]\nname='a'\nposes=['x.ply']\n";
        let d = parse(p, &format!("{head}labels='auto'\nparts=16\n"), None).unwrap().datasets.remove(0);
        assert_eq!(d.labels, LabelsSource::Auto);
        assert_eq!(d.spec.parts, PartsParams { count: Some(16), ..PartsParams::default() });
        let text = format!("{head}labels='auto'\n[dataset.parts]\ncount=3\npatches=64\n");
        let d = parse(p, &text, None).unwrap().datasets.remove(0);
        assert_eq!(d.spec.parts, PartsParams { count: Some(3), patches: Some(64), ..PartsParams::default() });
        let d = parse(p, &format!("{head}labels='./auto'\n"), None).unwrap().datasets.remove(0);
        assert_eq!(d.labels, LabelsSource::File(PathBuf::from("/data/./auto")));
        let err = format!("{:#}", parse(p, &format!("{head}labels='auto'\nparts=0\n"), None).unwrap_err());
        assert!(err.contains("parts"), "{err}");
    }

    #[test]
    fn dataset_names_stay_inside_the_output_root() {
        let p = Path::new("x.toml");
        for bad in ["../evil", "a/b", ".", "..", ".hidden", "", "a\\b"] {
            let text = format!("schema = 1\n[[dataset]]\nname={bad:?}\nposes=['x.ply']\nlabels='l'\n");
            let err = format!("{:#}", parse(p, &text, None).unwrap_err());
            assert!(err.contains("cannot be a folder name"), "{bad}: {err}");
        }
    }

    /// D18: names that collide on a case-insensitive file system, and names too long for
    /// a file name, are refused when the file is read.
    #[test]
    fn d18_names_differing_in_case_and_overlong_names_are_refused() {
        let p = Path::new("x.toml");
        let dataset = |name: &str| format!("[[dataset]]\nname={name:?}\nposes=['x.ply']\nlabels='l'\n");
        let text = format!("schema = 1\n{}{}", dataset("R"), dataset("r"));
        let err = format!("{:#}", parse(p, &text, None).unwrap_err());
        assert!(err.contains("'R' and 'r'") && err.contains("ignoring case"), "{err}");
        let long = "a".repeat(300);
        let err = format!("{:#}", parse(p, &format!("schema = 1\n{}", dataset(&long)), None).unwrap_err());
        assert!(err.contains("300 characters"), "{err}");
        for bad in ["a.", "con", "NUL.txt", "com1", "Lpt9"] {
            let err = format!("{:#}", parse(p, &format!("schema = 1\n{}", dataset(bad)), None).unwrap_err());
            assert!(err.contains("on every system"), "{bad}: {err}");
        }
        for fine in ["console", "com", "a.b", "nul1"] {
            assert!(parse(p, &format!("schema = 1\n{}", dataset(fine)), None).is_ok(), "{fine}");
        }
        let ok = "a".repeat(MAX_DATASET_NAME);
        assert!(parse(p, &format!("schema = 1\n{}", dataset(&ok)), None).is_ok());
    }

    #[test]
    fn a_dataset_target_replaces_the_defaults_target_and_two_in_one_table_are_refused() {
        let p = Path::new("x.toml");
        let head = "schema = 1\n[defaults.simplify]\nratio = 0.5\n[[dataset]]\nname='a'\nposes=['x.ply']\nlabels='l'\n";
        let text = format!("{head}[dataset.simplify]\ntarget_vertices = 100\n");
        let d = &parse(p, &text, None).unwrap().datasets[0];
        assert_eq!((d.spec.simplify.target_vertices, d.spec.simplify.ratio), (Some(100), None));
        let text = format!("{head}[dataset.simplify]\ntarget_vertices = 100\ntarget_faces = 200\n");
        let err = format!("{:#}", parse(p, &text, None).unwrap_err());
        assert!(err.contains("dataset 'a'") && err.contains("not several"), "{err}");
    }
}
