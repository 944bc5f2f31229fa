//! The edge-collapse engine: Garland and Heckbert 1997 ("Surface simplification using
//! quadric error metrics") with the cost of Zhao, Ngan and Li (paper §3.1, Eq. 5)
//! `E = d · (w1 + w2)/2 · v̄ᵀ(Q1 + Q2)v̄`, and Mohr and Gleicher 2003 ("Deformation
//! sensitive decimation") for quadrics summed over poses.
//!
//! The story, as [`run_engine`] tells it, in meshoptimizer's phase names:
//! 1. fill the face quadrics, classify every vertex and fill its quadric
//!    ([`Surface::new`], `classify.rs`);
//! 2. in passes until the target:
//!    - pick the live edges and rank them by cost in parallel
//!      ([`pick_and_rank_edge_collapses`], `edges.rs`: only the edges around the last
//!      pass's collapses are listed and costed again);
//!    - sort the cheap ones ([`sort_edge_collapses`], `sort.rs`);
//!    - choose in cost order those that share no endpoint, and perform them
//!      ([`perform_edge_collapses`], here), each evaluated again on the current surface
//!      (`placement.rs`) and re-checked against the safeguards (`safeguards.rs`: the seam
//!      rule, link condition, fold-over against the face itself and against its corners'
//!      input normals, degeneracy);
//! 3. compact the survivors into the output mesh ([`extract_output`]).
//!
//! Why passes and not a heap: the first version kept every edge in a binary heap with
//! lazy invalidation (stamps per vertex); profiling on SCAPE showed the loop stalled on
//! heap memory (8–9 pops per collapse, most of them stale, one cache miss per level)
//! at 5–8x meshoptimizer's time. meshoptimizer's pass-based ranking streams through
//! flat arrays instead and costs edges in parallel. A pass accepts collapses in cost
//! order up to the number still needed and up to a factor times the cost of the last
//! one needed (`sort.rs`), so it stays close to strict greedy order; within a pass, an
//! edge whose endpoint already moved is left for the next pass, so every cost used is
//! exact.
//!
//! Data layout: the [`Surface`]'s flat per-vertex arrays are indexed by the *slot*, which
//! is the input vertex index (`orig_idx`). The collapse loop is sequential, costing is an
//! order-preserving parallel map, and every tie is broken by vertex index, so the output
//! does not depend on the thread count.

use std::time::Instant;

use desal_mesh::{Progress, TriMesh, Vec3};

use crate::classify::{ALIVE, BOUNDARY, FROZEN, PINNED, SEAM};
use crate::config::{Params, SimplifyConfig, Target};
use crate::edges::{EdgeCosts, PassStamps, pick_and_rank_edge_collapses, upper_neighbours};
use crate::error::SimplifyError;
use crate::face_lists::FaceLists;
use crate::marks::ScratchMarks;
use crate::placement::{Candidate, evaluate};
use crate::report::{Refusal, Refusals, SimplifyReport, StopReason};
use crate::safeguards::{check_collapse, seam_rule_allows_either};
use crate::seams::SeamGraph;
use crate::sort::{Pass, SortedCollapses, sort_edge_collapses, unpack_edge};
use crate::surface::Surface;
use crate::types::{Simplified, SimplifyInput};

/// Marks a slot whose position is no longer any input vertex's (optimal placement).
const MOVED: u32 = u32::MAX;

/// Below this many undecided edges, [`choose_by_rounds`] sorts them and walks them.
const ROUNDS_MIN_EDGES: usize = 64;

/// [`choose_by_rounds`] stops its rounds when one decides fewer than one in this many of
/// the undecided edges.
const ROUNDS_MIN_DECIDED: usize = 4;

