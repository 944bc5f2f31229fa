//! The LBS deformation model: exact expectations on hand-made cases, the weight
//! invariants as properties, and held-out behaviour on the synthetic skinned tube.

mod common;

use common::{Tube, centroid, rotation};
use desal_measures::{
    EvalError, LbsConfig, PartTransform, PoissonSolver, fit_lbs, folds, training_poses, v2v,
};
use desal_mesh::{Mat3, PartLabels, PoseSet, TriMesh, Vec3};
use proptest::prelude::*;

fn max_distance(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (p - q).norm()).fold(0.0, f64::max)
}

fn rigid(axis_angle: Vec3, translation: Vec3) -> PartTransform {
    PartTransform { rotation: rotation(axis_angle), translation }
}

/// Issue 17: with a single part every vertex has one bone, weight 1, so a rigid motion
/// of the part is reproduced exactly — in-sample and for a motion never trained on.
#[test]
fn single_part_reproduces_a_rigid_motion() {
    let tube = Tube::new(7, 6);
    let labels = PartLabels::from_ids(vec![0; tube.template.len()]);
    let motions =
        [rigid(Vec3::zeros(), Vec3::zeros()), rigid(Vec3::new(0.3, 0.1, -0.2), Vec3::new(1.0, 2.0, 3.0))];
    let poses: Vec<Vec<Vec3>> =
        motions.iter().map(|m| tube.template.iter().map(|x| m.apply(x)).collect()).collect();
    let set = PoseSet::try_new(vec!["a".into(), "b".into()], poses, tube.faces.clone(), 0).unwrap();
    let transforms: Vec<Vec<PartTransform>> = motions.iter().map(|m| vec![*m]).collect();
    let model = fit_lbs(&set, &labels, &transforms, &[0, 1], &LbsConfig::default()).unwrap();
    for v in 0..model.vertex_count() {
        assert_eq!(model.weights(v), &[(0, 1.0)]);
    }
    let unseen = rigid(Vec3::new(-1.0, 0.5, 2.0), Vec3::new(-0.5, 0.0, 0.25));
    let got = model.synthesize(&[unseen]).unwrap();
    let truth: Vec<Vec3> = tube.template.iter().map(|x| unseen.apply(x)).collect();
    assert!(max_distance(&got, &truth) < 1e-12, "{}", max_distance(&got, &truth));
}

/// With `rings = 0` every vertex keeps only its own part: LBS is the rigid parts.
#[test]
fn zero_rings_gives_rigid_parts() {
    let tube = Tube::new(11, 6);
    let poses = tube.pose_set(3, 2);
    let transforms = common::part_transforms(&poses, &tube.labels);
    let config = LbsConfig { rings: 0, ..LbsConfig::default() };
    let model = fit_lbs(&poses, &tube.labels, &transforms, &[0, 1, 2, 3], &config).unwrap();
    for (v, &p) in tube.labels.labels.iter().enumerate() {
        assert_eq!(model.weights(v), &[(p, 1.0)], "vertex {v}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]
    /// Issue 17: whatever the settings and poses, every vertex's weights are positive,
    /// sum to one, number at most four (and at most `max_influences`), and name parts.
    #[test]
    fn weights_are_a_convex_combination_of_at_most_four_bones(
        rings in 0usize..6, max_influences in 0usize..7, prior in 0.0f64..2.0, seed in 0u64..1000, count in 1usize..6,
    ) {
        let tube = Tube::new(13, 6);
        let poses = tube.pose_set(count, seed);
        let transforms = common::part_transforms(&poses, &tube.labels);
        let training: Vec<usize> = (0..poses.pose_count()).collect();
        let config = LbsConfig { rings, max_influences, prior };
        let model = fit_lbs(&poses, &tube.labels, &transforms, &training, &config).unwrap();
        for v in 0..model.vertex_count() {
            let w = model.weights(v);
            prop_assert!(!w.is_empty() && w.len() <= max_influences.clamp(1, 4), "vertex {v}: {w:?}");
            prop_assert!(w.iter().all(|&(p, x)| x > 0.0 && p < 3), "vertex {v}: {w:?}");
            prop_assert!(w.windows(2).all(|pair| pair[0].0 < pair[1].0), "vertex {v}: {w:?}");
            let total: f64 = w.iter().map(|(_, x)| x).sum();
            prop_assert!((total - 1.0).abs() < 1e-12, "vertex {v}: {w:?}");
        }
    }
}

/// Held out, fitted weights must beat rigid parts clearly on a tube that was skinned:
/// otherwise the fit would be learning nothing.
#[test]
fn lbs_beats_rigid_parts_on_held_out_poses() {
    let tube = Tube::new(31, 12);
    let poses = tube.pose_set(24, 5);
    let transforms = common::part_transforms(&poses, &tube.labels);
    let test = &folds(poses.pose_count(), 0, 4)[0];
    let train = training_poses(poses.pose_count(), test);
    let model = fit_lbs(&poses, &tube.labels, &transforms, &train, &LbsConfig::default()).unwrap();
    let solver = PoissonSolver::new(poses.template_positions(), &poses.faces).unwrap();
    let mesh = |positions: Vec<Vec3>| TriMesh { positions, faces: poses.faces.clone() };
    let triangle_parts =
        desal_measures::Skeleton::new(poses.template_positions(), &poses.faces, &tube.labels, None)
            .triangle_parts;
    let (mut lbs_error, mut rigid_error) = (0.0, 0.0);
    for &p in test {
        let target = mesh(poses.poses[p].clone());
        lbs_error += v2v(&mesh(model.synthesize(&transforms[p]).unwrap()), &target);
        let rigid: Vec<Mat3> = triangle_parts.iter().map(|&k| transforms[p][k as usize].rotation).collect();
        rigid_error += v2v(&mesh(solver.solve(&rigid, &centroid(&target.positions))), &target);
    }
    eprintln!("held-out v2v: lbs {lbs_error:.3e}, rigid parts {rigid_error:.3e}; {:?}", model.report());
    assert!(lbs_error < 0.5 * rigid_error, "lbs {lbs_error:e} vs rigid {rigid_error:e}");
}

/// Inputs that do not fit the pose set are refused with the offending ids.
#[test]
fn mismatched_inputs_are_refused() {
    let tube = Tube::new(5, 6);
    let poses = tube.pose_set(2, 1);
    let mut transforms = common::part_transforms(&poses, &tube.labels);
    let config = LbsConfig::default();
    let fit =
        |t: &[Vec<PartTransform>], train: &[usize]| fit_lbs(&poses, &tube.labels, t, train, &config).err();
    assert_eq!(fit(&transforms, &[]), Some(EvalError::NoTrainingPoses));
    assert_eq!(fit(&transforms, &[1, 1]), Some(EvalError::DuplicateTrainingPose { pose: 1 }));
    assert_eq!(fit(&transforms[..2], &[0]), Some(EvalError::RotationPoseCount { expected: 3, found: 2 }));
    transforms[2][1].translation.y = f64::NAN;
    assert_eq!(fit(&transforms, &[0, 2]), Some(EvalError::NonFiniteTransform { pose: 2, part: 1 }));
    let model = fit_lbs(&poses, &tube.labels, &transforms, &[0, 1], &config).unwrap();
    assert_eq!(
        model.synthesize(&transforms[1][..2]).err(),
        Some(EvalError::RotationPartCount { pose: 0, expected: 3, found: 2 })
    );
}
