//! The deformation model's own floor: its error at full resolution, in-sample and held
//! out, against the pose set it is fitted on — the part of every method's error that no
//! simplification can remove — and the held-out / in-sample ratio that says how much of
//! the held-out figure is extrapolation.
//!
//! Both figures are means over the **non-template** poses (the template is reproduced
//! exactly by construction and would dilute them):
//! - *in-sample*: one model fitted on every pose synthesises each pose;
//! - *held out*: the non-template poses are dealt into `k` folds ([`crate::folds::folds`]); each
//!   fold's model, fitted on the other poses (template included), synthesises the fold.
//!
//! Errors are the paper's v2v (Eq. 7) and v2f (Eq. 6) of the synthesised pose against
//! the true one, in squared mesh units (m² for SCAPE).

use desal_mesh::{PartLabels, PoseSet, Real, TriMesh, Vec3};
use rayon::prelude::*;

use crate::error::EvalError;
use crate::folds::{pose_set_folds, tested_poses, training_poses};
use crate::metrics::{SurfaceIndex, VertexIndex, mean, v2f_halves_same_faces, vertex_faces};
use crate::pose_model::{FittedModel, PoseModel};
use crate::transform::PartTransform;

/// Mean v2v and v2f over a set of poses, squared mesh units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeanErrors {
    pub v2v: Real,
    pub v2f: Real,
}

/// A model's floor on one pose set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelFloor {
    /// Number of poses each mean is over (the non-template poses).
    pub pose_count: usize,
    /// Number of held-out folds actually used (`k` clamped, see [`crate::folds::folds`]).
    pub fold_count: usize,
    pub in_sample: MeanErrors,
    pub held_out: MeanErrors,
}

impl ModelFloor {
    /// Held-out v2v over in-sample v2v.
    pub fn v2v_ratio(&self) -> Real {
        self.held_out.v2v / self.in_sample.v2v
    }

    /// Held-out v2f over in-sample v2f.
    pub fn v2f_ratio(&self) -> Real {
        self.held_out.v2f / self.in_sample.v2f
    }
}

/// Measures `model`'s floor on `poses` with `k` held-out folds. `transforms[pose][part]`
/// is stage 1's rigid motion of each part for every pose; `labels` is in the vertex
/// index space of `poses`. Errors: whatever fitting the model refuses.
pub fn model_floor(
    poses: &PoseSet,
    labels: &PartLabels,
    transforms: &[Vec<PartTransform>],
    model: &PoseModel,
    k: usize,
) -> Result<ModelFloor, EvalError> {
    model_floor_indexed(poses, labels, transforms, model, k, None)
}

/// [`model_floor`] with each pose's surface index given by the caller (`truth[pose]`
/// must index `poses.pose_mesh(pose)`), for a caller that already built them: the same
/// floor.
pub fn model_floor_indexed(
    poses: &PoseSet,
    labels: &PartLabels,
    transforms: &[Vec<PartTransform>],
    model: &PoseModel,
    k: usize,
    truth: Option<&[SurfaceIndex]>,
) -> Result<ModelFloor, EvalError> {
    if let Some(truth) = truth {
        assert_eq!(truth.len(), poses.pose_count(), "one surface index per pose");
    }
    // Over whole groups when the poses have them (the template's group only trains).
    let test_folds = pose_set_folds(poses, k);
    let evaluated = tested_poses(&test_folds);
    let all: Vec<usize> = (0..poses.pose_count()).collect();
    let in_sample = synthesise(poses, labels, transforms, model, &all, &evaluated)?;
    // The folds' fits are independent: in parallel, collected in fold order.
    let fold_poses: Vec<Vec<Vec<Vec3>>> = test_folds
        .par_iter()
        .map(|test| {
            let training = training_poses(poses.pose_count(), test);
            synthesise(poses, labels, transforms, model, &training, test)
        })
        .collect::<Result<_, _>>()?;
    let mut held_out = vec![Vec::new(); poses.pose_count()];
    for (test, synthesised) in test_folds.iter().zip(fold_poses) {
        for (&p, positions) in test.iter().zip(synthesised) {
            held_out[p] = positions;
        }
    }
    let held_out: Vec<Vec<Vec3>> = evaluated.iter().map(|&p| std::mem::take(&mut held_out[p])).collect();
    Ok(ModelFloor {
        pose_count: evaluated.len(),
        fold_count: test_folds.len(),
        in_sample: mean_errors(poses, &evaluated, &in_sample, truth),
        held_out: mean_errors(poses, &evaluated, &held_out, truth),
    })
}

