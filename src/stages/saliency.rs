//! Stage 2 adapter: cache key, the call into `desal-saliency`, and the artifact
//! conversion.

use anyhow::Result;
use desal_io::artifact::{ArtifactKind, ContentHash, FitV1, SaliencyV1};
use desal_saliency::{Distance, Normalisation, ResidualTable, SaliencyConfig};
use serde_json::json;

use crate::cache::StageKey;
use crate::pipeline::{SaliencyParams, canonical_json};

/// Version of stage 2 as the driver runs it.
pub const VERSION: u32 = 1;

pub fn key(params: &SaliencyParams, poses: ContentHash, fit: ContentHash) -> StageKey {
    StageKey {
        stage: "saliency".into(),
        stage_version: VERSION,
        format_version: ArtifactKind::Saliency.current_version(),
        parameters: canonical_json(&json!({
            "squared": params.squared,
            "percentile": params.percentile,
            "exclude": params.exclude,
            "floor": params.floor.unwrap_or(desal_saliency::DEFAULT_WEIGHT_FLOOR),
        })),
        inputs: vec![("poses".into(), poses), ("fit".into(), fit)],
    }
}

pub fn config(params: &SaliencyParams) -> SaliencyConfig {
    SaliencyConfig {
        distance: if params.squared { Distance::Squared } else { Distance::Plain },
        normalisation: if params.percentile >= 100.0 {
            Normalisation::Max
        } else {
            Normalisation::Percentile(params.percentile)
        },
        exclude_poses: params.exclude.clone(),
        weight_floor: params.floor.unwrap_or(desal_saliency::DEFAULT_WEIGHT_FLOOR),
        ..SaliencyConfig::default()
    }
}

/// Runs stage 2 on a fit; `length_scale` is the template's bounding-box diagonal.
pub fn compute(
    params: &SaliencyParams,
    fit: &FitV1,
    length_scale: f64,
) -> Result<(SaliencyV1, serde_json::Value, String)> {
    let start = std::time::Instant::now();
    let table = ResidualTable {
        values: &fit.residuals,
        vertex_count: fit.vertex_count as usize,
        pose_names: &fit.pose_names,
        template: Some(fit.template as usize),
        length_scale,
    };
    let s = desal_saliency::compute_saliency(&table, &config(params))?;
    let seconds = start.elapsed().as_secs_f64();
    let r = &s.report;
    let normalisation = match r.normalisation {
        Normalisation::Max => "max".to_owned(),
        Normalisation::Percentile(p) => format!("p{p}"),
    };
    let distance = match r.distance {
        Distance::Plain => "plain",
        Distance::Squared => "squared",
    };
    let note = format!(
        "{} poses summed ({distance}), raw sums {:.3}..{:.3}, normalised by {normalisation} = {:.3}, weight floor {}",
        r.poses_used.len(),
        r.raw_min,
        r.raw_max,
        s.normaliser,
        r.weight_floor
    );
    let summary = json!({
        "seconds": seconds,
        "distance": distance,
        "normalisation": normalisation,
        "normaliser": s.normaliser,
        "weight_floor": r.weight_floor,
        "poses_used": r.poses_used.len(),
        "poses_excluded": r.poses_excluded,
        "raw_min": r.raw_min,
        "raw_max": r.raw_max,
        "raw_mean": r.raw_mean,
        "saturated_vertices": r.saturated_vertices,
        "rigid": r.rigid,
    });
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
    Ok((body, summary, note))
}

/// `desal inspect` lines for a saliency artifact.
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
