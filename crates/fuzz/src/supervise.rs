//! The supervisor: runs each target's iterations in a child process (this binary with
//! `--worker`), so that an abort (or an allocation past the child's memory limit, which
//! aborts it) fails the run instead of ending it, and under a watchdog, so that a hang
//! does too. The child reports `S <i>` before running input `i`, `P <i> <message>` for
//! a panic it caught, `M <i> <message>` when input `i` drove its peak memory past half
//! the limit (then it exits with [`MEMORY_EXIT`]), and `D <executed> <accepted>` when its
//! segment is done; after a crash, a hang or a memory finding the parent regenerates
//! input `i` (it depends only on the seed, the target and `i`), saves it, and starts a
//! new child at `i + 1`.
//!
//! The memory check catches what the limit alone misses: a reader that grows a buffer
//! with `try_reserve` (as `std::fs::read` does) gets an error at the limit and refuses
//! the input cleanly, though without a limit it would have read `/dev/zero` until the
//! machine ran out. The child runs its inputs on a thread with a 2 MiB stack, the size
//! of the threads desal's readers run on (std's default for spawned threads, which
//! rayon's workers in `desal run --jobs` use), so a recursion that would overflow there
//! overflows here too.

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

/// The exit status of a worker that stopped after a memory finding.
pub const MEMORY_EXIT: i32 = 5;

/// The stack of the thread a worker runs its inputs on, in bytes.
pub const WORKER_STACK: usize = 2 << 20;

/// What went wrong on one input.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Finding {
    /// `panic`, `abort` (the child died), `memory` (peak memory past half the limit) or
    /// `timeout`.
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
        let mut memory_finding: Option<u64> = None;
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
                        (Some("M"), Some(i)) => {
                            let message = words.next().unwrap_or("").to_owned();
                            report.findings.push(save(target, &seeds, options, "memory", i, message)?);
                            memory_finding = Some(i);
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
        if let (Some(i), Some(MEMORY_EXIT)) = (memory_finding, status.code()) {
            next = i + 1;
            continue;
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
            .args(&args)
            .arg("--memory-mb")
            .arg(options.memory_mb.to_string());
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

/// What a worker runs.
#[derive(Debug, Clone)]
pub struct WorkerOptions {
    pub target: Target,
    pub seed: u64,
    /// Inputs `start..end`.
    pub start: u64,
    pub end: u64,
    /// Or until this many seconds pass.
    pub seconds: Option<f64>,
    /// The child's memory limit in MiB: an input that drives the peak past half of it
    /// is a memory finding.
    pub memory_mb: u64,
    pub corpus_root: PathBuf,
}

/// The child side: runs the inputs of `options` on a thread with a [`WORKER_STACK`]
/// stack, reporting on stdout as the module doc describes; returns the exit status.
pub fn worker(options: WorkerOptions) -> i32 {
    std::thread::Builder::new()
        .name("desal-fuzz worker".into())
        .stack_size(WORKER_STACK)
        .spawn(move || run_worker(&options))
        .map_or(2, |thread| thread.join().unwrap_or(3))
}

fn run_worker(options: &WorkerOptions) -> i32 {
    let WorkerOptions { target, seed, start, end, seconds, memory_mb, ref corpus_root } = *options;
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
        if let Some(peak) = peak_memory_mib()
            && peak > memory_mb / 2
        {
            let _ =
                writeln!(out, "M {iteration} peak memory {peak} MiB, over half the {memory_mb} MiB limit");
            let _ = writeln!(out, "D {executed} {accepted}");
            let _ = out.flush();
            return MEMORY_EXIT;
        }
    }
    let _ = writeln!(out, "D {executed} {accepted}");
    0
}

/// The peak resident memory of this process in MiB (`VmHWM`; Linux only, else `None`).
fn peak_memory_mib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024)
}
