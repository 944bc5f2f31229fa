//! The per-triangle twist regression of the SCAPE model, and the choice of its ridge
//! and feature set by leave-one-out cross-validation over the training poses.
//!
//! Each triangle regresses the nine entries of its non-rigid deformation `Q` on a
//! feature vector `f = [twist of nearest joint, twist of second nearest joint, 1]`
//! (seven entries; [`JointFeatures::Nearest`] zeroes the second twist) by ridge least
//! squares `W = (AᵀA + λ D)⁻¹ AᵀB`, `D` = 1 on the twist entries, 0 on the constant.
//!
//! **Why cross-validation.** With few training poses the seven-coefficient fit
//! interpolates its poses and extrapolates badly (issue 17 measured held-out errors
//! ~10× the in-sample ones on 10 poses). Ridge regression is a linear smoother, so its
//! leave-one-out residuals have the closed form `e_i / (1 − h_ii)` with
//! `h_ii = f_iᵀ (AᵀA + λD)⁻¹ f_i` (Hastie, Tibshirani & Friedman, *The Elements of
//! Statistical Learning*, §7.10) — exact for any fixed penalty, so no refit is needed.
//!
//! **The rule** (applied by [`crate::fit_model`] with [`crate::Regression::CrossValidated`]): over every candidate — the two feature sets
//! times the ridge grid [`RIDGE_GRID`] — sum the squared leave-one-out residuals
//! `Σ_k Σ_i ‖e_ki / (1 − h_kii)‖²_F` over all triangles `k` and training poses `i`, and
//! keep the candidate with the smallest sum (ties: the first in the order
//! `Nearest` before `TwoNearest`, smaller ridge first). One choice per model (not per
//! triangle), so neighbouring triangles stay consistent.
//!
//! **Measured** (`tests/floor.rs`): on the sample's folds (9 training poses) it picks
//! the nearest joint with λ = 3.2e-3 in two folds of five and two joints with
//! λ = 1e-3…1e-2 in the others; on all 71 SCAPE poses two joints with λ = 1e-2. It
//! halves the sample's held-out / in-sample ratio at weak anchoring (anchor scale 0.1:
//! 7.4 → 3.2), mostly by raising the in-sample error, and does not lower held-out
//! position error (SCAPE at the default anchoring: v2v 6.97e-5 vs 6.77e-5 m² for the
//! fixed λ = 1e-3), which is why [`crate::Regression::Fixed`] stays the default.

use desal_mesh::Real;
use nalgebra::{SMatrix, SVector};

/// Regression inputs per triangle: the twists (3 + 3, radians) of its two nearest joints
/// and a constant 1.
pub(crate) const FEATURES: usize = 7;
/// Regression outputs per triangle: the entries of `Q`, column-major.
pub(crate) const OUTPUTS: usize = 9;

pub(crate) type Features = SVector<Real, FEATURES>;
pub(crate) type Target = SVector<Real, OUTPUTS>;
pub(crate) type Coefficients = SMatrix<Real, FEATURES, OUTPUTS>;
type Gram = SMatrix<Real, FEATURES, FEATURES>;

/// Ridge candidates λ of the cross-validated rule (dimensionless per pose; multiplied by
/// the number of training poses like [`crate::ModelConfig::ridge`]): half-decades from
/// `1e-4` (no shrinkage for a joint that moves by 0.1 rad or more) to `1e2` (every twist
/// coefficient shrunk to almost nothing: the rigid parts plus the mean `Q`).
pub const RIDGE_GRID: [Real; 13] =
    [1e-4, 3.162e-4, 1e-3, 3.162e-3, 1e-2, 3.162e-2, 1e-1, 3.162e-1, 1.0, 3.162, 10.0, 31.62, 100.0];

/// Which joint twists a triangle's regression sees.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointFeatures {
    /// The nearest joint's twist and a constant (four coefficients per entry of `Q`).
    Nearest,
    /// The two nearest joints' twists and a constant (seven coefficients): SCAPE's rule.
    TwoNearest,
}

impl JointFeatures {
    /// Number of joint-twist slots used (1 or 2).
    pub fn slots(self) -> usize {
        match self {
            JointFeatures::Nearest => 1,
            JointFeatures::TwoNearest => 2,
        }
    }

