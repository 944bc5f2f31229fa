//! Line plots: a few named series of `(x, y)` points on a linear x axis and a linear or
//! logarithmic y axis, with grid, tick values, axis labels, a title and a legend — the
//! error-vs-vertex-count plot of `desal eval --sweep`.
//!
//! The story of [`render_line_plot`]:
//! 1. find the data range ([`plot_frame`]): finite points only, and positive y on a log
//!    axis; choose "nice" ticks (steps of 1, 2 or 5 × 10ᵏ; on a log axis the values
//!    1, 2, 5 × 10ᵏ inside the range) and widen the range to the outer linear ticks;
//! 2. draw the grid, the axes' frame, the tick values, the axis labels and the title;
//! 3. draw each series as a polyline two pixels thick with square markers, colours from
//!    a fixed categorical palette in series order; a non-finite point breaks the line;
//! 4. draw the legend in the top-right corner of the plot area.
//!
//! Layout (pixels): a title band of [`crate::render::TITLE_HEIGHT`] on top, the y label
//! on the line below it, the plot area, then the x tick values and the x label below.

use crate::error::VizError;
use crate::font::{GLYPH_HEIGHT, draw_text, format_ticks, text_width};
use crate::image::RgbaImage;
use crate::render::TITLE_HEIGHT;

/// Series colours, in series order (Tableau 10, chosen for telling lines apart; the
/// ninth series reuses the first colour).
pub const PALETTE: [[u8; 3]; 8] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
];

const TEXT_SCALE: i64 = 2;
const TEXT_COLOUR: [u8; 4] = [20, 20, 20, 255];
const GRID_COLOUR: [u8; 4] = [225, 225, 225, 255];
/// Pixels between the plot area and the text around it.
const PAD: i64 = 8;
/// Side of a point marker, pixels.
const MARKER: i64 = 7;
/// Approximate number of ticks per axis.
const TICKS: usize = 6;

/// One line of the plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// Points in drawing order; non-finite coordinates (and, on a log axis, y ≤ 0) are
    /// skipped and break the line.
    pub points: Vec<(f64, f64)>,
}

/// How to draw a line plot.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotConfig {
    /// Image width in pixels. Default 640.
    pub width: u32,
    /// Image height in pixels. Default 420.
    pub height: u32,
    /// Title at the top left. Default empty.
    pub title: String,
    /// Label under the x axis. Default empty.
    pub x_label: String,
    /// Label above the y axis (the font draws no vertical text). Default empty.
    pub y_label: String,
    /// Logarithmic y axis (base 10). Default `false`.
    pub log_y: bool,
    /// Background colour (RGBA). Default opaque white.
    pub background: [u8; 4],
}

impl Default for PlotConfig {
    fn default() -> Self {
        Self {
            width: 640,
            height: 420,
            title: String::new(),
            x_label: String::new(),
            y_label: String::new(),
            log_y: false,
            background: [255, 255, 255, 255],
        }
    }
}

/// Where data coordinates land in the image.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotFrame {
    /// Data range of the x axis after widening to the ticks.
    pub x_range: (f64, f64),
    /// Data range of the y axis (data values, also on a log axis).
    pub y_range: (f64, f64),
    pub log_y: bool,
    pub x_ticks: Vec<f64>,
    pub y_ticks: Vec<f64>,
    /// The plot area `[x0, x1] × [y0, y1]` in pixels (y0 at the top).
    pub area: (i64, i64, i64, i64),
}

impl PlotFrame {
    /// Pixel coordinates (column, row) of data point `(x, y)`; `None` when the point
    /// cannot be drawn (non-finite, or y ≤ 0 on a log axis).
    pub fn pixel(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let y = if self.log_y { (y > 0.0).then(|| y.log10())? } else { y };
        if !(x.is_finite() && y.is_finite()) {
            return None;
        }
        let (ylo, yhi) = self.axis_y_range();
        let (x0, y0, x1, y1) = self.area;
        let tx = (x - self.x_range.0) / (self.x_range.1 - self.x_range.0);
        let ty = (y - ylo) / (yhi - ylo);
        Some((x0 as f64 + tx * (x1 - x0) as f64, y1 as f64 - ty * (y1 - y0) as f64))
    }

    /// The y range in axis space (log10 of the values on a log axis).
    fn axis_y_range(&self) -> (f64, f64) {
        if self.log_y { (self.y_range.0.log10(), self.y_range.1.log10()) } else { self.y_range }
    }
}

