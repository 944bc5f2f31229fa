//! Least-squares alignment of two paired point sets: the rigid solver (Kabsch 1976,
//! with Umeyama's 1991 reflection fix) and the unconstrained affine solver.
//!
//! References:
//! - W. Kabsch, "A solution for the best rotation to relate two sets of vectors",
//!   Acta Cryst. A32 (1976).
//! - S. Umeyama, "Least-squares estimation of transformation parameters between two
//!   point patterns", IEEE TPAMI 13(4) (1991): the sign correction that keeps the
//!   result a proper rotation (det = +1) even when the best orthogonal matrix is a
//!   reflection.
//!
//! Both solvers work on the centred second moments of the pairs ([`PairMoments`]), so
//! the stage can accumulate them over a part's vertex indices without copying points.

use desal_mesh::math::{Mat3, Real, Vec3};

/// A proper rigid motion `p ↦ rotation · p + translation` (`det(rotation) = +1`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidTransform {
    pub rotation: Mat3,
    pub translation: Vec3,
}

impl RigidTransform {
    pub fn identity() -> Self {
        Self { rotation: Mat3::identity(), translation: Vec3::zeros() }
    }

    /// The image of point `p`.
    #[inline]
    pub fn apply(&self, p: &Vec3) -> Vec3 {
        self.rotation * p + self.translation
    }
}

/// A general affine map `p ↦ linear · p + translation` (no orthogonality constraint).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AffineTransform {
    pub linear: Mat3,
    pub translation: Vec3,
}

impl AffineTransform {
    /// The image of point `p`.
    #[inline]
    pub fn apply(&self, p: &Vec3) -> Vec3 {
        self.linear * p + self.translation
    }
}

/// Centred second moments of paired points `(s_i, d_i)`: everything the rigid and the
/// affine least-squares solutions need.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PairMoments {
    /// Number of pairs.
    pub count: usize,
    /// Mean of the source points.
    pub src_centroid: Vec3,
    /// Mean of the destination points.
    pub dst_centroid: Vec3,
    /// `Σ (s_i − s̄)(d_i − d̄)ᵀ`, the cross-covariance (unnormalised).
    pub cross: Mat3,
    /// `Σ (s_i − s̄)(s_i − s̄)ᵀ`, the source scatter (unnormalised).
    pub src_scatter: Mat3,
}

impl PairMoments {
    /// Moments of `pairs`, which is iterated twice: centroids first, then centred
    /// products (the two-pass form keeps precision when points sit far from the origin).
    ///
    /// # Panics
    /// When `pairs` is empty.
    pub fn from_pairs<I>(pairs: I) -> Self
    where
        I: Iterator<Item = (Vec3, Vec3)> + Clone,
    {
        let mut count = 0usize;
        let (mut src_sum, mut dst_sum) = (Vec3::zeros(), Vec3::zeros());
        for (s, d) in pairs.clone() {
            src_sum += s;
            dst_sum += d;
            count += 1;
        }
        assert!(count > 0, "alignment needs at least one point pair");
        let src_centroid = src_sum / count as Real;
        let dst_centroid = dst_sum / count as Real;
        let (mut cross, mut src_scatter) = (Mat3::zeros(), Mat3::zeros());
        for (s, d) in pairs {
            let (sc, dc) = (s - src_centroid, d - dst_centroid);
            cross += sc * dc.transpose();
            src_scatter += sc * sc.transpose();
        }
        Self { count, src_centroid, dst_centroid, cross, src_scatter }
    }

    /// Moments of the pairs `(src[i], dst[i])` for every `i` in `indices`.
    pub fn from_indexed(indices: &[u32], src: &[Vec3], dst: &[Vec3]) -> Self {
        Self::from_pairs(indices.iter().map(|&i| (src[i as usize], dst[i as usize])))
    }
}

/// The proper rotation and translation minimising `Σ ‖R s_i + t − d_i‖²`, with the
/// singular values of the cross-covariance (descending), which tell how well the
/// rotation is determined: it is unique when the second one is non-zero.
pub fn solve_rigid(moments: &PairMoments) -> (RigidTransform, [Real; 3]) {
    // H = U Σ Vᵀ; the best orthogonal matrix is V Uᵀ. When that is a reflection, the
    // best *rotation* flips the axis of the smallest singular value (Umeyama).
    let svd = moments.cross.svd(true, true);
    let (u, v_t) = (svd.u.expect("u requested"), svd.v_t.expect("v_t requested"));
    let v = v_t.transpose();
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]).then(a.cmp(&b)));
    let smallest = order[2];
    let mut flip = Mat3::identity();
    if (v * u.transpose()).determinant() < 0.0 {
        flip[(smallest, smallest)] = -1.0;
    }
    let rotation = v * flip * u.transpose();
    let translation = moments.dst_centroid - rotation * moments.src_centroid;
    let singular = order.map(|k| svd.singular_values[k]);
    (RigidTransform { rotation, translation }, singular)
}

