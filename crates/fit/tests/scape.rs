//! Stage 1 on the paper's data (SCAPE, 71 poses × 12500 vertices), checked against the
//! independently measured figure in `../shared/datasets/README.md`: after a per-part
//! Kabsch fit, the mean per-vertex residual over the 70 non-template poses is about
//! 14.5 mm. Skipped, with a printed reason, when the dataset is absent.

use std::time::Instant;

use desal_fit::{FitConfig, FitModel, fit_pose_set};
use desal_mesh::{NoProgress, PartLabels, PoseSet};

fn load_scape() -> Option<(PoseSet, PartLabels)> {
    desal_testdata::scape()
}

#[test]
#[cfg_attr(
    not(desal_shared_data),
    ignore = "needs ../shared/datasets beside the checkout (development and CI only)"
)]
fn scape_mean_residual_is_about_14_5_mm() {
    let Some((poses, labels)) = load_scape() else { return };
    assert_eq!((poses.pose_count(), poses.vertex_count()), (71, 12500));

    let start = Instant::now();
    let rigid = fit_pose_set(&poses, &labels, &FitConfig::default(), &NoProgress).unwrap();
    eprintln!("fit (rigid) of 71 SCAPE poses: {:.2} ms", start.elapsed().as_secs_f64() * 1e3);
    eprint!("{}", rigid.summary.describe(5, 1000.0, "mm"));

    let mean_mm = rigid.summary.mean_residual * 1e3;
    assert!((14.47..14.58).contains(&mean_mm), "mean residual {mean_mm} mm");
    // The same figure straight from the stored f32 residuals.
    let posed = (0..71).filter(|&p| p != poses.template);
    let total: f64 = posed.flat_map(|p| rigid.pose_residuals(p).iter().map(|&r| r as f64)).sum();
    assert!((total / (70.0 * 12500.0) * 1e3 - mean_mm).abs() < 1e-3);

    // Rotations are proper.
    for fits in &rigid.part_fits {
        for fit in fits {
            assert!((fit.linear.determinant() - 1.0).abs() < 1e-9);
        }
    }

    let start = Instant::now();
    let config = FitConfig { model: FitModel::Affine, ..FitConfig::default() };
    let affine = fit_pose_set(&poses, &labels, &config, &NoProgress).unwrap();
    eprintln!(
        "fit (affine) of 71 SCAPE poses: {:.2} ms, mean residual {:.3} mm",
        start.elapsed().as_secs_f64() * 1e3,
        affine.summary.mean_residual * 1e3
    );
    assert!(affine.summary.rms_residual <= rigid.summary.rms_residual);
}
