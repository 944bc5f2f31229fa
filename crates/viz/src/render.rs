//! Heat-map rendering: a mesh with a per-vertex or per-face scalar, drawn from the front
//! and from the back side by side, with a colour bar, as an RGBA image.
//!
//! The story of [`render_heatmap`]:
//! 1. check the inputs and resolve the view frame (up and front directions; from the
//!    bounding box unless given: up is the longest extent, the camera looks along the
//!    shortest, which for a standing body is its depth);
//! 2. fit the body into each view with one scale for both views;
//! 3. rasterise each view with a z-buffer, orthographic projection, barycentric
//!    interpolation of the scalar and of vertex normals, and two-sided Lambert shading
//!    from a light near the camera;
//! 4. draw the title, the view captions and the colour bar with its tick values.
//!
//! Image layout (pixels): a title band of [`TITLE_HEIGHT`] on top; below it the two
//! views, `view_width × view_height` each, left = seen from `+front`, right = seen
//! from `−front`; then, when enabled, the colour-bar panel of [`BAR_PANEL_WIDTH`].

use desal_mesh::TriMesh;
use desal_mesh::math::{Real, Vec3, bounding_box};
use glam::Vec3 as ScreenPoint;

use crate::colormap::colormap;
pub use crate::direction::Direction;
use crate::error::VizError;
use crate::font::{GLYPH_HEIGHT, draw_text, format_tick, text_width};
use crate::image::RgbaImage;

/// Height of the title band above the views, in pixels.
pub const TITLE_HEIGHT: u32 = 28;
/// Width of the colour-bar panel right of the views, in pixels.
pub const BAR_PANEL_WIDTH: u32 = 120;
/// Fraction of each view left empty around the body, on every side.
const VIEW_MARGIN: Real = 0.05;
/// Text is drawn with each font pixel a 2 × 2 block.
const TEXT_SCALE: i64 = 2;
const TEXT_COLOUR: [u8; 4] = [20, 20, 20, 255];

/// A scalar field on the mesh, mapped to colour.
#[derive(Debug, Clone, Copy)]
pub enum Scalar<'a> {
    /// One value per vertex, interpolated across faces.
    PerVertex(&'a [f64]),
    /// One value per face, constant across it.
    PerFace(&'a [f64]),
}

/// How to draw a heat map. Defaults suit a standing body.
#[derive(Debug, Clone, PartialEq)]
pub struct RenderConfig {
    /// Width of each of the two views, in pixels. Default 320.
    pub view_width: u32,
    /// Height of the views, in pixels. Default 600.
    pub view_height: u32,
    /// The body's up direction (SCAPE: `PosX`, the bundled sample: `PosY`). Default
    /// `None`: the axis of the longest bounding-box extent, positive.
    pub up: Option<Direction>,
    /// The direction from the body towards the left view's camera; the right view looks
    /// from the opposite side. Default `None`: the remaining axis of the shortest
    /// bounding-box extent (a body's depth), positive. Which of the two views shows the
    /// face depends on the data; the captions name the side each is seen from.
    pub front: Option<Direction>,
    /// Scalar values mapped to the ends of the colour map; values outside are clamped.
    /// Default `None`: the minimum and maximum of the finite values.
    pub range: Option<(f64, f64)>,
    /// Title drawn at the top left, e.g. `"saliency"`. Default empty.
    pub title: String,
    /// Units drawn above the colour bar, e.g. `"m"` or `"0-1"`. Default empty.
    pub units: String,
    /// Whether to draw the colour-bar panel. Default `true`.
    pub colour_bar: bool,
    /// Background colour (RGBA). Default opaque white.
    pub background: [u8; 4],
    /// Colour of faces whose scalar is NaN. Default mid grey.
    pub missing_colour: [u8; 3],
    /// Share of light that does not depend on the surface orientation, in `[0, 1]`.
    /// Default 0.35: enough to keep dark colours readable on surfaces seen edge-on.
    pub ambient: f32,
}

impl Default for RenderConfig {
    fn default() -> Self {
        Self {
            view_width: 320,
            view_height: 600,
            up: None,
            front: None,
            range: None,
            title: String::new(),
            units: String::new(),
            colour_bar: true,
            background: [255, 255, 255, 255],
            missing_colour: [128, 128, 128],
            ambient: 0.35,
        }
    }
}

/// The resolved orientation of the left view's camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewFrame {
    pub up: Direction,
    pub front: Direction,
}

