//! Issue 42, item 9: a rig's LOD chain judged as the files an engine loads, level by level
//! and mesh by mesh, beside gltfpack at the same face counts.
//!
//! For every level of `[dataset.rig] lods`, desal's level is the rig `desal run` writes
//! (`simplified-lod<k>.glb`: `stages::rig::lod_glbs`, each level simplified from the one
//! before, its weights capped at `max_influences`), read back as any file; `gltfpack` and
//! `gltfpack-sa`, when they are among the eval's methods, are bisected to the level's
//! face count (`gltfpack::bisect`), and meshoptimizer's variants (`meshopt`,
//! `meshopt-regularize`, `meshopt-priority` with saliency as `Priority`) simplify the input
//! to that count in one run and are written by desal's own writer, so they differ from
//! desal's level in the mesh alone (its weights capped alike). Each is skinned with its own weights
//! ([`RigModel::welded`]) at frames no stage saw — random joint turns drawn with the
//! dataset's seed + 1 ([`RigModel::held_out`]), as many as the dataset samples — and
//! measured against the full rig skinned at the same frames:
//!
//! - the LBS v2f of the whole rig and of each mesh;
//! - the spikes per frame, each face judged against its own mesh ([`MeshSplit`]);
//! - each morph target's v2f at weight 1 in the bind pose, against the full mesh at
//!   weight 1.
//!
//! A simplified vertex belongs to the mesh of the full vertex nearest to it in the bind
//! pose (gltfpack renames meshes, and every tool here keeps input positions).

use anyhow::{Context, Result};
use desal_driver::stages::DatasetStages;
use desal_measures::metrics::v2f_halves_indexed;
use desal_measures::{SurfaceIndex, VertexIndex};
use desal_mesh::{TriMesh, Vec3};
use desal_rig::{MorphTarget, ReadOptions, Rig, SourceDocument};
use rayon::prelude::*;
use serde::Serialize;

use crate::measure::{MeshSplit, SpikeSurfaces, mesh_part, spike_count};
use crate::methods::{Inputs, Method};
use crate::rig::{RigModel, WeldedRig};

/// One LOD level: every method at its face count.
#[derive(Debug, Clone, Serialize)]
pub struct LevelReport {
    /// 1 for the first level below the input.
    pub level: usize,
    /// The level's `lods` entry (a fraction of the input's faces).
    pub fraction: f64,
    /// desal's faces at this level (welded), the count the others are bisected to.
    pub faces: usize,
    /// The input's meshes, in `Rig::meshes` order.
    pub meshes: Vec<String>,
    pub methods: Vec<LevelMethod>,
}

/// One method at one level.
#[derive(Debug, Clone, Serialize)]
pub struct LevelMethod {
    pub method: String,
    /// How the file was made (gltfpack's ratio and runs).
    pub note: String,
    /// Welded faces and vertices.
    pub faces: usize,
    pub vertices: usize,
    /// Most joint influences of a vertex, as written.
    pub max_influences: usize,
    /// Per held-out frame, the LBS v2f of the whole rig (squared input units).
    pub v2f: Vec<f64>,
    /// Per mesh of [`LevelReport::meshes`], its faces and its LBS v2f (mean over frames;
    /// `None` for a mesh the method has no face of).
    pub mesh_faces: Vec<usize>,
    pub mesh_v2f: Vec<Option<f64>>,
    /// Per held-out frame, the spikes.
    pub spikes: Vec<usize>,
    /// Every morph target of the input.
    pub morphs: Vec<MorphError>,
}

/// One morph target's error at weight 1.
#[derive(Debug, Clone, Serialize)]
pub struct MorphError {
    pub mesh: String,
    pub target: String,
    /// v2f of the mesh with the target at weight 1 against the full one; `None` when the
    /// method's file lost the target or every face of the mesh.
    pub v2f: Option<f64>,
}

/// The held-out frames' full-resolution targets, built once for every level and method.
struct FullFrames {
    /// Per frame (the held-out pose set's non-template poses): the whole posed rig and
    /// its index, and each mesh apart with its index (for its v2f and its spikes).
    frames: Vec<FullFrame>,
    split: MeshSplit,
    /// Bind-pose index of the full vertices, to tell a simplified vertex's mesh.
    bind: VertexIndex,
    /// Per input morph target: the full mesh at weight 1, compact, with its index.
    morphs: Vec<(TriMesh, SurfaceIndex)>,
    targets: Vec<MorphTarget>,
}

