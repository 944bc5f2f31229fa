//! `desal eval`: the paper's experiment (§4) — simplify with each method, carry the
//! simplification to every pose, fit the SCAPE deformation model on the simplified
//! set, deform to every pose and measure v2f/v2v against the ground truth.
//!
//! The peers are features of their own, all on by default: `meshopt` builds
//! meshoptimizer's C++ for its methods; `meshlab` (`meshlab.rs`, pymeshlab in a Python
//! found at run time) and `gltfpack` (`gltfpack.rs`, a program on the PATH) are
//! subprocesses, their methods named explicitly. A build without one refuses its methods
//! by name ([`methods::PEERS`]).
//!
//! The story of [`eval`], per dataset of the pipeline file:
//! 1. run the pipeline's cached stages (`desal run`), so the inputs are validated
//!    artifacts, and take the pose set, labels and stage-3 saliency weights from their
//!    results in-process;
//! 2. per method ([`methods`]): simplify the template, map it to original vertices,
//!    then [`measure::deform`]: part rotations on the simplified set, the SCAPE model
//!    in-sample and per held-out fold, every pose synthesised;
//! 3. [`measure::measure`] every deformed pose against the simplified and the
//!    full-resolution ground truth;
//! 4. write `eval.json`, `eval.md` ([`report`]), the figures ([`figures`]), optionally
//!    every deformed mesh and the vertex-count sweep ([`sweep`]) into a temporary
//!    folder, which then replaces `<out>/<dataset>/eval` whole.
//!
//! `desal run` replaces `<out>/<dataset>` whole when its own outputs change but carries
//! the `eval/` folder over (`outputs::KEPT_SUBFOLDER`).

pub mod every_measure;
pub mod figures;
pub mod floor;
#[cfg(feature = "gltfpack")]
pub mod gltfpack;
pub mod lods;
pub mod measure;
#[cfg(feature = "meshlab")]
pub mod meshlab;
#[cfg(feature = "meshopt")]
pub mod meshopt;
pub mod methods;
pub mod model;
pub mod regions;
pub mod report;
pub mod rig;
pub mod sweep;
pub mod upsampling;

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use desal_io::ply::{PlyWriteOptions, write_ply};
use desal_measures::SurfaceIndex;
use desal_mesh::{PoseSet, TriMesh, Vec3};
use desal_simplify::Target;
use rayon::prelude::*;

use desal_driver::pipeline::{Dataset, Pipeline};
use desal_driver::progress::Console;
use desal_driver::run::{DatasetRun, RunOptions};
use desal_driver::stages::DatasetStages;
use desal_driver::stages::simplify::SimplifyParams;
use desal_io::confine::file_stem_for;
use figures::{GridRow, Views};
use measure::{Deformed, MeanStd, Measured, Run};
use methods::{BASELINE, Inputs, Method, SimplifiedSet};
use report::{EvalReport, FoldRecord, MethodReport, MethodTimings, PoseRecord};

