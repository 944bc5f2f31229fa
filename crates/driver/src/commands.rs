//! The single-stage commands, shared by `desal <stage>` and the `desal-<stage>` binaries:
//! artifacts (or plain files) in, one artifact out, for debugging and for other
//! people's pipelines. The artifacts are byte-identical to those `desal run` makes.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use desal_io::artifact::{self, ArtifactBody, FitV1, LabelsV1, PoseSetV2, SaliencyV1};
use desal_mesh::NoProgress;

use crate::outputs::{FileWriter, write_all_or_nothing};
use crate::stages;
use crate::stages::fit::FitParams;
use crate::stages::ingest::clean_faces_with_warnings;
use crate::stages::saliency::SaliencyParams;

/// `desal fit`: stage 1 on an ingested pose set and labels.
#[derive(Debug)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct FitArgs {
    /// Pose-set artifact (`poses.dsa` from `desal run`).
    #[cfg_attr(feature = "cli", arg(long))]
    pub poses: PathBuf,
    /// Labels artifact (`labels.dsa`).
    #[cfg_attr(feature = "cli", arg(long))]
    pub labels: PathBuf,
    /// Where to write the fit artifact.
    #[cfg_attr(feature = "cli", arg(long, short))]
    pub output: PathBuf,
    /// `rigid` (Kabsch) or `affine` (the paper's literal fit, for the ablation).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = FitParams::default().method))]
    pub method: desal_fit::FitModel,
}

/// `desal saliency`: stage 2 on a fit.
#[derive(Debug)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct SaliencyArgs {
    /// Pose-set artifact the fit was made from.
    #[cfg_attr(feature = "cli", arg(long))]
    pub poses: PathBuf,
    /// Fit artifact (`fit.dsa`).
    #[cfg_attr(feature = "cli", arg(long))]
    pub fit: PathBuf,
    /// Where to write the saliency artifact.
    #[cfg_attr(feature = "cli", arg(long, short))]
    pub output: PathBuf,
    /// Sum squared residual distances.
    #[cfg_attr(feature = "cli", arg(long))]
    pub squared: bool,
    /// Normalise by this percentile of the per-vertex sums, in (0, 100] (100 = the maximum).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = SaliencyParams::default().percentile))]
    pub percentile: f64,
    /// Leave this pose out of the sum (repeatable).
    #[cfg_attr(feature = "cli", arg(long))]
    pub exclude: Vec<String>,
    /// Weight floor for stage 3.
    #[cfg_attr(feature = "cli", arg(long))]
    pub floor: Option<f64>,
    /// Also write the heat map PNG here.
    #[cfg_attr(feature = "cli", arg(long))]
    pub png: Option<PathBuf>,
    /// Also write the template with colours and a `saliency` property here.
    #[cfg_attr(feature = "cli", arg(long))]
    pub ply: Option<PathBuf>,
    /// Up axis for the picture (x, y, z, optionally signed); detected when absent.
    #[cfg_attr(feature = "cli", arg(long))]
    pub up_axis: Option<String>,
}