/// The frame [`render_line_plot`] draws in: data ranges, ticks and the plot area.
///
/// Errors: [`VizError::EmptyPlot`] when no series has a drawable point,
/// [`VizError::BadSize`] for an image too small to hold the axes (or over 8192 px).
pub fn plot_frame(series: &[Series], config: &PlotConfig) -> Result<PlotFrame, VizError> {
    if !(200..=8192).contains(&config.width) || !(150..=8192).contains(&config.height) {
        return Err(VizError::BadSize { width: config.width, height: config.height });
    }
    let drawable: Vec<(f64, f64)> = series
        .iter()
        .flat_map(|s| s.points.iter().copied())
        .filter(|&(x, y)| x.is_finite() && y.is_finite() && (!config.log_y || y > 0.0))
        .collect();
    if drawable.is_empty() {
        return Err(VizError::EmptyPlot { series: series.len() });
    }
    let span = |values: &mut dyn Iterator<Item = f64>| {
        values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
    };
    let (xlo, xhi) = span(&mut drawable.iter().map(|p| p.0));
    let (ylo, yhi) = span(&mut drawable.iter().map(|p| p.1));
    let (x_range, x_ticks) = linear_ticks(xlo, xhi);
    let (y_range, y_ticks) = if config.log_y { log_ticks(ylo, yhi) } else { linear_ticks(ylo, yhi) };

    let label_width = format_ticks(&y_ticks).iter().map(|l| text_width(l, TEXT_SCALE)).max().unwrap_or(0);
    let line = GLYPH_HEIGHT * TEXT_SCALE;
    let x0 = PAD + label_width + PAD;
    let y0 = TITLE_HEIGHT as i64 + line + 2 * PAD;
    let x1 = config.width as i64 - 3 * PAD;
    let y1 = config.height as i64 - 2 * line - 3 * PAD;
    if x1 - x0 < 40 || y1 - y0 < 40 {
        return Err(VizError::BadSize { width: config.width, height: config.height });
    }
    Ok(PlotFrame { x_range, y_range, log_y: config.log_y, x_ticks, y_ticks, area: (x0, y0, x1, y1) })
}

/// Renders `series` as a line plot, as described in the module docs. The image is
/// `config.width × config.height` pixels.
pub fn render_line_plot(series: &[Series], config: &PlotConfig) -> Result<RgbaImage, VizError> {
    let frame = plot_frame(series, config)?;
    let mut image = RgbaImage::filled(config.width, config.height, config.background);
    draw_axes(&mut image, &frame, config);
    for (k, s) in series.iter().enumerate() {
        draw_series(&mut image, &frame, s, colour_of(k));
    }
    draw_legend(&mut image, &frame, series);
    Ok(image)
}

/// The colour of series `k`.
pub fn colour_of(k: usize) -> [u8; 4] {
    let [r, g, b] = PALETTE[k % PALETTE.len()];
    [r, g, b, 255]
}

/// A tick step of 1, 2 or 5 × 10ᵏ giving about [`TICKS`] intervals over `span`.
fn nice_step(span: f64) -> f64 {
    let raw = span / TICKS as f64;
    let magnitude = 10f64.powf(raw.log10().floor());
    let normalised = raw / magnitude;
    let nice = if normalised <= 1.0 {
        1.0
    } else if normalised <= 2.0 {
        2.0
    } else if normalised <= 5.0 {
        5.0
    } else {
        10.0
    };
    nice * magnitude
}

/// Nice linear ticks covering `[lo, hi]`, and the range widened to the outer ticks. A
/// single value gets a range of ±10 % around it (±1 around zero).
fn linear_ticks(lo: f64, hi: f64) -> ((f64, f64), Vec<f64>) {
    let (lo, hi) = if hi > lo {
        (lo, hi)
    } else {
        let pad = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        (lo - pad, hi + pad)
    };
    let step = nice_step(hi - lo);
    let first = (lo / step).floor() as i64;
    let last = (hi / step).ceil() as i64;
    // Multiplying the integer index (not accumulating steps) keeps tick values exact.
    let ticks: Vec<f64> = (first..=last).map(|k| k as f64 * step).collect();
    ((ticks[0], ticks[ticks.len() - 1]), ticks)
}

/// Ticks for a log axis over positive `[lo, hi]`: the range is widened by 10 % each way
/// in log space; ticks are the values 1, 2, 5 × 10ᵏ inside it (decades only when those
/// are too many), or nice linear values inside it when fewer than two such values fall
/// in the range.
fn log_ticks(lo: f64, hi: f64) -> ((f64, f64), Vec<f64>) {
    let (llo, lhi) = (lo.log10(), hi.log10());
    let pad = if lhi > llo { 0.1 * (lhi - llo) } else { 0.1 };
    let range = (10f64.powf(llo - pad), 10f64.powf(lhi + pad));
    let inside = |v: &f64| *v >= range.0 && *v <= range.1;
    let decades = (range.0.log10().floor() as i32)..=(range.1.log10().ceil() as i32);
    let mut ticks: Vec<f64> =
        decades.clone().flat_map(|e| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(e))).filter(inside).collect();
    if ticks.len() > 2 * TICKS {
        ticks = decades.map(|e| 10f64.powi(e)).filter(inside).collect();
    }
    if ticks.len() < 2 {
        ticks = linear_ticks(range.0, range.1).1.into_iter().filter(inside).collect();
    }
    (range, ticks)
}

