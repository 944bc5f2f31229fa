//! `desal-refit`'s weights: where the simplified mesh deforms worse than the full one.
//!
//! `desal` is simplified once; the eval's deformation model is fitted on it in-sample
//! on the poses stage 2 saw (`Inputs::simplification_poses`) and synthesises each of
//! those poses; every full-resolution vertex then gets its mean squared distance to the
//! synthesised coarse surface (the full → simplified half of v2f, Eq. 6). The same model
//! fitted at full resolution gives the same distance to its own synthesised surface: the
//! part of the error no simplification removes. What the simplification adds is the
//! excess of the first over the second, and the weight of vertex `i` is
//!
//! `w_i = ((max(r_i − f_i, 0) + FLOOR · mean r) / mean(…))^EXPONENT`
//!
//! (`r` the coarse residual, `f` the full one, the mean over vertices of the bracket
//! dividing it). Stage 3 then runs again with these as its saliency weights, the rest of
//! `desal`'s settings unchanged: a collapse among vertices where the coarse surface
//! deforms badly costs more, so those regions keep more vertices. Last, its edges are
//! flipped where the triangles then follow the full surface better in every pose
//! (`flip.rs`).
//!
//! Both runs also choose *which* vertex of each collapse stays by how well the model
//! places it: every vertex's keep penalty is [`KEEP_PENALTY`] times its squared position
//! error under the full-resolution model (in-sample, mean over the same poses), and a
//! subset collapse keeps the endpoint with the smaller error per unit area plus penalty
//! (`SimplifyInput::keep_penalty`). The ranking, and so each region's vertex budget,
//! is the unpenalised one. A coarse vertex is where the coarse model is measured (v2v)
//! and what the coarse surface is spanned from (v2f), so keeping the one the model
//! places best lowers both.
//!
//! Why the excess and not `r` itself: `r` is mostly the model's own error (4.3e-5 of
//! 4.9e-5 m² on SCAPE), which piles up at the joints whatever the mesh; weighting by it
//! moved vertices there and made v2v worse by 9.5 % (γ = 0.5) without buying v2f (−0.7 %).
//! Why a floor: without it a vertex with no excess could be removed at no cost. Why
//! the exponent 0.65 and one round: measured on SCAPE (docs/eval/desal-method.md, "desal-refit");
//! a second round, re-weighted from the first round's mesh, swings back to `desal`.

use std::sync::OnceLock;

use desal_map::{MapConfig, MapError, MapMode, MapOutput};
use desal_measures::deform::{self, DeformError};
use desal_measures::{PoseModel, SurfaceIndex};
use desal_mesh::{Face, NoProgress, PartLabels, PoseSet, TriMesh, Vec3};
use desal_simplify::{Simplified, SimplifyConfig, SimplifyError, SimplifyInput};
use rayon::prelude::*;
use thiserror::Error;

pub mod flip;
pub mod upsampler;

