//! One interface over the two deformation models — SCAPE ([`crate::model`]) and LBS
//! ([`crate::lbs`]) — so that the same folds, metrics and tables apply to both: fit on
//! training poses from the parts' rigid motions, synthesise poses from them.

use desal_mesh::{PartLabels, PoseSet, Vec3};

use crate::error::EvalError;
use crate::lbs::{LbsConfig, LbsModel, fit_lbs};
use crate::model::{Model, ModelConfig, fit_model};
use crate::transform::{PartTransform, rotations_of};

/// Which deformation model, with its settings.
#[derive(Debug, Clone, PartialEq)]
pub enum PoseModel {
    /// The SCAPE pose-deformation model (placement by [`ModelConfig::anchoring`]).
    Scape(ModelConfig),
    /// Linear blend skinning with the parts as bones.
    Lbs(LbsConfig),
}

/// A fitted [`PoseModel`].
#[derive(Debug)]
pub enum FittedModel {
    /// Boxed: the SCAPE model's solvers make it far larger than an LBS model.
    Scape(Box<Model>),
    Lbs(LbsModel),
}

impl PoseModel {
    /// A stable lower-case name for reports: `scape` or `lbs`.
    pub fn name(&self) -> &'static str {
        match self {
            PoseModel::Scape(_) => "scape",
            PoseModel::Lbs(_) => "lbs",
        }
    }

    /// Fits the model on the poses `training_poses` of `poses`, with
    /// `transforms[pose][part]` stage 1's rigid motion of each part for every pose of the
    /// set (only the training poses are read) and `labels` in the same vertex index space.
    pub fn fit(
        &self,
        poses: &PoseSet,
        labels: &PartLabels,
        transforms: &[Vec<PartTransform>],
        training_poses: &[usize],
    ) -> Result<FittedModel, EvalError> {
        match self {
            PoseModel::Scape(config) => {
                let rotations: Vec<_> = transforms.iter().map(|t| rotations_of(t)).collect();
                Ok(FittedModel::Scape(Box::new(fit_model(
                    poses,
                    labels,
                    &rotations,
                    training_poses,
                    config,
                )?)))
            }
            PoseModel::Lbs(config) => {
                Ok(FittedModel::Lbs(fit_lbs(poses, labels, transforms, training_poses, config)?))
            }
        }
    }
}

impl FittedModel {
    /// Synthesises pose `i` from `transforms[i]` for every `i`, in parallel, in order.
    /// `target_centroids[i]` is only read by a SCAPE model placed by its centroid
    /// ([`crate::Anchoring::Centroid`]); LBS and an anchored SCAPE model place the pose by
    /// the parts' translations.
    pub fn synthesize_many(
        &self,
        transforms: &[Vec<PartTransform>],
        target_centroids: &[Vec3],
    ) -> Result<Vec<Vec<Vec3>>, EvalError> {
        match self {
            FittedModel::Scape(model) => model.synthesize_from_parts_many(transforms, target_centroids),
            FittedModel::Lbs(model) => {
                if transforms.len() != target_centroids.len() {
                    return Err(EvalError::TargetCountMismatch {
                        rotations: transforms.len(),
                        centroids: target_centroids.len(),
                    });
                }
                model.synthesize_many(transforms)
            }
        }
    }

    pub fn vertex_count(&self) -> usize {
        match self {
            FittedModel::Scape(model) => model.vertex_count(),
            FittedModel::Lbs(model) => model.vertex_count(),
        }
    }
}
