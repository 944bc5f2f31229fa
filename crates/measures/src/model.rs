//! The SCAPE pose-deformation model: fitting on a registered pose set, and synthesis of
//! a pose from its part rotations.
//!
//! Anguelov et al. 2005, "SCAPE: Shape Completion and Animation of People", §3–4 (pose
//! deformation only; no shape space). For triangle `k` of part `p(k)` in pose `X`:
//!
//! 1. the deformation gradient `T_k` from the template (Sumner & Popović frames,
//!    [`crate::gradient`]) is split into the part's rigid rotation and a non-rigid rest,
//!    `Q_k = R_{p(k)}ᵀ T_k`;
//! 2. the nine entries of `Q_k` are regressed linearly on the twists of the joints
//!    nearest the triangle plus a constant ([`crate::skeleton`], [`crate::ridge`]), fitted
//!    per triangle by ridge-regularised least squares over the training poses; the ridge
//!    and the number of joints are fixed ([`Regression::Fixed`]) or chosen by
//!    leave-one-out cross-validation over the training poses
//!    ([`Regression::CrossValidated`]; the rule is in [`crate::ridge`]);
//! 3. a new pose is synthesised from its part rotations: twists → predicted `Q_k` →
//!    `T_k = R_{p(k)} Q_k` → Poisson reconstruction ([`crate::poisson`]), then either moved
//!    to the target centroid ([`Anchoring::Centroid`], SCAPE's own rule) or pulled softly
//!    towards every part's rigid motion of the template ([`Anchoring::Parts`]), so that
//!    the regression's residual is not integrated down the kinematic chains.
//!
//! Part motions are inputs (`rotations[pose][part]` or [`PartTransform`]s, mapping
//! template part to posed part, as stage 1's fit produces them), so the model is fitted on
//! whatever mesh it is given — full resolution or simplified — with the motions fitted on
//! that mesh.

use desal_mesh::{Face, Mat3, PartLabels, PoseSet, Real, Vec3};
use rayon::prelude::*;

use crate::error::EvalError;
use crate::gradient::{deformation_gradient, inverse_template_frame};
use crate::poisson::{AnchoredPoissonSolver, PoissonSolver};
use crate::ridge::{
    Coefficients, FEATURES, Features, JointFeatures, Target, best_candidate, candidates, leave_one_out_error,
    mask_features, regress_triangle,
};
use crate::skeleton::Skeleton;
use crate::transform::{
    PartTransform, check_model_inputs, check_pose_rotations, check_pose_transforms, rotations_of,
};

/// How the twist regression's ridge and features are set.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Regression {
    /// [`ModelConfig::ridge`] and the two nearest joints, whatever the training poses
    /// (SCAPE's rule; this crate's only rule before issue 17).
    Fixed,
    /// The feature set and ridge with the smallest leave-one-out error over the
    /// training poses, from [`crate::ridge::RIDGE_GRID`] ([`ModelConfig::ridge`] is
    /// ignored). Inside a held-out fold this uses the fold's training poses only.
    CrossValidated,
}

/// How a synthesised pose is placed in space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Anchoring {
    /// One vertex per component is solved free and the whole mesh is moved to the
    /// target centroid (SCAPE's rule): the regression's residual accumulates along the
    /// kinematic chains, worst at the hands and feet.
    Centroid,
    /// Every vertex `v` of part `p` is also pulled towards `R_p x_v + t_p`, its part's
    /// rigid motion of the template, with weight `w_v = A_v / ℓ²` (`A_v`: a third of the
    /// template area of the triangles around `v`), where `ℓ = scale · √(template area)`.
    /// Deviations that vary over lengths above about `ℓ` (translation drift along the
    /// chains) follow the parts' motions; finer detail (bulges, the regression's `Q`)
    /// follows the gradients. `scale` is dimensionless, so the pull is the same on a
    /// simplified mesh, in any unit. Needs the parts' translations
    /// ([`Model::synthesize_from_parts`]).
    Parts {
        /// `ℓ / √(template area)`, > 0.
        scale: Real,
    },
}

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
    /// Fixed or cross-validated ridge and features. Default [`Regression::Fixed`]: the
    /// cross-validated rule is measured worse in held-out position error on SCAPE
    /// (5 folds, v2v 6.97e-5 vs 6.77e-5 m² at the default anchoring, 2.03e-4 vs
    /// 1.79e-4 with centroid placement) and level on the sample (1.48e-6 vs 1.46e-6;
    /// `tests/floor.rs`): leave-one-out error in `Q` picks a ridge of 1e-2 on SCAPE, but
    /// positions want less shrinkage, because the Poisson solve averages away the
    /// per-triangle noise that the `Q`-space criterion guards against.
    pub regression: Regression,
    /// Placement of synthesised poses by [`Model::synthesize_from_parts`] (the
    /// rotation-only [`Model::synthesize`] always uses the centroid). Default
    /// `Parts { scale: DEFAULT_ANCHOR_SCALE }`.
    pub anchoring: Anchoring,
}