/// `desal map`: stage 4 on a simplified template — desal's own artifact, or a PLY/OBJ/OFF
/// made by another tool (MeshLab, CGAL, meshoptimizer), mapped by the same greedy rule.
#[derive(Debug)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct MapArgs {
    /// Pose-set artifact (`poses.dsa`).
    #[cfg_attr(feature = "cli", arg(long))]
    pub poses: PathBuf,
    /// Labels artifact (`labels.dsa`).
    #[cfg_attr(feature = "cli", arg(long))]
    pub labels: PathBuf,
    /// The simplified template: `simplified.dsa`, or a mesh file (.ply, .obj, .off: CGAL writes OFF).
    #[cfg_attr(feature = "cli", arg(long))]
    pub simplified: PathBuf,
    /// Where to write the map artifact.
    #[cfg_attr(feature = "cli", arg(long, short))]
    pub output: PathBuf,
    /// Also write the simplified pose set here (`<pose>.ply` per pose, `parts.txt`,
    /// `vertex_map.txt`).
    #[cfg_attr(feature = "cli", arg(long))]
    pub out_dir: Option<PathBuf>,
    /// Also write the simplified rig here (`.glb`), for a pose set that `desal run`
    /// ingested from a skinned glTF rig: its skeleton, inverse bind matrices and
    /// animations with the simplified mesh, as `simplified.glb` (exact weights for
    /// desal's subset placement, weights refitted over the poses otherwise). Needs `--rig`.
    #[cfg_attr(feature = "cli", arg(long, requires = "rig"))]
    pub glb: Option<PathBuf>,
    /// The `.glb`/`.gltf` rig the pose set was ingested from; its bytes must be those the
    /// pose set records, and its `[dataset.rig]` settings are read from the pose set.
    #[cfg_attr(feature = "cli", arg(long, requires = "glb"))]
    pub rig: Option<PathBuf>,
}

/// `desal simplify`: stage 3 on a plain mesh, optionally weighted by saliency. Its knobs
/// are `[simplify]`'s ([`stages::simplify::SimplifyKnobs`]); the rest are its inputs and
/// the benchmark flag `--repeat`.
#[derive(Debug)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
#[cfg_attr(feature = "cli", command(group(clap::ArgGroup::new("target").required(true).args(["target_faces", "target_vertices", "ratio"]))))]
pub struct SimplifyArgs {
    /// Input mesh (PLY, OBJ or OFF).
    #[cfg_attr(feature = "cli", arg(long))]
    pub input: PathBuf,
    /// Output mesh (PLY), written atomically.
    #[cfg_attr(feature = "cli", arg(long))]
    pub output: PathBuf,
    #[cfg_attr(feature = "cli", command(flatten))]
    pub knobs: stages::simplify::SimplifyKnobs,
    /// Per-vertex saliency: a `saliency.dsa` artifact (its floored weights are used), a
    /// PLY with a float vertex property `saliency`, or a text file with one number in
    /// [0, 1] per line (`#` comments allowed). Enables the saliency factor of the cost.
    #[cfg_attr(feature = "cli", arg(long))]
    pub saliency: Option<PathBuf>,
    /// Weight floor applied to saliency read from PLY or text (`w = floor + (1 - floor) s`),
    /// or replacing an artifact's floor. Default: the artifact's, else 0.05.
    #[cfg_attr(feature = "cli", arg(long))]
    pub floor: Option<f64>,
    /// Part labels of the mesh's vertices (a labels `.txt` or `.json`), for
    /// `--keep-part-borders`.
    #[cfg_attr(feature = "cli", arg(long))]
    pub labels: Option<PathBuf>,
    /// Run the simplification this many times and print SIMPLIFY_SECONDS=<best>
    /// (simplification alone, no I/O), for the peers' benchmark harness.
    #[cfg_attr(feature = "cli", arg(long))]
    pub repeat: Option<usize>,
}

fn read<T: ArtifactBody>(path: &Path) -> Result<(T, desal_io::ContentHash)> {
    let (_, body, hash) = artifact::read_artifact::<T>(path)?;
    Ok((body, hash))
}

/// Prints the stage's one-line note and where the artifact went.
fn done(note: &str, output: &Path) {
    eprintln!("{note}");
    eprintln!("wrote {}", output.display());
}

pub fn fit(args: &FitArgs) -> Result<()> {
    let (poses, poses_hash) = read::<PoseSetV2>(&args.poses)?;
    let (labels, labels_hash) = read::<LabelsV1>(&args.labels)?;
    let set = poses.to_pose_set().with_context(|| format!("{}", args.poses.display()))?;
    let labels = labels.to_labels().with_context(|| format!("{}", args.labels.display()))?;
    labels
        .check_vertex_count(set.vertex_count())
        .with_context(|| format!("{} does not belong to {}", args.labels.display(), args.poses.display()))?;
    let params = FitParams { method: args.method };
    let key = params.key(poses_hash, labels_hash);
    let out = stages::fit::compute(&params, &set, &labels, &NoProgress)?;
    artifact::write_artifact(&args.output, &key.producer(&[]), &out.body)?;
    done(&out.note, &args.output);
    Ok(())
}

