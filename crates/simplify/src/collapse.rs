//! The edge-collapse engine: Garland and Heckbert 1997 ("Surface simplification using
//! quadric error metrics") with the cost of Zhao, Ngan and Li (paper §3.1, Eq. 5)
//! `E = d · (w1 + w2)/2 · v̄ᵀ(Q1 + Q2)v̄`, and Mohr and Gleicher 2003 ("Deformation
//! sensitive decimation") for quadrics summed over poses.
//!
//! The story, as [`run_engine`] tells it: fill the face quadrics, classify every vertex
//! and fill its quadric (`classify.rs`); then, in passes until the target: pick the live
//! edges, rank them by cost in parallel, four edges at a time in `f64` lanes
//! (`Engine::costs_of`; an edge with no endpoint changed by the last pass keeps its
//! cost: the quadric cost depends on the endpoints alone), sort the cheap
//! ones, choose in cost order those that share no endpoint, and perform them, each
//! evaluated again on the current mesh (`placement.rs`) and re-checked against the
//! safeguards (`safeguards.rs`: the seam rule, link condition, fold-over against
//! the face itself and against its corners' input normals, degeneracy); finally compact
//! the survivors into the output mesh. The phase names are meshoptimizer's
//! (`pickEdgeCollapses`, `rankEdgeCollapses`, `sortEdgeCollapses`,
//! `performEdgeCollapses`).
//!
//! Why passes and not a heap: the first version kept every edge in a binary heap with
//! lazy invalidation (stamps per vertex); profiling on SCAPE showed the loop stalled on
//! heap memory (8–9 pops per collapse, most of them stale, one cache miss per level)
//! at 5–8x meshoptimizer's time. meshoptimizer's pass-based ranking streams through
//! flat arrays instead and costs edges in parallel. A pass accepts collapses in cost
//! order up to the number still needed and up to `PASS_ERROR_FACTOR` times the cost of
//! the last one needed, so it stays close to strict greedy order; within a pass, an edge
//! whose endpoint already moved is left for the next pass, so every cost used is exact.
//!
//! Data layout: positions, quadrics and flags are flat per-vertex arrays indexed by the
//! *slot*, which is the input vertex index (`orig_idx`); the faces and every slot's face
//! list are a [`FaceLists`]. The collapse loop is sequential, costing is an
//! order-preserving parallel map, and every tie is broken by vertex index, so the output
//! does not depend on the thread count.

use std::time::Instant;

use desal_mesh::{Progress, TriMesh, Vec3};
use rayon::prelude::*;

use crate::classify::{
    ALIVE, BOUNDARY, CHUNK, ClassifyInput, FROZEN, PINNED, SEAM, classify_vertices, compute_input_normals,
    compute_vertex_normals, fill_face_planes,
};
use crate::config::{Metric, Placement, SimplifyConfig, Target};
use crate::error::SimplifyError;
use crate::face_lists::FaceLists;
use crate::marks::ScratchMarks;
use crate::quadric::Quadric;
use crate::report::{Refusal, Refusals, SimplifyReport, StopReason};
use crate::seams::SeamGraph;
use crate::types::{Simplified, SimplifyInput};

/// A pass accepts collapses costing up to this factor times the cost of the last
/// collapse still needed (meshoptimizer uses 1.5): many cheap candidates are skipped
/// because a neighbour went first, so the limit must exceed the needed-th cost, but a
/// small factor keeps the order close to strict greedy.
const PASS_ERROR_FACTOR: f64 = 1.5;

/// A pass never aims at more than this fraction of the collapses still needed, so that
/// early passes (when almost everything is cheap) do not flatten the greedy order.
const PASS_GOAL_FRACTION: f64 = 0.5;

/// Marks a slot whose position is no longer any input vertex's (optimal placement).
const MOVED: u32 = u32::MAX;

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
    let target = StopAt::new(config, engine.lists.live_face_count());
    progress.begin("collapse edges", target.remaining(&engine) as u64);
    // The passes run on a rayon worker (inline when the caller is one): each pass's
    // parallel sweep is then forked inside the pool, where from the caller's thread it
    // is injected into the pool and the caller sleeps until a worker wakes it (SCAPE at
    // 2 threads, paired runs: −2 % wall; −0.04 M instructions; geo_1m's peak RSS −2 MB,
    // the passes' vectors coming from the worker's allocator arena). Phase 1 stays on
    // the caller's thread: on a worker its arrays came from that arena too, and geo_1m's
    // peak grew by 5 to 16 MB.
    rayon::scope(|_| run_passes(&mut engine, &target, &mut marks, progress));
    progress.finish();
    let stop = if target.reached(&engine) { StopReason::TargetReached } else { StopReason::NoValidCollapse };
    Ok(engine.extract_output(mesh, stop, started))
}

