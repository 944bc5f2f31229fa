//! Where the vertex of a collapsed edge goes and what the collapse costs: the quadric
//! placements (optimal: the minimiser, then the best point of the edge, then the better
//! endpoint; subset: the better endpoint), Lindstrom–Turk's, and the factors of the
//! paper's Eq. 5. Read-only on the engine; `cost_of` is ranking's short path, asserted
//! equal to the full `evaluate` in debug builds.

use desal_mesh::Vec3;

use crate::classify::{FROZEN, PINNED};
use crate::collapse::{Candidate, Engine};
use crate::config::{Metric, Placement};
use crate::lanes::{Lanes, Points, four};
use crate::lindstrom_turk::Neighbourhood;
use crate::quadric::Quadric4;

/// Relative margin by which a computed placement must beat the better endpoint's error
/// to be used instead of it (rounding noise must not move a vertex off its position).
const SNAP_TOLERANCE: f64 = 1e-9;

impl Engine {
    /// Placement and cost of collapsing edge `(a, b)`; `None` when the edge may not
    /// collapse at all (a frozen endpoint, both pinned, or a non-finite cost).
    /// Inlined by force (into `try_collapse`; −0.35 M instructions on SCAPE).
    #[inline(always)]
    pub(crate) fn evaluate(&self, a: u32, b: u32) -> Option<Candidate> {
        let (fa, fb) = (self.flags[a as usize], self.flags[b as usize]);
        if (fa | fb) & FROZEN != 0 || (fa & fb) & PINNED != 0 {
            return None;
        }
        let pinned = Pinned { a: fa & PINNED != 0, b: fb & PINNED != 0, seam_keeps: self.seam_keeps(a, b) };
        let (pa, pb) = (&self.positions[a as usize], &self.positions[b as usize]);
        let (candidate, error) = match self.params.metric {
            Metric::LindstromTurk => self.evaluate_lindstrom_turk(a, b, pinned),
            Metric::Quadric => {
                let c = match (self.params.placement, pinned.any()) {
                    (Placement::Subset, _) => self.place_on_endpoint(a, b, pinned),
                    (Placement::Optimal, true) => {
                        let keep = pinned.endpoint(a, b, |_| 0.0);
                        self.candidate_at(a, b, self.positions[keep as usize], keep)
                    }
                    (Placement::Optimal, false) => self.place_optimally(a, b, pinned.seam_keeps),
                };
                (c, c.error)
            }
        };
        let cost = self.cost_factors(a, b, error, pa, pb);
        cost.is_finite().then_some(Candidate { cost, ..candidate })
    }

    /// `error` (per unit area with `normalized_error`) times the enabled factors of Eq.
    /// 5: edge length, mean saliency weight. Inlined by force: LLVM kept it a call, made
    /// once per edge costed.
    #[inline(always)]
    fn cost_factors(&self, a: u32, b: u32, error: f64, pa: &Vec3, pb: &Vec3) -> f64 {
        let mut cost = error;
        if self.params.normalized_error && self.params.metric == Metric::Quadric {
            let area = self.merged_area(a, b);
            if area > 0.0 {
                cost /= area;
            }
        }
        if self.params.balance {
            cost *= (pa - pb).norm();
        }
        if let Some(w) = &self.weights {
            cost *= 0.5 * (w[a as usize] + w[b as usize]);
        }
        cost
    }