fn draw_axes(image: &mut RgbaImage, frame: &PlotFrame, config: &PlotConfig) {
    let (x0, y0, x1, y1) = frame.area;
    let half_line = GLYPH_HEIGHT * TEXT_SCALE / 2;
    for (&t, label) in frame.x_ticks.iter().zip(format_ticks(&frame.x_ticks)) {
        let Some((px, _)) = frame.pixel(t, frame.y_range.0) else { continue };
        let px = px.round() as i64;
        image.fill_rect(px, y0, px + 1, y1, GRID_COLOUR);
        image.fill_rect(px, y1, px + 1, y1 + 5, TEXT_COLOUR);
        draw_text(image, px - text_width(&label, TEXT_SCALE) / 2, y1 + PAD, &label, TEXT_SCALE, TEXT_COLOUR);
    }
    for (&t, label) in frame.y_ticks.iter().zip(format_ticks(&frame.y_ticks)) {
        let Some((_, py)) = frame.pixel(frame.x_range.0, t) else { continue };
        let py = py.round() as i64;
        image.fill_rect(x0, py, x1, py + 1, GRID_COLOUR);
        image.fill_rect(x0 - 5, py, x0, py + 1, TEXT_COLOUR);
        let x = x0 - PAD - text_width(&label, TEXT_SCALE);
        draw_text(image, x, py - half_line, &label, TEXT_SCALE, TEXT_COLOUR);
    }
    // The frame last, over the grid.
    image.fill_rect(x0, y0, x1 + 1, y0 + 1, TEXT_COLOUR);
    image.fill_rect(x0, y1, x1 + 1, y1 + 1, TEXT_COLOUR);
    image.fill_rect(x0, y0, x0 + 1, y1 + 1, TEXT_COLOUR);
    image.fill_rect(x1, y0, x1 + 1, y1 + 1, TEXT_COLOUR);

    draw_text(image, 6, 6, &config.title, TEXT_SCALE, TEXT_COLOUR);
    draw_text(image, PAD, TITLE_HEIGHT as i64 + PAD / 2, &config.y_label, TEXT_SCALE, TEXT_COLOUR);
    let x_label_x = (x0 + x1) / 2 - text_width(&config.x_label, TEXT_SCALE) / 2;
    let x_label_y = y1 + 2 * PAD + 2 * half_line;
    draw_text(image, x_label_x, x_label_y, &config.x_label, TEXT_SCALE, TEXT_COLOUR);
}

fn draw_series(image: &mut RgbaImage, frame: &PlotFrame, series: &Series, colour: [u8; 4]) {
    let mut previous: Option<(f64, f64)> = None;
    for &(x, y) in &series.points {
        let current = frame.pixel(x, y);
        if let (Some(a), Some(b)) = (previous, current) {
            draw_thick_segment(image, a, b, colour);
        }
        if let Some((px, py)) = current {
            let (px, py) = (px.round() as i64, py.round() as i64);
            image.fill_rect(
                px - MARKER / 2,
                py - MARKER / 2,
                px + MARKER / 2 + 1,
                py + MARKER / 2 + 1,
                colour,
            );
        }
        previous = current;
    }
}

/// A segment two pixels thick, drawn by stepping half a pixel at a time.
fn draw_thick_segment(image: &mut RgbaImage, a: (f64, f64), b: (f64, f64), colour: [u8; 4]) {
    let length = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
    let steps = (2.0 * length).ceil().max(1.0) as usize;
    for k in 0..=steps {
        let t = k as f64 / steps as f64;
        let x = (a.0 + t * (b.0 - a.0)).round() as i64;
        let y = (a.1 + t * (b.1 - a.1)).round() as i64;
        image.fill_rect(x - 1, y - 1, x + 1, y + 1, colour);
    }
}

