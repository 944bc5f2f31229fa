//! Tiny hand-built models with exact expectations: reading (every refusal names its key),
//! evaluation, sampling and part labels.

use std::path::Path;

use desal_bodymodel::{
    BodyModel, BodyModelError, ExtraEntry, ModelKind, Params, SampleConfig, Sampler, labels_from_weights,
};
use desal_io::npz::{AnyArray, AnyData, NpzEntry, encode_npy_any, encode_npz_entries};
use desal_mesh::Vec3;

/// A 5-joint (FLAME-kind) chain along x: joint j at (j, 0, 0), vertex j at the joint
/// (the regressor picks vertex j for joint j) plus vertex 5 at (2, 0, 0) weighted fully
/// to joint 1. `shapedirs` has 302 columns: 300 shape + 2 expression.
fn tiny() -> Vec<(String, AnyArray)> {
    let v = 6;
    let mut v_template: Vec<f64> = (0..5).flat_map(|j| [j as f64, 0.0, 0.0]).collect();
    v_template.extend([2.0, 0.0, 0.0]);
    let mut weights = vec![0.0; v * 5];
    for j in 0..5 {
        weights[j * 5 + j] = 1.0;
    }
    weights[5 * 5 + 1] = 1.0;
    let mut regressor = vec![0.0; 5 * v];
    for j in 0..5 {
        regressor[j * v + j] = 1.0;
    }
    let mut shapedirs = vec![0.0; v * 3 * 302];
    shapedirs[(5 * 3 + 2) * 302] = 0.5; // shape 0 lifts vertex 5 along z
    shapedirs[(5 * 3 + 2) * 302 + 301] = 0.25; // expression 1 too
    let mut posedirs = vec![0.0; v * 3 * 36];
    posedirs[(5 * 3 + 1) * 36 + 1] = 0.1; // vertex 5, y, joint 1's entry (0, 1)
    let f64s = |shape: Vec<usize>, data: Vec<f64>| AnyArray { shape, data: AnyData::F64(data) };
    vec![
        ("v_template".into(), f64s(vec![v, 3], v_template)),
        ("f".into(), AnyArray { shape: vec![2, 3], data: AnyData::I32(vec![0, 1, 5, 1, 2, 5]) }),
        ("shapedirs".into(), f64s(vec![v, 3, 302], shapedirs)),
        ("posedirs".into(), f64s(vec![v, 3, 36], posedirs)),
        ("weights".into(), f64s(vec![v, 5], weights)),
        (
            "kintree_table".into(),
            AnyArray { shape: vec![2, 5], data: AnyData::I64(vec![-1, 0, 1, 2, 3, 0, 1, 2, 3, 4]) },
        ),
        ("J_regressor".into(), f64s(vec![5, v], regressor)),
        ("landmarks".into(), AnyArray { shape: vec![2], data: AnyData::U8(vec![7, 9]) }),
    ]
}

fn npz(arrays: &[(String, AnyArray)]) -> Vec<u8> {
    let entries: Vec<NpzEntry> =
        arrays.iter().map(|(k, a)| NpzEntry { name: k.clone(), npy: encode_npy_any(a).unwrap() }).collect();
    encode_npz_entries(&entries).unwrap()
}

fn read(arrays: &[(String, AnyArray)]) -> Result<BodyModel, BodyModelError> {
    BodyModel::from_npz_bytes(Path::new("tiny.npz"), &npz(arrays))
}

fn with(key: &str, array: AnyArray) -> Vec<(String, AnyArray)> {
    let mut arrays = tiny();
    arrays.iter_mut().find(|(k, _)| k == key).unwrap().1 = array;
    arrays
}

/// The kind comes from the joint count; FLAME's shapedirs split at 300; the unknown key
/// is kept as its exact `.npy` bytes.
#[test]
fn reads_kind_split_and_extras() {
    let model = read(&tiny()).unwrap();
    assert_eq!(model.kind, ModelKind::Flame);
    assert_eq!((model.shape_count, model.expression_count), (300, 2));
    assert_eq!(model.parents, [None, Some(0), Some(1), Some(2), Some(3)]);
    let landmarks = encode_npy_any(&tiny()[7].1).unwrap();
    assert_eq!(model.extras, [("landmarks".to_owned(), ExtraEntry::Npy(landmarks))]);
}

