//! The edge-collapse engine: Garland and Heckbert 1997 ("Surface simplification using
//! quadric error metrics") with the cost of Zhao, Ngan and Li (paper §3.1, Eq. 5)
//! `E = d · (w1 + w2)/2 · v̄ᵀ(Q1 + Q2)v̄`, and Mohr and Gleicher 2003 ("Deformation
//! sensitive decimation") for quadrics summed over poses.
//!
//! The story, as [`run_engine`] tells it: classify every vertex and fill its quadric in
//! one parallel pass; then, in passes until the target: list the live edges, cost in
//! parallel those with an endpoint changed by the last pass (the others keep their
//! cost: the quadric cost depends on the endpoints alone), sort the cheap ones, choose
//! in cost order those that share no endpoint, and perform them, each re-checked against
//! the safeguards (link condition, fold-over against the face itself and against its
//! corners' input normals, degeneracy); finally compact the survivors
//! into the output mesh.
//!
//! Why passes and not a heap: the first version kept every edge in a binary heap with
//! lazy invalidation (stamps per vertex); profiling on SCAPE showed the loop stalled on
//! heap memory (8–9 pops per collapse, most of them stale, one cache miss per level)
//! at 5–8x meshoptimizer's time. meshoptimizer's pass-based ranking (`rankEdgeCollapses`
//! / `performEdgeCollapses`) streams through flat arrays instead and costs edges in
//! parallel. A pass accepts collapses in cost order up to the number still needed and up
//! to `PASS_ERROR_FACTOR` times the cost of the last one needed, so it stays close to
//! strict greedy order; within a pass, an edge whose endpoint already moved is left for
//! the next pass, so every cost used is exact.
//!
//! Data layout: positions, quadrics and flags are flat per-vertex arrays indexed by the
//! *slot*, which is the input vertex index (`orig_idx`); a vertex's faces are a run of
//! `refs` (`face_start`, `face_len`), rewritten at the end of `refs` when the vertex
//! absorbs a neighbour and compacted when `refs` has doubled. The collapse loop is
//! sequential, costing is an order-preserving parallel map, and every tie is broken by
//! vertex index, so the output does not depend on the thread count.

use std::time::Instant;

use desal_mesh::{Progress, TriMesh, Vec3, VertexFaces};
use rayon::prelude::*;

use crate::config::{Metric, PartBorders, Placement, SimplifyConfig, Target};
use crate::error::SimplifyError;
use crate::lindstrom_turk::Neighbourhood;
use crate::quadric::Quadric;
use crate::report::{Refusals, SimplifyReport, StopReason, edge_length_stats};

/// Vertex flags, one byte per slot.
const ALIVE: u8 = 1;
/// The vertex is on a boundary edge (an edge with one face).
const BOUNDARY: u8 = 2;
/// Input non-manifold vertex (pinched fans, or an edge with more than two faces): no
/// incident edge is ever collapsed.
const FROZEN: u8 = 4;
/// The vertex keeps its position and is never removed; it may absorb neighbours.
const PINNED: u8 = 8;

/// A pass accepts collapses costing up to this factor times the cost of the last
/// collapse still needed (meshoptimizer uses 1.5): many cheap candidates are skipped
/// because a neighbour went first, so the limit must exceed the needed-th cost, but a
/// small factor keeps the order close to strict greedy.
const PASS_ERROR_FACTOR: f64 = 1.5;

/// A pass never aims at more than this fraction of the collapses still needed, so that
/// early passes (when almost everything is cheap) do not flatten the greedy order.
const PASS_GOAL_FRACTION: f64 = 0.5;

/// A new face with `2·area < DEGENERATE_RATIO · (longest edge)²` counts as degenerate
/// (a needle or cap flatter than one part in a million).
const DEGENERATE_RATIO: f64 = 1e-6;

/// Relative margin by which a computed placement must beat the better endpoint's error
/// to be used instead of it (rounding noise must not move a vertex off its position).
const SNAP_TOLERANCE: f64 = 1e-9;

/// Vertices per work item of the parallel classification pass.
const CHUNK: usize = 2048;

/// Marks a slot whose position is no longer any input vertex's (optimal placement).
const MOVED: u32 = u32::MAX;

/// The data one simplification reads.
#[derive(Debug, Clone, Copy)]
pub struct SimplifyInput<'a> {
    /// The mesh to simplify (the template).
    pub mesh: &'a TriMesh,
    /// One weight per input vertex (stage 2's saliency, floor already applied), used by
    /// the cost when [`SimplifyConfig::saliency`] is on. `None`: all weights 1.
    pub weights: Option<&'a [f64]>,
    /// One part id per input vertex, used by [`SimplifyConfig::part_borders`].
    pub part_labels: Option<&'a [u32]>,
}

impl<'a> SimplifyInput<'a> {
    /// A mesh with no weights and no labels.
    pub fn new(mesh: &'a TriMesh) -> Self {
        Self { mesh, weights: None, part_labels: None }
    }

    /// Adds per-vertex saliency weights.
    pub fn with_weights(self, weights: &'a [f64]) -> Self {
        Self { weights: Some(weights), ..self }
    }

    /// Adds per-vertex part labels.
    pub fn with_part_labels(self, labels: &'a [u32]) -> Self {
        Self { part_labels: Some(labels), ..self }
    }
}

/// The result of a simplification.
#[derive(Debug, Clone, PartialEq)]
pub struct Simplified {
    /// The simplified mesh; its vertex indices are `simp_idx`. Vertices appear in
    /// increasing order of the input vertex that holds their slot; faces keep the input's
    /// relative order; orientation is preserved.
    pub mesh: TriMesh,
    /// For every `simp_idx`, the `orig_idx` whose exact input position the vertex has,
    /// or `None` when optimal placement moved it. Always `Some` with
    /// [`Placement::Subset`] and for [`simplify_multipose`].
    pub simp_to_orig: Vec<Option<u32>>,
    pub report: SimplifyReport,
}

impl Simplified {
    /// `simp_to_orig` without the options, when every output vertex is an input vertex
    /// (subset placement); `None` otherwise.
    pub fn subset_indices(&self) -> Option<Vec<u32>> {
        self.simp_to_orig.iter().copied().collect()
    }
}

/// Simplifies `input.mesh` as `config` says (quadric edge collapse, the paper's cost).
///
/// Units: positions in mesh units; errors in the report are RMS distances in mesh
/// units. When the safeguards leave no valid collapse before the target, the result is
/// larger than the target and `report.stop` says so. Deterministic: the same input and
/// config give the same output whatever the rayon thread count.
pub fn simplify(input: &SimplifyInput<'_>, config: &SimplifyConfig) -> Result<Simplified, SimplifyError> {
    simplify_with_progress(input, config, &desal_mesh::NoProgress)
}

