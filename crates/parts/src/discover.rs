//! The orchestrator: discover near-rigid parts of a registered pose set, judged by
//! stage 1's own objective (the rigid-fit residual), every part kept connected.
//!
//! The idea is that of rigid-cluster initialisation in skinning decomposition (James &
//! Twigg 2005, "Skinning mesh animations"; Le & Deng 2012, "Smooth skinning
//! decomposition with rigid bones"): vertices that one rigid motion per pose explains
//! are a part. The story:
//! 1. cut the template into a few hundred small connected patches (`hierarchy`);
//! 2. merge adjacent parts bottom-up, cheapest first: the pair whose union adds least
//!    to stage 1's residual summed over all vertices and poses; the residual after each
//!    merge, up to `max_parts` parts, is the knee curve;
//! 3. keep the requested count, or the count at the knee (or the first count whose
//!    mean residual is within `rigid_tolerance`), and replay the merges to it;
//! 4. relax the borders at that count: refit every part, move each border vertex to
//!    the neighbouring part that explains it best, give every stray island of a part
//!    to the neighbouring part that explains it best, dissolve parts too small to fit;
//!    repeat until nothing moves (or `relax_sweeps`);
//! 5. number the parts by their smallest vertex.
//!
//! Every parallel step is an order-preserving map over vertices, parts or pairs whose
//! sums run in a fixed order, and every choice breaks ties by index, so the labels are
//! the same whatever the thread count.

use std::collections::BTreeMap;

use desal_fit::FitConfig;
use desal_mesh::math::{Real, bounding_box};
use desal_mesh::{PartLabels, PoseSet};
use rayon::prelude::*;

use crate::config::PartsConfig;
use crate::error::PartsError;
use crate::graph::VertexGraph;
use crate::hierarchy::{cut_patches, merge_sequence, replay};
use crate::knee::knee_index;
use crate::motion::{PartMotion, PoseData, fit_parts, members_of, own_costs};
use crate::report::{CurvePoint, PartsReport};

/// A move must lower a vertex's residual by more than this fraction: rounding alone
/// must not make two parts trade a vertex back and forth.
const MOVE_MARGIN: Real = 1e-12;

/// Discovers near-rigid parts of `poses` (see the module doc for the method).
///
/// Returns one part id per vertex (the pose set's vertex index space; ids `0..K`,
/// numbered by each part's smallest vertex, names `part0`, `part1`, …) and the report
/// with the residual-against-part-count curve (residuals in mesh units).
///
/// Guarantees: every part is connected on the mesh's edges (small loose pieces of the
/// mesh are attached to their nearest large piece first); every part has at least
/// `min_part_vertices` vertices and a rigid fit that stage 1 accepts in every pose; on
/// a connected mesh the part graph is connected. A mesh of C large pieces gets at
/// least C parts; a request for more parts than `patches` gets `patches`.
///
/// A pose set with no motion (a single pose, or every pose equal to the template
/// within `rigid_tolerance`) is not an error: it gets one part per connected piece
/// (one part for a connected mesh) and `report.motionless = true`, whatever `parts`
/// asks for; stage 1 then fits it exactly and saliency is uniform.
///
/// Errors: an option out of range, a mesh with no connected piece of
/// `min_part_vertices` vertices, or a connected piece that cannot carry a rigid fit.
pub fn discover_parts(
    poses: &PoseSet,
    config: &PartsConfig,
) -> Result<(PartLabels, PartsReport), PartsError> {
    config.validate()?;
    let data = PoseData::new(poses);
    let template = poses.template_positions();
    let (graph, pieces, piece_count) = VertexGraph::build(&poses.faces, template, config.min_part_vertices)?;
    let diagonal = bounding_box(template).map_or(0.0, |(lo, hi)| (hi - lo).norm());
    // Costs are sums over the non-template poses; the tolerance is per pose.
    let tolerance = config.rigid_tolerance * diagonal * data.pose_count as Real;

    let whole = State::new(&data, &graph, pieces.clone(), piece_count);
    if whole.worst_cost() <= tolerance {
        let point = CurvePoint { parts: piece_count, mean_residual: whole.mean_residual() };
        return finish(poses, &data, &whole, config, vec![point], 0, true, 0);
    }

    let (patch, patch_count) = cut_patches(&graph, template, &pieces, config.patches);
    let sequence = merge_sequence(&data, &graph, &patch, patch_count);
    let fewest = patch_count - sequence.merges.len();
    let most = config.max_parts.max(config.parts.unwrap_or(0)).min(patch_count).max(fewest);
    let samples = (data.vertex_count * data.pose_count) as Real;
    let curve: Vec<CurvePoint> = (fewest..=most)
        .map(|parts| CurvePoint { parts, mean_residual: sequence.residual[patch_count - parts] / samples })
        .collect();
    // Without K, a count that explains the motion to within the tolerance on average
    // needs no knee.
    let explained = curve.iter().position(|c| c.mean_residual * data.pose_count as Real <= tolerance);
    let chosen = match config.parts {
        Some(k) => curve.iter().rposition(|c| c.parts <= k).unwrap_or(0),
        None => explained.unwrap_or_else(|| knee_index(&curve)),
    };
    let parts = curve[chosen].parts;
    let labels = compact(&replay(&patch, patch_count, &sequence.merges, patch_count - parts));
    let mut state = State::new(&data, &graph, labels, parts);
    // A patch too small to fit may survive the merges; it goes before the borders move.
    dissolve_small_parts(&mut state, config);
    let sweeps = relax_borders(&mut state, config);
    finish(poses, &data, &state, config, curve, chosen, false, sweeps)
}

