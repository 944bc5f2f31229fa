//! Rigid motions of candidate parts: the pose data in the layout the inner loops want,
//! the per-pose Kabsch fit of a vertex set (stage 1's own solver, `desal_fit`), and the
//! cost of explaining a vertex by a part's motions — stage 1's residual
//! `Σ_poses ‖R v_T + t − v_X‖`, summed over the non-template poses.

use desal_fit::{PairMoments, solve_rigid};
use desal_mesh::PoseSet;
use desal_mesh::math::{Mat3, Real, Vec3};
use rayon::prelude::*;

/// The template and the posed positions, each centred on its own centroid (a shift per
/// pose changes the translations, never the residuals, and keeps the raw moment sums
/// well conditioned). Posed positions are stored vertex-major, so the cost of one vertex
/// reads one contiguous run.
#[derive(Debug, Clone)]
pub(crate) struct PoseData {
    pub(crate) vertex_count: usize,
    /// Non-template poses (the template explains itself exactly and never counts).
    pub(crate) pose_count: usize,
    /// Centred template positions, by vertex.
    pub(crate) source: Vec<Vec3>,
    /// Centred posed positions: `targets[v * pose_count + p]`, `p` over the non-template
    /// poses in pose order.
    targets: Vec<Vec3>,
}

impl PoseData {
    pub(crate) fn new(poses: &PoseSet) -> Self {
        let moved: Vec<&[Vec3]> = (0..poses.pose_count())
            .filter(|&p| p != poses.template)
            .map(|p| poses.poses[p].as_slice())
            .collect();
        let centres: Vec<Vec3> = moved.iter().map(|pose| centroid(pose)).collect();
        let template = poses.template_positions();
        let centre = centroid(template);
        let source = template.iter().map(|p| p - centre).collect();
        let targets = (0..poses.vertex_count())
            .into_par_iter()
            .flat_map_iter(|v| moved.iter().zip(&centres).map(move |(pose, c)| pose[v] - c))
            .collect();
        Self { vertex_count: poses.vertex_count(), pose_count: moved.len(), source, targets }
    }

    /// The centred positions of vertex `v` in the non-template poses.
    #[inline]
    pub(crate) fn targets_of(&self, v: usize) -> &[Vec3] {
        &self.targets[v * self.pose_count..(v + 1) * self.pose_count]
    }
}

fn centroid(points: &[Vec3]) -> Vec3 {
    points.iter().sum::<Vec3>() / points.len().max(1) as Real
}

/// One part's rigid motion onto every non-template pose (centred frames).
#[derive(Debug, Clone)]
pub(crate) struct PartMotion {
    rotations: Vec<Mat3>,
    translations: Vec<Vec3>,
    /// The smallest ratio of the second to the first singular value of the part's
    /// cross-covariance over the poses: below `desal_fit`'s default `1e-9` stage 1
    /// would refuse the part as degenerate. 1 when there are no poses.
    pub(crate) min_ratio: Real,
}

/// Raw moment sums of a vertex set onto every non-template pose: everything the
/// rigid fits need. Sums are additive, so the
/// moments of a union of parts are the sums of theirs.
#[derive(Debug, Clone)]
pub(crate) struct Moments {
    count: usize,
    src_sum: Vec3,
    src_outer: Mat3,
    /// Per pose: `Σ d` and `Σ s dᵀ`.
    dst_sum: Vec<Vec3>,
    cross: Vec<Mat3>,
}

impl Moments {
    /// The moments of `members`, summed in the order given.
    pub(crate) fn of(data: &PoseData, members: &[u32]) -> Self {
        let poses = data.pose_count;
        let mut m = Self {
            count: members.len(),
            src_sum: Vec3::zeros(),
            src_outer: Mat3::zeros(),
            dst_sum: vec![Vec3::zeros(); poses],
            cross: vec![Mat3::zeros(); poses],
        };
        for &v in members {
            let s = data.source[v as usize];
            m.src_sum += s;
            m.src_outer += s * s.transpose();
            for (p, d) in data.targets_of(v as usize).iter().enumerate() {
                m.dst_sum[p] += d;
                m.cross[p] += s * d.transpose();
            }
        }
        m
    }

    /// Adds `other`'s sums to these.
    pub(crate) fn add(&mut self, other: &Moments) {
        self.count += other.count;
        self.src_sum += other.src_sum;
        self.src_outer += other.src_outer;
        for p in 0..self.dst_sum.len() {
            self.dst_sum[p] += other.dst_sum[p];
            self.cross[p] += other.cross[p];
        }
    }

    /// Stage 1's centred moments for pose `p`.
    fn pair_moments(&self, p: usize) -> PairMoments {
        let count = self.count as Real;
        let src_centroid = self.src_sum / count;
        let dst_centroid = self.dst_sum[p] / count;
        PairMoments {
            count: self.count,
            src_centroid,
            dst_centroid,
            cross: self.cross[p] - count * src_centroid * dst_centroid.transpose(),
            src_scatter: self.src_outer - count * src_centroid * src_centroid.transpose(),
        }
    }
}