/// The default [`Anchoring::Parts`] scale, chosen by held-out error (5 folds, fixed
/// ridge, `tests/floor.rs` and its sweep) over 0.01, 0.02, 0.03, 0.05, 0.1:
///
/// | scale | SCAPE held-out v2v, m² | sample held-out v2v, m² | sample held-out / in-sample (v2v, v2f) |
/// |---|---|---|---|
/// | centroid | 1.79e-4 | 4.11e-5 | 8.5, 12.1 |
/// | 0.01 | 8.41e-5 | 1.68e-6 | 1.1, 1.2 |
/// | 0.02 | 6.77e-5 | 1.46e-6 | 1.6, 2.1 |
/// | 0.03 | 5.90e-5 | 1.78e-6 | 2.7, 3.8 |
/// | 0.05 | 5.37e-5 | 2.74e-6 | 5.1, 7.1 |
/// | 0.1 | 6.25e-5 | 6.19e-6 | 7.4, 10.6 |
///
/// SCAPE alone would pick 0.05; 0.02 costs SCAPE 26 % there but halves the sample's
/// held-out error and keeps its held-out / in-sample ratio below 3 (issue 17's target
/// for small pose sets), so it is the default. On SCAPE's body (√area ≈ 1.35 m) 0.02 is
/// a length of about 2.7 cm.
pub const DEFAULT_ANCHOR_SCALE: Real = 0.02;

