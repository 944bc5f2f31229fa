//! Pictures and viewer files written next to the artifacts: heat-map PNGs through
//! `desal-viz`, and PLY files with per-vertex colour and a named float property that
//! MeshLab and Blender read.

use std::path::Path;

use anyhow::{Result, bail};
use desal_io::ply::{PlyWriteOptions, write_ply};
use desal_mesh::{PartLabels, TriMesh};
use desal_viz::{Direction, RenderConfig, Scalar};

/// Parses a pipeline's `up_axis` ("x", "-y", "+z", ...); `None` means detect it.
pub fn parse_up_axis(text: Option<&str>) -> Result<Option<Direction>> {
    Ok(Some(match text {
        None => return Ok(None),
        Some("x" | "+x" | "X" | "+X") => Direction::PosX,
        Some("-x" | "-X") => Direction::NegX,
        Some("y" | "+y" | "Y" | "+Y") => Direction::PosY,
        Some("-y" | "-Y") => Direction::NegY,
        Some("z" | "+z" | "Z" | "+Z") => Direction::PosZ,
        Some("-z" | "-Z") => Direction::NegZ,
        Some(other) => bail!("up_axis '{other}' is not an axis: use x, y, z, optionally signed (-y)"),
    }))
}

/// A front-and-back heat map of `mesh` coloured by `scalar`, as PNG bytes.
pub fn heatmap_png(
    mesh: &TriMesh,
    scalar: Scalar,
    up: Option<Direction>,
    title: &str,
    units: &str,
    range: Option<(f64, f64)>,
) -> Result<Vec<u8>> {
    let config =
        RenderConfig { up, title: title.into(), units: units.into(), range, ..RenderConfig::default() };
    let image = desal_viz::render_heatmap(mesh, scalar, &config)?;
    Ok(desal_viz::encode_png(&image)?)
}

/// Writes `mesh` as binary PLY with per-vertex colours from `values` (mapped over
/// `[min, max]`) and the values themselves as float property `name`.
pub fn write_scalar_ply(path: &Path, mesh: &TriMesh, name: &str, values: &[f64]) -> Result<()> {
    let (lo, hi) = values.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let span = if hi > lo { hi - lo } else { 1.0 };
    let options = PlyWriteOptions {
        colors: Some(values.iter().map(|&v| desal_viz::colormap((v - lo) / span)).collect()),
        scalars: vec![(name.to_owned(), values.iter().map(|&v| v as f32).collect())],
        comments: vec![format!("desal: per-vertex {name}, colours over [{lo}, {hi}]")],
        ..PlyWriteOptions::default()
    };
    write_ply(path, mesh, &options)?;
    Ok(())
}

/// The parts on the template, one colour each (`desal_viz::part_face_values`), as PNG
/// bytes (`parts.png`).
pub fn parts_png(mesh: &TriMesh, labels: &PartLabels, up: Option<Direction>) -> Result<Vec<u8>> {
    let values = desal_viz::part_face_values(&mesh.faces, &labels.labels);
    let config = RenderConfig {
        up,
        title: format!("{} parts", labels.part_count()),
        range: Some((0.0, 1.0)),
        colour_bar: false,
        ..RenderConfig::default()
    };
    let image = desal_viz::render_heatmap(mesh, Scalar::PerFace(&values), &config)?;
    Ok(desal_viz::encode_png(&image)?)
}

/// The coarse levels of a hierarchy beside the template, front views, each drawn with
/// its parts' colours at its template positions (`hierarchy.png`). Every view uses the
/// template's frame, so the levels line up.
pub fn hierarchy_levels_png(
    template: &TriMesh,
    labels: &PartLabels,
    levels: &[&desal_io::artifact::HierarchyLevelV1],
    up: Option<Direction>,
) -> Result<Vec<u8>> {
    let frame = desal_viz::resolve_frame(template, &RenderConfig { up, ..RenderConfig::default() })?;
    let front_view = |mesh: &TriMesh, point_labels: &[u32], title: String| -> Result<desal_viz::RgbaImage> {
        let values = desal_viz::part_face_values(&mesh.faces, point_labels);
        let config = RenderConfig {
            up: Some(frame.up),
            front: Some(frame.front),
            title,
            range: Some((0.0, 1.0)),
            colour_bar: false,
            ..RenderConfig::default()
        };
        let image = desal_viz::render_heatmap(mesh, Scalar::PerFace(&values), &config)?;
        Ok(image.crop(0, 0, config.view_width, image.height))
    };
    let mut views =
        vec![front_view(template, &labels.labels, format!("level 0: {} v", template.vertex_count()))?];
    for (k, level) in levels.iter().enumerate() {
        let mesh = TriMesh {
            positions: level.coarse_to_orig.iter().map(|&o| template.positions[o as usize]).collect(),
            faces: level.faces.clone(),
        };
        let point_labels: Vec<u32> =
            level.coarse_to_orig.iter().map(|&o| labels.labels[o as usize]).collect();
        views.push(front_view(&mesh, &point_labels, format!("level {}: {} v", k + 1, mesh.vertex_count()))?);
    }
    Ok(desal_viz::encode_png(&desal_viz::RgbaImage::hstack(&views, [255, 255, 255, 255]))?)
}