pub fn saliency(args: &SaliencyArgs) -> Result<()> {
    let (poses, poses_hash) = read::<PoseSetV2>(&args.poses)?;
    let (fit, fit_hash) = read::<FitV1>(&args.fit)?;
    let set = poses.to_pose_set().with_context(|| format!("{}", args.poses.display()))?;
    if fit.vertex_count as usize != set.vertex_count()
        || fit.pose_names != set.names
        || fit.template as usize != set.template
    {
        anyhow::bail!(
            "{} was not made from {}: its poses or vertex count differ",
            args.fit.display(),
            args.poses.display()
        );
    }
    let params = SaliencyParams {
        squared: args.squared,
        percentile: args.percentile,
        exclude: args.exclude.clone(),
        floor: args.floor,
    };
    let template = set.template_mesh();
    let key = params.key(poses_hash, fit_hash)?;
    let up = crate::pictures::parse_up_axis(args.up_axis.as_deref())?;
    let out = stages::saliency::compute(&params, &fit, template.diagonal())?;
    let (body, note): (SaliencyV1, _) = (out.body, out.note);
    // Render before writing anything, so a failure leaves no partial output.
    let png = match &args.png {
        Some(_) => Some(crate::pictures::heatmap_png(
            &template,
            desal_viz::Scalar::PerVertex(&body.saliency),
            up,
            "deformation saliency",
            "0-1",
            Some((0.0, 1.0)),
        )?),
        None => None,
    };
    let saliency = body.saliency.clone();
    let producer = key.producer(&[]);
    let mut files: Vec<(PathBuf, FileWriter)> = vec![(
        args.output.clone(),
        Box::new(move |p| Ok(artifact::write_artifact(p, &producer, &body).map(|_| ())?)),
    )];
    if let (Some(path), Some(png)) = (&args.png, png) {
        files.push((path.clone(), Box::new(move |p| Ok(desal_io::write_atomic(p, &png)?))));
    }
    if let Some(path) = &args.ply {
        files.push((
            path.clone(),
            Box::new(move |p| crate::pictures::write_scalar_ply(p, &template, "saliency", &saliency)),
        ));
    }
    write_all_or_nothing(files)?;
    done(&note, &args.output);
    Ok(())
}

