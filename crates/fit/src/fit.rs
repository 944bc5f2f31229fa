//! The stage-1 orchestrator: fit every part of the template onto every pose and measure
//! the per-vertex residuals (paper §3.1, Eq. 1).
//!
//! The story, per pose X (in parallel) and per part k (in parallel within a pose):
//! 1. accumulate the centred moments of the pairs (template vertex, pose-X vertex) over
//!    the part's vertices;
//! 2. solve for the transform (a proper rotation by default, an affine map for the
//!    ablation) and reject a fit that is not unique;
//! 3. measure `‖R v_T + t − v_X‖` for each of the part's vertices.
//!
//! Parallel collects preserve order and every sum runs in vertex order, so the output
//! is bit-identical whatever the thread count.

use desal_mesh::math::{Real, Vec3};
use desal_mesh::{MeshError, PartLabels, PoseSet, Progress};
use rayon::prelude::*;

use crate::align::{PairMoments, solve_affine, solve_rigid};
use crate::error::FitError;
pub use crate::part_fit::PartFit;
use crate::summary::{FitSummary, summarise};

/// Which family of transforms is fitted per part.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FitModel {
    /// A proper rotation plus a translation (Kabsch/Umeyama): a rigid body part. The
    /// default and the model DESIGN.md prescribes.
    #[default]
    Rigid,
    /// **Ablation only.** The paper's literal "vectorise R and t" reading of Eq. 1: an
    /// unconstrained 3×3 linear map plus a translation. It also absorbs scaling and
    /// shear, so its residuals are never larger than the rigid ones and saliency
    /// under-reports muscle bulging.
    Affine,
}

impl FitModel {
    /// Every model, in the order error messages list them.
    pub const ALL: [FitModel; 2] = [FitModel::Rigid, FitModel::Affine];

    /// A stable lower-case name for reports, artifacts, pipeline files and the CLI: the
    /// one spelling table of this enum ([`std::str::FromStr`] reads it back).
    pub fn name(self) -> &'static str {
        match self {
            FitModel::Rigid => "rigid",
            FitModel::Affine => "affine",
        }
    }
}

impl std::fmt::Display for FitModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for FitModel {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        FitModel::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("fit method '{s}' is unknown: use \"rigid\" or \"affine\""))
    }
}

/// Parameters of stage 1.
#[derive(Debug, Clone, PartialEq)]
pub struct FitConfig {
    /// Transform family; default [`FitModel::Rigid`].
    pub model: FitModel,
    /// A fit is rejected as degenerate when the ratio of the second to the first
    /// singular value of the part's cross-covariance is below this (dimensionless).
    /// Default `1e-9`: the part must be at least a billionth as thick as it is long
    /// in the pose, i.e. only a genuinely collapsed limb is refused.
    pub degenerate_ratio: Real,
}

impl Default for FitConfig {
    fn default() -> Self {
        Self { model: FitModel::Rigid, degenerate_ratio: 1e-9 }
    }
}

/// Everything stage 1 produces.
#[derive(Debug, Clone, PartialEq)]
pub struct FitResult {
    /// The model that was fitted.
    pub model: FitModel,
    /// Pose names, in pose order (copied from the pose set).
    pub pose_names: Vec<String>,
    /// Part names, indexed by part id (copied from the labels).
    pub part_names: Vec<String>,
    /// Index of the template pose; its fits are the identity and its residuals zero.
    pub template: usize,
    /// Vertex count of every pose.
    pub vertex_count: usize,
    /// `part_fits[pose][part]`: the transform taking the template's part onto the pose.
    pub part_fits: Vec<Vec<PartFit>>,
    /// Per-vertex residual distances `‖R v_T + t − v_X‖` in mesh units, row-major by
    /// pose: `residuals[pose * vertex_count + vertex]`.
    pub residuals: Vec<f32>,
    /// Per-part and per-pose statistics, worst first.
    pub summary: FitSummary,
}

impl FitResult {
    /// The residuals of pose `pose`, indexed by vertex.
    pub fn pose_residuals(&self, pose: usize) -> &[f32] {
        &self.residuals[pose * self.vertex_count..(pose + 1) * self.vertex_count]
    }

    pub fn pose_count(&self) -> usize {
        self.pose_names.len()
    }

    pub fn part_count(&self) -> usize {
        self.part_names.len()
    }
}

/// Fits every part of the template onto every pose (stage 1).
///
/// `labels` must give one part id per vertex of `poses`, and every part must have at
/// least three non-collinear template vertices. The template pose itself gets identity
/// fits and exactly zero residuals. Progress is reported in poses.
///
/// Errors name the part and the pose: [`FitError::DegeneratePart`] for a part that
/// cannot support a fit, [`FitError::DegenerateFit`] when a pose collapses a part.
pub fn fit_pose_set(
    poses: &PoseSet,
    labels: &PartLabels,
    config: &FitConfig,
    progress: &dyn Progress,
) -> Result<FitResult, FitError> {
    check_labels(poses, labels)?;
    let members = labels.members();
    let vertex_count = poses.vertex_count();
    let mut residuals = vec![0f32; poses.pose_count() * vertex_count];

    progress.begin("fit", poses.pose_count() as u64);
    let per_pose: Vec<Result<Vec<PartFit>, FitError>> = residuals
        .par_chunks_mut(vertex_count)
        .enumerate()
        .map(|(pose, pose_residuals)| {
            let fits = fit_pose(poses, labels, &members, pose, config, pose_residuals);
            progress.advance(1);
            fits
        })
        .collect();
    progress.finish();
    // The first error in pose order, so that the message does not depend on scheduling.
    let part_fits = per_pose.into_iter().collect::<Result<Vec<_>, _>>()?;

    let part_sizes: Vec<usize> = members.iter().map(Vec::len).collect();
    let summary = summarise(&part_fits, &part_sizes, &poses.names, &labels.names, poses.template);
    Ok(FitResult {
        model: config.model,
        pose_names: poses.names.clone(),
        part_names: labels.names.clone(),
        template: poses.template,
        vertex_count,
        part_fits,
        residuals,
        summary,
    })
}

