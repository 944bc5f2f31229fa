//! Stages 3 and 4 through `desal run`, and every stage binary alone on the previous
//! stage's artifact.

use std::path::Path;
use std::process::Command;

use crate::support::*;

fn read_out(dir: &Path, file: &str) -> desal_mesh::TriMesh {
    desal_io::read_mesh(&dir.join("out/tube").join(file)).unwrap()
}

#[test]
fn every_simplified_pose_has_the_simplified_triangles_and_vertex_count() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "[dataset.simplify]\ntarget_vertices = 60\n");
    let report = run_ok(&pipeline, &[]);
    assert_eq!(report["output"]["vertices"], 60);
    assert_eq!(report["output"]["poses"], 4);
    let raw = read_out(dir.path(), "simplified-template-raw.ply");
    for pose in ["p0", "p1", "p2", "p3"] {
        let mesh = read_out(dir.path(), &format!("simplified/{pose}.ply"));
        assert_eq!(mesh.vertex_count(), 60, "{pose}");
        assert_eq!(mesh.faces, raw.faces, "{pose}: registered simplified poses share one triangle list");
    }
    let map: Vec<u32> = std::fs::read_to_string(dir.path().join("out/tube/vertex_map.txt"))
        .unwrap()
        .lines()
        .map(|l| l.parse().unwrap())
        .collect();
    assert_eq!(map.len(), 60);
    let mut sorted = map.clone();
    sorted.sort_unstable();
    sorted.dedup();
    assert_eq!(sorted.len(), 60, "mapped original vertices are distinct");
    // Each simplified pose is the original pose gathered at the mapped indices.
    let original = desal_io::read_mesh(&dir.path().join("poses/p2.ply")).unwrap();
    let simplified = read_out(dir.path(), "simplified/p2.ply");
    for (simp_idx, &orig_idx) in map.iter().enumerate() {
        assert_eq!(simplified.positions[simp_idx], original.positions[orig_idx as usize]);
    }
    let labels = std::fs::read_to_string(dir.path().join("out/tube/simplified/parts.txt")).unwrap();
    assert_eq!(labels.lines().filter(|l| !l.starts_with('#')).count(), 60);
}

#[test]
fn subset_placement_maps_exactly_onto_stage_3s_output() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline =
        write_tube_dataset(dir.path(), "[dataset.simplify]\ntarget_vertices = 50\nplacement = \"subset\"\n");
    run_ok(&pipeline, &[]);
    let raw = read_out(dir.path(), "simplified-template-raw.ply");
    let template = read_out(dir.path(), "simplified/p0.ply");
    assert_eq!(raw, template, "applying a subset map to the template reproduces stage 3's mesh exactly");
    let map = std::fs::read(dir.path().join("out/tube/map.json")).unwrap();
    let map: serde_json::Value = serde_json::from_slice(&map).unwrap();
    assert_eq!(map["mode"], "subset");
    assert_eq!(map["displacement_max"], 0.0);
}

#[test]
fn changed_simplify_parameter_reruns_simplify_and_map_only() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "[dataset.simplify]\ntarget_vertices = 60\n");
    run_ok(&pipeline, &[]);
    let text =
        std::fs::read_to_string(&pipeline).unwrap().replace("target_vertices = 60", "target_vertices = 70");
    std::fs::write(&pipeline, text).unwrap();
    let report = run_ok(&pipeline, &[]);
    assert_eq!(ran(&report), ["simplify", "map"], "{report}");
    assert_eq!(report["output"]["vertices"], 70);
}