/// `desal eval` / `desal-eval` arguments.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct EvalArgs {
    /// The pipeline file (TOML; see pipelines/README.md). Every dataset is evaluated.
    pub pipeline: PathBuf,
    /// Methods, comma-separated: qslim-optimal, saliency-optimal, paper-optimal,
    /// qslim-subset, saliency-subset, paper-subset,
    #[cfg_attr(feature = "meshopt", doc = "multipose, meshopt, meshopt-regularize, meshopt-priority;")]
    #[cfg_attr(not(feature = "meshopt"), doc = "multipose;")]
    #[cfg_attr(feature = "meshlab", doc = "meshlab and meshlab-saliency (Python with pymeshlab:")]
    #[cfg_attr(feature = "meshlab", doc = "$DESAL_PYTHON or python3);")]
    #[cfg_attr(feature = "gltfpack", doc = "gltfpack and gltfpack-sa (rig datasets; $DESAL_GLTFPACK")]
    #[cfg_attr(feature = "gltfpack", doc = "or gltfpack);")]
    /// a bare qslim, saliency or paper means both
    /// placements; external:NAME=PATH is another tool's simplified template; all = every
    /// built-in method but MeshLab's and gltfpack's.
    #[cfg_attr(feature = "cli", arg(long, value_delimiter = ',', default_value = "all"))]
    pub methods: Vec<String>,
    /// The deformation model: scape (part-anchored, the default: the lowest held-out
    /// error at full resolution), scape-cv (its ridge and features cross-validated in
    /// each training fold), scape-centroid (the paper's placement), lbs (linear blend
    /// skinning with the parts as bones), rig (a rig dataset's own skinning with each
    /// simplified rig's weights; the default for [dataset.rig] datasets).
    #[cfg_attr(feature = "cli", arg(long))]
    pub model: Option<String>,
    /// The row every relative change and sign test is taken against (default:
    /// qslim-optimal; gltfpack for a rig dataset that runs it).
    #[cfg_attr(feature = "cli", arg(long))]
    pub baseline: Option<String>,
    /// Measures to leave out, comma-separated: scape and lbs (the models measured beside
    /// --model), upsampling, surface, spikes (of the opening table), lods (a rig's LOD
    /// levels, `lods::evaluate`). Every measure is on by default; eval.md names what was
    /// skipped.
    #[cfg_attr(feature = "cli", arg(long, value_delimiter = ','))]
    pub skip: Vec<String>,
    /// Pick a method per use: without --methods, evaluate the candidates of every
    /// `[simplify] objective` (PICK_METHODS) instead of `all`, and print, per objective,
    /// the method with the lowest held-out error under its measure on this data.
    #[cfg_attr(feature = "cli", arg(long))]
    pub pick: bool,
    /// Skip the model's own floor (the model fitted and measured at full resolution).
    #[cfg_attr(feature = "cli", arg(long))]
    pub no_floor: bool,
    /// Number of held-out folds over the non-template poses (at least 2).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 5))]
    pub folds: usize,
    /// Output root (each dataset writes OUT/<name>/eval); overrides the file's `out`.
    #[cfg_attr(feature = "cli", arg(long))]
    pub out: Option<PathBuf>,
    /// Cache folder for the pipeline's stages (default: <output root>/.cache).
    #[cfg_attr(feature = "cli", arg(long))]
    pub cache_dir: Option<PathBuf>,
    /// Target vertex count of every method (default: the pipeline's simplify target).
    #[cfg_attr(feature = "cli", arg(long))]
    pub target_vertices: Option<usize>,
    /// Write every deformed mesh (and the simplified ground truth) as PLY under
    /// eval/deformed/<method>/{in-sample,held-out,ground-truth}/<pose>.ply.
    #[cfg_attr(feature = "cli", arg(long))]
    pub save_deformed: bool,
    /// Also evaluate the --sweep-methods at the --sweep-vertices counts: sweep.json,
    /// sweep.png and eval.md's sweep table.
    #[cfg_attr(feature = "cli", arg(long))]
    pub sweep: bool,
    /// Methods of the sweep, as in --methods (meshlab-saliency needs $DESAL_PYTHON).
    #[cfg_attr(feature = "cli", arg(long, value_delimiter = ',', default_value = sweep::SWEEP_METHODS))]
    pub sweep_methods: Vec<String>,
    /// Vertex counts of the sweep.
    #[cfg_attr(
        feature = "cli",
        arg(long, value_delimiter = ',', default_value = "1000,2000,3000,4000,5000,6000")
    )]
    pub sweep_vertices: Vec<usize>,
    /// Poses drawn in the figures (names, comma-separated; default: four spread over the
    /// set).
    #[cfg_attr(feature = "cli", arg(long, value_delimiter = ','))]
    pub figure_poses: Vec<String>,
    /// No progress output.
    #[cfg_attr(feature = "cli", arg(long))]
    pub quiet: bool,
}