/// The orchestrator shared by single- and multi-pose simplification, on validated
/// input. `poses[p]` are the positions of pose `p` (one pose: `input.mesh.positions`);
/// `input.mesh` is pose `template`.
pub(crate) fn run_engine(
    poses: &[&[Vec3]],
    template: usize,
    input: &SimplifyInput<'_>,
    config: &SimplifyConfig,
    progress: &dyn Progress,
) -> Result<Simplified, SimplifyError> {
    let started = Instant::now();
    let mesh = input.mesh;
    // Faces that repeat a vertex have no area and no orientation: they carry nothing a
    // collapse could preserve.
    // Copied whole, then filtered in place: a filtered collect pushes face by face.
    let mut faces = mesh.faces.clone();
    faces.retain(|&[a, b, c]| a != b && b != c && a != c);
    if faces.is_empty() {
        return Err(SimplifyError::EmptyMesh { vertices: mesh.positions.len(), faces: 0 });
    }

    let mut engine = Engine::new(poses, template, input, faces, config);
    let mut marks = ScratchMarks::new(mesh.positions.len());
    let target = StopAt::new(config, engine.surface.lists.live_face_count());
    progress.begin("collapse edges", target.remaining(&engine) as u64);
    // The passes run on a rayon worker (inline when the caller is one): each pass's
    // parallel sweep is then forked inside the pool, where from the caller's thread it
    // is injected into the pool and the caller sleeps until a worker wakes it. Phase 1
    // stays on the caller's thread, for the peak memory. BENCHMARKS.md "Issue 18: wall
    // time on two cores" has the figures.
    rayon::scope(|_| run_passes(&mut engine, &target, &mut marks, progress));
    progress.finish();
    let stop = if target.reached(&engine) { StopReason::TargetReached } else { StopReason::NoValidCollapse };
    Ok(extract_output(engine, mesh, stop, started))
}

/// The passes, until the target or until no valid collapse is left.
fn run_passes(engine: &mut Engine, target: &StopAt, marks: &mut ScratchMarks, progress: &dyn Progress) {
    // A batched pass that achieves nothing (its cheapest choices were all refused) is
    // followed by an exhaustive one, which tries every edge in cost order; when that
    // achieves nothing either, no valid collapse is left.
    let mut pass = Pass::Batched;
    // Edges and costs of the previous pass, which the next listing reuses where nothing
    // changed (`edges.rs`).
    let mut previous = EdgeCosts::default();
    // A pass after one that performed nothing (every exhaustive pass) would list and
    // cost again exactly the edges and costs it has: nothing changed in between.
    let mut changed = true;
    while !target.reached(engine) {
        engine.stamps.begin_pass();
        let ranked = if changed {
            let previous = std::mem::take(&mut previous);
            pick_and_rank_edge_collapses(&engine.surface, &engine.params, &engine.stamps, previous)
        } else {
            std::mem::take(&mut previous)
        };
        let order = sort_edge_collapses(&ranked, target.remaining(engine), pass);
        let before = engine.tally.collapses;
        perform_edge_collapses(engine, order, target, pass, marks);
        progress.advance((engine.tally.collapses - before) as u64);
        previous = ranked;
        changed = engine.tally.collapses > before;
        pass = match (changed, pass) {
            (true, _) => Pass::Batched,
            (false, Pass::Batched) => Pass::Exhaustive,
            (false, Pass::Exhaustive) => break,
        };
    }
}

/// The state the phases share: the settings, the surface (which the phases read and a
/// collapse changes), the stamps that let a pass reuse the last one's listing, where
/// each slot's position came from, and the report's running figures.
#[derive(Debug)]
struct Engine {
    params: Params,
    surface: Surface,
    stamps: PassStamps,
    /// The input vertex whose exact position the slot holds, or `MOVED`.
    origin: Vec<u32>,
    tally: Tally,
}

/// The report's running figures.
#[derive(Debug)]
struct Tally {
    live_vertices: usize,
    collapses: usize,
    /// The sum and maximum of the collapses' RMS errors.
    error_sum: f64,
    error_max: f64,
    refusals: Refusals,
    /// Vertices frozen or pinned by phase 1, and vertices on a seam.
    locked_vertices: usize,
    seam_vertices: usize,
}

impl Engine {
    /// Phase 1 ([`Surface::new`]), and the engine's bookkeeping around it.
    fn new(
        poses: &[&[Vec3]],
        template: usize,
        input: &SimplifyInput<'_>,
        faces: Vec<[u32; 3]>,
        config: &SimplifyConfig,
    ) -> Self {
        let n = input.mesh.positions.len();
        let surface = Surface::new(poses, template, input, faces, config);
        let tally = Tally {
            live_vertices: (0..n as u32).filter(|&v| surface.lists.count(v) > 0).count(),
            collapses: 0,
            error_sum: 0.0,
            error_max: 0.0,
            refusals: Refusals::default(),
            locked_vertices: surface.flags.iter().filter(|&&f| f & (FROZEN | PINNED) != 0).count(),
            seam_vertices: surface
                .seams
                .as_ref()
                .map_or(0, |s| (0..n as u32).filter(|&v| !s.of(v).is_empty()).count()),
        };
        Engine {
            params: Params::new(config, poses.len()),
            surface,
            stamps: PassStamps::new(n),
            origin: (0..n as u32).collect(),
            tally,
        }
    }
}

