//! The deformation model that stage 3's `desal-refit` and `desal eval` share: stage 1's
//! rigid motion of every part drives a pose model (SCAPE part-anchored by default,
//! SCAPE placed at the ground truth's centroid as in the paper, or LBS), fitted on all
//! poses (in-sample) and once per fold without the fold's poses (held-out; the template
//! always trains), which synthesises each pose from its part motions ([`deform`]).

use std::time::Instant;

use anyhow::{Context, Result};
use desal_eval::{FittedModel, ModelConfig, ModelReport, PartTransform, PoseModel};
use desal_mesh::{PartLabels, PoseSet, Vec3};
use serde::Serialize;

/// One fitted model and what it was used for.
#[derive(Debug, Clone, Serialize)]
pub struct ModelRun {
    /// `None` for the in-sample model, else the fold index.
    pub fold: Option<usize>,
    /// Pose indices the model was fitted on (ascending), exactly as passed to the fit.
    pub training_poses: Vec<usize>,
    /// Pose indices it synthesised for measurement.
    pub test_poses: Vec<usize>,
    /// SCAPE: joints of the part tree; LBS: bones (the parts).
    pub joint_count: usize,
    /// SCAPE: mean squared Frobenius residual of the per-triangle regression
    /// (dimensionless); LBS: mean squared skinning residual over the training poses
    /// (squared input units).
    pub mean_q_residual: f64,
    /// SCAPE: nonzeros of the Poisson factor; LBS: 0.
    pub factor_nonzeros: usize,
    /// Wall time of the model fit, seconds.
    pub fit_seconds: f64,
    /// Wall time of synthesising all `test_poses`, seconds.
    pub synthesis_seconds: f64,
}

/// Every pose of one simplified set, deformed by the model.
#[derive(Debug)]
pub struct Deformed {
    /// Per pose: synthesised by the model fitted on all poses.
    pub in_sample: Vec<Vec<Vec3>>,
    /// Per pose: synthesised by the model of the fold holding it out; `None` for the
    /// template (never held out).
    pub held_out: Vec<Option<Vec<Vec3>>>,
    /// Per pose: the fold that tests it (`None` for the template).
    pub fold_of_pose: Vec<Option<usize>>,
    /// The in-sample model first, then one per fold.
    pub models: Vec<ModelRun>,
    /// Wall time of the rigid fit on the simplified set, seconds.
    pub rotation_seconds: f64,
}

/// The deformation models `desal eval --model` offers, by name.
pub const MODELS: &[&str] = &["scape", "scape-cv", "scape-centroid", "lbs"];

/// The model `desal eval` uses when none is named: the part-anchored SCAPE model, the
/// lowest held-out error at full resolution on SCAPE (6.77e-5 m² v2v, against 1.79e-4
/// placed by the centroid and 9.24e-5 for LBS; `crates/eval/tests/floor.rs`).
pub const DEFAULT_MODEL: &str = "scape";

/// The deformation model named `name` (one of [`MODELS`]).
pub fn pose_model(name: &str) -> Result<PoseModel> {
    Ok(match name {
        "scape" => PoseModel::Scape(ModelConfig::default()),
        "scape-cv" => PoseModel::Scape(ModelConfig {
            regression: desal_eval::Regression::CrossValidated,
            ..ModelConfig::default()
        }),
        "scape-centroid" => PoseModel::Scape(ModelConfig {
            anchoring: desal_eval::Anchoring::Centroid,
            ..ModelConfig::default()
        }),
        "lbs" => PoseModel::Lbs(desal_eval::LbsConfig::default()),
        other => anyhow::bail!("unknown deformation model '{other}': use {}", MODELS.join(", ")),
    })
}

