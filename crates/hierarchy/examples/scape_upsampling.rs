//! The SCAPE figures of issue 13: held-out upsampling error of two-level hierarchies
//! ([2500, 625]) for COMA's recipe (plain QSlim subset + barycentric U) and the paper's
//! method (saliency + balance subset) with the barycentric and the fitted U, saliency
//! recomputed per level or carried down; and, with `--tune`, the neighbour/ridge curve
//! that chose the fitted upsampler's defaults.
//!
//! `cargo run --release -p desal-hierarchy --example scape_upsampling [-- --tune]`
//!
//! Held out: the upsamplers are fitted on the even poses (the template, pose 0, among
//! them) and measured on the odd ones. The tuning never sees the odd poses: it fits on
//! poses ≡ 0 (mod 4) and validates on poses ≡ 2 (mod 4).

#[path = "../tests/common/mod.rs"]
mod common;

use common::{LevelGeometry, Method, SaliencyPerLevel, build_geometry, build_levels, composed};
use desal_hierarchy::{FittedConfig, Neighbourhood, Upsampler, upsampling_error, upsampling_mse};
use desal_mesh::PoseSet;

const LEVELS: [usize; 2] = [2500, 625];

fn main() {
    let Some((full, labels)) = desal_testdata::scape() else { return };
    let tune = std::env::args().any(|a| a == "--tune");
    let poses = full.pose_count();
    let even: Vec<usize> = (0..poses).filter(|p| p % 2 == 0).collect();
    let odd: Vec<usize> = (0..poses).filter(|p| p % 2 == 1).collect();

    let qslim = build_geometry(&full, &labels, &LEVELS, Method::Qslim, SaliencyPerLevel::Recompute);
    let paper = build_geometry(&full, &labels, &LEVELS, Method::Paper, SaliencyPerLevel::Recompute);
    let carried = build_geometry(&full, &labels, &LEVELS, Method::Paper, SaliencyPerLevel::CarryDown);

    if tune {
        let fit: Vec<usize> = (0..poses).filter(|p| p % 4 == 0).collect();
        let validate: Vec<usize> = (0..poses).filter(|p| p % 4 == 2).collect();
        println!(
            "tuning on the paper hierarchy: fit on poses = 0 mod 4 ({}), validate on 2 mod 4 ({})",
            fit.len(),
            validate.len()
        );
        println!("held-out MSE (1e-6 m^2) at 2500 | at 625 composed; barycentric for reference:");
        let bary = mse_pair(&full, &paper, &fit, &validate, &Upsampler::Barycentric);
        println!("  barycentric                 {:>8.3} | {:>8.3}", bary.0 * 1e6, bary.1 * 1e6);
        for neighbourhood in [Neighbourhood::Geodesic, Neighbourhood::Euclidean] {
            for &neighbours in &[6usize, 8, 12, 16, 20, 24, 32] {
                for &ridge in &[0.0, 1e-3, 3e-3, 1e-2, 3e-2] {
                    let up = Upsampler::Fitted(FittedConfig {
                        neighbourhood,
                        ..FittedConfig::given(neighbours, ridge)
                    });
                    let (a, b) = mse_pair(&full, &paper, &fit, &validate, &up);
                    println!(
                        "  {neighbourhood:?} k = {neighbours:>2}, ridge = {ridge:<6} {:>8.3} | {:>8.3}   ratio {:.3} | {:.3}",
                        a * 1e6,
                        b * 1e6,
                        a / bary.0,
                        b / bary.1
                    );
                }
            }
        }
        println!();
    }

    println!(
        "held out: fit on the {} even poses, measure on the {} odd poses; errors in 1e-6 m^2",
        even.len(),
        odd.len()
    );
    println!(
        "{:<34} {:>10} {:>10} {:>12} {:>12}",
        "hierarchy / upsampler", "MSE 2500", "v2f 2500", "MSE 625", "v2f 625"
    );
    let fitted = Upsampler::default();
    let mut rows = Vec::new();
    for (name, geometry) in
        [("qslim", &qslim), ("paper (saliency per level)", &paper), ("paper (saliency carried)", &carried)]
    {
        for up in [Upsampler::Barycentric, fitted] {
            let levels = build_levels(&full, geometry, &even, &up);
            let e1 =
                upsampling_error(&full, &composed(&levels, 0), &geometry[0].orig, &odd).expect("measure");
            let e2 =
                upsampling_error(&full, &composed(&levels, 1), &geometry[1].orig, &odd).expect("measure");
            let (v1, v2) = (e1.v2f.expect("measured"), e2.v2f.expect("measured"));
            println!(
                "{:<34} {:>10.3} {:>10.3} {:>12.3} {:>12.3}",
                format!("{name} / {}", up.name()),
                e1.mse * 1e6,
                v1 * 1e6,
                e2.mse * 1e6,
                v2 * 1e6
            );
            rows.push((name, up.name(), e1.mse, e2.mse, v1, v2));
        }
    }
    let find = |n: &str, u: &str| rows.iter().find(|r| r.0 == n && r.1 == u).expect("row");
    for name in ["qslim", "paper (saliency per level)", "paper (saliency carried)"] {
        let (b, f) = (find(name, "barycentric"), find(name, "fitted"));
        println!(
            "{name}: fitted / barycentric MSE = {:.3} at 2500, {:.3} at 625 (v2f {:.3}, {:.3})",
            f.2 / b.2,
            f.3 / b.3,
            f.4 / b.4,
            f.5 / b.5
        );
    }
    let coma = find("qslim", "barycentric");
    for name in ["paper (saliency per level)", "paper (saliency carried)"] {
        let ours = find(name, "fitted");
        println!(
            "{name} + fitted vs COMA's recipe (qslim + barycentric): MSE {:.1} % lower at 2500, {:.1} % at 625",
            100.0 * (1.0 - ours.2 / coma.2),
            100.0 * (1.0 - ours.3 / coma.3)
        );
    }
}

/// Held-out MSE at level 1 and level 2 (composed), fitted on `fit`, measured on `test`
/// (MSE only: the tuning loop skips v2f's surface queries).
fn mse_pair(
    full: &PoseSet,
    geometry: &[LevelGeometry],
    fit: &[usize],
    test: &[usize],
    up: &Upsampler,
) -> (f64, f64) {
    let levels = build_levels(full, geometry, fit, up);
    let mse = |k: usize| -> f64 {
        let per_pose = upsampling_mse(full, &composed(&levels, k), &geometry[k].orig, test).expect("measure");
        per_pose.iter().sum::<f64>() / per_pose.len() as f64
    };
    (mse(0), mse(1))
}
