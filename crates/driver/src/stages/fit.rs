//! Stage 1: its parameters and their validation, its cache key, the call into
//! `desal-fit` and the artifact conversion.

use anyhow::Result;
use desal_fit::{FitConfig, FitModel, FitResult};
use desal_io::artifact::{ArtifactKind, ContentHash, FitV1};
use desal_mesh::{PartLabels, PoseSet, Progress};
use serde::{Deserialize, Serialize};
use serde_json::json;

use crate::cache::{StageKey, canonical_json};
use crate::stages::runner::StageOutput;

/// Stage 1 parameters (`[fit]` in pipeline files, `desal fit` flags).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields, default)]
pub struct FitParams {
    /// `rigid` (Kabsch, proper rotations; the default) or `affine` (the paper's literal
    /// unconstrained fit, for the ablation).
    #[serde(with = "crate::cache::by_name")]
    pub method: FitModel,
}

impl FitParams {
    /// The library configuration these parameters resolve to.
    pub fn config(&self) -> FitConfig {
        FitConfig { model: self.method, ..FitConfig::default() }
    }

    /// The cache key of a fit of `poses` with `labels`.
    pub fn key(&self, poses: ContentHash, labels: ContentHash) -> StageKey {
        let FitConfig { model, degenerate_ratio } = self.config();
        StageKey {
            stage: "fit".into(),
            stage_version: desal_fit::VERSION,
            format_version: ArtifactKind::Fit.current_version(),
            parameters: canonical_json(self),
            resolved: canonical_json(&json!({ "model": model.name(), "degenerate_ratio": degenerate_ratio })),
            inputs: vec![("poses".into(), poses), ("labels".into(), labels)],
        }
    }
}

/// `fit.json`: the fit's figures, worst parts and poses first.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FitSummary {
    pub model: String,
    pub seconds: f64,
    pub mean_residual: f64,
    pub rms_residual: f64,
    pub max_residual: f64,
    pub worst_parts: Vec<WorstPart>,
    pub worst_poses: Vec<WorstPose>,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct WorstPart {
    pub part: u32,
    pub name: String,
    pub vertices: usize,
    pub mean: f64,
    pub rms: f64,
    pub max: f64,
    pub worst_pose: String,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct WorstPose {
    pub pose: String,
    pub mean: f64,
    pub rms: f64,
    pub max: f64,
    pub worst_part: String,
}

/// Runs stage 1.
pub fn compute(
    params: &FitParams,
    set: &PoseSet,
    labels: &PartLabels,
    progress: &dyn Progress,
) -> Result<StageOutput<FitV1, FitSummary>> {
    let start = std::time::Instant::now();
    let result = desal_fit::fit_pose_set(set, labels, &params.config(), progress)?;
    let seconds = start.elapsed().as_secs_f64();
    let s = &result.summary;
    let worst = s
        .parts
        .first()
        .map_or(String::new(), |p| format!(", worst part {} ({:.2} mm)", p.name, p.mean * 1e3));
    let note = format!(
        "{} fit, {} poses x {} parts: mean residual {:.2} mm{worst}",
        result.model.name(),
        result.pose_count(),
        result.part_count(),
        s.mean_residual * 1e3
    );
    let summary = FitSummary {
        model: result.model.name().into(),
        seconds,
        mean_residual: s.mean_residual,
        rms_residual: s.rms_residual,
        max_residual: s.max_residual,
        worst_parts: s
            .parts
            .iter()
            .map(|p| WorstPart {
                part: p.part,
                name: p.name.clone(),
                vertices: p.vertices,
                mean: p.mean,
                rms: p.rms,
                max: p.max,
                worst_pose: p.worst_pose_name.clone(),
            })
            .collect(),
        worst_poses: s
            .poses
            .iter()
            .map(|p| WorstPose {
                pose: p.name.clone(),
                mean: p.mean,
                rms: p.rms,
                max: p.max,
                worst_part: p.worst_part_name.clone(),
            })
            .collect(),
    };
    Ok(StageOutput { body: to_artifact(&result), summary, note })
}

fn to_artifact(r: &FitResult) -> FitV1 {
    let fits: Vec<_> = r.part_fits.iter().flatten().collect();
    FitV1 {
        model: r.model.name().into(),
        pose_names: r.pose_names.clone(),
        part_names: r.part_names.clone(),
        template: r.template as u32,
        vertex_count: r.vertex_count as u32,
        linear: fits
            .iter()
            .map(|f| {
                let m = &f.linear;
                [
                    m[(0, 0)],
                    m[(0, 1)],
                    m[(0, 2)],
                    m[(1, 0)],
                    m[(1, 1)],
                    m[(1, 2)],
                    m[(2, 0)],
                    m[(2, 1)],
                    m[(2, 2)],
                ]
            })
            .collect(),
        translation: fits.iter().map(|f| f.translation.into()).collect(),
        rms: fits.iter().map(|f| f.rms).collect(),
        mean: fits.iter().map(|f| f.mean).collect(),
        max: fits.iter().map(|f| f.max).collect(),
        residuals: r.residuals.clone(),
        worst_parts: r.summary.parts.iter().map(|p| (p.part, p.mean, p.max, p.worst_pose as u32)).collect(),
        worst_poses: r.summary.poses.iter().map(|p| (p.pose as u32, p.mean, p.max, p.worst_part)).collect(),
    }
}

/// `desal inspect` lines for a fit artifact: overall figures and the worst parts and poses.
pub fn describe(fit: &FitV1, out: &mut String) {
    use std::fmt::Write as _;
    // The template fits itself exactly; the mean is over the other poses.
    let n = fit.vertex_count as usize;
    let rows: Vec<&[f32]> = fit
        .residuals
        .chunks(n.max(1))
        .enumerate()
        .filter(|(k, _)| *k != fit.template as usize)
        .map(|(_, r)| r)
        .collect();
    let count = (rows.len() * n).max(1) as f64;
    let mean = rows.iter().flat_map(|r| r.iter()).map(|&r| r as f64).sum::<f64>() / count;
    let _ = writeln!(
        out,
        "    {} fit: {} poses x {} parts, {} vertices; mean residual {:.3} mm over the non-template poses",
        fit.model,
        fit.pose_names.len(),
        fit.part_names.len(),
        fit.vertex_count,
        mean * 1e3
    );
    let _ = writeln!(out, "    worst parts (mean / max mm, worst pose):");
    for &(part, mean, max, pose) in fit.worst_parts.iter().take(5) {
        let _ = writeln!(
            out,
            "      {:<16} {:>8.3} {:>8.3}  {}",
            fit.part_names[part as usize],
            mean * 1e3,
            max * 1e3,
            fit.pose_names[pose as usize]
        );
    }
    let _ = writeln!(out, "    worst poses (mean / max mm, worst part):");
    for &(pose, mean, max, part) in fit.worst_poses.iter().take(5) {
        let _ = writeln!(
            out,
            "      {:<16} {:>8.3} {:>8.3}  {}",
            fit.pose_names[pose as usize],
            mean * 1e3,
            max * 1e3,
            fit.part_names[part as usize]
        );
    }
}
