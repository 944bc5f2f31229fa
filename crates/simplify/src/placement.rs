//! Where the vertex of a collapsed edge goes and what the collapse costs: the quadric
//! placements (optimal: the minimiser, then the best point of the edge, then the better
//! endpoint; subset: the better endpoint), Lindstrom–Turk's, and the factors of the
//! paper's Eq. 5. Functions over the arrays of the [`Surface`], which they only read;
//! [`cost_of`] is ranking's short path and [`costs_of`] its four-lane form, both
//! asserted equal to the full [`evaluate`] in debug builds.

use desal_mesh::Vec3;

use crate::classify::{FROZEN, PINNED};
use crate::config::{Metric, Params, Placement};
use crate::lanes::{Lanes, Points, four};
use crate::lindstrom_turk::Neighbourhood;
use crate::quadric::Quadric4;
use crate::safeguards::seam_rule_lets_remove;
use crate::surface::Surface;

/// Relative margin by which a computed placement must beat the better endpoint's error
/// to be used instead of it (rounding noise must not move a vertex off its position).
const SNAP_TOLERANCE: f64 = 1e-9;

/// One evaluated collapse: `remove` goes, `keep` moves to `position`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Candidate {
    pub(crate) remove: u32,
    pub(crate) keep: u32,
    pub(crate) position: Vec3,
    /// Merged quadric at `position` (summed over poses), before the cost's factors.
    pub(crate) error: f64,
    /// The ranking key: the metric's error times the enabled factors of Eq. 5.
    pub(crate) cost: f64,
}

/// Placement and cost of collapsing edge `(a, b)`; `None` when the edge may not
/// collapse at all (a frozen endpoint, both pinned, or a non-finite cost).
/// Inlined by force into `try_collapse`'s clones (BENCHMARKS.md "Issue 40").
#[inline(always)]
pub(crate) fn evaluate(s: &Surface, params: &Params, a: u32, b: u32) -> Option<Candidate> {
    let (fa, fb) = (s.flags[a as usize], s.flags[b as usize]);
    if (fa | fb) & FROZEN != 0 || (fa & fb) & PINNED != 0 {
        return None;
    }
    let pinned = Pinned { a: fa & PINNED != 0, b: fb & PINNED != 0, seam_keeps: seam_keeps(s, a, b) };
    let (pa, pb) = (&s.positions[a as usize], &s.positions[b as usize]);
    let (candidate, error) = match params.metric {
        Metric::LindstromTurk => evaluate_lindstrom_turk(s, params, a, b, pinned),
        Metric::Quadric => {
            let c = match (params.placement, pinned.any()) {
                (Placement::Subset, _) => place_on_endpoint(s, a, b, pinned),
                (Placement::Optimal, true) => {
                    let keep = pinned.endpoint(a, b, |_| 0.0);
                    candidate_at(s, a, b, s.positions[keep as usize], keep)
                }
                (Placement::Optimal, false) => place_optimally(s, params, a, b, pinned.seam_keeps),
            };
            (c, c.error)
        }
    };
    let cost = cost_factors(s, params, a, b, error, pa, pb);
    cost.is_finite().then_some(Candidate { cost, ..candidate })
}

/// `error` (per unit area with `normalized_error`) times the enabled factors of Eq.
/// 5: edge length, mean saliency weight. Inlined by force: LLVM kept it a call per edge
/// costed (BENCHMARKS.md "Issue 40").
#[inline(always)]
fn cost_factors(s: &Surface, params: &Params, a: u32, b: u32, error: f64, pa: &Vec3, pb: &Vec3) -> f64 {
    let mut cost = error;
    if params.normalized_error && params.metric == Metric::Quadric {
        let area = merged_area(s, a, b);
        if area > 0.0 {
            cost /= area;
        }
    }
    if params.balance {
        cost *= (pa - pb).norm();
    }
    if let Some(w) = &s.weights {
        cost *= 0.5 * (w[a as usize] + w[b as usize]);
    }
    cost
}

