//! Stage 3 of a rig's meshes under one budget (issue 42, item 2): stages 1–2 ran once
//! over every welded vertex of the rig; here each glTF mesh gets its rule and stage 3
//! runs per rule, through the one stage-3 entry (`simplify::run`), on the pose set cut to
//! those meshes:
//!
//! | rule | when | run |
//! |---|---|---|
//! | `whole` | `[dataset.rig.meshes."NAME"] ratio = 1.0`, or a mesh of several whose share of the target would be under [`KEEP_WHOLE_BELOW_FACES`] faces (eyes, teeth) | none: every vertex and face kept |
//! | `ratio` | `[dataset.rig.meshes."NAME"] ratio = r < 1`, or every mesh when the target is `ratio` | alone, to its own ratio |
//! | `shared` | the other meshes when the target is `target_faces` or `target_vertices` | together, to the total less what the others keep, so the budget goes where collapses cost least (a collapse never joins two meshes) |
//!
//! A mesh's *share* is its faces times the target's ratio (`ratio`, or the target over
//! the rig's faces or vertices). Without overrides, a rig of one mesh, or of several
//! under a face or vertex target with no small mesh, has no plan: stage 3 runs once as
//! before. The output keeps the meshes in document order, each a run of vertices
//! (`simplified-rig.json`'s ranges).
//!
//! Index spaces: `orig_idx` (the pose set's welded vertices), `group_idx` (a run's cut
//! pose set, its meshes' vertices in order).

use std::collections::BTreeMap;

use anyhow::{Result, bail};
use desal_io::ContentHash;
use desal_io::artifact::SimplifiedV1;
use desal_mesh::{PartLabels, PoseSet, Progress};
use desal_simplify::{StopReason, Target};
use serde::{Deserialize, Serialize};

use crate::cache::canonical_json;
use crate::stages::runner::StageOutput;
use crate::stages::saliency::SaliencyParams;
use crate::stages::simplify::{self, SimplifyParams, SimplifySummary};

/// A mesh of several whose share of the target is under this many faces is kept whole
/// unless `[dataset.rig.meshes."NAME"]` sets its ratio: eyes (a few hundred faces) and
/// teeth keep their shape at any target, and cost little.
pub const KEEP_WHOLE_BELOW_FACES: usize = 200;

/// The smallest face or vertex target stage 3 takes (a tetrahedron's 4).
const SMALLEST_TARGET: usize = 4;

/// `[dataset.rig.meshes."NAME"]`: one mesh's own setting.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshOverride {
    /// This mesh's faces kept, in (0, 1]; 1 keeps it whole.
    pub ratio: f64,
}

impl MeshOverride {
    pub fn check(&self, name: &str) -> Result<()> {
        if !(self.ratio > 0.0 && self.ratio <= 1.0) {
            bail!("rig.meshes.\"{name}\".ratio = {} is not in (0, 1]", self.ratio);
        }
        Ok(())
    }
}

/// How a mesh is simplified.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "kebab-case", tag = "rule", content = "ratio")]
pub enum MeshRule {
    Whole,
    Ratio(f64),
    Shared,
}

/// One mesh of a [`MeshPlan`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshSlot {
    pub name: String,
    /// Its welded vertices, `[first, end)` in `orig_idx`.
    pub vertices: [u32; 2],
    pub faces: usize,
    pub rule: MeshRule,
}

/// Every simplified mesh's rule, in document order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshPlan {
    pub slots: Vec<MeshSlot>,
}

/// A mesh as the plan reads it: the names it answers to (mesh name, node name, mesh
/// index) and its welded vertices.
#[derive(Debug, Clone)]
pub struct MeshOfRig {
    pub name: String,
    pub aliases: Vec<String>,
    pub vertices: [u32; 2],
}

