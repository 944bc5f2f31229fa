//! `desal run`: every dataset of a pipeline file through ingest → fit → saliency →
//! simplify → map, with the cache, progress, a summary table and `report.json`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use desal_io::artifact::{ArtifactBody, ContentHash};
use rayon::prelude::*;
use serde::Serialize;

use crate::cache::{Cache, StageKey};
use crate::pipeline::{Dataset, Pipeline};
use crate::progress::{Bars, ProgressMode, StepProgress};

/// The stages in run order. `--from` names one of them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, clap::ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Stage {
    Ingest,
    Fit,
    Saliency,
    Simplify,
    Map,
}

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
    pub progress: ProgressMode,
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
            progress: ProgressMode::Auto,
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

/// One stage's line in `report.json`.
#[derive(Debug, Clone, Serialize)]
pub struct StageRecord {
    pub name: String,
    pub cached: bool,
    pub seconds: f64,
    pub cache_key: String,
    /// Why the cache missed (absent on hits).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub miss_reason: Option<String>,
    /// One-line result of the stage, in meshoptimizer's spirit.
    pub note: String,
}

#[derive(Debug, Clone, Default, Serialize)]
pub struct Counts {
    pub vertices: usize,
    pub faces: usize,
    pub poses: usize,
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

/// Runs a pipeline; returns one report per dataset run (in file order).
pub fn run(pipeline: &Pipeline, options: &RunOptions) -> Result<Vec<DatasetReport>> {
    let cache = Cache::new(options.cache_dir.clone().unwrap_or_else(|| pipeline.out_root.join(".cache")));
    let selected = match options.shard {
        Some(shard) => shard.select(pipeline.datasets.len()),
        None => (0..pipeline.datasets.len()).collect(),
    };
    let bars = Bars::new(options.progress);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(options.jobs.max(1))
        .build()
        .context("cannot start the worker pool")?;
    let results: Vec<Result<DatasetReport>> = if options.jobs <= 1 {
        selected
            .iter()
            .map(|&k| run_dataset(pipeline, &pipeline.datasets[k], &cache, options, &bars))
            .collect()
    } else {
        pool.install(|| {
            selected
                .par_iter()
                .map(|&k| run_dataset(pipeline, &pipeline.datasets[k], &cache, options, &bars))
                .collect()
        })
    };
    let mut reports = Vec::new();
    let mut failures = Vec::new();
    for (k, result) in selected.iter().zip(results) {
        match result {
            Ok(r) => reports.push(r),
            Err(e) => failures.push(format!("dataset '{}': {e:#}", pipeline.datasets[*k].spec.name)),
        }
    }
    if !failures.is_empty() {
        bail!("{} of {} dataset(s) failed:\n{}", failures.len(), selected.len(), failures.join("\n"));
    }
    Ok(reports)
}

/// A stage's output: where its artifact is, its content hash and summary, and its body —
/// decoded from the cache entry only when something asks for it, so a warm run that
/// needs nothing recomputed decodes nothing.
#[derive(Debug)]
pub struct Staged<T> {
    body: std::cell::OnceCell<T>,
    pub hash: ContentHash,
    pub summary: serde_json::Value,
    /// The cache entry's artifact file (for copying into the output folder).
    pub artifact_path: PathBuf,
}

impl<T: ArtifactBody> Staged<T> {
    /// The artifact body, decoded on first use.
    pub fn body(&self) -> Result<&T> {
        if let Some(body) = self.body.get() {
            return Ok(body);
        }
        let (_, body, _) = desal_io::artifact::read_artifact::<T>(&self.artifact_path)?;
        Ok(self.body.get_or_init(|| body))
    }
}

/// Runs stages of one dataset against the cache, recording each.
#[derive(Debug)]
pub struct StageRunner<'a> {
    pub cache: &'a Cache,
    pub dataset: &'a str,
    pub options: &'a RunOptions,
    pub bars: &'a Bars,
    pub records: Vec<StageRecord>,
}