struct FullFrame {
    pose: usize,
    whole: (TriMesh, SurfaceIndex),
    /// Each mesh apart with its index (for its v2f and its spikes).
    meshes: SpikeSurfaces<'static>,
}

/// Every level of the dataset's `lods`, each method of `methods` that can run on a chain
/// (desal's own chain always; gltfpack's variants when asked for), measured at held-out
/// frames. Empty without `lods`.
pub fn evaluate(
    stages: &DatasetStages,
    inputs: &Inputs,
    methods: &[Method],
    log: &dyn Fn(&str),
) -> Result<Vec<LevelReport>> {
    let Some(source) = stages.rig.as_ref() else { return Ok(Vec::new()) };
    if stages.lods.is_empty() {
        return Ok(Vec::new());
    }
    let (model, targets) = RigModel::held_out(source)?;
    let full = FullFrames::new(&model, targets);
    log(&format!(
        "LOD levels: {} held-out frames (random turns, seed + 1), {} meshes, {} morph targets",
        full.frames.len(),
        full.split.mesh_count,
        full.targets.len()
    ));
    let levels = stages.lods.iter().map(|l| Ok((l.body()?, &l.summary))).collect::<Result<Vec<_>>>()?;
    let written =
        desal_driver::stages::rig::lod_glbs(source, &levels).context("writing desal's LOD levels")?;
    let options = ReadOptions { mesh: source.params.mesh.clone() };
    let mut reports = Vec::with_capacity(levels.len());
    for (k, ((_, summary), glb)) in levels.iter().zip(&written.levels).enumerate() {
        let name = desal_driver::stages::rig::lod_file_name(source, Some(k + 1));
        let path = source.file.with_file_name(&name);
        let (rig, document) = desal_rig::read_rig_and_document(&path, &glb.bytes, &options)
            .with_context(|| format!("reading back desal's {name}"))?;
        let mut rows = vec![full.measure(&model, "desal", format!("`{name}`"), &rig, &document)?];
        #[cfg(feature = "gltfpack")]
        for method in methods {
            let Method::Gltfpack(variant) = method else { continue };
            let aim = crate::gltfpack::Aim::Faces(summary.faces);
            let out = crate::gltfpack::bisect(&model, *variant, aim)
                .with_context(|| format!("{} at LOD level {}", variant.name(), k + 1))?;
            let note = format!(
                "{} `-si {:.6} {}` ({} runs bisecting its ratio{})",
                out.version,
                out.ratio,
                variant.flags().join(" "),
                out.runs,
                if out.reached(aim) { "" } else { "; it stopped above the face count" }
            );
            rows.push(full.measure(&model, variant.name(), note, &out.rig, &out.document)?);
        }
        #[cfg(feature = "meshopt")]
        for method in methods {
            let Method::Meshopt(variant) = method else { continue };
            let body = crate::meshopt::simplify_to_faces(
                &inputs.poses.template_mesh(),
                &inputs.weights,
                *variant,
                summary.faces,
            );
            let (rig, document) = written_subset(source, &body, summary, &options)
                .with_context(|| format!("{} at LOD level {}", variant.name(), k + 1))?;
            let note = "simplified from the input to the level's faces, written by desal's writer".to_owned();
            rows.push(full.measure(&model, variant.name(), note, &rig, &document)?);
        }
        #[cfg(not(all(feature = "gltfpack", feature = "meshopt")))]
        let _ = (methods, inputs);
        log(&format!("LOD level {}: {} methods measured", k + 1, rows.len()));
        reports.push(LevelReport {
            level: summary.level,
            fraction: summary.fraction,
            faces: summary.faces,
            meshes: model.rig.meshes.iter().map(|m| m.name.clone()).collect(),
            methods: rows,
        });
    }
    Ok(reports)
}