impl MeshPlan {
    /// The plan of `meshes` (the rig's, in document order, covering `set`'s vertices)
    /// under `target`, with `overrides` by mesh name, node name or index; `None` when
    /// stage 3 runs once as before (module doc). Refused: an override naming no mesh
    /// (`RigError::NoSuchMeshOverride`, naming `file`).
    pub fn new(
        file: &std::path::Path,
        meshes: &[MeshOfRig],
        set: &PoseSet,
        target: Target,
        overrides: &BTreeMap<String, MeshOverride>,
    ) -> Result<Option<MeshPlan>> {
        for (name, o) in overrides {
            o.check(name)?;
            if !meshes.iter().any(|m| m.aliases.contains(name)) {
                let known: Vec<&str> = meshes.iter().map(|m| m.name.as_str()).collect();
                return Err(desal_rig::RigError::NoSuchMeshOverride {
                    path: file.to_owned(),
                    wanted: name.clone(),
                    names: known.join(", "),
                }
                .into());
            }
        }
        let total_faces = set.faces.len().max(1);
        let share_ratio = match target {
            Target::Ratio(r) => r,
            Target::Faces(n) => n as f64 / total_faces as f64,
            Target::Vertices(n) => n as f64 / set.vertex_count().max(1) as f64,
        };
        let mut faces = vec![0usize; meshes.len()];
        for f in &set.faces {
            if let Some(k) = meshes.iter().position(|m| (m.vertices[0]..m.vertices[1]).contains(&f[0])) {
                faces[k] += 1;
            }
        }
        let slots: Vec<MeshSlot> = meshes
            .iter()
            .zip(&faces)
            .map(|(m, &faces)| {
                let own = overrides.iter().find(|(name, _)| m.aliases.contains(name)).map(|(_, o)| o.ratio);
                let rule = match (own, target) {
                    (Some(r), _) if r >= 1.0 => MeshRule::Whole,
                    (Some(r), _) => MeshRule::Ratio(r),
                    (None, _)
                        if meshes.len() > 1
                            && share_ratio * (faces as f64) < KEEP_WHOLE_BELOW_FACES as f64 =>
                    {
                        MeshRule::Whole
                    }
                    (None, Target::Ratio(r)) => MeshRule::Ratio(r),
                    (None, _) => MeshRule::Shared,
                };
                MeshSlot { name: m.name.clone(), vertices: m.vertices, faces, rule }
            })
            .collect();
        let one_run = match target {
            Target::Ratio(_) => slots.len() == 1 && overrides.is_empty(),
            _ => slots.iter().all(|s| s.rule == MeshRule::Shared),
        };
        Ok((!one_run).then_some(MeshPlan { slots }))
    }

    /// The plan's content hash, stage 3's key input `meshes`.
    pub fn hash(&self) -> ContentHash {
        ContentHash::of(canonical_json(self).as_bytes())
    }

    /// This plan on a subset of its vertices (`kept_orig`, ascending, e.g. a LOD level
    /// above the next one): the same meshes over the kept vertices, the whole ones still
    /// whole and every other shared (a level's target is a face count); `None` when
    /// `kept_orig` is not ascending.
    pub fn on_subset(&self, kept_orig: &[u32]) -> Option<MeshPlan> {
        if !kept_orig.windows(2).all(|w| w[0] < w[1]) {
            return None;
        }
        let index = |orig: u32| kept_orig.partition_point(|&k| k < orig) as u32;
        let slots = self
            .slots
            .iter()
            .map(|s| MeshSlot {
                name: s.name.clone(),
                vertices: [index(s.vertices[0]), index(s.vertices[1])],
                faces: 0,
                rule: if s.rule == MeshRule::Whole { MeshRule::Whole } else { MeshRule::Shared },
            })
            .collect();
        Some(MeshPlan { slots })
    }
}

/// One run's result mapped back: each output vertex's position, original vertex (when
/// kept in place) and mesh; faces in output numbers.
struct RunOutput {
    positions: Vec<[f64; 3]>,
    simp_to_orig: Vec<Option<u32>>,
    slot_of: Vec<usize>,
    faces: Vec<[u32; 3]>,
    summary: Option<SimplifySummary>,
}