    /// A stable lower-case name for reports.
    pub fn name(self) -> &'static str {
        match self {
            JointFeatures::Nearest => "nearest-joint",
            JointFeatures::TwoNearest => "two-nearest-joints",
        }
    }
}

/// Ridge least squares `W = (AᵀA + λ D)⁻¹ AᵀB` over `samples` `(f, q)`. Returns `W` and
/// the sum of squared residuals `Σ ‖q − Wᵀ f‖²` (unregularised).
pub(crate) fn regress_triangle(samples: &[(Features, Target)], ridge: Real) -> (Coefficients, Real) {
    let (ata, atb, btb) = moments(samples);
    let w = solve_ridge(&ata, &atb, ridge);
    // ‖B − AW‖² expanded, so the residuals need not be formed.
    let residual = btb - 2.0 * w.component_mul(&atb).sum() + (w.transpose() * ata * w).trace();
    (w, residual.max(0.0))
}

/// Sum over the samples of the squared leave-one-out residual `‖e_i / (1 − h_ii)‖²` of
/// the ridge fit with weight `ridge` (closed form, see the module doc).
pub(crate) fn leave_one_out_error(samples: &[(Features, Target)], ridge: Real) -> Real {
    let (ata, atb, _) = moments(samples);
    let regularised = regularise(&ata, ridge);
    let Some(chol) = regularised.cholesky() else {
        // Singular only with ridge = 0 and collinear features: no leave-one-out
        // prediction exists, so the candidate must lose.
        return Real::INFINITY;
    };
    let w = chol.solve(&atb);
    samples
        .iter()
        .map(|(f, q)| {
            let leverage = f.dot(&chol.solve(f));
            // A sample with leverage 1 is interpolated whatever the others say: its
            // leave-one-out prediction is undefined, so it counts as a huge error.
            let keep = (1.0 - leverage).max(1e-12);
            (q - w.transpose() * f).norm_squared() / (keep * keep)
        })
        .sum()
}

/// The feature set and ridge with the smallest summed leave-one-out error, given
/// `errors[c]` for every candidate `c` of [`candidates`] (same order).
pub(crate) fn best_candidate(errors: &[Real]) -> (JointFeatures, Real) {
    let all = candidates();
    debug_assert_eq!(errors.len(), all.len());
    let mut best = 0;
    for (c, e) in errors.iter().enumerate() {
        // Strictly smaller only: a tie keeps the earlier candidate (fewer features, then
        // the smaller ridge), so the choice is deterministic.
        if *e < errors[best] {
            best = c;
        }
    }
    all[best]
}

/// Every candidate of the cross-validated rule: `Nearest` with each ridge of the grid,
/// then `TwoNearest` with each.
pub(crate) fn candidates() -> Vec<(JointFeatures, Real)> {
    [JointFeatures::Nearest, JointFeatures::TwoNearest]
        .into_iter()
        .flat_map(|j| RIDGE_GRID.iter().map(move |&r| (j, r)))
        .collect()
}

/// Zeroes the twist slots a feature set does not use.
pub(crate) fn mask_features(mut f: Features, joints: JointFeatures) -> Features {
    for slot in joints.slots()..2 {
        f.fixed_rows_mut::<3>(3 * slot).fill(0.0);
    }
    f
}

fn moments(samples: &[(Features, Target)]) -> (Gram, Coefficients, Real) {
    let mut ata = Gram::zeros();
    let mut atb = Coefficients::zeros();
    let mut btb = 0.0;
    for (f, q) in samples {
        ata += f * f.transpose();
        atb += f * q.transpose();
        btb += q.norm_squared();
    }
    (ata, atb, btb)
}

fn regularise(ata: &Gram, ridge: Real) -> Gram {
    let mut regularised = *ata;
    for i in 0..FEATURES - 1 {
        regularised[(i, i)] += ridge;
    }
    regularised
}