/// A subset simplification (`body`, of the pose set's template) written as desal writes a
/// level of the chain (`lod_glbs`: the same weights, capped alike) and read back.
#[cfg(feature = "meshopt")]
fn written_subset(
    source: &desal_driver::stages::rig::RigSource,
    body: &desal_io::artifact::SimplifiedV1,
    level: &desal_driver::stages::rig::LodSummary,
    options: &ReadOptions,
) -> Result<(Rig, SourceDocument)> {
    let simp_to_orig: Vec<u32> =
        body.simp_to_orig.iter().map(|o| o.context("not a subset")).collect::<Result<_>>()?;
    let map = desal_io::artifact::MapV1 {
        simp_to_orig,
        faces: body.faces.clone(),
        mode: "subset".into(),
        displacement_mean: 0.0,
        displacement_max: 0.0,
    };
    let summary = desal_driver::stages::rig::LodSummary {
        vertices: map.simp_to_orig.len(),
        faces: map.faces.len(),
        stop: body.stop.clone(),
        ..level.clone()
    };
    let written = desal_driver::stages::rig::lod_glbs(source, &[(&map, &summary)])?;
    let glb = written.levels.first().context("one level written")?;
    let path = source.file.with_file_name("subset.glb");
    Ok(desal_rig::read_rig_and_document(&path, &glb.bytes, options)?)
}

impl FullFrames {
    fn new(model: &RigModel, targets: Vec<MorphTarget>) -> Self {
        let poses = &model.posed.poses;
        let split = model
            .mesh_split()
            .unwrap_or_else(|| MeshSplit { of_vertex: vec![0; poses.vertex_count()], mesh_count: 1 });
        let face_mesh = split.face_meshes(&poses.faces, |v| v);
        let frames = (0..poses.pose_count())
            .filter(|&p| p != poses.template)
            .map(|pose| FullFrame {
                pose,
                whole: indexed(poses.pose_mesh(pose)),
                meshes: SpikeSurfaces::per_mesh(poses, pose, &split),
            })
            .collect();
        let bind_positions = poses.template_positions();
        let morphs = targets
            .iter()
            .map(|target| {
                let moved = welded_deltas(model, target);
                let positions: Vec<Vec3> = bind_positions.iter().zip(&moved).map(|(p, d)| p + d).collect();
                indexed(mesh_part(&positions, &poses.faces, &face_mesh, target.part as u32))
            })
            .collect();
        Self { frames, bind: VertexIndex::new(bind_positions), split, morphs, targets }
    }

