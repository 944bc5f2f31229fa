//! Stage 4: greedy least-distance mapping of simplified vertices to original vertex
//! indices, and applying the map to every pose (paper §3.2).
//!
//! Two vertex index spaces meet here and are named everywhere: `orig_idx`, a vertex of
//! the original pose set (the same body point in every pose), and `simp_idx`, a vertex of
//! the simplified template (the index its triangles use). A [`VertexMap`] is
//! `simp_to_orig[simp_idx] = orig_idx`, one-to-one.
//!
//! - **Greedy mode** (the paper's optimal placement, or a simplified template made by
//!   another tool): [`greedy_map`] pairs each simplified vertex with a distinct original
//!   vertex, globally closest pair first; [`greedy_map_brute_force`] is its reference.
//! - **Subset mode**: stage 3 kept original vertices, so the map is given
//!   ([`VertexMap::from_subset`]).
//!
//! Then [`apply_map`] gathers every pose at the mapped vertices, with the simplified
//! triangles and the carried part labels, so all simplified poses are registered the same
//! way (in greedy mode the simplified template itself is replaced by the mapped original
//! template vertices; [`MapReport::displacement`] says how far that moved them).
//! [`map_pose_set`] runs the whole stage; [`map_template`] runs it up to the simplified
//! poses, for a caller that needs only the map, the carried labels and the report.
//!
//! **Invariant:** no file format, path or progress bar here; input is data, output is
//! data plus a [`MapReport`].

mod apply;
mod error;
mod greedy;
mod kdtree;
mod vertex_map;

use std::fmt;
use std::time::Instant;

use desal_mesh::{PartLabels, PoseSet, TriMesh};

pub use apply::{Displacement, apply_map, displacement, empty_parts, map_labels};
pub use error::MapError;
pub use greedy::{greedy_map, greedy_map_brute_force, greedy_map_with, squared_distance};
pub use vertex_map::VertexMap;

/// Version of this stage's output. The driver's cache key carries it, so bump it in the
/// same commit as any change that alters the output for the same input and config; the
/// golden test `tests/golden.rs` fails until you do.
pub const VERSION: u32 = 1;

/// Options of stage 4. The map never depends on them, only the time it takes.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MapConfig {
    /// Nearest original vertices fetched per simplified vertex at first by the fast
    /// greedy mapping (doubled for a vertex whose candidates are all taken). Default 8:
    /// on a 5:1 simplification of a body mesh nearly every vertex finds its partner among
    /// its 8 nearest, so few vertices need a second query.
    pub initial_candidates: usize,
}

impl Default for MapConfig {
    fn default() -> Self {
        Self { initial_candidates: 8 }
    }
}

/// Where the map comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapMode<'a> {
    /// Search it: greedy least-distance mapping of the simplified template's positions
    /// onto the original template (optimal placement, or another tool's output).
    Greedy,
    /// Take it: stage 3's subset placement kept these original vertices, in `simp_idx`
    /// order (`kept_orig[simp_idx] = orig_idx`).
    Subset { kept_orig: &'a [u32] },
}

impl MapMode<'_> {
    /// `"greedy"` or `"subset"`, for reports.
    pub fn name(&self) -> &'static str {
        match self {
            MapMode::Greedy => "greedy",
            MapMode::Subset { .. } => "subset",
        }
    }
}

/// What stage 4 produced.
#[derive(Debug, Clone, PartialEq)]
pub struct MapOutput {
    /// `simp_to_orig`, one entry per simplified vertex.
    pub map: VertexMap,
    /// Every pose simplified: `map.len()` vertices, the simplified triangles.
    pub poses: PoseSet,
    /// Part labels in `simp_idx` space, same part names as the input.
    pub labels: PartLabels,
    pub report: MapReport,
}

/// Counts, displacement and timings of one stage-4 run.
#[derive(Debug, Clone, PartialEq)]
pub struct MapReport {
    /// `"greedy"` or `"subset"`.
    pub mode: &'static str,
    /// Vertices per original pose.
    pub original_vertices: usize,
    /// Vertices per simplified pose (the map's length).
    pub simplified_vertices: usize,
    /// Triangles per simplified pose.
    pub simplified_faces: usize,
    /// Poses simplified.
    pub poses: usize,
    /// Distance between the given simplified template positions and the original
    /// template vertices they were mapped to, in the pose set's units (metres for SCAPE).
    /// Zero in subset mode when the template is stage 3's own output.
    pub displacement: Displacement,
    /// Part ids no simplified vertex carries (ascending).
    pub empty_parts: Vec<u32>,
    /// Wall time of building (or validating) the map, in seconds.
    pub map_seconds: f64,
    /// Wall time of applying it to every pose, in seconds.
    pub apply_seconds: f64,
}

