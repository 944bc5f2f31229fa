//! Which deformation model a dataset is evaluated with (`desal eval --model`), and the
//! one call that deforms a method's simplified set with it: a fitted pose model
//! (`measure::deform`: SCAPE or LBS with the parts as bones) or, for a rig dataset, the
//! rig's own skinning ([`crate::rig`]).

use anyhow::{Context, Result, bail};
use desal_measures::PoseModel;

use crate::measure::{self, Deformed};
use crate::methods::{Inputs, SimplifiedSet};
use crate::rig::SkinnedSet;

/// The rig's own linear blend skinning (rig datasets only).
pub const RIG: &str = "rig";

/// A dataset's deformation model.
#[derive(Debug, Clone)]
pub enum EvalModel {
    /// A model fitted on the simplified set's poses.
    Pose(PoseModel),
    /// The rig's skinning, with the simplified rig's own weights.
    Rig,
}

/// Every `--model` name, for messages.
pub fn names() -> String {
    let mut names: Vec<&str> = measure::MODELS.to_vec();
    names.push(RIG);
    names.join(", ")
}

/// Checks a `--model` name before anything runs.
pub fn check(name: Option<&str>) -> Result<()> {
    match name {
        None | Some(RIG) => Ok(()),
        Some(other) => Ok(measure::pose_model(other).map(|_| ())?),
    }
}

/// The model named `name` for a dataset (`is_rig`: it has a `[dataset.rig]`), and its
/// name. Unnamed: `rig` for a rig dataset (what an engine does with the result), else
/// [`measure::DEFAULT_MODEL`].
pub fn resolve(name: Option<&str>, is_rig: bool) -> Result<(String, EvalModel)> {
    let name = name.unwrap_or(if is_rig { RIG } else { measure::DEFAULT_MODEL });
    if name == RIG {
        if !is_rig {
            bail!(
                "--model rig skins with a rig's own weights: only a [dataset.rig] dataset has them (use {})",
                measure::MODELS.join(", ")
            );
        }
        return Ok((name.to_owned(), EvalModel::Rig));
    }
    Ok((name.to_owned(), EvalModel::Pose(measure::pose_model(name)?)))
}

impl EvalModel {
    /// Deforms `set` to every pose, in-sample and per fold of `folds`.
    pub fn deform(&self, inputs: &Inputs, set: &SimplifiedSet, folds: &[Vec<usize>]) -> Result<Deformed> {
        match self {
            EvalModel::Pose(model) => {
                Ok(measure::deform(&set.mapped.poses, &set.mapped.labels, folds, model)?)
            }
            EvalModel::Rig => {
                let rig = inputs.rig.as_ref().context("the rig model needs a [dataset.rig] dataset")?;
                let skinned = SkinnedSet {
                    positions: &set.raw.positions,
                    simp_to_welded: &set.mapped.map.simp_to_orig,
                    subset: set.mapped.report.mode == "subset",
                    own: set.skin.as_ref(),
                    poses: &set.mapped.poses,
                };
                rig.deform(&skinned, folds)
            }
        }
    }

    /// The fitted pose model, whose floor at full resolution is worth measuring (the
    /// rig's skinning at full resolution *is* the ground truth).
    pub fn pose_model(&self) -> Option<&PoseModel> {
        match self {
            EvalModel::Pose(model) => Some(model),
            EvalModel::Rig => None,
        }
    }
}
