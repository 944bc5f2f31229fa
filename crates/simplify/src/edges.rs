//! A pass's steps 1 and 2, meshoptimizer's `pickEdgeCollapses` and `rankEdgeCollapses` in
//! one parallel sweep over the slots: every live edge of the [`Surface`] once, with its
//! cost, and what the sweep reuses from the previous pass's listing.
//!
//! **Layout.** An edge is listed at its lower end as `[lo, hi]`, `lo < hi`. The sweep's
//! work items are chunks of `CHUNK` consecutive slots, and a chunk keeps its edges as one
//! [`ChunkEdges`]: the `hi` of every edge, grouped by `lo` and ascending within a group,
//! its cost beside it (infinite when the edge may not collapse), and where each slot's
//! group starts. A pass's listing is its chunks in slot order ([`EdgeCosts`]). The sort
//! (`sort.rs`) reads the chunks in place, so the edges are never copied into one array
//! at the pass's peak memory, and an edge takes 4 bytes (its `hi`) where a pair takes 8.
//!
//! **Reuse from pass to pass.** Late passes change few slots, so the sweep lists again
//! only what the last pass changed. [`PassStamps`] record, for each slot, the pass in
//! which
//! - its edges last changed (`touched`): a slot not touched in the last pass keeps its
//!   group of edges. A run of consecutive such slots is copied from the last listing in
//!   one copy (a copy per slot cost more than the rest of their listing);
//! - its quadric, position, weight or flags last changed (`modified`): an edge neither of
//!   whose endpoints was modified in the last pass keeps its cost, since the quadric cost
//!   depends on the endpoints alone. Lindstrom–Turk's cost reads the faces around the
//!   edge, so with that metric every edge listed is costed again.
//!
//! A collapse (`collapse.rs`) stamps the slots it changes; stamps are never cleared, as a
//! stamp from an earlier pass is stale by its number. Each work item consumes its own
//! chunk of the last listing (a slot's old edges are in its own chunk), so two passes'
//! listings are never whole in memory together. So only the edges around the last
//! pass's collapses are listed and costed again.
//!
//! **Batching.** With optimal quadric placement, the edges waiting for a cost are gathered
//! four at a time ([`CostBatch`]) and costed in `f64` lanes ([`costs_of`]), which the
//! AVX2 clone of the sweep runs as vector instructions; otherwise each edge is costed at
//! once ([`cost_of`]). Each cost goes to its edge's place, so the batching changes no
//! order and no value.
//!
//! **Cursors.** Two pairs of runs are matched by a cursor that only moves forwards (a
//! binary search each cost more): a listed slot's new edges against its old ones (both
//! ascend; the old cost of each new edge), and in a copied run of slots, each edge against
//! the group starts (the slot of an edge whose `hi` was modified, to cost it again).

use std::ops::Range;

use rayon::prelude::*;

use crate::classify::{ALIVE, CHUNK, FROZEN};
use crate::config::{Metric, Params, Placement};
use crate::face_lists::FaceLists;
use crate::placement::{cost_of, costs_of};
use crate::surface::Surface;

/// The live edges of one pass and their costs, chunk by chunk in slot order (see the
/// module doc).
#[derive(Debug, Default)]
pub(crate) struct EdgeCosts {
    pub(crate) chunks: Vec<ChunkEdges>,
}

/// The edges whose `lo` is one of `CHUNK` consecutive slots, from slot `first` on.
#[derive(Debug, Default)]
pub(crate) struct ChunkEdges {
    pub(crate) first: u32,
    /// The `hi` of every edge, by `lo`, then ascending.
    pub(crate) his: Vec<u32>,
    /// The cost of every edge, finite or `+inf`.
    pub(crate) costs: Vec<f64>,
    /// `start[i]` indexes the first edge of slot `first + i`.
    pub(crate) start: Vec<u32>,
}

impl ChunkEdges {
    /// The `hi`s and costs of the edges of slot `first + i` (empty before the first
    /// pass).
    fn of(&self, i: usize) -> (&[u32], &[f64]) {
        let Some(&start) = self.start.get(i) else { return (&[], &[]) };
        let end = self.start.get(i + 1).map_or(self.his.len(), |&e| e as usize);
        (&self.his[start as usize..end], &self.costs[start as usize..end])
    }
}

