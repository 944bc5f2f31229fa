//! Ingest validation: each kind of bad input gets an error naming the file and the
//! element, a non-zero exit, and no output at all.

use std::path::Path;

use desal_io::ply::{PlyWriteOptions, write_ply};
use desal_mesh::TriMesh;

use crate::support::*;

/// Runs the pipeline expecting failure; checks stderr mentions every `needles` and
/// that no output folder was created.
fn expect_failure(pipeline: &Path, needles: &[&str]) {
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    let err = stderr(&out);
    assert!(!out.status.success(), "desal should fail");
    for needle in needles {
        assert!(err.contains(needle), "stderr lacks '{needle}':\n{err}");
    }
    assert!(!pipeline.parent().unwrap().join("out/tube").exists(), "no partial output");
}

fn read(dir: &Path, pose: &str) -> TriMesh {
    desal_io::read_mesh(&dir.join(format!("poses/{pose}.ply"))).unwrap()
}

fn write(dir: &Path, pose: &str, mesh: &TriMesh) {
    write_ply(&dir.join(format!("poses/{pose}.ply")), mesh, &PlyWriteOptions::default()).unwrap();
}

#[test]
fn valid_tube_ingests_and_reports_counts() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let report = run_ok(&pipeline, &[]);
    assert_eq!(report["input"]["poses"], 4);
    assert_eq!(report["input"]["vertices"], 122);
    assert_eq!(report["input"]["faces"], 240);
    assert_eq!(report["stages"][0]["name"], "ingest");
}

#[test]
fn pose_with_wrong_vertex_count_names_file_and_counts() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let mut mesh = read(dir.path(), "p2");
    mesh.positions.push(mesh.positions[0]);
    write(dir.path(), "p2", &mesh);
    expect_failure(&pipeline, &["p2.ply", "123 vertices", "has 122"]);
}

#[test]
fn pose_with_other_triangles_names_first_face_unless_ignored() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let mut mesh = read(dir.path(), "p1");
    mesh.faces[7].swap(0, 1);
    write(dir.path(), "p1", &mesh);
    expect_failure(&pipeline, &["p1.ply", "face 7", "ignore_pose_faces"]);
    let pipeline = write_tube_dataset(dir.path(), "ignore_pose_faces = true");
    write(dir.path(), "p1", &mesh);
    run_ok(&pipeline, &[]);
}

#[test]
fn non_finite_coordinate_names_file_and_vertex() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let mut mesh = read(dir.path(), "p3");
    mesh.positions[42].z = f64::INFINITY;
    write(dir.path(), "p3", &mesh);
    expect_failure(&pipeline, &["p3.ply", "vertex 42", "non-finite"]);
}

#[test]
fn face_index_out_of_range_names_the_face() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let mut mesh = read(dir.path(), "p0");
    mesh.faces[3][1] = 500;
    write(dir.path(), "p0", &mesh);
    expect_failure(&pipeline, &["p0.ply", "face 3", "vertex 500"]);
}

#[test]
fn degenerate_and_duplicate_template_faces_are_removed_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "ignore_pose_faces = true");
    let mut mesh = read(dir.path(), "p0");
    mesh.faces.push([5, 5, 6]);
    mesh.faces.push(mesh.faces[0]);
    write(dir.path(), "p0", &mesh);
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    let err = stderr(&out);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("removed 1 degenerate face(s)") && err.contains("face 240"), "{err}");
    assert!(err.contains("removed 1 duplicate face(s)") && err.contains("face 241"), "{err}");
}

#[test]
fn labels_with_wrong_count_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let text = std::fs::read_to_string(dir.path().join("labels.txt")).unwrap();
    std::fs::write(dir.path().join("labels.txt"), format!("{text}1\n")).unwrap();
    expect_failure(&pipeline, &["labels.txt", "123 entries", "122 vertices"]);
}

