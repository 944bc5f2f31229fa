//! `[dataset.model]`: the CC0 body in SMPL's layout (`desal_sample::smpl_layout`, written
//! here as numpy and pickle files) sampled over shapes and poses, through every stage and
//! a hierarchy, keyed by the model's bytes; the smaller model it leaves (`model.npz`).

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

/// The simplified samples in `simplified/`, sorted.
fn simplified_plys(body: &Path) -> Vec<String> {
    let mut poses: Vec<String> = std::fs::read_dir(body.join("simplified"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.ends_with(".ply"))
        .collect();
    poses.sort();
    poses
}

/// Issue 41, item 4: a model source writes no per-sample PLY unless `write_poses = true`
/// asks; the map's files are written either way, and asking recomputes no stage (the
/// setting is in no stage key) but rewrites the folder (it is in `outputs_key`).
#[test]
fn a_model_source_writes_its_samples_only_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_model_dataset(dir.path(), "model.npz", "");
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let body = dir.path().join("out/body");
    assert_eq!(simplified_plys(&body), Vec::<String>::new(), "no sample PLY by default");
    assert!(body.join("simplified/parts.txt").is_file() && body.join("vertex_map.txt").is_file());
    let first = report(dir.path());

    let text =
        std::fs::read_to_string(&pipeline).unwrap().replace("seed = 7\n", "seed = 7\nwrite_poses = true\n");
    std::fs::write(&pipeline, text).unwrap();
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let second = report(dir.path());
    assert!(ran(&second).is_empty(), "write_poses is in no stage key");
    assert_ne!(first["outputs_key"], second["outputs_key"], "but in the folder's");
    let poses = simplified_plys(&body);
    assert_eq!(poses.len(), 7, "the template and 2 shapes × 3 poses: {poses:?}");
    assert_eq!(poses[0], "s000-p000.ply");
    assert!(poses.contains(&"s001-p002.ply".to_owned()) && poses.contains(&"template.ply".to_owned()));
    let template = desal_io::read_mesh(&body.join("simplified/template.ply")).unwrap();
    let raw = desal_io::read_mesh(&body.join("simplified-template-raw.ply")).unwrap();
    assert_eq!(template.faces, raw.faces, "subset placement: the mapped template is stage 3's");
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
        (
            text.replace("placement = \"subset\"", "placement = \"optimal\""),
            "pipeline.toml: dataset 'body'\n  caused by: [simplify] placement = \"optimal\": a [dataset.model] is \
             simplified with subset placement",
        ),
    ];
    for (toml, expected) in cases {
        std::fs::write(&pipeline, toml).unwrap();
        let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
        assert!(!out.status.success());
        assert!(stderr(&out).contains(expected), "{expected}: {}", stderr(&out));
        assert!(!dir.path().join("out/body/report.json").exists(), "no partial output");
    }
}

/// Random parameters within the fixture's basis: its 10 betas ~ U(−2, 2), per joint an
/// axis-angle of up to 0.5 rad per axis, a translation.
fn random_params(rng: &mut rand_chacha::ChaCha8Rng) -> (Vec<f64>, Vec<desal_mesh::Vec3>, desal_mesh::Vec3) {
    use rand::Rng;
    let mut turn = || {
        desal_mesh::Vec3::new(rng.gen_range(-0.5..0.5), rng.gen_range(-0.5..0.5), rng.gen_range(-0.5..0.5))
    };
    let pose: Vec<desal_mesh::Vec3> = (0..24).map(|_| turn()).collect();
    let translation = turn();
    let betas = (0..10).map(|_| rng.gen_range(-2.0..2.0)).collect();
    (betas, pose, translation)
}

/// Issue 41, item 5: a model dataset (subset placement by default) leaves `model.npz`,
/// the model on its kept vertices (`vertex_map.txt`) and simplified triangles, which
/// reads back as SMPL and at 10 random (betas, pose) evaluates to the full model's kept
/// vertices and joints to 1e-6 m; `model.json` gives the regressor's residual. The
/// pickle of the same model gives an npz of the same keys and the same model.
#[test]
fn a_model_dataset_leaves_the_simplified_model() {
    use desal_bodymodel::{BodyModel, Params};
    use rand::SeedableRng;

    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_model_dataset(dir.path(), "model.npz", "");
    let text = std::fs::read_to_string(&pipeline).unwrap();
    let text = text
        .replace("placement = \"subset\"\n", "")
        .replace("[dataset.hierarchy]\nlevels = [1500, 400]\n", "");
    std::fs::write(&pipeline, text).unwrap();
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let body = dir.path().join("out/body");
    let files = report(dir.path())["files"].clone();
    assert!(files.as_array().unwrap().iter().any(|f| f == "model.npz") && body.join("model.json").is_file());

    let full = BodyModel::read(&dir.path().join("model.npz")).unwrap();
    let small = BodyModel::read(&body.join("model.npz")).unwrap();
    let kept: Vec<usize> = std::fs::read_to_string(body.join("vertex_map.txt"))
        .unwrap()
        .lines()
        .map(|l| l.parse().unwrap())
        .collect();
    let simplified = desal_io::read_mesh(&body.join("simplified-template-raw.ply")).unwrap();
    assert_eq!(
        (small.kind, small.vertex_count(), small.faces.len()),
        (full.kind, kept.len(), simplified.faces.len())
    );
    assert_eq!(small.layout.keys, full.layout.keys, "the input's keys, in its order");

    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(41);
    let (mut worst_vertex, mut worst_joint) = (0.0f64, 0.0f64);
    for _ in 0..10 {
        let (betas, pose, translation) = random_params(&mut rng);
        let params = Params { betas: &betas, expression: &[], pose: &pose, translation };
        let (a, b) = (full.evaluate(&params).unwrap(), small.evaluate(&params).unwrap());
        for (s, &o) in kept.iter().enumerate() {
            worst_vertex = worst_vertex.max((b.vertices[s] - a.vertices[o]).norm());
        }
        for (p, q) in a.joints.iter().zip(&b.joints) {
            worst_joint = worst_joint.max((p - q).norm());
        }
    }
    println!(
        "model.npz at 10 random parameter sets: vertices {worst_vertex:.1e} m, joints {worst_joint:.1e} m"
    );
    assert!(worst_vertex < 1e-6 && worst_joint < 1e-6, "{worst_vertex} {worst_joint}");
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(body.join("model.json")).unwrap()).unwrap();
    assert!(summary["max_residual_m"].as_f64().unwrap() < 1e-9, "{summary}");
    assert_eq!(summary["joints"].as_array().unwrap().len(), 24);

    // The pickle: the same kept vertices (the same samples), an npz of the same keys.
    let npz_model = std::fs::read(body.join("model.npz")).unwrap();
    let text = std::fs::read_to_string(&pipeline).unwrap().replace("model.npz", "model.pkl");
    std::fs::write(&pipeline, text).unwrap();
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let from_pkl = BodyModel::read(&body.join("model.npz")).unwrap();
    let from_npz = BodyModel::from_npz_bytes(Path::new("model.npz"), &npz_model).unwrap();
    assert_eq!(from_pkl.layout.keys, from_npz.layout.keys);
    assert_eq!(from_pkl.faces, from_npz.faces);
    let close = from_pkl.v_template.iter().zip(&from_npz.v_template).all(|(a, b)| (a - b).norm() < 1e-6);
    assert!(close, "the pickle's simplified model differs");
}