pub fn map(args: &MapArgs) -> Result<()> {
    let (producer, poses, poses_hash) = artifact::read_artifact::<PoseSetV2>(&args.poses)?;
    // Checked before any work: the rig must be the one the pose set came from.
    let rig = match &args.rig {
        Some(file) => Some(stages::rig::source_of_pose_set(&producer, &args.poses, file)?),
        None => None,
    };
    let (labels, _) = read::<LabelsV1>(&args.labels)?;
    let set = poses.to_pose_set().with_context(|| format!("{}", args.poses.display()))?;
    let labels = labels.to_labels().with_context(|| format!("{}", args.labels.display()))?;
    let (simplified, simplified_hash) = if desal_io::artifact::is_artifact(&args.simplified) {
        read::<desal_io::artifact::SimplifiedV1>(&args.simplified)?
    } else {
        // Another tool's mesh: every position is new as far as desal knows, so the
        // greedy rule maps it, exactly as for optimal placement.
        let bytes = desal_io::file::read_regular_file(&args.simplified)?;
        let mut mesh = desal_io::read_mesh(&args.simplified)?;
        mesh.faces = clean_faces_with_warnings(&args.simplified, &mesh.faces).0;
        (stages::simplify::external(&mesh), desal_io::ContentHash::of(&bytes))
    };
    let key = stages::map::key(poses_hash, simplified_hash);
    let out = stages::map::compute(&simplified, &set, &labels)
        .with_context(|| format!("mapping {} onto {}", args.simplified.display(), args.poses.display()))?;
    let (simple_set, simple_labels) = stages::map::apply(&out.body, &set, &labels)?;
    // The rig is built before anything is written: one that cannot be built writes nothing.
    let glb = match (&args.glb, &rig) {
        (Some(path), Some(rig)) => Some((path, stages::rig::simplified_glb(rig, &simplified, &out.body)?)),
        _ => None,
    };
    // The folder first, whole or not at all (it is the step that fails on a bad path),
    // then the rig, and then no artifact claims a result that was not written.
    if let Some(dir) = &args.out_dir {
        crate::outputs::check_output_folder(dir)?;
        let files = crate::outputs::simplified_pose_set("", &out.body, simple_set, simple_labels);
        desal_io::replace_dir(dir, &[], |tmp| -> Result<()> {
            crate::outputs::DatasetOutputs { artifacts: Vec::new(), files }.write_into(tmp)
        })?;
    }
    if let Some((path, (edited, summary))) = &glb {
        desal_io::write_atomic(path, &edited.bytes)?;
        stages::rig::write_images_beside(path, &edited.images)?;
        eprintln!(
            "wrote {}: {} vertices, {} faces, weights {}",
            path.display(),
            summary.output_vertices,
            summary.output_faces,
            summary.weights
        );
    }
    artifact::write_artifact(&args.output, &key.producer(&[]), &out.body)?;
    done(&out.note, &args.output);
    Ok(())
}

pub fn simplify(args: &SimplifyArgs) -> Result<()> {
    use desal_simplify::SimplifyInput;
    use stages::simplify::{Method, SimplifyParams};
    let mut mesh = desal_io::read_mesh(&args.input)?;
    mesh.faces = clean_faces_with_warnings(&args.input, &mesh.faces).0;
    let weights = match &args.saliency {
        Some(path) => Some(read_weights(path, args.floor, mesh.vertex_count())?),
        None => None,
    };
    let k = &args.knobs;
    if [k.target_faces.is_some(), k.target_vertices.is_some(), k.ratio.is_some()] == [false; 3] {
        anyhow::bail!("give one of --target-faces, --target-vertices, --ratio");
    }
    if let Some(method @ (Method::DesalRefit | Method::Multipose)) = k.method {
        anyhow::bail!(
            "--method {} reads the poses, and a plain mesh has one: use `desal run` with a pipeline file",
            method.name()
        );
    }
    // The flags are `[simplify]`'s keys, resolved by the same parameters; saliency is on
    // when weights are read.
    let params = SimplifyParams::from(stages::simplify::SimplifyKnobs {
        saliency: Some(weights.is_some()),
        ..k.clone()
    });
    let config = params.config()?;
    let labels = match (&args.labels, params.keep_part_borders) {
        (Some(path), true) => {
            let labels = desal_io::labels::read_labels(path)?;
            labels.check_vertex_count(mesh.vertex_count()).with_context(|| format!("{}", path.display()))?;
            Some(labels)
        }
        (None, true) => anyhow::bail!("--keep-part-borders needs the mesh's part labels: give --labels"),
        (Some(path), false) => {
            anyhow::bail!("{}: --labels is read only with --keep-part-borders", path.display())
        }
        (None, false) => None,
    };
    let ids = labels.as_ref().map_or(&[][..], |l| l.labels.as_slice());
    let input =
        SimplifyInput::new(&mesh).with_inputs_read_by(&config, weights.as_deref().unwrap_or(&[]), ids);
    let mut best = f64::INFINITY;
    let mut result = None;
    for _ in 0..args.repeat.unwrap_or(1).max(1) {
        let started = std::time::Instant::now();
        let simplified = desal_simplify::simplify(&input, &config)
            .with_context(|| format!("simplifying {}", args.input.display()))?;
        best = best.min(started.elapsed().as_secs_f64());
        result = Some(simplified);
    }
    let simplified = result.expect("at least one run");
    desal_io::ply::write_ply(&args.output, &simplified.mesh, &desal_io::ply::PlyWriteOptions::default())?;
    eprintln!("{}", simplified.report);
    if args.repeat.is_some() {
        crate::print_out(&format!("SIMPLIFY_SECONDS={best}\n"))?;
    }
    Ok(())
}

