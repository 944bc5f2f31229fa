//! Regression tests for issue 12's cache, runner and output-folder rows, each named after
//! its row (the reader rows are in `crates/io/tests/reliability.rs`; kills at every
//! system call and concurrent shards are swept by `tests/faults/*.py` in `.ci/run`).

use std::path::{Path, PathBuf};

use crate::support::*;

fn key_of(report: &serde_json::Value, stage: &str) -> String {
    report["stages"].as_array().unwrap().iter().find(|s| s["name"] == stage).unwrap()["cache_key"]
        .as_str()
        .unwrap()
        .to_owned()
}

fn entry(dir: &Path, stage: &str, report: &serde_json::Value) -> PathBuf {
    dir.join("out/.cache").join(stage).join(key_of(report, stage))
}

fn inspect_ok(path: &Path) -> bool {
    desal(&["inspect", path.to_str().unwrap()]).status.success()
}

/// D1: a `--force` run killed while deleting an entry leaves it renamed aside (a
/// hidden `.KEY.old-PID-N` folder), never a half-empty entry under its key; the next
/// runs succeed and the leftover goes.
#[test]
fn d1_a_killed_force_deletion_does_not_poison_the_cache() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let report = run_ok(&pipeline, &[]);
    let fit = entry(dir.path(), "fit", &report);
    // What a kill between the rename and the delete leaves, from a process that is gone.
    let aside = fit.with_file_name(format!(".{}.old-{}-0", key_of(&report, "fit"), u32::MAX - 7));
    std::fs::rename(&fit, &aside).unwrap();
    std::fs::remove_file(aside.join("artifact.dsa")).unwrap();
    let text = std::fs::read_to_string(&pipeline).unwrap();
    std::fs::write(&pipeline, format!("{text}[dataset.simplify]\nratio = 0.5\n")).unwrap();
    let report = run_ok(&pipeline, &[]);
    assert!(ran(&report).contains(&"fit".to_owned()), "{report}");
    assert!(!aside.exists(), "the leftover is removed by the next store in its folder");
    run_ok(&pipeline, &[]);
}

/// D2: outputs are copies, so editing one never reaches the cache; and an entry whose
/// artifact is another key's is refused and recomputed, not served.
#[test]
fn d2_output_edits_never_reach_the_cache_and_foreign_entries_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let report = run_ok(&pipeline, &[]);
    let cached_fit = entry(dir.path(), "fit", &report).join("artifact.dsa");
    let before = std::fs::read(&cached_fit).unwrap();
    std::fs::write(dir.path().join("out/tube/fit.dsa"), b"edited by hand").unwrap();
    assert_eq!(std::fs::read(&cached_fit).unwrap(), before, "the cache entry is untouched");
    // Another pose set's fit filed under this fit's key (valid checksum, right kind, but
    // its producer names other inputs).
    let other = dir.path().join("other");
    let other_report = run_ok(&write_tube_dataset(&other, "template = \"p2\"\n"), &[]);
    std::fs::copy(entry(&other, "fit", &other_report).join("artifact.dsa"), &cached_fit).unwrap();
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("cache entry rejected"), "{}", stderr(&out));
    assert_eq!(std::fs::read(&cached_fit).unwrap(), before, "the entry is recomputed");
    assert_eq!(
        std::fs::read(dir.path().join("out/tube/fit.dsa")).unwrap(),
        before,
        "and the output rewritten"
    );
}

/// D3: a corrupt entry is recomputed in the cache and in the output folder.
#[test]
fn d3_a_corrupt_entry_is_replaced_in_the_output_too() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let report = run_ok(&pipeline, &[]);
    let cached = entry(dir.path(), "fit", &report).join("artifact.dsa");
    let mut bytes = std::fs::read(&cached).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 1;
    std::fs::write(&cached, &bytes).unwrap();
    run_ok(&pipeline, &[]);
    run_ok(&pipeline, &[]);
    assert!(inspect_ok(&dir.path().join("out/tube/fit.dsa")));
    assert!(inspect_ok(&cached));
}

/// D10: a garbage `summary.json` makes the entry corrupt (recomputed), never a report
/// of 0 poses.
#[test]
fn d10_a_garbage_summary_is_a_corrupt_entry() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let report = run_ok(&pipeline, &[]);
    std::fs::write(entry(dir.path(), "ingest", &report).join("summary.json"), b"{ garbage").unwrap();
    std::fs::remove_dir_all(dir.path().join("out/tube")).unwrap();
    let report = run_ok(&pipeline, &[]);
    assert_eq!(report["input"]["poses"], 4, "{report}");
    assert!(ran(&report).contains(&"ingest".to_owned()));
}

