//! Stage 2: its parameters and their validation, its cache key, the call into
//! `desal-saliency` and the artifact conversion.

use anyhow::Result;
use desal_io::artifact::{ArtifactKind, ContentHash, FitV1, SaliencyV1};
use desal_saliency::{Distance, Normalisation, ResidualTable, SaliencyConfig};
use serde::{Deserialize, Serialize};
use serde_json::json;

use crate::cache::{StageKey, canonical_json};
use crate::stages::runner::StageOutput;

/// Stage 2 parameters (`[saliency]` in pipeline files, `desal saliency` flags).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SaliencyParams {
    /// Sum squared residual distances instead of plain ones.
    pub squared: bool,
    /// Normalise by this percentile of the per-vertex sums, in (0, 100] (100 = the
    /// maximum, the paper).
    pub percentile: f64,
    /// Pose names left out of the sum.
    pub exclude: Vec<String>,
    /// Weight floor: stage 3 uses `floor + (1 - floor) * saliency`. Default
    /// [`desal_saliency::DEFAULT_WEIGHT_FLOOR`].
    pub floor: Option<f64>,
}

impl Default for SaliencyParams {
    fn default() -> Self {
        SaliencyParams { squared: false, percentile: 100.0, exclude: Vec::new(), floor: None }
    }
}

impl SaliencyParams {
    /// The poses of `set` stage 2 reads: the template and every pose `exclude` does not
    /// name (what pose-aware simplifications may look at, `desal eval`'s and the
    /// library's alike).
    pub fn seen_poses(&self, set: &desal_mesh::PoseSet) -> Vec<usize> {
        (0..set.pose_count())
            .filter(|&p| p == set.template || !self.exclude.contains(&set.names[p]))
            .collect()
    }

    /// The library configuration these parameters resolve to, validated.
    pub fn config(&self) -> Result<SaliencyConfig> {
        let config = SaliencyConfig {
            distance: if self.squared { Distance::Squared } else { Distance::Plain },
            normalisation: if self.percentile == 100.0 {
                Normalisation::Max
            } else {
                Normalisation::Percentile(self.percentile)
            },
            exclude_poses: self.exclude.clone(),
            weight_floor: self.floor.unwrap_or(desal_saliency::DEFAULT_WEIGHT_FLOOR),
            ..SaliencyConfig::default()
        };
        config.validate()?;
        Ok(config)
    }

    /// The cache key of a saliency of `poses` from `fit`.
    pub fn key(&self, poses: ContentHash, fit: ContentHash) -> Result<StageKey> {
        let SaliencyConfig { distance, normalisation, exclude_poses, weight_floor, rigid_tolerance } =
            self.config()?;
        let normalisation = match normalisation {
            Normalisation::Max => json!("max"),
            Normalisation::Percentile(p) => json!({ "percentile": p }),
        };
        Ok(StageKey {
            stage: "saliency".into(),
            stage_version: desal_saliency::VERSION,
            format_version: ArtifactKind::Saliency.current_version(),
            parameters: canonical_json(&json!({
                "squared": self.squared,
                "percentile": self.percentile,
                "exclude": self.exclude,
                "floor": weight_floor,
            })),
            resolved: canonical_json(&json!({
                "distance": distance_name(distance),
                "normalisation": normalisation,
                "exclude_poses": exclude_poses,
                "weight_floor": weight_floor,
                "rigid_tolerance": rigid_tolerance,
            })),
            inputs: vec![("poses".into(), poses), ("fit".into(), fit)],
        })
    }
}

fn distance_name(distance: Distance) -> &'static str {
    match distance {
        Distance::Plain => "plain",
        Distance::Squared => "squared",
    }
}

/// `saliency.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SaliencySummary {
    pub seconds: f64,
    pub distance: String,
    pub normalisation: String,
    pub normaliser: f64,
    pub weight_floor: f64,
    pub poses_used: usize,
    pub poses_excluded: Vec<String>,
    pub raw_min: f64,
    pub raw_max: f64,
    pub raw_mean: f64,
    pub saturated_vertices: usize,
    pub rigid: bool,
}

/// Runs stage 2 on a fit's residuals; `length_scale` is the template's diagonal.
pub fn compute(
    params: &SaliencyParams,
    fit: &FitV1,
    length_scale: f64,
) -> Result<StageOutput<SaliencyV1, SaliencySummary>> {
    let start = std::time::Instant::now();
    let table = ResidualTable {
        values: &fit.residuals,
        vertex_count: fit.vertex_count as usize,
        pose_names: &fit.pose_names,
        template: Some(fit.template as usize),
        length_scale,
    };
    let s = desal_saliency::compute_saliency(&table, &params.config()?)?;
    let seconds = start.elapsed().as_secs_f64();
    let r = &s.report;
    let normalisation = match r.normalisation {
        Normalisation::Max => "max".to_owned(),
        Normalisation::Percentile(p) => format!("p{p}"),
    };
    let distance = distance_name(r.distance);
    let note = format!(
        "{} poses summed ({distance}), raw sums {:.3}..{:.3}, normalised by {normalisation} = {:.3}, weight floor {}",
        r.poses_used.len(),
        r.raw_min,
        r.raw_max,
        s.normaliser,
        r.weight_floor
    );
    let summary = SaliencySummary {
        seconds,
        distance: distance.into(),
        normalisation: normalisation.clone(),
        normaliser: s.normaliser,
        weight_floor: r.weight_floor,
        poses_used: r.poses_used.len(),
        poses_excluded: r.poses_excluded.clone(),
        raw_min: r.raw_min,
        raw_max: r.raw_max,
        raw_mean: r.raw_mean,
        saturated_vertices: r.saturated_vertices,
        rigid: r.rigid,
    };
    let body = SaliencyV1 {
        saliency: s.saliency,
        weights: s.weights,
        raw: s.raw,
        normaliser: s.normaliser,
        distance: distance.into(),
        normalisation,
        weight_floor: r.weight_floor,
        poses_used: r.poses_used.clone(),
        poses_excluded: r.poses_excluded.clone(),
        rigid: r.rigid,
    };
    Ok(StageOutput { body, summary, note })
}

pub fn describe(s: &SaliencyV1, out: &mut String) {
    use std::fmt::Write as _;
    let n = s.saliency.len().max(1) as f64;
    let mean = s.saliency.iter().sum::<f64>() / n;
    let above_half = s.saliency.iter().filter(|&&v| v > 0.5).count();
    let _ = writeln!(
        out,
        "    {} vertices, {} poses ({} distance, normalised by {} = {:.4}); mean saliency {:.3}, {} vertices above 0.5; weight floor {}{}",
        s.saliency.len(),
        s.poses_used.len(),
        s.distance,
        s.normalisation,
        s.normaliser,
        mean,
        above_half,
        s.weight_floor,
        if s.rigid { " (rigid set: no deformation)" } else { "" }
    );
}
