//! The cache: hits on identical runs, exactly the right stages re-run on a change,
//! corrupt entries recomputed, killed runs leave nothing behind, shards partition.

use std::path::Path;
use std::process::Command;

use crate::support::*;

fn stages(report: &serde_json::Value) -> Vec<(String, bool)> {
    report["stages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| (s["name"].as_str().unwrap().to_owned(), s["cached"].as_bool().unwrap()))
        .collect()
}

#[test]
fn second_identical_run_is_all_hits() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let first = run_ok(&pipeline, &[]);
    assert!(stages(&first).iter().all(|(_, cached)| !cached), "{first}");
    let second = run_ok(&pipeline, &[]);
    assert!(ran(&second).is_empty(), "{second}");
    // The same cache keys, stage for stage.
    for (a, b) in first["stages"].as_array().unwrap().iter().zip(second["stages"].as_array().unwrap()) {
        assert_eq!(a["cache_key"], b["cache_key"]);
    }
}

#[test]
fn changed_saliency_parameter_reruns_saliency_and_later_only() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    run_ok(&pipeline, &[]);
    let text = std::fs::read_to_string(&pipeline).unwrap();
    std::fs::write(&pipeline, format!("{text}[dataset.saliency]\nsquared = true\n")).unwrap();
    let report = run_ok(&pipeline, &[]);
    let ran = ran(&report);
    assert_eq!(ran, ["saliency", "simplify", "map"], "{report}");
    let reason =
        report["stages"].as_array().unwrap().iter().find(|s| s["name"] == "saliency").unwrap()["miss_reason"]
            .as_str()
            .unwrap()
            .to_owned();
    assert!(reason.contains("squared false -> true"), "{reason}");
}

/// The knob added as the two-file demonstration (issue 11): `boundary_weight` in a
/// pipeline file re-runs simplify and map only, and `--explain` names it.
#[test]
fn changed_boundary_weight_reruns_simplify_and_map_only() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    run_ok(&pipeline, &[]);
    let text = std::fs::read_to_string(&pipeline).unwrap();
    let with_weight = if text.contains("[dataset.simplify]") {
        text.replace("[dataset.simplify]\n", "[dataset.simplify]\nboundary_weight = 2.5\n")
    } else {
        format!("{text}[dataset.simplify]\nboundary_weight = 2.5\n")
    };
    std::fs::write(&pipeline, with_weight).unwrap();
    let report = run_ok(&pipeline, &[]);
    assert_eq!(ran(&report), ["simplify", "map"], "{report}");
    let reason =
        report["stages"].as_array().unwrap().iter().find(|s| s["name"] == "simplify").unwrap()["miss_reason"]
            .as_str()
            .unwrap()
            .to_owned();
    assert!(reason.contains("boundary_weight (unset) -> 2.5"), "{reason}");
}

#[test]
fn changed_labels_file_reruns_from_fit_not_ingest() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    run_ok(&pipeline, &[]);
    // Move one vertex across the part border.
    let path = dir.path().join("labels.txt");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines: Vec<&str> = text.lines().collect();
    let k = lines.iter().position(|l| *l == "1").unwrap();
    lines[k] = "0";
    std::fs::write(&path, lines.join("\n")).unwrap();
    let report = run_ok(&pipeline, &[]);
    let ran = ran(&report);
    assert!(!ran.contains(&"ingest".to_owned()), "{report}");
    assert!(ran.contains(&"labels".to_owned()) && ran.contains(&"fit".to_owned()), "{report}");
}

#[test]
fn moving_the_data_keeps_the_cache_valid() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a");
    let pipeline = write_tube_dataset(&a, "");
    let cache = dir.path().join("cache");
    run_ok(&pipeline, &["--cache-dir", cache.to_str().unwrap()]);
    let b = dir.path().join("b");
    std::fs::rename(&a, &b).unwrap();
    let report = run_ok(&b.join("pipeline.toml"), &["--cache-dir", cache.to_str().unwrap()]);
    assert!(ran(&report).is_empty(), "paths must not enter cache keys: {report}");
}

fn entry(cache: &Path, stage: &str, report: &serde_json::Value) -> std::path::PathBuf {
    let key = report["stages"].as_array().unwrap().iter().find(|s| s["name"] == stage).unwrap()["cache_key"]
        .as_str()
        .unwrap()
        .to_owned();
    cache.join(stage).join(key)
}

#[test]
fn flipped_byte_in_a_cache_entry_is_detected_and_recomputed() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let first = run_ok(&pipeline, &[]);
    let artifact = entry(&dir.path().join("out/.cache"), "fit", &first).join("artifact.dsa");
    let original = std::fs::read(&artifact).unwrap();
    let mut bytes = original.clone();
    let last = bytes.len() - 1;
    bytes[last] ^= 0x01;
    std::fs::write(&artifact, bytes).unwrap();
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("checksum"), "{}", stderr(&out));
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("out/tube/report.json")).unwrap()).unwrap();
    assert_eq!(ran(&report), vec!["fit".to_owned()], "{report}");
    // The recomputed entry is byte-identical to the original (deterministic stages).
    assert!(std::fs::read(&artifact).unwrap() == original, "the recomputed fit entry differs");
}

#[test]
fn run_killed_while_storing_leaves_no_entry_and_the_next_run_succeeds() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let out = Command::new(env!("CARGO_BIN_EXE_desal"))
        .args(["run", pipeline.to_str().unwrap(), "--quiet"])
        .env("DESAL_FAULT_ABORT_IN_STORE", "fit")
        .output()
        .unwrap();
    assert!(!out.status.success(), "the injected abort must kill the run");
    let fit_dir = dir.path().join("out/.cache/fit");
    let entries: Vec<String> = std::fs::read_dir(&fit_dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        // A hidden `.KEY.tmp-PID-N` folder is the killed store's work in progress, which
        // no lookup reads (and the next store in this folder removes).
        .filter(|n| !n.starts_with('.'))
        .collect();
    assert!(entries.is_empty(), "a killed store left an entry: {entries:?}");
    assert!(!dir.path().join("out/tube").exists(), "no partial output folder");
    let report = run_ok(&pipeline, &[]);
    assert!(ran(&report).contains(&"fit".to_owned()));
    assert!(!ran(&report).contains(&"ingest".to_owned()), "ingest's finished entry is reused");
}

#[test]
fn shards_partition_a_batch_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    // Five datasets over the same data.
    let mut text = std::fs::read_to_string(&pipeline).unwrap();
    for k in 1..5 {
        text.push_str(&format!(
            "\n[[dataset]]\nname = \"tube{k}\"\nposes = \"poses/*.ply\"\nlabels = \"labels.txt\"\n"
        ));
    }
    std::fs::write(&pipeline, text).unwrap();
    let mut seen = Vec::new();
    for shard in ["1/3", "2/3", "3/3"] {
        let out = desal(&[
            "run",
            pipeline.to_str().unwrap(),
            "--quiet",
            "--shard",
            shard,
            "--out",
            dir.path().join(shard.replace('/', "of")).to_str().unwrap(),
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        let names: Vec<String> = std::fs::read_dir(dir.path().join(shard.replace('/', "of")))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| !n.starts_with('.'))
            .collect();
        seen.extend(names);
    }
    seen.sort();
    assert_eq!(seen, vec!["tube", "tube1", "tube2", "tube3", "tube4"], "union = all, no overlap");
    let out = desal(&["run", pipeline.to_str().unwrap(), "--shard", "4/3"]);
    assert!(!out.status.success());
}