/// [`evaluate`] with Lindstrom–Turk's cost: the placement of
/// [`Neighbourhood::placement`] (or the cheaper endpoint: for subset placement, for a
/// pinned endpoint, or when that placement is undefined or flies farther than
/// `max_placement_distance`), costed from the current faces around the edge. The
/// candidate's `error` stays the merged quadric's, for the report; the returned
/// error is Lindstrom–Turk's, for the ranking.
fn evaluate_lindstrom_turk(s: &Surface, params: &Params, a: u32, b: u32, pinned: Pinned) -> (Candidate, f64) {
    let pa = s.positions[a as usize];
    let pb = s.positions[b as usize];
    let squared_length = (pa - pb).norm_squared();
    let n = Neighbourhood::gather(a, b, &s.lists, &s.positions, &s.flags);
    let computed = if params.placement == Placement::Subset || pinned.any() {
        None
    } else {
        let mid = (pa + pb) * 0.5;
        let reach = params.max_placement_distance * squared_length.sqrt();
        n.placement(squared_length, || Neighbourhood::link_positions(a, b, &s.lists, &s.positions))
            .filter(|p| (p - mid).norm() <= reach)
    };
    let (position, keep) = match computed {
        Some(p) => (p, pinned.seam_keeps.unwrap_or_else(|| nearer_endpoint(a, b, &pa, &pb, &p))),
        None => {
            let keep = pinned.endpoint(a, b, |k| n.cost(&s.positions[k as usize], squared_length));
            (s.positions[keep as usize], keep)
        }
    };
    (candidate_at(s, a, b, position, keep), n.cost(&position, squared_length))
}

/// Subset placement: keep whichever endpoint has the smaller merged error (the lower
/// index on a tie); a pinned endpoint is always the one kept. With keep penalties,
/// the endpoint with the smaller merged error per unit area plus its penalty is kept,
/// and the collapse is ranked by the better endpoint's error, as without them
/// ([`SimplifyInput::keep_penalty`](crate::SimplifyInput::keep_penalty)); a pinned
/// endpoint or the seam rule still decides alone, ranked by the kept one's error.
fn place_on_endpoint(s: &Surface, a: u32, b: u32, pinned: Pinned) -> Candidate {
    let (keep, error) = match &s.keep_penalty {
        None => {
            let keep = pinned.endpoint(a, b, |k| subset_error(s, a, b, k));
            (keep, subset_error(s, a, b, keep))
        }
        Some(penalty) => {
            let (error_a, error_b) = (subset_error(s, a, b, a), subset_error(s, a, b, b));
            // The penalty is per unit area, as a normalised error is: scaled by
            // the merged area, it is comparable with the summed error.
            let area = merged_area(s, a, b);
            let error_of = |k: u32| if k == a { error_a } else { error_b };
            let keep = pinned.endpoint(a, b, |k| error_of(k) + area * penalty[k as usize]);
            let forced = pinned.any() || pinned.seam_keeps.is_some();
            (keep, if forced { error_of(keep) } else { error_a.min(error_b) })
        }
    };
    let remove = if keep == a { b } else { a };
    Candidate { remove, keep, position: s.positions[keep as usize], error, cost: 0.0 }
}

/// The summed quadric area of `a` and `b` over every pose.
#[inline]
fn merged_area(s: &Surface, a: u32, b: u32) -> f64 {
    let pc = s.pose_count;
    let (a, b) = (a as usize * pc, b as usize * pc);
    (0..pc).map(|p| s.quadrics[a + p].area + s.quadrics[b + p].area).sum()
}

/// Merged error of `(a, b)` when `keep` stays where it is, summed over poses.
#[inline]
fn subset_error(s: &Surface, a: u32, b: u32, keep: u32) -> f64 {
    let pc = s.pose_count;
    let (a, b, k) = (a as usize, b as usize, keep as usize);
    let mut error = 0.0;
    for p in 0..pc {
        let q = s.quadrics[a * pc + p] + s.quadrics[b * pc + p];
        let x = if pc == 1 { &s.positions[k] } else { &s.pose_positions[p][k] };
        error += q.eval(x);
    }
    error.max(0.0)
}

/// Optimal placement (single pose): the quadric's minimiser if well-conditioned and
/// near the edge, else the best point of the segment, else the better endpoint. The
/// slot kept is `seam_keeps` when the seam rule names one, else the nearer endpoint.
/// Inlined by force into `try_collapse`'s clones (BENCHMARKS.md "Issue 40").
#[inline(always)]
fn place_optimally(s: &Surface, params: &Params, a: u32, b: u32, seam_keeps: Option<u32>) -> Candidate {
    let (pa, pb) = (s.positions[a as usize], s.positions[b as usize]);
    let (position, error) = optimal_position(s, params, a, b);
    let keep = seam_keeps.unwrap_or_else(|| nearer_endpoint(a, b, &pa, &pb, &position));
    let remove = if keep == a { b } else { a };
    Candidate { remove, keep, position, error, cost: 0.0 }
}