impl StageRunner<'_> {
    /// Looks `key` up; on a miss (or when forced) runs `compute` and stores its result.
    pub fn stage<T: ArtifactBody>(
        &mut self,
        stage: Stage,
        key: StageKey,
        hints: &[(String, String)],
        compute: impl FnOnce() -> Result<(T, serde_json::Value, String)>,
    ) -> Result<Staged<T>> {
        let start = Instant::now();
        let forced = self.options.force || self.options.from.is_some_and(|from| stage >= from);
        let key_hash = key.hash();
        let entry = self.cache.entry_dir(&key).join("artifact.dsa");
        if !forced && let Some(hit) = self.cache.lookup::<T>(&key) {
            let note = hit.summary.get("note").and_then(|n| n.as_str()).unwrap_or("").to_owned();
            self.records.push(StageRecord {
                name: key.stage.clone(),
                cached: true,
                seconds: start.elapsed().as_secs_f64(),
                cache_key: key_hash.to_hex(),
                miss_reason: None,
                note,
            });
            self.cache.record(self.dataset, &key)?;
            return Ok(Staged {
                body: std::cell::OnceCell::new(),
                hash: hit.hash,
                summary: hit.summary,
                artifact_path: entry,
            });
        }
        let reason = if forced {
            "forced (--force or --from)".to_owned()
        } else {
            self.cache.explain_miss(self.dataset, &key)
        };
        if self.options.explain {
            self.bars.println(&format!("{}: {} missed the cache: {reason}", self.dataset, key.stage));
        }
        let (body, mut summary, note) = compute()?;
        if let serde_json::Value::Object(map) = &mut summary {
            map.insert("note".into(), serde_json::Value::String(note.clone()));
        }
        if forced {
            let _ = std::fs::remove_dir_all(self.cache.entry_dir(&key));
        }
        let producer = key.producer(hints);
        let hash = self.cache.store(&key, &producer, &body, &summary)?;
        self.cache.record(self.dataset, &key)?;
        self.records.push(StageRecord {
            name: key.stage.clone(),
            cached: false,
            seconds: start.elapsed().as_secs_f64(),
            cache_key: key_hash.to_hex(),
            miss_reason: Some(reason),
            note,
        });
        Ok(Staged { body: std::cell::OnceCell::from(body), hash, summary, artifact_path: entry })
    }
}

fn run_dataset(
    pipeline: &Pipeline,
    dataset: &Dataset,
    cache: &Cache,
    options: &RunOptions,
    bars: &Bars,
) -> Result<DatasetReport> {
    let start = Instant::now();
    check_output_folder(&dataset.out_dir)?;
    let progress: StepProgress = bars.for_dataset(&dataset.spec.name);
    let mut runner = StageRunner { cache, dataset: &dataset.spec.name, options, bars, records: Vec::new() };
    let stages = crate::stages::run_stages(dataset, &mut runner, &progress)?;
    let out_dir = dataset.out_dir.clone();
    let (input, output) = stages.counts();
    let outputs_key = outputs_key(&runner.records, &dataset.spec);
    let mut report = DatasetReport {
        dataset: dataset.spec.name.clone(),
        pipeline: pipeline.path.display().to_string(),
        input,
        output,
        stages: runner.records,
        seconds: 0.0,
        out_dir: out_dir.clone(),
        outputs_key: outputs_key.clone(),
        files: Vec::new(),
    };
    // A warm run whose outputs are already in place only refreshes report.json.
    if !options.force
        && let Some(files) = outputs_in_place(&out_dir, &outputs_key)
    {
        report.files = files;
        report.seconds = start.elapsed().as_secs_f64();
        desal_io::write_json(&out_dir.join("report.json"), &report)?;
        return Ok(report);
    }
    let outputs = stages.outputs(&dataset.spec)?;
    report.files = outputs
        .artifacts
        .iter()
        .map(|(name, _)| name.clone())
        .chain(outputs.files.iter().map(|(name, _)| name.clone()))
        .collect();
    report.seconds = start.elapsed().as_secs_f64();
    write_outputs(&out_dir, outputs, &report)?;
    Ok(report)
}

/// Identifies a dataset's output folder content: every stage's cache key, plus what the
/// derived files depend on beyond them (the picture's up axis, the desal version).
fn outputs_key(records: &[StageRecord], spec: &crate::pipeline::DatasetToml) -> String {
    let keys: Vec<&str> = records.iter().map(|r| r.cache_key.as_str()).collect();
    let text = crate::pipeline::canonical_json(&serde_json::json!({
        "stages": keys,
        "up_axis": spec.up_axis,
        "desal": env!("CARGO_PKG_VERSION"),
    }));
    ContentHash::of(text.as_bytes()).to_hex()
}

