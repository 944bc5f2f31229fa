//! The SCAPE pose-deformation model end to end: on a synthetic skinned tube (exact
//! expectations) and on SCAPE itself (the paper's data, skipped when absent).

mod common;

use common::{Tube, centroid, part_rotations};
use desal_measures::gradient::{deformation_gradient, inverse_template_frame};
use desal_measures::{ModelConfig, PoissonSolver, fit_model, folds, training_poses, v2f, v2v};
use desal_mesh::{Mat3, PoseSet, TriMesh, Vec3};

fn max_distance(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (p - q).norm()).fold(0.0, f64::max)
}

/// Issue 6: Poisson reconstruction of the *unmodified* deformation gradients of a posed
/// mesh returns that mesh, up to the translation fixed by the centroid.
#[test]
fn unmodified_gradients_reconstruct_every_pose() {
    let tube = Tube::new(31, 12);
    let poses = tube.pose_set(4, 11);
    let solver = PoissonSolver::new(poses.template_positions(), &poses.faces).unwrap();
    let template = poses.template_positions();
    for pose in &poses.poses {
        let gradients: Vec<Mat3> = poses
            .faces
            .iter()
            .map(|&[a, b, c]| {
                let [a, b, c] = [a as usize, b as usize, c as usize];
                let inv = inverse_template_frame(&template[a], &template[b], &template[c]).unwrap();
                deformation_gradient(&inv, [pose[a], pose[b], pose[c]])
            })
            .collect();
        let got = solver.solve(&gradients, &centroid(pose));
        assert!(max_distance(&got, pose) < 1e-10, "max error {}", max_distance(&got, pose));
    }
}

/// Issue 6: with at most seven training poses (the regression has seven coefficients
/// per entry) and a negligible ridge, the model interpolates its training poses, so
/// synthesising a training pose from its part rotations gives the pose back almost
/// exactly — through the twists, the regression and the Poisson solve together.
#[test]
fn model_reproduces_its_training_poses() {
    let tube = Tube::new(31, 12);
    let poses = tube.pose_set(5, 3);
    let rotations = part_rotations(&poses, &tube.labels);
    let all: Vec<usize> = (0..poses.pose_count()).collect();
    let config =
        ModelConfig { ridge: 1e-12, regression: desal_measures::Regression::Fixed, ..ModelConfig::default() };
    let model = fit_model(&poses, &tube.labels, &rotations, &all, &config).unwrap();
    assert_eq!(model.report().joint_count, 2);
    assert!(model.report().mean_q_residual < 1e-12, "{:?}", model.report());
    for (p, pose) in poses.poses.iter().enumerate() {
        let got = model.synthesize(&rotations[p], centroid(pose)).unwrap();
        // The tube is 3 units long: 1e-6 is a millionth of a percent of its size.
        assert!(max_distance(&got, pose) < 1e-6, "pose {p}: max error {}", max_distance(&got, pose));
    }
}

/// Held out, the regression must explain the skinning bulges better than rigid parts
/// (Q = I): otherwise the pose-dependent term would be useless.
#[test]
fn regression_beats_rigid_parts_on_held_out_poses() {
    let tube = Tube::new(31, 12);
    let poses = tube.pose_set(24, 5);
    let rotations = part_rotations(&poses, &tube.labels);
    let test = &folds(poses.pose_count(), 0, 4)[0];
    let train = training_poses(poses.pose_count(), test);
    let model = fit_model(&poses, &tube.labels, &rotations, &train, &ModelConfig::default()).unwrap();
    let solver = PoissonSolver::new(poses.template_positions(), &poses.faces).unwrap();
    let mesh = |positions: Vec<Vec3>| TriMesh { positions, faces: poses.faces.clone() };
    let (mut model_error, mut rigid_error) = (0.0, 0.0);
    for &p in test {
        let target = mesh(poses.poses[p].clone());
        let c = centroid(&target.positions);
        model_error += v2v(&mesh(model.synthesize(&rotations[p], c).unwrap()), &target);
        let rigid: Vec<Mat3> =
            model.skeleton().triangle_parts.iter().map(|&k| rotations[p][k as usize]).collect();
        rigid_error += v2v(&mesh(solver.solve(&rigid, &c)), &target);
    }
    eprintln!("held-out v2v: model {model_error:.3e}, rigid parts {rigid_error:.3e}");
    assert!(model_error < 0.5 * rigid_error, "model {model_error:e} vs rigid {rigid_error:e}");
}

