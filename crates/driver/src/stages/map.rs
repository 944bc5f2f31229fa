//! Stage 4: its cache key, the one path into `desal-map` (which map mode a stage-3
//! result gets, the belongs-together checks) and the artifact conversion.

use anyhow::{Result, bail};
use desal_io::artifact::{ArtifactKind, ContentHash, MapV1, SimplifiedV1};
use desal_map::{MapConfig, MapMode, MapOutput, MapReport, MappedTemplate, VertexMap};
use desal_mesh::{PartLabels, PoseSet, TriMesh};
use serde::{Deserialize, Serialize};
use serde_json::json;

use crate::cache::{StageKey, canonical_json};
use crate::stages::runner::StageOutput;
use crate::stages::simplify::mesh;

/// The cache key of a map of `simplified` onto `poses`.
pub fn key(poses: ContentHash, simplified: ContentHash) -> StageKey {
    let MapConfig { initial_candidates } = MapConfig::default();
    StageKey {
        stage: "map".into(),
        stage_version: desal_map::VERSION,
        format_version: ArtifactKind::Map.current_version(),
        parameters: "{}".into(),
        resolved: canonical_json(&json!({ "initial_candidates": initial_candidates })),
        inputs: vec![("poses".into(), poses), ("simplified".into(), simplified)],
    }
}

/// A mapped vertex this far (mean, as a fraction of the template's bounding-box
/// diagonal) from its original vertex means the simplified mesh is of another template:
/// desal's own and the peers' simplifications at SCAPE's 2500 vertices are at 0.2 %.
const MAX_MEAN_DISPLACEMENT: f64 = 0.05;

/// The same guard in units of the template's mean edge length, which catches a
/// simplification of another pose of the same body (a limb moved by centimetres is far
/// under 5 % of the diagonal but many edges away): desal's and the peers'
/// simplifications sit at a fraction of an edge (the sample at 2500 vertices: a quarter).
const MAX_DISPLACEMENT_EDGES: f64 = 4.0;

/// Refuses a stage-3 result made from another pose set: its input vertex count and the
/// exact positions of its kept original vertices must be the template's.
fn check_made_from(simplified: &SimplifiedV1, set: &PoseSet) -> Result<()> {
    if simplified.placement == "external" {
        return Ok(());
    }
    let template = set.template_positions();
    if simplified.input_vertices as usize != template.len() {
        bail!(
            "the simplified template was made from a mesh of {} vertices, but this template has {}: \
             it belongs to another pose set",
            simplified.input_vertices,
            template.len()
        );
    }
    for (s, (p, o)) in simplified.positions.iter().zip(&simplified.simp_to_orig).enumerate() {
        if let Some(o) = *o {
            let original = template.get(o as usize).map(|q| [q.x, q.y, q.z]);
            if original != Some(*p) {
                bail!(
                    "simplified vertex {s} claims to be original vertex {o}, but that vertex of this \
                     template is elsewhere: the simplified template belongs to another pose set"
                );
            }
        }
    }
    Ok(())
}

/// Maps a stage-3 result (desal's or another tool's) onto `set` and applies the map to
/// every pose: subset results by their own `simp_to_orig`, the rest by the paper's greedy
/// rule. Refuses a result of another pose set, and a mesh that does not lie on this
/// template.
pub fn map(simplified: &SimplifiedV1, set: &PoseSet, labels: &PartLabels) -> Result<MapOutput> {
    checked(simplified, set, labels, desal_map::map_pose_set, |out| &out.report)
}

/// [`map`] without applying the map to the poses: the map, the carried labels and the
/// report, which is all the stage keeps (the simplified poses are gathered by [`apply`]
/// when an output needs them).
fn map_template(simplified: &SimplifiedV1, set: &PoseSet, labels: &PartLabels) -> Result<MappedTemplate> {
    checked(simplified, set, labels, desal_map::map_template, |out| &out.report)
}

/// `run` (one of `desal_map`'s stage-4 entry points) on `simplified`, between the checks
/// both of the above make: the result is of this pose set, and lies on its template.
fn checked<T>(
    simplified: &SimplifiedV1,
    set: &PoseSet,
    labels: &PartLabels,
    run: impl FnOnce(&MapConfig, MapMode<'_>, &TriMesh, &PoseSet, &PartLabels) -> Result<T, desal_map::MapError>,
    report: impl FnOnce(&T) -> &MapReport,
) -> Result<T> {
    check_made_from(simplified, set)?;
    let kept = kept_orig(simplified);
    let out = run(&MapConfig::default(), mode(kept.as_deref()), &mesh(simplified), set, labels)?;
    check_lies_on(report(&out), set)?;
    Ok(out)
}

/// The kept original vertices of a subset result, `None` when any vertex is new.
fn kept_orig(simplified: &SimplifiedV1) -> Option<Vec<u32>> {
    simplified.simp_to_orig.iter().copied().collect()
}

/// Subset mode when the result kept original vertices, greedy otherwise.
fn mode(kept: Option<&[u32]>) -> MapMode<'_> {
    match kept {
        Some(kept_orig) => MapMode::Subset { kept_orig },
        None => MapMode::Greedy,
    }
}