/// What can go wrong in `desal-refit`; each says which step failed.
#[derive(Debug, Error)]
pub enum RefitError {
    #[error("desal-refit needs a pose besides the template to measure its residual on")]
    NoPoseToMeasure,
    #[error("desal-refit: the full-resolution model")]
    FullModel(#[source] DeformError),
    #[error("desal-refit: stage 3, {run} run")]
    Simplify {
        run: &'static str,
        #[source]
        source: SimplifyError,
    },
    #[error("desal-refit: stage 4 of the first run")]
    Map(#[source] MapError),
    #[error("desal-refit: the first run's residual")]
    Residual(#[source] DeformError),
    /// desal-refit maps and flips by original vertex: every simplified vertex must be one.
    #[error("desal-refit needs subset placement (every simplified vertex an original one)")]
    NotSubset,
}

type Result<T> = std::result::Result<T, RefitError>;

/// The exponent of the excess (`γ`). Without keep penalties (SCAPE, against
/// `qslim-optimal`, v2f / v2v held out): 0.25 −0.8 % / −2.8 %, 0.35 −2.5 % / −1.1 %,
/// 0.5 −3.0 % / +1.1 %, 0.75 −3.9 % / +4.7 %, 1 −5.2 % / +8.0 %: every step traded v2v
/// for v2f. With them ([`KEEP_PENALTY`] 5), the trade moves: 0.35 −5.7 % / −9.6 %,
/// 0.45 −7.6 % / −9.1 %, 0.5 −7.8 % / −8.4 %, 0.55 −9.4 % / −8.7 %, 0.6 −10.5 % / −8.8 %,
/// **0.65 −11.1 % / −8.8 %**, 0.75 −10.7 % / −6.9 %. 0.65 has the lowest v2f of those
/// with v2v ≥ 8 % below QSlim (docs/eval/desal-method.md).
pub const EXPONENT: f64 = 0.65;

/// Every vertex's excess is raised by this fraction of the mean coarse residual.
pub const FLOOR: f64 = 0.1;

/// The keep penalty per unit of the full model's squared position error (dimensionless:
/// both are squared lengths, the error per unit area too). SCAPE, 2500 vertices, held
/// out against `qslim-optimal`, v2f / v2v (docs/eval/desal-method.md), at [`EXPONENT`]
/// 0.65: 3 −9.8 % / −7.5 %, **5 −11.1 % / −8.8 %**, 7 −9.9 % / −8.1 %; at 0.35: none
/// −3.4 % / −1.2 %, 1 −5.5 % / −6.2 %, 3 −6.3 % / −8.4 %, 5 −5.7 % / −9.6 %, 10 −5.3 % /
/// −9.2 %.
pub const KEEP_PENALTY: f64 = 5.0;

/// What the full-resolution model gives `desal-refit`, computed once per eval: per
/// vertex, the mean squared distance to its own synthesised surface (`f` of the module
/// doc) and its mean squared position error, both over the non-template poses stage 2
/// saw, the model fitted in-sample on them.
#[derive(Debug)]
pub struct FullModel {
    residual: Vec<f64>,
    position_error: Vec<f64>,
}

impl FullModel {
    /// Fits the model at full resolution on the poses `seen` of `poses` and measures it.
    pub fn measure(poses: &PoseSet, seen: &[usize], labels: &PartLabels, model: &PoseModel) -> Result<Self> {
        let truth = poses.subset(seen);
        if truth.pose_count() < 2 {
            return Err(RefitError::NoPoseToMeasure);
        }
        let deformed = deform::deform(&truth, labels, &[], model).map_err(RefitError::FullModel)?.in_sample;
        let residual = surface_residual(&truth, &deformed, &truth.faces);
        let measured: Vec<usize> = (0..truth.pose_count()).filter(|&p| p != truth.template).collect();
        let mut position_error = vec![0.0; truth.vertex_count()];
        for &p in &measured {
            for ((e, x), y) in position_error.iter_mut().zip(&deformed[p]).zip(&truth.poses[p]) {
                *e += (x - y).norm_squared();
            }
        }
        let count = measured.len() as f64;
        position_error.iter_mut().for_each(|e| *e /= count);
        Ok(Self { residual, position_error })
    }

    /// The keep penalty of every vertex: [`KEEP_PENALTY`] times its position error.
    pub fn keep_penalty(&self) -> Vec<f64> {
        self.position_error.iter().map(|e| KEEP_PENALTY * e).collect()
    }
}

/// What `desal-refit`'s stage 3 reads: the pose set and its labels, the poses stage 2
/// saw, the template's attribute seams (kept, and never flipped), the pose model and
/// its measures at full resolution.
#[derive(Debug, Clone, Copy)]
pub struct Refit<'a> {
    pub poses: &'a PoseSet,
    pub labels: &'a PartLabels,
    pub seen: &'a [usize],
    pub seams: Option<&'a [[u32; 2]]>,
    pub model: &'a PoseModel,
    pub full: &'a FullModel,
}

/// The settings `desal-refit` resolves to beside stage 3's configuration: a `desal run`
/// stage 3 with `method = "desal-refit"` keys its cache entry by them, so a change to
/// any of them makes another simplification.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Settings {
    pub version: u32,
    pub model: &'static str,
    pub exponent: f64,
    pub floor: f64,
    pub keep_penalty: f64,
}

/// Today's [`Settings`].
pub const SETTINGS: Settings = Settings {
    version: VERSION,
    model: deform::DEFAULT_MODEL,
    exponent: EXPONENT,
    floor: FLOOR,
    keep_penalty: KEEP_PENALTY,
};

/// The version of `desal-refit`'s procedure beyond its constants (the weight rule, the
/// residual, the flips); bumped when one changes, so that cached results are remade.
pub const VERSION: u32 = 1;

/// `desal-refit`'s result: the weighted run's simplification with its edges flipped,
/// the configuration that run used, and the number of flips.
#[derive(Debug)]
pub struct Refitted {
    pub simplified: Simplified,
    /// The weighted run's configuration (`config` with the saliency factor on).
    pub config: SimplifyConfig,
    pub flips: usize,
}

/// `desal-refit` with the SCAPE pose model ([`deform::DEFAULT_MODEL`], as `desal eval`
/// runs it by default) fitted at full resolution on the poses `seen` (those stage 2
/// read), then [`Refit::simplify`] with `config` (`desal`'s settings and the target).
/// `seams`: the template's attribute seams.
pub fn refit(
    config: &SimplifyConfig,
    poses: &PoseSet,
    labels: &PartLabels,
    seen: &[usize],
    seams: Option<&[[u32; 2]]>,
) -> Result<Refitted> {
    let model = deform::pose_model(deform::DEFAULT_MODEL).map_err(RefitError::FullModel)?;
    let full = FullModel::measure(poses, seen, labels, &model)?;
    Refit { poses, labels, seen, seams, model: &model, full: &full }.simplify(config)
}

impl Refit<'_> {
    /// The whole of `desal-refit`'s stage 3 (module doc): `config` is `desal`'s (subset
    /// placement, the error per unit area, no saliency, no balance) with the target; the
    /// first run, its residual, the weighted run, both with the keep penalties, then the
    /// flips. The second run's output, with the flipped faces and a note that counts them.
    pub fn simplify(&self, config: &SimplifyConfig) -> Result<Refitted> {
        let template = self.poses.template_mesh();
        let penalty = self.full.keep_penalty();
        let run =
            |config: &SimplifyConfig, weights: &[f64], run: &'static str| {
                let mut input = SimplifyInput::new(&template)
                    .with_keep_penalty(&penalty)
                    .with_inputs_read_by(config, weights, &self.labels.labels);
                if let Some(seams) = self.seams {
                    input = input.with_seams(seams);
                }
                desal_simplify::simplify_with_progress(&input, config, &NoProgress)
                    .map_err(|source| RefitError::Simplify { run, source })
            };
        // The first run reads no weights (`desal` has no saliency factor).
        let first = run(config, &[], "first")?;
        let mapped = map_subset(&first, self.poses, self.labels)?;
        let weights = weights(self.poses, self.seen, self.full, self.model, &mapped)?;
        let config = SimplifyConfig { saliency: true, ..config.clone() };
        let mut simplified = run(&config, &weights, "weighted")?;
        let flips = self.flip(&mut simplified)?;
        Ok(Refitted { simplified, config, flips })
    }

    /// The last step (`flip.rs`): `simplified`'s edges flipped where its faces follow
    /// the full surface better over the poses stage 2 saw; the number of flips.
    fn flip(&self, simplified: &mut Simplified) -> Result<usize> {
        let Some(kept) = simplified.simp_to_orig.iter().copied().collect::<Option<Vec<u32>>>() else {
            return Err(RefitError::NotSubset);
        };
        // Every vertex on a seam is pinned: stage 3 hands a seam on along its collapses,
        // so a simplified seam edge need not be an original one.
        let mut on_seam = vec![false; self.poses.vertex_count()];
        for &v in self.seams.iter().copied().flatten().flatten() {
            on_seam[v as usize] = true;
        }
        let pinned: Vec<bool> = kept.iter().map(|&o| on_seam[o as usize]).collect();
        Ok(flip::flip_edges(&mut simplified.mesh.faces, &kept, self.poses, self.seen, &pinned))
    }
}