/// Runs `desal eval`: every dataset of the pipeline, every method; prints where each
/// dataset's results went.
pub fn eval(args: &EvalArgs, console: Arc<dyn Console>) -> Result<()> {
    let methods = if args.pick && args.methods == ["all"] {
        let pipeline = desal_driver::pipeline::load(&args.pipeline, args.out.as_deref())?;
        let rig = pipeline.datasets.iter().any(|d| d.spec.rig.is_some());
        let pose_model = args.model.as_deref() != Some(model::RIG) && !rig;
        let names: Vec<String> = PICK_METHODS
            .iter()
            .filter(|&&m| pose_model || m != "desal-refit")
            .map(|m| m.to_string())
            .collect();
        Method::parse_list(&names)?
    } else {
        Method::parse_list(&args.methods)?
    };
    let sweep_methods = if args.sweep {
        let sweep_methods = Method::parse_list(&args.sweep_methods).context("--sweep-methods")?;
        if let Some(m) = sweep_methods.iter().find(|m| matches!(m, Method::External { .. })) {
            bail!(
                "--sweep-methods: '{}' is another tool's mesh at one vertex count; it cannot be swept",
                m.name()
            );
        }
        sweep_methods
    } else {
        Vec::new()
    };
    model::check(args.model.as_deref())?;
    if let Some(s) = args.skip.iter().find(|s| !every_measure::SKIPPABLE.contains(&s.as_str())) {
        bail!("--skip {s}: not a measure that can be skipped (use {})", every_measure::SKIPPABLE.join(", "));
    }
    if let Some(b) = &args.baseline
        && !methods.iter().any(|m| m.name() == *b)
    {
        bail!("--baseline {b} is not one of the --methods");
    }
    if args.folds < 2 {
        bail!("--folds {} is too few: held-out evaluation needs at least 2 folds", args.folds);
    }
    if args.target_vertices == Some(0) || (args.sweep && args.sweep_vertices.contains(&0)) {
        bail!("a target vertex count must be positive");
    }
    // Another tool's meshes are read now, so a wrong path fails before anything runs.
    for method in &methods {
        if let Method::External { name, path } = method {
            desal_io::read_mesh(path).with_context(|| format!("method '{name}'"))?;
        }
    }
    let pipeline = desal_driver::pipeline::load(&args.pipeline, args.out.as_deref())?;
    let options = RunOptions {
        out: args.out.clone(),
        cache_dir: args.cache_dir.clone(),
        console,
        ..RunOptions::default()
    };
    let runs =
        desal_driver::run::run_with_stages(&pipeline, &options).context("running the pipeline's stages")?;
    for DatasetRun { dataset, stages, .. } in &runs {
        let dataset = &pipeline.datasets[*dataset];
        let (dir, picks) = evaluate_dataset(&pipeline, dataset, stages, &methods, &sweep_methods, args)
            .with_context(|| format!("evaluating dataset '{}'", dataset.spec.name))?;
        desal_driver::print_out(&format!("{}: {}\n", dataset.spec.name, dir.join("eval.md").display()))?;
        if args.pick {
            for pick in &picks {
                desal_driver::print_out(&format!(
                    "{}: objective = \"{}\" picks {} (score {:.3})\n",
                    dataset.spec.name, pick.objective, pick.method, pick.score
                ))?;
            }
        }
    }
    Ok(())
}

/// `--pick`'s candidates: the baseline, the paper's stage 3 and every method an objective
/// may pick (`desal-refit` only under a pose model).
pub const PICK_METHODS: [&str; 6] =
    ["qslim-optimal", "paper-optimal", "desal", "desal-refit", "desal-upsample", "multipose"];

/// One method carried through steps 2 and 3.
struct MethodRun {
    method: Method,
    set: SimplifiedSet,
    deformed: Deformed,
    measured: Measured,
    /// Per evaluated pose: the upsampling errors ([`upsampling`]); `None` when skipped.
    upsampling: Option<Vec<upsampling::PoseUpsamplers>>,
    /// The other models' held-out errors ([`every_measure`]).
    other_models: Vec<report::OtherModel>,
    /// The simplified template's v2f against the full one; `None` when skipped.
    surface_v2f: Option<f64>,
    /// [`measure::spikes`]: in the rest pose, then per evaluated pose; `None` when skipped.
    spikes: Option<(usize, Vec<usize>)>,
}