/// Refuses a mapped mesh that does not lie on `set`'s template ([`MAX_MEAN_DISPLACEMENT`],
/// [`MAX_DISPLACEMENT_EDGES`]).
fn check_lies_on(r: &MapReport, set: &PoseSet) -> Result<()> {
    let diagonal =
        desal_mesh::math::bounding_box(set.template_positions()).map_or(0.0, |(lo, hi)| (hi - lo).norm());
    let (edge_length, _) = set.template_mesh().edge_length_stats();
    if r.displacement.mean > MAX_MEAN_DISPLACEMENT * diagonal
        || r.displacement.mean > MAX_DISPLACEMENT_EDGES * edge_length
    {
        bail!(
            "the simplified mesh does not lie on this template: its vertices are {:.3e} from their \
             mapped original vertices on average ({:.1} % of the template's diagonal, {:.1} of its mean \
             edge lengths; a simplification of it is within a fraction of an edge) — is it a \
             simplification of this template, in the same units and pose?",
            r.displacement.mean,
            100.0 * r.displacement.mean / diagonal,
            r.displacement.mean / edge_length
        );
    }
    Ok(())
}

/// `map.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MapSummary {
    pub mode: String,
    pub original_vertices: usize,
    pub simplified_vertices: usize,
    pub simplified_faces: usize,
    pub poses: usize,
    pub displacement_mean: f64,
    pub displacement_max: f64,
    pub empty_parts: Vec<u32>,
    pub map_seconds: f64,
    pub apply_seconds: f64,
}

/// Runs stage 4 as a pipeline stage: [`map`] without the simplified poses (the stage
/// keeps the map only); warns about parts no simplified vertex carries.
pub fn compute(
    simplified: &SimplifiedV1,
    set: &PoseSet,
    labels: &PartLabels,
) -> Result<StageOutput<MapV1, MapSummary>> {
    let out = map_template(simplified, set, labels)?;
    let r = &out.report;
    if !r.empty_parts.is_empty() {
        let names: Vec<&str> = r.empty_parts.iter().map(|&p| labels.names[p as usize].as_str()).collect();
        eprintln!(
            "warning: no simplified vertex carries part(s) {}: the target is too coarse for them",
            names.join(", ")
        );
    }
    let summary = MapSummary {
        mode: r.mode.into(),
        original_vertices: r.original_vertices,
        simplified_vertices: r.simplified_vertices,
        simplified_faces: r.simplified_faces,
        poses: r.poses,
        displacement_mean: r.displacement.mean,
        displacement_max: r.displacement.max,
        empty_parts: r.empty_parts.clone(),
        map_seconds: r.map_seconds,
        apply_seconds: r.apply_seconds,
    };
    let body = MapV1 {
        simp_to_orig: out.map.simp_to_orig.clone(),
        faces: simplified.faces.clone(),
        mode: r.mode.into(),
        displacement_mean: r.displacement.mean,
        displacement_max: r.displacement.max,
    };
    Ok(StageOutput { body, summary, note: r.to_string() })
}

pub fn apply(map: &MapV1, set: &PoseSet, labels: &PartLabels) -> Result<(PoseSet, PartLabels)> {
    Ok(desal_map::apply_map(set, labels, &map.faces, &vertex_map(map, set)?)?)
}

/// The simplified vertices' labels, as [`apply`] gives them, without the simplified
/// poses.
pub fn labels(map: &MapV1, set: &PoseSet, labels: &PartLabels) -> Result<PartLabels> {
    Ok(desal_map::map_labels(set, labels, &map.faces, &vertex_map(map, set)?)?)
}

/// A map artifact's map onto `set`, checked against its own triangles.
fn vertex_map(map: &MapV1, set: &PoseSet) -> Result<VertexMap> {
    let vertex_map = VertexMap::try_new(map.simp_to_orig.clone(), set.vertex_count())?;
    if map.faces.iter().flatten().any(|&i| i as usize >= vertex_map.len()) {
        bail!("the map's triangles reference vertices beyond its {} entries", vertex_map.len());
    }
    Ok(vertex_map)
}

/// `desal inspect` lines for a map artifact.
pub fn describe(m: &MapV1, out: &mut String) {
    use std::fmt::Write as _;
    let _ = writeln!(
        out,
        "    {} map: {} simplified vertices, {} faces; displacement mean {:.3e} max {:.3e}",
        m.mode,
        m.simp_to_orig.len(),
        m.faces.len(),
        m.displacement_mean,
        m.displacement_max
    );
}