/// Stage 4 of a subset simplification of `poses`' template: every pose of the set at
/// the kept vertices, the labels carried along.
fn map_subset(simplified: &Simplified, poses: &PoseSet, labels: &PartLabels) -> Result<MapOutput> {
    let Some(kept_orig) = simplified.simp_to_orig.iter().copied().collect::<Option<Vec<u32>>>() else {
        return Err(RefitError::NotSubset);
    };
    desal_map::map_pose_set(
        &MapConfig::default(),
        MapMode::Subset { kept_orig: &kept_orig },
        &simplified.mesh,
        poses,
        labels,
    )
    .map_err(RefitError::Map)
}

/// The full model's measures, computed on the first call and kept in `cache`.
pub fn full_model<'a>(
    cache: &'a OnceLock<FullModel>,
    poses: &PoseSet,
    seen: &[usize],
    labels: &PartLabels,
    model: &PoseModel,
) -> Result<&'a FullModel> {
    if let Some(full) = cache.get() {
        return Ok(full);
    }
    let full = FullModel::measure(poses, seen, labels, model)?;
    Ok(cache.get_or_init(|| full))
}

/// The weights of `desal-refit` for `coarse`, `desal`'s simplified set mapped to every
/// pose of `poses` (module doc), measured on the poses `seen` (those stage 2 saw) against
/// `full`'s residual. `model` is the eval's.
pub fn weights(
    poses: &PoseSet,
    seen: &[usize],
    full: &FullModel,
    model: &PoseModel,
    coarse: &MapOutput,
) -> Result<Vec<f64>> {
    let truth = poses.subset(seen);
    let set = coarse.poses.subset(seen);
    let deformed = deform::deform(&set, &coarse.labels, &[], model).map_err(RefitError::Residual)?.in_sample;
    let r = surface_residual(&truth, &deformed, &set.faces);
    Ok(rule(&r, &full.residual, EXPONENT, FLOOR))
}