/// The stopping rule: a face count or a vertex count.
#[derive(Debug)]
enum StopAt {
    Faces(usize),
    Vertices(usize),
}

impl StopAt {
    fn new(config: &SimplifyConfig, faces: usize) -> Self {
        match (config.target, config.target_faces(faces)) {
            (Target::Vertices(n), _) => StopAt::Vertices(n),
            (_, Some(n)) => StopAt::Faces(n),
            (_, None) => unreachable!("only a vertex target has no face count"),
        }
    }

    fn reached(&self, engine: &Engine) -> bool {
        match *self {
            StopAt::Faces(n) => engine.surface.lists.live_face_count() <= n,
            StopAt::Vertices(n) => engine.tally.live_vertices <= n,
        }
    }

    fn remaining(&self, engine: &Engine) -> usize {
        match *self {
            // Most collapses remove two faces; rounding up reaches an odd gap.
            StopAt::Faces(n) => engine.surface.lists.live_face_count().saturating_sub(n).div_ceil(2),
            StopAt::Vertices(n) => engine.tally.live_vertices.saturating_sub(n),
        }
    }
}

/// Pass, step 4 (meshoptimizer's `performEdgeCollapses`): perform the sorted collapses.
/// A batched pass chooses, in cost order, as many as are still needed with no endpoint
/// shared (a shared endpoint would make the later cost stale), then performs them in
/// vertex order. An exhaustive pass performs them in cost order, skipping edges with an
/// endpoint already changed. Each is re-checked against the surface as it is then.
///
/// Why a batched pass performs in vertex order: cost order jumps around the whole
/// mesh; on a million faces the loop then waits on memory at every step. The chosen
/// set is the same either way; only the order of mutually non-adjacent collapses
/// changes.
fn perform_edge_collapses(
    engine: &mut Engine,
    order: SortedCollapses,
    target: &StopAt,
    pass: Pass,
    marks: &mut ScratchMarks,
) {
    match pass {
        Pass::Batched => {
            let wanted = target.remaining(engine).max(1);
            // With seams, the walk in cost order, which refuses an edge the seam rule
            // refuses both ways before it holds its endpoints; without, the same choice
            // by rounds.
            let mut chosen = match &engine.surface.seams {
                Some(seams) => choose_in_cost_order(
                    order,
                    wanted,
                    &mut engine.stamps,
                    Some(seams),
                    &engine.surface.flags,
                    &mut engine.tally.refusals,
                ),
                None => choose_by_rounds(order.into_keys(), wanted, &mut engine.stamps, marks),
            };
            // `(lo, hi)` order: vertex order. Packed into one integer, which orders
            // like the pair and compares in one instruction where a pair takes a
            // lexicographic loop.
            chosen.sort_unstable();
            for [a, b] in chosen.into_iter().map(|packed| [(packed >> 32) as u32, packed as u32]) {
                if target.reached(engine) {
                    break;
                }
                try_collapse(engine, a, b, marks);
            }
        }
        Pass::Exhaustive => {
            for [a, b] in order.map(unpack_edge) {
                if target.reached(engine) {
                    break;
                }
                if engine.stamps.is_held(a) || engine.stamps.is_held(b) {
                    continue;
                }
                if try_collapse(engine, a, b, marks) {
                    engine.stamps.hold(a);
                    engine.stamps.hold(b);
                }
            }
        }
    }
}