/// [`simplify`], reporting progress (one unit per collapse) to `progress`.
pub fn simplify_with_progress(
    input: &SimplifyInput<'_>,
    config: &SimplifyConfig,
    progress: &dyn Progress,
) -> Result<Simplified, SimplifyError> {
    let poses = [input.mesh.positions.as_slice()];
    run_engine(&poses, 0, input.mesh, input.weights, input.part_labels, config, progress)
}

/// Mohr and Gleicher 2003 multi-pose QEM: every vertex's quadric is kept per pose (the
/// planes of its faces *in that pose*), and keeping vertex `k` for an edge costs the
/// sum over poses of that pose's merged quadric evaluated at `k`'s position in that
/// pose. Placement is always [`Placement::Subset`] (a new position would have to be
/// invented in every pose); `config.placement` is ignored. The fold-over and
/// degeneracy safeguards look at the template pose. `weights`, `part_labels`, balance
/// and the target behave as in [`simplify`]; the output is the simplified template.
pub fn simplify_multipose(
    poses: &desal_mesh::PoseSet,
    weights: Option<&[f64]>,
    part_labels: Option<&[u32]>,
    config: &SimplifyConfig,
) -> Result<Simplified, SimplifyError> {
    let template = poses.template_mesh();
    let positions: Vec<&[Vec3]> = poses.poses.iter().map(|p| p.as_slice()).collect();
    let config = SimplifyConfig { placement: Placement::Subset, ..config.clone() };
    run_engine(&positions, poses.template, &template, weights, part_labels, &config, &desal_mesh::NoProgress)
}

/// The orchestrator shared by single- and multi-pose simplification. `poses[p]` are the
/// positions of pose `p` (one pose: `mesh.positions`); `mesh` is pose `template`.
fn run_engine(
    poses: &[&[Vec3]],
    template: usize,
    mesh: &TriMesh,
    weights: Option<&[f64]>,
    part_labels: Option<&[u32]>,
    config: &SimplifyConfig,
    progress: &dyn Progress,
) -> Result<Simplified, SimplifyError> {
    let started = Instant::now();
    config.validate()?;
    check_input(mesh, weights, part_labels)?;
    // Faces that repeat a vertex have no area and no orientation: they carry nothing a
    // collapse could preserve.
    let faces: Vec<[u32; 3]> =
        mesh.faces.iter().copied().filter(|&[a, b, c]| a != b && b != c && a != c).collect();
    if faces.is_empty() {
        return Err(SimplifyError::EmptyMesh { vertices: mesh.positions.len(), faces: 0 });
    }

    let mut engine = Engine::classify_vertices_and_fill_quadrics(
        poses,
        template,
        mesh,
        faces,
        weights,
        part_labels,
        config,
    );
    let target = StopAt::new(config, engine.live_faces);
    progress.begin("collapse edges", target.remaining(&engine) as u64);
    // A batched pass that achieves nothing (its cheapest choices were all refused) is
    // followed by an exhaustive one, which tries every edge in cost order; when that
    // achieves nothing either, no valid collapse is left.
    let mut pass = Pass::Batched;
    // Costs of the previous pass: an edge whose endpoints did not change since keeps its
    // cost (the quadric cost depends on the endpoints alone), so only edges around the
    // last pass's collapses are costed again.
    let mut previous = EdgeCosts::default();
    while !target.reached(&engine) {
        engine.pass += 1;
        let edges = engine.pick_edge_collapses();
        let costs = engine.cost_edge_collapses(&edges, &previous);
        let order = engine.rank_edge_collapses(&costs, target.remaining(&engine), pass == Pass::Batched);
        let before = engine.collapses;
        match pass {
            Pass::Batched => engine.perform_chosen_collapses(&edges, &order, &target),
            Pass::Exhaustive => engine.perform_collapses_in_order(&edges, &order, &target),
        }
        progress.advance((engine.collapses - before) as u64);
        if !engine.params.lindstrom_turk {
            previous = EdgeCosts { edges, costs };
        }
        pass = match (engine.collapses > before, pass) {
            (true, _) => Pass::Batched,
            (false, Pass::Batched) => Pass::Exhaustive,
            (false, Pass::Exhaustive) => break,
        };
    }
    progress.finish();
    let stop = if target.reached(&engine) { StopReason::TargetReached } else { StopReason::NoValidCollapse };
    Ok(engine.extract_output(mesh, stop, started))
}

/// Validates sizes and values the engine relies on; errors name the offending element.
fn check_input(
    mesh: &TriMesh,
    weights: Option<&[f64]>,
    part_labels: Option<&[u32]>,
) -> Result<(), SimplifyError> {
    let n = mesh.positions.len();
    if n == 0 || mesh.faces.is_empty() {
        return Err(SimplifyError::EmptyMesh { vertices: n, faces: mesh.faces.len() });
    }
    if let Some(vertex) = mesh.positions.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
        return Err(SimplifyError::NonFinitePosition { vertex });
    }
    for (face, f) in mesh.faces.iter().enumerate() {
        if let Some(&vertex) = f.iter().find(|&&v| v as usize >= n) {
            return Err(SimplifyError::FaceIndexOutOfRange { face, vertex, vertex_count: n });
        }
    }
    if let Some(w) = weights {
        if w.len() != n {
            return Err(SimplifyError::WeightCountMismatch { weights: w.len(), vertices: n });
        }
        if let Some(vertex) = w.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
            return Err(SimplifyError::BadWeight { vertex, value: w[vertex] });
        }
    }
    if let Some(l) = part_labels
        && l.len() != n
    {
        return Err(SimplifyError::LabelCountMismatch { labels: l.len(), vertices: n });
    }
    Ok(())
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
            StopAt::Faces(n) => engine.live_faces <= n,
            StopAt::Vertices(n) => engine.live_vertices <= n,
        }
    }

    fn remaining(&self, engine: &Engine) -> usize {
        match *self {
            // Most collapses remove two faces; rounding up reaches an odd gap.
            StopAt::Faces(n) => engine.live_faces.saturating_sub(n).div_ceil(2),
            StopAt::Vertices(n) => engine.live_vertices.saturating_sub(n),
        }
    }
}

/// One evaluated collapse: `remove` goes, `keep` moves to `position`.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    remove: u32,
    keep: u32,
    position: Vec3,
    /// Merged quadric at `position` (summed over poses), before the cost's factors.
    error: f64,
    /// The heap key: `error` times the enabled factors of Eq. 5.
    cost: f64,
}