/// Fits `model` on `set` (in-sample and per fold of `folds`, each a list of test poses
/// that excludes the template) and deforms the template to every pose. Every model is
/// driven by stage 1's rigid motion of each part, fitted on this set.
pub fn deform(
    set: &PoseSet,
    labels: &PartLabels,
    folds: &[Vec<usize>],
    model: &PoseModel,
) -> Result<Deformed> {
    let started = Instant::now();
    let transforms = part_motions(set, labels).context("stage 1 on the simplified pose set")?;
    let rotation_seconds = started.elapsed().as_secs_f64();
    let centroids: Vec<Vec3> = set.poses.iter().map(|p| centroid(p)).collect();
    let inputs = ModelInputs { set, labels, transforms: &transforms, centroids: &centroids, model };

    let all_poses: Vec<usize> = (0..set.pose_count()).collect();
    let (in_sample_run, in_sample) = inputs.fit_and_synthesise(None, &all_poses)?;
    let mut models = vec![in_sample_run];
    let mut held_out = vec![None; set.pose_count()];
    let mut fold_of_pose = vec![None; set.pose_count()];
    for (k, test) in folds.iter().enumerate() {
        debug_assert!(!test.contains(&set.template), "the template always trains");
        let (run, synthesised) = inputs.fit_and_synthesise(Some(k), test)?;
        for (&pose, positions) in test.iter().zip(synthesised) {
            held_out[pose] = Some(positions);
            fold_of_pose[pose] = Some(k);
        }
        models.push(run);
    }
    Ok(Deformed { in_sample, held_out, fold_of_pose, models, rotation_seconds })
}

/// Stage 1's rigid motion of every part in every pose of `set` (`[pose][part]`), what
/// every deformation model is driven by.
pub fn part_motions(set: &PoseSet, labels: &PartLabels) -> Result<Vec<Vec<PartTransform>>> {
    let fit =
        desal_fit::fit_pose_set(set, labels, &desal_fit::FitConfig::default(), &desal_mesh::NoProgress)?;
    Ok(fit
        .part_fits
        .iter()
        .map(|parts| {
            parts.iter().map(|f| PartTransform { rotation: f.linear, translation: f.translation }).collect()
        })
        .collect())
}

/// What every fit of one set's model reads.
struct ModelInputs<'a> {
    set: &'a PoseSet,
    labels: &'a PartLabels,
    transforms: &'a [Vec<PartTransform>],
    centroids: &'a [Vec3],
    model: &'a PoseModel,
}

impl ModelInputs<'_> {
    /// Fits one model on every pose but `test` (on every pose when `fold` is `None`) and
    /// synthesises the poses `test`, in that order.
    fn fit_and_synthesise(&self, fold: Option<usize>, test: &[usize]) -> Result<(ModelRun, Vec<Vec<Vec3>>)> {
        let set = self.set;
        let training = match fold {
            None => (0..set.pose_count()).collect(),
            Some(_) => desal_eval::training_poses(set.pose_count(), test),
        };
        let what = fold.map_or_else(|| "in-sample model".to_owned(), |k| format!("model of fold {k}"));
        let started = Instant::now();
        let model = self
            .model
            .fit(set, self.labels, self.transforms, &training)
            .with_context(|| format!("fitting the {what}"))?;
        let fit_seconds = started.elapsed().as_secs_f64();
        let started = Instant::now();
        let test_transforms: Vec<Vec<PartTransform>> =
            test.iter().map(|&p| self.transforms[p].clone()).collect();
        let test_centroids: Vec<Vec3> = test.iter().map(|&p| self.centroids[p]).collect();
        let synthesised = model
            .synthesize_many(&test_transforms, &test_centroids)
            .with_context(|| format!("synthesising with the {what}"))?;
        let synthesis_seconds = started.elapsed().as_secs_f64();
        let (joint_count, mean_q_residual, factor_nonzeros) = match &model {
            FittedModel::Scape(m) => {
                let ModelReport { joint_count, mean_q_residual, factor_nonzeros, .. } = *m.report();
                (joint_count, mean_q_residual, factor_nonzeros)
            }
            FittedModel::Lbs(m) => (self.labels.part_count(), m.report().mean_fit_residual, 0),
        };
        let run = ModelRun {
            fold,
            training_poses: training,
            test_poses: test.to_vec(),
            joint_count,
            mean_q_residual,
            factor_nonzeros,
            fit_seconds,
            synthesis_seconds,
        };
        Ok((run, synthesised))
    }
}

fn centroid(points: &[Vec3]) -> Vec3 {
    points.iter().sum::<Vec3>() / points.len() as f64
}