/// Up and front directions for `mesh` under `config`: the configured ones, or those
/// detected from the bounding box (see [`RenderConfig::up`] and [`RenderConfig::front`]).
pub fn resolve_frame(mesh: &TriMesh, config: &RenderConfig) -> Result<ViewFrame, VizError> {
    let (lo, hi) = bounding_box(&mesh.positions)
        .ok_or(VizError::EmptyMesh { vertices: mesh.vertex_count(), faces: mesh.face_count() })?;
    let extent = hi - lo;
    // Ties go to the lower axis index, so the choice is deterministic for a cube.
    let longest = |skip: Option<usize>| {
        (0..3).filter(|&a| Some(a) != skip).fold(None, |best: Option<usize>, a| match best {
            Some(b) if extent[b] >= extent[a] => Some(b),
            _ => Some(a),
        })
    };
    let shortest = |skip: usize| {
        (0..3).filter(|&a| a != skip).fold(None, |best: Option<usize>, a| match best {
            Some(b) if extent[b] <= extent[a] => Some(b),
            _ => Some(a),
        })
    };
    let up = match config.up {
        Some(up) => up,
        None => Direction::positive(longest(config.front.map(Direction::axis)).unwrap_or(1)),
    };
    let front = config.front.unwrap_or_else(|| Direction::positive(shortest(up.axis()).unwrap_or(2)));
    if up.axis() == front.axis() {
        return Err(VizError::ParallelAxes { up, front });
    }
    Ok(ViewFrame { up, front })
}

/// Renders `mesh` coloured by `scalar` from the front and from the back, with a colour
/// bar, as described in the module docs. The image is
/// `(2 · view_width + BAR_PANEL_WIDTH) × (TITLE_HEIGHT + view_height)` pixels (without
/// the panel's width when the colour bar is off).
pub fn render_heatmap(mesh: &TriMesh, scalar: Scalar, config: &RenderConfig) -> Result<RgbaImage, VizError> {
    check_inputs(mesh, scalar, config)?;
    let frame = resolve_frame(mesh, config)?;
    let range = config.range.unwrap_or_else(|| finite_range(scalar));
    let panel = if config.colour_bar { BAR_PANEL_WIDTH } else { 0 };
    let mut image = RgbaImage::filled(
        2 * config.view_width + panel,
        TITLE_HEIGHT + config.view_height,
        config.background,
    );

    let normals = mesh.vertex_normals();
    let placement = place_views(mesh, frame, config);
    for (view, toward) in [frame.front, frame.front.opposite()].into_iter().enumerate() {
        let origin_x = view as u32 * config.view_width;
        let camera = Camera::new(frame.up.vector(), toward.vector(), &placement, origin_x, config);
        rasterise_view(&mut image, mesh, &normals, scalar, range, &camera, config);
        let caption = format!("from {}", toward.label());
        draw_text(
            &mut image,
            origin_x as i64 + 6,
            TITLE_HEIGHT as i64 + 4,
            &caption,
            TEXT_SCALE,
            TEXT_COLOUR,
        );
    }
    draw_text(&mut image, 6, 6, &config.title, TEXT_SCALE, TEXT_COLOUR);
    if config.colour_bar {
        draw_colour_bar(&mut image, 2 * config.view_width, range, config);
    }
    Ok(image)
}

fn check_inputs(mesh: &TriMesh, scalar: Scalar, config: &RenderConfig) -> Result<(), VizError> {
    if mesh.vertex_count() == 0 || mesh.face_count() == 0 {
        return Err(VizError::EmptyMesh { vertices: mesh.vertex_count(), faces: mesh.face_count() });
    }
    let (kind, expected, found) = match scalar {
        Scalar::PerVertex(values) => ("vertex", mesh.vertex_count(), values.len()),
        Scalar::PerFace(values) => ("face", mesh.face_count(), values.len()),
    };
    if expected != found {
        return Err(VizError::ScalarLength { kind, expected, found });
    }
    let sizes = 1..=8192;
    if !(sizes.contains(&config.view_width) && sizes.contains(&config.view_height)) {
        return Err(VizError::BadSize { width: config.view_width, height: config.view_height });
    }
    Ok(())
}