/// Why a candidate collapse was refused.
#[derive(Debug, Clone, Copy)]
enum Refusal {
    Topology,
    Flip,
    Degenerate,
}

/// The live edges of one pass, `[lo, hi]` ascending, and the cost of each (infinite
/// when the edge may not collapse).
#[derive(Debug, Default)]
struct EdgeCosts {
    edges: Vec<[u32; 2]>,
    costs: Vec<f64>,
}

/// An input face's unnormalised normal and its length (one cache line holds two).
#[derive(Debug, Clone, Copy)]
struct InputNormal {
    normal: Vec3,
    length: f64,
}

/// Settings the inner loop reads, derived once from the config.
#[derive(Debug)]
struct Params {
    subset: bool,
    balance: bool,
    cos_max_rotation: f64,
    /// `-inf` when the corner-normal guard is off (180°).
    cos_max_corner_normal: f64,
    max_placement_distance: f64,
    /// Rank and place by Lindstrom–Turk's memoryless cost (single pose only).
    lindstrom_turk: bool,
}

/// All mutable state of one simplification (see the module doc for the layout).
#[derive(Debug)]
struct Engine {
    params: Params,
    pose_count: usize,
    /// Subtracted from every input position for precision; added back on output.
    center: Vec3,
    /// Current template positions, local coordinates, by slot.
    positions: Vec<Vec3>,
    /// Multi-pose only: local positions of every pose, `[pose][slot]` (never move).
    pose_positions: Vec<Vec<Vec3>>,
    /// `quadrics[slot * pose_count + pose]`.
    quadrics: Vec<Quadric>,
    /// Saliency weight per slot, when the saliency factor is on. A merged vertex takes
    /// the larger weight of the two, so salient detail is never diluted by absorbing a
    /// cheap neighbour.
    weights: Option<Vec<f64>>,
    faces: Vec<[u32; 3]>,
    /// Unnormalised normal of every input face in the template and its length: a
    /// collapse may not turn a face past the threshold from it either, since small
    /// steps add up.
    input_normals: Vec<InputNormal>,
    /// Unit area-weighted normal of every input vertex (template pose): the local
    /// surface orientation where a slot's vertex came from, whatever faces it has now.
    vertex_normals: Vec<Vec3>,
    face_alive: Vec<bool>,
    face_start: Vec<u32>,
    face_len: Vec<u32>,
    refs: Vec<u32>,
    /// `refs` is compacted when it grows past this length.
    refs_limit: usize,
    flags: Vec<u8>,
    /// Per-slot marks for neighbour-set operations without sorting (`epoch` values).
    marks: Vec<u32>,
    epoch: u32,
    /// Slots changed in the current pass (`== pass`): their edges wait for the next.
    changed_in_pass: Vec<u32>,
    /// The pass in which each slot's quadric, position, weight or flags last changed
    /// (0: never): its edges' costs from earlier passes are stale.
    modified_in_pass: Vec<u32>,
    /// The current pass, counted from 1.
    pass: u32,
    /// The input vertex whose exact position the slot holds, or `MOVED`.
    origin: Vec<u32>,
    live_faces: usize,
    live_vertices: usize,
    collapses: usize,
    error_sum: f64,
    error_max: f64,
    refusals: Refusals,
    locked_vertices: usize,
}

/// What the classification pass produces for a run of vertices.
#[derive(Debug, Default)]
struct ChunkOut {
    quadrics: Vec<Quadric>,
    flags: Vec<u8>,
}

impl Engine {
    /// Phase 1: per vertex, in parallel — its quadric (area-weighted face planes, plus
    /// boundary and part-border constraint planes, per pose), its flags (boundary,
    /// non-manifold, part border) and its edges to higher-indexed neighbours.
    fn classify_vertices_and_fill_quadrics(
        poses: &[&[Vec3]],
        template: usize,
        mesh: &TriMesh,
        faces: Vec<[u32; 3]>,
        weights: Option<&[f64]>,
        part_labels: Option<&[u32]>,
        config: &SimplifyConfig,
    ) -> Self {
        let n = mesh.positions.len();
        let pose_count = poses.len();
        let center = mesh.bounding_box().map_or(Vec3::zeros(), |(lo, hi)| (lo + hi) * 0.5);
        let local: Vec<Vec<Vec3>> = poses.iter().map(|p| p.iter().map(|x| x - center).collect()).collect();
        let vertex_faces = VertexFaces::new(n, &faces);
        // Each face's plane quadric once (a vertex sums those of its faces), and its
        // input normal. Several poses would need one quadric per face and pose: those
        // are computed where they are summed instead.
        let (face_quadrics, input_normals): (Vec<Quadric>, Vec<InputNormal>) = faces
            .par_iter()
            .map(|f| {
                let quadric = if pose_count == 1 {
                    let [a, b, c] = f.map(|v| local[0][v as usize]);
                    Quadric::from_triangle(&a, &b, &c)
                } else {
                    Quadric::default()
                };
                let [a, b, c] = f.map(|v| mesh.positions[v as usize]);
                let normal = (b - a).cross(&(c - a));
                (quadric, InputNormal { normal, length: normal.norm() })
            })
            .unzip();
        let vertex_normals: Vec<Vec3> = (0..n)
            .into_par_iter()
            .map(|v| {
                let sum: Vec3 =
                    vertex_faces.of(v as u32).iter().map(|&f| input_normals[f as usize].normal).sum();
                let length = sum.norm();
                if length > 0.0 { sum / length } else { Vec3::zeros() }
            })
            .collect();
        let context = ClassifyContext {
            faces: &faces,
            vertex_faces: &vertex_faces,
            poses: &local,
            face_quadrics: (pose_count == 1).then_some(face_quadrics.as_slice()),
            part_labels,
            config,
        };

        let chunks: Vec<ChunkOut> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|chunk| {
                let mut out = ChunkOut {
                    quadrics: Vec::with_capacity(CHUNK * pose_count),
                    flags: Vec::with_capacity(CHUNK),
                };
                let mut link = LinkScratch::default();
                for v in (chunk * CHUNK)..((chunk + 1) * CHUNK).min(n) {
                    context.classify_vertex(v as u32, &mut link, &mut out);
                }
                out
            })
            .collect();

