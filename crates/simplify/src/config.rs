//! Configuration of stage 3: the target, the cost's switchable factors, placement,
//! safeguards and constraint weights, each with a documented default.

use crate::error::SimplifyError;

/// How far to simplify. Face and vertex counts are of the *output*; the run stops as
/// soon as the count is at or below the target (a collapse removes one or two faces, so
/// a face target may be undershot by one).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// Stop at this many faces or fewer.
    Faces(usize),
    /// Stop at this many (referenced) vertices or fewer. The paper: 12500 → 2500.
    Vertices(usize),
    /// Keep this fraction of the input's faces, in `(0, 1]`.
    Ratio(f64),
}

/// Where the vertex of a collapsed edge goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Placement {
    /// Garland–Heckbert: the point minimising the merged quadric; when its 3×3 system
    /// is ill-conditioned or its solution lies far from the edge, the best point on the
    /// edge segment; when that is undefined, the better endpoint. Positions are new.
    #[default]
    Optimal,
    /// Half-edge collapse onto the better endpoint: every output vertex *is* an input
    /// vertex, and [`crate::Simplified::simp_to_orig`] is `Some` for all of them.
    Subset,
}

/// Which error the collapse order and the optimal placement minimise.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Metric {
    /// Garland–Heckbert: each vertex carries the quadric of its input faces, summed on
    /// every collapse, so the error is measured against the *input* surface (the paper's
    /// `Q`, Eq. 3–5).
    #[default]
    Quadric,
    /// Lindstrom and Turk 1998/1999 ("Fast and memory efficient polygonal
    /// simplification"; "Evaluation of memoryless simplification"), as in CGAL's default
    /// policy: memoryless — the cost of collapsing `(v1, v2)` to `v` is computed from the
    /// *current* faces around the edge: `½ Σ vol(v, t)² + ½ |v1 − v2|² Σ area(v, e)²`
    /// over the faces `t` around the edge (the tetrahedra the collapse sweeps) and the
    /// boundary edges `e` at its endpoints. Optimal placement preserves the enclosed
    /// volume and the boundary's area vector exactly, then minimises that cost, then
    /// (in directions still free) the squared distances to the link vertices, each
    /// constraint kept only when at least 1° from the span of the earlier ones. Its
    /// volume preservation keeps thin parts (fingers) from thinning out. The saliency and
    /// balance factors of Eq. 5 multiply it as they multiply the quadric error.
    /// [`crate::simplify_multipose`] always uses [`Metric::Quadric`].
    LindstromTurk,
}

/// What to do along the borders between body parts (edges whose endpoints carry
/// different part labels), when part labels are given.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum PartBorders {
    /// Part labels are ignored.
    #[default]
    Ignore,
    /// Every vertex on a part border keeps its original position and is never removed
    /// (it may absorb non-border neighbours). Borders survive exactly, at the cost of
    /// budget spent on them.
    Lock,
    /// A constraint quadric along each border edge, like the boundary quadric, with this
    /// weight (same units as [`SimplifyConfig::boundary_weight`]): borders are kept
    /// approximately, and may be simplified where they are straight.
    Constrain(f64),
}

/// Parameters of stage 3. `Default` is plain QSlim with optimal placement and every
/// safeguard on; the paper's method is `saliency: true, balance: true`.
#[derive(Debug, Clone, PartialEq)]
pub struct SimplifyConfig {
    /// How far to simplify. Default: `Ratio(0.2)`.
    pub target: Target,
    /// Where the kept vertex goes. Default: [`Placement::Optimal`].
    pub placement: Placement,
    /// Multiply the cost by the mean saliency weight `(w1 + w2) / 2` of the edge's
    /// endpoints (paper Eq. 5). Only has an effect when weights are given. Default: true.
    pub saliency: bool,
    /// Multiply the cost by the current edge length `d` (paper Eq. 5, the "balancing"
    /// term that evens out edge lengths). Default: false (plain QEM).
    pub balance: bool,
    /// Weight of the boundary constraint quadric: each boundary edge of length `l` adds
    /// the plane through it perpendicular to its face with weight `boundary_weight * l²`
    /// (a face quadric has weight = its area, about `0.43 l²` for an equilateral face),
    /// so the default 10 holds a boundary like twenty-odd faces standing across it.
    /// Default: 10.
    pub boundary_weight: f64,
    /// Treatment of part borders when labels are given. Default: [`PartBorders::Ignore`].
    pub part_borders: PartBorders,
    /// A collapse is refused when it leaves any surviving face's normal more than this
    /// angle, in degrees, from the face's normal before the collapse *or* in the input
    /// (small rotations add up over many collapses; the second test stops a face from
    /// slowly standing up or folding over). Default: 60.
    pub max_normal_rotation_deg: f64,
    /// A collapse is also refused when a surviving face's normal ends up more than this
    /// angle, in degrees, from the mean input normal of the vertices at its corners (the
    /// surface's own orientation where those vertices came from; for the moved corner,
    /// both endpoints'). The per-face test above compares a face with itself, so a face
    /// whose corners migrated far along a curved surface could stand on edge while
    /// passing it; this one compares with the surface under the corners. 70° was
    /// measured (BENCHMARKS.md "Fold guard"): on SCAPE → 5000 faces it halves the
    /// faces the peers' harness flags (QEM 6 → 3, subset 4 → 2, Lindstrom–Turk 3 → 0)
    /// for +0.3–0.9 % RMS, and on random coarse blobs it removes the folds the per-face
    /// test lets through (15 of 1500 runs → 0); 60° erodes the saliency's effect (the
    /// `fold_guard_survey` test prints both).
    /// `180` switches it off. Default: 70.
    pub max_corner_normal_deg: f64,
    /// Optimal placements farther than this many edge lengths from the edge midpoint are
    /// distrusted (near-singular quadric) and replaced by the best point on the edge.
    /// Default: 2.
    pub max_placement_distance: f64,
    /// The error ranking collapses and choosing optimal placements. Default:
    /// [`Metric::Quadric`] (the paper's). The report's errors are always quadric errors.
    pub metric: Metric,
    /// With [`Metric::Quadric`], rank each collapse by its quadric error divided by the
    /// face area its quadrics represent: a mean squared distance to the input surface
    /// rather than an area-weighted sum (meshoptimizer's `quadricError` normalises so).
    /// Large flat regions then cost no more to simplify than small curved ones, so the
    /// budget moves to hands, feet and face. The placement is unchanged (the division
    /// does not move the optimum). Default: false (Garland–Heckbert, the paper's).
    pub normalized_error: bool,
}

