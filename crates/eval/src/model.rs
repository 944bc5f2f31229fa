//! The SCAPE pose-deformation model: fitting on a registered pose set, and synthesis of
//! a pose from its part rotations.
//!
//! Anguelov et al. 2005, "SCAPE: Shape Completion and Animation of People", §3–4 (pose
//! deformation only; no shape space). For triangle `k` of part `p(k)` in pose `X`:
//!
//! 1. the deformation gradient `T_k` from the template (Sumner & Popović frames,
//!    [`crate::gradient`]) is split into the part's rigid rotation and a non-rigid rest,
//!    `Q_k = R_{p(k)}ᵀ T_k`;
//! 2. the nine entries of `Q_k` are regressed linearly on the twists of the two joints
//!    nearest the triangle plus a constant ([`crate::skeleton`]): seven coefficients per
//!    entry, fitted per triangle by ridge-regularised least squares over the training
//!    poses;
//! 3. a new pose is synthesised from its part rotations alone: twists → predicted `Q_k`
//!    → `T_k = R_{p(k)} Q_k` → Poisson reconstruction ([`crate::poisson`]), moved to the
//!    target centroid.
//!
//! Rotations are inputs (`rotations[pose][part]`, mapping template part to posed part,
//! as stage 1's fit produces them), so the model is fitted on whatever mesh it is given —
//! full resolution or simplified — with the rotations fitted on that mesh.

use desal_mesh::{Mat3, PartLabels, PoseSet, Real, Vec3};
use nalgebra::{SMatrix, SVector};
use rayon::prelude::*;

use crate::error::EvalError;
use crate::gradient::{deformation_gradient, inverse_template_frame};
use crate::poisson::PoissonSolver;
use crate::skeleton::Skeleton;

/// Regression inputs per triangle: the twists (3 + 3, radians) of its two nearest joints
/// and a constant 1.
const FEATURES: usize = 7;
/// Regression outputs per triangle: the entries of `Q`, column-major.
const OUTPUTS: usize = 9;

type Features = SVector<Real, FEATURES>;
type Coefficients = SMatrix<Real, FEATURES, OUTPUTS>;

/// Settings of the deformation model.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelConfig {
    /// Ridge weight λ (rad⁻² in effect, dimensionless per pose): `λ · (number of training
    /// poses)` is added to the six twist diagonal entries of each triangle's normal
    /// equations — the constant term is not penalised. Scaling by the pose count makes λ
    /// a penalty relative to the *mean* squared error, so its effect does not depend on
    /// the number of poses. Default `1e-3`: far below the variance of a moving joint's
    /// twist (0.1–1 rad²), so it only damps joints that barely move in the training
    /// poses (whose coefficients would otherwise fit noise) and keeps the system solvable
    /// with fewer than seven training poses (with only the template, `Q = I`).
    pub ridge: Real,
    /// Root part of the joint tree (sets each joint's parent/child direction); `None`:
    /// the part with the most vertices. Twists only change sign with the direction, so
    /// this does not change the fitted model's predictions.
    pub root_part: Option<u32>,
}

impl Default for ModelConfig {
    fn default() -> Self {
        Self { ridge: 1e-3, root_part: None }
    }
}

/// What fitting found, for logs and reports.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelReport {
    pub training_pose_count: usize,
    pub triangle_count: usize,
    pub joint_count: usize,
    /// Mean over training (triangle, pose) pairs of `‖Q − Q̂‖²_F`, the squared Frobenius
    /// residual of the regression (dimensionless): how much non-rigid deformation the
    /// twists do not explain.
    pub mean_q_residual: Real,
    /// Nonzeros of the Poisson system's Cholesky factor.
    pub factor_nonzeros: usize,
}

/// A fitted SCAPE pose-deformation model for one mesh (its template and triangles).
#[derive(Debug)]
pub struct Model {
    skeleton: Skeleton,
    part_count: usize,
    /// Per triangle, `Q` (column-major) `= coefficientsᵀ · features`.
    coefficients: Vec<Coefficients>,
    solver: PoissonSolver,
    report: ModelReport,
}