fn solve_ridge(ata: &Gram, atb: &Coefficients, ridge: Real) -> Coefficients {
    let regularised = regularise(ata, ridge);
    match regularised.cholesky() {
        Some(chol) => chol.solve(atb),
        // Only reachable with ridge = 0 and collinear twists: take the minimum-norm
        // least-squares solution instead.
        None => regularised.svd(true, true).solve(atb, 1e-12).expect("SVD with both factors computed"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// Random samples: twists in ±0.6 rad, `q` a noisy linear function of them.
    fn samples(count: usize, seed: u64) -> Vec<(Features, Target)> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let truth = Coefficients::from_fn(|_, _| rng.gen_range(-1.0..1.0));
        (0..count)
            .map(|_| {
                let mut f = Features::from_fn(|_, _| rng.gen_range(-0.6..0.6));
                f[FEATURES - 1] = 1.0;
                let noise = Target::from_fn(|_, _| rng.gen_range(-0.3..0.3));
                (f, truth.transpose() * f + noise)
            })
            .collect()
    }

    /// The brute-force leave-one-out error: refit without each sample in turn and
    /// measure the refit's error on it.
    fn brute_force_loo(samples: &[(Features, Target)], ridge: Real) -> Real {
        (0..samples.len())
            .map(|i| {
                let rest: Vec<_> =
                    samples.iter().enumerate().filter(|&(j, _)| j != i).map(|(_, s)| *s).collect();
                let (w, _) = regress_triangle(&rest, ridge);
                let (f, q) = &samples[i];
                (q - w.transpose() * f).norm_squared()
            })
            .sum()
    }

    /// The closed form equals refitting without each sample, for every candidate, and
    /// so the rule picks the candidate a brute-force search picks. Ten samples of seven
    /// features: few enough that the ridge matters.
    #[test]
    fn closed_form_leave_one_out_matches_brute_force() {
        for seed in 0..4 {
            let triangles: Vec<_> = (0..3).map(|t| samples(10, 10 * seed + t)).collect();
            let mut closed = Vec::new();
            let mut brute = Vec::new();
            for (joints, ridge) in candidates() {
                let (mut c, mut b) = (0.0, 0.0);
                for tri in &triangles {
                    let masked: Vec<_> = tri.iter().map(|(f, q)| (mask_features(*f, joints), *q)).collect();
                    c += leave_one_out_error(&masked, ridge * 10.0);
                    b += brute_force_loo(&masked, ridge * 10.0);
                }
                assert!((c - b).abs() <= 1e-9 * b, "{joints:?} λ={ridge}: closed {c} vs brute {b}");
                closed.push(c);
                brute.push(b);
            }
            assert_eq!(best_candidate(&closed), best_candidate(&brute), "seed {seed}");
        }
    }

    /// Pure noise around a constant: every twist coefficient only fits noise, so the
    /// rule must pick the simplest features and the largest ridge.
    #[test]
    fn noise_only_picks_the_strongest_shrinkage() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let data: Vec<(Features, Target)> = (0..12)
            .map(|_| {
                let mut f = Features::from_fn(|_, _| rng.gen_range(-0.6..0.6));
                f[FEATURES - 1] = 1.0;
                (f, Target::from_fn(|_, _| rng.gen_range(-0.3..0.3)))
            })
            .collect();
        let errors: Vec<Real> = candidates()
            .iter()
            .map(|&(j, r)| {
                let masked: Vec<_> = data.iter().map(|(f, q)| (mask_features(*f, j), *q)).collect();
                leave_one_out_error(&masked, r * 12.0)
            })
            .collect();
        assert_eq!(best_candidate(&errors), (JointFeatures::Nearest, 100.0));
    }

    /// Noise-free data linear in both joints' twists: the least-shrunk two-joint fit
    /// predicts left-out samples best.
    #[test]
    fn exact_linear_data_picks_two_joints_and_the_smallest_ridge() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let truth = Coefficients::from_fn(|_, _| rng.gen_range(-1.0..1.0));
        let data: Vec<(Features, Target)> = (0..30)
            .map(|_| {
                let mut f = Features::from_fn(|_, _| rng.gen_range(-0.6..0.6));
                f[FEATURES - 1] = 1.0;
                (f, truth.transpose() * f)
            })
            .collect();
        let errors: Vec<Real> = candidates()
            .iter()
            .map(|&(j, r)| {
                let masked: Vec<_> = data.iter().map(|(f, q)| (mask_features(*f, j), *q)).collect();
                leave_one_out_error(&masked, r * 30.0)
            })
            .collect();
        assert_eq!(best_candidate(&errors), (JointFeatures::TwoNearest, RIDGE_GRID[0]));
    }
}
