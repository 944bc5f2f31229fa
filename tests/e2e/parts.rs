//! `labels = "auto"` end to end (issue 16): discovered parts go through the whole
//! pipeline and the cache like a labels file, `desal parts` writes the same artifact as
//! `desal run`, a motionless pose set gets one part with a warning, and `desal eval`
//! runs on discovered parts.

use std::path::{Path, PathBuf};

use crate::support::*;

/// The tube dataset with `labels = "auto"` instead of its labels file.
fn auto_tube(dir: &Path, extra_toml: &str) -> PathBuf {
    let pipeline = write_tube_dataset(dir, extra_toml);
    let text =
        std::fs::read_to_string(&pipeline).unwrap().replace("labels = \"labels.txt\"", "labels = \"auto\"");
    std::fs::write(&pipeline, text).unwrap();
    pipeline
}

fn read_labels_dsa(path: &Path) -> desal_mesh::PartLabels {
    let (_, body, _) = desal_io::artifact::read_artifact::<desal_io::artifact::LabelsV1>(path).unwrap();
    body.to_labels().unwrap()
}

/// The tube is two rigid halves, bent at the middle: discovery finds exactly the two
/// halves the hand-made labels file draws, and the outputs say so in every form.
#[test]
fn auto_labels_run_end_to_end_and_find_the_tubes_two_halves() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = auto_tube(dir.path(), "");
    let report = run_ok(&pipeline, &[]);
    let names: Vec<&str> =
        report["stages"].as_array().unwrap().iter().map(|s| s["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["ingest", "parts", "fit", "saliency", "simplify", "map"], "{report}");
    let out = dir.path().join("out/tube");
    for file in ["labels.txt", "parts.png", "parts.json", "labels.dsa", "labels.json"] {
        assert!(out.join(file).is_file(), "{file} missing");
    }
    let auto = read_labels_dsa(&out.join("labels.dsa"));
    let given = desal_io::labels::read_labels(&dir.path().join("labels.txt")).unwrap();
    assert_eq!(auto.part_count(), 2);
    assert_eq!(desal_parts::adjusted_rand_index(&auto.labels, &given.labels), 1.0);
    // labels.txt is the artifact's labels, readable as a labels file.
    let text = std::fs::read_to_string(out.join("labels.txt")).unwrap();
    assert!(text.starts_with("# parts: part0 part1\n"), "{text}");
    let back = desal_io::labels::read_labels(&out.join("labels.txt")).unwrap();
    assert_eq!((back.labels, back.names), (auto.labels, auto.names));
    let parts: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("parts.json")).unwrap()).unwrap();
    assert_eq!(parts["parts"], 2, "{parts}");
    assert_eq!(parts["motionless"], false, "{parts}");
    assert!(std::fs::read(out.join("parts.png")).unwrap().starts_with(b"\x89PNG"));
}

/// The cache keys the auto labels: a second run is all hits; a new `parts` re-runs the
/// discovery and everything after it, never ingest.
#[test]
fn the_cache_keys_auto_labels_by_their_parameters() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = auto_tube(dir.path(), "");
    run_ok(&pipeline, &[]);
    let second = run_ok(&pipeline, &[]);
    assert!(ran(&second).is_empty(), "{second}");
    let text = std::fs::read_to_string(&pipeline).unwrap();
    std::fs::write(&pipeline, text.replace("labels = \"auto\"", "labels = \"auto\"\nparts = 3")).unwrap();
    let third = run_ok(&pipeline, &[]);
    assert_eq!(ran(&third), ["parts", "fit", "saliency", "simplify", "map"], "{third}");
}

/// `parts` with a labels file is a mistake the pipeline file refuses before any stage.
#[test]
fn parts_without_auto_labels_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "parts = 3");
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("`parts` applies to `labels = \"auto\"` only"), "{}", stderr(&out));
}