/// Fits the model on the poses `training_poses` of `poses`.
///
/// - `labels`: one part id per vertex of `poses` (same vertex index space);
/// - `rotations[pose][part]`: the rotation taking part `part` of the template to pose
///   `pose`, for **every** pose of the set (only the training poses are read);
/// - `training_poses`: distinct pose indices; the template need not be among them (with
///   held-out folds it always is, see [`crate::folds`]).
///
/// Cost: one pass over triangles × training poses, one sparse factorisation.
pub fn fit_model(
    poses: &PoseSet,
    labels: &PartLabels,
    rotations: &[Vec<Mat3>],
    training_poses: &[usize],
    config: &ModelConfig,
) -> Result<Model, EvalError> {
    check_inputs(poses, labels, rotations, training_poses)?;
    let template = poses.template_positions();
    let skeleton = Skeleton::new(template, &poses.faces, labels, config.root_part);
    let inverse_frames = invert_template_frames(poses)?;
    let training_twists: Vec<Vec<Vec3>> =
        training_poses.iter().map(|&p| skeleton.twists(&rotations[p])).collect();

    // Each triangle's regression is independent: fit them in parallel, in face order.
    let fits: Vec<(Coefficients, Real)> = (0..poses.face_count())
        .into_par_iter()
        .map(|face| {
            let samples = training_poses.iter().zip(&training_twists).map(|(&pose, twists)| {
                let features = triangle_features(&skeleton, face, twists);
                let q = non_rigid_deformation(poses, rotations, &skeleton, &inverse_frames, face, pose);
                (features, q)
            });
            regress_triangle(samples, config.ridge * training_poses.len() as Real)
        })
        .collect();

    let solver = PoissonSolver::new(template, &poses.faces)?;
    let residual_sum: Real = fits.iter().map(|(_, r)| r).sum();
    let report = ModelReport {
        training_pose_count: training_poses.len(),
        triangle_count: poses.face_count(),
        joint_count: skeleton.joints.len(),
        mean_q_residual: residual_sum / (poses.face_count() * training_poses.len()) as Real,
        factor_nonzeros: solver.factor_nonzeros(),
    };
    Ok(Model {
        skeleton,
        part_count: labels.part_count(),
        coefficients: fits.into_iter().map(|(w, _)| w).collect(),
        solver,
        report,
    })
}

impl Model {
    /// Synthesises a pose from its part rotations `rotations[part]` (template part →
    /// posed part) and moves it so that its vertex centroid is `target_centroid`.
    /// Returns positions in the model's vertex index space (the fitted pose set's).
    pub fn synthesize(&self, rotations: &[Mat3], target_centroid: Vec3) -> Result<Vec<Vec3>, EvalError> {
        self.check_rotations(rotations, 0)?;
        Ok(self.solver.solve(&self.predict_gradients(rotations), &target_centroid))
    }

    /// [`Model::synthesize`] for many poses in parallel: `rotations[i]` and
    /// `target_centroids[i]` describe pose `i`; results in the same order.
    pub fn synthesize_many(
        &self,
        rotations: &[Vec<Mat3>],
        target_centroids: &[Vec3],
    ) -> Result<Vec<Vec<Vec3>>, EvalError> {
        if rotations.len() != target_centroids.len() {
            return Err(EvalError::TargetCountMismatch {
                rotations: rotations.len(),
                centroids: target_centroids.len(),
            });
        }
        for (pose, r) in rotations.iter().enumerate() {
            self.check_rotations(r, pose)?;
        }
        Ok(rotations
            .par_iter()
            .zip(target_centroids)
            .map(|(r, c)| self.solver.solve(&self.predict_gradients(r), c))
            .collect())
    }

    /// The predicted non-rigid deformation `Q` of triangle `face` for a pose with the
    /// given joint twists (in [`Skeleton::joints`] order).
    pub fn predict_q(&self, face: usize, twists: &[Vec3]) -> Mat3 {
        let q = self.coefficients[face].transpose() * triangle_features(&self.skeleton, face, twists);
        Mat3::from_column_slice(q.as_slice())
    }

    pub fn skeleton(&self) -> &Skeleton {
        &self.skeleton
    }

    pub fn report(&self) -> &ModelReport {
        &self.report
    }

    pub fn vertex_count(&self) -> usize {
        self.solver.vertex_count()
    }

    /// `T_k = R_{p(k)} Q_k` for every triangle, in face order.
    fn predict_gradients(&self, rotations: &[Mat3]) -> Vec<Mat3> {
        let twists = self.skeleton.twists(rotations);
        (0..self.coefficients.len())
            .into_par_iter()
            .map(|face| {
                rotations[self.skeleton.triangle_parts[face] as usize] * self.predict_q(face, &twists)
            })
            .collect()
    }

    fn check_rotations(&self, rotations: &[Mat3], pose: usize) -> Result<(), EvalError> {
        if rotations.len() != self.part_count {
            return Err(EvalError::RotationPartCount {
                pose,
                expected: self.part_count,
                found: rotations.len(),
            });
        }
        if let Some(part) = rotations.iter().position(|r| !r.iter().all(|x| x.is_finite())) {
            return Err(EvalError::NonFiniteRotation { pose, part });
        }
        Ok(())
    }
}