/// For every slot, the pass in which something about it last changed (0: never), and
/// the current pass, counted from 1. Stamps are compared with a pass number, never
/// cleared.
#[derive(Debug)]
pub(crate) struct PassStamps {
    pass: u32,
    /// Its set of higher neighbours (its edges): its edges listed by earlier passes are
    /// stale.
    touched: Vec<u32>,
    /// Its quadric, position, weight or flags: its edges' costs from earlier passes are
    /// stale.
    modified: Vec<u32>,
    /// Held by an edge chosen or performed in the current pass (`collapse.rs`): its
    /// other edges wait for the next pass, whose costs see the change.
    held: Vec<u32>,
}

impl PassStamps {
    pub(crate) fn new(slots: usize) -> Self {
        Self { pass: 0, touched: vec![0; slots], modified: vec![0; slots], held: vec![0; slots] }
    }

    pub(crate) fn begin_pass(&mut self) {
        self.pass += 1;
    }

    /// Slot `v`'s edges change in this pass.
    #[inline]
    pub(crate) fn touch(&mut self, v: u32) {
        self.touched[v as usize] = self.pass;
    }

    /// Slot `v`'s quadric, position, weight or flags change in this pass.
    #[inline]
    pub(crate) fn modify(&mut self, v: u32) {
        self.modified[v as usize] = self.pass;
    }

    #[inline]
    pub(crate) fn hold(&mut self, v: u32) {
        self.held[v as usize] = self.pass;
    }

    #[inline]
    pub(crate) fn is_held(&self, v: u32) -> bool {
        self.held[v as usize] == self.pass
    }
}

/// Every live edge once, as `[lo, hi]` ascending, and its cost, reusing `previous`, the
/// last pass's listing, where nothing changed (see the module doc).
pub(crate) fn pick_and_rank_edge_collapses(
    surface: &Surface,
    params: &Params,
    stamps: &PassStamps,
    previous: EdgeCosts,
) -> EdgeCosts {
    let n = surface.positions.len();
    let have_previous = !previous.chunks.is_empty();
    let mut old_chunks = previous.chunks;
    old_chunks.resize_with(n.div_ceil(CHUNK), ChunkEdges::default);
    let chunks = old_chunks
        .into_par_iter()
        .enumerate()
        .map(|(chunk, old)| {
            let slots = (chunk * CHUNK) as u32..((chunk + 1) * CHUNK).min(n) as u32;
            list_chunk(surface, params, stamps, slots, old, have_previous)
        })
        .collect();
    EdgeCosts { chunks }
}

with_avx2_clone! {
    /// [`pick_and_rank_edge_collapses`] for the slots `slots`, from `old`, their edges in
    /// the last pass: each slot touched in the last pass is listed again, each run of
    /// untouched slots copied. A function of its own, with the surface a reference
    /// argument, not the body of the sweep's closure; compiled twice
    /// (see BENCHMARKS.md "Issue 40").
    fn list_chunk(
        surface: &Surface,
        params: &Params,
        stamps: &PassStamps,
        slots: Range<u32>,
        old: ChunkEdges,
        have_previous: bool,
    ) -> ChunkEdges {
        let sweep = Sweep {
            stamps,
            lists: &surface.lists,
            flags: &surface.flags,
            last: stamps.pass - 1,
            have_previous,
            reuse_costs: have_previous && params.metric == Metric::Quadric,
        };
        // The first pass lists each edge once, at its lower end: about three per slot on
        // a closed mesh, and 3⅛ leaves the chunks above the mean room (their vectors grew
        // at 3).
        let capacity = if have_previous { old.his.len() } else { 25 * slots.len() / 8 };
        let mut out = ChunkEdges {
            first: slots.start,
            his: Vec::with_capacity(capacity),
            costs: Vec::with_capacity(capacity),
            start: Vec::with_capacity(slots.len()),
        };
        let mut batch = CostBatch::new(surface, params);
        let mut upper: Vec<u32> = Vec::with_capacity(16);
        let mut v = slots.start;
        while v < slots.end {
            if sweep.touched(v) {
                sweep.list_slot(v, (v - slots.start) as usize, &old, &mut out, &mut batch, &mut upper);
                v += 1;
                continue;
            }
            let w = sweep.untouched_run_end(v, slots.end);
            let local = (v - slots.start) as usize..(w - slots.start) as usize;
            let copied = copy_runs(&old, &mut out, local.clone());
            sweep.cost_copied_again(&mut out, &mut batch, local.clone(), copied);
            #[cfg(debug_assertions)]
            sweep.check_copied_runs(&out, local, &mut upper);
            v = w;
        }
        batch.finish(&mut out.costs);
        out
    }
}