/// D11: the same data gives the same JSON bytes cold and from the cache (floats keep
/// every digit when read back).
#[test]
fn d11_cold_and_cached_json_are_byte_identical() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    run_ok(&pipeline, &[]);
    let cold = std::fs::read(dir.path().join("out/tube/poses.json")).unwrap();
    std::fs::remove_dir_all(dir.path().join("out/tube")).unwrap();
    let report = run_ok(&pipeline, &[]);
    assert!(ran(&report).is_empty());
    assert_eq!(std::fs::read(dir.path().join("out/tube/poses.json")).unwrap(), cold);
}

/// D12: a percentile outside (0, 100] is refused, in pipeline files and on the CLI.
#[test]
fn d12_a_percentile_above_100_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "[dataset.saliency]\npercentile = 150.0\n");
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("percentile"), "{}", stderr(&out));
    assert!(!dir.path().join("out").exists());
}

/// D13: a failing single-stage command leaves no partial output.
#[test]
fn d13_a_failing_single_stage_command_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    run_ok(&pipeline, &[]);
    let p = |name: &str| dir.path().join("out/tube").join(name).to_str().unwrap().to_owned();
    let (output, png) = (dir.path().join("s.dsa"), dir.path().join("s.png"));
    let folder = dir.path().join("a-folder");
    std::fs::create_dir_all(&folder).unwrap();
    let out = desal(&[
        "saliency",
        "--poses",
        &p("poses.dsa"),
        "--fit",
        &p("fit.dsa"),
        "-o",
        output.to_str().unwrap(),
        "--png",
        png.to_str().unwrap(),
        "--ply",
        folder.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(!output.exists() && !png.exists(), "nothing is written when one output fails");
    // desal map --out-dir into a folder desal did not write: refused before anything.
    std::fs::write(folder.join("mine.txt"), "mine").unwrap();
    let map = dir.path().join("m.dsa");
    let out = desal(&[
        "map",
        "--poses",
        &p("poses.dsa"),
        "--labels",
        &p("labels.dsa"),
        "--simplified",
        &p("simplified.dsa"),
        "-o",
        map.to_str().unwrap(),
        "--out-dir",
        folder.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(!map.exists());
    assert_eq!(std::fs::read_dir(&folder).unwrap().count(), 1, "the folder is as it was");
}

/// D14: `desal saliency` refuses a fit made with another template of the same poses.
#[test]
fn d14_saliency_refuses_a_fit_of_another_template() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    run_ok(&write_tube_dataset(&a, ""), &[]);
    run_ok(&write_tube_dataset(&b, "template = \"p2\"\n"), &[]);
    let p = |d: &Path, name: &str| d.join("out/tube").join(name).to_str().unwrap().to_owned();
    let output = dir.path().join("s.dsa");
    let out = desal(&[
        "saliency",
        "--poses",
        &p(&a, "poses.dsa"),
        "--fit",
        &p(&b, "fit.dsa"),
        "-o",
        output.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("was not made from"), "{}", stderr(&out));
    assert!(!output.exists());
}

/// D17: `desal inspect` describes every file it is given and fails if any is bad.
#[test]
fn d17_inspect_reports_every_file() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    run_ok(&pipeline, &[]);
    let good = dir.path().join("out/tube/fit.dsa");
    let missing = dir.path().join("missing.dsa");
    let out = desal(&["inspect", good.to_str().unwrap(), missing.to_str().unwrap(), good.to_str().unwrap()]);
    assert!(!out.status.success());
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.matches("rigid fit").count() >= 2, "both good files are described: {stdout}");
    assert!(stderr(&out).contains("missing.dsa"), "{}", stderr(&out));
}

/// `desal cache gc` keeps what the pipeline uses and removes the rest.
#[test]
fn cache_gc_keeps_the_pipelines_entries_only() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let first = run_ok(&pipeline, &[]);
    let text = std::fs::read_to_string(&pipeline).unwrap();
    std::fs::write(&pipeline, format!("{text}[dataset.simplify]\nratio = 0.5\n")).unwrap();
    let second = run_ok(&pipeline, &[]);
    let old_simplify = entry(dir.path(), "simplify", &first);
    assert!(old_simplify.exists());
    let out = desal(&["cache", "gc", pipeline.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        String::from_utf8_lossy(&out.stdout).contains("removed 2"),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    assert!(!old_simplify.exists() && !entry(dir.path(), "map", &first).exists());
    for stage in ["ingest", "labels", "fit", "saliency", "simplify", "map"] {
        assert!(entry(dir.path(), stage, &second).exists(), "{stage}");
    }
    assert!(ran(&run_ok(&pipeline, &[])).is_empty());
}