/// A batched pass's choice: in cost order, up to `wanted` edges sharing no endpoint
/// (each chosen edge holds its endpoints for the pass), packed `lo << 32 | hi`. An edge
/// the seam rule refuses both ways counts in `refusals`.
fn choose_in_cost_order(
    order: SortedCollapses,
    wanted: usize,
    stamps: &mut PassStamps,
    seams: Option<&SeamGraph>,
    flags: &[u8],
    refusals: &mut Refusals,
) -> Vec<u64> {
    let mut chosen = Vec::with_capacity(wanted.min(order.len()));
    for [a, b] in order.map(unpack_edge) {
        if chosen.len() == wanted {
            break;
        }
        if stamps.is_held(a) || stamps.is_held(b) {
            continue;
        }
        // An edge the seam rule refuses both ways is refused before it holds its
        // endpoints for the pass: it would stay cheap, and block them in every one.
        if seams.is_some() && !seam_rule_allows_either(seams, flags, a, b) {
            refusals.count(Refusal::Seam);
            continue;
        }
        stamps.hold(a);
        stamps.hold(b);
        chosen.push(u64::from(a) << 32 | u64::from(b));
    }
    chosen
}

/// [`choose_in_cost_order`]'s choice (without seams), found without sorting every key.
/// An edge whose key is the smallest at both its endpoints among the edges still
/// undecided is one the in-order choice takes (every smaller edge at its endpoints was
/// dropped because a smaller one took its other endpoint), and an undecided edge at an
/// endpoint it takes is one it skips; so rounds of taking every such edge and dropping
/// their neighbours decide the same edges as the in-order walk. When a round decides
/// few edges (a run of ever cheaper edges decides one per round), the rest are sorted
/// and walked in order. The walk stops at `wanted` edges, so of all the edges taken,
/// the `wanted` cheapest are kept. `marks` is scratch: each slot's smallest edge in a
/// round.
fn choose_by_rounds(
    mut keys: Vec<u128>,
    wanted: usize,
    stamps: &mut PassStamps,
    marks: &mut ScratchMarks,
) -> Vec<u64> {
    // `keys[..taken]` are taken, `keys[taken..end]` undecided.
    let mut taken = 0;
    let mut end = keys.len();
    while end - taken > ROUNDS_MIN_EDGES {
        let live = &mut keys[taken..end];
        let base = marks.fresh_range(live.len());
        for (i, &key) in live.iter().enumerate() {
            let [a, b] = unpack_edge(key);
            for v in [a, b] {
                let best = marks.get(v);
                if best < base || live[(best - base) as usize] > key {
                    marks.set(v, base + i as u32);
                }
            }
        }
        let mut took = 0;
        for i in 0..live.len() {
            let [a, b] = unpack_edge(live[i]);
            let me = base + i as u32;
            if marks.get(a) == me && marks.get(b) == me {
                stamps.hold(a);
                stamps.hold(b);
                // `live[took]` was seen already: the swap moves no edge still to be
                // looked at.
                live.swap(took, i);
                took += 1;
            }
        }
        let mut kept = took;
        for i in took..live.len() {
            let [a, b] = unpack_edge(live[i]);
            if !stamps.is_held(a) && !stamps.is_held(b) {
                live[kept] = live[i];
                kept += 1;
            }
        }
        let decided = live.len() - (kept - took);
        let before = live.len();
        taken += took;
        end = taken + (kept - took);
        if decided * ROUNDS_MIN_DECIDED < before {
            break;
        }
    }
    keys[taken..end].sort_unstable();
    let undecided = taken..end;
    for i in undecided {
        let [a, b] = unpack_edge(keys[i]);
        if !stamps.is_held(a) && !stamps.is_held(b) {
            stamps.hold(a);
            stamps.hold(b);
            keys.swap(taken, i);
            taken += 1;
        }
    }
    let taken = &mut keys[..taken];
    if taken.len() > wanted {
        taken.select_nth_unstable(wanted - 1);
    }
    // The low 64 bits of a key are `lo << 32 | hi`.
    taken[..wanted.min(taken.len())].iter().map(|&key| key as u64).collect()
}

with_avx2_clone! {
    /// Evaluates edge `(a, b)` on the current surface (`placement.rs`), checks the
    /// safeguards (`safeguards.rs`) and performs the collapse; a refusal is counted.
    /// True when the collapse was performed. Compiled twice, its steps inlined by force
    /// so that the AVX2 clone runs them with its features (BENCHMARKS.md "Issue 40").
    fn try_collapse(engine: &mut Engine, a: u32, b: u32, marks: &mut ScratchMarks) -> bool {
        let Some(c) = evaluate(&engine.surface, &engine.params, a, b) else { return false };
        if let Err(refusal) = check_collapse(&engine.surface, &engine.params, c.remove, c.keep, &c.position, marks) {
            engine.tally.refusals.count(refusal);
            return false;
        }
        collapse_edge(engine, &c);
        true
    }
}