/// Per vertex of `truth`, its mean squared distance over the non-template poses to the
/// surface `faces` posed at `deformed` (the same poses, a model's in-sample synthesis).
fn surface_residual(truth: &PoseSet, deformed: &[Vec<Vec3>], faces: &[Face]) -> Vec<f64> {
    let poses: Vec<usize> = (0..truth.pose_count()).filter(|&p| p != truth.template).collect();
    let n = truth.vertex_count();
    let per_pose: Vec<Vec<f64>> = poses
        .par_iter()
        .map(|&p| {
            let surface = TriMesh { positions: deformed[p].clone(), faces: faces.to_vec() };
            SurfaceIndex::new(&surface).distances_sq(&truth.poses[p])
        })
        .collect();
    let mut mean = vec![0.0; n];
    for distances in &per_pose {
        for (m, d) in mean.iter_mut().zip(distances) {
            *m += d;
        }
    }
    let count = poses.len() as f64;
    mean.iter_mut().for_each(|m| *m /= count);
    mean
}

/// The weight rule of the module doc, for the coarse residual `r` and the full one `f`
/// (one entry per vertex each).
fn rule(r: &[f64], f: &[f64], exponent: f64, floor: f64) -> Vec<f64> {
    assert_eq!(r.len(), f.len(), "one residual per vertex in both");
    let n = r.len() as f64;
    let lift = floor * r.iter().sum::<f64>() / n;
    let excess: Vec<f64> = r.iter().zip(f).map(|(r, f)| (r - f).max(0.0) + lift).collect();
    let mean = excess.iter().sum::<f64>() / n;
    excess.iter().map(|e| if mean > 0.0 { (e / mean).powf(exponent) } else { 1.0 }).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The excess over the full model's residual drives the weight, never below the
    /// floor; the weights have no unit (a residual scaled by 10 gives the same ones) and
    /// rise with the excess.
    #[test]
    fn the_weight_follows_the_excess_over_the_full_models_residual() {
        let r = [1.0, 2.0, 5.0, 0.5];
        let f = [1.0, 1.0, 1.0, 2.0];
        let w = rule(&r, &f, 0.5, 0.1);
        // Excess: 0, 1, 4, 0 (clamped), each + 0.1 · mean r (0.2125).
        let lift = 0.1 * (8.5 / 4.0);
        let e = [lift, 1.0 + lift, 4.0 + lift, lift];
        let mean = e.iter().sum::<f64>() / 4.0;
        for (w, e) in w.iter().zip(e) {
            assert!((w - (e / mean).sqrt()).abs() < 1e-12, "{w} against {}", (e / mean).sqrt());
        }
        assert_eq!(w[0], w[3], "no excess, the floor's weight, whatever the full residual");
        assert!(w[0] < w[1] && w[1] < w[2]);
        let scaled: Vec<f64> = rule(&r.map(|x| 10.0 * x), &f.map(|x| 10.0 * x), 0.5, 0.1);
        for (a, b) in w.iter().zip(&scaled) {
            assert!((a - b).abs() < 1e-12);
        }
        assert!(rule(&[0.0; 3], &[0.0; 3], 0.5, 0.1).iter().all(|&w| w == 1.0), "no residual at all");
    }
}