impl Default for SimplifyConfig {
    fn default() -> Self {
        Self {
            target: Target::Ratio(0.2),
            placement: Placement::Optimal,
            saliency: true,
            balance: false,
            boundary_weight: 10.0,
            part_borders: PartBorders::Ignore,
            max_normal_rotation_deg: 60.0,
            max_corner_normal_deg: 70.0,
            max_placement_distance: 2.0,
            metric: Metric::Quadric,
            normalized_error: false,
        }
    }
}

impl SimplifyConfig {
    /// Plain QSlim (no saliency, no balance) to `target`.
    pub fn qslim(target: Target) -> Self {
        Self { target, saliency: false, balance: false, ..Self::default() }
    }

    /// The paper's method (saliency and balance) to `target`.
    pub fn paper(target: Target) -> Self {
        Self { target, saliency: true, balance: true, ..Self::default() }
    }

    /// Checks every field against its documented range.
    pub fn validate(&self) -> Result<(), SimplifyError> {
        if let Target::Ratio(ratio) = self.target
            && !(ratio > 0.0 && ratio <= 1.0)
        {
            return Err(SimplifyError::BadRatio { ratio });
        }
        let non_negative = |field, value: f64| {
            if value.is_finite() && value >= 0.0 {
                Ok(())
            } else {
                Err(SimplifyError::BadConfig { field, value, expected: "finite and >= 0" })
            }
        };
        non_negative("boundary_weight", self.boundary_weight)?;
        non_negative("max_placement_distance", self.max_placement_distance)?;
        if let PartBorders::Constrain(w) = self.part_borders {
            non_negative("part_borders", w)?;
        }
        for (field, angle) in [
            ("max_normal_rotation_deg", self.max_normal_rotation_deg),
            ("max_corner_normal_deg", self.max_corner_normal_deg),
        ] {
            if !(angle > 0.0 && angle <= 180.0) {
                return Err(SimplifyError::BadConfig { field, value: angle, expected: "in (0, 180]" });
            }
        }
        Ok(())
    }

    /// The face count to stop at, for an input of `faces` faces (`None`: vertex target).
    pub(crate) fn target_faces(&self, faces: usize) -> Option<usize> {
        match self.target {
            Target::Faces(n) => Some(n),
            Target::Vertices(_) => None,
            Target::Ratio(r) => Some((faces as f64 * r).round() as usize),
        }
    }
}

/// The settings the engine's costs and safeguards read, derived once from a
/// [`SimplifyConfig`].
#[derive(Debug)]
pub(crate) struct Params {
    pub(crate) placement: Placement,
    /// [`Metric::Quadric`] whenever there are several poses.
    pub(crate) metric: Metric,
    pub(crate) balance: bool,
    pub(crate) cos_max_rotation: f64,
    /// `-inf` when the corner-normal guard is off (180°).
    pub(crate) cos_max_corner_normal: f64,
    pub(crate) max_placement_distance: f64,
    /// Quadric costs divided by the area their quadrics represent
    /// ([`SimplifyConfig::normalized_error`]).
    pub(crate) normalized_error: bool,
}

impl Params {
    /// The settings of `config` for `pose_count` poses.
    pub(crate) fn new(config: &SimplifyConfig, pose_count: usize) -> Self {
        Params {
            placement: config.placement,
            metric: if pose_count == 1 { config.metric } else { Metric::Quadric },
            balance: config.balance,
            cos_max_rotation: config.max_normal_rotation_deg.to_radians().cos(),
            cos_max_corner_normal: if config.max_corner_normal_deg >= 180.0 {
                f64::NEG_INFINITY
            } else {
                config.max_corner_normal_deg.to_radians().cos()
            },
            max_placement_distance: config.max_placement_distance,
            normalized_error: config.normalized_error,
        }
    }
}