/// The passes, until the target or until no valid collapse is left.
fn run_passes(engine: &mut Engine, target: &StopAt, marks: &mut ScratchMarks, progress: &dyn Progress) {
    // A batched pass that achieves nothing (its cheapest choices were all refused) is
    // followed by an exhaustive one, which tries every edge in cost order; when that
    // achieves nothing either, no valid collapse is left.
    let mut pass = Pass::Batched;
    // Edges and costs of the previous pass: a slot whose neighbours did not change
    // since keeps its edges, an edge whose endpoints did not change keeps its quadric
    // cost (Lindstrom–Turk's reads the faces around the edge: it is always recomputed).
    let mut previous = EdgeCosts::default();
    // A pass after one that performed nothing (every exhaustive pass) would list and
    // cost again exactly the edges and costs it has: nothing changed in between.
    let mut changed = true;
    while !target.reached(engine) {
        engine.pass += 1;
        let ranked = if changed {
            engine.pick_and_rank_edge_collapses(std::mem::take(&mut previous))
        } else {
            std::mem::take(&mut previous)
        };
        let order = sort_edge_collapses(&ranked, target.remaining(engine), pass);
        let before = engine.collapses;
        engine.perform_edge_collapses(order, target, pass, marks);
        progress.advance((engine.collapses - before) as u64);
        previous = ranked;
        changed = engine.collapses > before;
        pass = match (changed, pass) {
            (true, _) => Pass::Batched,
            (false, Pass::Batched) => Pass::Exhaustive,
            (false, Pass::Exhaustive) => break,
        };
    }
}

with_avx2_clone! {
    /// [`Engine::list_chunk`], inlined by force into both clones (−6.3 M instructions on
    /// SCAPE, counted by cachegrind on the AVX2 clone).
    fn list_chunk(
        engine: &Engine,
        slots: std::ops::Range<u32>,
        old: ChunkEdges,
        have_previous: bool,
    ) -> ChunkEdges {
        engine.list_chunk(slots, old, have_previous)
    }

    /// [`Engine::try_collapse`]. Its steps (placement, safeguards, the collapse) are
    /// inlined by force into both clones so that the AVX2 one runs them with its
    /// features: −2.3 M instructions on SCAPE; `FaceLists::collapse` stays a call
    /// (inlined too, +1.7 M).
    fn try_collapse(engine: &mut Engine, a: u32, b: u32, marks: &mut ScratchMarks) -> bool {
        engine.try_collapse(a, b, marks)
    }
}

/// Edges of the listing sweep waiting to be costed four at a time by
/// [`Engine::costs_of`] (optimal quadric placement; otherwise each is costed at once by
/// [`Engine::cost_of`]): lane `l` is edge `edges[l]`, whose cost goes to `costs[at[l]]`.
struct CostBatch {
    four: bool,
    edges: [[u32; 2]; 4],
    at: [usize; 4],
    len: usize,
}

impl CostBatch {
    fn new(four: bool) -> Self {
        Self { four, edges: [[0; 2]; 4], at: [0; 4], len: 0 }
    }

    /// Costs edge `(a, b)` into the last entry of `costs`.
    #[inline(always)]
    fn cost(&mut self, engine: &Engine, costs: &mut [f64], a: u32, b: u32) {
        self.cost_at(engine, costs, costs.len() - 1, a, b);
    }

    /// Costs edge `(a, b)` into `costs[at]`, now or once four are waiting.
    #[inline(always)]
    fn cost_at(&mut self, engine: &Engine, costs: &mut [f64], at: usize, a: u32, b: u32) {
        if !self.four {
            costs[at] = engine.cost_of(a, b);
            return;
        }
        // `& 3` (a no-op: `len < 4` here) spares the two bounds checks.
        let i = self.len & 3;
        self.edges[i] = [a, b];
        self.at[i] = at;
        self.len = i + 1;
        if self.len == 4 {
            let four = engine.costs_of(self.edges);
            for (&at, cost) in self.at.iter().zip(four) {
                costs[at] = cost;
            }
            self.len = 0;
        }
    }

    /// Costs the edges still waiting (fewer than four), one by one.
    fn finish(&mut self, engine: &Engine, costs: &mut [f64]) {
        for (&[a, b], &at) in self.edges.iter().zip(&self.at).take(self.len) {
            costs[at] = engine.cost_of(a, b);
        }
        self.len = 0;
    }
}

/// How a pass performs its ranked collapses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Pass {
    /// Cost-limited, chosen in cost order, performed in vertex order (fast).
    Batched,
    /// Every edge, performed in cost order (when a batched pass got stuck).
    Exhaustive,
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
            StopAt::Faces(n) => engine.lists.live_face_count() <= n,
            StopAt::Vertices(n) => engine.live_vertices <= n,
        }
    }

    fn remaining(&self, engine: &Engine) -> usize {
        match *self {
            // Most collapses remove two faces; rounding up reaches an odd gap.
            StopAt::Faces(n) => engine.lists.live_face_count().saturating_sub(n).div_ceil(2),
            StopAt::Vertices(n) => engine.live_vertices.saturating_sub(n),
        }
    }
}

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