/// Part ids numbered `0..K` in order of each part's smallest vertex.
fn compact(labels: &[u32]) -> Vec<u32> {
    number_by_smallest_vertex(labels).labels
}

/// The final labels and report.
#[allow(clippy::too_many_arguments)]
fn finish(
    poses: &PoseSet,
    data: &PoseData,
    state: &State,
    config: &PartsConfig,
    curve: Vec<CurvePoint>,
    chosen: usize,
    motionless: bool,
    sweeps: usize,
) -> Result<(PartLabels, PartsReport), PartsError> {
    let labels = number_by_smallest_vertex(&state.labels);
    check_fittable(poses, data, &labels)?;
    let report = PartsReport {
        requested: config.parts,
        parts: labels.part_count(),
        curve,
        chosen,
        motionless,
        part_sizes: labels.members().iter().map(Vec::len).collect(),
        mean_residual: state.mean_residual(),
        sweeps,
    };
    Ok((labels, report))
}

/// Relaxes the borders of given parts by the same rule discovery uses (step 4 of the
/// module doc) and returns them renumbered by smallest vertex, with a one-point curve.
pub fn refine_parts(
    poses: &PoseSet,
    labels: &PartLabels,
    config: &PartsConfig,
) -> Result<(PartLabels, PartsReport), PartsError> {
    config.validate()?;
    let data = PoseData::new(poses);
    let template = poses.template_positions();
    let (graph, _, _) = VertexGraph::build(&poses.faces, template, config.min_part_vertices)?;
    let mut state = State::new(&data, &graph, labels.labels.clone(), labels.part_count());
    make_connected(&mut state);
    state.refit();
    dissolve_small_parts(&mut state, config);
    let sweeps = relax_borders(&mut state, config);
    let labels = number_by_smallest_vertex(&state.labels);
    let report = PartsReport {
        requested: Some(labels.part_count()),
        parts: labels.part_count(),
        curve: vec![CurvePoint { parts: labels.part_count(), mean_residual: state.mean_residual() }],
        chosen: 0,
        motionless: false,
        part_sizes: labels.members().iter().map(Vec::len).collect(),
        mean_residual: state.mean_residual(),
        sweeps,
    };
    Ok((labels, report))
}

/// The current parts, their motions and each vertex's residual under its own part.
struct State<'a> {
    data: &'a PoseData,
    graph: &'a VertexGraph,
    /// Part id per vertex, `0..part_count`.
    labels: Vec<u32>,
    part_count: usize,
    /// `motions[part]`, fitted to `labels`.
    motions: Vec<PartMotion>,
    /// Each vertex's residual under its own part, summed over the poses (mesh units).
    costs: Vec<Real>,
}

impl<'a> State<'a> {
    fn new(data: &'a PoseData, graph: &'a VertexGraph, labels: Vec<u32>, part_count: usize) -> Self {
        let mut state = Self { data, graph, labels, part_count, motions: Vec::new(), costs: Vec::new() };
        state.refit();
        state
    }

