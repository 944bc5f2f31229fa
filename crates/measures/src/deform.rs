//! The deformation models by name, and the deformation of a whole pose set, that
//! `desal-refit` (stage 3) and `desal eval` share: stage 1's
//! rigid motion of every part drives a pose model (SCAPE part-anchored by default,
//! SCAPE placed at the ground truth's centroid as in the paper, or LBS), fitted on all
//! poses (in-sample) and once per fold without the fold's poses (held-out; the template
//! always trains), which synthesises each pose from its part motions ([`deform`]).

use std::time::Instant;

use desal_mesh::{PartLabels, PoseSet, Vec3};
use serde::Serialize;
use thiserror::Error;

use crate::error::EvalError;
use crate::floor::synthesise_fitted;
use crate::model::{ModelConfig, ModelReport};
use crate::pose_model::{FittedModel, PoseModel};
use crate::transform::PartTransform;

/// What can go wrong deforming a pose set by a named model.
#[derive(Debug, Error)]
pub enum DeformError {
    #[error("unknown deformation model '{0}': use {models}", models = MODELS.join(", "))]
    UnknownModel(String),
    /// Stage 1 (the rigid fit that drives every model) failed on the set.
    #[error("stage 1 on the simplified pose set")]
    PartMotions(#[source] desal_fit::FitError),
    /// Fitting the model named `what` (the in-sample model, or a fold's).
    #[error("fitting the {what}")]
    Fit {
        what: String,
        #[source]
        source: EvalError,
    },
    /// Synthesising the poses with the model named `what`.
    #[error("synthesising with the {what}")]
    Synthesis {
        what: String,
        #[source]
        source: EvalError,
    },
}

type Result<T> = std::result::Result<T, DeformError>;

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
/// placed by the centroid and 9.24e-5 for LBS; `crates/measures/tests/floor.rs`).
pub const DEFAULT_MODEL: &str = "scape";

/// The deformation model named `name` (one of [`MODELS`]).
pub fn pose_model(name: &str) -> Result<PoseModel> {
    Ok(match name {
        "scape" => PoseModel::Scape(ModelConfig::default()),
        "scape-cv" => PoseModel::Scape(ModelConfig {
            regression: crate::Regression::CrossValidated,
            ..ModelConfig::default()
        }),
        "scape-centroid" => PoseModel::Scape(ModelConfig {
            anchoring: crate::model::Anchoring::Centroid,
            ..ModelConfig::default()
        }),
        "lbs" => PoseModel::Lbs(crate::lbs::LbsConfig::default()),
        other => return Err(DeformError::UnknownModel(other.to_owned())),
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
    let transforms = part_motions(set, labels)?;
    let rotation_seconds = started.elapsed().as_secs_f64();
    let inputs = ModelInputs { set, labels, transforms: &transforms, model };

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
    let fit = desal_fit::fit_pose_set(set, labels, &desal_fit::FitConfig::default(), &desal_mesh::NoProgress)
        .map_err(DeformError::PartMotions)?;
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
    model: &'a PoseModel,
}

impl ModelInputs<'_> {
    /// Fits one model on every pose but `test` (on every pose when `fold` is `None`) and
    /// synthesises the poses `test`, in that order.
    fn fit_and_synthesise(&self, fold: Option<usize>, test: &[usize]) -> Result<(ModelRun, Vec<Vec<Vec3>>)> {
        let set = self.set;
        let training = match fold {
            None => (0..set.pose_count()).collect(),
            Some(_) => crate::folds::training_poses(set.pose_count(), test),
        };
        let what = fold.map_or_else(|| "in-sample model".to_owned(), |k| format!("model of fold {k}"));
        let started = Instant::now();
        let model = self
            .model
            .fit(set, self.labels, self.transforms, &training)
            .map_err(|source| DeformError::Fit { what: what.clone(), source })?;
        let fit_seconds = started.elapsed().as_secs_f64();
        let started = Instant::now();
        let synthesised = synthesise_fitted(&model, set, self.transforms, test)
            .map_err(|source| DeformError::Synthesis { what, source })?;
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