/// Inputs that do not fit the pose set are refused with the offending ids.
#[test]
fn mismatched_inputs_are_refused() {
    use desal_measures::EvalError;
    let tube = Tube::new(5, 6);
    let poses = tube.pose_set(2, 1);
    let mut rotations = part_rotations(&poses, &tube.labels);
    let config = ModelConfig::default();
    let fit = |r: &[Vec<Mat3>], train: &[usize]| fit_model(&poses, &tube.labels, r, train, &config).err();
    assert_eq!(fit(&rotations, &[]), Some(EvalError::NoTrainingPoses));
    assert_eq!(fit(&rotations, &[0, 3]), Some(EvalError::TrainingPoseOutOfRange { pose: 3, pose_count: 3 }));
    assert_eq!(fit(&rotations, &[1, 1]), Some(EvalError::DuplicateTrainingPose { pose: 1 }));
    assert_eq!(fit(&rotations[..2], &[0]), Some(EvalError::RotationPoseCount { expected: 3, found: 2 }));
    rotations[2].pop();
    assert_eq!(
        fit(&rotations, &[0, 2]),
        Some(EvalError::RotationPartCount { pose: 2, expected: 3, found: 2 })
    );
    let model = fit_model(&poses, &tube.labels, &rotations, &[0, 1], &config).unwrap();
    assert!(model.synthesize(&rotations[2], Vec3::zeros()).is_err());
}

/// SCAPE, model fitted on all 71 poses (in-sample), checked on every fifth pose: the
/// synthesised poses must beat the rigid-part reconstruction (Q = I) by a clear margin.
/// Prints the figures. (Evaluating all 71 poses takes ~15 s in a debug build: see the
/// ignored variant below, run in release for the report.)
///
/// What bounds the figure: SCAPE's registration slides vertices along the surface (the
/// median edge changes length by ~10% between the template and a pose), so much of each
/// triangle's Q is not a function of joint twists — the regression leaves a mean
/// squared Frobenius residual of ~0.29 — and the Poisson solve integrates what is left.
#[test]
#[cfg_attr(
    not(desal_shared_data),
    ignore = "needs ../shared/datasets beside the checkout (development and CI only)"
)]
fn scape_in_sample_error_beats_rigid_parts() {
    check_scape_in_sample(5);
}

/// The same over all 71 poses: `cargo test --release -p desal-measures --test model -- --ignored --nocapture`.
#[test]
#[ignore = "slow in debug builds (~15 s); run in release for the reported figure"]
fn scape_in_sample_error_all_poses() {
    check_scape_in_sample(1);
}

/// Held-out figure for the report: 5 folds over the non-template poses, each model
/// fitted without its test poses. Measured 1.79e-4 m² v2v (EVAL.md); checked against a
/// band around it.
#[test]
#[ignore = "slow in debug builds; run in release for the reported figure"]
fn scape_held_out_error() {
    let Some(dir) = common::scape_dir() else { return };
    let (poses, labels): (PoseSet, _) = common::load_scape(&dir);
    let rotations = part_rotations(&poses, &labels);
    let mut errors = Vec::new();
    // The pre-issue-17 model (fixed ridge, centroid placement): tests/floor.rs has the
    // new defaults.
    let config = ModelConfig {
        regression: desal_measures::Regression::Fixed,
        anchoring: desal_measures::Anchoring::Centroid,
        ..ModelConfig::default()
    };
    for test in folds(poses.pose_count(), poses.template, 5) {
        let train = training_poses(poses.pose_count(), &test);
        let model = fit_model(&poses, &labels, &rotations, &train, &config).unwrap();
        for &p in &test {
            let target = poses.pose_mesh(p);
            let positions = model.synthesize(&rotations[p], centroid(&target.positions)).unwrap();
            let deformed = TriMesh { positions, faces: poses.faces.clone() };
            errors.push((v2v(&deformed, &target), v2f(&deformed, &target)));
        }
    }
    let n = errors.len() as f64;
    let (v2v_mean, v2f_mean) = errors.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    eprintln!("SCAPE held-out (5 folds, {n} poses): v2v {v2v_mean:.3e} m², v2f {v2f_mean:.3e} m²");
    assert!((1.5e-4..2.2e-4).contains(&v2v_mean), "held-out v2v {v2v_mean:e} m²");
    assert!(v2f_mean <= v2v_mean, "v2f {v2f_mean:e} above v2v {v2v_mean:e}");
}