/// The affine map minimising `Σ ‖A s_i + t − d_i‖²` (the paper's literal "vectorise R
/// and t" reading of Eq. 1). When the source points are planar the linear part is not
/// unique; the minimum-norm solution is returned (the residuals are optimal either
/// way). Eigenvalues of the source scatter below `1e-12` of the largest count as zero.
pub fn solve_affine(moments: &PairMoments) -> AffineTransform {
    // Normal equations: A S = Cᵀ with S the source scatter and C the cross-covariance.
    let eigen = moments.src_scatter.symmetric_eigen();
    let largest = eigen.eigenvalues.iter().copied().fold(0.0, Real::max);
    let mut inverse = Mat3::zeros();
    for k in 0..3 {
        let lambda = eigen.eigenvalues[k];
        if lambda > 1e-12 * largest {
            let q = eigen.eigenvectors.column(k);
            inverse += q * q.transpose() / lambda;
        }
    }
    let linear = moments.cross.transpose() * inverse;
    let translation = moments.dst_centroid - linear * moments.src_centroid;
    AffineTransform { linear, translation }
}

/// The proper rigid transform that best maps `src[i]` onto `dst[i]` in the least-squares
/// sense (Kabsch with the reflection fix). Degenerate input (collinear or coincident
/// points) still yields *a* proper rotation that attains the minimum, just not a unique
/// one; use [`PairMoments`] and [`solve_rigid`] to inspect the singular values.
///
/// # Panics
/// When the slices differ in length or are empty.
pub fn kabsch(src: &[Vec3], dst: &[Vec3]) -> RigidTransform {
    assert_eq!(src.len(), dst.len(), "kabsch needs paired points");
    solve_rigid(&PairMoments::from_pairs(src.iter().copied().zip(dst.iter().copied()))).0
}

