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
/// testing the first check of each reader. Only the targets that are safe without the
/// supervisor's memory limit run here: a glTF mutant may name `/dev/zero` as a buffer or
/// declare a sparse count of 2e9, which in this process (no limit) would take the whole
/// machine's memory; the binary test below runs them under the limit.
#[test]
fn every_target_survives_400_mutants_in_process() {
    let root = corpus::default_root();
    for target in Target::ALL.into_iter().filter(|t| !t.needs_memory_limit()) {
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
    let total = 200 * Target::ALL.len();
    assert!(stdout.contains(&format!("{total} executions, 0 findings")), "{stdout}");
}

/// Each canary crashes on iteration 2 in its own way: a panic, an abort, a hang, an
/// allocation past the memory limit, a peak of memory under it. Each is reported, saved,
/// and fails the run; the run goes on past it (iterations 3 and 4 still execute).
#[test]
fn binary_catches_panic_abort_hang_and_oom_and_saves_the_input() {
    let out = tempfile::tempdir().unwrap();
    // The hang canary's watchdog is short; the others get a long one, so that filling
    // 1.1 GiB on a loaded machine is not mistaken for a hang.
    for (target, kind, timeout) in [
        ("canary-panic", "panic", "30"),
        ("canary-abort", "abort", "30"),
        ("canary-hang", "timeout", "2"),
        ("canary-oom", "abort", "30"),
        ("canary-memory", "memory", "30"),
    ] {
        let (code, stdout) =
            fuzz(&["--targets", target, "--iterations", "5", "--timeout-secs", timeout], out.path());
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

/// The glTF and npz mutations produce, within 300 inputs, the defects planted in the
/// structural canaries (issue 39 D1's short `byteStride` in a `.glb`; an npy shape that
/// does not match its data, behind valid CRCs), and the harness saves each input exactly.
/// This is the permanent proof that the `gltf-glb` and `npz` targets would catch such a
/// reader, whatever the real readers now do with these inputs.
#[test]
fn structural_canaries_are_found_and_saved() {
    let out = tempfile::tempdir().unwrap();
    for (target, expected) in
        [("canary-gltf-stride", "canary: accessor"), ("canary-npz-shape", "canary: npy entry")]
    {
        let (code, stdout) = fuzz(&["--targets", target, "--iterations", "300"], out.path());
        assert_eq!(code, 1, "{target}: {stdout}");
        assert!(stdout.contains(expected), "{target}: {stdout}");
        let t = Target::from_name(target).unwrap();
        let seeds = corpus::seeds(t, &corpus::default_root()).unwrap();
        let extension = Path::new(t.file_name()).extension().unwrap().to_str().unwrap();
        let first = stdout
            .lines()
            .find_map(|l| l.trim().strip_prefix("panic at iteration "))
            .and_then(|rest| rest.split(':').next())
            .and_then(|i| i.parse::<u64>().ok())
            .unwrap_or_else(|| panic!("{target}: no panic line in {stdout}"));
        let saved = out.path().join(format!("{target}-panic-seed1-iter{first}.{extension}"));
        assert_eq!(std::fs::read(&saved).unwrap(), desal_fuzz::input(t, &seeds, 1, first), "{target}");
    }
}