    /// Drops parts left without vertices, refits every part to the current labels and
    /// recomputes the costs.
    fn refit(&mut self) {
        let mut members = members_of(&self.labels, self.part_count);
        while let Some(empty) = members.iter().rposition(Vec::is_empty) {
            self.merge_part(empty as u32, 0);
            members = members_of(&self.labels, self.part_count);
        }
        self.motions = fit_parts(self.data, &members);
        self.costs = own_costs(self.data, &self.motions, &self.labels);
    }

    /// Gives part `part`'s vertices to part `into` and closes the gap in the ids (the
    /// last part takes `part`'s id). Leaves the motions stale.
    fn merge_part(&mut self, part: u32, into: u32) {
        let last = (self.part_count - 1) as u32;
        for label in &mut self.labels {
            if *label == part {
                *label = into;
            }
            if *label == last {
                *label = part;
            }
        }
        self.part_count -= 1;
    }

    fn worst_cost(&self) -> Real {
        self.costs.iter().copied().fold(0.0, Real::max)
    }

    /// Stage 1's mean residual with the current parts (mesh units).
    fn mean_residual(&self) -> Real {
        let samples = self.data.vertex_count * self.data.pose_count;
        if samples == 0 { 0.0 } else { self.costs.iter().sum::<Real>() / samples as Real }
    }

    /// The summed cost of explaining `vertices` by part `part`'s motions.
    fn cost_of(&self, vertices: &[u32], part: u32) -> Real {
        vertices.iter().map(|&v| self.motions[part as usize].cost(self.data, v as usize)).sum()
    }
}

/// Step 3: relaxes the borders until no vertex moves (or `relax_sweeps`); returns the
/// sweeps run. Expects `state` fitted; leaves it fitted.
fn relax_borders(state: &mut State, config: &PartsConfig) -> usize {
    for sweep in 0..config.relax_sweeps {
        let moves = pick_border_moves(state);
        if moves.is_empty() {
            return sweep;
        }
        for (v, part) in moves {
            state.labels[v as usize] = part;
        }
        make_connected(state);
        state.refit();
        dissolve_small_parts(state, config);
    }
    config.relax_sweeps
}

/// Every border vertex whose best-explaining part among its own and its neighbours'
/// differs from its own, with that part (ties: the smaller part id). Decided for all
/// vertices from the same labels, in parallel, in vertex order.
fn pick_border_moves(state: &State) -> Vec<(u32, u32)> {
    let labels = &state.labels;
    (0..state.data.vertex_count)
        .into_par_iter()
        .filter_map(|v| {
            let own = labels[v];
            let mut candidates: Vec<u32> =
                state.graph.around(v).iter().map(|&u| labels[u as usize]).filter(|&k| k != own).collect();
            if candidates.is_empty() {
                return None;
            }
            candidates.sort_unstable();
            candidates.dedup();
            let mut best = (state.costs[v] * (1.0 - MOVE_MARGIN), own);
            for k in candidates {
                let cost = state.motions[k as usize].cost(state.data, v);
                if cost < best.0 {
                    best = (cost, k);
                }
            }
            (best.1 != own).then_some((v as u32, best.1))
        })
        .collect()
}