fn evaluate_dataset(
    pipeline: &Pipeline,
    dataset: &Dataset,
    stages: &DatasetStages,
    methods: &[Method],
    sweep_methods: &[Method],
    args: &EvalArgs,
) -> Result<(PathBuf, Vec<report::Pick>)> {
    let started = Instant::now();
    let (model_name, model) = model::resolve(args.model.as_deref(), stages.rig.is_some())?;
    let name = dataset.spec.name.as_str();
    let log = |message: &str| {
        if !args.quiet {
            eprintln!("eval {name}: {message}");
        }
    };
    let mut inputs = load_inputs(dataset, stages)?;
    inputs.part_fits = model.pose_model().is_some();
    inputs.refit_model = model.pose_model().cloned();
    let poses = &inputs.poses;
    let target = match args.target_vertices {
        Some(v) => Target::Vertices(v),
        None => dataset.spec.simplify.target(),
    };
    // With groups, whole groups are held out and the template's group only trains.
    let folds = desal_measures::pose_set_folds(poses, args.folds);
    if folds.len() < 2 {
        match poses.group_count() {
            Some(groups) => bail!(
                "held-out evaluation over groups needs at least two groups besides the template's; the poses \
                 fall in {groups}"
            ),
            None => {
                bail!("held-out evaluation needs at least three poses (the template and two to hold out)")
            }
        }
    }
    let evaluated = desal_measures::tested_poses(&folds);
    // Checked now, so a bad --figure-poses fails before anything is computed.
    figure_poses(poses, &evaluated, &args.figure_poses)?;

    // Step 2: simplify, map and deform, one method at a time (each runs in parallel);
    // then the upsampling error of the simplified mesh and of its deformations.
    let fitted = desal_driver::stages::hierarchy::measured_fitted(dataset.spec.hierarchy.as_ref())?;
    // Every full-resolution pose's surface index, built once: the upsampling error of
    // every method, the floor and the measure query the same poses.
    let full_surfaces: Vec<SurfaceIndex> = (0..poses.pose_count())
        .into_par_iter()
        .map(|p| SurfaceIndex::with_vertex_rings(&poses.pose_mesh(p)))
        .collect();
    let skipped = |name: &str| args.skip.iter().any(|s| s == name);
    let other_models: Vec<(String, model::EvalModel)> = every_measure::OTHER_MODELS
        .iter()
        .filter(|&&name| name != model_name && !skipped(name))
        .map(|&name| Ok((name.to_owned(), model::resolve(Some(name), stages.rig.is_some())?.1)))
        .collect::<Result<_>>()?;
    let full_template = poses.template_mesh();
    // A rig of several meshes: spikes are judged mesh by mesh.
    let meshes = inputs.rig.as_ref().and_then(rig::RigModel::mesh_split);
    let mut prepared = Vec::new();
    for method in methods {
        let set = methods::simplify_and_map(method, &inputs, target)?;
        log(&format!("{}: {}", method.name(), set.note));
        let deformed = model
            .deform(&inputs, &set, &folds)
            .with_context(|| format!("{}: deformation model", method.name()))?;
        let fit: f64 = deformed.models.iter().map(|m| m.fit_seconds + m.synthesis_seconds).sum();
        log(&format!(
            "{}: {} models fitted, every pose synthesised ({fit:.2} s)",
            method.name(),
            deformed.models.len()
        ));
        let up = if skipped("upsampling") {
            None
        } else {
            let up_started = Instant::now();
            let up = upsampling::measure(poses, &set, &deformed, &folds, &evaluated, &fitted, &full_surfaces)
                .with_context(|| format!("{}: upsampling error", method.name()))?;
            log(&format!(
                "{}: upsampled to full resolution, barycentric and fitted U per fold ({:.2} s)",
                method.name(),
                up_started.elapsed().as_secs_f64()
            ));
            Some(up)
        };
        // The other models: one that cannot be fitted on this method's set (a part
        // left without a plane) is reported as such, not an error of the eval.
        let mut others = Vec::new();
        for (name, other) in &other_models {
            let started = Instant::now();
            let measured = other.deform(&inputs, &set, &folds).map(|deformed| {
                let run = measure::Run { simplified: &set.mapped.poses, deformed: &deformed };
                measure::held_out_vs_full(poses, &evaluated, &[run], &full_surfaces).remove(0)
            });
            let (poses_errors, error) = match measured {
                Ok(errors) => (errors, None),
                Err(e) => (Vec::new(), Some(format!("{e:#}"))),
            };
            log(&format!("{}: under {name} ({:.2} s)", method.name(), started.elapsed().as_secs_f64()));
            others.push(report::OtherModel { model: name.clone(), poses: poses_errors, error });
        }
        let surface_v2f =
            (!skipped("surface")).then(|| desal_measures::metrics::v2f(&set.raw, &full_template));
        let spikes = (!skipped("spikes")).then(|| {
            let run = measure::Run { simplified: &set.mapped.poses, deformed: &deformed };
            measure::spikes(
                poses,
                &evaluated,
                &run,
                &set.mapped.map.simp_to_orig,
                &full_surfaces,
                meshes.as_ref(),
            )
        });
        prepared.push((method.clone(), set, deformed, up, (others, surface_v2f, spikes)));
    }

    // The model's own floor: the same model on the full-resolution set, the same folds
    // (none for the rig's skinning: at full resolution it is the ground truth).
    let floor = match model.pose_model() {
        Some(model) if !args.no_floor => Some(model),
        _ => None,
    };
    let floor = if let Some(model) = floor {
        // Cached: it depends on the pose set, labels, model and folds only.
        let cache = desal_driver::cache::Cache::for_output(args.cache_dir.as_deref(), &pipeline.out_root);
        let key = floor::key(&model_name, model, args.folds, stages)?;
        let measured = floor::cached(&cache, &key, &model_name, || {
            model_floor(&inputs, model, args.folds, &full_surfaces)
                .context("the model's floor at full resolution")
        })?;
        let (f, seconds) = (&measured.floor, measured.seconds);
        log(&format!(
            "the model at full resolution: held-out v2v {:.3e}, {:.2}x in-sample ({seconds:.2} s{})",
            f.held_out.v2v,
            f.v2v_ratio(),
            if measured.cached { ", from the cache" } else { "" }
        ));
        Some(report::FloorReport::new(&measured))
    } else {
        None
    };

    // Step 3: every deformed pose against both ground truths.
    let measure_started = Instant::now();
    let runs: Vec<Run> = prepared
        .iter()
        .map(|(_, set, deformed, ..)| Run { simplified: &set.mapped.poses, deformed })
        .collect();
    let measured = measure::measure_indexed(poses, &evaluated, &runs, Some(&full_surfaces));
    let measure_seconds = measure_started.elapsed().as_secs_f64();
    log(&format!("measured {} poses x {} methods ({measure_seconds:.2} s)", evaluated.len(), prepared.len()));
    let runs: Vec<MethodRun> = prepared
        .into_iter()
        .zip(measured)
        .map(|((method, set, deformed, upsampling, (other_models, surface_v2f, spikes)), measured)| {
            MethodRun { method, set, deformed, measured, upsampling, other_models, surface_v2f, spikes }
        })
        .collect();

    // Step 4: reports, figures, meshes, sweep — into a temporary folder first.
    let regions = regions::Regions::new(&poses.template_mesh(), &inputs.labels);
    let baseline = match &args.baseline {
        Some(b) => b.clone(),
        #[cfg(feature = "gltfpack")]
        None if matches!(model, model::EvalModel::Rig)
            && runs.iter().any(|r| r.method.name() == "gltfpack") =>
        {
            "gltfpack".into()
        }
        None => BASELINE.into(),
    };
    let mut report = build_report(
        pipeline, dataset, &inputs, target, &folds, &evaluated, &runs, &regions, &fitted, &baseline,
    );
    report.model = model_name;
    let base_index = report.methods.iter().position(|m| Some(&m.name) == report.baseline.as_ref());
    report.measures = every_measure::columns(&report.methods, &report.model, base_index);
    let names: Vec<String> = report.methods.iter().map(|m| m.name.clone()).collect();
    report.picks = every_measure::picks(&report.measures, &report.model, &names)
        .into_iter()
        .map(|(objective, method, score)| report::Pick { objective: objective.name().into(), method, score })
        .collect();
    report.skipped = args.skip.clone();
    report.floor = floor;
    if !skipped("lods") {
        report.lods = lods::evaluate(stages, &inputs, methods, &log).context("the LOD levels")?;
    }
    report.measure_seconds = measure_seconds;
    let eval_dir = dataset.out_dir.join("eval");
    desal_io::replace_dir(&eval_dir, &[], |dir| -> Result<()> {
        let mut files = write_figures(dir, dataset, &inputs, &evaluated, &runs, args)?;
        if args.save_deformed {
            save_deformed(dir, poses, &evaluated, &runs)?;
            files.push("deformed/<method>/{in-sample,held-out,ground-truth}/<pose>.ply".into());
        }
        let mut sweep_md = String::new();
        if args.sweep {
            let sweep_baseline = sweep::baseline(sweep_methods, &baseline);
            let points = sweep::run_sweep(
                &inputs,
                sweep_methods,
                &sweep_baseline,
                &args.sweep_vertices,
                &folds,
                &evaluated,
                &model,
                &log,
            );
            desal_io::write_json(&dir.join("sweep.json"), &points)?;
            desal_io::write_atomic(&dir.join("sweep.png"), &figures::sweep_png(&sweep::panels(&points))?)?;
            files.extend(["sweep.json".into(), "sweep.png".into()]);
            sweep_md = sweep::markdown(&points, &sweep_baseline);
        }
        report.total_seconds = started.elapsed().as_secs_f64();
        desal_io::write_json(&dir.join("eval.json"), &report)?;
        let opening = every_measure::markdown(&report);
        let md = report::markdown(&report, &files, &opening)
            + &lods::markdown(&report.lods, report.baseline.as_deref().unwrap_or("gltfpack"))
            + &sweep_md;
        desal_io::write_atomic(&dir.join("eval.md"), md.as_bytes())?;
        Ok(())
    })?;
    Ok((eval_dir, report.picks))
}