/// Performs a checked collapse: the faces on the edge die, `remove`'s other faces are
/// re-pointed to `keep`, the quadrics add up and `keep` moves; the slots whose edges or
/// costs change are stamped for the next listing (`edges.rs`). Inlined by force into
/// `try_collapse`'s clones (BENCHMARKS.md "Issue 40").
#[inline(always)]
fn collapse_edge(engine: &mut Engine, c: &Candidate) {
    let Engine { surface: s, stamps, origin, tally, .. } = engine;
    let (r, k) = (c.remove, c.keep);
    // Every vertex around `remove` gains `keep` or loses `remove` as a neighbour, and
    // `keep` gains `remove`'s neighbours. A slot's edges are only those to higher
    // slots, so only `keep` and the vertices below `remove` or `keep` change theirs.
    let changes_edges = r.max(k);
    for &f in s.lists.of(r) {
        for x in s.lists.face(f) {
            if x < changes_edges {
                stamps.touch(x);
            }
        }
    }
    stamps.touch(k);
    // `remove` loses all its edges.
    stamps.touch(r);
    s.lists.collapse(r, k);
    if let Some(seams) = &mut s.seams {
        seams.collapse(r, k);
    }
    let pc = s.pose_count;
    for p in 0..pc {
        let qr = s.quadrics[r as usize * pc + p];
        s.quadrics[k as usize * pc + p] += &qr;
    }
    if let Some(w) = &mut s.weights {
        w[k as usize] = w[k as usize].max(w[r as usize]);
    }
    let (ku, ru) = (k as usize, r as usize);
    // The seam rule only lets a seam vertex go into a seam vertex, so `keep` is one.
    debug_assert!(s.flags[ru] & SEAM == 0 || s.flags[ku] & (SEAM | PINNED) != 0);
    s.flags[ku] |= s.flags[ru] & BOUNDARY;
    s.flags[ru] &= !ALIVE;
    stamps.modify(k);
    if c.position != s.positions[ku] {
        origin[ku] = MOVED;
        s.positions[ku] = c.position;
    }

    let area: f64 = (0..pc).map(|p| s.quadrics[ku * pc + p].area).sum();
    let rms = if area > 0.0 { (c.error / area).sqrt() } else { 0.0 };
    tally.error_sum += rms;
    tally.error_max = tally.error_max.max(rms);
    tally.collapses += 1;
    tally.live_vertices -= 1;
}

/// Phase 3: the surviving vertices (in slot order) and faces (in input order).
fn extract_output(engine: Engine, mesh: &TriMesh, stop: StopReason, started: Instant) -> Simplified {
    let Engine { surface: s, origin, tally, .. } = engine;
    let n = s.positions.len();
    let mut simp_of_slot = vec![u32::MAX; n];
    let mut positions = Vec::with_capacity(tally.live_vertices);
    let mut simp_to_orig = Vec::with_capacity(tally.live_vertices);
    for (slot, simp) in simp_of_slot.iter_mut().enumerate() {
        if s.flags[slot] & ALIVE == 0 || s.lists.count(slot as u32) == 0 {
            continue;
        }
        *simp = positions.len() as u32;
        let origin = origin[slot];
        if origin == MOVED {
            positions.push(s.positions[slot] + s.center);
            simp_to_orig.push(None);
        } else {
            positions.push(mesh.positions[origin as usize]);
            simp_to_orig.push(Some(origin));
        }
    }
    let faces: Vec<[u32; 3]> = s.lists.live().map(|f| f.map(|v| simp_of_slot[v as usize])).collect();
    debug_assert!(faces.iter().flatten().all(|&v| (v as usize) < positions.len()));
    let (edge_length_mean, edge_length_variance) =
        output_edge_length_stats(&s.lists, &simp_of_slot, &positions);
    debug_assert_eq!(
        [edge_length_mean.to_bits(), edge_length_variance.to_bits()],
        {
            let (m, v) = desal_mesh::edge_length_stats(&positions, &faces);
            [m.to_bits(), v.to_bits()]
        },
        "the edge-length statistics differ from desal_mesh's"
    );
    let report = SimplifyReport {
        input_vertices: mesh.positions.len(),
        input_faces: mesh.faces.len(),
        output_vertices: positions.len(),
        output_faces: faces.len(),
        collapses: tally.collapses,
        stop,
        refusals: tally.refusals,
        locked_vertices: tally.locked_vertices,
        seam_vertices: tally.seam_vertices,
        max_error: tally.error_max,
        mean_error: if tally.collapses > 0 { tally.error_sum / tally.collapses as f64 } else { 0.0 },
        edge_length_mean,
        edge_length_variance,
        diagonal: mesh.diagonal(),
        seconds: started.elapsed().as_secs_f64(),
    };
    Simplified { mesh: TriMesh { positions, faces }, simp_to_orig, report }
}