/// Joint 1 turned a quarter about z: vertex 5 (1 m out along x from joint 1) ends at
/// (1, 1, 0), moved first by its pose corrective: entry (0, 1) of R − I is −1, so
/// −0.1 m along y in the rest frame, which the turn carries to +0.1 along x.
/// Shape 0 and expression 1 lift it by 0.5 β + 0.25 ψ along z.
#[test]
fn evaluation_exact() {
    let model = read(&tiny()).unwrap();
    let mut pose = vec![Vec3::zeros(); 5];
    pose[1] = Vec3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2);
    let mut expression = vec![0.0; 2];
    expression[1] = 2.0;
    let params = Params {
        betas: &[1.0],
        expression: &expression,
        pose: &pose,
        translation: Vec3::new(0.0, 0.0, 10.0),
    };
    let posed = model.evaluate(&params).unwrap();
    let expected = Vec3::new(1.0 + 0.1, 1.0, 10.0 + 0.5 + 0.5);
    assert!((posed.vertices[5] - expected).norm() < 1e-14, "{:?}", posed.vertices[5]);
    // Joint 2 is carried by joint 1's turn; joint 0 stays.
    assert!((posed.joints[2] - Vec3::new(1.0, 1.0, 10.0)).norm() < 1e-14);
    assert_eq!(posed.joints[0], Vec3::new(0.0, 0.0, 10.0));
    let too_many = Params { betas: &[0.0; 301], ..params };
    assert!(matches!(model.evaluate(&too_many), Err(BodyModelError::BadParameters { given: 301, .. })));
}

/// Every refusal names the key at fault.
#[test]
fn bad_files_name_the_key() {
    let cases: Vec<(Vec<(String, AnyArray)>, &str)> = vec![
        (tiny().into_iter().filter(|(k, _)| k != "posedirs").collect(), "'posedirs' is missing"),
        (
            with("v_template", AnyArray { shape: vec![6, 2], data: AnyData::F64(vec![0.0; 12]) }),
            "'v_template' has shape [6, 2]",
        ),
        (with("f", AnyArray { shape: vec![1, 3], data: AnyData::I32(vec![0, 1, 6]) }), "'f' corner 2 is 6"),
        (
            with(
                "weights",
                AnyArray { shape: vec![6, 5], data: AnyData::F64([vec![f64::NAN], vec![0.0; 29]].concat()) },
            ),
            "'weights' value 0 is not finite",
        ),
        (
            with(
                "kintree_table",
                AnyArray { shape: vec![2, 5], data: AnyData::I64(vec![-1, 0, 3, 2, 3, 0, 1, 2, 3, 4]) },
            ),
            "joint 2's parent 3",
        ),
        (with("kintree_table", AnyArray { shape: vec![2, 7], data: AnyData::I64(vec![0; 14]) }), "7 joints"),
        (
            with("J_regressor", AnyArray { shape: vec![], data: AnyData::Unicode(vec!["x".into()]) }),
            "'J_regressor' holds str",
        ),
    ];
    for (arrays, message) in cases {
        let err = read(&arrays).unwrap_err().to_string();
        assert!(err.starts_with("tiny.npz: ") && err.contains(message), "{err}\n  expected: {message}");
    }
}

/// Truncated or corrupted files are refused, never a panic.
#[test]
fn damaged_files_never_panic() {
    let bytes = npz(&tiny());
    for len in 0..bytes.len() {
        assert!(BodyModel::from_npz_bytes(Path::new("t.npz"), &bytes[..len]).is_err());
        assert!(BodyModel::from_pkl_bytes(Path::new("t.pkl"), &bytes[..len]).is_err());
    }
}

/// The path reader goes through desal-io's regular-file check and picks the format by
/// extension.
#[test]
fn reads_paths_and_refuses_folders() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("tiny.npz");
    std::fs::write(&path, npz(&tiny())).unwrap();
    assert_eq!(BodyModel::read(&path).unwrap(), read(&tiny()).unwrap());
    let err = BodyModel::read(dir.path()).unwrap_err().to_string();
    assert!(err.contains("not a regular file"), "{err}");
}

/// 1 + shapes × poses samples; the template first (the rest surface, exactly up to
/// rounding); groups in order; the same seed gives the same samples, another seed others.
#[test]
fn sampler_sequence_and_determinism() {
    let model = read(&tiny()).unwrap();
    let config = SampleConfig { shapes: 3, poses: 2, seed: 7, ..SampleConfig::default() };
    let samples: Vec<(usize, Vec<Vec3>)> = Sampler::new(&model, config.clone()).unwrap().collect();
    assert_eq!(samples.len(), 7);
    assert_eq!(samples.iter().map(|s| s.0).collect::<Vec<_>>(), [0, 1, 1, 2, 2, 3, 3]);
    for (ours, rest) in samples[0].1.iter().zip(&model.v_template) {
        assert!((ours - rest).norm() < 1e-15);
    }
    let again: Vec<(usize, Vec<Vec3>)> = Sampler::new(&model, config.clone()).unwrap().collect();
    assert_eq!(samples, again);
    let other: Vec<(usize, Vec<Vec3>)> =
        Sampler::new(&model, SampleConfig { seed: 8, ..config }).unwrap().collect();
    assert_ne!(samples[1], other[1]);
}

