//! Stage 3 adapter: cache key, the call into `desal-simplify`, and the artifact
//! conversion.

use anyhow::{Result, bail};
use desal_io::artifact::{ArtifactKind, ContentHash, SimplifiedV1};
use desal_mesh::{PartLabels, TriMesh, Vec3};
use desal_simplify::{Metric, PartBorders, Placement, SimplifyConfig, SimplifyInput, StopReason, Target};
use serde_json::json;

use crate::cache::StageKey;
use crate::pipeline::{SimplifyParams, canonical_json};

/// Version of stage 3 as the driver runs it.
/// 2: the corner-normal fold guard (`max_corner_normal_deg`) changes results.
pub const VERSION: u32 = 2;

/// The target a parameter set asks for: vertices, else faces, else the ratio.
pub fn target(params: &SimplifyParams) -> Target {
    match (params.target_vertices, params.target_faces, params.ratio) {
        (Some(v), _, _) => Target::Vertices(v),
        (None, Some(f), _) => Target::Faces(f),
        (None, None, Some(r)) => Target::Ratio(r),
        (None, None, None) => Target::Ratio(0.2),
    }
}

pub fn config(params: &SimplifyParams) -> Result<SimplifyConfig> {
    let given = [params.target_vertices.is_some(), params.target_faces.is_some(), params.ratio.is_some()];
    if given.iter().filter(|&&g| g).count() > 1 {
        bail!("simplify: give one of target_vertices, target_faces and ratio, not several");
    }
    match target(params) {
        Target::Vertices(n) | Target::Faces(n) if n < 4 => {
            bail!(
                "simplify: a target of {n} is too small: the simplest closed surface has 4 vertices and 4 faces"
            )
        }
        _ => {}
    }
    let placement = match params.placement.as_str() {
        "optimal" => Placement::Optimal,
        "subset" => Placement::Subset,
        other => bail!("simplify.placement '{other}' is unknown: use \"optimal\" or \"subset\""),
    };
    let metric = match params.metric.as_str() {
        "quadric" => Metric::Quadric,
        "lindstrom-turk" => Metric::LindstromTurk,
        other => bail!("simplify.metric '{other}' is unknown: use \"quadric\" or \"lindstrom-turk\""),
    };
    let config = SimplifyConfig {
        target: target(params),
        placement,
        saliency: params.saliency,
        balance: params.balance,
        part_borders: if params.keep_part_borders { PartBorders::Lock } else { PartBorders::Ignore },
        metric,
        ..SimplifyConfig::default()
    };
    config.validate()?;
    Ok(config)
}

/// The key covers only what the result depends on: the resolved target, and the
/// saliency (labels) input only when the cost (border lock) uses it.
pub fn key(
    params: &SimplifyParams,
    poses: ContentHash,
    saliency: ContentHash,
    labels: ContentHash,
) -> StageKey {
    let target = match target(params) {
        Target::Vertices(v) => json!({ "vertices": v }),
        Target::Faces(f) => json!({ "faces": f }),
        Target::Ratio(r) => json!({ "ratio": r }),
    };
    let mut inputs = vec![("poses".to_owned(), poses)];
    if params.saliency {
        inputs.push(("saliency".into(), saliency));
    }
    if params.keep_part_borders {
        inputs.push(("labels".into(), labels));
    }
    StageKey {
        stage: "simplify".into(),
        stage_version: VERSION,
        format_version: ArtifactKind::Simplified.current_version(),
        parameters: canonical_json(&json!({
            "target": target,
            "placement": params.placement,
            "saliency": params.saliency,
            "balance": params.balance,
            "keep_part_borders": params.keep_part_borders,
            "metric": params.metric,
        })),
        inputs,
    }
}

