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
//! Why the excess and not `r` itself: `r` is mostly the model's own error (4.3e-5 of
//! 4.9e-5 m² on SCAPE), which piles up at the joints whatever the mesh; weighting by it
//! moved vertices there and made v2v worse by 9.5 % (γ = 0.5) without buying v2f (−0.7 %).
//! Why a floor: without it a vertex with no excess could be removed at no cost. Why
//! the exponent 0.35 and one round: measured on SCAPE (docs/eval/desal-method.md, "desal-refit");
//! a second round, re-weighted from the first round's mesh, swings back to `desal`.

use std::sync::OnceLock;

use anyhow::{Result, bail};
use desal_eval::{PoseModel, SurfaceIndex};
use desal_map::MapOutput;
use desal_mesh::{PartLabels, PoseSet, TriMesh};
use rayon::prelude::*;

use super::measure;

/// The exponent of the excess (`γ`): SCAPE, against `qslim-optimal`, v2f / v2v
/// held out: 0.25 −0.8 % / −2.8 %, 0.35 −2.5 % / −1.1 %, 0.5 −3.0 % / +1.1 %,
/// 0.75 −3.9 % / +4.7 %, 1 −5.2 % / +8.0 %.
pub const EXPONENT: f64 = 0.35;

/// Every vertex's excess is raised by this fraction of the mean coarse residual.
pub const FLOOR: f64 = 0.1;

/// The weights of `desal-refit` for `coarse`, `desal`'s simplified set mapped to every
/// pose of `poses` (module doc), measured on the poses `seen` (those stage 2 saw; the
/// full set's part labels `labels`). `model` is the eval's; `full_residual` caches the
/// full-resolution residual, filled on the first call.
pub fn weights(
    poses: &PoseSet,
    seen: &[usize],
    labels: &PartLabels,
    full_residual: &OnceLock<Vec<f64>>,
    model: &PoseModel,
    coarse: &MapOutput,
) -> Result<Vec<f64>> {
    let truth = poses.subset(seen);
    if truth.pose_count() < 2 {
        bail!("desal-refit needs a pose besides the template to measure its residual on");
    }
    let full = match full_residual.get() {
        Some(full) => full,
        None => {
            let residual = residual(&truth, &truth, labels, model)?;
            full_residual.get_or_init(|| residual)
        }
    };
    let r = residual(&truth, &coarse.poses.subset(seen), &coarse.labels, model)?;
    Ok(rule(&r, full, EXPONENT, FLOOR))
}

/// Per vertex of `truth`, its mean squared distance over the non-template poses to the
/// surface of `set` (the same poses, its part labels `labels`) deformed by `model`
/// fitted in-sample on every pose of `set`.
fn residual(truth: &PoseSet, set: &PoseSet, labels: &PartLabels, model: &PoseModel) -> Result<Vec<f64>> {
    let deformed = measure::deform(set, labels, &[], model)?.in_sample;
    let poses: Vec<usize> = (0..truth.pose_count()).filter(|&p| p != truth.template).collect();
    let n = truth.vertex_count();
    let per_pose: Vec<Vec<f64>> = poses
        .par_iter()
        .map(|&p| {
            let surface = TriMesh { positions: deformed[p].clone(), faces: set.faces.clone() };
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
    Ok(mean)
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
