//! Residual statistics per part and per pose, sorted worst first, so that a bad
//! segmentation (one part with a large residual in every pose) or a broken pose file
//! (one pose with a large residual in every part) is visible at a glance. The template
//! pose is left out of every statistic: it fits itself exactly.

use std::fmt::Write as _;

use desal_mesh::math::Real;

use crate::part_fit::PartFit;

/// Residual statistics over the non-template poses, in mesh units.
#[derive(Debug, Clone, PartialEq)]
pub struct FitSummary {
    /// Mean per-vertex residual over every vertex of every non-template pose (0 when the
    /// template is the only pose). SCAPE: about 14.5 mm.
    pub mean_residual: Real,
    /// Root mean square of the same residuals.
    pub rms_residual: Real,
    /// Largest single vertex residual.
    pub max_residual: Real,
    /// One entry per part, worst (largest mean) first; ties by part id.
    pub parts: Vec<PartSummary>,
    /// One entry per non-template pose, worst (largest mean) first; ties by pose index.
    pub poses: Vec<PoseSummary>,
}

/// How well one part fits, over all non-template poses.
#[derive(Debug, Clone, PartialEq)]
pub struct PartSummary {
    pub part: u32,
    pub name: String,
    /// Number of vertices in the part.
    pub vertices: usize,
    /// Mean vertex residual over the part's vertices and the non-template poses.
    pub mean: Real,
    pub rms: Real,
    pub max: Real,
    /// The pose where this part fits worst (largest mean residual).
    pub worst_pose: usize,
    pub worst_pose_name: String,
}

/// How well one pose is fitted, over all parts.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseSummary {
    pub pose: usize,
    pub name: String,
    /// Mean vertex residual over all vertices of the pose.
    pub mean: Real,
    pub rms: Real,
    pub max: Real,
    /// The part that fits this pose worst (largest mean residual).
    pub worst_part: u32,
    pub worst_part_name: String,
}

/// Builds the summary from `part_fits[pose][part]` and the vertex count of each part.
pub(crate) fn summarise(
    part_fits: &[Vec<PartFit>],
    part_sizes: &[usize],
    pose_names: &[String],
    part_names: &[String],
    template: usize,
) -> FitSummary {
    let posed: Vec<usize> = (0..part_fits.len()).filter(|&p| p != template).collect();
    let vertex_count: usize = part_sizes.iter().sum();

    let mut parts: Vec<PartSummary> = (0..part_sizes.len())
        .map(|part| {
            let fits = posed.iter().map(|&pose| (pose, &part_fits[pose][part]));
            let worst = fits.clone().fold(None, |best: Option<(usize, Real)>, (pose, f)| match best {
                Some((_, m)) if m >= f.mean => best,
                _ => Some((pose, f.mean)),
            });
            let worst_pose = worst.map_or(template, |(pose, _)| pose);
            PartSummary {
                part: part as u32,
                name: part_names[part].clone(),
                vertices: part_sizes[part],
                mean: mean_of(fits.clone().map(|(_, f)| f.mean)),
                rms: mean_of(fits.clone().map(|(_, f)| f.rms * f.rms)).sqrt(),
                max: fits.map(|(_, f)| f.max).fold(0.0, Real::max),
                worst_pose,
                worst_pose_name: pose_names[worst_pose].clone(),
            }
        })
        .collect();

    let mut poses: Vec<PoseSummary> = posed
        .iter()
        .map(|&pose| {
            let fits = &part_fits[pose];
            let weighted = |value: &dyn Fn(&PartFit) -> Real| {
                fits.iter().zip(part_sizes).map(|(f, &n)| value(f) * n as Real).sum::<Real>()
                    / vertex_count as Real
            };
            let worst_part = (0..fits.len()).fold(0, |w, k| if fits[k].mean > fits[w].mean { k } else { w });
            PoseSummary {
                pose,
                name: pose_names[pose].clone(),
                mean: weighted(&|f| f.mean),
                rms: weighted(&|f| f.rms * f.rms).sqrt(),
                max: fits.iter().map(|f| f.max).fold(0.0, Real::max),
                worst_part: worst_part as u32,
                worst_part_name: part_names[worst_part].clone(),
            }
        })
        .collect();

    let mean_residual = mean_of(poses.iter().map(|p| p.mean));
    let rms_residual = mean_of(poses.iter().map(|p| p.rms * p.rms)).sqrt();
    let max_residual = poses.iter().map(|p| p.max).fold(0.0, Real::max);
    parts.sort_by(|a, b| b.mean.total_cmp(&a.mean).then(a.part.cmp(&b.part)));
    poses.sort_by(|a, b| b.mean.total_cmp(&a.mean).then(a.pose.cmp(&b.pose)));
    FitSummary { mean_residual, rms_residual, max_residual, parts, poses }
}

/// Mean of `values`, 0 when there are none.
fn mean_of(values: impl Iterator<Item = Real>) -> Real {
    let (sum, count) = values.fold((0.0, 0usize), |(s, c), v| (s + v, c + 1));
    if count == 0 { 0.0 } else { sum / count as Real }
}

impl FitSummary {
    /// A short human-readable report: the overall figures and the `top` worst parts and
    /// poses. Residuals are multiplied by `scale` and labelled `unit`; for a mesh in
    /// metres, `describe(5, 1000.0, "mm")`.
    pub fn describe(&self, top: usize, scale: Real, unit: &str) -> String {
        let mut text = String::new();
        let _ = writeln!(
            text,
            "mean residual {:.3} {unit}, rms {:.3} {unit}, max {:.3} {unit}",
            self.mean_residual * scale,
            self.rms_residual * scale,
            self.max_residual * scale
        );
        let _ = writeln!(text, "worst parts (mean / max {unit}, worst pose):");
        for p in self.parts.iter().take(top) {
            let _ = writeln!(
                text,
                "  {:>3} {:<16} {:>9.3} {:>9.3}  {}",
                p.part,
                p.name,
                p.mean * scale,
                p.max * scale,
                p.worst_pose_name
            );
        }
        let _ = writeln!(text, "worst poses (mean / max {unit}, worst part):");
        for p in self.poses.iter().take(top) {
            let _ = writeln!(
                text,
                "  {:>3} {:<16} {:>9.3} {:>9.3}  {}",
                p.pose,
                p.name,
                p.mean * scale,
                p.max * scale,
                p.worst_part_name
            );
        }
        text
    }
}