/// What every step of one chunk's listing reads.
struct Sweep<'a> {
    stamps: &'a PassStamps,
    lists: &'a FaceLists,
    flags: &'a [u8],
    /// The last pass: its changes are not in the old listing; earlier ones are.
    last: u32,
    /// Whether there is an old listing (every pass but the first).
    have_previous: bool,
    /// Whether an edge whose endpoints were not modified in the last pass keeps its old
    /// cost (the quadric metric).
    reuse_costs: bool,
}

impl Sweep<'_> {
    /// Whether slot `v`'s edges must be listed again.
    #[inline]
    fn touched(&self, v: u32) -> bool {
        !self.have_previous || self.stamps.touched[v as usize] >= self.last
    }

    /// Whether neither `a` nor `b` was modified in the last pass.
    #[inline]
    fn unchanged(&self, a: u32, b: u32) -> bool {
        self.stamps.modified[a as usize] < self.last && self.stamps.modified[b as usize] < self.last
    }

    /// Lists slot `v` (`i` in the chunk) again: its edges to higher live neighbours, each
    /// with its old cost when it was listed before and is unchanged, else costed.
    /// Inlined by force into `list_chunk`'s clones (BENCHMARKS.md "Issue 40").
    #[inline(always)]
    fn list_slot(
        &self,
        v: u32,
        i: usize,
        old: &ChunkEdges,
        out: &mut ChunkEdges,
        batch: &mut CostBatch<'_>,
        upper: &mut Vec<u32>,
    ) {
        out.start.push(out.his.len() as u32);
        if self.flags[v as usize] & (ALIVE | FROZEN) != ALIVE {
            return;
        }
        let (old_his, old_costs) = old.of(i);
        // Both runs ascend: the cursor `j` finds the old edge of each new one.
        let mut j = 0;
        for &x in upper_neighbours(self.lists, v, upper).iter() {
            while j < old_his.len() && old_his[j] < x {
                j += 1;
            }
            let listed = j < old_his.len() && old_his[j] == x;
            let reused = (listed && self.reuse_costs && self.unchanged(v, x)).then(|| old_costs[j]);
            out.his.push(x);
            out.costs.push(reused.unwrap_or(f64::NAN));
            if reused.is_none() {
                batch.cost(&mut out.costs, v, x);
            }
        }
    }

    /// The end of the run of slots from `v` (untouched) that were not touched in the last
    /// pass, within the chunk (`end`).
    #[inline]
    fn untouched_run_end(&self, v: u32, end: u32) -> u32 {
        let after = &self.stamps.touched[v as usize + 1..end as usize];
        v + 1 + after.iter().position(|&t| t >= self.last).unwrap_or(after.len()) as u32
    }

    /// Costs again the edges of `copied` (the edges of the chunk's slots `local`) whose
    /// `hi` was modified in the last pass (every one without cost reuse); a slot not
    /// touched in the last pass was not modified in it either.
    /// Inlined by force into `list_chunk`'s clones (BENCHMARKS.md "Issue 40").
    #[inline(always)]
    fn cost_copied_again(
        &self,
        out: &mut ChunkEdges,
        batch: &mut CostBatch<'_>,
        local: Range<usize>,
        copied: Range<usize>,
    ) {
        // The slot of edge `e`, found by a cursor that only moves forwards.
        let mut slot = local.start;
        for e in copied {
            let x = out.his[e];
            if self.reuse_costs && self.stamps.modified[x as usize] < self.last {
                continue;
            }
            while slot + 1 < local.end && out.start[slot + 1] as usize <= e {
                slot += 1;
            }
            batch.cost_at(&mut out.costs, e, out.first + slot as u32, x);
        }
    }

    /// Debug builds: the copied runs are what listing the slots `local` would give.
    #[cfg(debug_assertions)]
    fn check_copied_runs(&self, out: &ChunkEdges, local: Range<usize>, upper: &mut Vec<u32>) {
        for k in local {
            let u = out.first + k as u32;
            let run = out.start[k] as usize..out.start.get(k + 1).map_or(out.his.len(), |&e| e as usize);
            debug_assert!(self.stamps.modified[u as usize] < self.last);
            if self.flags[u as usize] & (ALIVE | FROZEN) == ALIVE {
                debug_assert_eq!(upper_neighbours(self.lists, u, upper), &out.his[run]);
            } else {
                debug_assert!(run.is_empty());
            }
        }
    }
}

