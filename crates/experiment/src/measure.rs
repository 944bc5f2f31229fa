//! The experiment proper (paper §4), for the simplified pose sets of several methods:
//!
//! 1. [`deform`]: stage 1's rigid fit on the *simplified* set gives every pose's part
//!    motions; the deformation model ([`pose_model`]: SCAPE part-anchored by default,
//!    SCAPE placed at the ground truth's centroid as in the paper, or LBS) is fitted on
//!    all poses (in-sample) and once per fold without the fold's poses (held-out; the
//!    template always trains); each model synthesises its poses from their part motions.
//! 2. [`measure`]: every deformed pose against two ground truths — the simplified pose
//!    (the paper's measure) and the full-resolution pose (what a user cares about) — by
//!    v2f (Eq. 6) and v2v (Eq. 7). Poses are measured in parallel; each target's search
//!    structures are built once and shared by every method and split.
//!
//! A test pose's rotations come from its own ground truth, as in SCAPE: a pose is
//! *given* by its part rotations, and what is held out is the deformation model's
//! training data. Rotations of different poses are fitted independently, so nothing
//! of a test pose reaches its model. The simplified mesh is another matter: it is made
//! once per method, and stage 2's saliency (and `multipose`'s quadrics) saw every pose;
//! `docs/eval/blind-saliency.sh` measures what that is worth (EVAL.md).

use std::borrow::Cow;

use desal_measures::metrics::mean;
use desal_measures::{SurfaceIndex, V2fHalves, VertexIndex};
use desal_mesh::{Face, PoseSet, TriMesh, Vec3};
use rayon::prelude::*;
use serde::Serialize;

pub use desal_measures::deform::{
    DEFAULT_MODEL, Deformed, MODELS, ModelRun, deform, part_motions, pose_model,
};

/// v2f and v2v of one deformed mesh against one target, in squared input units.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Errors {
    /// Paper Eq. 6: symmetric, both sums over the total vertex count.
    pub v2f: f64,
    /// Paper Eq. 7: mean over deformed vertices of the squared distance to the nearest
    /// target vertex.
    pub v2v: f64,
    /// Mean over deformed vertices of the squared distance to the target surface.
    pub v2f_deformed_to_target: f64,
    /// Mean over target vertices of the squared distance to the deformed surface.
    pub v2f_target_to_deformed: f64,
}

/// The errors of one deformed pose against both ground truths.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PoseErrors {
    /// Against the method's own simplified pose (the paper's measure).
    pub vs_simplified: Errors,
    /// Against the full-resolution pose.
    pub vs_full: Errors,
}

/// A target mesh with its search structures, built once and queried by every method.
struct Target<'a> {
    mesh: TriMesh,
    surface: Cow<'a, SurfaceIndex>,
    vertices: VertexIndex,
}

impl<'a> Target<'a> {
    fn new(mesh: TriMesh) -> Self {
        let surface = SurfaceIndex::new(&mesh);
        Self::with_surface(mesh, Cow::Owned(surface))
    }

    fn with_surface(mesh: TriMesh, surface: Cow<'a, SurfaceIndex>) -> Self {
        Self { vertices: VertexIndex::new(&mesh.positions), surface, mesh }
    }

    /// The target of `mesh`, the same faces as this target's in another pose: both
    /// indices refitted, not built (the same answers).
    fn refit(&self, mesh: TriMesh) -> Target<'static> {
        let surface = Cow::Owned(self.surface.refit(&mesh));
        self.with_surface_refitted(mesh, surface)
    }

    /// [`Target::with_surface`] for `mesh`, the same vertices as this target's in
    /// another pose: its vertex index refitted, not built (the same answers).
    fn with_surface_refitted<'b>(&self, mesh: TriMesh, surface: Cow<'b, SurfaceIndex>) -> Target<'b> {
        Target { vertices: self.vertices.refit(&mesh.positions), surface, mesh }
    }
}

/// Where each query of [`errors`] starts (see `SurfaceIndex::nearest_seeded`): any
/// seeds give the same errors, near ones give them faster.
struct Seeds<'a> {
    /// Per deformed vertex, a target face near it.
    to_surface: &'a [u32],
    /// Per target vertex, a deformed face near it.
    back: &'a [u32],
    /// Per deformed vertex, a target vertex near it.
    to_vertex: &'a [u32],
}