    /// One file's rig (`rig`, read with `document`) at every held-out frame and morph
    /// target.
    fn measure(
        &self,
        model: &RigModel,
        method: &str,
        note: String,
        rig: &Rig,
        document: &SourceDocument,
    ) -> Result<LevelMethod> {
        let welded = model.welded(rig, &format!("{method}'s rig"))?;
        let WeldedRig { mesh, skin, sources } = &welded;
        let to_full: Vec<u32> =
            mesh.positions.iter().map(|p| self.bind.nearest(p).map_or(0, |(v, _)| v)).collect();
        let face_mesh = self.split.face_meshes(&mesh.faces, |v| to_full[v as usize]);
        let mesh_count = self.split.mesh_count;
        let mesh_faces =
            (0..mesh_count as u32).map(|m| face_mesh.iter().filter(|&&f| f == m).count()).collect();
        let per_frame: Vec<(f64, Vec<Option<f64>>, usize)> = self
            .frames
            .par_iter()
            .map(|frame| {
                let positions =
                    desal_rig::skin_points(&mesh.positions, &skin.influences, &skin.joints[frame.pose]);
                let whole = TriMesh { positions, faces: mesh.faces.clone() };
                let v2f = v2f_halves_indexed(&whole, &frame.whole.0, &frame.whole.1).combined();
                let meshes = (0..mesh_count)
                    .map(|m| {
                        let part = mesh_part(&whole.positions, &whole.faces, &face_mesh, m as u32);
                        (part.face_count() > 0).then(|| {
                            let (full, index) = frame.meshes.part(m).expect("a frame is split by mesh");
                            v2f_halves_indexed(&part, full, index).combined()
                        })
                    })
                    .collect();
                let spikes = spike_count(&whole.positions, &whole.faces, &face_mesh, &frame.meshes);
                (v2f, meshes, spikes)
            })
            .collect();
        let frames = per_frame.len() as f64;
        let mesh_v2f = (0..mesh_count)
            .map(|m| {
                per_frame.iter().map(|(_, meshes, _)| meshes[m]).sum::<Option<f64>>().map(|sum| sum / frames)
            })
            .collect();
        let own_targets = desal_rig::morph_targets(rig, document)?;
        // Each of the file's meshes stands for the input mesh most of its vertices are in.
        let part_of: Vec<Option<usize>> =
            sources.iter().map(|&s| rig.meshes.iter().position(|m| m.vertices.contains(&s))).collect();
        let mut votes = vec![vec![0usize; mesh_count]; rig.meshes.len()];
        for (v, part) in part_of.iter().enumerate() {
            if let Some(p) = part {
                votes[*p][self.split.of_vertex[to_full[v] as usize] as usize] += 1;
            }
        }
        let stands_for: Vec<Option<usize>> =
            votes.iter().map(|v| (0..mesh_count).max_by_key(|&m| (v[m], std::cmp::Reverse(m)))).collect();
        let morphs = self
            .targets
            .iter()
            .zip(&self.morphs)
            .map(|(target, (full, index))| {
                let own = own_targets
                    .iter()
                    .filter(|t| stands_for[t.part] == Some(target.part) && t.index == target.index);
                let mut positions = mesh.positions.clone();
                let mut found = false;
                for own in own {
                    found = true;
                    let start = rig.meshes[own.part].vertices.start;
                    for (v, &s) in sources.iter().enumerate() {
                        if part_of[v] == Some(own.part) {
                            let d = own.deltas[(s - start) as usize];
                            positions[v] += Vec3::new(d[0].into(), d[1].into(), d[2].into());
                        }
                    }
                }
                let part = mesh_part(&positions, &mesh.faces, &face_mesh, target.part as u32);
                let v2f = (found && part.face_count() > 0)
                    .then(|| v2f_halves_indexed(&part, full, index).combined());
                MorphError {
                    mesh: model.rig.meshes[target.part].name.clone(),
                    target: target.name.clone(),
                    v2f,
                }
            })
            .collect();
        Ok(LevelMethod {
            method: method.to_owned(),
            note,
            faces: mesh.face_count(),
            vertices: mesh.vertex_count(),
            max_influences: skin.max_influences,
            v2f: per_frame.iter().map(|(v, _, _)| *v).collect(),
            mesh_faces,
            mesh_v2f,
            spikes: per_frame.iter().map(|(_, _, s)| *s).collect(),
            morphs,
        })
    }
}

/// A target's deltas per welded vertex of `model`'s pose set (zero off its mesh): each
/// welded vertex takes its first split copy's.
fn welded_deltas(model: &RigModel, target: &MorphTarget) -> Vec<Vec3> {
    let range = &model.rig.meshes[target.part].vertices;
    model
        .posed
        .weld
        .representatives()
        .into_iter()
        .map(|s| {
            if range.contains(&s) {
                let d = target.deltas[(s - range.start) as usize];
                Vec3::new(d[0].into(), d[1].into(), d[2].into())
            } else {
                Vec3::zeros()
            }
        })
        .collect()
}

fn indexed(mesh: TriMesh) -> (TriMesh, SurfaceIndex) {
    let index = SurfaceIndex::new(&mesh);
    (mesh, index)
}

