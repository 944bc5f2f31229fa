//! A pass's step 3, meshoptimizer's `sortEdgeCollapses`: the ranked edges this pass may
//! perform, cheapest first, each packed with its cost into one integer. A batched pass
//! keeps the edges up to a cost limit, found by a selection over the costs' binades
//! ([`nth_smallest_cost`]), and takes them all; an exhaustive pass keeps every finite
//! cost and sorts only as far as it takes ([`SortedCollapses`]).

use crate::edges::EdgeCosts;

/// A pass accepts collapses costing up to this factor times the cost of the last
/// collapse still needed (meshoptimizer uses 1.5): many cheap candidates are skipped
/// because a neighbour went first, so the limit must exceed the needed-th cost, but a
/// small factor keeps the order close to strict greedy.
const PASS_ERROR_FACTOR: f64 = 1.5;

/// A pass never aims at more than this fraction of the collapses still needed, so that
/// early passes (when almost everything is cheap) do not flatten the greedy order.
const PASS_GOAL_FRACTION: f64 = 0.5;

/// How a pass performs its ranked collapses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Pass {
    /// Cost-limited, chosen in cost order, performed in vertex order (fast).
    Batched,
    /// Every edge, performed in cost order (when a batched pass got stuck).
    Exhaustive,
}

with_avx2_clone! {
    /// Pass, step 3: the edges this pass may perform, cheapest first (ties by `(lo, hi)`),
    /// each packed by [`pack_collapse`]. A batched pass keeps only costs up to
    /// `PASS_ERROR_FACTOR` times the cost of the `needed`-th cheapest (capped by
    /// `PASS_GOAL_FRACTION`) and takes them all; an exhaustive one keeps every finite cost
    /// and stops at the target, usually early (SCAPE → 5000: after 1006 of 8878), so its
    /// order is sorted as it is taken. Compiled twice (BENCHMARKS.md "Issue 40").
    pub(crate) fn sort_edge_collapses(ranked: &EdgeCosts, needed: usize, pass: Pass) -> SortedCollapses {
        let count = ranked.chunks.iter().map(|c| c.costs.len()).sum::<usize>();
        let mut limit = f64::INFINITY;
        if pass == Pass::Batched && count > 0 {
            let goal = ((needed as f64 * PASS_GOAL_FRACTION).ceil() as usize).clamp(1, count);
            limit = nth_smallest_cost(ranked, goal - 1) * PASS_ERROR_FACTOR;
        }
        // Every ranked cost is finite or +inf (`cost_of`), so "finite and at most `limit`"
        // is one comparison with `limit`, or with the largest finite value when `limit` is
        // infinite.
        let bound = if limit == f64::INFINITY { f64::MAX } else { limit };
        // Allocated once for every edge: no growth copies. The pages past the kept edges
        // are never written, so they cost address space, not memory (geo_1m's peak RSS
        // did not move); counting the kept edges first cost more (BENCHMARKS.md "Issue 40").
        let mut order: Vec<u128> = Vec::with_capacity(count);
        for c in &ranked.chunks {
            // Most edges fail the limit: the slot of a kept edge is found by a cursor that
            // only moves forwards, not by a walk through every slot's run.
            let mut slot = 0;
            for (j, (&hi, &cost)) in c.his.iter().zip(&c.costs).enumerate() {
                debug_assert!(cost.is_finite() || cost == f64::INFINITY, "ranked cost {cost}");
                if cost <= bound {
                    while c.start.get(slot + 1).is_some_and(|&next| next as usize <= j) {
                        slot += 1;
                    }
                    order.push(pack_collapse(cost, [c.first + slot as u32, hi]));
                }
            }
        }
        let first_batch = match pass {
            Pass::Batched => order.len(),
            Pass::Exhaustive => EXHAUSTIVE_FIRST_BATCH,
        };
        SortedCollapses::new(order, first_batch)
    }
}

/// The first batch an exhaustive pass sorts; each later one is twice the last, so the
/// selections that split the batches off cost a few sweeps of the order in all.
const EXHAUSTIVE_FIRST_BATCH: usize = 1024;

/// Packed collapses taken in ascending order, sorted a batch at a time: the batch's
/// smallest keys are selected out of the rest, then sorted. The keys are distinct (each
/// holds its edge), so the order taken is the full sort's.
#[derive(Debug)]
pub(crate) struct SortedCollapses {
    keys: Vec<u128>,
    /// `keys[..sorted]` are sorted and smaller than every later key.
    sorted: usize,
    /// The next key to take.
    next: usize,
    /// The size of the next batch.
    batch: usize,
}

impl SortedCollapses {
    /// `keys` (distinct), to be taken in ascending order, the first `batch` sorted first.
    pub(crate) fn new(keys: Vec<u128>, batch: usize) -> Self {
        Self { keys, sorted: 0, next: 0, batch }
    }

    pub(crate) fn len(&self) -> usize {
        self.keys.len()
    }

    /// The keys, in no particular order.
    pub(crate) fn into_keys(self) -> Vec<u128> {
        self.keys
    }
}

impl Iterator for SortedCollapses {
    type Item = u128;

