//! Part discovery on the paper's data (SCAPE, 71 poses × 12500 vertices) with K = 16,
//! against the hand-made 16-part labels (`vertex_part_labels_16.txt`), by the issue's
//! three measures: the adjusted Rand index, the Pearson correlation of the saliency
//! computed from each labelling, and stage 1's mean rigid-fit residual. Also prints the
//! knee curve of a run without K. Skipped, with a printed reason, when the dataset is
//! absent.
//!
//! Measured: ARI 0.767, saliency r 0.763, 13.34 mm against the hand-made 14.52 mm; the
//! sixteen parts match the hand-made ones one to one (each discovered part has most of
//! its vertices in a different hand-made part: `examples/parts_png.rs` prints the
//! table). The residual target (no higher than the hand-made parts) is met; the
//! issue's ARI >= 0.8 and r >= 0.9 are NOT: the assertions below hold the reached
//! figures (with a small margin) so that a regression fails, and do not claim the
//! issue's. Why they are out of reach for parts judged by the rigid-fit residual: the
//! hand-made parts themselves, their borders relaxed by this crate's rule
//! (`scape_relaxing_the_hand_made_borders`), fall to 13.34 mm but move to ARI 0.773 and
//! saliency r 0.779 against their own starting point — the torso's chest/stomach/hip
//! borders and the shoulders are soft, and the residual optimum puts those borders
//! elsewhere than the hand did.
//!
//! Figures: `cargo test --release -p desal-parts --test scape -- --nocapture`.

mod common;

use desal_fit::{FitConfig, FitResult, fit_pose_set};
use desal_mesh::math::Real;
use desal_mesh::{NoProgress, PartLabels, PoseSet};
use desal_parts::{PartsConfig, PartsReport, adjusted_rand_index, discover_parts, refine_parts};
use desal_saliency::{ResidualTable, SaliencyConfig, compute_saliency};

fn fit(poses: &PoseSet, labels: &PartLabels) -> FitResult {
    fit_pose_set(poses, labels, &FitConfig::default(), &NoProgress).expect("stage 1 accepts the parts")
}

/// Stage 2 with its defaults (the paper's: plain distances, max-normalised).
fn saliency(poses: &PoseSet, fit: &FitResult) -> Vec<Real> {
    let table = ResidualTable {
        values: &fit.residuals,
        vertex_count: fit.vertex_count,
        pose_names: &fit.pose_names,
        template: Some(fit.template),
        length_scale: poses.template_mesh().diagonal(),
    };
    compute_saliency(&table, &SaliencyConfig::default()).unwrap().saliency
}

fn pearson(a: &[Real], b: &[Real]) -> Real {
    let n = a.len() as Real;
    let (ma, mb) = (a.iter().sum::<Real>() / n, b.iter().sum::<Real>() / n);
    let cov: Real = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: Real = a.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: Real = b.iter().map(|y| (y - mb).powi(2)).sum();
    cov / (va * vb).sqrt()
}

fn print_curve(report: &PartsReport) {
    eprintln!("knee curve (parts: mean residual mm), chosen {}:", report.curve[report.chosen].parts);
    for point in &report.curve {
        eprintln!("  {:>3}: {:8.3}", point.parts, point.mean_residual * 1e3);
    }
}