impl Default for ModelConfig {
    fn default() -> Self {
        Self {
            ridge: 1e-3,
            root_part: None,
            regression: Regression::Fixed,
            anchoring: Anchoring::Parts { scale: DEFAULT_ANCHOR_SCALE },
        }
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
    /// The ridge λ used (per pose, as [`ModelConfig::ridge`]): the configured one, or the
    /// cross-validated choice.
    pub ridge: Real,
    /// The joint features used.
    pub joint_features: JointFeatures,
    /// Mean over training (triangle, pose) pairs of the squared leave-one-out residual
    /// of `Q` under the chosen regression (dimensionless); `None` with
    /// [`Regression::Fixed`].
    pub mean_q_loo_residual: Option<Real>,
}

/// A fitted SCAPE pose-deformation model for one mesh (its template and triangles).
#[derive(Debug)]
pub struct Model {
    skeleton: Skeleton,
    part_count: usize,
    joint_features: JointFeatures,
    /// Per triangle, `Q` (column-major) `= coefficientsᵀ · features`.
    coefficients: Vec<Coefficients>,
    solver: PoissonSolver,
    /// Present with [`Anchoring::Parts`].
    anchored: Option<AnchoredPoissonSolver>,
    /// Template positions and part of each vertex: the anchors' inputs.
    template: Vec<Vec3>,
    vertex_parts: Vec<u32>,
    report: ModelReport,
}

/// Fits the model on the poses `training_poses` of `poses`.
///
/// - `labels`: one part id per vertex of `poses` (same vertex index space);
/// - `rotations[pose][part]`: the rotation taking part `part` of the template to pose
///   `pose`, for **every** pose of the set (only the training poses are read);
/// - `training_poses`: distinct pose indices; the template need not be among them (with
///   held-out folds it always is, see [`crate::folds::folds`]).
///
/// Cost: one pass over triangles × training poses (plus one per ridge candidate with
/// [`Regression::CrossValidated`]), one sparse factorisation (two with
/// [`Anchoring::Parts`]).
pub fn fit_model(
    poses: &PoseSet,
    labels: &PartLabels,
    rotations: &[Vec<Mat3>],
    training_poses: &[usize],
    config: &ModelConfig,
) -> Result<Model, EvalError> {
    check_model_inputs(poses, labels, rotations, training_poses, check_pose_rotations)?;
    let template = poses.template_positions();
    let skeleton = Skeleton::new(template, &poses.faces, labels, config.root_part);
    let inverse_frames = invert_template_frames(poses)?;
    let training_twists: Vec<Vec<Vec3>> =
        training_poses.iter().map(|&p| skeleton.twists(&rotations[p])).collect();
    // Every triangle's samples `(features, Q)` over the training poses, built on demand
    // so that the whole set (triangles × poses) is never held at once.
    let triangle_samples = |face: usize| -> Vec<(Features, Target)> {
        training_poses
            .iter()
            .zip(&training_twists)
            .map(|(&pose, twists)| {
                let features = triangle_features(&skeleton, face, twists);
                let q = non_rigid_deformation(poses, rotations, &skeleton, &inverse_frames, face, pose);
                (features, q)
            })
            .collect()
    };
    let pose_scale = training_poses.len() as Real;

    let (joint_features, ridge, loo_sum) = match config.regression {
        Regression::Fixed => (JointFeatures::TwoNearest, config.ridge, None),
        Regression::CrossValidated => {
            let (joints, ridge, sum) = cross_validate(poses.face_count(), pose_scale, &triangle_samples);
            (joints, ridge, Some(sum))
        }
    };

    // Each triangle's regression is independent: fit them in parallel, in face order.
    let fits: Vec<(Coefficients, Real)> = (0..poses.face_count())
        .into_par_iter()
        .map(|face| {
            let samples: Vec<_> = triangle_samples(face)
                .into_iter()
                .map(|(f, q)| (mask_features(f, joint_features), q))
                .collect();
            regress_triangle(&samples, ridge * pose_scale)
        })
        .collect();

    let solver = PoissonSolver::new(template, &poses.faces)?;
    let anchored = match config.anchoring {
        Anchoring::Centroid => None,
        Anchoring::Parts { scale } => Some(AnchoredPoissonSolver::new(
            template,
            &poses.faces,
            &anchor_weights(template, &poses.faces, scale),
        )?),
    };
    let residual_sum: Real = fits.iter().map(|(_, r)| r).sum();
    let sample_count = (poses.face_count() * training_poses.len()) as Real;
    let report = ModelReport {
        training_pose_count: training_poses.len(),
        triangle_count: poses.face_count(),
        joint_count: skeleton.joints.len(),
        mean_q_residual: residual_sum / sample_count,
        factor_nonzeros: solver.factor_nonzeros(),
        ridge,
        joint_features,
        mean_q_loo_residual: loo_sum.map(|s| s / sample_count),
    };
    Ok(Model {
        skeleton,
        part_count: labels.part_count(),
        joint_features,
        coefficients: fits.into_iter().map(|(w, _)| w).collect(),
        solver,
        anchored,
        template: template.to_vec(),
        vertex_parts: labels.labels.clone(),
        report,
    })
}

/// The rule of [`crate::ridge`]: every candidate's leave-one-out error summed over the
/// triangles (in face order, so the sum does not depend on the thread count), and the
/// best candidate with its sum.
fn cross_validate(
    face_count: usize,
    pose_scale: Real,
    triangle_samples: &(impl Fn(usize) -> Vec<(Features, Target)> + Sync),
) -> (JointFeatures, Real, Real) {
    let all = candidates();
    let per_triangle: Vec<Vec<Real>> = (0..face_count)
        .into_par_iter()
        .map(|face| {
            let samples = triangle_samples(face);
            all.iter()
                .map(|&(joints, ridge)| {
                    let masked: Vec<_> =
                        samples.iter().map(|(f, q)| (mask_features(*f, joints), *q)).collect();
                    leave_one_out_error(&masked, ridge * pose_scale)
                })
                .collect()
        })
        .collect();
    let mut sums = vec![0.0; all.len()];
    for errors in &per_triangle {
        for (s, e) in sums.iter_mut().zip(errors) {
            *s += e;
        }
    }
    let (joints, ridge) = best_candidate(&sums);
    let best = all.iter().position(|&c| c == (joints, ridge)).expect("the best is a candidate");
    (joints, ridge, sums[best])
}

/// `w_v = A_v / ℓ²` with `A_v` a third of the area of the template triangles around `v`
/// and `ℓ = scale · √(total area)`; a vertex on no triangle gets the mean weight, so the
/// anchored system stays positive definite.
fn anchor_weights(template: &[Vec3], faces: &[Face], scale: Real) -> Vec<Real> {
    let mut area = vec![0.0; template.len()];
    let mut total = 0.0;
    for &[a, b, c] in faces {
        let (pa, pb, pc) = (template[a as usize], template[b as usize], template[c as usize]);
        let third = 0.5 * (pb - pa).cross(&(pc - pa)).norm() / 3.0;
        for v in [a, b, c] {
            area[v as usize] += third;
        }
        total += 3.0 * third;
    }
    let length_squared = scale * scale * total;
    let mean = total / template.len().max(1) as Real;
    area.iter().map(|&a| if a > 0.0 { a } else { mean } / length_squared).collect()
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

    /// Synthesises a pose from its parts' rigid motions `transforms[part]` (template part
    /// → posed part, stage 1's fit), placed by the fitted [`ModelConfig::anchoring`]:
    /// with [`Anchoring::Parts`] every vertex is pulled towards its part's motion of the
    /// template and `target_centroid` is not used; with [`Anchoring::Centroid`] only the
    /// rotations are read and the pose is moved to `target_centroid`, as
    /// [`Model::synthesize`]. Positions in the model's vertex index space.
    pub fn synthesize_from_parts(
        &self,
        transforms: &[PartTransform],
        target_centroid: Vec3,
    ) -> Result<Vec<Vec3>, EvalError> {
        check_pose_transforms(transforms, self.part_count, 0)?;
        Ok(self.solve_from_parts(transforms, &target_centroid))
    }

    /// [`Model::synthesize_from_parts`] for many poses in parallel: `transforms[i]` and
    /// `target_centroids[i]` describe pose `i`; results in the same order.
    pub fn synthesize_from_parts_many(
        &self,
        transforms: &[Vec<PartTransform>],
        target_centroids: &[Vec3],
    ) -> Result<Vec<Vec<Vec3>>, EvalError> {
        if transforms.len() != target_centroids.len() {
            return Err(EvalError::TargetCountMismatch {
                rotations: transforms.len(),
                centroids: target_centroids.len(),
            });
        }
        for (pose, t) in transforms.iter().enumerate() {
            check_pose_transforms(t, self.part_count, pose)?;
        }
        Ok(transforms.par_iter().zip(target_centroids).map(|(t, c)| self.solve_from_parts(t, c)).collect())
    }

    /// Whether [`Model::synthesize_from_parts`] anchors the parts.
    pub fn is_anchored(&self) -> bool {
        self.anchored.is_some()
    }

    /// The predicted non-rigid deformation `Q` of triangle `face` for a pose with the
    /// given joint twists (in [`Skeleton::joints`] order).
    pub fn predict_q(&self, face: usize, twists: &[Vec3]) -> Mat3 {
        let features = mask_features(triangle_features(&self.skeleton, face, twists), self.joint_features);
        let q = self.coefficients[face].transpose() * features;
        Mat3::from_column_slice(q.as_slice())
    }

    fn solve_from_parts(&self, transforms: &[PartTransform], target_centroid: &Vec3) -> Vec<Vec3> {
        let gradients = self.predict_gradients(&rotations_of(transforms));
        match &self.anchored {
            None => self.solver.solve(&gradients, target_centroid),
            Some(anchored) => {
                let anchors: Vec<Vec3> = self
                    .template
                    .iter()
                    .zip(&self.vertex_parts)
                    .map(|(x, &p)| transforms[p as usize].apply(x))
                    .collect();
                anchored.solve(&gradients, &anchors)
            }
        }
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
        check_pose_rotations(rotations, self.part_count, pose)
    }
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
) -> Target {
    let [a, b, c] = poses.faces[face];
    let posed = &poses.poses[pose];
    let gradient = deformation_gradient(
        &inverse_frames[face],
        [posed[a as usize], posed[b as usize], posed[c as usize]],
    );
    let part = skeleton.triangle_parts[face] as usize;
    let q = rotations[pose][part].transpose() * gradient;
    Target::from_column_slice(q.as_slice())
}