/// Errors of `deformed` (with its surface index) against `target`, and the per-vertex
/// squared distances of `deformed` to the target surface. Computed exactly as
/// `desal_measures::v2f` and `desal_measures::v2v` compute them (the same distances, found from
/// `seeds`), so that re-measuring saved meshes reproduces the figures.
fn errors(
    deformed: &TriMesh,
    deformed_surface: &SurfaceIndex,
    target: &Target,
    seeds: &Seeds,
) -> (Errors, Vec<f64>) {
    let to_surface = target.surface.distances_sq_seeded(&deformed.positions, seeds.to_surface);
    let back = deformed_surface.distances_sq_seeded(&target.mesh.positions, seeds.back);
    let halves = V2fHalves {
        a_to_b: mean(&to_surface),
        b_to_a: mean(&back),
        a_vertex_count: deformed.vertex_count(),
        b_vertex_count: target.mesh.vertex_count(),
    };
    let errors = Errors {
        v2f: halves.combined(),
        v2v: mean(&target.vertices.distances_sq_seeded(&deformed.positions, seeds.to_vertex)),
        v2f_deformed_to_target: halves.a_to_b,
        v2f_target_to_deformed: halves.b_to_a,
    };
    (errors, to_surface)
}

/// What [`measure`] found for one method, in the order of the evaluated poses.
#[derive(Debug, Default)]
pub struct Measured {
    pub in_sample: Vec<PoseErrors>,
    pub held_out: Vec<PoseErrors>,
    /// Per evaluated pose, per deformed vertex: squared distance of the held-out
    /// deformed vertex to the simplified ground-truth surface (heat maps).
    pub held_out_vertex_errors: Vec<Vec<f64>>,
}

/// One method's material for [`measure`].
#[derive(Debug, Clone, Copy)]
pub struct Run<'a> {
    /// The simplified ground truth (every pose) and its triangles.
    pub simplified: &'a PoseSet,
    pub deformed: &'a Deformed,
}

/// Per method, where [`errors`]' queries start: a deformed pose lies near its
/// simplified truth vertex for vertex, and both near the full pose where the templates
/// are near each other.
struct RunSeeds {
    /// Per simplified vertex, a simplified face of it.
    coarse_faces: Vec<u32>,
    /// Per simplified vertex, itself.
    coarse_vertices: Vec<u32>,
    /// Per simplified vertex, the full face nearest to it in the templates.
    full_faces: Vec<u32>,
    /// Per simplified vertex, the full vertex nearest to it in the templates.
    full_vertices: Vec<u32>,
    /// Per full vertex, the simplified face nearest to it in the templates.
    full_to_coarse_faces: Vec<u32>,
}

impl RunSeeds {
    /// `coarse_template` is the target of `run`'s simplified template.
    fn new(full: &PoseSet, full_template: &Target, run: &Run, coarse_template: &Target) -> Self {
        let coarse = run.simplified;
        let template = &coarse_template.mesh;
        let coarse_surface = &coarse_template.surface;
        let nearest = |found: Option<(u32, f64)>| found.map_or(u32::MAX, |(i, _)| i);
        Self {
            coarse_faces: desal_measures::vertex_faces(&coarse.faces, coarse.vertex_count()),
            coarse_vertices: (0..coarse.vertex_count() as u32).collect(),
            full_faces: template
                .positions
                .par_iter()
                .map(|p| nearest(full_template.surface.nearest(p)))
                .collect(),
            full_vertices: template
                .positions
                .par_iter()
                .map(|p| nearest(full_template.vertices.nearest(p)))
                .collect(),
            full_to_coarse_faces: full.poses[full.template]
                .par_iter()
                .map(|p| nearest(coarse_surface.nearest(p)))
                .collect(),
        }
    }

    /// Against the method's simplified pose.
    fn vs_simplified(&self) -> Seeds<'_> {
        Seeds { to_surface: &self.coarse_faces, back: &self.coarse_faces, to_vertex: &self.coarse_vertices }
    }

    /// Against the full-resolution pose.
    fn vs_full(&self) -> Seeds<'_> {
        Seeds {
            to_surface: &self.full_faces,
            back: &self.full_to_coarse_faces,
            to_vertex: &self.full_vertices,
        }
    }
}