/// One row per series — a short line sample and the name — in a framed white box at
/// the top right of the plot area.
fn draw_legend(image: &mut RgbaImage, frame: &PlotFrame, series: &[Series]) {
    if series.is_empty() {
        return;
    }
    let line = GLYPH_HEIGHT * TEXT_SCALE;
    let sample = 24;
    let name_width = series.iter().map(|s| text_width(&s.name, TEXT_SCALE)).max().unwrap_or(0);
    let (width, height) = (PAD + sample + PAD + name_width + PAD, PAD + series.len() as i64 * (line + PAD));
    let (_, y0, x1, _) = frame.area;
    let (left, top) = (x1 - PAD - width, y0 + PAD);
    image.fill_rect(left, top, left + width, top + height, [255, 255, 255, 255]);
    image.fill_rect(left, top, left + width, top + 1, TEXT_COLOUR);
    image.fill_rect(left, top + height - 1, left + width, top + height, TEXT_COLOUR);
    image.fill_rect(left, top, left + 1, top + height, TEXT_COLOUR);
    image.fill_rect(left + width - 1, top, left + width, top + height, TEXT_COLOUR);
    for (k, s) in series.iter().enumerate() {
        let row = top + PAD + k as i64 * (line + PAD);
        let mid = row + line / 2;
        image.fill_rect(left + PAD, mid - 1, left + PAD + sample, mid + 1, colour_of(k));
        draw_text(image, left + 2 * PAD + sample, row, &s.name, TEXT_SCALE, TEXT_COLOUR);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(points: &[(f64, f64)]) -> Series {
        Series { name: "a".into(), points: points.to_vec() }
    }

    /// The vertex counts of a sweep get round ticks, and the range is widened to them.
    #[test]
    fn ticks_are_round_and_cover_the_data() {
        let frame = plot_frame(&[line(&[(1000.0, 1.0), (6000.0, 3.0)])], &PlotConfig::default()).unwrap();
        assert_eq!(frame.x_ticks, vec![1000.0, 2000.0, 3000.0, 4000.0, 5000.0, 6000.0]);
        assert_eq!(frame.x_range, (1000.0, 6000.0));
        assert_eq!(frame.y_ticks.first(), Some(&1.0));
        assert_eq!(frame.y_ticks.last(), Some(&3.0));
    }

    /// The middle of a straight series is drawn in the first palette colour, and a
    /// corner of the image stays background.
    #[test]
    fn a_segment_is_drawn_through_its_midpoint() {
        let config = PlotConfig::default();
        let series = [line(&[(0.0, 0.0), (10.0, 10.0)])];
        let frame = plot_frame(&series, &config).unwrap();
        let image = render_line_plot(&series, &config).unwrap();
        let (px, py) = frame.pixel(5.0, 5.0).unwrap();
        assert_eq!(image.get(px.round() as u32, py.round() as u32), colour_of(0));
        assert_eq!(image.get(config.width - 1, config.height - 1), config.background);
    }

    /// On a log axis a decade is the same height wherever it is, and 1e-5 is above 1e-6.
    #[test]
    fn log_axis_spaces_decades_evenly() {
        let config = PlotConfig { log_y: true, ..PlotConfig::default() };
        let frame = plot_frame(&[line(&[(0.0, 1e-6), (1.0, 1e-4)])], &config).unwrap();
        let row = |y| frame.pixel(0.0, y).unwrap().1;
        assert!(row(1e-5) < row(1e-6));
        assert!((row(1e-6) - row(1e-5) - (row(1e-5) - row(1e-4))).abs() < 1e-9);
        assert!(frame.y_ticks.contains(&1e-5), "{:?}", frame.y_ticks);
        assert_eq!(frame.pixel(0.0, 0.0), None, "zero has no place on a log axis");
    }

    /// Points that cannot be drawn are skipped; with none left the plot is refused.
    #[test]
    fn a_plot_without_drawable_points_is_an_error() {
        let config = PlotConfig { log_y: true, ..PlotConfig::default() };
        let series = [line(&[(f64::NAN, 1.0), (1.0, 0.0), (2.0, -3.0)])];
        assert_eq!(plot_frame(&series, &config), Err(VizError::EmptyPlot { series: 1 }));
        let tiny = PlotConfig { width: 10, ..PlotConfig::default() };
        assert!(matches!(plot_frame(&[line(&[(0.0, 1.0)])], &tiny), Err(VizError::BadSize { .. })));
    }

    /// One point alone still gets a range (±10 %) and a marker at its pixel.
    #[test]
    fn a_single_point_is_centred_with_a_marker() {
        let config = PlotConfig::default();
        let series = [line(&[(3.0, 2.0)])];
        let frame = plot_frame(&series, &config).unwrap();
        assert!(frame.x_range.0 < 3.0 && frame.x_range.1 > 3.0);
        let (px, py) = frame.pixel(3.0, 2.0).unwrap();
        let image = render_line_plot(&series, &config).unwrap();
        assert_eq!(image.get(px.round() as u32 + 2, py.round() as u32 + 2), colour_of(0));
    }
}