#[test]
fn unknown_part_id_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let mut labels = vec![0u32; 122];
    labels[17] = 4;
    let json = serde_json::json!({"parts": ["a", "b"], "labels": labels});
    std::fs::write(dir.path().join("labels.json"), json.to_string()).unwrap();
    let text = std::fs::read_to_string(&pipeline).unwrap().replace("labels.txt", "labels.json");
    std::fs::write(&pipeline, text).unwrap();
    expect_failure(&pipeline, &["labels.json", "vertex 17", "part id 4"]);
}

#[test]
fn part_without_three_non_collinear_vertices_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let mut labels = vec!["0"; 122];
    labels[0] = "1";
    labels[1] = "1";
    std::fs::write(dir.path().join("labels.txt"), labels.join("\n")).unwrap();
    expect_failure(&pipeline, &["labels.txt", "part 1", "2 vertices", "non-collinear"]);
}

#[test]
fn empty_pose_glob_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let text = std::fs::read_to_string(&pipeline).unwrap().replace("poses/*.ply", "nothing/*.ply");
    std::fs::write(&pipeline, text).unwrap();
    expect_failure(&pipeline, &["matches no files", "nothing/*.ply"]);
}

#[test]
fn truncated_and_foreign_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_tube_dataset(dir.path(), "");
    let path = dir.path().join("poses/p1.ply");
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() / 2]).unwrap();
    expect_failure(&pipeline, &["p1.ply", "truncated"]);
    std::fs::write(&path, b"\x89PNG not a mesh").unwrap();
    expect_failure(&pipeline, &["p1.ply", "not a readable mesh"]);
}

#[test]
#[cfg_attr(
    not(desal_shared_data),
    ignore = "needs ../shared/datasets beside the checkout (development and CI only)"
)]
fn scape_pipeline_ingests_all_71_poses() {
    if shared_dataset("scape").is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let pipeline = Path::new(env!("CARGO_MANIFEST_DIR")).join("pipelines/scape.toml");
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet", "--out", dir.path().to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("scape/report.json")).unwrap()).unwrap();
    assert_eq!(report["input"]["poses"], 71);
    assert_eq!(report["input"]["vertices"], 12500);
    assert_eq!(report["input"]["faces"], 24998);
}

#[test]
fn bundled_sample_runs_end_to_end_and_writes_pictures() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = Path::new(env!("CARGO_MANIFEST_DIR")).join("pipelines/sample.toml");
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet", "--out", dir.path().to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let sample = dir.path().join("sample");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(sample.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["input"]["poses"], 11);
    assert_eq!(report["input"]["vertices"], 13380);
    let png = std::fs::read(sample.join("saliency.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let ply = desal_io::ply::read_ply_full(&sample.join("saliency.ply")).unwrap();
    let saliency = &ply.scalars.iter().find(|(n, _)| n == "saliency").expect("saliency property").1;
    assert_eq!(saliency.len(), 13380);
    assert!(saliency.iter().all(|s| (0.0..=1.0).contains(s)));
    assert_eq!(saliency.iter().cloned().fold(0.0, f32::max), 1.0, "normalised by the max");
}

#[test]
fn bad_stage_parameters_are_refused_before_anything_runs() {
    for (extra, expected) in [
        ("[dataset.saliency]\npercentile = 0\n", "percentile"),
        ("[dataset.saliency]\nexclude = [\"nosuch\"]\n", "pose 'nosuch'"),
        ("up_axis = \"w\"\n", "up_axis 'w'"),
        ("[dataset.fit]\nmethod = \"spline\"\n", "fit method 'spline' is unknown"),
        ("[dataset.simplify]\ntarget_vertices = 2\n", "too small"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let pipeline = write_tube_dataset(dir.path(), extra);
        let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
        assert!(!out.status.success(), "{extra}");
        assert!(stderr(&out).contains(expected), "{extra}: {}", stderr(&out));
        assert!(!dir.path().join("out").exists(), "{extra}: nothing may be written, not even the cache");
    }
}