/// The optimal placement of `(a, b)` (see [`place_optimally`]) and the merged
/// quadric's error there: all that ranking needs. Inlined by force: as a call it
/// returned the pair through memory (BENCHMARKS.md "Issue 40").
#[inline(always)]
fn optimal_position(s: &Surface, params: &Params, a: u32, b: u32) -> (Vec3, f64) {
    // One slot count for both arrays (as in `costs_of`).
    let positions = &s.positions[..];
    let quadrics = &s.quadrics[..positions.len()];
    let (pa, pb) = (positions[a as usize], positions[b as usize]);
    let q = quadrics[a as usize] + quadrics[b as usize];
    let (error_a, error_b) = (q.eval(&pa), q.eval(&pb));
    let (endpoint, endpoint_error) = if error_b < error_a { (pb, error_b) } else { (pa, error_a) };
    let mid = (pa + pb) * 0.5;
    let reach = params.max_placement_distance * (pa - pb).norm();
    let computed = match q.minimiser() {
        Some(p) if (p - mid).norm() <= reach => Some(p),
        _ => q.minimiser_on_segment(&pa, &pb),
    };
    // An endpoint as good as the computed point up to rounding is preferred: the
    // vertex then keeps its exact input position (and `simp_to_orig` entry).
    if let Some(p) = computed {
        let error = q.eval(&p).max(0.0);
        if beats_endpoint(error, endpoint_error) {
            return (p, error);
        }
    }
    (endpoint, endpoint_error.max(0.0))
}

/// The cost of collapsing `(a, b)`, infinite when it may not collapse: what
/// [`evaluate`] gives, without choosing the slot kept (the common case, an
/// optimal quadric placement with neither endpoint pinned, has a short path; the seam
/// rule changes only which slot an optimal placement keeps, not its cost). Inlined by
/// force into the listing's clones (BENCHMARKS.md "Issue 40").
#[inline(always)]
pub(crate) fn cost_of(s: &Surface, params: &Params, a: u32, b: u32) -> f64 {
    let full = || evaluate(s, params, a, b).map_or(f64::INFINITY, |c| c.cost);
    let (fa, fb) = (s.flags[a as usize], s.flags[b as usize]);
    if params.placement == Placement::Subset
        || params.metric == Metric::LindstromTurk
        || (fa | fb) & (FROZEN | PINNED) != 0
    {
        return full();
    }
    let (pa, pb) = (&s.positions[a as usize], &s.positions[b as usize]);
    let cost = cost_factors(s, params, a, b, optimal_position(s, params, a, b).1, pa, pb);
    let cost = finite_or_infinity(cost);
    debug_assert_eq!(cost.to_bits(), full().to_bits(), "fast and full cost of edge ({a}, {b}) differ");
    cost
}

/// [`cost_of`] of four edges at once, bit for bit (asserted in debug builds):
/// the common case, a well-conditioned minimiser near the edge, in four lanes, and
/// any lane off it (a frozen or pinned endpoint, the segment or endpoint fallback)
/// by `cost_of` alone. For optimal quadric placement only; inlined by force into
/// the listing sweep, whose AVX2 clone runs the lanes as vectors (BENCHMARKS.md
/// "Issue 40").
#[inline(always)]
pub(crate) fn costs_of(s: &Surface, params: &Params, edges: [[u32; 2]; 4]) -> [f64; 4] {
    // Optimal placement is single-pose only (`simplify_multipose` places on a subset).
    debug_assert!(params.placement == Placement::Optimal && params.metric == Metric::Quadric);
    debug_assert_eq!(s.pose_count, 1);
    let (a, b) = (four(|l| edges[l][0] as usize), four(|l| edges[l][1] as usize));
    // One slot count for both arrays (single pose: a quadric per slot), so that one
    // bounds check per vertex covers both.
    let positions = &s.positions[..];
    let quadrics = &s.quadrics[..positions.len()];
    let pa = Points::of(four(|l| &positions[a[l]]));
    let pb = Points::of(four(|l| &positions[b[l]]));
    let q = Quadric4::sums(four(|l| (&quadrics[a[l]], &quadrics[b[l]])));
    let (error_a, error_b) = (q.eval(&pa), q.eval(&pb));
    let half = Lanes::splat(0.5);
    let mid = Points { x: (pa.x + pb.x) * half, y: (pa.y + pb.y) * half, z: (pa.z + pb.z) * half };
    let reach = Lanes::splat(params.max_placement_distance) * pa.distance(&pb);
    let (p, solved) = q.minimiser();
    let near = p.distance(&mid).le(reach);
    // The lanes on the common path, both tests combined before the loop, not in it
    // (BENCHMARKS.md "Issue 40").
    let common = four(|l| solved[l] && near[l]);
    let error = q.eval(&p);
    let flags = &s.flags[..positions.len()];
    let mut costs = [0.0; 4];
    for (l, cost) in costs.iter_mut().enumerate() {
        let [a, b] = edges[l];
        if !common[l] || (flags[a as usize] | flags[b as usize]) & (FROZEN | PINNED) != 0 {
            *cost = cost_of(s, params, a, b);
            continue;
        }
        // `optimal_position`'s choice, and `cost_of`'s factors.
        let endpoint_error = if error_b.0[l] < error_a.0[l] { error_b.0[l] } else { error_a.0[l] };
        let error = error.0[l].max(0.0);
        let chosen = if beats_endpoint(error, endpoint_error) { error } else { endpoint_error.max(0.0) };
        let (pa, pb) = (&positions[a as usize], &positions[b as usize]);
        let factored = cost_factors(s, params, a, b, chosen, pa, pb);
        *cost = finite_or_infinity(factored);
        debug_assert_eq!(
            cost.to_bits(),
            cost_of(s, params, a, b).to_bits(),
            "four-lane cost of edge ({a}, {b})"
        );
    }
    costs
}

