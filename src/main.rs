//! `desal`: the driver. `run` chains every stage over a pipeline file with the cache;
//! `eval` runs the paper's experiment; `inspect` describes an artifact. Thin: arguments → options → one library call.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Result;
use clap::{Parser, Subcommand};
use desal_driver::run::{RunOptions, Shard};
use desal_driver::stages::runner::Stage;

mod bars;
mod inspect;

#[derive(Debug, Parser)]
#[command(
    name = "desal",
    version,
    about = "Deformation-saliency simplification of registered body pose sets"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run the whole pipeline for every dataset of a pipeline file.
    Run {
        /// The pipeline file (TOML; see pipelines/README.md).
        pipeline: PathBuf,
        /// Output root (each dataset writes to OUT/<name>); overrides the file's `out`.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Cache folder (default: <output root>/.cache). Share it between shards.
        #[arg(long)]
        cache_dir: Option<PathBuf>,
        /// Recompute every stage.
        #[arg(long)]
        force: bool,
        /// Recompute this stage and the ones after it.
        #[arg(long, value_enum)]
        from: Option<Stage>,
        /// Datasets run in parallel.
        #[arg(long, default_value_t = 1)]
        jobs: usize,
        /// Run the I-th of N deterministic parts of the batch (1-based), e.g. 2/8.
        #[arg(long)]
        shard: Option<Shard>,
        /// No progress output.
        #[arg(long)]
        quiet: bool,
        /// Say why each stage missed the cache.
        #[arg(long)]
        explain: bool,
    },
    /// Part labels discovered from a pose-set artifact (what `labels = "auto"` runs).
    Parts(desal_driver::commands::PartsArgs),
    /// Stage 1 alone: per-part rigid fit on artifacts.
    Fit(desal_driver::commands::FitArgs),
    /// Stage 2 alone: deformation saliency from a fit.
    Saliency(desal_driver::commands::SaliencyArgs),
    /// Stage 3 alone: simplify a mesh file, optionally weighted by saliency.
    Simplify(desal_driver::commands::SimplifyArgs),
    /// Stage 4 alone: map a simplified template (desal's or another tool's) to original
    /// vertices and apply it to every pose.
    Map(desal_driver::commands::MapArgs),
    /// Coarse levels for mesh networks (D, U, A per level) as `hierarchy.npz`.
    Hierarchy(desal_driver::commands::HierarchyArgs),
    /// The paper's experiment: simplify with each method, fit the SCAPE deformation model
    /// on the simplified poses, deform to every pose and measure v2f/v2v (eval.md).
    Eval(desal_experiment::EvalArgs),
    /// The cache: `desal cache gc PIPELINE.toml` keeps the entries the pipeline's
    /// datasets use (running it, from the cache, to know their keys) and removes the rest.
    Cache {
        #[command(subcommand)]
        action: CacheAction,
    },
    /// Describe artifacts: kind, version, producer, inputs, summary figures.
    Inspect {
        #[arg(required = true)]
        files: Vec<PathBuf>,
    },
}

#[derive(Debug, Subcommand)]
enum CacheAction {
    /// Remove every entry the pipeline's datasets do not use.
    Gc {
        /// The pipeline file whose entries are kept (all its datasets, every shard).
        pipeline: PathBuf,
        /// Replaces the pipeline file's output root.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Cache folder (default: <output root>/.cache).
        #[arg(long)]
        cache_dir: Option<PathBuf>,
    },
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => desal_driver::report_error(&e),
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Run { pipeline, out, cache_dir, force, from, jobs, shard, quiet, explain } => {
            let options = RunOptions {
                out: out.clone(),
                cache_dir,
                force,
                from,
                jobs,
                shard,
                console: bars::console(quiet),
                explain,
            };
            let pipeline = desal_driver::pipeline::load(&pipeline, out.as_deref())?;
            let reports = desal_driver::run::run(&pipeline, &options)?;
            desal_driver::print_out(&desal_driver::run::summary_table(&reports))
        }
        Command::Parts(args) => desal_driver::commands::parts(&args),
        Command::Fit(args) => desal_driver::commands::fit(&args),
        Command::Saliency(args) => desal_driver::commands::saliency(&args),
        Command::Simplify(args) => desal_driver::commands::simplify(&args),
        Command::Map(args) => desal_driver::commands::map(&args),
        Command::Hierarchy(args) => desal_driver::commands::hierarchy(&args),
        Command::Eval(args) => {
            let console = bars::console(args.quiet);
            desal_experiment::eval(&args, console)
        }
        Command::Cache { action: CacheAction::Gc { pipeline, out, cache_dir } } => {
            let loaded = desal_driver::pipeline::load(&pipeline, out.as_deref())?;
            let cache = desal_driver::cache::Cache::for_output(cache_dir.as_deref(), &loaded.out_root);
            // Before the run stores anything there: a folder of user files is refused.
            cache.check_is_cache()?;
            let options = RunOptions {
                out,
                cache_dir: cache_dir.clone(),
                console: bars::console(true),
                ..RunOptions::default()
            };
            let runs = desal_driver::run::run_with_stages(&loaded, &options)?;
            let keep =
                runs.iter().flat_map(|r| r.report.stages.iter().map(|s| s.cache_key.clone())).collect();
            // `desal eval`'s floors of these pose sets and labels are kept too.
            let inputs = runs
                .iter()
                .flat_map(|r| [r.stages.poses.hash(), r.stages.labels.hash()])
                .collect::<anyhow::Result<_>>()?;
            let (kept, removed, freed) = cache.gc(&keep, desal_experiment::floor::STAGE, &inputs)?;
            desal_driver::print_out(&format!(
                "{}: kept {kept} entries, removed {removed} ({:.1} MB)\n",
                cache.root().display(),
                freed as f64 / 1e6
            ))
        }
        Command::Inspect { files } => {
            // Every file is described or its error printed; the exit code says whether
            // any failed.
            let mut failed = 0;
            for file in &files {
                match inspect::describe(file) {
                    Ok(text) => desal_driver::print_out(&text)?,
                    Err(e) => {
                        desal_driver::report_error(&e);
                        failed += 1;
                    }
                }
            }
            anyhow::ensure!(failed == 0, "{failed} of {} files could not be inspected", files.len());
            Ok(())
        }
    }
}