/// Stage 3 by `plan`: each rule's runs (module doc), merged in document order.
#[allow(clippy::too_many_arguments)]
pub fn run(
    plan: &MeshPlan,
    params: &SimplifyParams,
    saliency: &SaliencyParams,
    set: &PoseSet,
    labels: &PartLabels,
    weights: &[f64],
    seams: Option<&[[u32; 2]]>,
    progress: &dyn Progress,
) -> Result<StageOutput<SimplifiedV1, SimplifySummary>> {
    let start = std::time::Instant::now();
    let cut = |slots: &[usize], target: Target| -> Result<RunOutput> {
        run_on(plan, slots, params, target, saliency, set, labels, weights, seams, progress)
    };
    let mut runs: Vec<RunOutput> = Vec::new();
    let mut kept_faces = 0usize;
    let mut kept_vertices = 0usize;
    for (k, slot) in plan.slots.iter().enumerate() {
        let run = match slot.rule {
            MeshRule::Whole => whole(plan, k, set),
            MeshRule::Ratio(r) => cut(&[k], Target::Ratio(r))?,
            MeshRule::Shared => continue,
        };
        kept_faces += run.faces.len();
        kept_vertices += run.positions.len();
        runs.push(run);
    }
    let shared: Vec<usize> =
        (0..plan.slots.len()).filter(|&k| plan.slots[k].rule == MeshRule::Shared).collect();
    if !shared.is_empty() {
        // The shared meshes take what the others left of the total; when the others
        // already take it all, they are simplified as far as stage 3 can (the smallest
        // target it takes, a tetrahedron's): a missed target is a result, not an error.
        let target = match params.target() {
            Target::Faces(n) => Target::Faces(n.saturating_sub(kept_faces).max(SMALLEST_TARGET)),
            Target::Vertices(n) => Target::Vertices(n.saturating_sub(kept_vertices).max(SMALLEST_TARGET)),
            Target::Ratio(r) => Target::Ratio(r),
        };
        runs.push(cut(&shared, target)?);
    }
    merge(plan, params, set, runs, start)
}

/// A whole mesh: its vertices and faces as they are.
fn whole(plan: &MeshPlan, k: usize, set: &PoseSet) -> RunOutput {
    let [first, end] = plan.slots[k].vertices;
    let template = set.template_positions();
    RunOutput {
        positions: (first..end).map(|o| template[o as usize].into()).collect(),
        simp_to_orig: (first..end).map(Some).collect(),
        slot_of: vec![k; (end - first) as usize],
        faces: set
            .faces
            .iter()
            .filter(|f| (first..end).contains(&f[0]))
            .map(|f| f.map(|v| v - first))
            .collect(),
        summary: None,
    }
}