/// `desal parts` on the run's `poses.dsa` writes the run's `labels.dsa`, byte for byte,
/// and the text and picture beside it.
#[test]
fn desal_parts_writes_the_same_labels_artifact_as_desal_run() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = auto_tube(dir.path(), "");
    run_ok(&pipeline, &[]);
    let out = dir.path().join("out/tube");
    let labels = dir.path().join("labels-alone.dsa");
    let txt = dir.path().join("labels-alone.txt");
    let png = dir.path().join("parts-alone.png");
    let run = desal(&[
        "parts",
        "--poses",
        out.join("poses.dsa").to_str().unwrap(),
        "-o",
        labels.to_str().unwrap(),
        "--txt",
        txt.to_str().unwrap(),
        "--png",
        png.to_str().unwrap(),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert_eq!(std::fs::read(&labels).unwrap(), std::fs::read(out.join("labels.dsa")).unwrap());
    assert_eq!(std::fs::read(&txt).unwrap(), std::fs::read(out.join("labels.txt")).unwrap());
    assert!(png.is_file());
}

/// Poses that do not move have one part, and the run says why on stderr.
#[test]
fn a_motionless_pose_set_gets_one_part_and_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = auto_tube(dir.path(), "");
    let rest = std::fs::read(dir.path().join("poses/p0.ply")).unwrap();
    for k in 1..4 {
        std::fs::write(dir.path().join(format!("poses/p{k}.ply")), &rest).unwrap();
    }
    let run = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(stderr(&run).contains("the poses do not move"), "{}", stderr(&run));
    let labels = read_labels_dsa(&dir.path().join("out/tube/labels.dsa"));
    assert_eq!(labels.part_count(), 1);
}

/// `desal eval` on the bundled sample with discovered parts: the model's joints are the
/// borders between them, and both methods get held-out figures.
#[test]
fn desal_eval_runs_on_auto_labels() {
    let dir = tempfile::tempdir().unwrap();
    let samples = Path::new(env!("CARGO_MANIFEST_DIR")).join("data-samples");
    let pipeline = dir.path().join("pipeline.toml");
    let text = format!(
        "schema = 1\nout = \"out\"\n\n[[dataset]]\nname = \"sample\"\nposes = \"{}/*.ply\"\ntemplate = \"00_rest\"\n\
         labels = \"auto\"\nparts = 16\nup_axis = \"y\"\n\n[dataset.simplify]\ntarget_vertices = 800\nplacement = \"optimal\"\n\
         saliency = true\nbalance = true\n",
        samples.join("poses").display(),
    );
    std::fs::write(&pipeline, text).unwrap();
    let methods = "qslim-optimal,paper-optimal";
    let out = desal(&["eval", pipeline.to_str().unwrap(), "--folds", "2", "--methods", methods, "--quiet"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let json = dir.path().join("out/sample/eval/eval.json");
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(json).unwrap()).unwrap();
    let paper = report["methods"].as_array().unwrap().iter().find(|m| m["name"] == "paper-optimal").unwrap();
    let change = &paper["versus_baseline"]["held_out"]["vs_full"];
    assert!(change["v2v_percent"].is_f64() && change["v2f_percent"].is_f64(), "{change}");
    let labels = read_labels_dsa(&dir.path().join("out/sample/labels.dsa"));
    assert_eq!(labels.part_count(), 16);
    // Discovered parts name no head, hand or foot: the regions are joints vs other, with
    // every vertex in one of them and no NaN row (issue 17, item 5).
    let regions = paper["regions"].as_array().unwrap();
    let names: Vec<&str> = regions.iter().map(|r| r["region"].as_str().unwrap()).collect();
    assert_eq!(names, ["joints", "other"]);
    let vertices: u64 = regions.iter().map(|r| r["vertices"].as_u64().unwrap()).sum();
    assert_eq!(vertices, 800);
    let md = std::fs::read_to_string(dir.path().join("out/sample/eval/eval.md")).unwrap();
    let table = md.split("## Where the vertices went").nth(1).unwrap().split("\n## ").next().unwrap();
    assert!(!table.contains("NaN") && !table.contains("head/hands/feet: vertices"), "{table}");
    assert!(table.contains("| joints: vertices (%) | joints: mean area | other: vertices (%) |"), "{table}");
}