/// [`desal_measures::model_floor`] of `model` on the full-resolution pose set, driven by
/// stage 1's rigid fit of that set, with `k` folds (the method runs' own).
fn model_floor(
    inputs: &Inputs,
    model: &desal_measures::PoseModel,
    k: usize,
    full_surfaces: &[SurfaceIndex],
) -> Result<desal_measures::ModelFloor> {
    let transforms = measure::part_motions(&inputs.poses, &inputs.labels)?;
    Ok(desal_measures::model_floor_indexed(
        &inputs.poses,
        &inputs.labels,
        &transforms,
        model,
        k,
        Some(full_surfaces),
    )?)
}

/// What every method reads, from the pipeline stages' results.
fn load_inputs(dataset: &Dataset, stages: &DatasetStages) -> Result<Inputs> {
    let poses = stages.pose_set()?.clone();
    let labels = stages.part_labels()?.clone();
    let weights = stages.saliency.body()?.weights.clone();
    // The settings, not the method: every method sets its own (`desal` and `desal-refit`
    // are methods of the eval too).
    let base_config = SimplifyParams { method: None, ..dataset.spec.simplify.clone() }.config()?;
    let simplification_poses = dataset.spec.saliency.seen_poses(&poses);
    let rig = stages.rig.as_ref().map(|source| rig::RigModel::load(source, &poses)).transpose()?;
    // From the rig just loaded (`stages::seams::rig_seam_edges` would read and pose it again).
    let seams = rig
        .as_ref()
        .filter(|_| dataset.spec.simplify.keeps_seams())
        .map(|r| desal_rig::seam_edges(&r.rig.mesh, &r.posed.weld));
    Ok(Inputs {
        poses,
        labels,
        weights,
        simplification_poses,
        base_config,
        rig,
        part_fits: true,
        seams,
        refit_model: None,
        full_model: Default::default(),
    })
}