/// The smallest and largest finite value (`(0, 1)` when there is none).
fn finite_range(scalar: Scalar) -> (f64, f64) {
    let values = match scalar {
        Scalar::PerVertex(v) | Scalar::PerFace(v) => v,
    };
    let finite = values.iter().copied().filter(|v| v.is_finite());
    let lo = finite.clone().fold(f64::INFINITY, f64::min);
    let hi = finite.fold(f64::NEG_INFINITY, f64::max);
    if lo.is_finite() { (lo, hi) } else { (0.0, 1.0) }
}

/// Where the body goes in the views: shared by both so that they line up.
#[derive(Debug, Clone, Copy)]
struct Placement {
    /// Pixels per mesh unit.
    scale: Real,
    /// The body's bounding-box centre.
    centre: Vec3,
}

/// One scale for both views: the larger of the body's two screen extents fills its
/// view up to the margin.
fn place_views(mesh: &TriMesh, frame: ViewFrame, config: &RenderConfig) -> Placement {
    let (lo, hi) = bounding_box(&mesh.positions).expect("checked non-empty");
    let extent = hi - lo;
    let right_axis = 3 - frame.up.axis() - frame.front.axis();
    let usable = 1.0 - 2.0 * VIEW_MARGIN;
    let fit_width = config.view_width as Real * usable / extent[right_axis].max(Real::EPSILON);
    let fit_height = config.view_height as Real * usable / extent[frame.up.axis()].max(Real::EPSILON);
    Placement { scale: fit_width.min(fit_height), centre: (lo + hi) / 2.0 }
}

/// An orthographic camera looking along `−toward`, mapping mesh points to pixel
/// coordinates of one view (x right, y down) and a depth that grows towards the camera.
struct Camera {
    right: Vec3,
    up: Vec3,
    toward: Vec3,
    placement: Placement,
    /// Pixel coordinates of the view's centre.
    centre_px: (Real, Real),
    /// The view's pixel rectangle `[x0, x1) × [y0, y1)`.
    bounds: (i64, i64, i64, i64),
    /// Unit vector towards the light: over the camera's shoulder (up and to the left).
    light: Vec3,
}

impl Camera {
    fn new(up: Vec3, toward: Vec3, placement: &Placement, origin_x: u32, config: &RenderConfig) -> Self {
        let right = up.cross(&toward);
        let (w, h) = (config.view_width as Real, config.view_height as Real);
        let top = TITLE_HEIGHT as Real;
        let light = (toward + 0.5 * up - 0.3 * right).normalize();
        Self {
            right,
            up,
            toward,
            placement: *placement,
            centre_px: (origin_x as Real + w / 2.0, top + h / 2.0),
            bounds: (origin_x as i64, TITLE_HEIGHT as i64, (origin_x as Real + w) as i64, (top + h) as i64),
            light,
        }
    }

    /// Pixel x, pixel y and depth of mesh point `p`.
    fn project(&self, p: &Vec3) -> ScreenPoint {
        let d = p - self.placement.centre;
        let s = self.placement.scale;
        ScreenPoint::new(
            (self.centre_px.0 + d.dot(&self.right) * s) as f32,
            (self.centre_px.1 - d.dot(&self.up) * s) as f32,
            d.dot(&self.toward) as f32,
        )
    }
}