fn run_bin(name: &str, args: &[&str]) {
    let exe = Path::new(env!("CARGO_BIN_EXE_desal")).with_file_name(name);
    let out = Command::new(&exe).args(args).output().unwrap();
    assert!(out.status.success(), "{name}: {}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn stage_binaries_alone_reproduce_the_pipeline_artifacts_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "[dataset.simplify]\ntarget_vertices = 60\n");
    run_ok(&pipeline, &[]);
    let out = dir.path().join("out/tube");
    let p = |name: &str| out.join(name).to_str().unwrap().to_owned();
    let alone = dir.path().join("alone");
    std::fs::create_dir_all(&alone).unwrap();
    let a = |name: &str| alone.join(name).to_str().unwrap().to_owned();
    run_bin("desal-fit", &["--poses", &p("poses.dsa"), "--labels", &p("labels.dsa"), "-o", &a("fit.dsa")]);
    run_bin(
        "desal-saliency",
        &["--poses", &p("poses.dsa"), "--fit", &a("fit.dsa"), "-o", &a("saliency.dsa")],
    );
    run_bin(
        "desal-map",
        &[
            "--poses",
            &p("poses.dsa"),
            "--labels",
            &p("labels.dsa"),
            "--simplified",
            &p("simplified.dsa"),
            "-o",
            &a("map.dsa"),
        ],
    );
    for name in ["fit.dsa", "saliency.dsa", "map.dsa"] {
        assert_eq!(
            std::fs::read(out.join(name)).unwrap(),
            std::fs::read(alone.join(name)).unwrap(),
            "{name}"
        );
    }
}

#[test]
fn another_tools_mesh_is_mapped_by_the_greedy_rule() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "[dataset.simplify]\ntarget_vertices = 60\n");
    run_ok(&pipeline, &[]);
    let out = dir.path().join("out/tube");
    let p = |name: &str| out.join(name).to_str().unwrap().to_owned();
    let target = dir.path().join("ext");
    run_bin(
        "desal-map",
        &[
            "--poses",
            &p("poses.dsa"),
            "--labels",
            &p("labels.dsa"),
            "--simplified",
            &p("simplified-template-raw.ply"),
            "-o",
            target.join("map.dsa").to_str().unwrap(),
            "--out-dir",
            target.to_str().unwrap(),
        ],
    );
    // The raw template PLY holds the same positions (as f32) as stage 3's artifact, so
    // the greedy rule maps it to the same original vertices.
    assert_eq!(
        std::fs::read_to_string(target.join("vertex_map.txt")).unwrap(),
        std::fs::read_to_string(out.join("vertex_map.txt")).unwrap()
    );
    assert!(target.join("p3.ply").exists());
}

#[test]
fn simplify_binary_takes_plain_files_and_refuses_a_saliency_of_the_wrong_length() {
    let dir = tempfile::tempdir().unwrap();
    write_tube_dataset(dir.path(), "");
    let input = dir.path().join("poses/p0.ply");
    let output = dir.path().join("small.ply");
    let saliency = dir.path().join("saliency.txt");
    let values: Vec<String> = (0..122).map(|v| format!("{}", (v % 10) as f64 / 10.0)).collect();
    std::fs::write(&saliency, values.join("\n")).unwrap();
    let exe = Path::new(env!("CARGO_BIN_EXE_desal")).with_file_name("desal-simplify");
    let args = |extra: &[&str]| {
        let mut a = vec!["--input", input.to_str().unwrap(), "--output", output.to_str().unwrap()];
        a.extend_from_slice(extra);
        a.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    let out = Command::new(&exe)
        .args(args(&["--target-vertices", "40", "--saliency", saliency.to_str().unwrap(), "--repeat", "2"]))
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stdout).starts_with("SIMPLIFY_SECONDS="));
    assert_eq!(desal_io::read_mesh(&output).unwrap().vertex_count(), 40);
    std::fs::remove_file(&output).unwrap();
    std::fs::write(&saliency, values[..100].join("\n")).unwrap();
    let out = Command::new(&exe)
        .args(args(&["--target-vertices", "40", "--saliency", saliency.to_str().unwrap()]))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("saliency.txt") && err.contains("100 saliency values") && err.contains("122"),
        "{err}"
    );
    assert!(!output.exists(), "no partial output");

    // The metric switch reaches the simplifier: Lindstrom–Turk places vertices by a
    // different rule, so the same target gives other positions.
    let quadric = dir.path().join("quadric.ply");
    let lt = dir.path().join("lt.ply");
    for (path, metric) in [(&quadric, "quadric"), (&lt, "lindstrom-turk")] {
        let out = Command::new(&exe)
            .args(["--input", input.to_str().unwrap(), "--output", path.to_str().unwrap()])
            .args(["--target-vertices", "40", "--metric", metric])
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    let (quadric, lt) = (desal_io::read_mesh(&quadric).unwrap(), desal_io::read_mesh(&lt).unwrap());
    assert_eq!((quadric.vertex_count(), lt.vertex_count()), (40, 40));
    assert_ne!(quadric.positions, lt.positions);
}

