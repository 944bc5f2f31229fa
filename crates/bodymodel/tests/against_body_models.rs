//! desal's evaluation against body-models' (NumPy backend) on the CC0 fixture, to 1e-6 m.
//!
//! `tests/data/body_models_expected.npz` was written by `tests/against_body_models.py`
//! (body-models 0.26.2): parameters, body-models' vertices at every 16th vertex and its
//! posed joints, and the SHA-256 of the fixture it loaded. This test builds the same
//! fixture from `data-samples/source` (`desal_sample::smpl_layout`), checks the hash, so
//! the expected values belong to these bytes, then evaluates. After a change to the
//! fixture's generator, run the script again.

use std::path::Path;

use desal_bodymodel::{BodyModel, Params};
use desal_io::npz::{AnyArray, AnyData, decode_npy_any, read_npz_entries_from};
use desal_mesh::Vec3;
use desal_sample::SourceAssets;
use desal_sample::smpl_layout::{SmplLayoutModel, smpl_layout_model};
use sha2::{Digest, Sha256};

const TOLERANCE: f64 = 1e-6;

fn fixture() -> SmplLayoutModel {
    let assets = SourceAssets::load(&desal_sample::source::repository_source_dir()).unwrap();
    smpl_layout_model(&assets).unwrap()
}

fn expected() -> Vec<(String, AnyArray)> {
    read_expected(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/body_models_expected.npz"))
}

fn read_expected(path: &Path) -> Vec<(String, AnyArray)> {
    let entries = read_npz_entries_from(path, &std::fs::read(path).unwrap()).unwrap();
    entries.into_iter().map(|e| (e.name, decode_npy_any(&e.npy).unwrap())).collect()
}

fn get<'a>(arrays: &'a [(String, AnyArray)], key: &str) -> &'a AnyArray {
    &arrays.iter().find(|(k, _)| k == key).unwrap_or_else(|| panic!("no '{key}'")).1
}

fn f64s(a: &AnyArray) -> Vec<f64> {
    a.data.to_f64().unwrap()
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// The model's vertices and joints match body-models' for six parameter sets (zero pose,
/// a shape, two poses, two of both with a pelvis turn and a translation).
#[test]
fn evaluation_matches_body_models() {
    compare(&fixture().npz().unwrap(), &expected());
}

/// The same comparison with body-models run now, when `DESAL_BODY_MODELS_PYTHON` names a
/// Python that has it (`pip install body-models==0.26.2`): the fixture is written to a
/// temporary folder and the script evaluates it there.
#[test]
fn evaluation_matches_body_models_live() {
    let Some(python) = std::env::var_os("DESAL_BODY_MODELS_PYTHON") else {
        println!("skipped: DESAL_BODY_MODELS_PYTHON is not set (a Python with body-models 0.26.2)");
        return;
    };
    let fixture = fixture();
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("model.npz"), fixture.npz().unwrap()).unwrap();
    std::fs::write(dir.path().join("model.pkl"), fixture.pkl()).unwrap();
    let out = dir.path().join("expected.npz");
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/against_body_models.py");
    let status = std::process::Command::new(python)
        .arg(script)
        .arg("--fixture")
        .arg(dir.path())
        .arg("--out")
        .arg(&out)
        .arg("--flame")
        .status()
        .unwrap();
    assert!(status.success(), "against_body_models.py failed: {status}");
    compare(&fixture.npz().unwrap(), &read_expected(&out));
    compare_flame(&dir.path().join("flame_random.npz"), &dir.path().join("flame_random_expected.npz"));
}

/// A random model in FLAME's layout (written by the script with `--flame`): `shapedirs`
/// 300 shape + 10 expression columns, dense random correctives, FLAME's tree; 20 betas and
/// 10 expression coefficients per set.
#[test]
fn flame_layout_matches_body_models() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    compare_flame(&data.join("flame_random.npz"), &data.join("flame_random_expected.npz"));
}

