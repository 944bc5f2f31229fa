//! The second deformation model: linear blend skinning (LBS), the model most real-time
//! trackers deform with. Bones are the parts; a pose is synthesised from the parts'
//! rigid motions (stage 1's fit) alone:
//!
//! `y_v = Σ_p w_vp (R_p x_v + t_p)`, `x_v` the template position of vertex `v`.
//!
//! Fitting (Magnenat-Thalmann et al. 1988 for the model; the weights are fitted per
//! vertex by constrained least squares, as in James & Twigg 2005, "Skinning Mesh
//! Animations", §4.3):
//! 1. **Prior weights from the parts.** Part membership (one-hot) is diffused over the
//!    mesh graph for [`LbsConfig::rings`] rings: each ring replaces a vertex's weights by
//!    the mean of its own and its neighbours'. A vertex's candidate bones are the parts
//!    with positive diffused weight, the largest [`LbsConfig::max_influences`] of them
//!    (ties to the lower part id); its prior `w⁰` is their diffused weights, normalised.
//! 2. **Least squares on the training poses.** Per vertex, minimise
//!    `Σ_i ‖Σ_p w_p (R_ip x_v + t_ip) − y_iv‖² + μ ‖w − w⁰‖²` subject to `w ≥ 0` and
//!    `Σ_p w_p = 1`, over its candidates. The prior term keeps the weights of a vertex
//!    that the training poses do not constrain (all its candidate bones moved alike) at
//!    the smooth prior; `μ = prior · (training poses) · h̄²`, `h̄` the mean template edge
//!    length, so a unit change of weight costs as much as a misfit of `√prior · h̄` in
//!    every pose, whatever the mesh's resolution or unit. The problem is a convex
//!    quadratic programme in at most four variables: it is solved exactly by trying
//!    every support (non-empty subset of the candidates), solving its equality-
//!    constrained system and keeping the best feasible one (ties: the first subset in
//!    bit-mask order), so the result is deterministic.
//!
//! **Invariant:** the weights of every vertex are non-negative, sum to one and number
//! at most four: a single-part mesh reproduces its part's rigid motion exactly.

use desal_mesh::{EdgeTopology, Face, PartLabels, PoseSet, Real, Vec3};
use nalgebra::{SMatrix, SVector};
use rayon::prelude::*;

use crate::error::EvalError;
use crate::transform::{PartTransform, check_model_inputs, check_pose_transforms};

/// The most influences a vertex can have (the usual GPU skinning limit).
pub const MAX_INFLUENCES: usize = 4;

/// Settings of the LBS model.
#[derive(Debug, Clone, PartialEq)]
pub struct LbsConfig {
    /// Rings of the mesh graph over which part membership is diffused to make the prior
    /// weights (and the candidate bones) of step 1. Default 3: three edges either side of a part border,
    /// a few centimetres on a full-resolution body, the width over which skin blends at
    /// the knees and elbows. 0: one bone per vertex (rigid parts).
    pub rings: usize,
    /// At most this many bones per vertex, `1..=4`. Default 4.
    pub max_influences: usize,
    /// Strength of the pull towards the prior weights (dimensionless, see the module
    /// doc). Default `0.1`. Held-out v2v, 5 folds (`default_sweeps` in
    /// `tests/floor.rs`), m²:
    ///
    /// | rings, prior | 3, 0.01 | 3, 0.1 | 3, 1 | 1, 0.1 | 6, 0.1 | 10, 0.1 |
    /// |---|---|---|---|---|---|---|
    /// | SCAPE | 9.24e-5 | 9.24e-5 | 9.25e-5 | 9.91e-5 | 8.72e-5 | 8.35e-5 |
    /// | sample | 1.46e-6 | 1.22e-6 | 1.21e-6 | 1.91e-6 | 1.42e-6 | 1.92e-6 |
    ///
    /// The prior hardly matters on SCAPE; wider blends help SCAPE (−10 % at 10 rings)
    /// and hurt the sample (+58 %), so the defaults stay at 3 rings, prior 0.1.
    pub prior: Real,
}

impl Default for LbsConfig {
    fn default() -> Self {
        Self { rings: 3, max_influences: MAX_INFLUENCES, prior: 0.1 }
    }
}

/// What fitting found, for logs and reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LbsReport {
    pub training_pose_count: usize,
    pub vertex_count: usize,
    /// Mean number of bones with a positive weight per vertex.
    pub mean_influences: Real,
    /// Mean over training (vertex, pose) pairs of the squared distance between the
    /// skinned and the true vertex, squared mesh units (m² for SCAPE).
    pub mean_fit_residual: Real,
}