/// `desal simplify`'s flags are `[simplify]`'s knobs: part borders are kept from a labels
/// file (and the border vertices stay where they were), a switch takes `false` as a
/// pipeline file does, and the methods that read the poses are refused.
#[test]
fn simplify_binary_offers_the_knobs_of_a_pipeline_file() {
    let dir = tempfile::tempdir().unwrap();
    write_tube_dataset(dir.path(), "");
    let (input, labels) = (dir.path().join("poses/p0.ply"), dir.path().join("labels.txt"));
    let output = dir.path().join("small.ply");
    let simplify = |extra: &[&str]| {
        desal(
            &["simplify", "--input", input.to_str().unwrap(), "--output", output.to_str().unwrap()]
                .into_iter()
                .chain(extra.iter().copied())
                .collect::<Vec<_>>(),
        )
    };
    let out = simplify(&["--target-vertices", "40", "--keep-part-borders"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("give --labels"), "{}", stderr(&out));
    let out = simplify(&["--target-vertices", "40", "--labels", labels.to_str().unwrap()]);
    assert!(stderr(&out).contains("only with --keep-part-borders"), "{}", stderr(&out));
    assert!(!output.exists(), "no partial output");

    let kept = simplify(&[
        "--target-vertices",
        "40",
        "--placement",
        "subset",
        "--keep-part-borders",
        "--labels",
        labels.to_str().unwrap(),
    ]);
    assert!(kept.status.success(), "{}", stderr(&kept));
    let kept = desal_io::read_mesh(&output).unwrap();
    let free =
        simplify(&["--target-vertices", "40", "--placement", "subset", "--keep-part-borders", "false"]);
    assert!(free.status.success(), "{}", stderr(&free));
    let free = desal_io::read_mesh(&output).unwrap();
    assert_ne!(kept.positions, free.positions, "locking the border changes the result");
    // Every input vertex on the border between the two parts is still there.
    let mesh = desal_io::read_mesh(&input).unwrap();
    let ids = desal_io::labels::read_labels(&labels).unwrap().labels;
    let on_border = |v: usize| {
        mesh.faces.iter().any(|f| f.contains(&(v as u32)) && f.iter().any(|&w| ids[w as usize] != ids[v]))
    };
    for v in (0..mesh.vertex_count()).filter(|&v| on_border(v)) {
        assert!(kept.positions.contains(&mesh.positions[v]), "border vertex {v} was collapsed");
    }

    for method in ["multipose", "desal-refit"] {
        let out = simplify(&["--target-vertices", "40", "--method", method]);
        assert!(!out.status.success());
        assert!(stderr(&out).contains("use `desal run`"), "{method}: {}", stderr(&out));
    }
}

#[test]
fn run_never_takes_over_a_folder_it_did_not_write_and_keeps_eval() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    // Someone's own files where the dataset's outputs would go: refused, untouched.
    let out_dir = dir.path().join("out/tube");
    std::fs::create_dir_all(&out_dir).unwrap();
    std::fs::write(out_dir.join("thesis.tex"), "mine").unwrap();
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("holds no report.json"), "{}", stderr(&out));
    assert_eq!(std::fs::read_to_string(out_dir.join("thesis.tex")).unwrap(), "mine");
    std::fs::remove_file(out_dir.join("thesis.tex")).unwrap();

    // desal eval's folder survives a run whose outputs change.
    run_ok(&pipeline, &[]);
    std::fs::create_dir_all(out_dir.join("eval")).unwrap();
    std::fs::write(out_dir.join("eval/eval.md"), "table").unwrap();
    let text = std::fs::read_to_string(&pipeline).unwrap();
    std::fs::write(&pipeline, format!("{text}[dataset.simplify]\nratio = 0.5\n")).unwrap();
    let report = run_ok(&pipeline, &[]);
    assert!(
        report["stages"].as_array().unwrap().iter().any(|s| s["name"] == "simplify" && s["cached"] == false)
    );
    assert_eq!(std::fs::read_to_string(out_dir.join("eval/eval.md")).unwrap(), "table");
}