/// The affine map that best maps `src[i]` onto `dst[i]` (see [`solve_affine`]).
///
/// # Panics
/// When the slices differ in length or are empty.
pub fn affine_fit(src: &[Vec3], dst: &[Vec3]) -> AffineTransform {
    assert_eq!(src.len(), dst.len(), "affine_fit needs paired points");
    solve_affine(&PairMoments::from_pairs(src.iter().copied().zip(dst.iter().copied())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use desal_mesh::math::UnitQuat;
    use proptest::prelude::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn random_points(rng: &mut ChaCha8Rng, n: usize) -> Vec<Vec3> {
        (0..n)
            .map(|_| Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0)))
            .collect()
    }

    fn random_rotation(rng: &mut ChaCha8Rng) -> Mat3 {
        let axis = Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
        let angle = rng.gen_range(-3.1..3.1);
        UnitQuat::from_scaled_axis(axis.normalize() * angle).to_rotation_matrix().into_inner()
    }

    fn max_abs(m: Mat3) -> Real {
        m.iter().fold(0.0, |a, x| a.max(x.abs()))
    }

    fn sum_sq(t: &RigidTransform, src: &[Vec3], dst: &[Vec3]) -> Real {
        src.iter().zip(dst).map(|(s, d)| (t.apply(s) - d).norm_squared()).sum()
    }

    /// The textbook solution without the sign correction: `V Uᵀ`.
    fn naive_rotation(src: &[Vec3], dst: &[Vec3]) -> Mat3 {
        let m = PairMoments::from_pairs(src.iter().copied().zip(dst.iter().copied()));
        let svd = m.cross.svd(true, true);
        svd.v_t.unwrap().transpose() * svd.u.unwrap().transpose()
    }

    #[test]
    fn kabsch_recovers_random_rigid_motions_to_1e12() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for _ in 0..200 {
            let src = random_points(&mut rng, 40);
            let rotation = random_rotation(&mut rng);
            let translation = Vec3::new(rng.gen_range(-5.0..5.0), rng.gen_range(-5.0..5.0), 3.0);
            let dst: Vec<Vec3> = src.iter().map(|p| rotation * p + translation).collect();
            let fit = kabsch(&src, &dst);
            assert!(max_abs(fit.rotation - rotation) < 1e-12, "{}", fit.rotation - rotation);
            assert!((fit.translation - translation).amax() < 1e-12);
        }
    }

    /// Planar points: the cross-covariance has rank 2, so the third singular vectors'
    /// signs are arbitrary and `V Uᵀ` is a reflection for some inputs. The corrected
    /// solver must still recover the true rotation; the test also proves (by the
    /// count) that the naive solver really fails on some of these inputs.
    #[test]
    fn kabsch_recovers_rotations_of_planar_parts_where_naive_svd_reflects() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut naive_reflections = 0;
        for _ in 0..200 {
            let src: Vec<Vec3> =
                random_points(&mut rng, 12).into_iter().map(|p| Vec3::new(p.x, p.y, 0.0)).collect();
            let rotation = random_rotation(&mut rng);
            let translation = Vec3::new(0.5, -2.0, 1.0);
            let dst: Vec<Vec3> = src.iter().map(|p| rotation * p + translation).collect();
            if naive_rotation(&src, &dst).determinant() < 0.0 {
                naive_reflections += 1;
            }
            let fit = kabsch(&src, &dst);
            assert!(max_abs(fit.rotation - rotation) < 1e-12, "{}", fit.rotation - rotation);
            assert!((fit.translation - translation).amax() < 1e-12);
        }
        assert!(naive_reflections > 0, "the test data never triggers the reflection case");
    }

    /// A mirrored target: the best orthogonal map is the mirror itself (det = −1),
    /// which is what the naive solver returns. The corrected solver must return a
    /// proper rotation, and the best one: no sampled rotation (random, or a small
    /// perturbation of the answer) may fit better.
    #[test]
    fn kabsch_returns_the_best_proper_rotation_for_a_mirrored_target() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let src: Vec<Vec3> =
            random_points(&mut rng, 30).into_iter().map(|p| Vec3::new(2.0 * p.x, p.y, 0.5 * p.z)).collect();
        let mirror = Mat3::from_diagonal(&Vec3::new(1.0, 1.0, -1.0));
        let dst: Vec<Vec3> = src.iter().map(|p| mirror * p).collect();
        assert!(naive_rotation(&src, &dst).determinant() < 0.0);

        let fit = kabsch(&src, &dst);
        assert!((fit.rotation.determinant() - 1.0).abs() < 1e-12);
        assert!(max_abs(fit.rotation.transpose() * fit.rotation - Mat3::identity()) < 1e-12);
        let best = sum_sq(&fit, &src, &dst);
        let centroid_src = src.iter().sum::<Vec3>() / src.len() as Real;
        let centroid_dst = dst.iter().sum::<Vec3>() / dst.len() as Real;
        for k in 0..2000 {
            let rotation = if k % 2 == 0 {
                random_rotation(&mut rng)
            } else {
                let small =
                    Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
                UnitQuat::from_scaled_axis(small * 1e-3).to_rotation_matrix().into_inner() * fit.rotation
            };
            let candidate = RigidTransform { rotation, translation: centroid_dst - rotation * centroid_src };
            assert!(sum_sq(&candidate, &src, &dst) >= best - 1e-12);
        }
    }

    #[test]
    fn affine_fit_recovers_an_affine_map() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let src = random_points(&mut rng, 25);
        let linear = Mat3::new(1.2, 0.3, -0.1, 0.0, 0.8, 0.4, 0.2, -0.5, 1.5);
        let translation = Vec3::new(1.0, 2.0, 3.0);
        let dst: Vec<Vec3> = src.iter().map(|p| linear * p + translation).collect();
        let fit = affine_fit(&src, &dst);
        assert!(max_abs(fit.linear - linear) < 1e-12);
        assert!((fit.translation - translation).amax() < 1e-12);
    }

    #[test]
    fn affine_fit_of_planar_points_is_exact_on_the_points() {
        let src = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
        ];
        let dst: Vec<Vec3> = src.iter().map(|p| Vec3::new(2.0 * p.x, p.y + p.x, 1.0)).collect();
        let fit = affine_fit(&src, &dst);
        for (s, d) in src.iter().zip(&dst) {
            assert!((fit.apply(s) - d).norm() < 1e-12);
        }
    }

    proptest! {
        /// The affine family contains every rigid motion, so its least-squares residual
        /// can never exceed the rigid one.
        #[test]
        fn affine_residual_never_exceeds_rigid(seed in 0u64..10_000, noise in 0.0f64..0.5) {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let src = random_points(&mut rng, 15);
            let rotation = random_rotation(&mut rng);
            let dst: Vec<Vec3> = src
                .iter()
                .map(|p| rotation * p + Vec3::new(rng.gen_range(-noise..=noise), rng.gen_range(-noise..=noise), 0.1))
                .collect();
            let rigid = kabsch(&src, &dst);
            let affine = affine_fit(&src, &dst);
            let rigid_sq = sum_sq(&rigid, &src, &dst);
            let affine_sq: Real = src.iter().zip(&dst).map(|(s, d)| (affine.apply(s) - d).norm_squared()).sum();
            prop_assert!(affine_sq <= rigid_sq + 1e-12);
        }

        /// Kabsch is optimal: no random rotation (with its best translation) does better.
        #[test]
        fn kabsch_beats_random_rotations(seed in 0u64..10_000) {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let src = random_points(&mut rng, 10);
            let dst = random_points(&mut rng, 10);
            let fit = kabsch(&src, &dst);
            prop_assert!((fit.rotation.determinant() - 1.0).abs() < 1e-12);
            let best = sum_sq(&fit, &src, &dst);
            let cs = src.iter().sum::<Vec3>() / 10.0;
            let cd = dst.iter().sum::<Vec3>() / 10.0;
            for _ in 0..50 {
                let rotation = random_rotation(&mut rng);
                let candidate = RigidTransform { rotation, translation: cd - rotation * cs };
                prop_assert!(sum_sq(&candidate, &src, &dst) >= best - 1e-12);
            }
        }
    }
}