fn compare_flame(model: &Path, expected: &Path) {
    let model = BodyModel::read(model).unwrap();
    assert_eq!(
        (model.kind, model.shape_count, model.expression_count),
        (desal_bodymodel::ModelKind::Flame, 300, 10)
    );
    let expected = read_expected(expected);
    let (betas, expression) = (f64s(get(&expected, "betas")), f64s(get(&expected, "expression")));
    let (pose, translation) = (f64s(get(&expected, "pose")), f64s(get(&expected, "translation")));
    let (vertices, joints) = (f64s(get(&expected, "vertices")), f64s(get(&expected, "joints")));
    let (v, j) = (model.vertex_count(), model.joint_count());
    let mut worst = 0.0f64;
    for s in 0..get(&expected, "betas").shape[0] {
        let pose: Vec<Vec3> =
            pose[s * 3 * j..(s + 1) * 3 * j].chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
        let t = &translation[s * 3..s * 3 + 3];
        let params = Params {
            betas: &betas[s * 20..(s + 1) * 20],
            expression: &expression[s * 10..(s + 1) * 10],
            pose: &pose,
            translation: Vec3::new(t[0], t[1], t[2]),
        };
        let posed = model.evaluate(&params).unwrap();
        let ours = posed.vertices.iter().chain(&posed.joints).flat_map(|p| p.iter().copied());
        let theirs = vertices[s * v * 3..(s + 1) * v * 3].iter().chain(&joints[s * j * 3..(s + 1) * j * 3]);
        worst = ours.zip(theirs).map(|(a, b)| (a - b).abs()).fold(worst, f64::max);
    }
    println!("FLAME layout against body-models: max |diff| {worst:.2e}");
    assert!(worst < TOLERANCE, "{worst:e}");
}

fn compare(npz: &[u8], expected: &[(String, AnyArray)]) {
    let AnyData::Unicode(digest) = &get(expected, "fixture_sha256").data else { panic!("no digest") };
    assert_eq!(
        hex(&Sha256::digest(npz)),
        digest[0],
        "the fixture's generator changed since tests/against_body_models.py ran: run it again"
    );
    let model = BodyModel::from_npz_bytes(Path::new("model.npz"), npz).unwrap();
    let (betas, pose, translation) =
        (f64s(get(expected, "betas")), f64s(get(expected, "pose")), f64s(get(expected, "translation")));
    let index = get(expected, "vertex_index").data.to_i64().unwrap();
    let (vertices, joints) = (f64s(get(expected, "vertices")), f64s(get(expected, "joints")));
    let sets = get(expected, "betas").shape[0];
    let (mut worst_vertex, mut worst_joint) = (0.0f64, 0.0f64);
    for s in 0..sets {
        let pose: Vec<Vec3> =
            pose[s * 72..(s + 1) * 72].chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
        let t = &translation[s * 3..s * 3 + 3];
        let params = Params {
            betas: &betas[s * 10..(s + 1) * 10],
            expression: &[],
            pose: &pose,
            translation: Vec3::new(t[0], t[1], t[2]),
        };
        let posed = model.evaluate(&params).unwrap();
        for (k, &v) in index.iter().enumerate() {
            let at = (s * index.len() + k) * 3;
            let theirs = Vec3::new(vertices[at], vertices[at + 1], vertices[at + 2]);
            worst_vertex = worst_vertex.max((posed.vertices[v as usize] - theirs).abs().max());
        }
        for (j, ours) in posed.joints.iter().enumerate() {
            let at = (s * 24 + j) * 3;
            worst_joint =
                worst_joint.max((ours - Vec3::new(joints[at], joints[at + 1], joints[at + 2])).abs().max());
        }
    }
    println!(
        "against body-models: {sets} parameter sets, max |diff| vertices {worst_vertex:.2e} m, joints {worst_joint:.2e} m"
    );
    assert!(worst_vertex < TOLERANCE && worst_joint < TOLERANCE, "{worst_vertex:e} {worst_joint:e}");
}

/// The fixture's pickle (Python 2 chumpy layout, CSC regressor) reads into the same model
/// as its npz; only the kept extra entries differ in form, and the element types the file
/// stored (the pickle's chumpy arrays and CSC data are float64).
#[test]
fn pickle_and_npz_read_alike() {
    let fixture = fixture();
    let from_npz = BodyModel::from_npz_bytes(Path::new("model.npz"), &fixture.npz().unwrap()).unwrap();
    let from_pkl = BodyModel::from_pkl_bytes(Path::new("model.pkl"), &fixture.pkl()).unwrap();
    let strip = |m: &BodyModel| BodyModel { extras: Vec::new(), layout: Default::default(), ..m.clone() };
    assert_eq!(strip(&from_npz), strip(&from_pkl));
    assert_eq!(from_npz.layout.keys, from_pkl.layout.keys);
    let names = |m: &BodyModel| m.extras.iter().map(|(k, _)| k.clone()).collect::<Vec<_>>();
    assert_eq!(names(&from_npz), ["J", "bs_style", "bs_type"]);
    assert_eq!(names(&from_pkl), names(&from_npz));
}