#[allow(clippy::too_many_arguments)]
fn build_report(
    pipeline: &Pipeline,
    dataset: &Dataset,
    inputs: &Inputs,
    target: Target,
    folds: &[Vec<usize>],
    evaluated: &[usize],
    runs: &[MethodRun],
    regions: &regions::Regions,
    fitted: &desal_hierarchy::Upsampler,
    baseline_name: &str,
) -> EvalReport {
    let poses = &inputs.poses;
    let mut methods: Vec<MethodReport> =
        runs.iter().map(|run| method_report(poses, evaluated, run, regions, fitted)).collect();
    let baseline = methods.iter().position(|m| m.name == baseline_name);
    if let Some(b) = baseline {
        let base_poses = methods[b].poses.clone();
        for (k, m) in methods.iter_mut().enumerate() {
            if k != b {
                m.versus_baseline = Some(report::versus(&m.poses, &base_poses));
            }
        }
    }
    EvalReport {
        dataset: dataset.spec.name.clone(),
        pipeline: pipeline.path.display().to_string(),
        desal_version: env!("CARGO_PKG_VERSION").into(),
        units: "squared distances in the input's units (m² for metre data)".into(),
        pose_names: poses.names.clone(),
        template: poses.template,
        evaluated_poses: evaluated.to_vec(),
        original_vertices: poses.vertex_count(),
        original_faces: poses.face_count(),
        target: match target {
            Target::Vertices(v) => format!("vertices {v}"),
            Target::Faces(f) => format!("faces {f}"),
            Target::Ratio(r) => format!("ratio {r}"),
        },
        folds: folds
            .iter()
            .enumerate()
            .map(|(fold, test)| FoldRecord {
                fold,
                test_poses: test.clone(),
                training_poses: desal_measures::training_poses(poses.pose_count(), test),
            })
            .collect(),
        baseline: baseline.map(|_| baseline_name.to_owned()),
        methods,
        measures: Vec::new(),
        picks: Vec::new(),
        skipped: Vec::new(),
        joint_band_radius: regions.radius,
        model: String::new(),
        floor: None,
        lods: Vec::new(),
        measure_seconds: 0.0,
        total_seconds: 0.0,
    }
}

fn method_report(
    poses: &PoseSet,
    evaluated: &[usize],
    run: &MethodRun,
    regions: &regions::Regions,
    fitted: &desal_hierarchy::Upsampler,
) -> MethodReport {
    let set = &run.set.mapped;
    let template = set.poses.template_mesh();
    let records: Vec<PoseRecord> = evaluated
        .iter()
        .enumerate()
        .map(|(k, &pose)| PoseRecord {
            pose,
            name: poses.names[pose].clone(),
            fold: run.deformed.fold_of_pose[pose].expect("every evaluated pose is in a fold"),
            in_sample: run.measured.in_sample[k],
            held_out: run.measured.held_out[k],
            upsampling: run.upsampling.as_ref().map(|u| u[k]),
            spikes: run.spikes.as_ref().map(|(_, per_pose)| per_pose[k]),
        })
        .collect();
    let in_sample = &run.deformed.models[0];
    let (edge_length_mean, edge_length_variance) = template.edge_length_stats();
    MethodReport {
        name: run.method.name(),
        placement: run.method.placement().into(),
        source: match &run.method {
            Method::External { path, .. } => Some(path.display().to_string()),
            _ => None,
        },
        vertices: set.poses.vertex_count(),
        faces: set.poses.face_count(),
        stop: run.set.stop.map(|s| s.name().into()),
        simplify_note: run.set.note.clone(),
        map_mode: set.report.mode.into(),
        displacement_mean: set.report.displacement.mean,
        displacement_max: set.report.displacement.max,
        edge_length_mean,
        edge_length_variance,
        face_area: MeanStd::of((0..template.face_count()).map(|f| template.face_area(f))),
        regions: regions.stats(&template, &set.labels),
        summary: report::summarise(&run.measured.in_sample, &run.measured.held_out),
        upsampling: run.upsampling.as_ref().map(|u| upsampling::summarise(u, fitted)),
        other_models: run.other_models.clone(),
        surface_v2f: run.surface_v2f,
        spikes_rest: run.spikes.as_ref().map(|(rest, _)| *rest),
        versus_baseline: None,
        poses: records,
        models: run.deformed.models.clone(),
        timings: MethodTimings {
            simplify: run.set.simplify_seconds,
            map: set.report.map_seconds,
            apply_map: set.report.apply_seconds,
            rotations: run.deformed.rotation_seconds,
            model_fit_in_sample: in_sample.fit_seconds,
            synthesis_per_pose: in_sample.synthesis_seconds / in_sample.test_poses.len() as f64,
            model_fit_total: run.deformed.models.iter().map(|m| m.fit_seconds).sum(),
            synthesis_total: run.deformed.models.iter().map(|m| m.synthesis_seconds).sum(),
        },
    }
}