/// Stage-3 weights from a saliency artifact, a PLY `saliency` property or a text file,
/// one per vertex of the mesh being simplified.
/// `desal hierarchy`: the coarse levels of a pose set (`[dataset.hierarchy]`) as one
/// stage on artifacts, with the pipeline's default stage-1–3 settings (plus
/// `--balance`); writes the same `hierarchy.npz` bytes as `desal run`.
#[derive(Debug)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct HierarchyArgs {
    /// Pose-set artifact (`poses.dsa`).
    #[cfg_attr(feature = "cli", arg(long))]
    pub poses: PathBuf,
    /// Labels artifact (`labels.dsa`).
    #[cfg_attr(feature = "cli", arg(long))]
    pub labels: PathBuf,
    /// Coarse vertex counts, strictly decreasing, e.g. `2500,625`.
    #[cfg_attr(feature = "cli", arg(long, value_delimiter = ',', required = true))]
    pub levels: Vec<usize>,
    /// `fitted` (pose-aware, default) or `barycentric` (COMA's).
    #[cfg_attr(feature = "cli", arg(long, value_enum, default_value_t = stages::hierarchy::UpsamplerName::default()))]
    pub upsampler: stages::hierarchy::UpsamplerName,
    /// Fitted only: candidate coarse vertices per fine vertex (default: chosen per level
    /// by held-out error, 8 to 32).
    #[cfg_attr(feature = "cli", arg(long))]
    pub neighbours: Option<usize>,
    /// Fitted only: relative ridge toward the barycentric row (default: chosen per level
    /// by held-out error, 1e-5 to 3e-2).
    #[cfg_attr(feature = "cli", arg(long))]
    pub ridge: Option<f64>,
    /// Multiply each level's simplification cost by the edge length (the paper's balance
    /// term; off by default, as in pipeline files).
    #[cfg_attr(feature = "cli", arg(long))]
    pub balance: bool,
    /// Also measure the held-out upsampling error by v2f (slow on large meshes).
    #[cfg_attr(feature = "cli", arg(long))]
    pub heldout_v2f: bool,
    /// Where to write `hierarchy.npz`.
    #[cfg_attr(feature = "cli", arg(long, short))]
    pub output: PathBuf,
    /// Also write the levels' figures (`hierarchy.json`) here.
    #[cfg_attr(feature = "cli", arg(long))]
    pub json: Option<PathBuf>,
}

pub fn hierarchy(args: &HierarchyArgs) -> Result<()> {
    use stages::hierarchy::{HierarchyParams, HierarchyReport};
    let (poses, _) = read::<PoseSetV2>(&args.poses)?;
    let (labels, _) = read::<LabelsV1>(&args.labels)?;
    let set = poses.to_pose_set().with_context(|| format!("{}", args.poses.display()))?;
    let labels = labels.to_labels().with_context(|| format!("{}", args.labels.display()))?;
    let params = HierarchyParams {
        levels: args.levels.clone(),
        upsampler: args.upsampler,
        neighbours: args.neighbours,
        ridge: args.ridge,
        neighbourhood: None,
        heldout_v2f: args.heldout_v2f,
    };
    params.config()?;
    let stage = crate::memory::StageParams {
        simplify: stages::simplify::SimplifyParams { balance: args.balance, ..Default::default() },
        ..Default::default()
    };
    let (arrays, summaries) = crate::memory::hierarchy(&stage, &params, &set, &labels, &NoProgress)?;
    for level in &summaries {
        eprintln!("{}", level.note());
    }
    let report =
        HierarchyReport::new(arrays.levels.clone(), args.upsampler_name(), set.group_count(), &summaries);
    let report = serde_json::to_value(&report)?;
    let mut files: Vec<(PathBuf, FileWriter)> =
        vec![(args.output.clone(), Box::new(move |p| Ok(desal_io::npz::write_hierarchy_npz(p, &arrays)?)))];
    if let Some(json) = &args.json {
        files.push((json.clone(), Box::new(move |p| Ok(desal_io::write_json(p, &report)?))));
    }
    write_all_or_nothing(files)?;
    eprintln!("wrote {}", args.output.display());
    Ok(())
}