/// A fitted LBS model for one mesh.
#[derive(Debug)]
pub struct LbsModel {
    template: Vec<Vec3>,
    part_count: usize,
    /// Vertex `v`'s `(part, weight)` pairs are `influences[offsets[v]..offsets[v + 1]]`,
    /// ascending part id, weights > 0.
    offsets: Vec<u32>,
    influences: Vec<(u32, Real)>,
    report: LbsReport,
}

/// Fits LBS weights on the poses `training_poses` of `poses`.
///
/// - `labels`: one part id per vertex of `poses` (same vertex index space);
/// - `transforms[pose][part]`: stage 1's rigid motion of each part, for **every** pose
///   of the set (only the training poses are read);
/// - `training_poses`: distinct pose indices.
pub fn fit_lbs(
    poses: &PoseSet,
    labels: &PartLabels,
    transforms: &[Vec<PartTransform>],
    training_poses: &[usize],
    config: &LbsConfig,
) -> Result<LbsModel, EvalError> {
    check_model_inputs(poses, labels, transforms, training_poses, check_pose_transforms)?;
    let template = poses.template_positions();
    let max_influences = config.max_influences.clamp(1, MAX_INFLUENCES);
    let priors = prior_weights(template.len(), &poses.faces, labels, config.rings, max_influences);
    let mu = config.prior * training_poses.len() as Real * mean_edge_length_squared(template, &poses.faces);

    // Vertices are independent: fit them in parallel, in vertex order.
    let fitted: Vec<(Vec<(u32, Real)>, Real)> = priors
        .into_par_iter()
        .enumerate()
        .map(|(v, prior)| {
            let displacements = |part: u32| -> Vec<Vec3> {
                training_poses
                    .iter()
                    .map(|&pose| transforms[pose][part as usize].apply(&template[v]) - poses.poses[pose][v])
                    .collect()
            };
            fit_vertex(&prior, displacements, mu)
        })
        .collect();

    let mut offsets = Vec::with_capacity(template.len() + 1);
    offsets.push(0u32);
    let mut influences = Vec::new();
    let mut residual = 0.0;
    for (weights, r) in fitted {
        influences.extend(weights);
        offsets.push(influences.len() as u32);
        residual += r;
    }
    let report = LbsReport {
        training_pose_count: training_poses.len(),
        vertex_count: template.len(),
        mean_influences: influences.len() as Real / template.len().max(1) as Real,
        mean_fit_residual: residual / (template.len() * training_poses.len()).max(1) as Real,
    };
    Ok(LbsModel { template: template.to_vec(), part_count: labels.part_count(), offsets, influences, report })
}

impl LbsModel {
    /// Skins the template with one pose's part motions `transforms[part]` (template part
    /// → posed part). Positions in the model's vertex index space.
    pub fn synthesize(&self, transforms: &[PartTransform]) -> Result<Vec<Vec3>, EvalError> {
        check_pose_transforms(transforms, self.part_count, 0)?;
        Ok(self.skin(transforms))
    }

    /// [`LbsModel::synthesize`] for many poses in parallel, results in the same order.
    pub fn synthesize_many(&self, transforms: &[Vec<PartTransform>]) -> Result<Vec<Vec<Vec3>>, EvalError> {
        for (pose, t) in transforms.iter().enumerate() {
            check_pose_transforms(t, self.part_count, pose)?;
        }
        Ok(transforms.par_iter().map(|t| self.skin(t)).collect())
    }

    /// Vertex `vertex`'s `(part, weight)` pairs: ascending part id, weights > 0 summing
    /// to one, at most [`MAX_INFLUENCES`].
    pub fn weights(&self, vertex: usize) -> &[(u32, Real)] {
        &self.influences[self.offsets[vertex] as usize..self.offsets[vertex + 1] as usize]
    }

    pub fn vertex_count(&self) -> usize {
        self.template.len()
    }

    pub fn report(&self) -> &LbsReport {
        &self.report
    }

    fn skin(&self, transforms: &[PartTransform]) -> Vec<Vec3> {
        self.template
            .iter()
            .enumerate()
            .map(|(v, x)| self.weights(v).iter().map(|&(p, w)| w * transforms[p as usize].apply(x)).sum())
            .collect()
    }
}

