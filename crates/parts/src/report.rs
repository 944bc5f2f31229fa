//! What discovery reports: the residual-against-part-count curve, the chosen count,
//! the part sizes. Plain data, for the driver's JSON sidecar.

use desal_mesh::math::Real;

/// One point of the residual curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvePoint {
    /// Number of parts.
    pub parts: usize,
    /// Stage 1's mean rigid-fit residual with these parts: the mean over every vertex
    /// and every non-template pose of `‖R v_T + t − v_X‖`, in mesh units (metres for
    /// SCAPE and the sample). Stage 1 reports the same figure as
    /// `FitSummary::mean_residual`.
    pub mean_residual: Real,
}

/// The report of one discovery run.
#[derive(Debug, Clone, PartialEq)]
pub struct PartsReport {
    /// The requested part count (`PartsConfig::parts`); `None` when chosen at the knee.
    pub requested: Option<usize>,
    /// The number of parts returned.
    pub parts: usize,
    /// Residual against part count, before the borders are relaxed: one point per count
    /// from the mesh's connected pieces (usually 1) to `max_parts` (or the requested
    /// count, if larger), increasing.
    pub curve: Vec<CurvePoint>,
    /// Index into `curve` of the returned count: the requested one, or the knee.
    pub chosen: usize,
    /// True when the pose set does not move (one pose, or every pose equal to the
    /// template within `rigid_tolerance`): one part per connected piece is returned.
    pub motionless: bool,
    /// Vertices per part, indexed by the returned part id.
    pub part_sizes: Vec<usize>,
    /// The returned parts' mean residual, after the borders are relaxed (as in
    /// [`CurvePoint::mean_residual`]).
    pub mean_residual: Real,
    /// Border-relaxation sweeps run, in total.
    pub sweeps: usize,
}