/// Per run, the target of its simplified template and where its queries start.
fn run_targets(
    full: &PoseSet,
    full_template: &Target,
    runs: &[Run],
) -> (Vec<Target<'static>>, Vec<RunSeeds>) {
    let templates: Vec<Target> = runs.iter().map(|run| Target::new(run.simplified.template_mesh())).collect();
    let seeds = runs
        .iter()
        .zip(&templates)
        .map(|(run, template)| RunSeeds::new(full, full_template, run, template))
        .collect();
    (templates, seeds)
}

/// Measures every method's deformed poses `evaluated` (none of them the template)
/// against the simplified and full ground truths. Returns one [`Measured`] per run.
pub fn measure(full: &PoseSet, evaluated: &[usize], runs: &[Run]) -> Vec<Measured> {
    measure_indexed(full, evaluated, runs, None)
}

/// [`measure`], with `full_surfaces[pose]`, when given, indexing `full.pose_mesh(pose)`
/// (built once by the caller for every measure of the run): the same results.
pub fn measure_indexed(
    full: &PoseSet,
    evaluated: &[usize],
    runs: &[Run],
    full_surfaces: Option<&[SurfaceIndex]>,
) -> Vec<Measured> {
    type PoseResult = Vec<(PoseErrors, PoseErrors, Vec<f64>)>;
    let full_template = match full_surfaces {
        Some(s) => Target::with_surface(full.pose_mesh(full.template), Cow::Borrowed(&s[full.template])),
        None => Target::new(full.pose_mesh(full.template)),
    };
    // Every other pose's targets are the templates' indices refitted: the same answers
    // for less than a build.
    let full_target = |pose: usize| match full_surfaces {
        Some(s) => full_template.with_surface_refitted(full.pose_mesh(pose), Cow::Borrowed(&s[pose])),
        None => full_template.refit(full.pose_mesh(pose)),
    };
    let (simplified_templates, seeds) = run_targets(full, &full_template, runs);
    let per_pose: Vec<PoseResult> = evaluated
        .par_iter()
        .map(|&pose| {
            let full_target = full_target(pose);
            runs.iter()
                .zip(&seeds)
                .zip(&simplified_templates)
                .map(|((run, seeds), template)| {
                    let simplified_target = template.refit(run.simplified.pose_mesh(pose));
                    let faces = &run.simplified.faces;
                    let held_out =
                        run.deformed.held_out[pose].as_ref().expect("evaluated poses are held out once");
                    let targets = (&simplified_target, &full_target);
                    let seeds = (seeds.vs_simplified(), seeds.vs_full());
                    let (in_sample, _) = pose_errors(&run.deformed.in_sample[pose], faces, targets, &seeds);
                    let (held_out, vertex_errors) = pose_errors(held_out, faces, targets, &seeds);
                    (in_sample, held_out, vertex_errors)
                })
                .collect()
        })
        .collect();
    // Transpose to per-method results, in pose order.
    let mut measured: Vec<Measured> = runs.iter().map(|_| Measured::default()).collect();
    for pose_result in per_pose {
        for (m, (in_sample, held_out, vertex_errors)) in measured.iter_mut().zip(pose_result) {
            m.in_sample.push(in_sample);
            m.held_out.push(held_out);
            m.held_out_vertex_errors.push(vertex_errors);
        }
    }
    measured
}

/// The held-out errors against the full-resolution pose only, per run, in the order of
/// `evaluated`: what a second deformation model of the same methods needs (the opening
/// table of `eval.md`), at a quarter of [`measure_indexed`]'s queries. The same figures
/// as its `held_out[..].vs_full` for the same run.
pub fn held_out_vs_full(
    full: &PoseSet,
    evaluated: &[usize],
    runs: &[Run],
    full_surfaces: &[SurfaceIndex],
) -> Vec<Vec<Errors>> {
    let full_template =
        Target::with_surface(full.pose_mesh(full.template), Cow::Borrowed(&full_surfaces[full.template]));
    let (simplified_templates, seeds) = run_targets(full, &full_template, runs);
    let per_pose: Vec<Vec<Errors>> = evaluated
        .par_iter()
        .map(|&pose| {
            let full_target = full_template
                .with_surface_refitted(full.pose_mesh(pose), Cow::Borrowed(&full_surfaces[pose]));
            runs.iter()
                .zip(&seeds)
                .zip(&simplified_templates)
                .map(|((run, seeds), template)| {
                    let held_out =
                        run.deformed.held_out[pose].as_ref().expect("evaluated poses are held out once");
                    let deformed =
                        TriMesh { positions: held_out.clone(), faces: run.simplified.faces.clone() };
                    let deformed_surface = template.surface.refit(&deformed);
                    errors(&deformed, &deformed_surface, &full_target, &seeds.vs_full()).0
                })
                .collect()
        })
        .collect();
    (0..runs.len()).map(|r| per_pose.iter().map(|pose| pose[r]).collect()).collect()
}