#[test]
#[cfg_attr(
    not(desal_shared_data),
    ignore = "needs ../shared/datasets beside the checkout (development and CI only)"
)]
fn scape_sixteen_parts_match_the_hand_made_ones() {
    let Some((poses, given)) = desal_testdata::scape() else { return };
    let config = PartsConfig { parts: Some(16), ..PartsConfig::default() };
    let (auto, report) = discover_parts(&poses, &config).unwrap();
    print_curve(&report);
    eprintln!("part sizes: {:?} ({} border sweeps)", report.part_sizes, report.sweeps);
    assert_eq!(auto.part_count(), 16);
    common::assert_connected_parts(&poses, &auto);
    assert!(report.part_sizes.iter().all(|&n| n >= config.min_part_vertices), "{:?}", report.part_sizes);

    let ari = adjusted_rand_index(&auto.labels, &given.labels);
    let (fit_auto, fit_given) = (fit(&poses, &auto), fit(&poses, &given));
    let r = pearson(&saliency(&poses, &fit_auto), &saliency(&poses, &fit_given));
    let (mm_auto, mm_given) = (fit_auto.summary.mean_residual * 1e3, fit_given.summary.mean_residual * 1e3);
    eprintln!("ARI {ari:.3}, saliency r {r:.3}, mean residual {mm_auto:.3} mm (hand-made {mm_given:.3} mm)");
    // The report's residual is stage 1's, computed independently here.
    assert!(
        (report.mean_residual * 1e3 - mm_auto).abs() < 1e-6,
        "{} vs {mm_auto}",
        report.mean_residual * 1e3
    );
    assert!(ari >= 0.75, "ARI {ari}");
    assert!(r >= 0.74, "saliency r {r}");
    assert!(mm_auto <= mm_given, "{mm_auto} mm > {mm_given} mm");
}

#[test]
#[cfg_attr(
    not(desal_shared_data),
    ignore = "needs ../shared/datasets beside the checkout (development and CI only)"
)]
fn scape_knee_curve() {
    let Some((poses, _)) = desal_testdata::scape() else { return };
    let (auto, report) = discover_parts(&poses, &PartsConfig::default()).unwrap();
    print_curve(&report);
    assert_eq!(auto.part_count(), report.curve[report.chosen].parts);
    // The curve falls from one rigid body to many parts.
    assert!(report.curve.len() >= 10);
    assert!(report.curve.last().unwrap().mean_residual < 0.5 * report.curve[0].mean_residual);
}

/// The figure behind the module doc's "why": the hand-made parts, their borders relaxed
/// by discovery's own rule (up to 200 sweeps), fit better but move away from themselves.
#[test]
#[cfg_attr(
    not(desal_shared_data),
    ignore = "needs ../shared/datasets beside the checkout (development and CI only)"
)]
fn scape_relaxing_the_hand_made_borders() {
    let Some((poses, given)) = desal_testdata::scape() else { return };
    let config = PartsConfig { relax_sweeps: 200, ..PartsConfig::default() };
    let (refined, report) = refine_parts(&poses, &given, &config).unwrap();
    let ari = adjusted_rand_index(&refined.labels, &given.labels);
    let (fit_given, fit_refined) = (fit(&poses, &given), fit(&poses, &refined));
    let (before, after) = (fit_given.summary.mean_residual * 1e3, fit_refined.summary.mean_residual * 1e3);
    let r = pearson(&saliency(&poses, &fit_refined), &saliency(&poses, &fit_given));
    eprintln!(
        "hand-made parts relaxed: {before:.3} mm -> {after:.3} mm in {} sweeps; ARI {ari:.3}, saliency r {r:.3} against themselves",
        report.sweeps
    );
    assert!(after < before);
    assert!(ari < 0.8, "relaxed hand-made parts stay within ARI {ari} of themselves");
}

/// The real data at full size: one and two rayon threads give the same labels and the
/// same knee curve, bit for bit.
#[test]
#[cfg_attr(
    not(desal_shared_data),
    ignore = "needs ../shared/datasets beside the checkout (development and CI only)"
)]
fn scape_labels_do_not_depend_on_the_thread_count() {
    let Some((poses, _)) = desal_testdata::scape() else { return };
    let config = PartsConfig { parts: Some(16), ..PartsConfig::default() };
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| discover_parts(&poses, &config).unwrap())
    };
    let ((one, report_one), (two, report_two)) = (run(1), run(2));
    assert_eq!(one, two);
    let bits = |r: &PartsReport| {
        r.curve
            .iter()
            .map(|c| c.mean_residual.to_bits())
            .chain([r.mean_residual.to_bits()])
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&report_one), bits(&report_two));
}
