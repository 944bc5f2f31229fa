//! The fuzz harness on a short budget: every target for a few hundred iterations in
//! process, the corpus accepted as it is, and the supervisor's detection of each kind of
//! finding proven on canary targets (a harness that cannot see a crash proves nothing).

use std::path::Path;
use std::process::Command;

use desal_fuzz::{Target, corpus, execute, run_in_process};

/// Every seed is a valid input its reader accepts: mutants then start from real files.
#[test]
fn every_seed_is_accepted_by_its_reader() {
    let root = corpus::default_root();
    for target in Target::ALL {
        let seeds = corpus::seeds(target, &root).unwrap();
        assert!(!seeds.is_empty(), "{}", target.name());
        for seed in &seeds {
            assert!(execute(target, 0, &seed.bytes), "{}: seed '{}' is refused", target.name(), seed.name);
        }
    }
}

/// 400 mutants per target, no panic. The counts are fixed by the seed (the run is
/// deterministic); some mutants must still be accepted, or the mutations would only be
/// testing the first check of each reader.
#[test]
fn every_target_survives_400_mutants_in_process() {
    let root = corpus::default_root();
    for target in Target::ALL {
        let seeds = corpus::seeds(target, &root).unwrap();
        let tally = run_in_process(target, &seeds, 7, 0..400);
        assert_eq!(tally.executions, 400);
        assert!(tally.panics.is_empty(), "{}: {:?}", target.name(), tally.panics);
        assert!(tally.accepted > 0, "{}: no mutant was accepted", target.name());
        println!("{}: 400 executions, {} accepted", target.name(), tally.accepted);
    }
}

/// The in-process loop catches a panic and names its iteration.
#[test]
fn in_process_run_reports_a_panic() {
    let seeds = corpus::seeds(Target::CanaryPanic, &corpus::default_root()).unwrap();
    let tally = run_in_process(Target::CanaryPanic, &seeds, 1, 0..5);
    assert_eq!(tally.panics.len(), 1);
    assert_eq!(tally.panics[0].0, 2);
    assert!(tally.panics[0].1.contains("canary panic"));
}

fn fuzz(args: &[&str], out: &Path) -> (i32, String) {
    let output = Command::new(env!("CARGO_BIN_EXE_desal-fuzz"))
        .args(args)
        .arg("--out")
        .arg(out)
        .output()
        .expect("desal-fuzz runs");
    (output.status.code().unwrap_or(-1), String::from_utf8_lossy(&output.stdout).into_owned())
}

/// The binary on every real target, 200 iterations each: exit 0, one line per target.
#[test]
fn binary_runs_every_target_cleanly() {
    let out = tempfile::tempdir().unwrap();
    let (code, stdout) = fuzz(&["--iterations", "200"], out.path());
    assert_eq!(code, 0, "{stdout}");
    for target in Target::ALL {
        assert!(stdout.contains(&format!("  {:<12}      200 executions", target.name())), "{stdout}");
    }
    assert!(stdout.contains("1200 executions, 0 findings"), "{stdout}");
}

/// Each canary crashes on iteration 2 in its own way: a panic, an abort, a hang, an
/// allocation past the memory limit. Each is reported, saved, and fails the run; the
/// run goes on past it (iterations 3 and 4 still execute).
#[test]
fn binary_catches_panic_abort_hang_and_oom_and_saves_the_input() {
    let out = tempfile::tempdir().unwrap();
    for (target, kind) in [
        ("canary-panic", "panic"),
        ("canary-abort", "abort"),
        ("canary-hang", "timeout"),
        ("canary-oom", "abort"),
    ] {
        let (code, stdout) =
            fuzz(&["--targets", target, "--iterations", "5", "--timeout-secs", "2"], out.path());
        assert_eq!(code, 1, "{target}: {stdout}");
        assert!(stdout.contains(&format!("{kind} at iteration 2")), "{target}: {stdout}");
        assert!(stdout.contains("5 executions"), "{target}: {stdout}");
        let saved = out.path().join(format!("{target}-{kind}-seed1-iter2.bin"));
        // The saved bytes are exactly input 2 (regenerated from the seed).
        let t = Target::from_name(target).unwrap();
        let seeds = corpus::seeds(t, &corpus::default_root()).unwrap();
        assert_eq!(std::fs::read(&saved).unwrap(), desal_fuzz::input(t, &seeds, 1, 2), "{target}");
    }
}
