//! `[dataset.model]`: the CC0 body in SMPL's layout (`desal_sample::smpl_layout`, written
//! here as numpy and pickle files) sampled over shapes and poses, through every stage and
//! a hierarchy, keyed by the model's bytes.

use std::path::{Path, PathBuf};

use desal_sample::SourceAssets;
use desal_sample::smpl_layout::smpl_layout_model;

use crate::support::*;

/// The model files and a pipeline reading `file` from them, in `dir`.
fn write_model_dataset(dir: &Path, file: &str, extra: &str) -> PathBuf {
    let assets = SourceAssets::load(&desal_sample::source::repository_source_dir()).unwrap();
    let model = smpl_layout_model(&assets).unwrap();
    std::fs::write(dir.join("model.npz"), model.npz().unwrap()).unwrap();
    std::fs::write(dir.join("model.pkl"), model.pkl()).unwrap();
    let pipeline = dir.join("pipeline.toml");
    std::fs::write(
        &pipeline,
        format!(
            "schema = 1\nout = \"out\"\n\n[[dataset]]\nname = \"body\"\n\n[dataset.model]\nfile = \"{file}\"\n\
             shapes = 2\nposes = 3\nseed = 7\n{extra}\n[dataset.simplify]\nplacement = \"subset\"\n\
             target_vertices = 1500\n\n[dataset.hierarchy]\nlevels = [1500, 400]\n"
        ),
    )
    .unwrap();
    pipeline
}

fn report(dir: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(dir.join("out/body/report.json")).unwrap()).unwrap()
}

/// A model source makes the template and shapes × poses samples named by shape, labels
/// from its skinning weights, and a hierarchy; a second run is served by the cache, and
/// the pickle of the same model gives the same samples.
#[test]
fn a_body_model_is_sampled_and_simplified_with_a_hierarchy() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_model_dataset(dir.path(), "model.npz", "");
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let first = report(dir.path());
    let names: Vec<&str> =
        first["stages"].as_array().unwrap().iter().map(|s| s["name"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        ["model-ingest", "model-labels", "fit", "saliency", "simplify", "map", "hierarchy-1", "hierarchy-2"]
    );
    assert_eq!(first["input"]["poses"], 7, "the template and 2 shapes × 3 poses");
    let body = dir.path().join("out/body");
    let mut poses: Vec<String> = std::fs::read_dir(body.join("simplified"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".ply"))
        .collect();
    poses.sort();
    assert_eq!(poses[0], "s000-p000.ply");
    assert!(poses.contains(&"s001-p002.ply".to_owned()) && poses.contains(&"template.ply".to_owned()));
    let labels = std::fs::read_to_string(body.join("labels.json")).unwrap();
    assert!(labels.contains("left_elbow") && labels.contains("pelvis"), "{labels}");
    assert!(body.join("hierarchy.npz").is_file());

    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(ran(&report(dir.path())).is_empty(), "a warm run computes nothing");

    // The pickle holds the same model: another ingest key (other bytes), the same poses.
    let npz_poses = std::fs::read(body.join("poses.dsa")).unwrap();
    let text = std::fs::read_to_string(&pipeline).unwrap().replace("model.npz", "model.pkl");
    std::fs::write(&pipeline, text).unwrap();
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(ran(&report(dir.path())).contains(&"model-ingest".to_owned()));
    let a =
        desal_io::artifact::decode_artifact::<desal_io::artifact::PoseSetV2>(Path::new("npz"), &npz_poses)
            .unwrap()
            .1;
    let b = desal_io::artifact::read_artifact::<desal_io::artifact::PoseSetV2>(&body.join("poses.dsa"))
        .unwrap()
        .1;
    assert_eq!(a.names, b.names);
    let worst = a
        .positions
        .iter()
        .flatten()
        .zip(b.positions.iter().flatten())
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
        .fold(0.0f32, f32::max);
    assert!(worst < 1e-5, "npz and pkl samples differ by {worst} m");
}

/// A model table beside pose files, an empty sample count and a missing file are refused
/// before any stage runs, naming what is wrong.
#[test]
fn a_model_source_is_checked_when_the_pipeline_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_model_dataset(dir.path(), "model.npz", "");
    let text = std::fs::read_to_string(&pipeline).unwrap();
    let cases = [
        (
            text.replace("name = \"body\"", "name = \"body\"\nposes = \"*.ply\"\nlabels = \"l.txt\""),
            "replaces `poses`",
        ),
        (text.replace("shapes = 2", "shapes = 0"), "shapes and poses must be at least 1"),
        (text.replace("model.npz", "missing.npz"), "missing.npz"),
    ];
    for (toml, expected) in cases {
        std::fs::write(&pipeline, toml).unwrap();
        let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
        assert!(!out.status.success());
        assert!(stderr(&out).contains(expected), "{expected}: {}", stderr(&out));
        assert!(!dir.path().join("out/body/report.json").exists(), "no partial output");
    }
}