/// The output folder's file list when its report.json carries `outputs_key` and every
/// listed file is present; `None` when the outputs must be written.
fn outputs_in_place(out_dir: &Path, outputs_key: &str) -> Option<Vec<String>> {
    let old: serde_json::Value = desal_io::atomic::read_json(&out_dir.join("report.json")).ok()?;
    if old.get("outputs_key")?.as_str()? != outputs_key {
        return None;
    }
    let files: Vec<String> =
        old.get("files")?.as_array()?.iter().map(|f| f.as_str().map(str::to_owned)).collect::<Option<_>>()?;
    files.iter().all(|f| out_dir.join(f).exists()).then_some(files)
}

/// Everything a dataset run leaves in its output folder.
pub struct DatasetOutputs {
    pub input: Counts,
    pub output: Counts,
    /// `(file name in the output folder, cache artifact to link or copy)`.
    pub artifacts: Vec<(String, PathBuf)>,
    /// `(relative path, writer)` for derived files (PLY, PNG, text, JSON).
    pub files: Vec<(String, FileWriter)>,
}

/// Writes one derived output file to the path it is given.
pub type FileWriter = Box<dyn FnOnce(&Path) -> Result<()> + Send>;

impl std::fmt::Debug for DatasetOutputs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let files: Vec<&str> = self.files.iter().map(|(name, _)| name.as_str()).collect();
        f.debug_struct("DatasetOutputs").field("artifacts", &self.artifacts).field("files", &files).finish()
    }
}

/// `desal eval`'s folder inside a dataset's output folder: kept when `desal run` replaces
/// the rest (it depends on the pipeline's inputs, not on the run's stage parameters).
const KEPT_SUBFOLDER: &str = "eval";

/// Refuses to take over a folder that `desal run` did not write: the output folder is
/// replaced whole, so a non-empty folder without a `report.json` (someone's own files, or
/// a typo in `out` or `name`) would be lost.
fn check_output_folder(out_dir: &Path) -> Result<()> {
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

/// Writes the outputs into a temp folder beside `out_dir`, then swaps it into place, so
/// the folder is either the previous run's or this run's, never a mix. `desal eval`'s
/// `eval/` subfolder is carried over into the new folder.
fn write_outputs(out_dir: &Path, outputs: DatasetOutputs, report: &DatasetReport) -> Result<()> {
    // Checked again right before the swap: `run_dataset` checked before the stages ran,
    // and someone may have written into the folder since.
    check_output_folder(out_dir)?;
    let parent = out_dir.parent().context("output folder has no parent")?;
    let name = out_dir.file_name().context("output folder has no name")?.to_string_lossy().into_owned();
    std::fs::create_dir_all(parent).with_context(|| format!("cannot create {}", parent.display()))?;
    let tmp = parent.join(format!(".{name}.tmp-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).with_context(|| format!("cannot create {}", tmp.display()))?;
    let result = (|| -> Result<()> {
        for (file, source) in &outputs.artifacts {
            link_or_copy(source, &tmp.join(file))?;
        }
        for (file, write) in outputs.files {
            let path = tmp.join(&file);
            if let Some(dir) = path.parent() {
                std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
            }
            write(&path).with_context(|| format!("cannot write {file}"))?;
        }
        desal_io::write_json(&tmp.join("report.json"), report)?;
        Ok(())
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_dir_all(&tmp);
        return Err(e);
    }
    let old = parent.join(format!(".{name}.old-{}", std::process::id()));
    if out_dir.exists() {
        std::fs::rename(out_dir, &old).with_context(|| format!("cannot replace {}", out_dir.display()))?;
    }
    std::fs::rename(&tmp, out_dir)
        .with_context(|| format!("cannot move outputs into {}", out_dir.display()))?;
    let kept = old.join(KEPT_SUBFOLDER);
    if kept.is_dir() {
        // On failure the previous folder stays (as `old`) rather than lose `eval/`.
        std::fs::rename(&kept, out_dir.join(KEPT_SUBFOLDER)).with_context(|| {
            format!(
                "cannot carry {} over; the previous outputs are kept in {}",
                KEPT_SUBFOLDER,
                old.display()
            )
        })?;
    }
    let _ = std::fs::remove_dir_all(&old);
    Ok(())
}

/// Cache entries are immutable, so a hard link is a safe, free copy; fall back to copying
/// across file systems.
fn link_or_copy(source: &Path, dest: &Path) -> Result<()> {
    if std::fs::hard_link(source, dest).is_err() {
        std::fs::copy(source, dest)
            .with_context(|| format!("cannot copy {} to {}", source.display(), dest.display()))?;
    }
    Ok(())
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
