//! Evaluating a model, exactly as SMPL's official code (Loper et al. 2015, "SMPL: A
//! Skinned Multi-Person Linear Model", §3, eq. 1–4 and 10) and body-models' NumPy backend:
//!
//! 1. shape: `v_shaped = v_template + shapedirs · β (+ exprdirs · ψ)`;
//! 2. joints: `J = J_regressor · v_shaped`;
//! 3. pose blend shapes: `v_posed = v_shaped + posedirs · vec(R(θ_j) − I)` over joints
//!    `j ≥ 1`, each 3×3 flattened row by row, `R` by Rodrigues' formula;
//! 4. forward kinematics along the tree: `G_0 = (R_0, J_0)`,
//!    `G_j = G_parent ∘ (R_j, J_j − J_parent)`;
//! 5. linear blend skinning: `v = Σ_j w_j (G_j · (v_posed − J_j))`, plus a translation.
//!
//! Everything is f64. [`BodyModel::shape`] (steps 1–2) is kept apart from
//! [`BodyModel::pose`] (3–5) so that many poses of one shape pay for the shape once.

use desal_mesh::{Mat3, Vec3};

use crate::error::BodyModelError;
use crate::model::BodyModel;

/// A model's rest surface and joints for one shape (and expression).
#[derive(Debug, Clone, PartialEq)]
pub struct Shaped {
    /// `v_shaped[vertex]`, in the model's units (metres for the SMPL family).
    pub vertices: Vec<Vec3>,
    /// Rest joint positions, `J_regressor · v_shaped`.
    pub joints: Vec<Vec3>,
}

/// A posed model.
#[derive(Debug, Clone, PartialEq)]
pub struct Posed {
    pub vertices: Vec<Vec3>,
    /// Posed joint positions (the world translations of forward kinematics).
    pub joints: Vec<Vec3>,
}

/// One item of [`BodyModel::pose_batch`].
#[derive(Debug, Clone, Copy)]
pub struct PoseItem<'a> {
    pub shaped: &'a Shaped,
    /// One axis-angle per joint.
    pub pose: &'a [Vec3],
    pub translation: Vec3,
}

/// One evaluation's parameters. Shorter `betas` or `expression` than the model's bases
/// leave the remaining components at zero (as body-models does).
#[derive(Debug, Clone, Copy)]
pub struct Params<'a> {
    pub betas: &'a [f64],
    pub expression: &'a [f64],
    /// One axis-angle per joint, joint 0 the global orientation about the root joint.
    pub pose: &'a [Vec3],
    pub translation: Vec3,
}

impl BodyModel {
    /// Steps 1–2: the shaped rest surface and its joints.
    pub fn shape(&self, betas: &[f64], expression: &[f64]) -> Result<Shaped, BodyModelError> {
        check_count("betas", betas.len(), self.shape_count)?;
        check_count("expression coefficients", expression.len(), self.expression_count)?;
        let mut vertices = self.v_template.clone();
        add_blend_shapes(&mut vertices, &self.shapedirs, self.shape_count, betas);
        add_blend_shapes(&mut vertices, &self.exprdirs, self.expression_count, expression);
        let joints = (0..self.joint_count())
            .map(|j| self.joint_regressor.row(j).fold(Vec3::zeros(), |acc, (v, w)| acc + vertices[v] * w))
            .collect();
        Ok(Shaped { vertices, joints })
    }

    /// Steps 3–5: `shaped` posed by one axis-angle per joint, then translated.
    pub fn pose(&self, shaped: &Shaped, pose: &[Vec3], translation: Vec3) -> Result<Posed, BodyModelError> {
        let mut posed = self.pose_batch(&[PoseItem { shaped, pose, translation }])?;
        Ok(posed.pop().expect("one item in, one out"))
    }

    /// [`BodyModel::pose`] for several items at once, the same numbers bit for bit: the
    /// pose correctives, the largest array (`V · 3 · 9 (J − 1)` values), are read once for
    /// the whole batch instead of once per pose.
    pub fn pose_batch(&self, items: &[PoseItem]) -> Result<Vec<Posed>, BodyModelError> {
        if let Some(item) = items.iter().find(|item| item.pose.len() != self.joint_count()) {
            return Err(BodyModelError::BadParameters {
                what: "joint rotations",
                given: item.pose.len(),
                available: self.joint_count(),
            });
        }
        let rotations: Vec<Vec<Mat3>> =
            items.iter().map(|item| item.pose.iter().map(rodrigues).collect()).collect();
        let posed_rest = self.add_pose_blend_shapes(items, &rotations);
        let posed = items.iter().zip(&rotations).zip(posed_rest).map(|((item, rotations), rest)| {
            let world = self.forward_kinematics(&item.shaped.joints, rotations);
            // Skinning transforms: world motion relative to the rest joint.
            let skinning: Vec<(Mat3, Vec3)> =
                world.iter().zip(&item.shaped.joints).map(|((r, t), j)| (*r, t - r * j)).collect();
            let vertices = rest
                .iter()
                .enumerate()
                .map(|(v, p)| {
                    let (mut r, mut t) = (Mat3::zeros(), Vec3::zeros());
                    for (joint, w) in self.weights.row(v) {
                        r += skinning[joint].0 * w;
                        t += skinning[joint].1 * w;
                    }
                    r * p + t + item.translation
                })
                .collect();
            let joints = world.iter().map(|(_, t)| t + item.translation).collect();
            Posed { vertices, joints }
        });
        Ok(posed.collect())
    }