/// Appends to `out` the old edges and costs of the chunk's slots `local` (untouched in
/// the last pass), their group starts shifted to `out`'s; returns where the copied edges
/// are in `out`.
#[inline]
fn copy_runs(old: &ChunkEdges, out: &mut ChunkEdges, local: Range<usize>) -> Range<usize> {
    let (i, j) = (local.start, local.end);
    let from = old.start[i] as usize;
    let to = old.start.get(j).map_or(old.his.len(), |&e| e as usize);
    let base = out.his.len();
    // In `u32`, wrapping (the shift may be either way): one vector add for four slots.
    let shift = (base as u32).wrapping_sub(from as u32);
    out.start.extend(old.start[i..j].iter().map(|&s| s.wrapping_add(shift)));
    out.his.extend_from_slice(&old.his[from..to]);
    out.costs.extend_from_slice(&old.costs[from..to]);
    base..out.his.len()
}

/// The neighbours of `v` with a higher index, ascending, in `upper`: slot `v`'s edges. A
/// vertex has few neighbours: insertion into a sorted run beats collecting, sorting and
/// deduplicating, and the run is short enough that a linear scan from its end finds the
/// place (`Vec::insert` and a binary search cost a `memmove` call and a loop each).
/// Inlined by force into `list_chunk`'s clones (BENCHMARKS.md "Issue 40").
#[inline(always)]
pub(crate) fn upper_neighbours<'a>(lists: &FaceLists, v: u32, upper: &'a mut Vec<u32>) -> &'a [u32] {
    upper.clear();
    for &f in lists.of(v) {
        for x in lists.face(f) {
            if x <= v {
                continue;
            }
            let mut at = upper.len();
            while at > 0 && upper[at - 1] > x {
                at -= 1;
            }
            if at > 0 && upper[at - 1] == x {
                continue;
            }
            upper.push(x);
            // On a slice: through the `Vec` its length is read again at every step.
            let run = upper.as_mut_slice();
            for i in (at + 1..run.len()).rev() {
                run[i] = run[i - 1];
            }
            run[at] = x;
        }
    }
    upper
}

/// Edges of the listing sweep waiting to be costed four at a time by [`costs_of`]
/// (optimal quadric placement; otherwise each is costed at once by [`cost_of`]): lane
/// `l` is edge `edges[l]`, whose cost goes to `costs[at[l]]`.
struct CostBatch<'a> {
    surface: &'a Surface,
    params: &'a Params,
    four: bool,
    edges: [[u32; 2]; 4],
    at: [usize; 4],
    len: usize,
}

impl<'a> CostBatch<'a> {
    fn new(surface: &'a Surface, params: &'a Params) -> Self {
        let four = params.placement == Placement::Optimal && params.metric == Metric::Quadric;
        Self { surface, params, four, edges: [[0; 2]; 4], at: [0; 4], len: 0 }
    }

    /// Costs edge `(a, b)` into the last entry of `costs`.
    #[inline]
    fn cost(&mut self, costs: &mut [f64], a: u32, b: u32) {
        self.cost_at(costs, costs.len() - 1, a, b);
    }

    /// Costs edge `(a, b)` into `costs[at]`, now or once four are waiting. Inlined by
    /// force into `list_chunk`'s clones (BENCHMARKS.md "Issue 40").
    #[inline(always)]
    fn cost_at(&mut self, costs: &mut [f64], at: usize, a: u32, b: u32) {
        if !self.four {
            costs[at] = cost_of(self.surface, self.params, a, b);
            return;
        }
        // `& 3` (a no-op: `len < 4` here) spares the two bounds checks.
        let i = self.len & 3;
        self.edges[i] = [a, b];
        self.at[i] = at;
        self.len = i + 1;
        if self.len == 4 {
            let four = costs_of(self.surface, self.params, self.edges);
            for (&at, cost) in self.at.iter().zip(four) {
                costs[at] = cost;
            }
            self.len = 0;
        }
    }

    /// Costs the edges still waiting (fewer than four), one by one.
    fn finish(&mut self, costs: &mut [f64]) {
        for (&[a, b], &at) in self.edges.iter().zip(&self.at).take(self.len) {
            costs[at] = cost_of(self.surface, self.params, a, b);
        }
        self.len = 0;
    }
}
