//! The per-run report of stage 3, in meshoptimizer's spirit: counts in and out, the
//! quadric error of the collapses, the output's edge-length statistics (paper Fig. 3),
//! what the safeguards refused, and the time taken.

use std::fmt;

/// Why the collapse loop ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// The target count was reached.
    TargetReached,
    /// Every remaining edge is refused by a safeguard (or locked): the output is larger
    /// than the target. This is a result, not an error.
    NoValidCollapse,
}

/// Collapses refused by each safeguard (a refused edge may be counted again when it is
/// retried after its neighbourhood changed).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Refusals {
    /// Would create a non-manifold edge, pinch two boundaries, or collapse a
    /// tetrahedron-like fan (the link condition).
    pub topology: usize,
    /// Would rotate a face normal past `max_normal_rotation_deg` (from before the
    /// collapse or from the input face).
    pub flip: usize,
    /// Would create a (near-)zero-area triangle.
    pub degenerate: usize,
    /// The fold guard: would leave a face more than `max_corner_normal_deg` from the
    /// input normals of the vertices at its corners.
    pub fold: usize,
    /// The seam rule: would remove a seam vertex other than along its seam, or shrink a
    /// seam loop below three edges (only with [`crate::SimplifyInput::seams`]).
    pub seam: usize,
}

/// Why one candidate collapse was refused (which counter of [`Refusals`] it adds to).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Refusal {
    Topology,
    Flip,
    Degenerate,
    Fold,
    Seam,
}

impl Refusals {
    pub(crate) fn count(&mut self, refusal: Refusal) {
        match refusal {
            Refusal::Topology => self.topology += 1,
            Refusal::Flip => self.flip += 1,
            Refusal::Degenerate => self.degenerate += 1,
            Refusal::Fold => self.fold += 1,
            Refusal::Seam => self.seam += 1,
        }
    }
}

/// What one run did. Errors are RMS distances in mesh units: for a collapse,
/// `sqrt(Q(v̄) / area(Q))`, the area-weighted RMS distance of the new vertex to the
/// planes of all original faces it stands for (constraint planes included in `Q`).
#[derive(Debug, Clone, PartialEq)]
pub struct SimplifyReport {
    pub input_vertices: usize,
    pub input_faces: usize,
    /// Referenced vertices of the output.
    pub output_vertices: usize,
    pub output_faces: usize,
    /// Edge collapses performed.
    pub collapses: usize,
    pub stop: StopReason,
    pub refusals: Refusals,
    /// Vertices that no collapse may touch: input non-manifold vertices (pinched fans,
    /// edges with more than two faces) and, with [`crate::PartBorders::Lock`], border
    /// vertices (those may still absorb neighbours), and the ends and junctions of seams
    /// (which may too).
    pub locked_vertices: usize,
    /// Input vertices on a seam edge, locked ones included (0 without seams).
    pub seam_vertices: usize,
    /// Largest and mean collapse error, in mesh units (see the type's doc).
    pub max_error: f64,
    pub mean_error: f64,
    /// Mean and population variance of the output's edge lengths, in mesh units and
    /// squared mesh units (the paper's Fig. 3 figure).
    pub edge_length_mean: f64,
    pub edge_length_variance: f64,
    /// Bounding-box diagonal of the input, mesh units (to read errors relatively).
    pub diagonal: f64,
    /// Wall time of the whole call, seconds.
    pub seconds: f64,
}

impl fmt::Display for SimplifyReport {
    /// One line: "24998 → 5000 faces, 12500 → 2501 vertices, error max 1.2e-3 mean
    /// 2.0e-4 (× diag), edge length 1.1e-2 ± 4.0e-3, 8.1 ms" (then ", 300 seam vertices"
    /// when the input has seams).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let rel = |e: f64| if self.diagonal > 0.0 { e / self.diagonal } else { e };
        write!(
            f,
            "{} → {} faces, {} → {} vertices, error max {:.2e} mean {:.2e} (× diag), \
             edge length {:.3e} ± {:.3e}, {:.1} ms",
            self.input_faces,
            self.output_faces,
            self.input_vertices,
            self.output_vertices,
            rel(self.max_error),
            rel(self.mean_error),
            self.edge_length_mean,
            self.edge_length_variance.sqrt(),
            self.seconds * 1e3,
        )?;
        if self.seam_vertices > 0 {
            write!(f, ", {} seam vertices", self.seam_vertices)?;
        }
        if self.stop == StopReason::NoValidCollapse {
            write!(f, " (stopped early: no valid collapse left)")?;
        }
        Ok(())
    }
}