/// Betas are clipped, the root turns about the up axis only, the spreads are the
/// configured ones, expressions are drawn only when asked.
#[test]
fn sampler_distributions() {
    let model = read(&tiny()).unwrap();
    let config = SampleConfig { shapes: 200, poses: 1, expressions: true, ..SampleConfig::default() };
    let mut sampler = Sampler::new(&model, config).unwrap();
    let template = sampler.next_sample().unwrap();
    assert!(template.betas.is_empty() && template.pose.iter().all(|r| *r == Vec3::zeros()));
    let (mut sum_sq, mut count) = (0.0, 0);
    while let Some(s) = sampler.next_sample() {
        assert_eq!((s.betas.len(), s.expression.len()), (10, 2));
        assert!(s.betas.iter().all(|b| b.abs() <= 2.5));
        assert!(s.pose[0].x == 0.0 && s.pose[0].z == 0.0 && s.pose[0].y.abs() <= std::f64::consts::PI);
        // FLAME: joint 1 (neck) is a body joint, 0.3 rad.
        sum_sq += s.pose[1].norm_squared();
        count += 3;
    }
    let sigma = (sum_sq / count as f64).sqrt();
    assert!((sigma - 0.3).abs() < 0.03, "{sigma}");
    let no_expressions =
        read(&with("shapedirs", AnyArray { shape: vec![6, 3, 1], data: AnyData::F64(vec![0.0; 18]) }))
            .unwrap();
    let err = Sampler::new(&no_expressions, SampleConfig { expressions: true, ..SampleConfig::default() })
        .unwrap_err();
    assert!(err.to_string().contains("'expressions'"), "{err}");
}

/// Dominant joints merge along the tree, smallest (then latest) first, mirror pairs
/// together.
#[test]
fn labels_merge_along_the_tree() {
    let model = read(&tiny()).unwrap();
    // Dominant joints: vertices 0..5 → joints 0..5, vertex 5 → joint 1. Sizes 1, 2, 1, 1, 1.
    let five = labels_from_weights(&model, 5);
    assert_eq!(five.labels, [0, 1, 2, 3, 4, 1]);
    // The chain's vertices are collinear, so every part has zero area: the latest merges
    // first. Joint 4 (right_eye) takes its mirror, joint 3 (left_eye), with it: 4 asked
    // gives 3 parts.
    let four = labels_from_weights(&model, 4);
    assert_eq!(four.names, ["root", "neck", "jaw"]);
    assert_eq!(four.labels, [0, 1, 2, 2, 2, 1]);
    // Then the jaw (with both eyes) into the neck: {0}, {1, 2, 3, 4}.
    let two = labels_from_weights(&model, 2);
    assert_eq!(two.names, ["root", "neck"]);
    assert_eq!(two.labels, [0, 1, 1, 1, 1, 1]);
}

/// A chain of `joints` joints (joint j at (j, 0, 0), vertex j on it, weighted to it), with
/// `extra` arrays added: enough for the kinds whose layout is tested here.
fn chain(joints: usize, extra: Vec<(String, AnyArray)>) -> Vec<(String, AnyArray)> {
    let v = joints;
    let f64s = |shape: Vec<usize>, data: Vec<f64>| AnyArray { shape, data: AnyData::F64(data) };
    let identity: Vec<f64> = (0..v * v).map(|k| if k % (v + 1) == 0 { 1.0 } else { 0.0 }).collect();
    let parents: Vec<i64> = (0..joints as i64).map(|j| j - 1).chain(0..joints as i64).collect();
    let mut arrays = vec![
        ("v_template".into(), f64s(vec![v, 3], (0..v).flat_map(|j| [j as f64, 0.0, 0.0]).collect())),
        ("f".into(), AnyArray { shape: vec![1, 3], data: AnyData::U32(vec![0, 1, 2]) }),
        ("shapedirs".into(), f64s(vec![v, 3, 10], vec![0.0; v * 30])),
        ("posedirs".into(), f64s(vec![v, 3, 9 * (joints - 1)], vec![0.0; v * 27 * (joints - 1)])),
        ("weights".into(), f64s(vec![v, joints], identity.clone())),
        ("kintree_table".into(), AnyArray { shape: vec![2, joints], data: AnyData::I64(parents) }),
        ("J_regressor".into(), f64s(vec![joints, v], identity)),
    ];
    for (key, array) in extra {
        match arrays.iter_mut().find(|(k, _)| *k == key) {
            Some(slot) => slot.1 = array,
            None => arrays.push((key, array)),
        }
    }
    arrays
}

