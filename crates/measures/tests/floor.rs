//! The deformation models' own floor at full resolution (issue 17): in-sample and held
//! out, and the held-out / in-sample ratio, for the SCAPE model (centroid or
//! part-anchored placement, fixed or cross-validated ridge) and for LBS, on SCAPE
//! (71 poses, 5 folds; skipped when absent) and on the bundled sample (11 poses,
//! 5 folds). The part motions are stage 1's own fit (desal-fit).
//!
//! The figures are slow in debug builds; run them in release:
//! `cargo test --release -p desal-measures --test floor -- --ignored --nocapture --test-threads 1`

mod common;

use desal_measures::{Anchoring, LbsConfig, ModelConfig, ModelFloor, PoseModel, Regression, model_floor};
use desal_mesh::{PartLabels, PoseSet};

const FOLDS: usize = 5;

/// The SCAPE model before issue 17: fixed ridge, centroid placement.
fn scape_old() -> ModelConfig {
    ModelConfig { regression: Regression::Fixed, anchoring: Anchoring::Centroid, ..ModelConfig::default() }
}

/// Every model variant the report compares, with its row name.
fn variants() -> Vec<(&'static str, PoseModel)> {
    let new = ModelConfig::default();
    vec![
        ("scape fixed ridge, centroid (old)", PoseModel::Scape(scape_old())),
        (
            "scape cv ridge, centroid",
            PoseModel::Scape(ModelConfig { regression: Regression::CrossValidated, ..scape_old() }),
        ),
        ("scape fixed ridge, anchored (default)", PoseModel::Scape(new.clone())),
        (
            "scape cv ridge, anchored",
            PoseModel::Scape(ModelConfig { regression: Regression::CrossValidated, ..new }),
        ),
        ("lbs (default)", PoseModel::Lbs(LbsConfig::default())),
    ]
}

fn print_floor(dataset: &str, name: &str, f: &ModelFloor) {
    eprintln!(
        "{dataset:6} {name:36} in-sample v2v {:.3e} v2f {:.3e} | held-out v2v {:.3e} v2f {:.3e} | ratio v2v {:.2} v2f {:.2}",
        f.in_sample.v2v,
        f.in_sample.v2f,
        f.held_out.v2v,
        f.held_out.v2f,
        f.v2v_ratio(),
        f.v2f_ratio()
    );
}

/// Every variant's floor on one pose set, printed, in `variants()` order.
fn floors(dataset: &str, poses: &PoseSet, labels: &PartLabels) -> Vec<ModelFloor> {
    let transforms = common::part_transforms(poses, labels);
    variants()
        .iter()
        .map(|(name, model)| {
            let floor = model_floor(poses, labels, &transforms, model, FOLDS).unwrap();
            print_floor(dataset, name, &floor);
            floor
        })
        .collect()
}

/// The sample: 11 poses, each moving different joints, so a held-out pose often turns a
/// joint no training pose turned — the small-pose-set case of issue 17.
#[test]
#[ignore = "slow in debug builds; run in release for the reported figures"]
fn sample_floor() {
    let (poses, labels) = common::load_sample();
    let f = floors("sample", &poses, &labels);
    let (old, default, lbs) = (&f[0], &f[2], &f[4]);
    assert_eq!((default.pose_count, default.fold_count), (10, 5));
    // Issue 17's target: the default models' held-out / in-sample ratio below 3 (the
    // old model's is 8.5 in v2v).
    for model in [default, lbs] {
        assert!(model.v2v_ratio() < 3.0 && model.v2f_ratio() < 3.0, "{model:?}");
    }
    assert!(old.v2v_ratio() > 5.0, "{old:?}");
    // Bands around the measured held-out v2v: 1.46e-6 m² (default), 1.22e-6 (LBS),
    // against 4.11e-5 for the old model.
    assert!((1.2e-6..1.8e-6).contains(&default.held_out.v2v), "{default:?}");
    assert!((1.0e-6..1.5e-6).contains(&lbs.held_out.v2v), "{lbs:?}");
}

/// SCAPE, 71 poses, 5 folds.
#[test]
#[ignore = "slow in debug builds; run in release for the reported figures"]
fn scape_floor() {
    let Some((poses, labels)) = desal_testdata::scape() else { return };
    let f = floors("scape", &poses, &labels);
    let (old, default, lbs) = (&f[0], &f[2], &f[4]);
    assert_eq!((default.pose_count, default.fold_count), (70, 5));
    // Bands around the measured held-out v2v: 1.79e-4 m² for the old model (as before
    // issue 17, tests/model.rs), 6.77e-5 for the default, 9.24e-5 for LBS.
    assert!((1.5e-4..2.2e-4).contains(&old.held_out.v2v), "{old:?}");
    assert!((6.0e-5..7.5e-5).contains(&default.held_out.v2v), "{default:?}");
    assert!((8.3e-5..1.0e-4).contains(&lbs.held_out.v2v), "{lbs:?}");
    assert!(default.held_out.v2f < 0.4 * old.held_out.v2f, "default {default:?} vs old {old:?}");
}

/// The sweeps the defaults were chosen from: held-out error of the anchored SCAPE model
/// over the anchor scale, and of LBS over its prior strength and rings.
#[test]
#[ignore = "slow; run in release to re-derive the defaults"]
fn default_sweeps() {
    let sample = common::load_sample();
    let mut sets = vec![("sample", sample.0, sample.1)];
    if let Some((poses, labels)) = desal_testdata::scape() {
        sets.push(("scape", poses, labels));
    }
    for (dataset, poses, labels) in &sets {
        let transforms = common::part_transforms(poses, labels);
        for scale in [0.01, 0.02, 0.03, 0.05, 0.1] {
            let model = PoseModel::Scape(ModelConfig {
                anchoring: Anchoring::Parts { scale },
                ..ModelConfig::default()
            });
            let floor = model_floor(poses, labels, &transforms, &model, FOLDS).unwrap();
            print_floor(dataset, &format!("scape anchored scale {scale}"), &floor);
        }
        for (rings, prior) in [(3, 0.01), (3, 0.1), (3, 1.0), (1, 0.1), (6, 0.1), (10, 0.1)] {
            let model = PoseModel::Lbs(LbsConfig { rings, prior, ..LbsConfig::default() });
            let floor = model_floor(poses, labels, &transforms, &model, FOLDS).unwrap();
            print_floor(dataset, &format!("lbs rings {rings} prior {prior}"), &floor);
        }
    }
}