#[test]
fn map_refuses_a_simplified_template_of_another_pose_set() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a");
    let b = dir.path().join("b");
    run_ok(
        &write_tube_dataset(&a, "[dataset.simplify]\nplacement = \"subset\"\ntarget_vertices = 60\n"),
        &[],
    );
    // The same vertex count, another template (a bent pose).
    run_ok(&write_tube_dataset(&b, "template = \"p2\"\n"), &[]);
    let p = |dir: &Path, name: &str| dir.join("out/tube").join(name).to_str().unwrap().to_owned();
    let output = dir.path().join("map.dsa");
    let exe = Path::new(env!("CARGO_BIN_EXE_desal")).with_file_name("desal-map");
    let out = Command::new(exe)
        .args(["--poses", &p(&b, "poses.dsa"), "--labels", &p(&b, "labels.dsa")])
        .args(["--simplified", &p(&a, "simplified.dsa"), "-o", output.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(stderr(&out).contains("belongs to another pose set"), "{}", stderr(&out));
    assert!(!output.exists());
}

/// `[simplify] method = "desal-refit"`: `desal run` simplifies with desal's own method
/// (subset placement, the flips' note in `simplified.json`), caches it under a key of
/// its own (a second run computes nothing; naming the method again after a plain run
/// reruns stage 3 and the map only), and refuses a setting the method would replace.
#[test]
fn run_simplifies_with_desal_refit_when_the_pipeline_names_it() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "[dataset.simplify]\ntarget_vertices = 60\n");
    run_ok(&pipeline, &[]);
    let text = std::fs::read_to_string(&pipeline).unwrap();
    std::fs::write(
        &pipeline,
        text.replace("target_vertices = 60", "target_vertices = 60\nmethod = \"desal-refit\""),
    )
    .unwrap();
    let report = run_ok(&pipeline, &[]);
    assert_eq!(ran(&report), ["simplify", "map"], "{report}");
    assert_eq!(report["output"]["vertices"], 60);
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("out/tube/simplified.json")).unwrap()).unwrap();
    assert_eq!(summary["method"], "desal-refit");
    assert_eq!(summary["placement"], "subset");
    let map: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("out/tube/map.json")).unwrap()).unwrap();
    assert_eq!(map["displacement_max"], 0.0, "every simplified vertex an original one");
    assert!(ran(&run_ok(&pipeline, &[])).is_empty(), "a second run is served by the cache");

    // A setting the method makes itself, given another value, is refused before any stage.
    let text = std::fs::read_to_string(&pipeline).unwrap();
    std::fs::write(
        &pipeline,
        text.replace("method = \"desal-refit\"", "method = \"desal-refit\"\nbalance = true"),
    )
    .unwrap();
    let out = crate::support::desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(!out.status.success());
    let err = crate::support::stderr(&out);
    assert!(
        err.contains("method = \"desal-refit\" sets balance = false itself; remove balance = true"),
        "{err}"
    );
}
