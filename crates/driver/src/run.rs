//! `desal run`: every dataset of a pipeline file through ingest → fit → saliency →
//! simplify → map, with the cache, progress, a summary table and `report.json`.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use rayon::prelude::*;

use crate::cache::Cache;
pub use crate::outputs::DatasetReport;
use crate::outputs::{check_output_folder, publish};
use crate::pipeline::{Dataset, Pipeline};
use crate::progress::{Console, Lines};
use crate::stages::DatasetStages;
use crate::stages::runner::{RunnerOptions, Stage, StageRunner};

/// Options of one `desal run`.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Replaces the pipeline file's output root.
    pub out: Option<PathBuf>,
    /// Cache folder; default `<output root>/.cache`.
    pub cache_dir: Option<PathBuf>,
    /// Recompute every stage (entries are overwritten, not trusted).
    pub force: bool,
    /// Recompute this stage and the ones after it.
    pub from: Option<Stage>,
    /// Datasets run in parallel.
    pub jobs: usize,
    /// Run only datasets `k` with `k % count == index` (0-based, file order).
    pub shard: Option<Shard>,
    /// Where progress and messages go.
    pub console: Arc<dyn Console>,
    /// Print why each stage missed the cache.
    pub explain: bool,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            out: None,
            cache_dir: None,
            force: false,
            from: None,
            jobs: 1,
            shard: None,
            console: Arc::new(Lines::default()),
            explain: false,
        }
    }
}

/// `--shard I/N`: the I-th of N deterministic parts of a batch (1-based on the command
/// line, as Slurm's `SLURM_ARRAY_TASK_ID` usually is with `--array=1-N`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (i, n) = s.split_once('/').ok_or("expected I/N, e.g. 2/8")?;
        let index: usize = i.trim().parse().map_err(|_| format!("'{i}' is not a number"))?;
        let count: usize = n.trim().parse().map_err(|_| format!("'{n}' is not a number"))?;
        if count == 0 || index == 0 || index > count {
            return Err(format!("shard {index}/{count}: I must be in 1..=N"));
        }
        Ok(Shard { index: index - 1, count })
    }
}

impl Shard {
    /// The dataset indices (into `0..total`) this shard runs.
    pub fn select(&self, total: usize) -> Vec<usize> {
        (0..total).filter(|k| k % self.count == self.index).collect()
    }
}

/// Runs a pipeline; returns one report per dataset run (in file order).
pub fn run(pipeline: &Pipeline, options: &RunOptions) -> Result<Vec<DatasetReport>> {
    Ok(run_with_stages(pipeline, options)?.into_iter().map(|r| r.report).collect())
}

/// One dataset's run: its report and its stages' results, for callers that go on
/// in-process (`desal eval`).
#[derive(Debug)]
pub struct DatasetRun {
    /// Index of the dataset in the pipeline file.
    pub dataset: usize,
    pub report: DatasetReport,
    pub stages: DatasetStages,
}

/// Runs a pipeline and keeps every dataset's stage results (in file order).
pub fn run_with_stages(pipeline: &Pipeline, options: &RunOptions) -> Result<Vec<DatasetRun>> {
    let cache = Cache::for_output(options.cache_dir.as_deref(), &pipeline.out_root);
    let selected = match options.shard {
        Some(shard) => shard.select(pipeline.datasets.len()),
        None => (0..pipeline.datasets.len()).collect(),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(options.jobs.max(1))
        .build()
        .context("cannot start the worker pool")?;
    let results: Vec<Result<DatasetRun>> = if options.jobs <= 1 {
        selected.iter().map(|&k| run_dataset(pipeline, &pipeline.datasets[k], &cache, options)).collect()
    } else {
        pool.install(|| {
            selected
                .par_iter()
                .map(|&k| run_dataset(pipeline, &pipeline.datasets[k], &cache, options))
                .collect()
        })
    };
    let mut reports = Vec::new();
    let mut failures = Vec::new();
    for (k, result) in selected.iter().zip(results) {
        match result {
            Ok(mut r) => {
                r.dataset = *k;
                reports.push(r)
            }
            Err(e) => failures.push(format!("dataset '{}': {e:#}", pipeline.datasets[*k].spec.name)),
        }
    }
    if !failures.is_empty() {
        bail!("{} of {} dataset(s) failed:\n{}", failures.len(), selected.len(), failures.join("\n"));
    }
    Ok(reports)
}

fn run_dataset(
    pipeline: &Pipeline,
    dataset: &Dataset,
    cache: &Cache,
    options: &RunOptions,
) -> Result<DatasetRun> {
    let start = Instant::now();
    // What an interrupted run left beside or in the output folder goes first (a live
    // run's never).
    if let Some(root) = dataset.out_dir.parent() {
        desal_io::dir::remove_leftovers(root);
    }
    desal_io::dir::remove_leftovers(&dataset.out_dir);
    check_output_folder(&dataset.out_dir)?;
    let progress = options.console.for_dataset(&dataset.spec.name);
    let runner_options = RunnerOptions { force: options.force, from: options.from, explain: options.explain };
    let mut runner = StageRunner {
        cache,
        dataset: &dataset.spec.name,
        options: runner_options,
        console: &*options.console,
        records: Vec::new(),
    };
    let stages = crate::stages::run_stages(&dataset.inputs(), &mut runner, &*progress)?;
    let (input, output) = stages.counts();
    let mut report = DatasetReport {
        dataset: dataset.spec.name.clone(),
        pipeline: pipeline.path.display().to_string(),
        input,
        output,
        stages: runner.records,
        seconds: 0.0,
        out_dir: dataset.out_dir.clone(),
        outputs_key: String::new(),
        files: Vec::new(),
    };
    publish(&mut report, &stages, dataset.spec.up_axis.as_deref(), options.force, start)?;
    Ok(DatasetRun { dataset: 0, report, stages })
}

/// The table printed at the end of a run: one block per dataset, one line per stage.
pub fn summary_table(reports: &[DatasetReport]) -> String {
    use std::fmt::Write as _;
    let mut out = String::new();
    for r in reports {
        let _ = writeln!(
            out,
            "{}: {} poses, {} -> {} vertices, {} -> {} faces, {:.3} s -> {}",
            r.dataset,
            r.input.poses,
            r.input.vertices,
            r.output.vertices,
            r.input.faces,
            r.output.faces,
            r.seconds,
            r.out_dir.display()
        );
        for s in &r.stages {
            let state = if s.cached { "cached" } else { "ran" };
            let _ = writeln!(out, "  {:<10} {:<7} {:>9.4} s  {}", s.name, state, s.seconds, s.note);
        }
    }
    out
}
