//! The CC0 fixture (`desal_sample::smpl_layout`) through the crate: it reads as SMPL, its
//! regressor reproduces the rig's joints, its labels make 16 parts, and the sampler
//! streams it.

use std::path::Path;

use desal_bodymodel::{BodyModel, ExtraEntry, ModelKind, SampleConfig, Sampler, labels_from_weights};
use desal_io::npz::decode_npy_any;
use desal_sample::SourceAssets;
use desal_sample::smpl_layout::smpl_layout_model;

fn fixture() -> BodyModel {
    let assets = SourceAssets::load(&desal_sample::source::repository_source_dir()).unwrap();
    let npz = smpl_layout_model(&assets).unwrap().npz().unwrap();
    BodyModel::from_npz_bytes(Path::new("model.npz"), &npz).unwrap()
}

/// SMPL's kind and sizes; the regressed rest joints are the rig's (`J`, kept as an extra
/// entry) to float32 rounding.
#[test]
fn fixture_reads_as_smpl() {
    let model = fixture();
    assert_eq!(model.kind, ModelKind::Smpl);
    assert_eq!((model.vertex_count(), model.faces.len(), model.joint_count()), (13380, 26756, 24));
    assert_eq!((model.shape_count, model.expression_count), (10, 0));
    let shaped = model.shape(&[], &[]).unwrap();
    let Some((_, ExtraEntry::Npy(npy))) = model.extras.iter().find(|(k, _)| k == "J") else { panic!("no J") };
    let rig = decode_npy_any(npy).unwrap().data.to_f64().unwrap();
    let worst = shaped
        .joints
        .iter()
        .flat_map(|j| j.iter().copied())
        .zip(rig)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-6, "{worst}");
}

/// 16 asked: 15 anatomical parts (the hands pair merges last), symmetric, each holding
/// vertices, the same on every call.
#[test]
fn fixture_labels_make_body_parts() {
    let model = fixture();
    let labels = labels_from_weights(&model, 16);
    let names: Vec<&str> = labels.names.iter().map(String::as_str).collect();
    assert_eq!(
        names,
        [
            "pelvis",
            "left_hip",
            "right_hip",
            "spine1",
            "left_knee",
            "right_knee",
            "spine2",
            "left_ankle",
            "right_ankle",
            "spine3",
            "head",
            "left_shoulder",
            "right_shoulder",
            "left_elbow",
            "right_elbow"
        ]
    );
    let mut sizes = vec![0usize; names.len()];
    labels.labels.iter().for_each(|&p| sizes[p as usize] += 1);
    assert!(sizes.iter().all(|&n| n > 0), "{sizes:?}");
    // Mirror parts hold mirror vertex sets, up to the mesh's own asymmetry.
    for (left, right) in [(1, 2), (4, 5), (7, 8), (11, 12), (13, 14)] {
        assert!(sizes[left].abs_diff(sizes[right]) <= 2, "{} {} {sizes:?}", names[left], names[right]);
    }
    assert_eq!(labels, labels_from_weights(&model, 16));
}

/// The stream: the template is the rest surface (to the fixture's float32 weights, whose
/// sums miss 1 by ~1e-7, as SMPL's own do); a sample's height stays that of a body.
#[test]
fn fixture_streams() {
    let model = fixture();
    let config = SampleConfig { shapes: 2, poses: 2, seed: 41, ..SampleConfig::default() };
    let mut count = 0;
    for (group, vertices) in Sampler::new(&model, config).unwrap() {
        assert_eq!(vertices.len(), 13380);
        if count == 0 {
            assert_eq!(group, 0);
            let worst =
                vertices.iter().zip(&model.v_template).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
            assert!(worst < 1e-6, "{worst}");
        }
        let (lo, hi) = vertices.iter().fold((f64::MAX, f64::MIN), |(lo, hi), v| (lo.min(v.y), hi.max(v.y)));
        assert!((1.0..2.2).contains(&(hi - lo)), "sample {count}: height {}", hi - lo);
        count += 1;
    }
    assert_eq!(count, 5);
}