fn check_inputs(
    poses: &PoseSet,
    labels: &PartLabels,
    rotations: &[Vec<Mat3>],
    training_poses: &[usize],
) -> Result<(), EvalError> {
    if labels.vertex_count() != poses.vertex_count() {
        return Err(EvalError::LabelCountMismatch {
            labels: labels.vertex_count(),
            vertices: poses.vertex_count(),
        });
    }
    if rotations.len() != poses.pose_count() {
        return Err(EvalError::RotationPoseCount { expected: poses.pose_count(), found: rotations.len() });
    }
    if training_poses.is_empty() {
        return Err(EvalError::NoTrainingPoses);
    }
    let mut seen = vec![false; poses.pose_count()];
    for &pose in training_poses {
        if pose >= poses.pose_count() {
            return Err(EvalError::TrainingPoseOutOfRange { pose, pose_count: poses.pose_count() });
        }
        if std::mem::replace(&mut seen[pose], true) {
            return Err(EvalError::DuplicateTrainingPose { pose });
        }
        let r = &rotations[pose];
        if r.len() != labels.part_count() {
            return Err(EvalError::RotationPartCount { pose, expected: labels.part_count(), found: r.len() });
        }
        if let Some(part) = r.iter().position(|m| !m.iter().all(|x| x.is_finite())) {
            return Err(EvalError::NonFiniteRotation { pose, part });
        }
    }
    Ok(())
}

/// `V̂⁻¹` per template triangle; a zero-area triangle is an error naming the face.
fn invert_template_frames(poses: &PoseSet) -> Result<Vec<Mat3>, EvalError> {
    let template = poses.template_positions();
    poses
        .faces
        .iter()
        .enumerate()
        .map(|(face, &[a, b, c])| {
            inverse_template_frame(&template[a as usize], &template[b as usize], &template[c as usize])
                .ok_or(EvalError::DegenerateTriangle { face })
        })
        .collect()
}

/// `[twist of nearest joint, twist of second nearest joint, 1]`; a missing joint (a mesh
/// with fewer than two joints) contributes zeros.
fn triangle_features(skeleton: &Skeleton, face: usize, twists: &[Vec3]) -> Features {
    let mut f = Features::zeros();
    for (slot, joint) in skeleton.triangle_joints[face].iter().enumerate() {
        if let Some(j) = joint {
            f.fixed_rows_mut::<3>(3 * slot).copy_from(&twists[*j as usize]);
        }
    }
    f[FEATURES - 1] = 1.0;
    f
}

/// `Q = R_{p(k)}ᵀ T_k` of triangle `face` in pose `pose`, column-major.
fn non_rigid_deformation(
    poses: &PoseSet,
    rotations: &[Vec<Mat3>],
    skeleton: &Skeleton,
    inverse_frames: &[Mat3],
    face: usize,
    pose: usize,
) -> SVector<Real, OUTPUTS> {
    let [a, b, c] = poses.faces[face];
    let posed = &poses.poses[pose];
    let gradient = deformation_gradient(
        &inverse_frames[face],
        [posed[a as usize], posed[b as usize], posed[c as usize]],
    );
    let part = skeleton.triangle_parts[face] as usize;
    let q = rotations[pose][part].transpose() * gradient;
    SVector::<Real, OUTPUTS>::from_column_slice(q.as_slice())
}

/// Ridge least squares `W = (AᵀA + λ D)⁻¹ AᵀB` over the samples `(features, q)`, where
/// `D` is 1 on the twist entries and 0 on the constant. Returns `W` and the sum of
/// squared residuals `Σ ‖q − Wᵀ f‖²` (unregularised).
fn regress_triangle(
    samples: impl Iterator<Item = (Features, SVector<Real, OUTPUTS>)>,
    ridge: Real,
) -> (Coefficients, Real) {
    let mut ata = SMatrix::<Real, FEATURES, FEATURES>::zeros();
    let mut atb = Coefficients::zeros();
    let mut btb = 0.0;
    for (f, q) in samples {
        ata += f * f.transpose();
        atb += f * q.transpose();
        btb += q.norm_squared();
    }
    let mut regularised = ata;
    for i in 0..FEATURES - 1 {
        regularised[(i, i)] += ridge;
    }
    let w = match regularised.cholesky() {
        Some(chol) => chol.solve(&atb),
        // Only reachable with ridge = 0 and collinear twists: take the minimum-norm
        // least-squares solution instead.
        None => regularised.svd(true, true).solve(&atb, 1e-12).expect("SVD with both factors computed"),
    };
    // ‖B − AW‖² expanded, so the samples need not be kept.
    let residual = btb - 2.0 * w.component_mul(&atb).sum() + (w.transpose() * ata * w).trace();
    (w, residual.max(0.0))
}