/// Issue 42, item 7: the simplified faces of `positions` (with `faces`) whose normal turns
/// more than 90° from the normal of the full surface's face nearest to their centroid:
/// spikes and folds a viewer shows as dark or inside-out triangles. Faces of zero area
/// are not counted. `surfaces` is the full pose as [`SpikeSurfaces`] splits it; a face of
/// mesh `face_mesh[f]` is judged against that mesh's full surface (all in mesh 0 when
/// `face_mesh` is empty).
pub(crate) fn spike_count(
    positions: &[Vec3],
    faces: &[Face],
    face_mesh: &[u32],
    surfaces: &SpikeSurfaces,
) -> usize {
    faces
        .par_iter()
        .enumerate()
        .filter(|&(f, &[a, b, c])| {
            let [a, b, c] = [a, b, c].map(|v| positions[v as usize]);
            let normal = (b - a).cross(&(c - a));
            if normal.norm_squared() == 0.0 {
                return false;
            }
            let mesh = if face_mesh.is_empty() { 0 } else { face_mesh[f] as usize };
            surfaces.nearest_normal(mesh, &((a + b + c) / 3.0)).is_some_and(|n| normal.dot(&n) < 0.0)
        })
        .count()
}

/// Which glTF mesh each full (welded) vertex belongs to, for a rig of several meshes: a
/// simplified face is judged against its own mesh's full surface, so an eyelid is
/// compared with the full eyelids and not with the eyeball behind them (whose faces turn
/// the other way wherever the two meshes touch or cross, as they do at full resolution).
#[derive(Debug, Clone)]
pub struct MeshSplit {
    /// Per full vertex, its mesh.
    pub of_vertex: Vec<u32>,
    pub mesh_count: usize,
}

impl MeshSplit {
    /// The mesh of each face of `faces` over full vertices: the mesh most of its corners
    /// are in (the first corner's when all three differ).
    pub fn face_meshes(&self, faces: &[Face], to_full: impl Fn(u32) -> u32) -> Vec<u32> {
        faces
            .iter()
            .map(|&[a, b, c]| {
                let [a, b, c] = [a, b, c].map(|v| self.of_vertex[to_full(v) as usize]);
                if b == c { b } else { a }
            })
            .collect()
    }
}

/// One full pose's surface for [`spike_count`]: whole, or each mesh of a [`MeshSplit`]
/// apart ([`mesh_part`]) with its index.
pub(crate) enum SpikeSurfaces<'a> {
    Whole { mesh: TriMesh, surface: &'a SurfaceIndex },
    PerMesh(Vec<(TriMesh, SurfaceIndex)>),
}

impl<'a> SpikeSurfaces<'a> {
    /// `full`'s pose `pose`, indexed whole by `surface` or split by `meshes`.
    fn new(full: &PoseSet, pose: usize, surface: &'a SurfaceIndex, meshes: Option<&MeshSplit>) -> Self {
        match meshes {
            None => Self::Whole { mesh: full.pose_mesh(pose), surface },
            Some(split) => Self::per_mesh(full, pose, split),
        }
    }

    /// `full`'s pose `pose` split by `split`, one index per mesh.
    pub(crate) fn per_mesh(full: &PoseSet, pose: usize, split: &MeshSplit) -> Self {
        let face_mesh = split.face_meshes(&full.faces, |v| v);
        let parts = (0..split.mesh_count as u32)
            .into_par_iter()
            .map(|m| {
                let part = mesh_part(&full.poses[pose], &full.faces, &face_mesh, m);
                let index = SurfaceIndex::new(&part);
                (part, index)
            })
            .collect();
        Self::PerMesh(parts)
    }

    /// Mesh `m` of a split pose and its index (`None` when whole).
    pub(crate) fn part(&self, m: usize) -> Option<&(TriMesh, SurfaceIndex)> {
        match self {
            Self::Whole { .. } => None,
            Self::PerMesh(parts) => parts.get(m),
        }
    }