impl HierarchyArgs {
    fn upsampler_name(&self) -> &'static str {
        match self.upsampler {
            stages::hierarchy::UpsamplerName::Fitted => "fitted",
            stages::hierarchy::UpsamplerName::Barycentric => "barycentric",
        }
    }
}

fn read_weights(path: &Path, floor: Option<f64>, vertex_count: usize) -> Result<Vec<f64>> {
    let floor_of = |f: f64| -> Result<f64> {
        anyhow::ensure!((0.0..=1.0).contains(&f), "--floor {f} is outside [0, 1]");
        Ok(f)
    };
    let weights: Vec<f64> = if artifact::is_artifact(path) {
        let (body, _) = read::<SaliencyV1>(path)?;
        match floor {
            None => body.weights,
            Some(f) => {
                let f = floor_of(f)?;
                body.saliency.iter().map(|&s| desal_saliency::weight(s, f)).collect()
            }
        }
    } else {
        let saliency = read_saliency_values(path)?;
        let f = floor_of(floor.unwrap_or(desal_saliency::DEFAULT_WEIGHT_FLOOR))?;
        if let Some((v, s)) = saliency.iter().enumerate().find(|(_, s)| !(0.0..=1.0).contains(*s)) {
            anyhow::bail!("{}: saliency of vertex {v} is {s}, outside [0, 1]", path.display());
        }
        saliency.iter().map(|&s| desal_saliency::weight(s, f)).collect()
    };
    anyhow::ensure!(
        weights.len() == vertex_count,
        "{}: {} saliency values for a mesh of {vertex_count} vertices",
        path.display(),
        weights.len()
    );
    Ok(weights)
}

/// Saliency values from a PLY's `saliency` vertex property or a text file with one
/// number per line.
fn read_saliency_values(path: &Path) -> Result<Vec<f64>> {
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("ply")) {
        let ply = desal_io::ply::read_ply_full(path)?;
        let (_, values) = ply.scalars.iter().find(|(name, _)| name == "saliency").with_context(|| {
            format!("{}: the PLY has no float vertex property `saliency`", path.display())
        })?;
        return Ok(values.iter().map(|&x| x as f64).collect());
    }
    let text = desal_io::file::read_text_file(path)?;
    text.lines()
        .enumerate()
        .map(|(i, line)| (i, line.trim()))
        .filter(|(_, line)| !line.is_empty() && !line.starts_with('#'))
        .map(|(i, line)| {
            line.parse::<f64>()
                .with_context(|| format!("{}:{}: `{line}` is not a number", path.display(), i + 1))
        })
        .collect()
}

/// `desal parts`: near-rigid parts discovered from an ingested pose set, written as the
/// labels artifact `labels = "auto"` gives (byte for byte).
#[derive(Debug)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct PartsArgs {
    /// Pose-set artifact (`poses.dsa` from `desal run`).
    #[cfg_attr(feature = "cli", arg(long))]
    pub poses: PathBuf,
    /// The number of parts; absent: chosen at the knee of the residual curve.
    #[cfg_attr(feature = "cli", arg(long))]
    pub parts: Option<usize>,
    /// Where to write the labels artifact.
    #[cfg_attr(feature = "cli", arg(long, short))]
    pub output: PathBuf,
    /// Also write the labels as text here (one id per vertex, `# parts:` header).
    #[cfg_attr(feature = "cli", arg(long))]
    pub txt: Option<PathBuf>,
    /// Also draw the parts on the template here (PNG).
    #[cfg_attr(feature = "cli", arg(long))]
    pub png: Option<PathBuf>,
    /// Up axis for the picture (x, y, z, optionally signed); detected when absent.
    #[cfg_attr(feature = "cli", arg(long))]
    pub up_axis: Option<String>,
}