/// Fits `model` on `training` and synthesises the poses `test`, in that order.
fn synthesise(
    poses: &PoseSet,
    labels: &PartLabels,
    transforms: &[Vec<PartTransform>],
    model: &PoseModel,
    training: &[usize],
    test: &[usize],
) -> Result<Vec<Vec<Vec3>>, EvalError> {
    let fitted = model.fit(poses, labels, transforms, training)?;
    synthesise_fitted(&fitted, poses, transforms, test)
}

/// Synthesises the poses `test` of `poses` (in that order) with a fitted model, each
/// from its part motions (`transforms[pose]`) and placed at its centroid where the
/// model places by centroid: how every fold of the floor and of `crate::deform` does.
pub(crate) fn synthesise_fitted(
    fitted: &FittedModel,
    poses: &PoseSet,
    transforms: &[Vec<PartTransform>],
    test: &[usize],
) -> Result<Vec<Vec<Vec3>>, EvalError> {
    let test_transforms: Vec<Vec<PartTransform>> = test.iter().map(|&p| transforms[p].clone()).collect();
    let centroids: Vec<Vec3> = test.iter().map(|&p| centroid(&poses.poses[p])).collect();
    fitted.synthesize_many(&test_transforms, &centroids)
}

/// Mean v2v and v2f of `synthesised[i]` against pose `evaluated[i]`; the per-pose
/// errors are summed in pose order, so the means do not depend on the thread count.
fn mean_errors(
    poses: &PoseSet,
    evaluated: &[usize],
    synthesised: &[Vec<Vec3>],
    truth: Option<&[SurfaceIndex]>,
) -> MeanErrors {
    // The synthesised pose has the target's faces and vertex i lies near target vertex
    // i: every query starts from its own vertex (v2v) or a face of it (v2f).
    let face_seeds = vertex_faces(&poses.faces, poses.vertex_count());
    let vertex_seeds: Vec<u32> = (0..poses.vertex_count() as u32).collect();
    let per_pose: Vec<(Real, Real)> = evaluated
        .par_iter()
        .zip(synthesised)
        .map(|(&p, positions)| {
            let target = poses.pose_mesh(p);
            let deformed = TriMesh { positions: positions.clone(), faces: poses.faces.clone() };
            // `v2f(&deformed, &target)`, with the deformation's index refitted from the
            // target's (same faces, nearby positions) instead of built.
            let built;
            let surface = match truth {
                Some(truth) => &truth[p],
                None => {
                    built = SurfaceIndex::new(&target);
                    &built
                }
            };
            let v2f =
                v2f_halves_same_faces(&deformed, &surface.refit(&deformed), &target, surface, &face_seeds);
            // `v2v(&deformed, &target)`, seeded.
            let v2v = mean(
                &VertexIndex::new(&target.positions).distances_sq_seeded(&deformed.positions, &vertex_seeds),
            );
            (v2v, v2f.combined())
        })
        .collect();
    let n = per_pose.len().max(1) as Real;
    let (v2v_sum, v2f_sum) = per_pose.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
    MeanErrors { v2v: v2v_sum / n, v2f: v2f_sum / n }
}

fn centroid(points: &[Vec3]) -> Vec3 {
    points.iter().sum::<Vec3>() / points.len().max(1) as Real
}