/// Stage 3 on the meshes `slots` alone, to `target`.
#[allow(clippy::too_many_arguments)]
fn run_on(
    plan: &MeshPlan,
    slots: &[usize],
    params: &SimplifyParams,
    target: Target,
    saliency: &SaliencyParams,
    set: &PoseSet,
    labels: &PartLabels,
    weights: &[f64],
    seams: Option<&[[u32; 2]]>,
    progress: &dyn Progress,
) -> Result<RunOutput> {
    let group_to_orig: Vec<u32> =
        slots.iter().flat_map(|&k| plan.slots[k].vertices[0]..plan.slots[k].vertices[1]).collect();
    let mut group_of = vec![u32::MAX; set.vertex_count()];
    for (g, &o) in group_to_orig.iter().enumerate() {
        group_of[o as usize] = g as u32;
    }
    let faces: Vec<[u32; 3]> = set
        .faces
        .iter()
        .filter(|f| group_of[f[0] as usize] != u32::MAX)
        .map(|f| f.map(|v| group_of[v as usize]))
        .collect();
    if faces.iter().flatten().any(|&v| v == u32::MAX) {
        bail!("a face of the rig joins two meshes, which the weld never does");
    }
    let cut = desal_hierarchy::level_poses(set, &group_to_orig, &faces)?;
    let carried = PartLabels {
        labels: group_to_orig.iter().map(|&o| labels.labels[o as usize]).collect(),
        names: labels.names.clone(),
        parents: labels.parents.clone(),
    };
    // The cut's parts: those of other meshes are empty here, and one of these meshes may
    // hold too few vertices of a joint to fit; a rig's labels hand them to their parents.
    let (cut_labels, _) = carried.merge_unfittable_parts(cut.template_positions());
    let cut_weights: Vec<f64> = group_to_orig.iter().map(|&o| weights[o as usize]).collect();
    let cut_seams: Option<Vec<[u32; 2]>> = seams.map(|s| {
        s.iter()
            .filter(|e| group_of[e[0] as usize] != u32::MAX && group_of[e[1] as usize] != u32::MAX)
            .map(|e| e.map(|v| group_of[v as usize]))
            .collect()
    });
    let (target_vertices, target_faces, ratio) = match target {
        Target::Vertices(n) => (Some(n), None, None),
        Target::Faces(n) => (None, Some(n), None),
        Target::Ratio(r) => (None, None, Some(r)),
    };
    let own = SimplifyParams { target_vertices, target_faces, ratio, ..params.clone() };
    let out = simplify::run(&own, saliency, &cut, &cut_labels, &cut_weights, cut_seams.as_deref(), progress)?;
    let simp_to_orig: Vec<Option<u32>> =
        out.body.simp_to_orig.iter().map(|g| g.map(|g| group_to_orig[g as usize])).collect();
    let slot_of = slots_of_output(plan, slots, &simp_to_orig, &out.body.faces)?;
    Ok(RunOutput {
        positions: out.body.positions,
        simp_to_orig,
        slot_of,
        faces: out.body.faces,
        summary: Some(out.summary),
    })
}

/// The mesh of each output vertex of a run over `slots`: a vertex kept in place is its
/// original's; the others take the mesh of a vertex they share a face with (faces never
/// join two meshes); a piece of moved vertices only takes the mesh of the vertex before
/// it in output order, which stage 3 keeps in input order, so meshes follow one another.
fn slots_of_output(
    plan: &MeshPlan,
    slots: &[usize],
    simp_to_orig: &[Option<u32>],
    faces: &[[u32; 3]],
) -> Result<Vec<usize>> {
    let slot_of_orig = |o: u32| {
        slots.iter().copied().find(|&k| (plan.slots[k].vertices[0]..plan.slots[k].vertices[1]).contains(&o))
    };
    let mut slot: Vec<Option<usize>> = simp_to_orig.iter().map(|o| o.and_then(slot_of_orig)).collect();
    // Spread along faces until nothing changes (each pass reaches one ring further).
    loop {
        let mut changed = false;
        for f in faces {
            if let Some(k) = f.iter().find_map(|&v| slot[v as usize]) {
                for &v in f {
                    if slot[v as usize].is_none() {
                        slot[v as usize] = Some(k);
                        changed = true;
                    }
                }
            }
        }
        if !changed {
            break;
        }
    }
    let Some(&first) = slots.first() else { bail!("stage 3 ran over no mesh") };
    let mut previous = first;
    let slot: Vec<usize> = slot
        .into_iter()
        .map(|k| {
            previous = k.unwrap_or(previous);
            previous
        })
        .collect();
    if slot.windows(2).any(|w| w[0] > w[1]) {
        bail!("stage 3's output does not keep the meshes in order; please report this");
    }
    Ok(slot)
}