fn check_scape_in_sample(pose_stride: usize) {
    let Some(dir) = common::scape_dir() else { return };
    let (poses, labels): (PoseSet, _) = common::load_scape(&dir);
    let rotations = part_rotations(&poses, &labels);
    let all: Vec<usize> = (0..poses.pose_count()).collect();
    let model = fit_model(&poses, &labels, &rotations, &all, &ModelConfig::default()).unwrap();
    let checked: Vec<usize> = (0..poses.pose_count()).step_by(pose_stride).collect();
    let centroids: Vec<Vec3> = checked.iter().map(|&p| centroid(&poses.poses[p])).collect();
    let checked_rotations: Vec<Vec<Mat3>> = checked.iter().map(|&p| rotations[p].clone()).collect();
    let synthesised = model.synthesize_many(&checked_rotations, &centroids).unwrap();
    let solver = PoissonSolver::new(poses.template_positions(), &poses.faces).unwrap();
    let mesh = |positions: Vec<Vec3>| TriMesh { positions, faces: poses.faces.clone() };
    let (mut model_v2v, mut model_v2f, mut rigid_v2v) = (0.0, 0.0, 0.0);
    for ((&p, positions), c) in checked.iter().zip(synthesised).zip(&centroids) {
        let target = poses.pose_mesh(p);
        let deformed = mesh(positions);
        model_v2v += v2v(&deformed, &target);
        model_v2f += v2f(&deformed, &target);
        let rigid: Vec<Mat3> =
            model.skeleton().triangle_parts.iter().map(|&k| rotations[p][k as usize]).collect();
        rigid_v2v += v2v(&mesh(solver.solve(&rigid, c)), &target);
    }
    let n = checked.len() as f64;
    let (model_v2v, model_v2f, rigid_v2v) = (model_v2v / n, model_v2f / n, rigid_v2v / n);
    eprintln!(
        "SCAPE in-sample over {n} poses: model v2v {model_v2v:.3e} m², v2f {model_v2f:.3e} m²; \
         rigid parts v2v {rigid_v2v:.3e} m²; {:?}",
        model.report()
    );
    assert!(model_v2v < 0.8 * rigid_v2v, "model {model_v2v:e} m² vs rigid parts {rigid_v2v:e} m²");
}

/// Three disjoint tube segments (parts 0, 1, 2 along x, no triangle across a border):
/// the worst case for centroid placement, which can only keep each component at its
/// template offset from the overall centroid.
fn broken_chain() -> (PoseSet, desal_mesh::PartLabels) {
    let segment = Tube::new(6, 8);
    let shrink = |p: &Vec3| Vec3::new(p.x / 3.0, p.y, p.z);
    let (mut template, mut faces, mut labels) = (Vec::new(), Vec::new(), Vec::new());
    for part in 0..3u32 {
        let base = template.len() as u32;
        template.extend(segment.template.iter().map(|p| shrink(p) + Vec3::new(1.1 * part as f64, 0.0, 0.0)));
        faces.extend(segment.faces.iter().map(|f| f.map(|v| v + base)));
        labels.extend(std::iter::repeat_n(part, segment.template.len()));
    }
    let poses = PoseSet::try_new(vec!["t".into()], vec![template], faces, 0).unwrap();
    (poses, desal_mesh::PartLabels::from_ids(labels))
}