/// [`desal_mesh::edge_length_stats`] of the output (`simp_of_slot`, `positions`: the
/// output's vertex numbering and positions), from the slots' upper neighbours: the
/// output's numbering keeps slot order, so slots ascending, each with its upper
/// neighbours ascending, are the unique edges in the sorted order that function sums
/// them in, and the figures are its own, bit for bit, without its sort of every
/// corner pair (BENCHMARKS.md "Issue 40").
fn output_edge_length_stats(lists: &FaceLists, simp_of_slot: &[u32], positions: &[Vec3]) -> (f64, f64) {
    let mut upper = Vec::with_capacity(16);
    let mut stats = desal_mesh::LengthStats::default();
    for v in 0..simp_of_slot.len() as u32 {
        let simp_v = simp_of_slot[v as usize];
        if simp_v == u32::MAX {
            continue;
        }
        for &x in upper_neighbours(lists, v, &mut upper) {
            let simp_x = simp_of_slot[x as usize] as usize;
            stats.add((positions[simp_v as usize] - positions[simp_x]).norm());
        }
    }
    stats.mean_variance()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sort::pack_collapse;

    /// The choice by rounds takes exactly the edges the walk in cost order takes, for
    /// scattered costs with many ties, for costs rising along the slots (runs of ever
    /// cheaper edges: few decided per round, so the sorted walk finishes), and for
    /// every cap on the number taken.
    #[test]
    fn choice_by_rounds_is_the_choice_in_cost_order() {
        let side = 24u32;
        let positions =
            (0..side * side).map(|i| Vec3::new(f64::from(i % side), f64::from(i / side), 0.0)).collect();
        let mesh = TriMesh { positions, faces: desal_testdata::golden::grid_faces(side, side) };
        let lists = FaceLists::new(mesh.positions.len(), mesh.faces.clone());
        let mut stamps = PassStamps::new(mesh.positions.len());
        let mut marks = ScratchMarks::new(mesh.positions.len());
        let mut upper = Vec::new();
        let edges: Vec<[u32; 2]> = (0..side * side)
            .flat_map(|v| {
                upper_neighbours(&lists, v, &mut upper).iter().map(move |&x| [v, x]).collect::<Vec<_>>()
            })
            .collect();
        let costings: [&dyn Fn(usize, [u32; 2]) -> f64; 3] = [
            &|i, _| ((i as u64 * 2_654_435_761) % 7) as f64,
            &|_, [lo, hi]| f64::from(lo) + 0.5 * f64::from(hi % 3),
            &|_, [lo, _]| f64::from(side * side - lo),
        ];
        let mut refusals = Refusals::default();
        for cost in costings {
            let keys: Vec<u128> =
                edges.iter().enumerate().map(|(i, &e)| pack_collapse(cost(i, e), e)).collect();
            for wanted in [1, 7, 50, 150, edges.len()] {
                stamps.begin_pass();
                let order = SortedCollapses::new(keys.clone(), keys.len());
                let mut in_order = choose_in_cost_order(order, wanted, &mut stamps, None, &[], &mut refusals);
                stamps.begin_pass();
                let mut by_rounds = choose_by_rounds(keys.clone(), wanted, &mut stamps, &mut marks);
                in_order.sort_unstable();
                by_rounds.sort_unstable();
                assert_eq!(by_rounds, in_order, "wanted {wanted}");
            }
        }
    }
}