/// SMPL-H: 52 joints; the mean hand poses land on joints 22.. and 37..; sampled hand
/// joints spread 0.2 rad about them, body joints 0.3 about zero.
#[test]
fn smplh_hand_means_and_spreads() {
    let mean = |value: f64| AnyArray { shape: vec![45], data: AnyData::F64(vec![value; 45]) };
    let arrays = chain(52, vec![("hands_meanl".into(), mean(0.5)), ("hands_meanr".into(), mean(-0.5))]);
    let model = read(&arrays).unwrap();
    assert_eq!(model.kind, ModelKind::SmplH);
    assert_eq!(
        (model.pose_mean[21], model.pose_mean[22], model.pose_mean[51]),
        (Vec3::zeros(), Vec3::repeat(0.5), Vec3::repeat(-0.5))
    );
    // The means are also kept as they came, for a writer.
    assert!(model.extras.iter().any(|(k, _)| k == "hands_meanl"));
    let config = SampleConfig { shapes: 1, poses: 400, ..SampleConfig::default() };
    let mut sampler = Sampler::new(&model, config).unwrap();
    sampler.next_sample();
    let (mut body, mut hand, mut hand_mean) = (0.0, 0.0, Vec3::zeros());
    let mut count = 0.0;
    while let Some(s) = sampler.next_sample() {
        body += s.pose[5].norm_squared() / 3.0;
        hand += (s.pose[30] - Vec3::repeat(0.5)).norm_squared() / 3.0;
        hand_mean += s.pose[30];
        count += 1.0;
    }
    let (body, hand) = ((body / count).sqrt(), (hand / count).sqrt());
    assert!((body - 0.3).abs() < 0.03 && (hand - 0.2).abs() < 0.02, "{body} {hand}");
    assert!((hand_mean / count - Vec3::repeat(0.5)).norm() < 0.05);
}

/// MANO: 16 joints; `shapedirs` may come flattened, `(V·3·S,)`.
#[test]
fn mano_flattened_shapedirs() {
    let mut flat = vec![0.0; 16 * 3 * 10];
    flat[(4 * 3 + 1) * 10 + 2] = 0.5; // vertex 4, y, beta 2
    let arrays =
        chain(16, vec![("shapedirs".into(), AnyArray { shape: vec![480], data: AnyData::F64(flat) })]);
    let model = read(&arrays).unwrap();
    assert_eq!((model.kind, model.shape_count), (ModelKind::Mano, 10));
    let shaped = model.shape(&[0.0, 0.0, 2.0], &[]).unwrap();
    assert_eq!(shaped.vertices[4], Vec3::new(4.0, 1.0, 0.0));
}

/// SMPL-X 1.0: `shapedirs` 20 wide is 10 shape + 10 expression; 55 joints.
#[test]
fn smplx_v1_split() {
    let arrays = chain(
        55,
        vec![(
            "shapedirs".into(),
            AnyArray { shape: vec![55, 3, 20], data: AnyData::F64(vec![0.0; 55 * 60]) },
        )],
    );
    let model = read(&arrays).unwrap();
    assert_eq!((model.kind, model.shape_count, model.expression_count), (ModelKind::SmplX, 10, 10));
    assert_eq!(model.kind.joint_names()[22], "jaw");
}

/// Batched evaluation is the single one bit for bit: every sample (poses 11 per shape,
/// so batches of 8 and 3, with expressions) equals its own parameters evaluated alone.
#[test]
fn batches_match_single_evaluation() {
    let model = read(&tiny()).unwrap();
    let config = SampleConfig { shapes: 2, poses: 11, expressions: true, seed: 3, ..SampleConfig::default() };
    let mut sampler = Sampler::new(&model, config).unwrap();
    assert_eq!(sampler.len(), 23);
    let mut count = 0;
    while let Some(s) = sampler.next_sample() {
        let shaped = model.shape(&s.betas, &s.expression).unwrap();
        assert_eq!(
            model.pose(&shaped, &s.pose, Vec3::zeros()).unwrap().vertices,
            s.vertices,
            "sample {count}"
        );
        count += 1;
        assert_eq!(sampler.len(), 23 - count);
    }
    assert_eq!(count, 23);
}

/// Written back unchanged (`BodyModel::to_npz`), the FLAME-kind model is its file byte
/// for byte: `shapedirs` is its 300 shape and 2 expression columns joined again, the
/// tree keeps its −1, the unknown key its bytes.
#[test]
fn shape_and_expression_columns_write_back_as_one_array() {
    let bytes = npz(&tiny());
    let written = read(&tiny()).unwrap().to_npz().unwrap();
    assert!(written.dropped.is_empty());
    assert!(written.bytes == bytes, "the written npz differs from the file it was read from");
}
