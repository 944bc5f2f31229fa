//! The upsampling error of every method (issue 13): how well each method's simplified
//! mesh, with an upsampler U, brings a pose back to full resolution — a measure of the
//! simplification free of any pose model — and how well it brings back the *deformed*
//! coarse mesh, which is how mesh networks use a hierarchy (they predict the coarse mesh
//! and upsample it).
//!
//! Per method, the simplified mesh is one level below the input (`map` = `orig` = the
//! method's `simp_to_orig`). Per held-out fold of `desal eval`, U is built on the fold's
//! training poses only (`desal_hierarchy::composed_upsamplers`, the hierarchy stage's
//! path): COMA's barycentric U (template only, so one for all folds) and the fitted U
//! (`stages::hierarchy::measured_fitted`), every fold's at once
//! (`composed_upsamplers_per_mask`: the same rows up to rounding, a fifth of the sums).
//! On each of the fold's test poses, `desal_hierarchy::upsampling_errors` measures, against the full-resolution pose, mean
//! squared vertex distance and v2f (m²):
//! - `ground_truth`: U · (the pose at `orig`), the upsampling error proper;
//! - `deformed`: U · (the held-out deformed coarse pose of [`crate::measure::deform`]).

use anyhow::{Context, Result};
use desal_hierarchy::{
    ChainLevel, Coarse, CsrMatrix, Upsampled, Upsampler, composed_upsamplers, composed_upsamplers_per_mask,
    upsampling_errors_indexed,
};
use desal_measures::SurfaceIndex;
use desal_mesh::{PoseSet, Vec3};
use serde::Serialize;

use crate::measure::{Deformed, MeanStd};
use crate::methods::SimplifiedSet;

/// One pose's upsampling errors (m²).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct MseV2f {
    pub mse: f64,
    pub v2f: f64,
}

/// One pose, one upsampler: the ground truth and the held-out deformation upsampled.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct PoseUpsampling {
    pub ground_truth: MseV2f,
    pub deformed: MseV2f,
}

/// One pose, both upsamplers.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct PoseUpsamplers {
    pub barycentric: PoseUpsampling,
    pub fitted: PoseUpsampling,
}

/// Mean ± standard deviation over the evaluated poses of one upsampler's figures.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct UpsamplingSummary {
    pub ground_truth_mse: MeanStd,
    pub ground_truth_v2f: MeanStd,
    pub deformed_mse: MeanStd,
    pub deformed_v2f: MeanStd,
}

/// `eval.json`'s `methods[].upsampling`.
#[derive(Debug, Clone, Serialize)]
pub struct UpsamplingReport {
    /// The fitted upsampler's name and options, as the hierarchy stage keys them.
    pub fitted: String,
    pub barycentric: UpsamplingSummary,
    pub fitted_summary: UpsamplingSummary,
    /// `fitted_summary.ground_truth_mse.mean / barycentric.ground_truth_mse.mean`.
    pub ground_truth_mse_ratio: f64,
}

/// Per evaluated pose (in `evaluated`'s order), both upsamplers' errors for one method.
/// `folds` are `desal eval`'s (test poses each; the template always trains);
/// `full_surfaces[pose]` indexes `full.pose_mesh(pose)`.
pub fn measure(
    full: &PoseSet,
    set: &SimplifiedSet,
    deformed: &Deformed,
    folds: &[Vec<usize>],
    evaluated: &[usize],
    fitted: &Upsampler,
    full_surfaces: &[SurfaceIndex],
) -> Result<Vec<PoseUpsamplers>> {
    let orig = &set.mapped.map.simp_to_orig;
    let level = [ChainLevel { coarse_to_fine: orig, coarse_faces: &set.mapped.poses.faces }];
    let all = vec![true; full.pose_count()];
    let barycentric: CsrMatrix = composed_upsamplers(full, &level, &all, &Upsampler::Barycentric)
        .context("barycentric upsampler")?
        .pop()
        .expect("one level");
    // Every fold's fitted U at once: they share their candidates and their sums over
    // poses.
    let masks: Vec<Vec<bool>> = folds
        .iter()
        .map(|test| {
            let training = desal_measures::training_poses(full.pose_count(), test);
            (0..full.pose_count()).map(|p| training.contains(&p)).collect()
        })
        .collect();
    let mask_refs: Vec<&[bool]> = masks.iter().map(|m| m.as_slice()).collect();
    let fitted_ups =
        composed_upsamplers_per_mask(full, &level, &mask_refs, fitted).context("fitted upsampler")?;
    let mut per_pose = vec![PoseUpsamplers::default(); full.pose_count()];
    for (test, mut fitted_up) in folds.iter().zip(fitted_ups) {
        let fitted_up = fitted_up.pop().expect("one level");
        let deformed_coarse: Vec<Vec<Vec3>> = test
            .iter()
            .map(|&p| deformed.held_out[p].clone().expect("every test pose is held out"))
            .collect();
        let candidates = [&barycentric, &fitted_up].map(|u| {
            let u = std::slice::from_ref(u);
            [
                Upsampled { up_to_full: u, coarse: Coarse::GroundTruth(orig) },
                Upsampled { up_to_full: u, coarse: Coarse::Given(&deformed_coarse) },
            ]
        });
        let errors = upsampling_errors_indexed(full, test, candidates.as_flattened(), full_surfaces)?;
        for (slot, &pose) in test.iter().enumerate() {
            let at = |k: usize| {
                let e = errors[k].per_pose[slot];
                MseV2f { mse: e.mse, v2f: e.v2f.expect("measured") }
            };
            per_pose[pose] = PoseUpsamplers {
                barycentric: PoseUpsampling { ground_truth: at(0), deformed: at(1) },
                fitted: PoseUpsampling { ground_truth: at(2), deformed: at(3) },
            };
        }
    }
    Ok(evaluated.iter().map(|&p| per_pose[p]).collect())
}

/// The summary of [`measure`]'s per-pose figures.
pub fn summarise(per_pose: &[PoseUpsamplers], fitted: &Upsampler) -> UpsamplingReport {
    let summary = |pick: fn(&PoseUpsamplers) -> PoseUpsampling| {
        let of = |f: fn(&PoseUpsampling) -> f64| MeanStd::of(per_pose.iter().map(move |p| f(&pick(p))));
        UpsamplingSummary {
            ground_truth_mse: of(|u| u.ground_truth.mse),
            ground_truth_v2f: of(|u| u.ground_truth.v2f),
            deformed_mse: of(|u| u.deformed.mse),
            deformed_v2f: of(|u| u.deformed.v2f),
        }
    };
    let barycentric = summary(|p| p.barycentric);
    let fitted_summary = summary(|p| p.fitted);
    UpsamplingReport {
        fitted: format!("{fitted:?}"),
        ground_truth_mse_ratio: fitted_summary.ground_truth_mse.mean / barycentric.ground_truth_mse.mean,
        barycentric,
        fitted_summary,
    }
}
