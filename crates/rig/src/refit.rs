//! Least-squares skinning weights for a vertex placed anew (optimal placement): the
//! weights `w` over candidate joints that make its linear blend skinning follow target
//! positions across the pose set,
//!
//! `min_w Σ_k ‖ Σ_j w_j · M_jk · x − y_k ‖²`   subject to `w ≥ 0`, `Σ_j w_j = 1`, at most 4
//! non-zero,
//!
//! with `x` the vertex's bind position, `M_jk` joint `j`'s skinning matrix in pose `k`
//! and `y_k` the target in pose `k`. The simplex constraint is enforced as a heavily
//! weighted extra row inside Lawson–Hanson non-negative least squares (Lawson & Hanson
//! 1974, ch. 23), then the weights are renormalised exactly. With more than 4 non-zero
//! weights, the 4 largest are kept and refitted.

use desal_mesh::Vec3;
use desal_mesh::math::Mat4;
use nalgebra::{DMatrix, DVector};

use crate::pose::transform_point;

/// Most influences a refitted vertex keeps by default (glTF's one `JOINTS_0`/`WEIGHTS_0`
/// set, what every engine skins).
pub const MAX_INFLUENCES: usize = 4;

/// Weight of the `Σ w = 1` row relative to the data rows (scaled by their magnitude).
const SUM_ROW_WEIGHT: f64 = 1e3;

/// Fits weights over `candidates` (skin joint indices). `joints[k][j]` is joint `j`'s
/// skinning matrix in pose `k`, `targets[k]` the target position in pose `k`. Returns
/// `(joint, weight)` pairs, weights positive and summing to 1 (at most `max_influences`,
/// at least 1), and the fit's sum of squared residuals; `None` when no candidate is given.
pub fn fit_weights(
    x: &Vec3,
    candidates: &[usize],
    joints: &[Vec<Mat4>],
    targets: &[Vec3],
    max_influences: usize,
) -> Option<(Vec<(usize, f64)>, f64)> {
    let max_influences = max_influences.max(1);
    if candidates.is_empty() {
        return None;
    }
    // Columns: the vertex carried by each candidate joint, stacked over the poses.
    let rows = 3 * targets.len();
    let columns = |cands: &[usize]| {
        let mut a = DMatrix::<f64>::zeros(rows + 1, cands.len());
        for (c, &j) in cands.iter().enumerate() {
            for (k, pose) in joints.iter().enumerate() {
                let p = transform_point(&pose[j], x);
                a[(3 * k, c)] = p.x;
                a[(3 * k + 1, c)] = p.y;
                a[(3 * k + 2, c)] = p.z;
            }
        }
        a
    };
    let mut b = DVector::<f64>::zeros(rows + 1);
    for (k, y) in targets.iter().enumerate() {
        b[3 * k] = y.x;
        b[3 * k + 1] = y.y;
        b[3 * k + 2] = y.z;
    }
    let scale = SUM_ROW_WEIGHT * (1.0 + b.amax());
    b[rows] = scale;
    let solve = |cands: &[usize]| {
        let mut a = columns(cands);
        for c in 0..cands.len() {
            a[(rows, c)] = scale;
        }
        nnls(&a, &b)
    };
    let mut chosen: Vec<usize> = candidates.to_vec();
    let mut w = solve(&chosen);
    if w.iter().filter(|&&x| x > 0.0).count() > max_influences {
        let mut order: Vec<usize> = (0..chosen.len()).collect();
        order.sort_by(|&a, &b| w[b].total_cmp(&w[a]).then(a.cmp(&b)));
        order.truncate(max_influences);
        order.sort_unstable();
        chosen = order.iter().map(|&i| chosen[i]).collect();
        w = solve(&chosen);
    }
    let total: f64 = w.iter().sum();
    if total.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let weights: Vec<(usize, f64)> =
        chosen.iter().zip(w.iter()).filter(|(_, w)| **w > 0.0).map(|(&j, &w)| (j, w / total)).collect();
    let residual = residual(x, &weights, joints, targets);
    Some((weights, residual))
}

/// `Σ_k ‖ Σ_j w_j M_jk x − y_k ‖²`.
pub fn residual(x: &Vec3, weights: &[(usize, f64)], joints: &[Vec<Mat4>], targets: &[Vec3]) -> f64 {
    joints
        .iter()
        .zip(targets)
        .map(|(pose, y)| {
            let p: Vec3 = weights.iter().map(|&(j, w)| w * transform_point(&pose[j], x)).sum();
            (p - y).norm_squared()
        })
        .sum()
}

