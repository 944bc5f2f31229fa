//! The supervisor: runs each target's iterations in a child process (this binary with
//! `--worker`), so that an abort (or an allocation past the child's memory limit, which
//! aborts it) fails the run instead of ending it, and under a watchdog, so that a hang
//! does too. The child reports `S <i>` before running input `i`, `P <i> <message>` for
//! a panic it caught, and `D <executed> <accepted>` when its segment is done; after a
//! crash or a hang the parent regenerates input `i` (it depends only on the seed, the
//! target and `i`), saves it, and starts a new child at `i + 1`.

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::Mutex;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use crate::{Target, corpus, execute, input, panic_message};

/// The knobs of one fuzz run.
#[derive(Debug, Clone)]
pub struct Options {
    pub seed: u64,
    /// Wall-clock budget per target.
    pub seconds: Option<f64>,
    /// Iteration budget per target.
    pub iterations: Option<u64>,
    /// Address-space limit of each child, in MiB (`ulimit -v`; unix with `/bin/sh` only).
    pub memory_mb: u64,
    /// An input running longer than this is a hang.
    pub timeout: Duration,
    /// Where crashing inputs are saved.
    pub out_dir: PathBuf,
    /// The checkout the corpus is read from.
    pub corpus_root: PathBuf,
}

/// What went wrong on one input.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Finding {
    /// `panic`, `abort` (the child died) or `timeout`.
    pub kind: &'static str,
    pub iteration: u64,
    pub message: String,
    /// The saved input.
    pub saved: PathBuf,
}

/// One target's results.
#[derive(Debug, Clone)]
pub struct TargetReport {
    pub target: Target,
    pub seeds: usize,
    pub executions: u64,
    pub accepted: u64,
    pub seconds: f64,
    pub findings: Vec<Finding>,
}

/// Fuzzes `target` within `options`' budget through child processes of `exe` (this
/// binary). Err only when the run itself cannot start (no corpus, no child).
pub fn fuzz_target(exe: &Path, target: Target, options: &Options) -> Result<TargetReport, String> {
    let seeds = corpus::seeds(target, &options.corpus_root)?;
    let started = Instant::now();
    let mut report = TargetReport {
        target,
        seeds: seeds.len(),
        executions: 0,
        accepted: 0,
        seconds: 0.0,
        findings: Vec::new(),
    };
    let end = options.iterations.unwrap_or(u64::MAX);
    let mut next = 0u64;
    while next < end {
        let left = options.seconds.map(|s| s - started.elapsed().as_secs_f64());
        if left.is_some_and(|l| l <= 0.0) {
            break;
        }
        let mut child = spawn_worker(exe, target, options, next, end, left)?;
        let lines = read_lines(&mut child);
        let mut last_started: Option<u64> = None;
        let outcome = loop {
            match lines.recv_timeout(options.timeout) {
                Ok(line) => {
                    let mut words = line.splitn(3, ' ');
                    match (words.next(), words.next().and_then(|w| w.parse::<u64>().ok())) {
                        (Some("S"), Some(i)) => {
                            last_started = Some(i);
                            report.executions += 1;
                        }
                        (Some("P"), Some(i)) => {
                            let message = words.next().unwrap_or("").to_owned();
                            report.findings.push(save(target, &seeds, options, "panic", i, message)?);
                        }
                        (Some("D"), Some(_)) => {
                            let accepted = words.next().and_then(|w| w.parse().ok()).unwrap_or(0);
                            report.accepted += accepted;
                        }
                        _ => {}
                    }
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => break Outcome::Exited,
                Err(mpsc::RecvTimeoutError::Timeout) => break Outcome::Hung,
            }
        };
        let status = match outcome {
            Outcome::Hung => {
                let _ = child.kill();
                let _ = child.wait();
                let i = last_started.unwrap_or(next);
                let message = format!("no progress for {:.1} s", options.timeout.as_secs_f64());
                report.findings.push(save(target, &seeds, options, "timeout", i, message)?);
                next = i + 1;
                continue;
            }
            Outcome::Exited => child.wait().map_err(|e| format!("waiting for the worker: {e}"))?,
        };
        if status.success() {
            break; // the segment ran to its end or its deadline
        }
        let i = last_started.unwrap_or(next);
        report.findings.push(save(target, &seeds, options, "abort", i, describe_exit(&status))?);
        next = i + 1;
    }
    report.seconds = started.elapsed().as_secs_f64();
    Ok(report)
}

enum Outcome {
    Exited,
    Hung,
}

fn spawn_worker(
    exe: &Path,
    target: Target,
    options: &Options,
    start: u64,
    end: u64,
    seconds_left: Option<f64>,
) -> Result<Child, String> {
    let mut args: Vec<String> = vec![
        "--worker".into(),
        target.name().into(),
        "--seed".into(),
        options.seed.to_string(),
        "--start".into(),
        start.to_string(),
        "--end".into(),
        end.to_string(),
        "--corpus-root".into(),
        options.corpus_root.display().to_string(),
    ];
    if let Some(left) = seconds_left {
        args.extend(["--seconds".into(), format!("{left:.3}")]);
    }
    // The memory limit goes through the shell's ulimit: std cannot set rlimits, and the
    // crate forbids unsafe code. An allocation past it fails, which aborts the child.
    let mut command = if cfg!(unix) && Path::new("/bin/sh").exists() {
        let mut c = Command::new("/bin/sh");
        c.arg("-c")
            .arg("ulimit -v \"$1\" 2>/dev/null; shift; exec \"$@\"")
            .arg("sh")
            .arg((options.memory_mb * 1024).to_string())
            .arg(exe)
            .args(&args);
        c
    } else {
        let mut c = Command::new(exe);
        c.args(&args);
        c
    };
    command
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .map_err(|e| format!("cannot start the worker {}: {e}", exe.display()))
}

/// The child's stdout, line by line, on a channel (so the parent can time out on it).
fn read_lines(child: &mut Child) -> mpsc::Receiver<String> {
    let stdout = child.stdout.take().expect("stdout is piped");
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stdout).lines() {
            let Ok(line) = line else { break };
            if tx.send(line).is_err() {
                break;
            }
        }
    });
    rx
}