    /// Steps 1–5 in one call.
    pub fn evaluate(&self, params: &Params) -> Result<Posed, BodyModelError> {
        let shaped = self.shape(params.betas, params.expression)?;
        self.pose(&shaped, params.pose, params.translation)
    }

    /// Per item, `v_shaped + posedirs · vec(R_j − I)` over joints 1.. (the root's rotation
    /// moves the whole body rigidly and has no corrective); each row of `posedirs` is
    /// read once for all items.
    fn add_pose_blend_shapes(&self, items: &[PoseItem], rotations: &[Vec<Mat3>]) -> Vec<Vec<Vec3>> {
        let features: Vec<Vec<f64>> = rotations
            .iter()
            .map(|rotations| {
                let mut feature = Vec::with_capacity(self.pose_feature_count());
                for r in &rotations[1..] {
                    let delta = r - Mat3::identity();
                    // Row by row, as numpy flattens a C-order (3, 3) block.
                    feature.extend((0..9).map(|k| delta[(k / 3, k % 3)]));
                }
                feature
            })
            .collect();
        let mut out: Vec<Vec<Vec3>> = items.iter().map(|item| item.shaped.vertices.clone()).collect();
        let columns = self.pose_feature_count();
        if columns == 0 {
            return out;
        }
        for (v, rows) in self.posedirs.chunks_exact(3 * columns).enumerate() {
            for axis in 0..3 {
                let row = &rows[axis * columns..(axis + 1) * columns];
                for (posed, feature) in out.iter_mut().zip(&features) {
                    posed[v][axis] += dot(row, feature);
                }
            }
        }
        out
    }

    /// World rotation and translation of every joint; parents come first.
    fn forward_kinematics(&self, joints: &[Vec3], rotations: &[Mat3]) -> Vec<(Mat3, Vec3)> {
        let mut world: Vec<(Mat3, Vec3)> = Vec::with_capacity(joints.len());
        for (j, r) in rotations.iter().enumerate() {
            let g = match self.parents[j] {
                None => (*r, joints[j]),
                Some(p) => {
                    let (rp, tp) = world[p];
                    (rp * r, rp * (joints[j] - joints[p]) + tp)
                }
            };
            world.push(g);
        }
        world
    }
}

fn check_count(what: &'static str, given: usize, available: usize) -> Result<(), BodyModelError> {
    if given > available {
        return Err(BodyModelError::BadParameters { what, given, available });
    }
    Ok(())
}

/// `vertices += dirs · coefficients`, `dirs` row-major `(V·3, columns)`; only the first
/// `coefficients.len()` columns are used.
fn add_blend_shapes(vertices: &mut [Vec3], dirs: &[f64], columns: usize, coefficients: &[f64]) {
    if coefficients.is_empty() || columns == 0 {
        return;
    }
    let n = coefficients.len();
    for (vertex, rows) in vertices.iter_mut().zip(dirs.chunks_exact(3 * columns)) {
        for axis in 0..3 {
            vertex[axis] += dot(&rows[axis * columns..axis * columns + n], coefficients);
        }
    }
}

/// `a · b` in four interleaved partial sums, which the compiler vectorises (a single
/// running sum must be added in order and is not); the order is fixed, so the result is
/// the same on every run.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut lanes = [0.0f64; 4];
    let (a4, b4) = (a.chunks_exact(4), b.chunks_exact(4));
    let (a_rest, b_rest) = (a4.remainder(), b4.remainder());
    for (x, y) in a4.zip(b4) {
        for k in 0..4 {
            lanes[k] += x[k] * y[k];
        }
    }
    let tail: f64 = a_rest.iter().zip(b_rest).map(|(x, y)| x * y).sum();
    (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]) + tail
}

/// Rodrigues' formula: the rotation by `|r|` about `r / |r|`, as
/// `I + (sin θ / θ) K + ((1 − cos θ) / θ²) K²` with `K = [r]×`; below 1e-12 rad the
/// first-order `I + K`, which is exact to double precision there.
pub fn rodrigues(r: &Vec3) -> Mat3 {
    let theta = r.norm();
    let k = r.cross_matrix();
    if theta < 1e-12 {
        return Mat3::identity() + k;
    }
    let (s, c) = theta.sin_cos();
    Mat3::identity() + k * (s / theta) + k * k * ((1.0 - c) / (theta * theta))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A quarter turn about z takes x to y; the result is a rotation.
    #[test]
    fn rodrigues_quarter_turn() {
        let r = rodrigues(&Vec3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2));
        assert!((r * Vec3::x() - Vec3::y()).norm() < 1e-15);
        assert!((r * r.transpose() - Mat3::identity()).norm() < 1e-15);
        assert_eq!(rodrigues(&Vec3::zeros()), Mat3::identity());
    }
}