/// The live edges of one pass, `[lo, hi]` ascending, and the cost of each (infinite
/// when the edge may not collapse), kept in the chunks of slots that listed them: one
/// pass over the edges fewer, and no second copy at the pass's peak memory. An edge is
/// stored as its `hi` alone, under its `lo`'s run (4 bytes where a pair takes 8).
#[derive(Debug, Default)]
struct EdgeCosts {
    chunks: Vec<ChunkEdges>,
}

/// The edges whose `lo` is one of `CHUNK` consecutive slots, from slot `first` on.
#[derive(Debug, Default)]
struct ChunkEdges {
    first: u32,
    /// The `hi` of every edge, by `lo`, then ascending.
    his: Vec<u32>,
    costs: Vec<f64>,
    /// `start[i]` indexes the first edge of slot `first + i`.
    start: Vec<u32>,
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

/// Settings the inner loop reads, derived once from the config.
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

/// All mutable state of one simplification (see the module doc for the layout).
#[derive(Debug)]
pub(crate) struct Engine {
    pub(crate) params: Params,
    pub(crate) pose_count: usize,
    /// Subtracted from every input position for precision; added back on output.
    center: Vec3,
    /// Current template positions, local coordinates, by slot.
    pub(crate) positions: Vec<Vec3>,
    /// Multi-pose only: local positions of every pose, `[pose][slot]` (never move).
    pub(crate) pose_positions: Vec<Vec<Vec3>>,
    /// `quadrics[slot * pose_count + pose]`.
    pub(crate) quadrics: Vec<Quadric>,
    /// Saliency weight per slot, when the saliency factor is on. A merged vertex takes
    /// the larger weight of the two, so salient detail is never diluted by absorbing a
    /// cheap neighbour.
    pub(crate) weights: Option<Vec<f64>>,
    /// Keep penalty per slot (subset placement; [`SimplifyInput::keep_penalty`]). A slot
    /// always holds the input vertex it started with, so the input's array serves.
    pub(crate) keep_penalty: Option<Vec<f64>>,
    pub(crate) lists: FaceLists,
    /// Unnormalised normal of every input face in the template: a collapse may not
    /// turn a face past the threshold from it either, since small steps add up.
    pub(crate) input_normals: Vec<Vec3>,
    /// Unit area-weighted normal of every input vertex (template pose): the local
    /// surface orientation where a slot's vertex came from, whatever faces it has now.
    pub(crate) vertex_normals: Vec<Vec3>,
    pub(crate) flags: Vec<u8>,
    /// The current seam edges, when the input has seams.
    pub(crate) seams: Option<SeamGraph>,
    /// The pass in which each slot's set of higher neighbours (its edges) last changed
    /// (0: never): its edges listed by earlier passes are stale.
    touched_in_pass: Vec<u32>,
    /// Slots changed in the current pass (`== pass`): their edges wait for the next.
    changed_in_pass: Vec<u32>,
    /// The pass in which each slot's quadric, position, weight or flags last changed
    /// (0: never): its edges' costs from earlier passes are stale.
    modified_in_pass: Vec<u32>,
    /// The current pass, counted from 1.
    pass: u32,
    /// The input vertex whose exact position the slot holds, or `MOVED`.
    origin: Vec<u32>,
    live_vertices: usize,
    collapses: usize,
    error_sum: f64,
    error_max: f64,
    refusals: Refusals,
    locked_vertices: usize,
    seam_vertices: usize,
}

impl Engine {
    /// Phase 1: centre the positions, classify every vertex and fill its quadric from
    /// the face planes, then fill the input and vertex normals (`classify.rs`).
    pub(crate) fn new(
        poses: &[&[Vec3]],
        template: usize,
        input: &SimplifyInput<'_>,
        faces: Vec<[u32; 3]>,
        config: &SimplifyConfig,
    ) -> Self {
        let SimplifyInput { mesh, weights, part_labels, seams, keep_penalty } = *input;
        let n = mesh.positions.len();
        let pose_count = poses.len();
        let center = mesh.bounding_box().map_or(Vec3::zeros(), |(lo, hi)| (lo + hi) * 0.5);
        let local: Vec<Vec<Vec3>> = poses.iter().map(|p| p.iter().map(|x| x - center).collect()).collect();
        let lists = FaceLists::new(n, faces);
        let seams = seams.map(|edges| SeamGraph::new(n, edges));
        // Each face's plane quadric once (a vertex sums those of its faces). Several
        // poses would need one per face and pose: those are computed where summed.
        let face_planes = (pose_count == 1).then(|| fill_face_planes(lists.faces(), &local[0]));
        let (flags, quadrics) = classify_vertices(&ClassifyInput {
            lists: &lists,
            poses: &local,
            face_planes: face_planes.as_deref(),
            part_labels,
            seams: seams.as_ref(),
            config,
        });
        // The planes go before the normals come: the two are never in memory together
        // (on a million faces, 40 and 36 MB, the allocated heap's peak when they were).
        drop(face_planes);
        let input_normals = compute_input_normals(lists.faces(), &mesh.positions);
        let vertex_normals = compute_vertex_normals(&lists, &input_normals);
        let live_vertices = (0..n as u32).filter(|&v| lists.count(v) > 0).count();
        let locked_vertices = flags.iter().filter(|&&f| f & (FROZEN | PINNED) != 0).count();
        let seam_vertices =
            seams.as_ref().map_or(0, |s| (0..n as u32).filter(|&v| !s.of(v).is_empty()).count());
        let mut pose_positions = local;
        // One pose: the moving positions are the only copy; several: the template's
        // positions are copied out, since every pose's stay fixed for the cost.
        let positions = if pose_count == 1 {
            pose_positions.pop().expect("one pose")
        } else {
            pose_positions[template].clone()
        };
        Engine {
            params: Params {
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
            },
            pose_count,
            center,
            positions,
            pose_positions,
            quadrics,
            // `+ 0.0` turns a −0 weight into +0: costs are ranked by their bit patterns,
            // where −0 would sort after every positive cost.
            weights: weights.filter(|_| config.saliency).map(|w| w.iter().map(|&x| x + 0.0).collect()),
            keep_penalty: keep_penalty.filter(|_| config.placement == Placement::Subset).map(<[f64]>::to_vec),
            lists,
            input_normals,
            vertex_normals,
            flags,
            seams,
            touched_in_pass: vec![0; n],
            changed_in_pass: vec![0; n],
            modified_in_pass: vec![0; n],
            pass: 0,
            origin: (0..n as u32).collect(),
            live_vertices,
            collapses: 0,
            error_sum: 0.0,
            error_max: 0.0,
            refusals: Refusals::default(),
            locked_vertices,
            seam_vertices,
        }
    }