    fn next(&mut self) -> Option<u128> {
        if self.next == self.sorted && self.sorted < self.keys.len() {
            let rest = &mut self.keys[self.sorted..];
            let batch = self.batch.min(rest.len());
            if batch < rest.len() {
                rest.select_nth_unstable(batch - 1);
            }
            rest[..batch].sort_unstable();
            self.sorted += batch;
            self.batch *= 2;
        }
        let key = *self.keys.get(self.next)?;
        self.next += 1;
        Some(key)
    }
}

/// Bits of a cost's [`total_order_key`] (sign and exponent) that pick its bucket in
/// [`nth_smallest_cost`].
const BUCKET_BITS: u32 = 12;

/// The `n`-th smallest of all ranked costs (from 0), in `f64::total_cmp`'s order,
/// exactly. Counting the costs per binade finds the binade that holds it; only that
/// binade's costs are copied and selected in, so the pass's peak memory is not a copy
/// of every cost (12 MB on a million faces). The counts are `u32`s on the stack (16 KB;
/// a heap vector per call cost more, BENCHMARKS.md "Issue 40"): 2³² edges would take
/// 2.9 G faces, 34 GB of indices alone.
fn nth_smallest_cost(ranked: &EdgeCosts, n: usize) -> f64 {
    let bucket = |cost: f64| (total_order_key(cost) >> (64 - BUCKET_BITS)) as usize;
    let mut counts = [0u32; 1 << BUCKET_BITS];
    for c in &ranked.chunks {
        for &cost in &c.costs {
            counts[bucket(cost)] += 1;
        }
    }
    let mut below = 0;
    let mut target = 0;
    for (b, &count) in counts.iter().enumerate() {
        if below + count as usize > n {
            target = b;
            break;
        }
        below += count as usize;
    }
    let mut keys: Vec<u64> = Vec::with_capacity(counts[target] as usize);
    for c in &ranked.chunks {
        // Each key computed once, its bucket read off it.
        keys.extend(
            c.costs
                .iter()
                .map(|&cost| total_order_key(cost))
                .filter(|&key| (key >> (64 - BUCKET_BITS)) as usize == target),
        );
    }
    let (_, &mut nth, _) = keys.select_nth_unstable(n - below);
    from_total_order_key(nth)
}

/// One ranked collapse as one integer that orders by cost, then by `(lo, hi)`: a
/// non-negative finite f64's bit pattern orders like its value (bits 64..128), and
/// `(lo, hi)` packed below orders like the pair. One integer comparison per step of
/// the sort, where a tuple needs two.
#[inline]
pub(crate) fn pack_collapse(cost: f64, [lo, hi]: [u32; 2]) -> u128 {
    (u128::from(cost.to_bits()) << 64) | (u128::from(lo) << 32) | u128::from(hi)
}

/// The edge of a [`pack_collapse`]d collapse.
#[inline]
pub(crate) fn unpack_edge(packed: u128) -> [u32; 2] {
    [(packed >> 32) as u32, packed as u32]
}

/// The unsigned integer whose order is `f64::total_cmp`'s: the transform `total_cmp`
/// applies, with the sign bit flipped so that negative values come first.
#[inline]
fn total_order_key(x: f64) -> u64 {
    let bits = x.to_bits() as i64;
    (bits ^ ((((bits >> 63) as u64) >> 1) as i64)) as u64 ^ (1 << 63)
}

/// The inverse of [`total_order_key`].
#[inline]
fn from_total_order_key(key: u64) -> f64 {
    let key = (key ^ (1 << 63)) as i64;
    f64::from_bits((key ^ ((((key >> 63) as u64) >> 1) as i64)) as u64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::edges::ChunkEdges;

    /// Sorted a batch at a time (batches of 1024, 2048, ...), 5000 distinct keys come out
    /// in the full sort's order.
    #[test]
    fn collapses_sorted_in_batches_come_out_fully_sorted() {
        let keys: Vec<u128> = (0..5000u128).map(|i| (i * 2_654_435_761) % 1_000_003).collect();
        let mut sorted = keys.clone();
        sorted.sort_unstable();
        let batched = SortedCollapses::new(keys, EXHAUSTIVE_FIRST_BATCH);
        assert_eq!(batched.collect::<Vec<_>>(), sorted);
    }

    /// The binade-bucketed selection returns exactly what sorting every cost by
    /// `total_cmp` returns at each rank, infinite and zero costs (of both signs)
    /// included, over costs split into several chunks.
    #[test]
    fn nth_smallest_cost_matches_a_full_sort() {
        let costs: Vec<f64> = (0..500u64)
            .map(|i| match i % 7 {
                0 => f64::INFINITY,
                1 => 0.0,
                2 => -0.0,
                _ => ((i * 2_654_435_761) % 1000) as f64 * 10f64.powi((i % 13) as i32 - 6),
            })
            .collect();
        let ranked = EdgeCosts {
            chunks: costs
                .chunks(64)
                .map(|c| ChunkEdges { costs: c.to_vec(), ..ChunkEdges::default() })
                .collect(),
        };
        let mut sorted = costs.clone();
        sorted.sort_by(f64::total_cmp);
        for (n, expected) in sorted.iter().enumerate() {
            assert_eq!(nth_smallest_cost(&ranked, n).to_bits(), expected.to_bits(), "rank {n}");
        }
    }
}