/// The endpoint the seam rule keeps when it lets only the other one go (`None`: both
/// may go, or neither, which `check_seam_rule` refuses).
#[inline]
fn seam_keeps(s: &Surface, a: u32, b: u32) -> Option<u32> {
    let seams = s.seams.as_ref()?;
    match (
        seam_rule_lets_remove(Some(seams), &s.flags, a, b),
        seam_rule_lets_remove(Some(seams), &s.flags, b, a),
    ) {
        (false, true) => Some(a),
        (true, false) => Some(b),
        _ => None,
    }
}

fn candidate_at(s: &Surface, a: u32, b: u32, position: Vec3, keep: u32) -> Candidate {
    let remove = if keep == a { b } else { a };
    let q = s.quadrics[a as usize] + s.quadrics[b as usize];
    Candidate { remove, keep, position, error: q.eval(&position).max(0.0), cost: 0.0 }
}

/// Whether a computed placement with merged error `error` beats the better endpoint's
/// `endpoint_error` by more than rounding ([`SNAP_TOLERANCE`]): only then is the vertex
/// moved off its input position. The rule of `optimal_position` and of its lanes in
/// `costs_of`.
#[inline]
fn beats_endpoint(error: f64, endpoint_error: f64) -> bool {
    endpoint_error > error * (1.0 + SNAP_TOLERANCE)
}

/// A ranked cost: finite, or `+inf` for an edge that may not collapse (NaN included).
#[inline]
fn finite_or_infinity(cost: f64) -> f64 {
    if cost.is_finite() { cost } else { f64::INFINITY }
}

/// Which endpoints of an edge are pinned (never both: such an edge is not evaluated),
/// and which one the seam rule keeps, if it keeps one.
#[derive(Debug, Clone, Copy)]
struct Pinned {
    a: bool,
    b: bool,
    /// The endpoint that must stay (it may still move) because the seam rule lets only
    /// the other one go.
    seam_keeps: Option<u32>,
}

impl Pinned {
    fn any(self) -> bool {
        self.a || self.b
    }

    /// The endpoint a collapse onto an endpoint keeps: the pinned one, else the one the
    /// seam rule keeps, else the one with the smaller `error_keeping` (the lower index on
    /// a tie).
    #[inline]
    fn endpoint(self, a: u32, b: u32, error_keeping: impl Fn(u32) -> f64) -> u32 {
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        if self.a {
            a
        } else if self.b {
            b
        } else if let Some(keep) = self.seam_keeps {
            keep
        } else if error_keeping(hi) < error_keeping(lo) {
            hi
        } else {
            lo
        }
    }
}

/// The slot a moved vertex keeps: the endpoint nearer its new position (the lower index
/// on a tie), so a vertex that did not move keeps its identity.
#[inline]
fn nearer_endpoint(a: u32, b: u32, pa: &Vec3, pb: &Vec3, position: &Vec3) -> u32 {
    let (da, db) = ((position - pa).norm_squared(), (position - pb).norm_squared());
    if da < db || (da == db && a < b) { a } else { b }
}

#[cfg(test)]
mod tests {
    use desal_mesh::{TriMesh, Vec3};