/// Step 1: per vertex, its candidate bones and their normalised diffused weights
/// (largest first, ties to the lower part id).
fn prior_weights(
    vertex_count: usize,
    faces: &[Face],
    labels: &PartLabels,
    rings: usize,
    max_influences: usize,
) -> Vec<Vec<(u32, Real)>> {
    let part_count = labels.part_count();
    let (offsets, neighbours) = EdgeTopology::new(faces).vertex_neighbours(vertex_count);
    let mut weights = vec![0.0; vertex_count * part_count];
    for (v, &p) in labels.labels.iter().enumerate() {
        weights[v * part_count + p as usize] = 1.0;
    }
    for _ in 0..rings {
        let previous = weights.clone();
        weights.par_chunks_mut(part_count).enumerate().for_each(|(v, row)| {
            let around = &neighbours[offsets[v] as usize..offsets[v + 1] as usize];
            let share = 1.0 / (1 + around.len()) as Real;
            for (p, w) in row.iter_mut().enumerate() {
                let sum: Real = previous[v * part_count + p]
                    + around.iter().map(|&u| previous[u as usize * part_count + p]).sum::<Real>();
                *w = sum * share;
            }
        });
    }
    weights
        .chunks(part_count)
        .map(|row| {
            let mut ranked: Vec<(u32, Real)> =
                row.iter().enumerate().filter(|&(_, &w)| w > 0.0).map(|(p, &w)| (p as u32, w)).collect();
            ranked.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
            ranked.truncate(max_influences);
            let total: Real = ranked.iter().map(|(_, w)| w).sum();
            ranked.iter().map(|&(p, w)| (p, w / total)).collect()
        })
        .collect()
}

fn mean_edge_length_squared(template: &[Vec3], faces: &[Face]) -> Real {
    let edges = EdgeTopology::new(faces).edges;
    let sum: Real = edges.iter().map(|&[a, b]| (template[a as usize] - template[b as usize]).norm()).sum();
    let mean = sum / edges.len().max(1) as Real;
    mean * mean
}

type Square = SMatrix<Real, { MAX_INFLUENCES + 1 }, { MAX_INFLUENCES + 1 }>;
type Column = SVector<Real, { MAX_INFLUENCES + 1 }>;

/// Step 2 for one vertex: the constrained least-squares weights over the candidates of
/// `prior`, given `displacements(part)[i] = R_ip x_v + t_ip − y_iv` per training pose
/// `i`. Returns the positive weights (ascending part id) and the vertex's summed squared
/// fit residual over the training poses.
fn fit_vertex(
    prior: &[(u32, Real)],
    displacements: impl Fn(u32) -> Vec<Vec3>,
    mu: Real,
) -> (Vec<(u32, Real)>, Real) {
    let k = prior.len();
    debug_assert!((1..=MAX_INFLUENCES).contains(&k));
    let d: Vec<Vec<Vec3>> = prior.iter().map(|&(p, _)| displacements(p)).collect();
    // With Σ w = 1 the skinned error is Σ_p w_p d_p, so the data term is wᵀ G w with
    // G_pq = Σ_i d_ip · d_iq: translation-invariant and well scaled.
    let mut gram = [[0.0; MAX_INFLUENCES]; MAX_INFLUENCES];
    for p in 0..k {
        for q in 0..=p {
            let g: Real = d[p].iter().zip(&d[q]).map(|(a, b)| a.dot(b)).sum();
            gram[p][q] = g;
            gram[q][p] = g;
        }
    }
    let objective = |w: &[Real]| -> Real {
        let mut value = 0.0;
        for p in 0..k {
            for q in 0..k {
                value += w[p] * gram[p][q] * w[q];
            }
            value += mu * (w[p] - prior[p].1).powi(2);
        }
        value
    };

    let mut best: Option<([Real; MAX_INFLUENCES], Real)> = None;
    for mask in 1u32..(1 << k) {
        let Some(w) = solve_on_support(mask, k, &gram, prior, mu) else { continue };
        let value = objective(&w[..k]);
        // Strictly better only, so ties keep the first support in mask order.
        if best.is_none_or(|(_, b)| value < b) {
            best = Some((w, value));
        }
    }
    // The full support with μ > 0 is always solvable, and a prior alone is feasible, so
    // this only falls back when μ = 0 and every support is singular.
    let (w, _) = best.unwrap_or_else(|| {
        let mut w = [0.0; MAX_INFLUENCES];
        for (slot, &(_, p)) in prior.iter().enumerate() {
            w[slot] = p;
        }
        (w, 0.0)
    });
    let data_residual = {
        let mut value = 0.0;
        for p in 0..k {
            for q in 0..k {
                value += w[p] * gram[p][q] * w[q];
            }
        }
        value.max(0.0)
    };
    let mut weights: Vec<(u32, Real)> =
        prior.iter().zip(&w).filter(|&(_, &w)| w > 0.0).map(|(&(p, _), &w)| (p, w)).collect();
    weights.sort_by_key(|&(p, _)| p);
    (weights, data_residual)
}