    /// Pass, steps 1 and 2 (meshoptimizer's pick and rank) in one parallel sweep over
    /// the slots: every live edge once, as `[lo, hi]` ascending, and its cost. Slots
    /// whose neighbours did not change in the last pass copy their edges and costs from
    /// `previous`, a run of consecutive such slots in one copy (late passes change few
    /// slots: a copy per slot cost more than the rest of their listing), and the costs
    /// of their edges to a slot modified in it are computed again; a changed slot lists
    /// its edges again, copying the cost of each edge neither of whose endpoints changed
    /// (the quadric cost depends on the endpoints alone). So only the edges around the
    /// last pass's collapses are listed and costed again.
    fn pick_and_rank_edge_collapses(&self, previous: EdgeCosts) -> EdgeCosts {
        let n = self.positions.len();
        let have_previous = !previous.chunks.is_empty();
        // Each work item consumes its own chunk of `previous` (a slot's old edges are in
        // its own chunk), so the two passes' lists are never whole in memory together.
        let mut old_chunks = previous.chunks;
        old_chunks.resize_with(n.div_ceil(CHUNK), ChunkEdges::default);
        let chunks = old_chunks
            .into_par_iter()
            .enumerate()
            .map(|(chunk, old)| {
                let slots = (chunk * CHUNK) as u32..((chunk + 1) * CHUNK).min(n) as u32;
                list_chunk(self, slots, old, have_previous)
            })
            .collect();
        EdgeCosts { chunks }
    }