impl fmt::Display for MapReport {
    /// One line: "12500 → 2500 vertices, 4996 faces, 71 poses (greedy): displacement
    /// mean 1.2e-3 / max 4.0e-3, map 2.1 ms, apply 6.3 ms".
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} → {} vertices, {} faces, {} poses ({}): displacement mean {:.3e} / max {:.3e}, map {:.1} ms, apply {:.1} ms",
            self.original_vertices,
            self.simplified_vertices,
            self.simplified_faces,
            self.poses,
            self.mode,
            self.displacement.mean,
            self.displacement.max,
            self.map_seconds * 1e3,
            self.apply_seconds * 1e3,
        )?;
        if !self.empty_parts.is_empty() {
            write!(f, ", parts without vertices: {:?}", self.empty_parts)?;
        }
        Ok(())
    }
}

/// Stage 4 without the simplified poses ([`map_template`]).
#[derive(Debug, Clone, PartialEq)]
pub struct MappedTemplate {
    /// `simp_to_orig`, one entry per simplified vertex.
    pub map: VertexMap,
    /// Part labels in `simp_idx` space, as [`MapOutput::labels`].
    pub labels: PartLabels,
    /// As [`map_pose_set`]'s, but `apply_seconds` is the time of carrying the labels
    /// only (no pose is gathered).
    pub report: MapReport,
}

/// Runs stage 4: builds the map from `simplified` (the simplified template, `simp_idx`
/// space) to the template of `poses` (`orig_idx` space) as `mode` says, measures the
/// displacement, and applies the map to every pose and to `labels`.
///
/// Errors: see [`greedy_map`], [`VertexMap::from_subset`] and [`apply_map`]; in subset
/// mode also a `kept_orig` whose length is not the simplified vertex count.
pub fn map_pose_set(
    config: &MapConfig,
    mode: MapMode<'_>,
    simplified: &TriMesh,
    poses: &PoseSet,
    labels: &PartLabels,
) -> Result<MapOutput, MapError> {
    let MappedTemplate { map, labels, mut report } = map_template(config, mode, simplified, poses, labels)?;
    let apply_started = Instant::now();
    let simplified_poses = apply::gather_poses(poses, &simplified.faces, &map)?;
    report.apply_seconds += apply_started.elapsed().as_secs_f64();
    Ok(MapOutput { map, poses: simplified_poses, labels, report })
}

/// [`map_pose_set`] without gathering the simplified poses: the same map, labels and
/// report (but `apply_seconds`, see [`MappedTemplate::report`]), for a caller that
/// applies the map later, if at all ([`apply_map`]).
///
/// Errors: those of [`map_pose_set`].
pub fn map_template(
    config: &MapConfig,
    mode: MapMode<'_>,
    simplified: &TriMesh,
    poses: &PoseSet,
    labels: &PartLabels,
) -> Result<MappedTemplate, MapError> {
    let (map, map_seconds) = build_map(config, mode, simplified, poses.template_positions())?;
    let displacement = displacement(&simplified.positions, poses.template_positions(), &map)?;

    let apply_started = Instant::now();
    let simplified_labels = map_labels(poses, labels, &simplified.faces, &map)?;
    let apply_seconds = apply_started.elapsed().as_secs_f64();

    let report = MapReport {
        mode: mode.name(),
        original_vertices: poses.vertex_count(),
        simplified_vertices: map.len(),
        simplified_faces: simplified.faces.len(),
        poses: poses.pose_count(),
        displacement,
        empty_parts: empty_parts(&simplified_labels),
        map_seconds,
        apply_seconds,
    };
    Ok(MappedTemplate { map, labels: simplified_labels, report })
}

/// The map of `mode` from the simplified template onto `template`, and the seconds it
/// took.
fn build_map(
    config: &MapConfig,
    mode: MapMode<'_>,
    simplified: &TriMesh,
    template: &[desal_mesh::Vec3],
) -> Result<(VertexMap, f64), MapError> {
    let map_started = Instant::now();
    let map = match mode {
        MapMode::Greedy => greedy_map_with(config, &simplified.positions, template)?,
        MapMode::Subset { kept_orig } => {
            if kept_orig.len() != simplified.positions.len() {
                return Err(MapError::MapLengthMismatch {
                    positions: simplified.positions.len(),
                    map: kept_orig.len(),
                });
            }
            VertexMap::from_subset(kept_orig, template.len())?
        }
    };
    Ok((map, map_started.elapsed().as_secs_f64()))
}
