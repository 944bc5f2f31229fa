//! The knobs of part discovery, their defaults and their checks.

use desal_mesh::math::Real;

use crate::error::PartsError;

/// Parameters of [`crate::discover_parts`].
///
/// Defaults were measured on SCAPE (71 poses × 12500 vertices) and the bundled sample
/// (11 × 13380); see the crate's `tests/scape.rs` and `tests/sample.rs`.
#[derive(Debug, Clone, PartialEq)]
pub struct PartsConfig {
    /// The number of parts wanted. `None`: discover up to [`PartsConfig::max_parts`]
    /// parts and keep the count at the knee of the residual curve. Fewer parts are
    /// returned when the mesh has fewer than that many patches (a result, not an error).
    pub parts: Option<usize>,
    /// The largest part count tried when `parts` is `None`. Default 24.
    pub max_parts: usize,
    /// The smallest part, in vertices (at least 3). Smaller parts are dissolved into a
    /// neighbour. Default 20: a few rings of vertices, enough for a well-posed fit
    /// under noise, far below SCAPE's smallest hand-made part (338 vertices).
    pub min_part_vertices: usize,
    /// Patches the template is first cut into (geodesic Voronoi cells of farthest-point
    /// seeds), which are then merged bottom-up; the most parts discovery can return.
    /// Default 256: about 50 vertices each on SCAPE; 512 measured worse there (ARI 0.715
    /// against 0.768 with 30 sweeps) as well as slower.
    pub patches: usize,
    /// Upper bound on border-relaxation sweeps (refit every part, move border vertices
    /// to the neighbouring part that explains them best) at the chosen count. Each sweep
    /// moves a border by at most one ring. Default 10: on SCAPE (K = 16) 3 sweeps give
    /// ARI 0.725 and 13.44 mm, 10 give 0.767 and 13.34 mm, 30 give 0.768 and 13.35 mm
    /// (`examples/parts_png.rs`).
    pub relax_sweeps: usize,
    /// Motion below this, as a mean distance per vertex and pose relative to the
    /// template's bounding-box diagonal, counts as none: without `parts`, the first
    /// count whose mean residual is within it is returned, and a pose set whose
    /// single part is explained within it is motionless. Default `1e-6` (far below any real motion,
    /// above `f32` rounding of the input).
    pub rigid_tolerance: Real,
}

impl Default for PartsConfig {
    fn default() -> Self {
        Self {
            parts: None,
            max_parts: 24,
            min_part_vertices: 20,
            patches: 256,
            relax_sweeps: 10,
            rigid_tolerance: 1e-6,
        }
    }
}

impl PartsConfig {
    /// Checks every option against its documented range.
    pub fn validate(&self) -> Result<(), PartsError> {
        let bad = |option, value: f64, expected| Err(PartsError::BadOption { option, value, expected });
        if let Some(k) = self.parts
            && k == 0
        {
            return bad("parts", k as f64, "at least 1");
        }
        if self.max_parts == 0 {
            return bad("max_parts", 0.0, "at least 1");
        }
        if self.min_part_vertices < 3 {
            return bad(
                "min_part_vertices",
                self.min_part_vertices as f64,
                "at least 3 (a rigid fit needs 3 vertices)",
            );
        }
        if self.patches == 0 {
            return bad("patches", 0.0, "at least 1");
        }
        if !(self.rigid_tolerance.is_finite() && self.rigid_tolerance >= 0.0) {
            return bad("rigid_tolerance", self.rigid_tolerance, "a finite number >= 0");
        }
        Ok(())
    }
}