fn describe_exit(status: &std::process::ExitStatus) -> String {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(signal) = status.signal() {
            let name = match signal {
                6 => " (SIGABRT: an abort, e.g. a failed allocation)",
                9 => " (SIGKILL)",
                11 => " (SIGSEGV)",
                _ => "",
            };
            return format!("the worker was killed by signal {signal}{name}");
        }
    }
    format!("the worker exited with {status}")
}

/// Regenerates input `iteration` and writes it to the findings folder.
fn save(
    target: Target,
    seeds: &[corpus::Seed],
    options: &Options,
    kind: &'static str,
    iteration: u64,
    message: String,
) -> Result<Finding, String> {
    let bytes = input(target, seeds, options.seed, iteration);
    let extension = Path::new(target.file_name()).extension().and_then(|e| e.to_str()).unwrap_or("bin");
    let saved = options.out_dir.join(format!(
        "{}-{kind}-seed{}-iter{iteration}.{extension}",
        target.name(),
        options.seed
    ));
    std::fs::create_dir_all(&options.out_dir)
        .and_then(|()| std::fs::write(&saved, &bytes))
        .map_err(|e| format!("cannot save the finding to {}: {e}", saved.display()))?;
    Ok(Finding { kind, iteration, message, saved })
}

/// The panic message of the current input, set by the worker's panic hook.
static LAST_PANIC: Mutex<Option<String>> = Mutex::new(None);

/// The child side: runs inputs `start..end` of `target` (or until `seconds` pass),
/// reporting on stdout as the module doc describes.
pub fn worker(
    target: Target,
    seed: u64,
    start: u64,
    end: u64,
    seconds: Option<f64>,
    corpus_root: &Path,
) -> i32 {
    let seeds = match corpus::seeds(target, corpus_root) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("desal-fuzz worker: {e}");
            return 2;
        }
    };
    // Panics are findings reported to the parent, not noise on the terminal.
    std::panic::set_hook(Box::new(|info| {
        let location = info.location().map(|l| format!(" at {}:{}", l.file(), l.line())).unwrap_or_default();
        let text = panic_message(info.payload());
        *LAST_PANIC.lock().unwrap_or_else(|e| e.into_inner()) = Some(format!("{text}{location}"));
    }));
    let deadline = seconds.map(|s| Instant::now() + Duration::from_secs_f64(s.max(0.0)));
    let mut out = std::io::stdout().lock();
    let (mut executed, mut accepted) = (0u64, 0u64);
    for iteration in start..end {
        if deadline.is_some_and(|d| Instant::now() >= d) {
            break;
        }
        let bytes = input(target, &seeds, seed, iteration);
        // Flushed before the input runs: if it kills the process, the parent knows which.
        if writeln!(out, "S {iteration}").and_then(|()| out.flush()).is_err() {
            return 3;
        }
        executed += 1;
        match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| execute(target, iteration, &bytes))) {
            Ok(ok) => accepted += u64::from(ok),
            Err(_) => {
                let message = LAST_PANIC.lock().unwrap_or_else(|e| e.into_inner()).take().unwrap_or_default();
                let _ = writeln!(out, "P {iteration} {}", message.replace(['\n', '\r'], " "));
            }
        }
    }
    let _ = writeln!(out, "D {executed} {accepted}");
    0
}