/// The minimiser of `wᵀ(G + μI)w − 2μ w⁰ᵀw` with `Σ w = 1` and `w_p = 0` off the
/// support `mask` (bit `p` set: candidate `p` is in), or `None` when that system is
/// singular or its solution has a negative weight. Weights within rounding of zero are
/// clamped and the rest renormalised, so the result is exactly feasible.
fn solve_on_support(
    mask: u32,
    k: usize,
    gram: &[[Real; MAX_INFLUENCES]; MAX_INFLUENCES],
    prior: &[(u32, Real)],
    mu: Real,
) -> Option<[Real; MAX_INFLUENCES]> {
    // KKT system [[G_S + μI, 1], [1ᵀ, 0]]; unused slots are identity rows with zero
    // right-hand side, so one fixed-size solve serves every support.
    let mut a = Square::identity();
    let mut b = Column::zeros();
    let lagrange = MAX_INFLUENCES;
    a[(lagrange, lagrange)] = 0.0;
    b[lagrange] = 1.0;
    for p in (0..k).filter(|p| mask & (1 << p) != 0) {
        for q in (0..k).filter(|q| mask & (1 << q) != 0) {
            a[(p, q)] = gram[p][q] + if p == q { mu } else { 0.0 };
        }
        a[(p, lagrange)] = 1.0;
        a[(lagrange, p)] = 1.0;
        b[p] = mu * prior[p].1;
    }
    let x = a.lu().solve(&b)?;
    if !x.iter().all(|v| v.is_finite()) {
        return None;
    }
    let mut w = [0.0; MAX_INFLUENCES];
    for p in (0..k).filter(|p| mask & (1 << p) != 0) {
        if x[p] < -1e-12 {
            return None;
        }
        w[p] = x[p].max(0.0);
    }
    let total: Real = w.iter().sum();
    if total <= 0.0 {
        return None;
    }
    for v in &mut w {
        *v /= total;
    }
    Some(w)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two candidates, bone 0's prediction 1 unit off in x in every pose, bone 1's exact:
    /// with a negligible prior μ the exact bone takes all the weight but `μ/(2·3)`, the
    /// closed-form optimum of `3 w₀² + μ((w₀ − ½)² + (½ − w₀)²)`, i.e. `w₀ = μ/(3 + 2μ)`.
    #[test]
    fn exact_bone_takes_all_the_weight() {
        let prior = [(0u32, 0.5), (1u32, 0.5)];
        let d = |p: u32| vec![if p == 0 { Vec3::x() } else { Vec3::zeros() }; 3];
        let mu = 1e-6;
        let (w, residual) = fit_vertex(&prior, d, mu);
        let w0 = mu / (3.0 + 2.0 * mu);
        assert_eq!(w.len(), 2);
        assert!((w[0].1 - w0).abs() < 1e-15 && (w[1].1 - (1.0 - w0)).abs() < 1e-15, "{w:?}");
        assert!((residual - 3.0 * w0 * w0).abs() < 1e-20);
    }

    /// Bones off by +1 and −1 along x: the half-and-half blend is exact, so with any
    /// prior equal to it the fit returns exactly (0.5, 0.5).
    #[test]
    fn opposite_errors_blend_half_and_half() {
        let prior = [(2u32, 0.5), (5u32, 0.5)];
        let d = |p: u32| vec![if p == 2 { Vec3::x() } else { -Vec3::x() }; 4];
        let (w, residual) = fit_vertex(&prior, d, 0.3);
        assert_eq!(w, vec![(2, 0.5), (5, 0.5)]);
        assert!(residual < 1e-24);
    }

    /// Bones that every training pose moves alike leave the data term flat: the prior
    /// decides.
    #[test]
    fn unconstrained_vertex_keeps_its_prior() {
        let prior = [(0u32, 0.75), (1u32, 0.25)];
        let d = |_: u32| vec![Vec3::new(0.0, 0.1, 0.0); 2];
        let (w, _) = fit_vertex(&prior, d, 1.0);
        assert!((w[0].1 - 0.75).abs() < 1e-12 && (w[1].1 - 0.25).abs() < 1e-12, "{w:?}");
    }
}