/// The figure poses: the named ones, or four spread evenly over the evaluated poses.
fn figure_poses(poses: &PoseSet, evaluated: &[usize], names: &[String]) -> Result<Vec<usize>> {
    if names.is_empty() {
        let count = evaluated.len().min(4);
        return Ok((0..count).map(|k| evaluated[k * evaluated.len() / count]).collect());
    }
    names
        .iter()
        .map(|n| {
            let pose = poses.pose_index(n).with_context(|| format!("--figure-poses: no pose named '{n}'"))?;
            if pose == poses.template {
                bail!("--figure-poses: '{n}' is the template, which is never held out");
            }
            Ok(pose)
        })
        .collect()
}

/// One PNG to render: its path relative to the eval folder, and how to draw it.
type Figure<'a> = (String, Box<dyn Fn() -> Result<Vec<u8>> + Send + Sync + 'a>);

/// Writes every PNG; returns their paths relative to `dir`. The pictures are drawn in
/// parallel (each is independent, so the bytes do not depend on the thread count) and
/// written in a fixed order.
fn write_figures(
    dir: &Path,
    dataset: &Dataset,
    inputs: &Inputs,
    evaluated: &[usize],
    runs: &[MethodRun],
    args: &EvalArgs,
) -> Result<Vec<String>> {
    let poses = &inputs.poses;
    let shown = figure_poses(poses, evaluated, &args.figure_poses)?;
    let slot = |pose: usize| evaluated.iter().position(|&p| p == pose).expect("figure poses are evaluated");
    let up = desal_driver::pictures::parse_up_axis(dataset.spec.up_axis.as_deref())?;
    let views = Views::of(&poses.template_mesh(), up)?;
    let views = &views;

    // Figs. 4–5: face areas of every simplified template, one range for all.
    let templates: Vec<TriMesh> = runs.iter().map(|r| r.set.mapped.poses.template_mesh()).collect();
    let areas: Vec<Vec<f64>> = templates.iter().map(figures::face_areas_cm2).collect();
    let area_range = figures::shared_range(areas.iter().map(Vec::as_slice), 99.0);

    // Error maps: distance (mm) of each held-out deformed vertex to the simplified
    // ground-truth surface, per figure pose and as the RMS over all poses.
    let to_mm = |squared: &[f64]| squared.iter().map(|d| d.sqrt() * 1e3).collect::<Vec<f64>>();
    let rms_mm: Vec<Vec<f64>> = runs
        .iter()
        .map(|run| {
            let per_pose = &run.measured.held_out_vertex_errors;
            let n = per_pose.len() as f64;
            (0..per_pose[0].len())
                .map(|v| (per_pose.iter().map(|p| p[v]).sum::<f64>() / n).sqrt() * 1e3)
                .collect()
        })
        .collect();
    let shown_mm: Vec<Vec<Vec<f64>>> = runs
        .iter()
        .map(|run| shown.iter().map(|&p| to_mm(&run.measured.held_out_vertex_errors[slot(p)])).collect())
        .collect();
    let error_range =
        figures::shared_range(shown_mm.iter().flatten().chain(&rms_mm).map(Vec::as_slice), 99.0);
    let deformed_mesh = |run: &MethodRun, pose: usize| TriMesh {
        positions: run.deformed.held_out[pose].clone().expect("evaluated poses are held out"),
        faces: run.set.mapped.poses.faces.clone(),
    };

    // Fig. 7: ground truth and a few methods' held-out deformations side by side.
    let featured: Vec<usize> = {
        let preferred: Vec<usize> = runs
            .iter()
            .enumerate()
            .filter(|(_, r)| {
                matches!(r.method, Method::External { .. })
                    || ["qslim-optimal", "paper-optimal", "multipose"].contains(&r.method.name().as_str())
            })
            .map(|(k, _)| k)
            .collect();
        if preferred.is_empty() { (0..runs.len().min(3)).collect() } else { preferred }
    };
    let mut rows = vec![GridRow {
        label: "ground truth".into(),
        cells: shown.iter().map(|&p| (poses.pose_mesh(p), None)).collect(),
    }];
    for &m in &featured {
        let run = &runs[m];
        rows.push(GridRow {
            label: run.method.name(),
            cells: shown
                .iter()
                .enumerate()
                .map(|(k, &p)| (deformed_mesh(run, p), Some(shown_mm[m][k].clone())))
                .collect(),
        });
    }
    let titles: Vec<String> = shown.iter().map(|&p| poses.names[p].clone()).collect();

    // The drawings, in the order the files are listed; they borrow everything above.
    let mut jobs: Vec<Figure> = Vec::new();
    for (run, template) in runs.iter().zip(&templates) {
        let name = run.method.name();
        let title = format!("{name}: face area");
        jobs.push((
            format!("face-area/{}.png", file_stem_for(&name)),
            Box::new(move || figures::face_area_png(views, template, &title, area_range)),
        ));
    }
    let (rms_mm, shown_mm, deformed_mesh) = (&rms_mm, &shown_mm, &deformed_mesh);
    let stems = &desal_io::confine::file_stems_for(&poses.names);
    for (m, run) in runs.iter().enumerate() {
        let name = run.method.name();
        let first = shown[0];
        let title = format!("{name}: RMS error, all poses (on {})", poses.names[first]);
        jobs.push((
            format!("errors/{}.png", file_stem_for(&format!("{name}-rms"))),
            Box::new(move || {
                figures::error_png(views, &deformed_mesh(run, first), &rms_mm[m], &title, error_range)
            }),
        ));
        for (k, &pose) in shown.iter().enumerate() {
            let title = format!("{name}: {}", poses.names[pose]);
            jobs.push((
                format!("errors/{}-{}.png", file_stem_for(&name), stems[pose]),
                Box::new(move || {
                    figures::error_png(views, &deformed_mesh(run, pose), &shown_mm[m][k], &title, error_range)
                }),
            ));
        }
    }
    let (rows, titles) = (&rows, &titles);
    jobs.push((
        "deformation.png".into(),
        Box::new(move || figures::deformation_grid_png(views, rows, titles, error_range)),
    ));

    // Consumed here, so the drawings' borrows end before the data they borrow.
    let rendered: Vec<(String, Vec<u8>)> =
        jobs.into_par_iter().map(|(name, draw)| Ok((name, draw()?))).collect::<Result<_>>()?;
    let mut files = Vec::new();
    for (name, bytes) in rendered {
        let path = dir.join(&name);
        std::fs::create_dir_all(path.parent().expect("inside dir"))?;
        desal_io::write_atomic(&path, &bytes)?;
        files.push(name);
    }
    Ok(files)
}