/// Issue 17: part-anchored synthesis reproduces a chain whose parts each move rigidly —
/// here three separate segments, each turned and moved its own way — exactly: the
/// gradients (`Q = I`, fitted on the template alone) are the parts' rotations and the
/// anchors their motions, so both terms vanish at the true pose. Centroid placement
/// cannot: it misplaces every segment by centimetres to decimetres.
#[test]
fn anchoring_reproduces_a_rigidly_moved_chain() {
    use desal_measures::{Anchoring, PartTransform, Regression};
    let (poses, labels) = broken_chain();
    let transforms: Vec<PartTransform> = (0..3)
        .map(|k| PartTransform {
            rotation: common::rotation(Vec3::new(0.2 * k as f64, -0.4, 0.3 + 0.5 * k as f64)),
            translation: Vec3::new(0.3, -0.1 * k as f64, 0.7 * k as f64),
        })
        .collect();
    let truth: Vec<Vec3> =
        poses.poses[0].iter().zip(&labels.labels).map(|(x, &p)| transforms[p as usize].apply(x)).collect();
    let rotations = vec![desal_measures::rotations_of(&[PartTransform::identity(); 3])];
    for scale in [0.01, 0.1, 1.0] {
        let config = ModelConfig {
            regression: Regression::Fixed,
            anchoring: Anchoring::Parts { scale },
            ..Default::default()
        };
        let model = fit_model(&poses, &labels, &rotations, &[0], &config).unwrap();
        assert!(model.is_anchored());
        let got = model.synthesize_from_parts(&transforms, Vec3::zeros()).unwrap();
        assert!(max_distance(&got, &truth) < 1e-10, "scale {scale}: {}", max_distance(&got, &truth));
    }
    let config =
        ModelConfig { regression: Regression::Fixed, anchoring: Anchoring::Centroid, ..Default::default() };
    let model = fit_model(&poses, &labels, &rotations, &[0], &config).unwrap();
    let got = model.synthesize_from_parts(&transforms, centroid(&truth)).unwrap();
    assert!(max_distance(&got, &truth) > 0.05, "centroid placement: {}", max_distance(&got, &truth));
}

/// Issue 17: on the skinned tube, held out, anchoring the parts' translations beats the
/// centroid: the regression's residual no longer accumulates down the chain. The tube
/// blends its bones over ±0.2 around each joint, so the anchors' length `ℓ` must not be
/// much shorter than that, or the pull towards the rigid parts creases the blend: at
/// scale 0.1 (`ℓ` = 0.24 on this tube) anchoring wins; at the default 0.02 (`ℓ` = 0.05,
/// tuned on bodies whose blend zones are a few centimetres) it does not, and the test
/// says so.
#[test]
fn anchoring_beats_the_centroid_on_held_out_poses() {
    use desal_measures::{Anchoring, PoseModel};
    let tube = Tube::new(31, 12);
    let poses = tube.pose_set(24, 5);
    let transforms = common::part_transforms(&poses, &tube.labels);
    let held_out_v2v = |anchoring| {
        let model = PoseModel::Scape(ModelConfig { anchoring, ..ModelConfig::default() });
        desal_measures::model_floor(&poses, &tube.labels, &transforms, &model, 4).unwrap().held_out.v2v
    };
    let wide = held_out_v2v(Anchoring::Parts { scale: 0.1 });
    let narrow = held_out_v2v(Anchoring::Parts { scale: desal_measures::DEFAULT_ANCHOR_SCALE });
    let centroid = held_out_v2v(Anchoring::Centroid);
    eprintln!(
        "tube held-out v2v: anchored 0.1 {wide:.3e}, anchored 0.02 {narrow:.3e}, centroid {centroid:.3e}"
    );
    assert!(wide < centroid, "anchored {wide:e} vs centroid {centroid:e}");
    assert!(narrow > wide, "narrow {narrow:e} vs wide {wide:e}");
}