pub fn parts(args: &PartsArgs) -> Result<()> {
    let (poses, poses_hash) = read::<PoseSetV2>(&args.poses)?;
    let set = poses.to_pose_set().with_context(|| format!("{}", args.poses.display()))?;
    let params = stages::parts::PartsParams { count: args.parts, ..Default::default() };
    let key = params.key(poses_hash)?;
    let up = crate::pictures::parse_up_axis(args.up_axis.as_deref())?;
    let out = stages::parts::compute(&params, &set)?;
    let labels = out.body.to_labels()?;
    // Everything is rendered before anything is written: all files or none.
    let producer = key.producer(&[]);
    let body = out.body;
    let mut files: Vec<(PathBuf, FileWriter)> = vec![(
        args.output.clone(),
        Box::new(move |p| Ok(artifact::write_artifact(p, &producer, &body).map(|_| ())?)),
    )];
    if let Some(path) = &args.txt {
        let text = stages::parts::labels_txt(&labels);
        files.push((path.clone(), Box::new(move |p| Ok(desal_io::write_atomic(p, text.as_bytes())?))));
    }
    if let Some(path) = &args.png {
        let png = crate::pictures::parts_png(&set.template_mesh(), &labels, up)?;
        files.push((path.clone(), Box::new(move |p| Ok(desal_io::write_atomic(p, &png)?))));
    }
    write_all_or_nothing(files)?;
    done(&out.note, &args.output);
    Ok(())
}

#[cfg(all(test, feature = "cli"))]
mod tests {
    use super::*;
    use clap::Parser;
    use desal_simplify::SimplifyConfig;

    #[derive(Debug, Parser)]
    struct Simplify {
        #[command(flatten)]
        args: SimplifyArgs,
    }

    #[derive(Debug, Parser)]
    struct Fit {
        #[command(flatten)]
        args: FitArgs,
    }

    #[derive(Debug, Parser)]
    struct Saliency {
        #[command(flatten)]
        args: SaliencyArgs,
    }

    /// The one table of defaults (README "Defaults"): the library, pipeline files and the
    /// CLI agree on every knob they share.
    #[test]
    fn cli_pipeline_and_library_defaults_agree() {
        let cli =
            Simplify::try_parse_from(["desal-simplify", "--input", "a", "--output", "b", "--ratio", "0.5"])
                .unwrap()
                .args;
        let library = SimplifyConfig::default();
        let pipeline = stages::simplify::SimplifyParams::default().config().unwrap();
        assert_eq!(pipeline, library, "pipeline files resolve to the library's defaults");
        // The flags are `[simplify]`'s knobs: left out, they resolve as a pipeline file's do.
        let from_cli = stages::simplify::SimplifyParams::from(cli.knobs).config().unwrap();
        assert_eq!(from_cli, SimplifyConfig { target: desal_simplify::Target::Ratio(0.5), ..library });

        let cli =
            Fit::try_parse_from(["desal-fit", "--poses", "p", "--labels", "l", "-o", "o"]).unwrap().args;
        assert_eq!(cli.method, FitParams::default().method);
        assert_eq!(FitParams::default().config(), desal_fit::FitConfig::default());

        let cli = Saliency::try_parse_from(["desal-saliency", "--poses", "p", "--fit", "f", "-o", "o"])
            .unwrap()
            .args;
        let library = desal_saliency::SaliencyConfig::default();
        let params = SaliencyParams::default();
        assert_eq!(params.config().unwrap(), library);
        assert_eq!(
            (cli.percentile, cli.squared, cli.floor),
            (params.percentile, params.squared, params.floor)
        );
    }
}