/// The runs' outputs as one stage-3 output, every mesh's vertices in document order.
fn merge(
    plan: &MeshPlan,
    params: &SimplifyParams,
    set: &PoseSet,
    runs: Vec<RunOutput>,
    start: std::time::Instant,
) -> Result<StageOutput<SimplifiedV1, SimplifySummary>> {
    let mut positions = Vec::new();
    let mut simp_to_orig = Vec::new();
    let mut faces = Vec::new();
    for k in 0..plan.slots.len() {
        for run in &runs {
            let mine: Vec<usize> = (0..run.slot_of.len()).filter(|&v| run.slot_of[v] == k).collect();
            let Some(&first) = mine.first() else { continue };
            let offset = positions.len() as u32;
            positions.extend(mine.iter().map(|&v| run.positions[v]));
            simp_to_orig.extend(mine.iter().map(|&v| run.simp_to_orig[v]));
            let base = first as u32;
            faces.extend(
                run.faces
                    .iter()
                    .filter(|f| run.slot_of[f[0] as usize] == k)
                    .map(|f| f.map(|v| v - base + offset)),
            );
        }
    }
    let summaries: Vec<&SimplifySummary> = runs.iter().filter_map(|r| r.summary.as_ref()).collect();
    let mesh = desal_mesh::TriMesh {
        positions: positions.iter().map(|&p| p.into()).collect(),
        faces: faces.clone(),
    };
    let (edge_length_mean, edge_length_variance) = desal_mesh::edge_length_stats(&mesh.positions, &faces);
    let sum = |f: fn(&SimplifySummary) -> usize| summaries.iter().map(|s| f(s)).sum::<usize>();
    let first = summaries.first().copied();
    let stop = summaries
        .iter()
        .map(|s| s.stop)
        .find(|&s| s != StopReason::TargetReached)
        .unwrap_or(StopReason::TargetReached);
    let max_error = summaries.iter().map(|s| s.max_error).fold(0.0, f64::max);
    let moved = sum(|s| s.output_vertices).max(1) as f64;
    let mean_error = summaries.iter().map(|s| s.mean_error * s.output_vertices as f64).sum::<f64>() / moved;
    let seams =
        |f: fn(&SimplifySummary) -> Option<usize>| summaries.iter().filter_map(|s| f(s)).reduce(|a, b| a + b);
    let config = params.config()?;
    let method = match (first, params.method) {
        (Some(s), _) => s.method.clone(),
        (None, Some(m)) => m.name().to_owned(),
        (None, None) => simplify::Cost::of(&config).name().to_owned(),
    };
    let summary = SimplifySummary {
        method,
        placement: first.map_or(config.placement, |s| s.placement),
        metric: config.metric,
        input_vertices: set.vertex_count(),
        input_faces: set.faces.len(),
        output_vertices: positions.len(),
        output_faces: faces.len(),
        collapses: sum(|s| s.collapses),
        stop,
        refused_topology: sum(|s| s.refused_topology),
        refused_flip: sum(|s| s.refused_flip),
        refused_fold: sum(|s| s.refused_fold),
        refused_degenerate: sum(|s| s.refused_degenerate),
        refused_seam: seams(|s| s.refused_seam),
        locked_vertices: sum(|s| s.locked_vertices),
        seam_vertices: seams(|s| s.seam_vertices),
        max_error,
        mean_error,
        edge_length_mean,
        edge_length_variance,
        seconds: start.elapsed().as_secs_f64(),
    };
    let rules: Vec<String> = plan
        .slots
        .iter()
        .map(|s| match s.rule {
            MeshRule::Whole => format!("{} whole", s.name),
            MeshRule::Ratio(r) => format!("{} at ratio {r}", s.name),
            MeshRule::Shared => format!("{} shared", s.name),
        })
        .collect();
    let note = format!(
        "{} -> {} faces, {} -> {} vertices over {} meshes ({}), error max {:.2e}",
        summary.input_faces,
        summary.output_faces,
        summary.input_vertices,
        summary.output_vertices,
        plan.slots.len(),
        rules.join(", "),
        max_error
    );
    let body = SimplifiedV1 {
        positions,
        faces,
        simp_to_orig,
        placement: summary.placement.name().into(),
        input_vertices: summary.input_vertices as u32,
        input_faces: summary.input_faces as u32,
        collapses: summary.collapses as u32,
        stop: summary.stop.name().into(),
        max_error,
        mean_error,
        edge_length_mean,
        edge_length_variance,
    };
    Ok(StageOutput { body, summary, note })
}