/// The held-out per-vertex upsampling error of each level step, as RMS distance per
/// full-resolution vertex in mm (the square root of the mean squared distance over the
/// measured poses, each measured in the fold that held it out; positions are taken to
/// be metres, as in the stages' notes).
#[derive(Debug, Clone)]
pub struct UpsamplingMaps {
    pub levels: Vec<LevelMap>,
}

/// One level step of [`UpsamplingMaps`].
#[derive(Debug, Clone)]
pub struct LevelMap {
    pub level: usize,
    pub coarse_vertices: usize,
    /// Per full-resolution vertex, mm.
    pub fitted_rms: Vec<f64>,
    pub barycentric_rms: Vec<f64>,
    /// Fitted over barycentric held-out MSE.
    pub ratio: f64,
}

impl UpsamplingMaps {
    pub fn new(summaries: &[&crate::stages::hierarchy::LevelSummary]) -> Self {
        let rms = |mse: &[f32]| mse.iter().map(|&m| 1e3 * f64::from(m).max(0.0).sqrt()).collect();
        let levels = summaries
            .iter()
            .map(|s| LevelMap {
                level: s.level,
                coarse_vertices: s.vertices,
                fitted_rms: rms(&s.heldout_fitted.vertex_mse),
                barycentric_rms: rms(&s.heldout_barycentric.vertex_mse),
                ratio: s.heldout_mse_ratio,
            })
            .collect();
        Self { levels }
    }

    /// One colour range for every panel: zero to the 99th percentile of the
    /// barycentric errors (the larger), so that the two upsamplers compare by colour.
    fn range(&self) -> (f64, f64) {
        let mut all: Vec<f64> = self
            .levels
            .iter()
            .flat_map(|l| l.barycentric_rms.iter().copied())
            .filter(|v| v.is_finite())
            .collect();
        all.sort_by(f64::total_cmp);
        let top = all.get((all.len() * 99 / 100).min(all.len().saturating_sub(1))).copied().unwrap_or(1.0);
        (0.0, if top > 0.0 { top } else { 1.0 })
    }

    /// Per level, the PLY properties `fitted_rms_mm` and `barycentric_rms_mm`.
    pub fn columns(&self, level: usize) -> Vec<(String, Vec<f32>)> {
        let l = &self.levels[level];
        let f32s = |v: &[f64]| v.iter().map(|&x| x as f32).collect();
        vec![
            ("fitted_rms_mm".into(), f32s(&l.fitted_rms)),
            ("barycentric_rms_mm".into(), f32s(&l.barycentric_rms)),
        ]
    }
}

/// `upsampling-error.png`: one row per level step, the fitted U's held-out per-vertex
/// RMS upsampling error beside the barycentric U's, on the template, in one colour range.
pub fn upsampling_error_png(
    template: &TriMesh,
    maps: &UpsamplingMaps,
    up: Option<Direction>,
) -> Result<Vec<u8>> {
    let range = maps.range();
    let mut rows = Vec::new();
    for LevelMap {
        level,
        coarse_vertices: vertices,
        fitted_rms: fitted,
        barycentric_rms: barycentric,
        ratio,
    } in &maps.levels
    {
        let panel = |values: &[f64], title: String, colour_bar: bool| -> Result<desal_viz::RgbaImage> {
            let config = RenderConfig {
                up,
                title,
                units: "mm RMS".into(),
                range: Some(range),
                colour_bar,
                ..RenderConfig::default()
            };
            Ok(desal_viz::render_heatmap(template, Scalar::PerVertex(values), &config)?)
        };
        rows.push(desal_viz::RgbaImage::hstack(
            &[
                panel(fitted, format!("level {level} ({vertices} v): fitted U, {ratio:.3}x MSE"), false)?,
                panel(barycentric, "barycentric U (COMA)".into(), true)?,
            ],
            [255, 255, 255, 255],
        ));
    }
    Ok(desal_viz::encode_png(&desal_viz::RgbaImage::vstack(&rows, [255, 255, 255, 255]))?)
}

/// Writes `mesh` as binary PLY with the float properties `columns` (no colours).
pub fn write_scalars_ply(path: &Path, mesh: &TriMesh, columns: Vec<(String, Vec<f32>)>) -> Result<()> {
    let options = PlyWriteOptions {
        scalars: columns,
        comments: vec!["desal: held-out per-vertex upsampling error".into()],
        ..PlyWriteOptions::default()
    };
    write_ply(path, mesh, &options)?;
    Ok(())
}
