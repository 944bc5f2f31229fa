//! Stage-1 behaviour on small synthetic pose sets with exact expectations: rigidly
//! moved parts fit exactly, the template fits itself, errors name part and pose, the
//! affine ablation never fits worse, and the output is independent of thread count.

use desal_fit::{FitConfig, FitError, FitModel, fit_pose_set};
use desal_mesh::math::{Mat3, UnitQuat, Vec3};
use desal_mesh::{NoProgress, PartLabels, PoseSet};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const VERTICES: usize = 60;

/// Random template points; vertices `0..30` are part 0 ("left"), `30..60` part 1 ("right").
fn template(rng: &mut ChaCha8Rng) -> Vec<Vec3> {
    (0..VERTICES)
        .map(|v| {
            let offset = if v < VERTICES / 2 { -1.0 } else { 1.0 };
            Vec3::new(offset + rng.gen_range(-0.5..0.5), rng.gen_range(-0.5..0.5), rng.gen_range(-0.5..0.5))
        })
        .collect()
}

fn labels() -> PartLabels {
    let ids = (0..VERTICES).map(|v| u32::from(v >= VERTICES / 2)).collect();
    PartLabels::try_new(ids, vec!["left".into(), "right".into()]).unwrap()
}

fn random_rotation(rng: &mut ChaCha8Rng) -> Mat3 {
    let axis = Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
    UnitQuat::from_scaled_axis(axis.normalize() * rng.gen_range(-3.0..3.0)).to_rotation_matrix().into_inner()
}

fn pose_set(poses: Vec<Vec<Vec3>>) -> PoseSet {
    let names = (0..poses.len()).map(|p| format!("pose{p}")).collect();
    PoseSet::try_new(names, poses, vec![[0, 1, 2]], 0).unwrap()
}

/// Template plus `count` poses, each part moved by its own random rigid motion, plus
/// (when `bulge > 0`) a non-rigid swelling of every posed vertex.
fn moved_pose_set(seed: u64, count: usize, bulge: f64) -> (PoseSet, Vec<[(Mat3, Vec3); 2]>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let base = template(&mut rng);
    let mut poses = vec![base.clone()];
    let mut motions = Vec::new();
    for _ in 0..count {
        let motion =
            [0, 1].map(|_| (random_rotation(&mut rng), Vec3::new(rng.gen_range(-2.0..2.0), 0.3, -1.0)));
        let pose = base
            .iter()
            .enumerate()
            .map(|(v, p)| {
                let (r, t) = motion[usize::from(v >= VERTICES / 2)];
                let swollen = p * (1.0 + bulge * p.y.powi(2));
                r * swollen + t
            })
            .collect();
        poses.push(pose);
        motions.push(motion);
    }
    (pose_set(poses), motions)
}

#[test]
fn rigidly_moved_parts_are_recovered_with_zero_residual() {
    let (poses, motions) = moved_pose_set(1, 5, 0.0);
    let result = fit_pose_set(&poses, &labels(), &FitConfig::default(), &NoProgress).unwrap();
    for (pose, motion) in motions.iter().enumerate().map(|(i, m)| (i + 1, m)) {
        for (part, (rotation, translation)) in motion.iter().enumerate() {
            let fit = &result.part_fits[pose][part];
            assert!((fit.linear - rotation).amax() < 1e-12, "pose {pose} part {part}");
            assert!((fit.translation - translation).amax() < 1e-12);
            assert!(fit.max < 1e-12);
        }
    }
    assert!(result.residuals.iter().all(|&r| r < 1e-6));
    assert_eq!(result.residuals.len(), 6 * VERTICES);
}

#[test]
fn the_template_fits_itself_exactly() {
    let (poses, _) = moved_pose_set(2, 3, 0.2);
    let result = fit_pose_set(&poses, &labels(), &FitConfig::default(), &NoProgress).unwrap();
    assert!(result.pose_residuals(0).iter().all(|&r| r == 0.0));
    assert_eq!(result.part_fits[0][1].linear, Mat3::identity());
    // The non-rigid poses do have residuals, and the summary leaves the template out.
    assert!(result.pose_residuals(1).iter().any(|&r| r > 1e-3));
    assert_eq!(result.summary.poses.len(), 3);
    assert!(result.summary.poses.iter().all(|p| p.pose != 0));
}

#[test]
fn residuals_match_the_reported_transforms() {
    let (poses, _) = moved_pose_set(3, 4, 0.3);
    let labels = labels();
    let result = fit_pose_set(&poses, &labels, &FitConfig::default(), &NoProgress).unwrap();
    for pose in 0..poses.pose_count() {
        for v in 0..VERTICES {
            let fit = &result.part_fits[pose][labels.labels[v] as usize];
            let expected = (fit.apply(&poses.poses[0][v]) - poses.poses[pose][v]).norm();
            assert!((result.pose_residuals(pose)[v] as f64 - expected).abs() < 1e-6 * (1.0 + expected));
        }
    }
}