    use super::{cost_of, costs_of, evaluate};
    use crate::classify::PINNED;
    use crate::config::{Metric, Params, PartBorders, SimplifyConfig};
    use crate::surface::Surface;

    /// A grid of `n × n` quads, flat except for a bump in its middle: flat regions have
    /// singular quadrics (the segment or endpoint fallback), the bump regular ones, and
    /// the border constraint planes.
    fn bumped_grid(n: usize) -> TriMesh {
        let mut positions = Vec::new();
        for i in 0..=n {
            for j in 0..=n {
                let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
                let r2 = (x - 0.5).powi(2) + (y - 0.5).powi(2);
                positions.push(Vec3::new(x, y, 0.3 * (-r2 * 20.0).exp() * (1.0 + 0.1 * (17.0 * x).sin())));
            }
        }
        let at = |i: usize, j: usize| (i * (n + 1) + j) as u32;
        let mut faces = Vec::new();
        for i in 0..n {
            for j in 0..n {
                faces.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                faces.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        TriMesh { positions, faces }
    }

    /// The four-lane cost is bit for bit the one-edge cost, for every edge of the grid
    /// in groups of four, with each factor of Eq. 5 on and off (edge length, normalised
    /// error, saliency weights), and whatever mix of regular and fallback lanes a group
    /// holds (singular quadrics on the flat part, pinned endpoints on a locked part
    /// border).
    #[test]
    fn four_lane_costs_are_the_one_edge_costs() {
        let mesh = bumped_grid(12);
        let mut edges: Vec<[u32; 2]> = mesh
            .faces
            .iter()
            .flat_map(|&[a, b, c]| [[a, b], [b, c], [c, a]])
            .map(|[a, b]| [a.min(b), a.max(b)])
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let weights: Vec<f64> = (0..mesh.positions.len()).map(|v| 1.0 + (v % 7) as f64 * 0.3).collect();
        let labels: Vec<u32> = mesh.positions.iter().map(|p| u32::from(p.x > 0.6)).collect();
        for mask in 0..16u32 {
            let bit = |b: u32| mask & (1 << b) != 0;
            let config = SimplifyConfig {
                balance: bit(0),
                normalized_error: bit(1),
                part_borders: if bit(3) { PartBorders::Lock } else { PartBorders::Ignore },
                ..SimplifyConfig::default()
            };
            let mut input = crate::SimplifyInput::new(&mesh).with_part_labels(&labels);
            if bit(2) {
                input = input.with_weights(&weights);
            }
            let s = Surface::new(&[mesh.positions.as_slice()], 0, &input, mesh.faces.clone(), &config);
            let params = Params::new(&config, 1);
            assert_eq!(params.metric, Metric::Quadric);
            let (mut singular, mut pinned) = (0, 0);
            for group in edges.chunks_exact(4) {
                let group: [[u32; 2]; 4] = group.try_into().expect("four");
                let four = costs_of(&s, &params, group);
                for (&[a, b], cost) in group.iter().zip(four) {
                    assert_eq!(
                        cost.to_bits(),
                        cost_of(&s, &params, a, b).to_bits(),
                        "edge ({a}, {b}), mask {mask}: {cost}"
                    );
                    singular += usize::from(s.quadrics[a as usize].minimiser().is_none());
                    pinned += usize::from((s.flags[a as usize] | s.flags[b as usize]) & PINNED != 0);
                }
            }
            assert!(singular > 0, "the flat part of the grid has singular quadrics");
            assert_eq!(pinned > 0, bit(3), "a locked border pins its vertices (mask {mask})");
        }
    }

    /// The seam rule decides which endpoint an evaluation keeps: on a 3 × 3 grid with a
    /// seam along its middle row (3–4–5), the centre 4 is inside the seam and may leave
    /// only along it, so collapsing edge (1, 4) with border vertex 1, which may go
    /// anywhere, removes 1 and keeps 4, both ways round.
    #[test]
    fn the_seam_rule_decides_the_endpoint_kept() {
        let mesh = bumped_grid(2);
        let seams = [[3, 4], [4, 5]];
        let input = crate::SimplifyInput::new(&mesh).with_seams(&seams);
        let config = SimplifyConfig::default();
        let s = Surface::new(&[mesh.positions.as_slice()], 0, &input, mesh.faces.clone(), &config);
        let params = Params::new(&config, 1);
        for (a, b) in [(1, 4), (4, 1)] {
            let kept = evaluate(&s, &params, a, b).expect("1 may go onto 4");
            assert_eq!((kept.remove, kept.keep), (1, 4));
        }
    }
}