    /// [`Self::evaluate`] with Lindstrom–Turk's cost: the placement of
    /// [`Neighbourhood::placement`] (or the cheaper endpoint: for subset placement, for a
    /// pinned endpoint, or when that placement is undefined or flies farther than
    /// `max_placement_distance`), costed from the current faces around the edge. The
    /// candidate's `error` stays the merged quadric's, for the report; the returned
    /// error is Lindstrom–Turk's, for the ranking.
    fn evaluate_lindstrom_turk(&self, a: u32, b: u32, pinned: Pinned) -> (Candidate, f64) {
        let pa = self.positions[a as usize];
        let pb = self.positions[b as usize];
        let squared_length = (pa - pb).norm_squared();
        let n = Neighbourhood::gather(a, b, &self.lists, &self.positions, &self.flags);
        let computed = if self.params.placement == Placement::Subset || pinned.any() {
            None
        } else {
            let mid = (pa + pb) * 0.5;
            let reach = self.params.max_placement_distance * squared_length.sqrt();
            n.placement(squared_length, || Neighbourhood::link_positions(a, b, &self.lists, &self.positions))
                .filter(|p| (p - mid).norm() <= reach)
        };
        let (position, keep) = match computed {
            Some(p) => (p, pinned.seam_keeps.unwrap_or_else(|| nearer_endpoint(a, b, &pa, &pb, &p))),
            None => {
                let keep = pinned.endpoint(a, b, |k| n.cost(&self.positions[k as usize], squared_length));
                (self.positions[keep as usize], keep)
            }
        };
        (self.candidate_at(a, b, position, keep), n.cost(&position, squared_length))
    }

    /// Subset placement: keep whichever endpoint has the smaller merged error (the lower
    /// index on a tie); a pinned endpoint is always the one kept. With keep penalties,
    /// the endpoint with the smaller merged error per unit area plus its penalty is kept,
    /// and the collapse is ranked by the better endpoint's error, as without them
    /// ([`SimplifyInput::keep_penalty`](crate::SimplifyInput::keep_penalty)); a pinned
    /// endpoint or the seam rule still decides alone, ranked by the kept one's error.
    fn place_on_endpoint(&self, a: u32, b: u32, pinned: Pinned) -> Candidate {
        let (keep, error) = match &self.keep_penalty {
            None => {
                let keep = pinned.endpoint(a, b, |k| self.subset_error(a, b, k));
                (keep, self.subset_error(a, b, keep))
            }
            Some(penalty) => {
                let (error_a, error_b) = (self.subset_error(a, b, a), self.subset_error(a, b, b));
                // The penalty is per unit area, as a normalised error is: scaled by
                // the merged area, it is comparable with the summed error.
                let area = self.merged_area(a, b);
                let error_of = |k: u32| if k == a { error_a } else { error_b };
                let keep = pinned.endpoint(a, b, |k| error_of(k) + area * penalty[k as usize]);
                let forced = pinned.any() || pinned.seam_keeps.is_some();
                (keep, if forced { error_of(keep) } else { error_a.min(error_b) })
            }
        };
        let remove = if keep == a { b } else { a };
        Candidate { remove, keep, position: self.positions[keep as usize], error, cost: 0.0 }
    }

    /// The summed quadric area of `a` and `b` over every pose.
    #[inline]
    fn merged_area(&self, a: u32, b: u32) -> f64 {
        let pc = self.pose_count;
        let (a, b) = (a as usize * pc, b as usize * pc);
        (0..pc).map(|p| self.quadrics[a + p].area + self.quadrics[b + p].area).sum()
    }

    /// Merged error of `(a, b)` when `keep` stays where it is, summed over poses.
    #[inline]
    fn subset_error(&self, a: u32, b: u32, keep: u32) -> f64 {
        let pc = self.pose_count;
        let (a, b, k) = (a as usize, b as usize, keep as usize);
        let mut error = 0.0;
        for p in 0..pc {
            let q = self.quadrics[a * pc + p] + self.quadrics[b * pc + p];
            let x = if pc == 1 { &self.positions[k] } else { &self.pose_positions[p][k] };
            error += q.eval(x);
        }
        error.max(0.0)
    }

    /// Optimal placement (single pose): the quadric's minimiser if well-conditioned and
    /// near the edge, else the best point of the segment, else the better endpoint. The
    /// slot kept is `seam_keeps` when the seam rule names one, else the nearer endpoint.
    /// Inlined by force, like every step of `try_collapse`, so that its AVX2 clone's
    /// features reach it (`collapse.rs`).
    #[inline(always)]
    fn place_optimally(&self, a: u32, b: u32, seam_keeps: Option<u32>) -> Candidate {
        let (pa, pb) = (self.positions[a as usize], self.positions[b as usize]);
        let (position, error) = self.optimal_position(a, b);
        let keep = seam_keeps.unwrap_or_else(|| nearer_endpoint(a, b, &pa, &pb, &position));
        let remove = if keep == a { b } else { a };
        Candidate { remove, keep, position, error, cost: 0.0 }
    }