/// Lawson–Hanson non-negative least squares: `argmin ‖A w − b‖` over `w ≥ 0`.
fn nnls(a: &DMatrix<f64>, b: &DVector<f64>) -> Vec<f64> {
    let n = a.ncols();
    let mut w = DVector::<f64>::zeros(n);
    let mut passive = vec![false; n];
    let tolerance = 1e-12 * a.norm() * b.norm().max(1.0);
    for _ in 0..(3 * n + 10) {
        let gradient = a.transpose() * (b - a * &w);
        // The most promising inactive variable.
        let next = (0..n).filter(|&i| !passive[i]).max_by(|&i, &j| gradient[i].total_cmp(&gradient[j]));
        match next {
            Some(i) if gradient[i] > tolerance => passive[i] = true,
            _ => break,
        }
        loop {
            let z = solve_passive(a, b, &passive);
            if (0..n).filter(|&i| passive[i]).all(|i| z[i] > 0.0) {
                w = z;
                break;
            }
            // Step back to the boundary and drop the variables that reach zero.
            let mut alpha = f64::INFINITY;
            for i in (0..n).filter(|&i| passive[i] && z[i] <= 0.0) {
                alpha = alpha.min(w[i] / (w[i] - z[i]));
            }
            w = &w + alpha * (&z - &w);
            for i in 0..n {
                if passive[i] && w[i] <= 1e-15 {
                    passive[i] = false;
                    w[i] = 0.0;
                }
            }
            if !passive.iter().any(|&p| p) {
                break;
            }
        }
    }
    w.iter().map(|&x| x.max(0.0)).collect()
}

/// Unconstrained least squares on the passive columns; zeros elsewhere.
fn solve_passive(a: &DMatrix<f64>, b: &DVector<f64>, passive: &[bool]) -> DVector<f64> {
    let idx: Vec<usize> = (0..passive.len()).filter(|&i| passive[i]).collect();
    let sub = a.select_columns(&idx);
    let solution = sub.clone().svd(true, true).solve(b, 1e-12).unwrap_or_else(|_| DVector::zeros(idx.len()));
    let mut z = DVector::<f64>::zeros(passive.len());
    for (k, &i) in idx.iter().enumerate() {
        z[i] = solution[k];
    }
    z
}

#[cfg(test)]
mod tests {
    use super::*;

    fn translation(t: Vec3) -> Mat4 {
        Mat4::new_translation(&t)
    }

    #[test]
    fn recovers_the_weights_that_made_the_targets() {
        // Three joints translating differently; the targets blend two of them 0.3 / 0.7.
        let x = Vec3::new(0.1, 0.2, 0.3);
        let poses: Vec<Vec<Mat4>> = (0..5)
            .map(|k| {
                let k = k as f64;
                vec![
                    translation(Vec3::new(k, 0.0, 0.0)),
                    translation(Vec3::new(0.0, k * k, 0.0)),
                    translation(Vec3::new(0.0, 0.0, -k)),
                ]
            })
            .collect();
        let targets: Vec<Vec3> = poses
            .iter()
            .map(|p| 0.3 * transform_point(&p[0], &x) + 0.7 * transform_point(&p[2], &x))
            .collect();
        let (weights, residual) = fit_weights(&x, &[0, 1, 2], &poses, &targets, MAX_INFLUENCES).unwrap();
        assert_eq!(weights.len(), 2, "{weights:?}");
        assert_eq!(weights[0].0, 0);
        assert!((weights[0].1 - 0.3).abs() < 1e-9, "{weights:?}");
        assert_eq!(weights[1].0, 2);
        assert!((weights[1].1 - 0.7).abs() < 1e-9, "{weights:?}");
        assert!(residual < 1e-16);
    }

    #[test]
    fn keeps_at_most_four_non_negative_weights_summing_to_one() {
        let x = Vec3::new(0.5, -0.2, 0.1);
        let joints = 7;
        let poses: Vec<Vec<Mat4>> =
            (0..9)
                .map(|k| {
                    (0..joints)
                        .map(|j| {
                            let a = 0.3 * (k as f64 + 1.0) * ((j as f64) * 0.7).sin();
                            Mat4::new_rotation(Vec3::new(a, 0.5 * a, -0.2 * a))
                                .append_translation(&Vec3::new(0.1 * j as f64, 0.0, 0.05 * k as f64))
                        })
                        .collect()
                })
                .collect();
        // Targets far from any blend: force the constraints to bind.
        let targets: Vec<Vec3> = (0..9).map(|k| Vec3::new(-(k as f64), 2.0, 0.3)).collect();
        let candidates: Vec<usize> = (0..joints).collect();
        for limit in [MAX_INFLUENCES, 2, 1] {
            let (weights, _) = fit_weights(&x, &candidates, &poses, &targets, limit).unwrap();
            assert!(!weights.is_empty() && weights.len() <= limit, "{limit}: {weights:?}");
            assert!(weights.iter().all(|&(_, w)| w > 0.0));
            let total: f64 = weights.iter().map(|w| w.1).sum();
            assert!((total - 1.0).abs() < 1e-12);
        }
    }
}
