//! `desal-fuzz`: mutation-fuzzes desal's readers for a bounded time or iteration count
//! and exits non-zero on any panic, abort or hang, saving each crashing input.
//!
//! ```text
//! desal-fuzz [--targets all|ply,obj,off,labels-text,labels-json,artifact,gltf-json,gltf-glb,npz]
//!            [--seconds 60] [--iterations N] [--seed 1] [--out target/fuzz-findings]
//!            [--memory-mb 2048] [--timeout-secs 10] [--corpus-root <checkout>]
//! ```
//! `--seconds` and `--iterations` are per target; a target stops at whichever comes
//! first (default: 60 seconds). Exit status: 0 clean, 1 findings, 2 usage or corpus error.

use std::path::PathBuf;
use std::time::Duration;

use desal_fuzz::Target;
use desal_fuzz::supervise::{self, Options};

fn main() {
    std::process::exit(run(std::env::args().skip(1).collect()));
}

fn run(args: Vec<String>) -> i32 {
    let mut targets: Vec<Target> = Target::ALL.to_vec();
    let mut options = Options {
        seed: 1,
        seconds: None,
        iterations: None,
        memory_mb: 2048,
        timeout: Duration::from_secs(10),
        out_dir: PathBuf::from("target/fuzz-findings"),
        corpus_root: desal_fuzz::corpus::default_root(),
    };
    let mut worker: Option<Target> = None;
    let (mut start, mut end) = (0u64, u64::MAX);
    let mut it = args.into_iter();
    while let Some(flag) = it.next() {
        let mut value = || it.next().ok_or_else(|| format!("{flag} needs a value"));
        let parsed: Result<(), String> = (|| {
            match flag.as_str() {
                "--targets" => targets = parse_targets(&value()?)?,
                "--seconds" => options.seconds = Some(number(&flag, &value()?)?),
                "--iterations" => options.iterations = Some(number(&flag, &value()?)?),
                "--seed" => options.seed = number(&flag, &value()?)?,
                "--out" => options.out_dir = PathBuf::from(value()?),
                "--memory-mb" => options.memory_mb = number(&flag, &value()?)?,
                "--timeout-secs" => options.timeout = Duration::from_secs_f64(number(&flag, &value()?)?),
                "--corpus-root" => options.corpus_root = PathBuf::from(value()?),
                "--worker" => {
                    let name = value()?;
                    worker =
                        Some(Target::from_name(&name).ok_or_else(|| format!("unknown target '{name}'"))?);
                }
                "--start" => start = number(&flag, &value()?)?,
                "--end" => end = number(&flag, &value()?)?,
                "--help" | "-h" => return Err(String::new()),
                other => return Err(format!("unknown argument '{other}'")),
            }
            Ok(())
        })();
        if let Err(e) = parsed {
            if !e.is_empty() {
                eprintln!("desal-fuzz: {e}");
            }
            eprintln!(
                "usage: desal-fuzz [--targets all|{}] [--seconds S] [--iterations N] [--seed N] [--out DIR] \
                 [--memory-mb M] [--timeout-secs S] [--corpus-root DIR]",
                Target::ALL.map(Target::name).join(",")
            );
            return 2;
        }
    }
    if let Some(target) = worker {
        return supervise::worker(supervise::WorkerOptions {
            target,
            seed: options.seed,
            start,
            end,
            seconds: options.seconds,
            memory_mb: options.memory_mb,
            corpus_root: options.corpus_root,
        });
    }
    if options.seconds.is_none() && options.iterations.is_none() {
        options.seconds = Some(60.0);
    }
    let exe = match std::env::current_exe() {
        Ok(exe) => exe,
        Err(e) => {
            eprintln!("desal-fuzz: cannot find its own executable: {e}");
            return 2;
        }
    };
    println!(
        "desal-fuzz: seed {}, per target {}, memory limit {} MiB, watchdog {:.1} s",
        options.seed,
        budget(&options),
        options.memory_mb,
        options.timeout.as_secs_f64()
    );
    let (mut executions, mut findings) = (0u64, 0usize);
    for target in targets {
        let report = match supervise::fuzz_target(&exe, target, &options) {
            Ok(r) => r,
            Err(e) => {
                eprintln!("desal-fuzz: {}: {e}", target.name());
                return 2;
            }
        };
        println!(
            "  {:<12} {:>8} executions in {:>5.1} s ({:>6.0}/s), {} accepted, {} seeds, {} findings",
            target.name(),
            report.executions,
            report.seconds,
            report.executions as f64 / report.seconds.max(1e-9),
            report.accepted,
            report.seeds,
            report.findings.len()
        );
        for f in &report.findings {
            println!("    {} at iteration {}: {} -> {}", f.kind, f.iteration, f.message, f.saved.display());
        }
        executions += report.executions;
        findings += report.findings.len();
    }
    println!("desal-fuzz: {executions} executions, {findings} findings");
    i32::from(findings > 0)
}

fn budget(options: &Options) -> String {
    match (options.seconds, options.iterations) {
        (Some(s), Some(n)) => format!("{s} s or {n} iterations"),
        (Some(s), None) => format!("{s} s"),
        (None, Some(n)) => format!("{n} iterations"),
        (None, None) => "unbounded".into(),
    }
}

fn parse_targets(list: &str) -> Result<Vec<Target>, String> {
    if list == "all" {
        return Ok(Target::ALL.to_vec());
    }
    list.split(',')
        .map(|name| Target::from_name(name).ok_or_else(|| format!("unknown target '{name}'")))
        .collect()
}

fn number<T: std::str::FromStr>(flag: &str, text: &str) -> Result<T, String> {
    text.parse().map_err(|_| format!("{flag}: '{text}' is not a number"))
}