/// Checks label count and that every part spans a plane in the template.
fn check_labels(poses: &PoseSet, labels: &PartLabels) -> Result<(), FitError> {
    labels.check_vertex_count(poses.vertex_count()).map_err(FitError::Labels)?;
    labels.check_parts_fittable(poses.template_positions()).map_err(|e| match e {
        MeshError::DegeneratePart { part, name, vertices } => FitError::DegeneratePart {
            part,
            part_name: name,
            pose: poses.template,
            pose_name: poses.names[poses.template].clone(),
            vertices,
        },
        other => FitError::Labels(other),
    })
}

/// Fits every part onto pose `pose`, writing its residuals into `pose_residuals`.
fn fit_pose(
    poses: &PoseSet,
    labels: &PartLabels,
    members: &[Vec<u32>],
    pose: usize,
    config: &FitConfig,
    pose_residuals: &mut [f32],
) -> Result<Vec<PartFit>, FitError> {
    if pose == poses.template {
        // The template fits itself exactly; its residual row stays zero.
        return Ok(vec![PartFit::identity(); members.len()]);
    }
    let template = poses.template_positions();
    let target = &poses.poses[pose];
    let fitted: Vec<Result<(PartFit, Vec<Real>), FitError>> = members
        .par_iter()
        .enumerate()
        .map(|(part, verts)| {
            fit_part(verts, template, target, config).map_err(|failure| {
                failure.into_error(part as u32, labels.names[part].clone(), pose, poses.names[pose].clone())
            })
        })
        .collect();

    let mut fits = Vec::with_capacity(members.len());
    for (verts, result) in members.iter().zip(fitted) {
        let (fit, distances) = result?;
        for (&v, &d) in verts.iter().zip(&distances) {
            pose_residuals[v as usize] = d as f32;
        }
        fits.push(fit);
    }
    Ok(fits)
}

/// Why one part's fit failed, before the part and pose names are attached.
enum PartFailure {
    Degenerate { ratio: Real, threshold: Real },
    NonFinite,
}

impl PartFailure {
    fn into_error(self, part: u32, part_name: String, pose: usize, pose_name: String) -> FitError {
        match self {
            PartFailure::Degenerate { ratio, threshold } => {
                FitError::DegenerateFit { part, part_name, pose, pose_name, ratio, threshold }
            }
            PartFailure::NonFinite => FitError::NonFinite { part, part_name, pose, pose_name },
        }
    }
}

/// Fits the template vertices `verts` onto `target` and returns the fit with the
/// residual distance of each vertex of `verts`, in the same order.
fn fit_part(
    verts: &[u32],
    template: &[Vec3],
    target: &[Vec3],
    config: &FitConfig,
) -> Result<(PartFit, Vec<Real>), PartFailure> {
    let moments = PairMoments::from_indexed(verts, template, target);
    let (linear, translation, singular) = match config.model {
        FitModel::Rigid => {
            let (rigid, singular) = solve_rigid(&moments);
            (rigid.rotation, rigid.translation, singular)
        }
        FitModel::Affine => {
            let affine = solve_affine(&moments);
            let mut singular: Vec<Real> = moments.cross.singular_values().iter().copied().collect();
            singular.sort_by(|a, b| b.total_cmp(a));
            (affine.linear, affine.translation, [singular[0], singular[1], singular[2]])
        }
    };
    // A part collapsed to a line or a point has no unique orientation: refuse it
    // rather than report residuals of an arbitrary rotation.
    let ratio = if singular[0] > 0.0 { singular[1] / singular[0] } else { 0.0 };
    if ratio.is_nan() || ratio < config.degenerate_ratio {
        return Err(PartFailure::Degenerate { ratio, threshold: config.degenerate_ratio });
    }
    if !(linear.iter().all(|x| x.is_finite()) && translation.iter().all(|x| x.is_finite())) {
        return Err(PartFailure::NonFinite);
    }

    let distances: Vec<Real> = verts
        .iter()
        .map(|&v| (linear * template[v as usize] + translation - target[v as usize]).norm())
        .collect();
    let count = distances.len() as Real;
    let sum: Real = distances.iter().sum();
    let sum_sq: Real = distances.iter().map(|d| d * d).sum();
    let max = distances.iter().copied().fold(0.0, Real::max);
    let fit = PartFit { linear, translation, rms: (sum_sq / count).sqrt(), mean: sum / count, max };
    Ok((fit, distances))
}