    /// [`Self::pick_and_rank_edge_collapses`] for the slots `slots`, from `old`, their
    /// edges in the last pass. A method of its own, not the body of the sweep's closure
    /// (−1.6 M instructions on SCAPE: `self` is then a reference argument, which LLVM may
    /// assume nothing writes through the chunk's vectors, where a reference captured by
    /// the closure is reloaded). Inlined by force into the clones of the free
    /// [`list_chunk`].
    #[inline(always)]
    fn list_chunk(&self, slots: std::ops::Range<u32>, old: ChunkEdges, have_previous: bool) -> ChunkEdges {
        // Changes made in the last pass are not in `old`; earlier ones are.
        let last = self.pass - 1;
        let reuse_costs = have_previous && self.params.metric == Metric::Quadric;
        let unchanged = |a: u32, b: u32| {
            self.modified_in_pass[a as usize] < last && self.modified_in_pass[b as usize] < last
        };
        // The first pass lists each edge once, at its lower end: about three per slot on
        // a closed mesh, and 3⅛ leaves the chunks above the mean room (−0.2 M instructions
        // on SCAPE against 3, whose vectors grew).
        let capacity = if have_previous { old.his.len() } else { 25 * slots.len() / 8 };
        let mut out = ChunkEdges {
            first: slots.start,
            his: Vec::with_capacity(capacity),
            costs: Vec::with_capacity(capacity),
            start: Vec::with_capacity(slots.len()),
        };
        let mut upper: Vec<u32> = Vec::with_capacity(16);
        let mut batch = CostBatch::new(
            self.params.placement == Placement::Optimal && self.params.metric == Metric::Quadric,
        );
        let touched = |v: u32| !have_previous || self.touched_in_pass[v as usize] >= last;
        let mut v = slots.start;
        while v < slots.end {
            if touched(v) {
                out.start.push(out.his.len() as u32);
                if self.flags[v as usize] & (ALIVE | FROZEN) == ALIVE {
                    let (old_his, old_costs) = old.of((v - slots.start) as usize);
                    // Both runs ascend: the old edge of each new one is found by a
                    // cursor that only moves forwards (a binary search each cost more).
                    let mut j = 0;
                    for &x in self.upper_neighbours(v, &mut upper).iter() {
                        while j < old_his.len() && old_his[j] < x {
                            j += 1;
                        }
                        let listed = j < old_his.len() && old_his[j] == x;
                        let reused = (listed && reuse_costs && unchanged(v, x)).then(|| old_costs[j]);
                        out.his.push(x);
                        out.costs.push(reused.unwrap_or(f64::NAN));
                        if reused.is_none() {
                            batch.cost(self, &mut out.costs, v, x);
                        }
                    }
                }
                v += 1;
                continue;
            }
            // Slots `v..w`, untouched in the last pass, keep their edges: the runs
            // are copied whole, and only the costs of edges to a slot modified in
            // it are computed again.
            let after = &self.touched_in_pass[v as usize + 1..slots.end as usize];
            let w = v + 1 + after.iter().position(|&t| t >= last).unwrap_or(after.len()) as u32;
            let (i, j) = ((v - slots.start) as usize, (w - slots.start) as usize);
            let from = old.start[i] as usize;
            let to = old.start.get(j).map_or(old.his.len(), |&e| e as usize);
            let base = out.his.len();
            // In `u32`, wrapping (the shift may be either way): one vector add for
            // four slots.
            let shift = (base as u32).wrapping_sub(from as u32);
            out.start.extend(old.start[i..j].iter().map(|&s| s.wrapping_add(shift)));
            out.his.extend_from_slice(&old.his[from..to]);
            out.costs.extend_from_slice(&old.costs[from..to]);
            let end = out.his.len();
            // The slot of edge `e`, found by a cursor that only moves forwards.
            let mut slot = i;
            for e in base..end {
                let x = out.his[e];
                if reuse_costs && self.modified_in_pass[x as usize] < last {
                    continue;
                }
                while slot + 1 < j && out.start[slot + 1] as usize <= e {
                    slot += 1;
                }
                batch.cost_at(self, &mut out.costs, e, slots.start + slot as u32, x);
            }
            #[cfg(debug_assertions)]
            for u in v..w {
                let k = (u - slots.start) as usize;
                let run = out.start[k] as usize..out.start.get(k + 1).map_or(end, |&e| e as usize);
                // A slot untouched in the last pass was not modified in it either.
                debug_assert!(self.modified_in_pass[u as usize] < last);
                if self.flags[u as usize] & (ALIVE | FROZEN) == ALIVE {
                    debug_assert_eq!(self.upper_neighbours(u, &mut upper), &out.his[run]);
                } else {
                    debug_assert!(run.is_empty());
                }
            }
            v = w;
        }
        batch.finish(self, &mut out.costs);
        out
    }