#[test]
fn affine_residuals_are_never_larger_than_rigid_ones() {
    let (poses, _) = moved_pose_set(4, 6, 0.4);
    let rigid = fit_pose_set(&poses, &labels(), &FitConfig::default(), &NoProgress).unwrap();
    let config = FitConfig { model: FitModel::Affine, ..FitConfig::default() };
    let affine = fit_pose_set(&poses, &labels(), &config, &NoProgress).unwrap();
    assert_eq!(affine.model, FitModel::Affine);
    let mut strictly_better = 0;
    for pose in 0..poses.pose_count() {
        for part in 0..2 {
            let (r, a) = (rigid.part_fits[pose][part].rms, affine.part_fits[pose][part].rms);
            assert!(a <= r + 1e-12, "pose {pose} part {part}: affine {a} > rigid {r}");
            strictly_better += usize::from(a < 0.99 * r);
        }
    }
    // The swelling is not rigid, so the affine model must actually absorb some of it.
    assert!(strictly_better > 0);
    assert!(affine.summary.mean_residual < rigid.summary.mean_residual);
}

#[test]
fn summary_puts_the_broken_pose_and_part_first() {
    let (mut poses, _) = moved_pose_set(5, 4, 0.05);
    let mut rng = ChaCha8Rng::seed_from_u64(99);
    // Pose 3's right part gets scrambled, as a broken file would.
    for p in &mut poses.poses[3][VERTICES / 2..] {
        *p += Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
    }
    let result = fit_pose_set(&poses, &labels(), &FitConfig::default(), &NoProgress).unwrap();
    let summary = &result.summary;
    assert_eq!(summary.poses[0].name, "pose3");
    assert_eq!(summary.poses[0].worst_part_name, "right");
    assert_eq!(summary.parts[0].name, "right");
    assert_eq!(summary.parts[0].worst_pose_name, "pose3");
    assert!(summary.poses.windows(2).all(|w| w[0].mean >= w[1].mean));
    let text = summary.describe(2, 1000.0, "mm");
    assert!(text.contains("pose3") && text.contains("right"), "{text}");
}

#[test]
fn a_part_with_two_vertices_is_an_error_naming_part_and_template() {
    let (poses, _) = moved_pose_set(6, 2, 0.0);
    let mut ids: Vec<u32> = (0..VERTICES).map(|v| u32::from(v >= VERTICES / 2)).collect();
    ids[0] = 2;
    ids[1] = 2;
    let labels = PartLabels::try_new(ids, vec!["left".into(), "right".into(), "tiny".into()]).unwrap();
    let err = fit_pose_set(&poses, &labels, &FitConfig::default(), &NoProgress).unwrap_err();
    assert_eq!(
        err,
        FitError::DegeneratePart {
            part: 2,
            part_name: "tiny".into(),
            pose: 0,
            pose_name: "pose0".into(),
            vertices: 2
        }
    );
    assert!(err.to_string().contains("'tiny'") && err.to_string().contains("'pose0'"));
}

#[test]
fn a_pose_that_collapses_a_part_onto_a_line_is_an_error_naming_part_and_pose() {
    let (mut poses, _) = moved_pose_set(7, 3, 0.0);
    for p in &mut poses.poses[2][..VERTICES / 2] {
        *p = Vec3::new(p.x, 0.0, 0.0);
    }
    let err = fit_pose_set(&poses, &labels(), &FitConfig::default(), &NoProgress).unwrap_err();
    match err {
        FitError::DegenerateFit { part, ref part_name, pose, ref pose_name, .. } => {
            assert_eq!((part, part_name.as_str(), pose, pose_name.as_str()), (0, "left", 2, "pose2"));
        }
        other => panic!("unexpected error {other:?}"),
    }
}

#[test]
fn labels_of_the_wrong_length_are_an_error() {
    let (poses, _) = moved_pose_set(8, 1, 0.0);
    let labels = PartLabels::try_new(vec![0; VERTICES - 1], vec!["all".into()]).unwrap();
    let err = fit_pose_set(&poses, &labels, &FitConfig::default(), &NoProgress).unwrap_err();
    assert!(matches!(err, FitError::Labels(_)), "{err:?}");
}

#[test]
fn output_does_not_depend_on_the_thread_count() {
    let (poses, _) = moved_pose_set(9, 8, 0.3);
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| fit_pose_set(&poses, &labels(), &FitConfig::default(), &NoProgress).unwrap())
    };
    assert_eq!(run(1), run(3));
}
