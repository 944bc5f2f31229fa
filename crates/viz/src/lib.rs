//! Software rendering of a mesh with a per-vertex or per-face scalar to an RGBA image:
//! heat maps for saliency (the paper's Fig. 1), face areas (Figs. 4–5) and errors; and
//! line plots of a few series.
//!
//! - [`render`]: [`render_heatmap`], an orthographic z-buffer rasteriser with Lambert
//!   shading, front and back views side by side and a colour bar.
//! - [`colormap()`]: the viridis colour map, also used for PLY vertex colours.
//! - [`image`]: [`RgbaImage`] and [`encode_png`] (bytes, not files).
//! - [`font`]: a built-in 5×7 bitmap font for labels.
//! - [`plot`]: [`render_line_plot`], line plots with ticks and a legend (errors against
//!   vertex count).
//!
//! **Invariant:** no file system access and no GPU: the caller writes the bytes, and the
//! output is a pure function of the mesh, the scalar and the config.

pub mod colormap;
pub mod direction;
pub mod error;
pub mod font;
pub mod image;
pub mod plot;
pub mod render;

pub use colormap::{colormap, part_face_values};
pub use error::VizError;
pub use image::{RgbaImage, encode_png};
pub use plot::{PlotConfig, PlotFrame, Series, plot_frame, render_line_plot};
pub use render::{Direction, RenderConfig, Scalar, ViewFrame, render_heatmap, resolve_frame};
