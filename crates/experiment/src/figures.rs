//! The pictures of `desal eval`, as PNG bytes through `desal-viz`:
//!
//! - face-area heat maps of each method's simplified template (paper Figs. 4–5), one
//!   colour range for all methods so that they compare;
//! - per-vertex error heat maps of the held-out deformed meshes (one per figure pose,
//!   and the RMS over all poses), one range for all methods;
//! - the deformation grid (paper Fig. 7): the full-resolution ground truth and a few
//!   methods' held-out deformations of the figure poses, side by side;
//! - the sweep plot: error against vertex count.
//!
//! Every view of one dataset uses the template's up and front directions, so posed
//! meshes are seen from the same side as the template.

use anyhow::Result;
use desal_mesh::TriMesh;
use desal_viz::render::{BAR_PANEL_WIDTH, TITLE_HEIGHT};
use desal_viz::{Direction, PlotConfig, RenderConfig, RgbaImage, Scalar, Series};

const WHITE: [u8; 4] = [255, 255, 255, 255];

/// The view directions of a dataset's pictures.
#[derive(Debug, Clone, Copy)]
pub struct Views {
    up: Direction,
    front: Direction,
}

impl Views {
    /// The directions `desal-viz` chooses for `template` (with `up` when the pipeline
    /// names it).
    pub fn of(template: &TriMesh, up: Option<Direction>) -> Result<Self> {
        let frame = desal_viz::resolve_frame(template, &RenderConfig { up, ..RenderConfig::default() })?;
        Ok(Self { up: frame.up, front: frame.front })
    }

    fn config(&self, title: &str, units: &str, range: (f64, f64)) -> RenderConfig {
        RenderConfig {
            up: Some(self.up),
            front: Some(self.front),
            title: title.into(),
            units: units.into(),
            range: Some(range),
            ..RenderConfig::default()
        }
    }
}

/// Face areas of a simplified template, in cm² (input in metres), front and back.
pub fn face_area_png(views: &Views, mesh: &TriMesh, title: &str, range_cm2: (f64, f64)) -> Result<Vec<u8>> {
    let areas = face_areas_cm2(mesh);
    let image =
        desal_viz::render_heatmap(mesh, Scalar::PerFace(&areas), &views.config(title, "cm^2", range_cm2))?;
    Ok(desal_viz::encode_png(&image)?)
}

/// Face areas in cm², assuming metre input.
pub fn face_areas_cm2(mesh: &TriMesh) -> Vec<f64> {
    (0..mesh.face_count()).map(|f| mesh.face_area(f) * 1e4).collect()
}

/// A per-vertex error map (values in mm) on a deformed mesh, front and back.
pub fn error_png(
    views: &Views,
    mesh: &TriMesh,
    values_mm: &[f64],
    title: &str,
    range_mm: (f64, f64),
) -> Result<Vec<u8>> {
    let config = views.config(title, "mm", range_mm);
    let image = desal_viz::render_heatmap(mesh, Scalar::PerVertex(values_mm), &config)?;
    Ok(desal_viz::encode_png(&image)?)
}

/// One row of the deformation grid: a label and, per figure pose, a mesh with optional
/// per-vertex errors in mm (`None`: drawn grey, as the ground truth is).
#[derive(Debug)]
pub struct GridRow {
    pub label: String,
    pub cells: Vec<(TriMesh, Option<Vec<f64>>)>,
}

/// Size of one grid cell's view, pixels.
const CELL_WIDTH: u32 = 240;
const CELL_HEIGHT: u32 = 420;

