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