/// Gives every stray island of a part (a connected component other than the part's
/// largest, ties by smallest vertex) to the adjacent part whose motions explain it
/// best (ties: smaller id). An island joins only a part's main component, which never
/// changes within a pass, so each pass leaves the joined parts connected; islands
/// surrounded by other islands wait for the next pass. Uses the current motions.
fn make_connected(state: &mut State) {
    loop {
        let (component, sizes) = state.graph.components(&state.labels);
        let mut vertices: Vec<Vec<u32>> = vec![Vec::new(); sizes.len()];
        for (v, &c) in component.iter().enumerate() {
            vertices[c as usize].push(v as u32);
        }
        let label_of = |c: usize| state.labels[vertices[c][0] as usize];
        let mut main = vec![usize::MAX; state.part_count];
        for c in 0..sizes.len() {
            let m = &mut main[label_of(c) as usize];
            if *m == usize::MAX || sizes[c] > sizes[*m] {
                *m = c;
            }
        }
        let strays: Vec<usize> = (0..sizes.len()).filter(|&c| main[label_of(c) as usize] != c).collect();
        if strays.is_empty() {
            return;
        }
        let decisions: Vec<Option<u32>> = strays
            .par_iter()
            .map(|&c| {
                let mut candidates: Vec<u32> = vertices[c]
                    .iter()
                    .flat_map(|&v| state.graph.around(v as usize))
                    .filter(|&&u| {
                        let cu = component[u as usize] as usize;
                        cu != c && main[label_of(cu) as usize] == cu
                    })
                    .map(|&u| state.labels[u as usize])
                    .collect();
                candidates.sort_unstable();
                candidates.dedup();
                candidates
                    .into_iter()
                    .map(|k| (state.cost_of(&vertices[c], k), k))
                    .reduce(|a, b| if b.0 < a.0 { b } else { a })
                    .map(|(_, k)| k)
            })
            .collect();
        if decisions.iter().all(Option::is_none) {
            // Cannot happen on a connected piece (some island always touches a main
            // component); kept so that a bug cannot loop forever.
            debug_assert!(false, "stray islands with no main component next to them");
            return;
        }
        for (&c, decision) in strays.iter().zip(decisions) {
            if let Some(k) = decision {
                for &v in &vertices[c] {
                    state.labels[v as usize] = k;
                }
            }
        }
    }
}

/// Dissolves every part too small (under `min_part_vertices`) or too thin (a fit that
/// stage 1 would refuse as degenerate in some pose) into the adjacent part that
/// explains it best, smallest first (ties by id), then closes the gap in the ids.
/// Expects `state` fitted; leaves it fitted.
fn dissolve_small_parts(state: &mut State, config: &PartsConfig) {
    let degenerate_ratio = FitConfig::default().degenerate_ratio;
    loop {
        let members = members_of(&state.labels, state.part_count);
        let mut weak: Vec<usize> = (0..state.part_count)
            .filter(|&k| {
                members[k].len() < config.min_part_vertices || state.motions[k].min_ratio < degenerate_ratio
            })
            .collect();
        weak.sort_by_key(|&k| (members[k].len(), k));
        // A weak part with no neighbour is a whole connected piece of the mesh: it
        // stays, and the final check reports it if it cannot be fitted.
        let Some((part, into)) =
            weak.into_iter().find_map(|k| best_neighbour(state, &members[k], k as u32).map(|into| (k, into)))
        else {
            return;
        };
        state.merge_part(part as u32, into);
        state.refit();
    }
}

/// The part other than `own` next to `vertices` whose motions explain them best (ties:
/// the smaller id), if any.
fn best_neighbour(state: &State, vertices: &[u32], own: u32) -> Option<u32> {
    let mut neighbours: Vec<u32> = vertices
        .iter()
        .flat_map(|&v| state.graph.around(v as usize))
        .map(|&u| state.labels[u as usize])
        .filter(|&k| k != own)
        .collect();
    neighbours.sort_unstable();
    neighbours.dedup();
    neighbours
        .into_iter()
        .map(|k| (state.cost_of(vertices, k), k))
        .reduce(|a, b| if b.0 < a.0 { b } else { a })
        .map(|(_, k)| k)
}

/// The same partition with parts numbered in order of their smallest vertex, named
/// `part0`, `part1`, …
fn number_by_smallest_vertex(labels: &[u32]) -> PartLabels {
    let mut renumber: BTreeMap<u32, u32> = BTreeMap::new();
    let ids: Vec<u32> = labels
        .iter()
        .map(|&k| {
            let next = renumber.len() as u32;
            *renumber.entry(k).or_insert(next)
        })
        .collect();
    PartLabels::from_ids(ids)
}

/// Every part spans a plane in the template and fits every pose as stage 1 requires.
fn check_fittable(poses: &PoseSet, data: &PoseData, labels: &PartLabels) -> Result<(), PartsError> {
    let members = labels.members();
    if let Err(desal_mesh::MeshError::DegeneratePart { part, vertices, .. }) =
        labels.check_parts_fittable(poses.template_positions())
    {
        return Err(PartsError::DegeneratePart { part, vertices });
    }
    let degenerate_ratio = FitConfig::default().degenerate_ratio;
    for (part, m) in members.iter().enumerate() {
        if PartMotion::fit(data, m).min_ratio < degenerate_ratio {
            return Err(PartsError::DegeneratePart { part: part as u32, vertices: m.len() });
        }
    }
    Ok(())
}