/// Runs stage 3 on the template with the saliency weights.
pub fn compute(
    params: &SimplifyParams,
    template: &TriMesh,
    weights: &[f64],
    labels: &PartLabels,
    progress: &dyn desal_mesh::Progress,
) -> Result<(SimplifiedV1, serde_json::Value, String)> {
    let config = config(params)?;
    let mut input = SimplifyInput::new(template);
    if params.saliency {
        input = input.with_weights(weights);
    }
    if params.keep_part_borders {
        input = input.with_part_labels(&labels.labels);
    }
    let result = desal_simplify::simplify_with_progress(&input, &config, progress)?;
    let r = &result.report;
    let note = r.to_string();
    let stop = match r.stop {
        StopReason::TargetReached => "target",
        StopReason::NoValidCollapse => "no-valid-collapse",
    };
    let summary = json!({
        "method": method_name(params),
        "placement": params.placement,
        "metric": params.metric,
        "input_vertices": r.input_vertices,
        "input_faces": r.input_faces,
        "output_vertices": r.output_vertices,
        "output_faces": r.output_faces,
        "collapses": r.collapses,
        "stop": stop,
        "refused_topology": r.refusals.topology,
        "refused_flip": r.refusals.flip,
        "refused_degenerate": r.refusals.degenerate,
        "locked_vertices": r.locked_vertices,
        "max_error": r.max_error,
        "mean_error": r.mean_error,
        "edge_length_mean": r.edge_length_mean,
        "edge_length_variance": r.edge_length_variance,
        "seconds": r.seconds,
    });
    let body = SimplifiedV1 {
        positions: result.mesh.positions.iter().map(|p| [p.x, p.y, p.z]).collect(),
        faces: result.mesh.faces.clone(),
        simp_to_orig: result.simp_to_orig.clone(),
        placement: params.placement.clone(),
        input_vertices: r.input_vertices as u32,
        input_faces: r.input_faces as u32,
        collapses: r.collapses as u32,
        stop: stop.into(),
        max_error: r.max_error,
        mean_error: r.mean_error,
        edge_length_mean: r.edge_length_mean,
        edge_length_variance: r.edge_length_variance,
    };
    Ok((body, summary, note))
}

/// `qslim`, `saliency`, `balance` or `paper`, from the two cost switches.
pub fn method_name(params: &SimplifyParams) -> &'static str {
    match (params.saliency, params.balance) {
        (false, false) => "qslim",
        (true, false) => "saliency",
        (false, true) => "balance",
        (true, true) => "paper",
    }
}

/// A simplified template made by another tool, as a stage-3 body: no vertex is known to
/// be an original one, so stage 4 maps all of them by the greedy rule.
pub fn external(mesh: &TriMesh) -> SimplifiedV1 {
    SimplifiedV1 {
        positions: mesh.positions.iter().map(|p| [p.x, p.y, p.z]).collect(),
        faces: mesh.faces.clone(),
        simp_to_orig: vec![None; mesh.vertex_count()],
        placement: "external".into(),
        input_vertices: 0,
        input_faces: 0,
        collapses: 0,
        stop: "external".into(),
        max_error: f64::NAN,
        mean_error: f64::NAN,
        edge_length_mean: f64::NAN,
        edge_length_variance: f64::NAN,
    }
}

/// The simplified template as a mesh.
pub fn mesh(body: &SimplifiedV1) -> TriMesh {
    TriMesh { positions: body.positions.iter().map(|&p| Vec3::from(p)).collect(), faces: body.faces.clone() }
}

/// `desal inspect` lines for a simplified artifact.
pub fn describe(s: &SimplifiedV1, out: &mut String) {
    use std::fmt::Write as _;
    let kept = s.simp_to_orig.iter().filter(|o| o.is_some()).count();
    let _ = writeln!(
        out,
        "    {} placement: {} -> {} vertices, {} -> {} faces ({} collapses, stopped: {})",
        s.placement,
        s.input_vertices,
        s.positions.len(),
        s.input_faces,
        s.faces.len(),
        s.collapses,
        s.stop
    );
    let _ = writeln!(
        out,
        "    collapse error (RMS distance, mesh units) max {:.3e} mean {:.3e}; edge length mean {:.4e}, variance {:.3e}; {} of {} vertices are original vertices",
        s.max_error,
        s.mean_error,
        s.edge_length_mean,
        s.edge_length_variance,
        kept,
        s.positions.len()
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameters_are_checked_and_the_metric_enters_the_cache_key() {
        let quadric = SimplifyParams::default();
        assert_eq!(config(&quadric).unwrap().metric, Metric::Quadric);
        let lt = SimplifyParams { metric: "lindstrom-turk".into(), ..SimplifyParams::default() };
        assert_eq!(config(&lt).unwrap().metric, Metric::LindstromTurk);
        let hash = ContentHash::of(b"poses");
        assert_ne!(key(&quadric, hash, hash, hash).hash(), key(&lt, hash, hash, hash).hash());
        let two =
            SimplifyParams { target_vertices: Some(100), ratio: Some(0.5), ..SimplifyParams::default() };
        assert!(config(&two).unwrap_err().to_string().contains("not several"));
        let zero = SimplifyParams { target_vertices: Some(0), ..SimplifyParams::default() };
        assert!(config(&zero).unwrap_err().to_string().contains("too small"));
        let typo = SimplifyParams { metric: "lindstrom".into(), ..SimplifyParams::default() };
        let err = config(&typo).unwrap_err().to_string();
        assert!(err.contains("simplify.metric 'lindstrom'"), "{err}");
    }
}