    /// The unit normal of the face of mesh `mesh` nearest to `p` (any face when whole).
    fn nearest_normal(&self, mesh: usize, p: &Vec3) -> Option<Vec3> {
        let (mesh, surface) = match self {
            Self::Whole { mesh, surface } => (mesh, *surface),
            Self::PerMesh(parts) => {
                let (part, surface) = parts.get(mesh)?;
                (part, surface)
            }
        };
        surface.nearest(p).map(|(f, _)| mesh.face_normal(f as usize))
    }
}

/// The faces of mesh `m` (by `face_mesh`, one per face) over `positions`, with only the
/// vertices they use.
pub(crate) fn mesh_part(positions: &[Vec3], faces: &[Face], face_mesh: &[u32], m: u32) -> TriMesh {
    let chosen: Vec<Face> =
        faces.iter().zip(face_mesh).filter(|&(_, &of)| of == m).map(|(f, _)| *f).collect();
    let (kept, faces) = desal_mesh::used_vertices(positions.len(), &chosen);
    TriMesh { positions: kept.iter().map(|&v| positions[v as usize]).collect(), faces }
}

/// [`spike_count`] of a run: in the rest pose (the simplified template against the full
/// one), then per pose of `evaluated`, its held-out deformation against the full pose.
/// `simp_to_full` maps the run's vertices to full ones (stage 4's map), for `meshes`.
pub fn spikes(
    full: &PoseSet,
    evaluated: &[usize],
    run: &Run,
    simp_to_full: &[u32],
    full_surfaces: &[SurfaceIndex],
    meshes: Option<&MeshSplit>,
) -> (usize, Vec<usize>) {
    let faces = &run.simplified.faces;
    let face_mesh = meshes.map_or_else(Vec::new, |m| m.face_meshes(faces, |v| simp_to_full[v as usize]));
    let at = |positions: &[Vec3], pose: usize| {
        let surfaces = SpikeSurfaces::new(full, pose, &full_surfaces[pose], meshes);
        spike_count(positions, faces, &face_mesh, &surfaces)
    };
    let rest = at(&run.simplified.poses[run.simplified.template], full.template);
    let held_out = evaluated
        .iter()
        .map(|&pose| at(run.deformed.held_out[pose].as_ref().expect("evaluated poses are held out"), pose))
        .collect();
    (rest, held_out)
}

/// Both ground truths `(simplified, full)` for one deformed pose, with their seeds;
/// also the per-vertex squared distances to the simplified surface.
fn pose_errors(
    positions: &[Vec3],
    faces: &[Face],
    (simplified, full): (&Target, &Target),
    (simplified_seeds, full_seeds): &(Seeds, Seeds),
) -> (PoseErrors, Vec<f64>) {
    let deformed = TriMesh { positions: positions.to_vec(), faces: faces.to_vec() };
    // The deformation has the simplified target's faces and lies near it: its tree,
    // refitted, serves as well as a new one.
    let deformed_surface = simplified.surface.refit(&deformed);
    let (vs_simplified, vertex_errors) = errors(&deformed, &deformed_surface, simplified, simplified_seeds);
    let (vs_full, _) = errors(&deformed, &deformed_surface, full, full_seeds);
    (PoseErrors { vs_simplified, vs_full }, vertex_errors)
}

/// Mean and sample standard deviation (n − 1; 0 for a single value) of a figure over
/// poses.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MeanStd {
    pub mean: f64,
    pub std: f64,
}