impl PartMotion {
    /// The least-squares proper rigid motion of `members` (template → each pose), as
    /// stage 1 fits it.
    ///
    /// # Panics
    /// When `members` is empty.
    pub(crate) fn fit(data: &PoseData, members: &[u32]) -> Self {
        assert!(!members.is_empty(), "a part has at least one vertex");
        Self::from_moments(&Moments::of(data, members))
    }

    /// The rigid motion of the vertex set with these moments.
    pub(crate) fn from_moments(moments: &Moments) -> Self {
        let poses = moments.dst_sum.len();
        let mut motion = Self {
            rotations: Vec::with_capacity(poses),
            translations: Vec::with_capacity(poses),
            min_ratio: 1.0,
        };
        for p in 0..poses {
            let (rigid, singular) = solve_rigid(&moments.pair_moments(p));
            let ratio = if singular[0] > 0.0 { singular[1] / singular[0] } else { 0.0 };
            motion.min_ratio = motion.min_ratio.min(ratio);
            motion.rotations.push(rigid.rotation);
            motion.translations.push(rigid.translation);
        }
        motion
    }

    /// Stage 1's residual of vertex `v` under this motion, summed over the non-template
    /// poses (mesh units).
    #[inline]
    pub(crate) fn cost(&self, data: &PoseData, v: usize) -> Real {
        let s = data.source[v];
        let mut sum = 0.0;
        for ((r, t), d) in self.rotations.iter().zip(&self.translations).zip(data.targets_of(v)) {
            sum += (r * s + t - d).norm();
        }
        sum
    }
}

/// Fits every part: `members[part]` are its vertices. Parallel over parts, each fit a
/// sequential sum in vertex order, so the result does not depend on the thread count.
pub(crate) fn fit_parts(data: &PoseData, members: &[Vec<u32>]) -> Vec<PartMotion> {
    members.par_iter().map(|m| PartMotion::fit(data, m)).collect()
}

/// `members[part]`: the vertices of every part, ascending.
pub(crate) fn members_of(labels: &[u32], part_count: usize) -> Vec<Vec<u32>> {
    let mut members = vec![Vec::new(); part_count];
    for (v, &p) in labels.iter().enumerate() {
        members[p as usize].push(v as u32);
    }
    members
}

/// Each vertex's cost under its own part, in parallel (order-preserving).
pub(crate) fn own_costs(data: &PoseData, motions: &[PartMotion], labels: &[u32]) -> Vec<Real> {
    (0..data.vertex_count).into_par_iter().map(|v| motions[labels[v] as usize].cost(data, v)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use desal_mesh::math::UnitQuat;

    /// A tetrahedron moved rigidly: the fit explains it exactly (cost 0 to rounding),
    /// and a translated copy of a vertex costs exactly its offset in each pose.
    #[test]
    fn a_rigid_motion_is_explained_exactly() {
        let template = vec![Vec3::zeros(), Vec3::x(), Vec3::y(), Vec3::z()];
        let rotation =
            UnitQuat::from_scaled_axis(Vec3::new(0.3, -0.2, 0.9)).to_rotation_matrix().into_inner();
        let moved: Vec<Vec3> = template.iter().map(|p| rotation * p + Vec3::new(1.0, 2.0, 3.0)).collect();
        let poses = PoseSet::try_new(
            vec!["t".into(), "a".into(), "b".into()],
            vec![template.clone(), moved.clone(), moved],
            vec![[0, 1, 2], [0, 3, 1], [1, 3, 2], [0, 2, 3]],
            0,
        )
        .unwrap();
        let data = PoseData::new(&poses);
        assert_eq!(data.pose_count, 2);
        let motion = PartMotion::fit(&data, &[0, 1, 2, 3]);
        for v in 0..4 {
            assert!(motion.cost(&data, v) < 1e-12, "vertex {v}: {}", motion.cost(&data, v));
        }
        assert!(motion.min_ratio > 0.1);
        // Moving vertex 3 by 0.5 in pose 'b' only makes the fit inexact; moments add
        // up, so the fit from the moments of {0, 1} plus those of {2, 3} is the fit of
        // all four (to rounding).
        let mut shifted = poses.clone();
        shifted.poses[2][3] += Vec3::new(0.5, 0.0, 0.0);
        let data = PoseData::new(&shifted);
        let whole = PartMotion::fit(&data, &[0, 1, 2, 3]);
        let mut sum = Moments::of(&data, &[0, 1]);
        sum.add(&Moments::of(&data, &[2, 3]));
        let added = PartMotion::from_moments(&sum);
        assert!(whole.cost(&data, 3) > 0.1);
        for v in 0..4 {
            assert!((whole.cost(&data, v) - added.cost(&data, v)).abs() < 1e-12);
        }
        // Three collinear vertices have no second singular value.
        let line = PoseSet::try_new(
            vec!["t".into(), "a".into()],
            vec![
                vec![Vec3::zeros(), Vec3::x(), 2.0 * Vec3::x()],
                vec![Vec3::zeros(), Vec3::y(), 2.0 * Vec3::y()],
            ],
            vec![[0, 1, 2]],
            0,
        )
        .unwrap();
        assert!(PartMotion::fit(&PoseData::new(&line), &[0, 1, 2]).min_ratio < 1e-9);
    }
}