    /// The neighbours of `v` with a higher index, ascending, in `upper`. A vertex has
    /// few neighbours: insertion into a sorted run beats collecting, sorting and
    /// deduplicating, and the run is short enough that a linear scan from its end finds
    /// the place (`Vec::insert` and a binary search cost a `memmove` call and a loop
    /// each).
    /// Inlined by force into the listing sweep (−0.13 M instructions on SCAPE).
    #[inline(always)]
    fn upper_neighbours<'a>(&self, v: u32, upper: &'a mut Vec<u32>) -> &'a [u32] {
        upper.clear();
        for &f in self.lists.of(v) {
            for x in self.lists.face(f) {
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

    /// Pass, step 4: perform the sorted collapses. A batched pass chooses, in cost
    /// order, as many as are still needed with no endpoint shared (a shared endpoint
    /// would make the later cost stale), then performs them in vertex order. An
    /// exhaustive pass performs them in cost order, skipping edges with an endpoint
    /// already changed. Each is re-checked against the mesh as it is then.
    ///
    /// Why a batched pass performs in vertex order: cost order jumps around the whole
    /// mesh; on a million faces the loop then waits on memory at every step. The chosen
    /// set is the same either way; only the order of mutually non-adjacent collapses
    /// changes.
    fn perform_edge_collapses(
        &mut self,
        order: SortedCollapses,
        target: &StopAt,
        pass: Pass,
        marks: &mut ScratchMarks,
    ) {
        match pass {
            Pass::Batched => {
                let wanted = target.remaining(self).max(1);
                let mut chosen = if self.seams.is_some() {
                    self.choose_in_cost_order(order, wanted)
                } else {
                    self.choose_by_rounds(order.keys, wanted, marks)
                };
                // `(lo, hi)` order: vertex order. Packed into one integer, which orders
                // like the pair and compares in one instruction where a pair takes a
                // lexicographic loop.
                chosen.sort_unstable();
                for [a, b] in chosen.into_iter().map(|packed| [(packed >> 32) as u32, packed as u32]) {
                    if target.reached(self) {
                        break;
                    }
                    try_collapse(self, a, b, marks);
                }
            }
            Pass::Exhaustive => {
                for [a, b] in order.map(unpack_edge) {
                    if target.reached(self) {
                        break;
                    }
                    if self.changed_this_pass(a) || self.changed_this_pass(b) {
                        continue;
                    }
                    if try_collapse(self, a, b, marks) {
                        self.changed_in_pass[a as usize] = self.pass;
                        self.changed_in_pass[b as usize] = self.pass;
                    }
                }
            }
        }
    }

    /// A batched pass's choice: in cost order, up to `wanted` edges sharing no endpoint
    /// (each chosen edge holds its endpoints for the pass), packed `lo << 32 | hi`.
    fn choose_in_cost_order(&mut self, order: SortedCollapses, wanted: usize) -> Vec<u64> {
        let mut chosen = Vec::with_capacity(wanted.min(order.len()));
        for [a, b] in order.map(unpack_edge) {
            if chosen.len() == wanted {
                break;
            }
            if self.changed_this_pass(a) || self.changed_this_pass(b) {
                continue;
            }
            // An edge the seam rule refuses both ways is refused before it holds its
            // endpoints for the pass: it would stay cheap, and block them in every one.
            if self.seams.is_some() && !self.seam_rule_allows_either(a, b) {
                self.refusals.count(Refusal::Seam);
                continue;
            }
            self.changed_in_pass[a as usize] = self.pass;
            self.changed_in_pass[b as usize] = self.pass;
            chosen.push(u64::from(a) << 32 | u64::from(b));
        }
        chosen
    }

    /// [`Self::choose_in_cost_order`]'s choice (without seams), found without sorting
    /// every key. An edge whose key is the smallest at both its endpoints among the
    /// edges still undecided is one the in-order choice takes (every smaller edge at
    /// its endpoints was dropped because a smaller one took its other endpoint), and
    /// an undecided edge at an endpoint it takes is one it skips; so rounds of taking
    /// every such edge and dropping their neighbours decide the same edges as the
    /// in-order walk. When a round decides few edges (a run of ever cheaper edges
    /// decides one per round), the rest are sorted and walked in order. The walk
    /// stops at `wanted` edges, so of all the edges taken, the `wanted` cheapest are
    /// kept. `marks` is scratch: each slot's smallest edge in a round.
    fn choose_by_rounds(&mut self, mut keys: Vec<u128>, wanted: usize, marks: &mut ScratchMarks) -> Vec<u64> {
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
                    self.changed_in_pass[a as usize] = self.pass;
                    self.changed_in_pass[b as usize] = self.pass;
                    // `live[took]` was seen already: the swap moves no edge still to be
                    // looked at.
                    live.swap(took, i);
                    took += 1;
                }
            }
            let mut kept = took;
            for i in took..live.len() {
                let [a, b] = unpack_edge(live[i]);
                if !self.changed_this_pass(a) && !self.changed_this_pass(b) {
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
            if !self.changed_this_pass(a) && !self.changed_this_pass(b) {
                self.changed_in_pass[a as usize] = self.pass;
                self.changed_in_pass[b as usize] = self.pass;
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

    #[inline]
    fn changed_this_pass(&self, v: u32) -> bool {
        self.changed_in_pass[v as usize] == self.pass
    }

    /// Evaluates edge `(a, b)` on the current mesh, checks the safeguards and performs
    /// the collapse; a refusal is counted. True when the collapse was performed.
    /// Inlined by force into the clones of the free [`try_collapse`].
    #[inline(always)]
    fn try_collapse(&mut self, a: u32, b: u32, marks: &mut ScratchMarks) -> bool {
        let Some(candidate) = self.evaluate(a, b) else { return false };
        if let Err(refusal) = self.check_collapse(&candidate, marks) {
            self.refusals.count(refusal);
            return false;
        }
        self.collapse_edge(&candidate);
        true
    }

    /// Performs a checked collapse: the faces on the edge die, `remove`'s other faces
    /// are re-pointed to `keep`, the quadrics add up and `keep` moves.
    /// Inlined by force, like every step of `try_collapse`, so that its AVX2 clone's
    /// features reach it (the free [`try_collapse`]).
    #[inline(always)]
    fn collapse_edge(&mut self, c: &Candidate) {
        let (r, k) = (c.remove, c.keep);
        // Every vertex around `remove` gains `keep` or loses `remove` as a neighbour, and
        // `keep` gains `remove`'s neighbours. A slot's edges are only those to higher
        // slots, so only `keep` and the vertices below `remove` or `keep` change theirs.
        let changes_edges = r.max(k);
        for &f in self.lists.of(r) {
            for x in self.lists.face(f) {
                if x < changes_edges {
                    self.touched_in_pass[x as usize] = self.pass;
                }
            }
        }
        self.touched_in_pass[k as usize] = self.pass;
        // `remove` loses all its edges.
        self.touched_in_pass[r as usize] = self.pass;
        self.lists.collapse(r, k);
        if let Some(seams) = &mut self.seams {
            seams.collapse(r, k);
        }
        let pc = self.pose_count;
        for p in 0..pc {
            let qr = self.quadrics[r as usize * pc + p];
            self.quadrics[k as usize * pc + p] += &qr;
        }
        if let Some(w) = &mut self.weights {
            w[k as usize] = w[k as usize].max(w[r as usize]);
        }
        let (ku, ru) = (k as usize, r as usize);
        // The seam rule only lets a seam vertex go into a seam vertex, so `keep` is one.
        debug_assert!(self.flags[ru] & SEAM == 0 || self.flags[ku] & (SEAM | PINNED) != 0);
        self.flags[ku] |= self.flags[ru] & BOUNDARY;
        self.flags[ru] &= !ALIVE;
        self.modified_in_pass[ku] = self.pass;
        if c.position != self.positions[ku] {
            self.origin[ku] = MOVED;
            self.positions[ku] = c.position;
        }

        let area: f64 = (0..pc).map(|p| self.quadrics[ku * pc + p].area).sum();
        let rms = if area > 0.0 { (c.error / area).sqrt() } else { 0.0 };
        self.error_sum += rms;
        self.error_max = self.error_max.max(rms);
        self.collapses += 1;
        self.live_vertices -= 1;
    }

    /// Phase 4: the surviving vertices (in slot order) and faces (in input order).
    fn extract_output(self, mesh: &TriMesh, stop: StopReason, started: Instant) -> Simplified {
        let n = self.positions.len();
        let mut simp_of_slot = vec![u32::MAX; n];
        let mut positions = Vec::with_capacity(self.live_vertices);
        let mut simp_to_orig = Vec::with_capacity(self.live_vertices);
        for (slot, simp) in simp_of_slot.iter_mut().enumerate() {
            if self.flags[slot] & ALIVE == 0 || self.lists.count(slot as u32) == 0 {
                continue;
            }
            *simp = positions.len() as u32;
            let origin = self.origin[slot];
            if origin == MOVED {
                positions.push(self.positions[slot] + self.center);
                simp_to_orig.push(None);
            } else {
                positions.push(mesh.positions[origin as usize]);
                simp_to_orig.push(Some(origin));
            }
        }
        let faces: Vec<[u32; 3]> = self.lists.live().map(|f| f.map(|v| simp_of_slot[v as usize])).collect();
        debug_assert!(faces.iter().flatten().all(|&v| (v as usize) < positions.len()));
        let (edge_length_mean, edge_length_variance) =
            self.output_edge_length_stats(&simp_of_slot, &positions);
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
            collapses: self.collapses,
            stop,
            refusals: self.refusals,
            locked_vertices: self.locked_vertices,
            seam_vertices: self.seam_vertices,
            max_error: self.error_max,
            mean_error: if self.collapses > 0 { self.error_sum / self.collapses as f64 } else { 0.0 },
            edge_length_mean,
            edge_length_variance,
            diagonal: mesh.diagonal(),
            seconds: started.elapsed().as_secs_f64(),
        };
        Simplified { mesh: TriMesh { positions, faces }, simp_to_orig, report }
    }
}

impl Engine {
    /// [`desal_mesh::edge_length_stats`] of the output (`simp_of_slot`, `positions`: the
    /// output's vertex numbering and positions), from the slots' upper neighbours: the
    /// output's numbering keeps slot order, so slots ascending, each with its upper
    /// neighbours ascending, are the unique edges in the sorted order that function sums
    /// them in, and the figures are its own, bit for bit, without its sort of every
    /// corner pair (2.5 % of a SCAPE run's instructions).
    fn output_edge_length_stats(&self, simp_of_slot: &[u32], positions: &[Vec3]) -> (f64, f64) {
        let mut upper = Vec::with_capacity(16);
        let mut stats = desal_mesh::LengthStats::default();
        for v in 0..simp_of_slot.len() as u32 {
            let simp_v = simp_of_slot[v as usize];
            if simp_v == u32::MAX {
                continue;
            }
            for &x in self.upper_neighbours(v, &mut upper) {
                let simp_x = simp_of_slot[x as usize] as usize;
                stats.add((positions[simp_v as usize] - positions[simp_x]).norm());
            }
        }
        stats.mean_variance()
    }
}

with_avx2_clone! {
    /// Pass, step 3: the edges this pass may perform, cheapest first (ties by `(lo, hi)`),
    /// each packed by [`pack_collapse`]. A batched pass keeps only costs up to
    /// `PASS_ERROR_FACTOR` times the cost of the `needed`-th cheapest (capped by
    /// `PASS_GOAL_FRACTION`) and takes them all; an exhaustive one keeps every finite cost
    /// and stops at the target, usually early (SCAPE → 5000: after 1006 of 8878), so its
    /// order is sorted as it is taken. Compiled twice (−0.2 M instructions on SCAPE).
    fn sort_edge_collapses(ranked: &EdgeCosts, needed: usize, pass: Pass) -> SortedCollapses {
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
        // did not move); counting the kept edges first cost 0.2 M more instructions.
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
        SortedCollapses { keys: order, sorted: 0, next: 0, batch: first_batch }
    }
}

/// Below this many undecided edges, [`Engine::choose_by_rounds`] sorts them and walks them.
const ROUNDS_MIN_EDGES: usize = 64;

/// [`Engine::choose_by_rounds`] stops its rounds when one decides fewer than one in this
/// many of the undecided edges.
const ROUNDS_MIN_DECIDED: usize = 4;

/// The first batch an exhaustive pass sorts; each later one is twice the last, so the
/// selections that split the batches off cost a few sweeps of the order in all.
const EXHAUSTIVE_FIRST_BATCH: usize = 1024;

/// Packed collapses taken in ascending order, sorted a batch at a time: the batch's
/// smallest keys are selected out of the rest, then sorted. The keys are distinct (each
/// holds its edge), so the order taken is the full sort's.
#[derive(Debug)]
struct SortedCollapses {
    keys: Vec<u128>,
    /// `keys[..sorted]` are sorted and smaller than every later key.
    sorted: usize,
    /// The next key to take.
    next: usize,
    /// The size of the next batch.
    batch: usize,
}

impl SortedCollapses {
    fn len(&self) -> usize {
        self.keys.len()
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
/// a heap vector per call cost 0.1 M more instructions on SCAPE): 2³² edges would take
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
fn pack_collapse(cost: f64, [lo, hi]: [u32; 2]) -> u128 {
    (u128::from(cost.to_bits()) << 64) | (u128::from(lo) << 32) | u128::from(hi)
}

/// The edge of a [`pack_collapse`]d collapse.
#[inline]
fn unpack_edge(packed: u128) -> [u32; 2] {
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
    use crate::SimplifyInput;

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
        let input = SimplifyInput::new(&mesh);
        let config = SimplifyConfig::default();
        let mut engine = Engine::new(&[mesh.positions.as_slice()], 0, &input, mesh.faces.clone(), &config);
        let mut marks = ScratchMarks::new(mesh.positions.len());
        let mut upper = Vec::new();
        let edges: Vec<[u32; 2]> = (0..side * side)
            .flat_map(|v| {
                engine.upper_neighbours(v, &mut upper).iter().map(move |&x| [v, x]).collect::<Vec<_>>()
            })
            .collect();
        let costings: [&dyn Fn(usize, [u32; 2]) -> f64; 3] = [
            &|i, _| ((i as u64 * 2_654_435_761) % 7) as f64,
            &|_, [lo, hi]| f64::from(lo) + 0.5 * f64::from(hi % 3),
            &|_, [lo, _]| f64::from(side * side - lo),
        ];
        for cost in costings {
            let keys: Vec<u128> =
                edges.iter().enumerate().map(|(i, &e)| pack_collapse(cost(i, e), e)).collect();
            for wanted in [1, 7, 50, 150, edges.len()] {
                engine.pass += 1;
                let order = SortedCollapses { keys: keys.clone(), sorted: 0, next: 0, batch: keys.len() };
                let mut in_order = engine.choose_in_cost_order(order, wanted);
                engine.pass += 1;
                let mut by_rounds = engine.choose_by_rounds(keys.clone(), wanted, &mut marks);
                in_order.sort_unstable();
                by_rounds.sort_unstable();
                assert_eq!(by_rounds, in_order, "wanted {wanted}");
            }
        }
    }

    /// Sorted a batch at a time (batches of 1024, 2048, ...), 5000 distinct keys come out
    /// in the full sort's order.
    #[test]
    fn collapses_sorted_in_batches_come_out_fully_sorted() {
        let keys: Vec<u128> = (0..5000u128).map(|i| (i * 2_654_435_761) % 1_000_003).collect();
        let mut sorted = keys.clone();
        sorted.sort_unstable();
        let batched = SortedCollapses { keys, sorted: 0, next: 0, batch: EXHAUSTIVE_FIRST_BATCH };
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