/// Draws one view: z-buffered triangles, scalar interpolated per pixel, shaded.
fn rasterise_view(
    image: &mut RgbaImage,
    mesh: &TriMesh,
    normals: &[Vec3],
    scalar: Scalar,
    range: (f64, f64),
    camera: &Camera,
    config: &RenderConfig,
) {
    let (x0, y0, x1, y1) = camera.bounds;
    let width = (x1 - x0) as usize;
    let mut depth = vec![f32::NEG_INFINITY; width * (y1 - y0) as usize];
    let projected: Vec<ScreenPoint> = mesh.positions.iter().map(|p| camera.project(p)).collect();
    let to_unit = |value: f64| if range.1 > range.0 { (value - range.0) / (range.1 - range.0) } else { 0.0 };

    for (f, face) in mesh.faces.iter().enumerate() {
        let [a, b, c] = face.map(|v| projected[v as usize]);
        let area = edge(a, b, c);
        if area.abs() < 1e-12 {
            continue; // Seen edge-on: covers no pixel centre.
        }
        let min_x = (a.x.min(b.x).min(c.x).floor() as i64).max(x0);
        let max_x = (a.x.max(b.x).max(c.x).ceil() as i64).min(x1 - 1);
        let min_y = (a.y.min(b.y).min(c.y).floor() as i64).max(y0);
        let max_y = (a.y.max(b.y).max(c.y).ceil() as i64).min(y1 - 1);
        for py in min_y..=max_y {
            for px in min_x..=max_x {
                let p = ScreenPoint::new(px as f32 + 0.5, py as f32 + 0.5, 0.0);
                // Barycentric weights; dividing by the signed area makes them positive
                // inside whatever the triangle's winding on screen.
                let w = [edge(b, c, p) / area, edge(c, a, p) / area, edge(a, b, p) / area];
                if w.iter().any(|&wi| wi < -1e-5) {
                    continue;
                }
                let z = w[0] * a.z + w[1] * b.z + w[2] * c.z;
                let slot = (py - y0) as usize * width + (px - x0) as usize;
                if z <= depth[slot] {
                    continue;
                }
                depth[slot] = z;
                let value = match scalar {
                    Scalar::PerVertex(values) => {
                        face.iter().zip(w).map(|(&v, wi)| values[v as usize] * wi as f64).sum()
                    }
                    Scalar::PerFace(values) => values[f],
                };
                let normal: Vec3 = face.iter().zip(w).map(|(&v, wi)| normals[v as usize] * wi as Real).sum();
                let lambert = normal.try_normalize(0.0).map_or(1.0, |n| n.dot(&camera.light).abs()) as f32;
                let light = config.ambient + (1.0 - config.ambient) * lambert;
                let base = if value.is_nan() { config.missing_colour } else { colormap(to_unit(value)) };
                let shaded = base.map(|ch| (ch as f32 * light).round().clamp(0.0, 255.0) as u8);
                image.put(px, py, [shaded[0], shaded[1], shaded[2], 255]);
            }
        }
    }
}

/// Twice the signed area of triangle `(a, b, c)` on screen (x and y only).
#[inline]
fn edge(a: ScreenPoint, b: ScreenPoint, c: ScreenPoint) -> f32 {
    (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)
}

/// The colour bar: units on top, a vertical gradient (maximum at the top) with a
/// frame, and five tick values to its right.
fn draw_colour_bar(image: &mut RgbaImage, panel_x: u32, range: (f64, f64), config: &RenderConfig) {
    let x = panel_x as i64 + 10;
    let (bar_width, text_height) = (22, GLYPH_HEIGHT * TEXT_SCALE);
    let top = TITLE_HEIGHT as i64 + 30;
    let bottom = (TITLE_HEIGHT + config.view_height) as i64 - 20;
    if bottom - top < 10 {
        return; // Too small a view for a readable bar.
    }
    let units_x = (panel_x as i64 + (BAR_PANEL_WIDTH as i64 - text_width(&config.units, TEXT_SCALE)) / 2)
        .max(panel_x as i64);
    draw_text(image, units_x, TITLE_HEIGHT as i64 + 6, &config.units, TEXT_SCALE, TEXT_COLOUR);
    for y in top..bottom {
        let t = (bottom - 1 - y) as f64 / (bottom - 1 - top) as f64;
        let [r, g, b] = colormap(t);
        image.fill_rect(x, y, x + bar_width, y + 1, [r, g, b, 255]);
    }
    let frame_colour = TEXT_COLOUR;
    image.fill_rect(x - 1, top - 1, x + bar_width + 1, top, frame_colour);
    image.fill_rect(x - 1, bottom, x + bar_width + 1, bottom + 1, frame_colour);
    image.fill_rect(x - 1, top - 1, x, bottom + 1, frame_colour);
    image.fill_rect(x + bar_width, top - 1, x + bar_width + 1, bottom + 1, frame_colour);
    for k in 0..=4 {
        let t = k as f64 / 4.0;
        let y = bottom - 1 - ((bottom - 1 - top) as f64 * t).round() as i64;
        image.fill_rect(x + bar_width + 1, y, x + bar_width + 5, y + 1, frame_colour);
        let value = range.0 + t * (range.1 - range.0);
        draw_text(
            image,
            x + bar_width + 8,
            y - text_height / 2,
            &format_tick(value),
            TEXT_SCALE,
            TEXT_COLOUR,
        );
    }
}