/// The `## LOD levels` section of `eval.md` (empty without levels).
pub fn markdown(levels: &[LevelReport], baseline: &str) -> String {
    use std::fmt::Write;
    let Some(first) = levels.first() else { return String::new() };
    let mut md = String::new();
    let frames = first.methods.first().map_or(0, |m| m.v2f.len());
    let _ = writeln!(
        md,
        "## LOD levels as written, mesh by mesh (held-out frames)\n\n\
         Each level of `lods` as `desal run` writes it (`simplified-lod<k>.glb`, each level simplified from the \
         one before) and the peers at the same face count, each read back and skinned with its own weights at \
         {frames} frames no stage saw (random joint turns drawn with the dataset's seed + 1), against the full rig \
         at the same frames: LBS v2f of the whole rig and of each mesh (squared input units, mean over the \
         frames; Δ against `{baseline}`, frames on which it is lower), spikes per frame (each face against its \
         own mesh), and each morph target's v2f at weight 1 in the bind pose (`eval.json`'s `lods` has every \
         figure).\n"
    );
    for level in levels {
        let base = level.methods.iter().find(|m| m.method == baseline);
        let _ = writeln!(
            md,
            "### Level {} ({} of the faces: {} faces)\n",
            level.level, level.fraction, level.faces
        );
        let mesh_heads: String = level.meshes.iter().map(|m| format!(" {m} v2f |")).collect();
        let _ = writeln!(
            md,
            "| method | faces | vertices | influences | LBS v2f | Δ | frames lower |{mesh_heads} spikes | morph targets lower |"
        );
        let _ = writeln!(md, "|---|---|---|---|---|---|---|{}---|---|", "---|".repeat(level.meshes.len()));
        for m in &level.methods {
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
            let spikes: Vec<f64> = m.spikes.iter().map(|&s| s as f64).collect();
            let (delta, won, spike_delta, morphs_won) = match base {
                Some(b) if b.method != m.method => {
                    let won = m.v2f.iter().zip(&b.v2f).filter(|(a, b)| a < b).count();
                    let base_spikes: Vec<f64> = b.spikes.iter().map(|&s| s as f64).collect();
                    let morph_won = m
                        .morphs
                        .iter()
                        .zip(&b.morphs)
                        .filter(|(a, b)| match (a.v2f, b.v2f) {
                            (Some(a), Some(b)) => a <= b,
                            (Some(_), None) => true,
                            _ => false,
                        })
                        .count();
                    (
                        percent(mean(&m.v2f), mean(&b.v2f)),
                        format!("{won}/{}", m.v2f.len()),
                        format!(" ({})", percent(mean(&spikes), mean(&base_spikes))),
                        format!("{morph_won}/{}", m.morphs.len()),
                    )
                }
                _ => ("—".into(), "—".into(), String::new(), "—".into()),
            };
            let meshes: String = m
                .mesh_v2f
                .iter()
                .zip(&m.mesh_faces)
                .map(|(v, f)| match v {
                    Some(v) => format!(" {v:.3e} ({f} faces) |"),
                    None => " — |".into(),
                })
                .collect();
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {:.3e} | {delta} | {won} |{meshes} {:.1}{spike_delta} | {morphs_won} |",
                m.method,
                m.faces,
                m.vertices,
                m.max_influences,
                mean(&m.v2f),
                mean(&spikes),
            );
        }
        if level.methods.first().is_some_and(|m| !m.morphs.is_empty()) {
            let heads: String = level.methods.iter().map(|m| format!(" {} |", m.method)).collect();
            let _ = writeln!(md, "\nMorph targets, v2f at weight 1:\n\n| mesh | target |{heads}");
            let _ = writeln!(md, "|---|---|{}", "---|".repeat(level.methods.len()));
            for (t, target) in level.methods[0].morphs.iter().enumerate() {
                let cells: String = level
                    .methods
                    .iter()
                    .map(|m| match m.morphs[t].v2f {
                        Some(v) => format!(" {v:.3e} |"),
                        None => " lost |".into(),
                    })
                    .collect();
                let _ = writeln!(md, "| {} | {} |{cells}", target.mesh, target.target);
            }
        }
        let notes: Vec<String> =
            level.methods.iter().map(|m| format!("`{}`: {}", m.method, m.note)).collect();
        let _ = writeln!(md, "\n{}\n", notes.join("; "));
    }
    md
}

/// `a` against `b` as a signed percentage.
fn percent(a: f64, b: f64) -> String {
    if b == 0.0 { "—".into() } else { format!("{:+.1} %", 100.0 * (a / b - 1.0)) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compact_keeps_one_mesh_and_its_vertices() {
        let v = |x: f64| Vec3::new(x, 0.0, x * x);
        let positions: Vec<Vec3> = (0..6).map(|i| v(i as f64)).collect();
        let faces = [[0, 1, 2], [3, 4, 5], [2, 1, 0]];
        let part = mesh_part(&positions, &faces, &[0, 1, 0], 1);
        assert_eq!(part.positions, vec![v(3.0), v(4.0), v(5.0)]);
        assert_eq!(part.faces, vec![[0, 1, 2]]);
        assert_eq!(mesh_part(&positions, &faces, &[0, 1, 0], 0).face_count(), 2);
        assert_eq!(mesh_part(&positions, &faces, &[0, 1, 0], 2).face_count(), 0);
        assert_eq!(percent(1.5, 2.0), "-25.0 %");
        assert_eq!(percent(1.0, 0.0), "—");
    }
}