/// Every evaluated pose of every method as PLY: in-sample and held-out deformations and
/// the simplified ground truth they are measured against.
fn save_deformed(dir: &Path, poses: &PoseSet, evaluated: &[usize], runs: &[MethodRun]) -> Result<()> {
    let mut jobs: Vec<(PathBuf, TriMesh)> = Vec::new();
    // Pose names come from files (a rig's animation names): one rule makes each a file name.
    let stems = desal_io::confine::file_stems_for(&poses.names);
    for run in runs {
        let base = dir.join("deformed").join(file_stem_for(&run.method.name()));
        let faces = &run.set.mapped.poses.faces;
        let mesh = |positions: &[Vec3]| TriMesh { positions: positions.to_vec(), faces: faces.clone() };
        for &pose in evaluated {
            let file = format!("{}.ply", stems[pose]);
            jobs.push((base.join("in-sample").join(&file), mesh(&run.deformed.in_sample[pose])));
            let held_out = run.deformed.held_out[pose].as_ref().expect("evaluated poses are held out");
            jobs.push((base.join("held-out").join(&file), mesh(held_out)));
            jobs.push((base.join("ground-truth").join(&file), run.set.mapped.poses.pose_mesh(pose)));
        }
    }
    for sub in jobs.iter().filter_map(|(p, _)| p.parent()) {
        std::fs::create_dir_all(sub).with_context(|| format!("cannot create {}", sub.display()))?;
    }
    jobs.par_iter().try_for_each(|(path, mesh)| -> Result<()> {
        write_ply(path, mesh, &PlyWriteOptions::default())?;
        Ok(())
    })
}