/// The deformation grid (paper Fig. 7): one row per [`GridRow`], one column per pose,
/// each cell the front view titled with the row label (the first row's cells with
/// `column_titles` instead), and the error colour bar on the right.
pub fn deformation_grid_png(
    views: &Views,
    rows: &[GridRow],
    column_titles: &[String],
    range_mm: (f64, f64),
) -> Result<Vec<u8>> {
    let mut row_images = Vec::new();
    for (r, row) in rows.iter().enumerate() {
        let mut cells = Vec::new();
        for (c, (mesh, errors)) in row.cells.iter().enumerate() {
            let title =
                if r == 0 { column_titles.get(c).cloned().unwrap_or_default() } else { row.label.clone() };
            let config = RenderConfig {
                view_width: CELL_WIDTH,
                view_height: CELL_HEIGHT,
                colour_bar: false,
                ..views.config(&title, "", range_mm)
            };
            // Without errors every value is NaN, which the renderer paints grey.
            let grey = vec![f64::NAN; mesh.vertex_count()];
            let values = errors.as_deref().unwrap_or(&grey);
            let image = desal_viz::render_heatmap(mesh, Scalar::PerVertex(values), &config)?;
            cells.push(image.crop(0, 0, CELL_WIDTH, TITLE_HEIGHT + CELL_HEIGHT));
        }
        row_images.push(RgbaImage::hstack(&cells, WHITE));
    }
    let grid = RgbaImage::vstack(&row_images, WHITE);
    let bar = colour_bar(views, rows, range_mm)?;
    Ok(desal_viz::encode_png(&RgbaImage::hstack(&[grid, bar], WHITE))?)
}

/// The renderer's colour-bar panel for `range_mm`, cut from a throwaway rendering of
/// the first mesh of the grid.
fn colour_bar(views: &Views, rows: &[GridRow], range_mm: (f64, f64)) -> Result<RgbaImage> {
    let Some((mesh, _)) = rows.iter().flat_map(|r| r.cells.iter()).next() else {
        return Ok(RgbaImage::filled(0, 0, WHITE));
    };
    // Views wide enough that their captions stay clear of the panel.
    let config =
        RenderConfig { view_width: 120, view_height: CELL_HEIGHT, ..views.config("", "mm", range_mm) };
    let values = vec![f64::NAN; mesh.vertex_count()];
    let image = desal_viz::render_heatmap(mesh, Scalar::PerVertex(&values), &config)?;
    Ok(image.crop(2 * config.view_width, 0, BAR_PANEL_WIDTH, image.height))
}

/// One panel of the sweep plot: a figure against the vertex count, one series per
/// method.
#[derive(Debug)]
pub struct SweepPanel {
    pub title: String,
    pub y_label: String,
    pub series: Vec<Series>,
}

/// The sweep panels in a grid two wide, log y axes.
pub fn sweep_png(panels: &[SweepPanel]) -> Result<Vec<u8>> {
    let mut images = Vec::new();
    for panel in panels {
        let config = PlotConfig {
            width: 600,
            height: 400,
            title: panel.title.clone(),
            x_label: "vertices".into(),
            y_label: panel.y_label.clone(),
            log_y: true,
            ..PlotConfig::default()
        };
        images.push(desal_viz::render_line_plot(&panel.series, &config)?);
    }
    let rows: Vec<RgbaImage> = images.chunks(2).map(|pair| RgbaImage::hstack(pair, WHITE)).collect();
    Ok(desal_viz::encode_png(&RgbaImage::vstack(&rows, WHITE))?)
}

/// A colour range shared by several value sets: 0 to the given percentile of all
/// finite values (so a few outliers do not wash out the map); `(0, 1)` when empty.
pub fn shared_range<'a>(sets: impl Iterator<Item = &'a [f64]>, percentile: f64) -> (f64, f64) {
    let mut all: Vec<f64> = sets.flat_map(|s| s.iter().copied()).filter(|v| v.is_finite()).collect();
    if all.is_empty() {
        return (0.0, 1.0);
    }
    all.sort_by(f64::total_cmp);
    let k = ((percentile / 100.0) * (all.len() - 1) as f64).round() as usize;
    let hi = all[k.min(all.len() - 1)];
    (0.0, if hi > 0.0 { hi } else { 1.0 })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_range_cuts_outliers_at_the_percentile() {
        let a: Vec<f64> = (0..=99).map(f64::from).collect();
        let b = [1e6, f64::NAN];
        let (lo, hi) = shared_range([a.as_slice(), b.as_slice()].into_iter(), 99.0);
        assert_eq!(lo, 0.0);
        assert_eq!(hi, 99.0, "the 100th of 101 finite values; the outlier is cut");
        assert_eq!(shared_range(std::iter::empty(), 99.0), (0.0, 1.0));
    }
}