impl MeanStd {
    pub fn of(values: impl Iterator<Item = f64> + Clone) -> Self {
        let n = values.clone().count() as f64;
        let mean = values.clone().sum::<f64>() / n;
        let var = if n > 1.0 { values.map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0) } else { 0.0 };
        Self { mean, std: var.sqrt() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_and_sample_deviation() {
        let s = MeanStd::of([1.0, 2.0, 3.0, 6.0].into_iter());
        assert_eq!(s.mean, 3.0);
        assert!((s.std - (14.0f64 / 3.0).sqrt()).abs() < 1e-15);
        assert_eq!(MeanStd::of([5.0].into_iter()), MeanStd { mean: 5.0, std: 0.0 });
    }

    /// The shared-index errors equal the library's own v2f and v2v on the same pair.
    #[test]
    fn errors_match_the_library_metrics() {
        let v = |x: f64, y: f64, z: f64| Vec3::new(x, y, z);
        let a = TriMesh {
            positions: vec![v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.1), v(1.0, 1.0, 0.3)],
            faces: vec![[0, 1, 2], [1, 3, 2]],
        };
        let b = TriMesh {
            positions: vec![
                v(0.0, 0.1, 0.2),
                v(1.2, 0.0, 0.0),
                v(0.0, 1.0, -0.1),
                v(0.9, 1.1, 0.0),
                v(0.5, 0.5, 0.4),
            ],
            faces: vec![[0, 1, 4], [1, 3, 4], [3, 2, 4], [2, 0, 4]],
        };
        // Arbitrary seeds (in range or not): the same errors.
        let seeds =
            Seeds { to_surface: &[3, 0, 1, 2], back: &[1, 0, 9, 1, 0], to_vertex: &[4, 4, 0, u32::MAX] };
        let (e, per_vertex) = errors(&a, &SurfaceIndex::new(&a), &Target::new(b.clone()), &seeds);
        assert_eq!(e.v2f, desal_measures::v2f(&a, &b));
        assert_eq!(e.v2v, desal_measures::v2v(&a, &b));
        assert_eq!(mean(&per_vertex), e.v2f_deformed_to_target);
        assert!(e.v2f_deformed_to_target <= e.v2v);
    }
}

#[cfg(test)]
mod spike_tests {
    use super::*;

    /// A face turned inside out against the surface it approximates is a spike; a face
    /// that follows it, or has no area, is not.
    #[test]
    fn a_face_turned_against_the_full_surface_is_counted() {
        let full = TriMesh {
            positions: vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ],
            faces: vec![[0, 1, 2], [0, 2, 3]],
        };
        let surface = SurfaceIndex::new(&full);
        let positions = full.positions.clone();
        let whole = SpikeSurfaces::Whole { mesh: full.clone(), surface: &surface };
        assert_eq!(spike_count(&positions, &full.faces, &[], &whole), 0);
        assert_eq!(spike_count(&positions, &[[0, 2, 1], [0, 2, 3], [0, 0, 1]], &[], &whole), 1);
    }

    /// Two meshes face to face 1 cm apart (an eyelid over an eyeball): a face of the upper
    /// one pushed 6 mm down lies nearer the lower one, whose normal turns the other way.
    /// Judged whole it is a spike; judged against its own mesh, as a rig of several meshes
    /// is, it is not, while a face of it turned over still is.
    #[test]
    fn a_face_is_judged_against_its_own_mesh() {
        let v = |x: f64, y: f64, z: f64| Vec3::new(x, y, z);
        let positions = vec![
            // Mesh 0, facing up at z = 0.01.
            v(0.0, 0.0, 0.01),
            v(1.0, 0.0, 0.01),
            v(0.0, 1.0, 0.01),
            // Mesh 1, facing down at z = 0.
            v(0.0, 0.0, 0.0),
            v(0.0, 1.0, 0.0),
            v(1.0, 0.0, 0.0),
        ];
        let full =
            PoseSet::try_new(vec!["rest".into()], vec![positions.clone()], vec![[0, 1, 2], [3, 4, 5]], 0)
                .expect("a valid pose set");
        let split = MeshSplit { of_vertex: vec![0, 0, 0, 1, 1, 1], mesh_count: 2 };
        let surface = SurfaceIndex::new(&full.pose_mesh(0));
        let mut moved = positions.clone();
        for p in &mut moved[..3] {
            p.z = 0.004;
        }
        let faces = [[0, 1, 2]];
        let count = |positions: &[Vec3], faces: &[Face], meshes: Option<&MeshSplit>| {
            let face_mesh = meshes.map_or_else(Vec::new, |m| m.face_meshes(faces, |v| v));
            spike_count(positions, faces, &face_mesh, &SpikeSurfaces::new(&full, 0, &surface, meshes))
        };
        assert_eq!(count(&moved, &faces, None), 1, "judged whole, the lower mesh is nearer");
        assert_eq!(count(&moved, &faces, Some(&split)), 0, "judged against its own mesh");
        assert_eq!(count(&moved, &[[0, 2, 1]], Some(&split)), 1, "turned over, it is a spike");
        assert_eq!(split.face_meshes(&[[0, 3, 4], [3, 0, 1], [0, 3, 5]], |v| v), [1, 0, 1]);
    }
}