    /// The optimal placement of `(a, b)` (see [`Self::place_optimally`]) and the merged
    /// quadric's error there: all that ranking needs. Inlined by force (into `cost_of`
    /// and `place_optimally`): as a call it returned the pair through memory (measured:
    /// −0.7 M instructions on SCAPE at c807891, where it had cost +0.3 M at f81532d).
    #[inline(always)]
    fn optimal_position(&self, a: u32, b: u32) -> (Vec3, f64) {
        // One slot count for both arrays (as in `costs_of`).
        let positions = &self.positions[..];
        let quadrics = &self.quadrics[..positions.len()];
        let (pa, pb) = (positions[a as usize], positions[b as usize]);
        let q = quadrics[a as usize] + quadrics[b as usize];
        let (error_a, error_b) = (q.eval(&pa), q.eval(&pb));
        let (endpoint, endpoint_error) = if error_b < error_a { (pb, error_b) } else { (pa, error_a) };
        let mid = (pa + pb) * 0.5;
        let reach = self.params.max_placement_distance * (pa - pb).norm();
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
    /// [`Self::evaluate`] gives, without choosing the slot kept (the common case, an
    /// optimal quadric placement with neither endpoint pinned, has a short path; the seam
    /// rule changes only which slot an optimal placement keeps, not its cost). Inlined
    /// by force into the listing sweep (measured: −1.4 M instructions on SCAPE once
    /// `optimal_position` is inlined into it; no change at f81532d, when it was not).
    #[inline(always)]
    pub(crate) fn cost_of(&self, a: u32, b: u32) -> f64 {
        let full = || self.evaluate(a, b).map_or(f64::INFINITY, |c| c.cost);
        let (fa, fb) = (self.flags[a as usize], self.flags[b as usize]);
        if self.params.placement == Placement::Subset
            || self.params.metric == Metric::LindstromTurk
            || (fa | fb) & (FROZEN | PINNED) != 0
        {
            return full();
        }
        let (pa, pb) = (&self.positions[a as usize], &self.positions[b as usize]);
        let cost = self.cost_factors(a, b, self.optimal_position(a, b).1, pa, pb);
        let cost = finite_or_infinity(cost);
        debug_assert_eq!(cost.to_bits(), full().to_bits(), "fast and full cost of edge ({a}, {b}) differ");
        cost
    }

    /// [`Self::cost_of`] of four edges at once, bit for bit (asserted in debug builds):
    /// the common case, a well-conditioned minimiser near the edge, in four lanes, and
    /// any lane off it (a frozen or pinned endpoint, the segment or endpoint fallback)
    /// by `cost_of` alone. For optimal quadric placement only; inlined by force into
    /// the listing sweep, whose AVX2 clone runs the lanes as vectors.
    #[inline(always)]
    pub(crate) fn costs_of(&self, edges: [[u32; 2]; 4]) -> [f64; 4] {
        // Optimal placement is single-pose only (`simplify_multipose` places on a subset).
        debug_assert!(self.params.placement == Placement::Optimal && self.params.metric == Metric::Quadric);
        debug_assert_eq!(self.pose_count, 1);
        let (a, b) = (four(|l| edges[l][0] as usize), four(|l| edges[l][1] as usize));
        // One slot count for both arrays (single pose: a quadric per slot), so that one
        // bounds check per vertex covers both.
        let positions = &self.positions[..];
        let quadrics = &self.quadrics[..positions.len()];
        let pa = Points::of(four(|l| &positions[a[l]]));
        let pb = Points::of(four(|l| &positions[b[l]]));
        let q = Quadric4::sums(four(|l| (&quadrics[a[l]], &quadrics[b[l]])));
        let (error_a, error_b) = (q.eval(&pa), q.eval(&pb));
        let half = Lanes::splat(0.5);
        let mid = Points { x: (pa.x + pb.x) * half, y: (pa.y + pb.y) * half, z: (pa.z + pb.z) * half };
        let reach = Lanes::splat(self.params.max_placement_distance) * pa.distance(&pb);
        let (p, solved) = q.minimiser();
        let near = p.distance(&mid).le(reach);
        // The lanes on the common path, both tests combined before the loop (−0.33 M
        // instructions on SCAPE against `solved[l] && near[l]` in it).
        let common = four(|l| solved[l] && near[l]);
        let error = q.eval(&p);
        let flags = &self.flags[..positions.len()];
        let mut costs = [0.0; 4];
        for (l, cost) in costs.iter_mut().enumerate() {
            let [a, b] = edges[l];
            if !common[l] || (flags[a as usize] | flags[b as usize]) & (FROZEN | PINNED) != 0 {
                *cost = self.cost_of(a, b);
                continue;
            }
            // `optimal_position`'s choice, and `cost_of`'s factors.
            let endpoint_error = if error_b.0[l] < error_a.0[l] { error_b.0[l] } else { error_a.0[l] };
            let error = error.0[l].max(0.0);
            let chosen = if beats_endpoint(error, endpoint_error) { error } else { endpoint_error.max(0.0) };
            let (pa, pb) = (&positions[a as usize], &positions[b as usize]);
            let factored = self.cost_factors(a, b, chosen, pa, pb);
            *cost = finite_or_infinity(factored);
            debug_assert_eq!(
                cost.to_bits(),
                self.cost_of(a, b).to_bits(),
                "four-lane cost of edge ({a}, {b})"
            );
        }
        costs
    }

    /// The endpoint the seam rule keeps when it lets only the other one go (`None`: both
    /// may go, or neither, which `check_seam_rule` refuses).
    #[inline]
    fn seam_keeps(&self, a: u32, b: u32) -> Option<u32> {
        self.seams.as_ref()?;
        match (self.seam_rule_lets_remove(a, b), self.seam_rule_lets_remove(b, a)) {
            (false, true) => Some(a),
            (true, false) => Some(b),
            _ => None,
        }
    }

    fn candidate_at(&self, a: u32, b: u32, position: Vec3, keep: u32) -> Candidate {
        let remove = if keep == a { b } else { a };
        let q = self.quadrics[a as usize] + self.quadrics[b as usize];
        Candidate { remove, keep, position, error: q.eval(&position).max(0.0), cost: 0.0 }
    }
}

/// Whether a computed placement with merged error `error` beats the better endpoint's
/// `endpoint_error` by more than rounding ([`SNAP_TOLERANCE`]): only then is the vertex
/// moved off its input position. The rule of `optimal_position` and of its lanes in
/// `costs_of`.
#[inline(always)]
fn beats_endpoint(error: f64, endpoint_error: f64) -> bool {
    endpoint_error > error * (1.0 + SNAP_TOLERANCE)
}

/// A ranked cost: finite, or `+inf` for an edge that may not collapse (NaN included).
#[inline(always)]
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

    use crate::classify::PINNED;
    use crate::collapse::Engine;
    use crate::config::{Metric, PartBorders, SimplifyConfig};

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
            let engine = Engine::new(&[mesh.positions.as_slice()], 0, &input, mesh.faces.clone(), &config);
            assert_eq!(engine.params.metric, Metric::Quadric);
            let (mut singular, mut pinned) = (0, 0);
            for group in edges.chunks_exact(4) {
                let group: [[u32; 2]; 4] = group.try_into().expect("four");
                let four = engine.costs_of(group);
                for (&[a, b], cost) in group.iter().zip(four) {
                    assert_eq!(
                        cost.to_bits(),
                        engine.cost_of(a, b).to_bits(),
                        "edge ({a}, {b}), mask {mask}: {cost}"
                    );
                    singular += usize::from(engine.quadrics[a as usize].minimiser().is_none());
                    pinned +=
                        usize::from((engine.flags[a as usize] | engine.flags[b as usize]) & PINNED != 0);
                }
            }
            assert!(singular > 0, "the flat part of the grid has singular quadrics");
            assert_eq!(pinned > 0, bit(3), "a locked border pins its vertices (mask {mask})");
        }
    }
}