        let mut quadrics = Vec::with_capacity(n * pose_count);
        let mut flags = Vec::with_capacity(n);
        for c in chunks {
            quadrics.extend(c.quadrics);
            flags.extend(c.flags);
        }
        let live_vertices = (0..n).filter(|&v| !vertex_faces.of(v as u32).is_empty()).count();
        let locked_vertices = flags.iter().filter(|&&f| f & (FROZEN | PINNED) != 0).count();
        let face_len = (0..n).map(|v| vertex_faces.offsets[v + 1] - vertex_faces.offsets[v]).collect();
        let refs_limit = 2 * vertex_faces.faces.len() + 1024;
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
                subset: config.placement == Placement::Subset,
                balance: config.balance,
                cos_max_rotation: config.max_normal_rotation_deg.to_radians().cos(),
                cos_max_corner_normal: if config.max_corner_normal_deg >= 180.0 {
                    f64::NEG_INFINITY
                } else {
                    config.max_corner_normal_deg.to_radians().cos()
                },
                max_placement_distance: config.max_placement_distance,
                lindstrom_turk: config.metric == Metric::LindstromTurk && pose_count == 1,
            },
            pose_count,
            center,
            positions,
            pose_positions,
            quadrics,
            // `+ 0.0` turns a −0 weight into +0: costs are ranked by their bit patterns,
            // where −0 would sort after every positive cost.
            weights: weights.filter(|_| config.saliency).map(|w| w.iter().map(|&x| x + 0.0).collect()),
            live_faces: faces.len(),
            face_alive: vec![true; faces.len()],
            input_normals,
            vertex_normals,
            faces,
            face_start: vertex_faces.offsets[..n].to_vec(),
            face_len,
            refs: {
                let mut refs = vertex_faces.faces;
                refs.reserve(refs_limit + 64 - refs.len());
                refs
            },
            refs_limit,
            flags,
            marks: vec![0; n],
            epoch: 0,
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
        }
    }

    /// Pass, step 1: every live edge once, as `[lo, hi]`, ascending.
    fn pick_edge_collapses(&self) -> Vec<[u32; 2]> {
        let n = self.positions.len();
        let chunks: Vec<Vec<[u32; 2]>> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|chunk| {
                let mut edges = Vec::with_capacity(3 * CHUNK);
                let mut upper: Vec<u32> = Vec::with_capacity(16);
                for v in (chunk * CHUNK) as u32..((chunk + 1) * CHUNK).min(n) as u32 {
                    if self.flags[v as usize] & (ALIVE | FROZEN) != ALIVE {
                        continue;
                    }
                    // A vertex has few neighbours: insertion into a sorted run beats
                    // collecting, sorting and deduplicating.
                    upper.clear();
                    for &f in self.faces_of(v) {
                        for x in self.faces[f as usize] {
                            if x > v
                                && let Err(at) = upper.binary_search(&x)
                            {
                                upper.insert(at, x);
                            }
                        }
                    }
                    edges.extend(upper.iter().map(|&x| [v, x]));
                }
                edges
            })
            .collect();
        chunks.concat()
    }

    /// Pass, step 2: the cost of every edge (in parallel, order kept): taken from
    /// `previous` when neither endpoint changed in the last pass, evaluated otherwise.
    fn cost_edge_collapses(&self, edges: &[[u32; 2]], previous: &EdgeCosts) -> Vec<f64> {
        let stale = self.pass - 1;
        let chunks: Vec<Vec<f64>> = edges
            .par_chunks(CHUNK)
            .map(|chunk| {
                // Both lists ascend: walk `previous` alongside from the chunk's first edge.
                let mut j = previous.edges.partition_point(|e| *e < chunk[0]);
                chunk
                    .iter()
                    .map(|&[a, b]| {
                        while j < previous.edges.len() && previous.edges[j] < [a, b] {
                            j += 1;
                        }
                        let unchanged = self.modified_in_pass[a as usize] < stale
                            && self.modified_in_pass[b as usize] < stale;
                        if unchanged && previous.edges.get(j) == Some(&[a, b]) {
                            previous.costs[j]
                        } else {
                            self.cost_of(a, b)
                        }
                    })
                    .collect()
            })
            .collect();
        chunks.concat()
    }

    /// Pass, step 3: the indices into the pass's edges of those this pass may perform,
    /// cheapest first (ties by edge, i.e. `(lo, hi)`). With `limited`, only costs up to
    /// `PASS_ERROR_FACTOR` times the cost of the `needed`-th cheapest (capped by
    /// `PASS_GOAL_FRACTION`) are kept.
    fn rank_edge_collapses(&self, costs: &[f64], needed: usize, limited: bool) -> Vec<u32> {
        let mut limit = f64::INFINITY;
        if limited && !costs.is_empty() {
            let goal = ((needed as f64 * PASS_GOAL_FRACTION).ceil() as usize).clamp(1, costs.len());
            let mut scratch = costs.to_vec();
            let (_, nth, _) = scratch.select_nth_unstable_by(goal - 1, f64::total_cmp);
            limit = *nth * PASS_ERROR_FACTOR;
        }
        // Non-negative finite f64 bit patterns order like the values.
        let mut order: Vec<(u64, u32)> = costs
            .iter()
            .enumerate()
            .filter(|&(_, &c)| c.is_finite() && c <= limit)
            .map(|(i, c)| (c.to_bits(), i as u32))
            .collect();
        order.sort_unstable();
        order.into_iter().map(|(_, i)| i).collect()
    }

    /// Pass, step 4: choose, in cost order, as many collapses as are still needed with
    /// no endpoint shared (a shared endpoint would make the later cost stale), then
    /// perform them in vertex order, each re-checked against the current mesh.
    ///
    /// Why two steps: performing in cost order jumps around the whole mesh; on a
    /// million faces the loop then waits on memory at every step. The chosen set is the
    /// same either way; only the order of mutually non-adjacent collapses changes, and
    /// the safeguards see the mesh as it is when each one is performed.
    fn perform_chosen_collapses(&mut self, edges: &[[u32; 2]], order: &[u32], target: &StopAt) {
        let wanted = target.remaining(self).max(1);
        let mut chosen = Vec::with_capacity(wanted.min(order.len()));
        for &i in order {
            if chosen.len() == wanted {
                break;
            }
            let [a, b] = edges[i as usize];
            if self.changed_in_pass[a as usize] == self.pass || self.changed_in_pass[b as usize] == self.pass
            {
                continue;
            }
            self.changed_in_pass[a as usize] = self.pass;
            self.changed_in_pass[b as usize] = self.pass;
            chosen.push(i);
        }
        // Edge indices ascend with (lo, hi): vertex order.
        chosen.sort_unstable();
        for i in chosen {
            if target.reached(self) {
                break;
            }
            let [a, b] = edges[i as usize];
            let Some(candidate) = self.evaluate(a, b) else { continue };
            if let Err(refusal) = self.check_collapse(&candidate) {
                self.count_refusal(refusal);
                continue;
            }
            self.collapse_edge(&candidate);
        }
    }

    /// Pass, step 4 when batched passes are stuck: perform the ranked collapses in cost
    /// order, each checked as it comes, skipping edges with an endpoint already changed.
    fn perform_collapses_in_order(&mut self, edges: &[[u32; 2]], order: &[u32], target: &StopAt) {
        for &i in order {
            if target.reached(self) {
                break;
            }
            let [a, b] = edges[i as usize];
            if self.changed_in_pass[a as usize] == self.pass || self.changed_in_pass[b as usize] == self.pass
            {
                continue;
            }
            let Some(candidate) = self.evaluate(a, b) else { continue };
            if let Err(refusal) = self.check_collapse(&candidate) {
                self.count_refusal(refusal);
                continue;
            }
            self.collapse_edge(&candidate);
            self.changed_in_pass[a as usize] = self.pass;
            self.changed_in_pass[b as usize] = self.pass;
        }
    }

    /// Placement and cost of collapsing edge `(a, b)`; `None` when the edge may not
    /// collapse at all (a frozen endpoint, both pinned, or a non-finite cost).
    fn evaluate(&self, a: u32, b: u32) -> Option<Candidate> {
        let (fa, fb) = (self.flags[a as usize], self.flags[b as usize]);
        if (fa | fb) & FROZEN != 0 || (fa & fb) & PINNED != 0 {
            return None;
        }
        let (pinned_a, pinned_b) = (fa & PINNED != 0, fb & PINNED != 0);
        if self.params.lindstrom_turk {
            return self.evaluate_lindstrom_turk(a, b, pinned_a, pinned_b);
        }
        let mut c = if self.params.subset {
            self.place_on_endpoint(a, b, pinned_a, pinned_b)
        } else if pinned_a || pinned_b {
            let keep = if pinned_a { a } else { b };
            self.candidate_at(a, b, self.positions[keep as usize], keep)
        } else {
            self.place_optimally(a, b)
        };
        let pa = &self.positions[a as usize];
        let pb = &self.positions[b as usize];
        c.cost = self.cost_factors(a, b, c.error, pa, pb);
        c.cost.is_finite().then_some(c)
    }

    /// `error` times the enabled factors of Eq. 5: edge length, mean saliency weight.
    #[inline]
    fn cost_factors(&self, a: u32, b: u32, error: f64, pa: &Vec3, pb: &Vec3) -> f64 {
        let mut cost = error;
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
    /// candidate's `error` stays the merged quadric's, for the report.
    fn evaluate_lindstrom_turk(&self, a: u32, b: u32, pinned_a: bool, pinned_b: bool) -> Option<Candidate> {
        let pa = self.positions[a as usize];
        let pb = self.positions[b as usize];
        let squared_length = (pa - pb).norm_squared();
        let n = self.lindstrom_turk_neighbourhood(a, b);
        let computed = if self.params.subset || pinned_a || pinned_b {
            None
        } else {
            let mid = (pa + pb) * 0.5;
            let reach = self.params.max_placement_distance * squared_length.sqrt();
            n.placement(squared_length, || self.link_positions(a, b)).filter(|p| (p - mid).norm() <= reach)
        };
        let (position, keep) = match computed {
            Some(p) => {
                let (da, db) = ((p - pa).norm_squared(), (p - pb).norm_squared());
                (p, if da < db || (da == db && a < b) { a } else { b })
            }
            None => {
                let (lo, hi) = if a < b { (a, b) } else { (b, a) };
                let keep = if pinned_a {
                    a
                } else if pinned_b {
                    b
                } else if n.cost(&self.positions[hi as usize], squared_length)
                    < n.cost(&self.positions[lo as usize], squared_length)
                {
                    hi
                } else {
                    lo
                };
                (self.positions[keep as usize], keep)
            }
        };
        let mut c = self.candidate_at(a, b, position, keep);
        c.cost = self.cost_factors(a, b, n.cost(&position, squared_length), &pa, &pb);
        c.cost.is_finite().then_some(c)
    }

    /// The faces incident to `a` or `b` (each once) and the boundary edges at either.
    fn lindstrom_turk_neighbourhood(&self, a: u32, b: u32) -> Neighbourhood {
        let mut n = Neighbourhood::default();
        let p = |v: u32| &self.positions[v as usize];
        for (v, other) in [(a, b), (b, a)] {
            for &f in self.faces_of(v) {
                let face = self.faces[f as usize];
                // Faces on the edge are in both lists: count them with `a`.
                if v == b && face.contains(&other) {
                    continue;
                }
                n.add_triangle(p(face[0]), p(face[1]), p(face[2]));
            }
        }
        for (v, other) in [(a, b), (b, a)] {
            if self.flags[v as usize] & BOUNDARY == 0 {
                continue;
            }
            for &f in self.faces_of(v) {
                let face = self.faces[f as usize];
                let i = face.iter().position(|&x| x == v).expect("face of v");
                for (s, t) in [(face[i], face[(i + 1) % 3]), (face[(i + 2) % 3], face[i])] {
                    let x = if s == v { t } else { s };
                    if v == b && x == other {
                        continue;
                    }
                    let sharing =
                        self.faces_of(v).iter().filter(|&&g| self.faces[g as usize].contains(&x)).count();
                    if sharing == 1 {
                        n.add_boundary_edge(p(s), p(t));
                    }
                }
            }
        }
        n
    }

    /// Positions of the vertices adjacent to `a` or `b`, other than `a` and `b`, in
    /// index order.
    fn link_positions(&self, a: u32, b: u32) -> Vec<Vec3> {
        let mut link: Vec<u32> = [a, b]
            .iter()
            .flat_map(|&v| self.faces_of(v).iter().flat_map(|&f| self.faces[f as usize]))
            .filter(|&x| x != a && x != b)
            .collect();
        link.sort_unstable();
        link.dedup();
        link.iter().map(|&x| self.positions[x as usize]).collect()
    }

    /// Subset placement: keep whichever endpoint has the smaller merged error (the lower
    /// index on a tie); a pinned endpoint is always the one kept.
    fn place_on_endpoint(&self, a: u32, b: u32, pinned_a: bool, pinned_b: bool) -> Candidate {
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        let error_keeping = |k: u32| self.subset_error(a, b, k);
        let keep = if pinned_a {
            a
        } else if pinned_b {
            b
        } else if error_keeping(hi) < error_keeping(lo) {
            hi
        } else {
            lo
        };
        let remove = if keep == a { b } else { a };
        Candidate {
            remove,
            keep,
            position: self.positions[keep as usize],
            error: error_keeping(keep),
            cost: 0.0,
        }
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
    /// near the edge, else the best point of the segment, else the better endpoint.
    fn place_optimally(&self, a: u32, b: u32) -> Candidate {
        let (pa, pb) = (self.positions[a as usize], self.positions[b as usize]);
        let (position, error) = self.optimal_position(a, b);
        // The slot kept is the endpoint the new position coincides with, else the
        // nearer one (lower index on a tie), so unmoved vertices keep their identity.
        let (da, db) = ((position - pa).norm_squared(), (position - pb).norm_squared());
        let keep = if da < db || (da == db && a < b) { a } else { b };
        let remove = if keep == a { b } else { a };
        Candidate { remove, keep, position, error, cost: 0.0 }
    }

    /// The optimal placement of `(a, b)` (see [`Self::place_optimally`]) and the merged
    /// quadric's error there: all that ranking needs.
    #[inline]
    fn optimal_position(&self, a: u32, b: u32) -> (Vec3, f64) {
        let q = self.quadrics[a as usize] + self.quadrics[b as usize];
        let (pa, pb) = (self.positions[a as usize], self.positions[b as usize]);
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
            if endpoint_error > error * (1.0 + SNAP_TOLERANCE) {
                return (p, error);
            }
        }
        (endpoint, endpoint_error.max(0.0))
    }

    /// The cost of collapsing `(a, b)`, infinite when it may not collapse: what
    /// [`Self::evaluate`] gives, without choosing the slot kept (the common case, an
    /// optimal placement with neither endpoint pinned, has a short path).
    #[inline]
    fn cost_of(&self, a: u32, b: u32) -> f64 {
        let (fa, fb) = (self.flags[a as usize], self.flags[b as usize]);
        if self.params.subset || self.params.lindstrom_turk || (fa | fb) & (FROZEN | PINNED) != 0 {
            return self.evaluate(a, b).map_or(f64::INFINITY, |c| c.cost);
        }
        let (pa, pb) = (&self.positions[a as usize], &self.positions[b as usize]);
        let cost = self.cost_factors(a, b, self.optimal_position(a, b).1, pa, pb);
        if cost.is_finite() { cost } else { f64::INFINITY }
    }

    fn candidate_at(&self, a: u32, b: u32, position: Vec3, keep: u32) -> Candidate {
        let remove = if keep == a { b } else { a };
        let q = self.quadrics[a as usize] + self.quadrics[b as usize];
        Candidate { remove, keep, position, error: q.eval(&position).max(0.0), cost: 0.0 }
    }

    /// All safeguards for one candidate: the link condition, then the geometry of every
    /// face that survives the collapse.
    fn check_collapse(&mut self, c: &Candidate) -> Result<(), Refusal> {
        if !self.link_condition_holds(c.remove, c.keep) {
            return Err(Refusal::Topology);
        }
        self.check_moved_faces(c.remove, c.keep, &c.position)?;
        if c.position != self.positions[c.keep as usize] {
            self.check_moved_faces(c.keep, c.remove, &c.position)?;
        }
        Ok(())
    }

    /// The link condition (Dey et al. 1999) in the form that matters for a 2-manifold
    /// with boundary: the endpoints' common neighbours are exactly the apexes of the
    /// faces on the edge; an interior edge does not join two boundary vertices (that
    /// would pinch); and no apex is left with a degenerate fan (a closed fan of three
    /// faces — the tetrahedron case — or a single boundary face).
    fn link_condition_holds(&mut self, a: u32, b: u32) -> bool {
        let common = self.count_common_neighbours(a, b);

        let mut apexes = [0u32; 2];
        let mut shared = 0;
        for &f in self.faces_of(a) {
            let face = self.faces[f as usize];
            if face.contains(&b) {
                if shared == 2 {
                    return false;
                }
                apexes[shared] = face.iter().copied().find(|&x| x != a && x != b).expect("three distinct");
                shared += 1;
            }
        }
        if shared == 0 || common != shared {
            return false;
        }
        let boundary = |v: u32| self.flags[v as usize] & BOUNDARY != 0;
        if shared == 2 && boundary(a) && boundary(b) {
            return false;
        }
        apexes[..shared].iter().all(|&o| {
            let fan = self.face_len[o as usize];
            if boundary(o) { fan >= 2 } else { fan >= 4 }
        })
    }

    /// Moving `moved` to `position` (merging it with `other`): refuse if any of its faces
    /// not shared with `other` becomes degenerate, turns its normal past the threshold
    /// from before the collapse or from the input, or ends up too far from the input
    /// normals of the vertices at its corners (`max_corner_normal_deg`).
    fn check_moved_faces(&self, moved: u32, other: u32, position: &Vec3) -> Result<(), Refusal> {
        for &f in self.faces_of(moved) {
            let face = self.faces[f as usize];
            if face.contains(&other) {
                continue;
            }
            let corners = face.map(|v| self.positions[v as usize]);
            let old = (corners[1] - corners[0]).cross(&(corners[2] - corners[0]));
            let new_corners = [0, 1, 2].map(|i| if face[i] == moved { *position } else { corners[i] });
            let e0 = new_corners[1] - new_corners[0];
            let e1 = new_corners[2] - new_corners[0];
            let e2 = new_corners[2] - new_corners[1];
            let new = e0.cross(&e1);
            let longest_sq = e0.norm_squared().max(e1.norm_squared()).max(e2.norm_squared());
            let twice_area = new.norm();
            // Written so that a NaN area is refused too.
            if twice_area.partial_cmp(&(DEGENERATE_RATIO * longest_sq)) != Some(std::cmp::Ordering::Greater) {
                return Err(Refusal::Degenerate);
            }
            let old_norm = old.norm();
            // A face that was already degenerate has no normal to compare with.
            if old_norm > 0.0 && new.dot(&old) <= self.params.cos_max_rotation * old_norm * twice_area {
                return Err(Refusal::Flip);
            }
            let input = &self.input_normals[f as usize];
            if new.dot(&input.normal) <= self.params.cos_max_rotation * input.length * twice_area {
                return Err(Refusal::Flip);
            }
            let n = &self.vertex_normals;
            let reference: Vec3 = face
                .iter()
                .map(|&v| if v == moved { n[v as usize] + n[other as usize] } else { n[v as usize] })
                .sum();
            if new.dot(&reference) <= self.params.cos_max_corner_normal * reference.norm() * twice_area {
                return Err(Refusal::Flip);
            }
        }
        Ok(())
    }

    fn count_refusal(&mut self, r: Refusal) {
        match r {
            Refusal::Topology => self.refusals.topology += 1,
            Refusal::Flip => self.refusals.flip += 1,
            Refusal::Degenerate => self.refusals.degenerate += 1,
        }
    }

    /// Performs a checked collapse: faces on the edge die, `remove`'s other faces are
    /// re-pointed to `keep`, the quadrics add up and `keep` moves.
    fn collapse_edge(&mut self, c: &Candidate) {
        let (r, k) = (c.remove, c.keep);
        let mut apexes = [u32::MAX; 2];
        let mut dead = 0;
        let (r_start, r_len) = (self.face_start[r as usize] as usize, self.face_len[r as usize] as usize);
        for i in r_start..r_start + r_len {
            let f = self.refs[i] as usize;
            let face = &mut self.faces[f];
            if face.contains(&k) {
                apexes[dead] = face.iter().copied().find(|&x| x != r && x != k).expect("three distinct");
                dead += 1;
                self.face_alive[f] = false;
            } else {
                for v in face.iter_mut() {
                    if *v == r {
                        *v = k;
                    }
                }
            }
        }
        self.rewrite_face_list(k, r);
        for &o in apexes.iter().take(dead) {
            self.drop_dead_faces(o);
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
        self.live_faces -= dead;
        self.live_vertices -= 1;
    }

    /// Appends `keep`'s new face list (its live faces, then `remove`'s) to `refs`.
    fn rewrite_face_list(&mut self, keep: u32, remove: u32) {
        if self.refs.len() > self.refs_limit {
            self.compact_refs();
        }
        let start = self.refs.len();
        for v in [keep, remove] {
            let s = self.face_start[v as usize] as usize;
            for i in s..s + self.face_len[v as usize] as usize {
                let f = self.refs[i];
                if self.face_alive[f as usize] {
                    self.refs.push(f);
                }
            }
        }
        self.face_start[keep as usize] = start as u32;
        self.face_len[keep as usize] = (self.refs.len() - start) as u32;
        self.face_len[remove as usize] = 0;
    }

    /// Removes dead faces from `v`'s list, in place.
    fn drop_dead_faces(&mut self, v: u32) {
        let s = self.face_start[v as usize] as usize;
        let len = self.face_len[v as usize] as usize;
        let mut w = s;
        for i in s..s + len {
            let f = self.refs[i];
            if self.face_alive[f as usize] {
                self.refs[w] = f;
                w += 1;
            }
        }
        self.face_len[v as usize] = (w - s) as u32;
    }

    /// Copies every live vertex's face run to the front, dropping abandoned runs.
    fn compact_refs(&mut self) {
        let mut refs = Vec::with_capacity(self.refs_limit + 64);
        for v in 0..self.face_start.len() {
            let s = self.face_start[v] as usize;
            self.face_start[v] = refs.len() as u32;
            refs.extend_from_slice(&self.refs[s..s + self.face_len[v] as usize]);
        }
        self.refs_limit = (2 * refs.len()).max(self.refs_limit / 2) + 1024;
        refs.reserve(self.refs_limit + 64 - refs.len());
        self.refs = refs;
    }

    #[inline]
    fn faces_of(&self, v: u32) -> &[u32] {
        let s = self.face_start[v as usize] as usize;
        &self.refs[s..s + self.face_len[v as usize] as usize]
    }

    /// A fresh mark value (marks of earlier calls become stale).
    #[inline]
    fn next_epoch(&mut self) -> u32 {
        self.epoch = self.epoch.wrapping_add(1);
        if self.epoch == 0 {
            self.marks.fill(0);
            self.epoch = 1;
        }
        self.epoch
    }

    /// The number of vertices adjacent to both `a` and `b`.
    fn count_common_neighbours(&mut self, a: u32, b: u32) -> usize {
        let of_a = self.next_epoch();
        let s = self.face_start[a as usize] as usize;
        for i in s..s + self.face_len[a as usize] as usize {
            for x in self.faces[self.refs[i] as usize] {
                self.marks[x as usize] = of_a;
            }
        }
        let counted = self.next_epoch();
        let mut common = 0;
        let s = self.face_start[b as usize] as usize;
        for i in s..s + self.face_len[b as usize] as usize {
            for x in self.faces[self.refs[i] as usize] {
                if x != a && x != b && self.marks[x as usize] == of_a {
                    self.marks[x as usize] = counted;
                    common += 1;
                }
            }
        }
        common
    }

    /// Phase 4: the surviving vertices (in slot order) and faces (in input order).
    fn extract_output(self, mesh: &TriMesh, stop: StopReason, started: Instant) -> Simplified {
        let n = self.positions.len();
        let mut simp_of_slot = vec![u32::MAX; n];
        let mut positions = Vec::with_capacity(self.live_vertices);
        let mut simp_to_orig = Vec::with_capacity(self.live_vertices);
        for (slot, simp) in simp_of_slot.iter_mut().enumerate() {
            if self.flags[slot] & ALIVE == 0 || self.face_len[slot] == 0 {
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
        let faces: Vec<[u32; 3]> = self
            .faces
            .iter()
            .zip(&self.face_alive)
            .filter(|(_, alive)| **alive)
            .map(|(f, _)| f.map(|v| simp_of_slot[v as usize]))
            .collect();
        debug_assert!(faces.iter().flatten().all(|&v| (v as usize) < positions.len()));
        let (edge_length_mean, edge_length_variance) = edge_length_stats(&positions, &faces);
        let report = SimplifyReport {
            input_vertices: mesh.positions.len(),
            input_faces: mesh.faces.len(),
            output_vertices: positions.len(),
            output_faces: faces.len(),
            collapses: self.collapses,
            stop,
            refusals: self.refusals,
            locked_vertices: self.locked_vertices,
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

/// Per-vertex scratch of the classification pass: the neighbours of one vertex, how
/// many of its faces each shares, and a union-find over them for the fan count.
#[derive(Debug, Default)]
struct LinkScratch {
    neighbours: Vec<u32>,
    counts: Vec<u32>,
    parent: Vec<usize>,
}

impl LinkScratch {
    fn slot(&mut self, x: u32) -> usize {
        match self.neighbours.iter().position(|&n| n == x) {
            Some(i) => i,
            None => {
                self.neighbours.push(x);
                self.counts.push(0);
                self.parent.push(self.parent.len());
                self.neighbours.len() - 1
            }
        }
    }

    fn root(&mut self, mut i: usize) -> usize {
        while self.parent[i] != i {
            self.parent[i] = self.parent[self.parent[i]];
            i = self.parent[i];
        }
        i
    }
}

/// What the classification of one vertex reads.
struct ClassifyContext<'a> {
    faces: &'a [[u32; 3]],
    vertex_faces: &'a VertexFaces,
    /// Local positions, `[pose][vertex]`.
    poses: &'a [Vec<Vec3>],
    /// The plane quadric of every face, when there is one pose.
    face_quadrics: Option<&'a [Quadric]>,
    part_labels: Option<&'a [u32]>,
    config: &'a SimplifyConfig,
}

impl ClassifyContext<'_> {
    /// Classifies vertex `v` and appends its quadrics (one per pose) and flags to
    /// `out`. A vertex is non-manifold (FROZEN) when an incident edge has more than two
    /// faces or its faces form more than one fan (a pinch, like SCAPE's vertex 419).
    fn classify_vertex(&self, v: u32, link: &mut LinkScratch, out: &mut ChunkOut) {
        let (faces, config) = (self.faces, self.config);
        link.neighbours.clear();
        link.counts.clear();
        link.parent.clear();
        let my_faces = self.vertex_faces.of(v);
        for &f in my_faces {
            let [x, y] = others(faces[f as usize], v);
            let (i, j) = (link.slot(x), link.slot(y));
            link.counts[i] += 1;
            link.counts[j] += 1;
            let (ri, rj) = (link.root(i), link.root(j));
            link.parent[ri.max(rj)] = ri.min(rj);
        }
        let fans = (0..link.neighbours.len()).filter(|&i| link.parent[i] == i).count();
        let mut flags = if my_faces.is_empty() { 0 } else { ALIVE };
        let on_boundary = link.counts.contains(&1);
        if on_boundary {
            flags |= BOUNDARY;
        }
        if fans > 1 || link.counts.iter().any(|&c| c > 2) {
            flags |= FROZEN;
        }
        let label_of = |x: u32| self.part_labels.map(|l| l[x as usize]);
        let on_part_border =
            self.part_labels.is_some() && link.neighbours.iter().any(|&x| label_of(x) != label_of(v));
        if on_part_border && config.part_borders == PartBorders::Lock {
            flags |= PINNED;
        }
        let border_weight = match config.part_borders {
            PartBorders::Constrain(w) if on_part_border && w > 0.0 => Some(w),
            _ => None,
        };
        let boundary_weight = (on_boundary && config.boundary_weight > 0.0).then_some(config.boundary_weight);

        for (pose, positions) in self.poses.iter().enumerate() {
            let mut q = Quadric::default();
            let pv = &positions[v as usize];
            for &f in my_faces {
                let face = faces[f as usize];
                let [p0, p1, p2] = face.map(|x| positions[x as usize]);
                match self.face_quadrics {
                    Some(fq) if pose == 0 => q += &fq[f as usize],
                    _ => q += &Quadric::from_triangle(&p0, &p1, &p2),
                }
                if boundary_weight.is_none() && border_weight.is_none() {
                    continue;
                }
                let cross = (p1 - p0).cross(&(p2 - p0));
                for x in others(face, v) {
                    let px = &positions[x as usize];
                    if let Some(w) = boundary_weight {
                        let i = link.neighbours.iter().position(|&n| n == x).expect("collected above");
                        if link.counts[i] == 1 {
                            q += &Quadric::edge_constraint(pv, px, &cross, w);
                        }
                    }
                    if let Some(w) = border_weight
                        && label_of(x) != label_of(v)
                    {
                        q += &Quadric::edge_constraint(pv, px, &cross, w);
                    }
                }
            }
            out.quadrics.push(q);
        }
        out.flags.push(flags);
    }
}

/// The two vertices of `face` other than `v`, in face order after `v`.
#[inline]
fn others(face: [u32; 3], v: u32) -> [u32; 2] {
    if face[0] == v {
        [face[1], face[2]]
    } else if face[1] == v {
        [face[2], face[0]]
    } else {
        [face[0], face[1]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat hexagonal fan: centre 0 at the origin, ring 1..=6 at unit distance.
    fn hexagon_fan() -> TriMesh {
        let mut positions = vec![Vec3::zeros()];
        positions.extend((0..6).map(|k| {
            let t = k as f64 * std::f64::consts::TAU / 6.0;
            Vec3::new(t.cos(), t.sin(), 0.0)
        }));
        let faces = (0..6u32).map(|k| [0, 1 + k, 1 + (k + 1) % 6]).collect();
        TriMesh { positions, faces }
    }

    fn engine_for(mesh: &TriMesh) -> Engine {
        let config = SimplifyConfig::default();
        Engine::classify_vertices_and_fill_quadrics(
            &[mesh.positions.as_slice()],
            0,
            mesh,
            mesh.faces.clone(),
            None,
            None,
            &config,
        )
    }

    /// Collapsing ring vertex 1 into the centre while moving the centre past the
    /// opposite side of the ring turns the far faces over: refused as a flip. The same
    /// collapse onto the centre's own position is accepted.
    #[test]
    fn collapse_that_flips_a_face_is_refused() {
        let mut engine = engine_for(&hexagon_fan());
        let flipping =
            Candidate { remove: 1, keep: 0, position: Vec3::new(-1.5, 0.0, 0.0), error: 0.0, cost: 0.0 };
        assert!(matches!(engine.check_collapse(&flipping), Err(Refusal::Flip)));
        let fine = Candidate { position: Vec3::zeros(), ..flipping };
        assert!(engine.check_collapse(&fine).is_ok());
    }

    /// Moving the centre exactly onto the line through two ring vertices flattens the
    /// face between them to zero area: refused as degenerate.
    #[test]
    fn collapse_that_degenerates_a_face_is_refused() {
        let mut engine = engine_for(&hexagon_fan());
        // Face (0, 3, 4): ring 3 and 4 lie at 120° and 180°; their midpoint line.
        let (p3, p4) = (engine.positions[3], engine.positions[4]);
        let on_line = p3 + (p4 - p3) * 0.5;
        let c = Candidate { remove: 1, keep: 0, position: on_line, error: 0.0, cost: 0.0 };
        assert!(matches!(engine.check_collapse(&c), Err(Refusal::Degenerate)));
    }

    /// The link condition: in a closed octahedron every edge may collapse (apexes keep
    /// fans of four), but once a vertex has valence 3 its edges may not.
    #[test]
    fn link_condition_refuses_tetrahedral_fans() {
        let tetra = TriMesh {
            positions: vec![Vec3::zeros(), Vec3::x(), Vec3::y(), Vec3::z()],
            faces: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        };
        let mut engine = engine_for(&tetra);
        assert!(!engine.link_condition_holds(0, 1));
        let octahedron = TriMesh {
            positions: vec![Vec3::x(), -Vec3::x(), Vec3::y(), -Vec3::y(), Vec3::z(), -Vec3::z()],
            faces: vec![
                [0, 2, 4],
                [2, 1, 4],
                [1, 3, 4],
                [3, 0, 4],
                [2, 0, 5],
                [1, 2, 5],
                [3, 1, 5],
                [0, 3, 5],
            ],
        };
        let mut engine = engine_for(&octahedron);
        assert!(engine.link_condition_holds(0, 4));
    }
}
