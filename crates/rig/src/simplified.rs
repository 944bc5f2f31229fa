//! The simplified rig: the input rig with its skinned mesh replaced by the simplified
//! one. The skeleton, inverse bind matrices and animations are the input's, unchanged.
//!
//! Index spaces: `simp` indexes the simplified mesh (stage 3/4's output), `welded` the
//! pose set the pipeline ran on ([`crate::weld`]), `split` the input mesh's own
//! vertices, and `out` the written mesh's vertices.
//!
//! The story of [`simplified_rig`]:
//! 1. Each simplified face picks, for each corner, a split copy of its welded vertex: the
//!    copies whose attributes lie closest together ([`pick_copies`]). On a seam, the faces
//!    on each side pick that side's copy, so the seam stays a seam in the output: one
//!    output vertex per (simplified vertex, copy) used.
//! 2. Attributes (UV, normal) come from the copy.
//! 3. Subset placement: the copy's own bind position and exact joints and weights.
//!    Optimal placement: the new position, and weights refitted by least squares over the
//!    pose set ([`crate::refit`]) on the joints of the mapped vertex and its neighbours,
//!    unless the mapped vertex's own (4 largest) weights fit better.

use desal_mesh::math::Mat4;
use desal_mesh::{Face, Vec3};

use crate::RigError;
use crate::model::{Influences, PrimitiveSpan, Rig, SkinnedMesh};
use crate::refit::{MAX_INFLUENCES, fit_weights, residual};
use crate::weld::Weld;

/// The simplified mesh and how it was placed, as stages 3 and 4 give it.
#[derive(Debug, Clone, Copy)]
pub struct SimplifiedInput<'a> {
    /// Bind-pose positions of the simplified vertices (`simp` space).
    pub positions: &'a [Vec3],
    /// Triangles over `simp`.
    pub faces: &'a [Face],
    /// `simp_to_welded[simp]`: the welded vertex stage 4 mapped it to.
    pub simp_to_welded: &'a [u32],
    /// True when every simplified vertex is a welded input vertex (subset placement).
    pub subset: bool,
}

/// What the refit needs: the pose set's skinning matrices and targets.
#[derive(Debug, Clone, Copy)]
pub struct PoseTargets<'a> {
    /// `joints[k][j]`: joint `j`'s skinning matrix in pose `k`.
    pub joints: &'a [Vec<Mat4>],
    /// `positions[k][welded]`: welded vertex positions in pose `k`.
    pub positions: &'a [Vec<Vec3>],
}

/// Figures of [`simplified_rig`].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SimplifiedReport {
    pub simplified_vertices: usize,
    /// Vertices written: simplified vertices plus their extra seam copies.
    pub output_vertices: usize,
    pub output_faces: usize,
    /// Simplified vertices written more than once (they lie on a UV or normal seam).
    pub seam_vertices: usize,
    /// Optimal placement: vertices whose weights were refitted (the rest kept the mapped
    /// vertex's own weights, which fitted better).
    pub refitted_vertices: usize,
    pub max_influences: usize,
    /// Faces whose corners have no copies in one UV chart (the simplification collapsed
    /// across a seam there), so their texture is stretched across the seam.
    pub cross_chart_faces: usize,
}

/// How many influences each simplified vertex keeps.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct WeightOptions {
    /// At most this many influences per vertex (at least 1): subset placement keeps, of a
    /// vertex with more, the ones of its own joints that skin it closest over the poses
    /// (refitted, or its largest renormalised when they do better), and the refit fits at
    /// most this many.
    /// `None`: subset placement keeps the exact weights, however many (the sample has up
    /// to 7), and the refit keeps at most [`MAX_INFLUENCES`].
    pub max_influences: Option<usize>,
}

/// Builds the simplified rig with the default [`WeightOptions`]. `weld` is the weld of
/// `rig.mesh` the pipeline ran on.
pub fn simplified_rig(
    rig: &Rig,
    weld: &Weld,
    simplified: &SimplifiedInput,
    targets: &PoseTargets,
) -> Result<(Rig, SimplifiedReport), RigError> {
    simplified_rig_with(rig, weld, simplified, targets, &WeightOptions::default())
}

/// Builds the simplified rig, its weights as `options` say.
pub fn simplified_rig_with(
    rig: &Rig,
    weld: &Weld,
    simplified: &SimplifiedInput,
    targets: &PoseTargets,
    options: &WeightOptions,
) -> Result<(Rig, SimplifiedReport), RigError> {
    check_input(weld, simplified)?;
    let mesh = &rig.mesh;

    // 1. A copy per corner; each face goes to the primitive most of its corners' copies
    //    lie in (the first corner's when all three differ), so every primitive keeps its
    //    own faces and material.
    let primitive_of = |split: u32| mesh.primitive_of(split).unwrap_or(0);
    let mut faces_of: Vec<Vec<[(u32, u32); 3]>> = vec![Vec::new(); mesh.primitives.len().max(1)];
    let charts = uv_charts(mesh);
    let mut cross_chart_faces = 0;
    // A face the simplification kept as it was keeps its input corners (so a mesh kept
    // whole comes back with every split vertex); others pick theirs.
    let welded_of = |split: u32| weld.split_to_welded[split as usize] as usize;
    let mut input_faces = std::collections::HashMap::with_capacity(mesh.triangles.len());
    for t in &mesh.triangles {
        let mut key = t.map(welded_of);
        key.sort_unstable();
        input_faces.entry(key).or_insert(*t);
    }
    for face in simplified.faces {
        let welded = face.map(|s| simplified.simp_to_welded[s as usize] as usize);
        let mut key = welded;
        key.sort_unstable();
        let copies = match input_faces.get(&key) {
            Some(t) => welded.map(|w| *t.iter().find(|&&c| welded_of(c) == w).expect("the same corners")),
            None => pick_copies(mesh, welded.map(|w| weld.copies_of(w))),
        };
        if let Some(charts) = &charts {
            cross_chart_faces +=
                usize::from(copies.iter().any(|&c| charts[c as usize] != charts[copies[0] as usize]));
        }
        let primitives = copies.map(primitive_of);
        let p = if primitives[1] == primitives[2] { primitives[1] } else { primitives[0] };
        // A corner whose chosen copy lies in another primitive takes one of its own, if any.
        let corner = |i: usize| {
            let own = weld.copies_of(welded[i]).iter().find(|&&c| primitive_of(c) == p);
            (face[i], if primitives[i] == p { copies[i] } else { own.copied().unwrap_or(copies[i]) })
        };
        faces_of[p].push([corner(0), corner(1), corner(2)]);
    }

    // One output vertex per (simp, copy) of a primitive, in order of first use; the
    // primitives' runs in their input order.
    let mut out_vertices: Vec<(u32, u32)> = Vec::new();
    let mut triangles = Vec::with_capacity(simplified.faces.len());
    let mut primitives = Vec::new();
    for (p, faces) in faces_of.iter().enumerate() {
        let mut out_index: std::collections::HashMap<(u32, u32), u32> = std::collections::HashMap::new();
        let (first_vertex, first_triangle) = (out_vertices.len() as u32, triangles.len() as u32);
        for face in faces {
            triangles.push(face.map(|key| {
                *out_index.entry(key).or_insert_with(|| {
                    out_vertices.push(key);
                    (out_vertices.len() - 1) as u32
                })
            }));
        }
        if let Some(span) = mesh.primitives.get(p)
            && !faces.is_empty()
        {
            primitives.push(PrimitiveSpan {
                mesh: span.mesh,
                primitive: span.primitive,
                vertices: first_vertex..out_vertices.len() as u32,
                triangles: first_triangle..triangles.len() as u32,
            });
        }
    }

    // 3. Influences per simplified vertex (the same for all its copies).
    let (simp_weights, refitted) = simplified_influences(mesh, weld, simplified, targets, options);

    // 2. Attributes from the copy; positions and influences by placement.
    let mut influences = Influences::new();
    let mut positions = Vec::with_capacity(out_vertices.len());
    let mut normals = mesh.normals.as_ref().map(|_| Vec::with_capacity(out_vertices.len()));
    let mut uvs = mesh.uvs.as_ref().map(|_| Vec::with_capacity(out_vertices.len()));
    for &(s, copy) in &out_vertices {
        let copy = copy as usize;
        if simplified.subset {
            positions.push(mesh.positions[copy]);
        } else {
            let p = simplified.positions[s as usize];
            positions.push([p.x as f32, p.y as f32, p.z as f32]);
        }
        // A welded vertex's copies have bit-identical weights (crate::weld).
        influences.push_row(simp_weights[s as usize].iter().copied());
        if let (Some(out), Some(input)) = (&mut normals, &mesh.normals) {
            out.push(input[copy]);
        }
        if let (Some(out), Some(input)) = (&mut uvs, &mesh.uvs) {
            out.push(input[copy]);
        }
    }
    let simp_count = simplified.positions.len();
    let mut used = vec![0u32; simp_count];
    for &(s, _) in &out_vertices {
        used[s as usize] += 1;
    }
    let report = SimplifiedReport {
        simplified_vertices: simp_count,
        output_vertices: out_vertices.len(),
        output_faces: triangles.len(),
        seam_vertices: used.iter().filter(|&&n| n > 1).count(),
        refitted_vertices: refitted,
        max_influences: influences.max_influences(),
        cross_chart_faces,
    };
    let sources = out_vertices.iter().map(|&(_, copy)| copy).collect();
    let out_mesh = SkinnedMesh {
        name: mesh.name.clone(),
        positions,
        normals,
        uvs,
        influences,
        triangles,
        primitives,
        sources,
    };
    let mut out = rig.clone();
    // Each glTF mesh's run of the output: its primitives' runs, which follow one another.
    for part in &mut out.meshes {
        let runs: Vec<&PrimitiveSpan> = out_mesh.primitives.iter().filter(|p| p.mesh == part.mesh).collect();
        let (first, last) = (runs.first(), runs.last());
        let end = |r: Option<&&PrimitiveSpan>| r.map_or(0, |r| r.vertices.end);
        part.vertices = first.map_or(end(last), |r| r.vertices.start)..end(last);
        part.triangles = first.map_or(0, |r| r.triangles.start)..last.map_or(0, |r| r.triangles.end);
    }
    out.mesh = out_mesh;
    Ok((out, report))
}

/// The joints and weights of every simplified vertex (`simp` space), and how many were
/// refitted. Subset placement: the mapped welded vertex's exact weights (when capped, at
/// most `max_influences` of its own joints fitted over `targets`: [`capped_weights`]).
/// Optimal placement: the least-squares
/// refit over `targets` ([`refit_vertex`]). `desal eval` calls this with the training
/// poses of each fold, so a held-out pose never reaches the weights it is skinned with.
pub fn simplified_influences(
    mesh: &SkinnedMesh,
    weld: &Weld,
    simplified: &SimplifiedInput,
    targets: &PoseTargets,
    options: &WeightOptions,
) -> (Vec<Vec<(u16, f32)>>, usize) {
    if simplified.subset {
        let weights = simplified
            .simp_to_welded
            .iter()
            .map(|&welded| {
                let representative = weld.copies_of(welded as usize)[0] as usize;
                let exact = mesh.influences.of(representative);
                match options.max_influences {
                    Some(limit) if mesh.influences.of(representative).count() > limit => {
                        capped_weights(mesh, representative, welded as usize, targets, limit)
                    }
                    _ => exact.map(|(j, w)| (j as u16, w)).collect(),
                }
            })
            .collect();
        return (weights, 0);
    }
    let limit = options.max_influences.unwrap_or(MAX_INFLUENCES).max(1);
    let neighbours = welded_neighbours(weld);
    let fitted: Vec<(Vec<(u16, f32)>, bool)> = (0..simplified.positions.len())
        .map(|s| {
            let welded = simplified.simp_to_welded[s] as usize;
            refit_vertex(mesh, weld, &neighbours, welded, &simplified.positions[s], targets, limit)
        })
        .collect();
    let refitted = fitted.iter().filter(|f| f.1).count();
    (fitted.into_iter().map(|f| f.0).collect(), refitted)
}

fn check_input(weld: &Weld, s: &SimplifiedInput) -> Result<(), RigError> {
    if s.simp_to_welded.len() != s.positions.len() {
        return Err(RigError::Output(format!(
            "{} mapped vertices for {} simplified vertices",
            s.simp_to_welded.len(),
            s.positions.len()
        )));
    }
    if let Some(w) = s.simp_to_welded.iter().find(|&&w| w as usize >= weld.welded_count()) {
        return Err(RigError::Output(format!(
            "mapped to vertex {w}, but the rig has {} welded vertices",
            weld.welded_count()
        )));
    }
    if let Some(f) = s.faces.iter().position(|f| f.iter().any(|&v| v as usize >= s.positions.len())) {
        return Err(RigError::Output(format!("face {f} uses a vertex out of range")));
    }
    Ok(())
}

/// The split copies of a face's three corners in the fewest primitives, and among those
/// the ones whose attributes (UV, normal) lie closest together: the least sum of squared
/// attribute distances over the face's three edges, ties to the lower split indices. A
/// face on one side of a seam (a UV seam or the border between two primitives) has all
/// its corners' copies on that side close together; a copy from the other side would
/// stretch the face across the texture, or into another material.
fn pick_copies(mesh: &SkinnedMesh, copies: [&[u32]; 3]) -> [u32; 3] {
    if copies.iter().all(|c| c.len() == 1) {
        return copies.map(|c| c[0]);
    }
    let attribute_distance = |a: u32, b: u32| -> f64 {
        let (a, b) = (a as usize, b as usize);
        let mut d = 0.0;
        if let Some(uvs) = &mesh.uvs {
            d += (0..2).map(|i| f64::from(uvs[a][i] - uvs[b][i]).powi(2)).sum::<f64>();
        }
        if let Some(normals) = &mesh.normals {
            d += (0..3).map(|i| f64::from(normals[a][i] - normals[b][i]).powi(2)).sum::<f64>();
        }
        d
    };
    let primitive_count = |corners: [u32; 3]| {
        let p = corners.map(|c| mesh.primitive_of(c));
        1 + usize::from(p[1] != p[0]) + usize::from(p[2] != p[0] && p[2] != p[1])
    };
    let mut best = (usize::MAX, f64::INFINITY, copies.map(|c| c[0]));
    for &a in copies[0] {
        for &b in copies[1] {
            for &c in copies[2] {
                let primitives = primitive_count([a, b, c]);
                let d = attribute_distance(a, b) + attribute_distance(b, c) + attribute_distance(c, a);
                if (primitives, d) < (best.0, best.1) {
                    best = (primitives, d, [a, b, c]);
                }
            }
        }
    }
    best.2
}

/// The UV chart of every split vertex: connected components of the split mesh (`None`
/// without UVs).
fn uv_charts(mesh: &SkinnedMesh) -> Option<Vec<u32>> {
    mesh.uvs.as_ref()?;
    let mut parent: Vec<u32> = (0..mesh.vertex_count() as u32).collect();
    fn find(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            parent[v as usize] = parent[parent[v as usize] as usize];
            v = parent[v as usize];
        }
        v
    }
    for t in &mesh.triangles {
        for i in 0..2 {
            let (a, b) = (find(&mut parent, t[i]), find(&mut parent, t[i + 1]));
            let (lo, hi) = (a.min(b), a.max(b));
            parent[hi as usize] = lo;
        }
    }
    Some((0..mesh.vertex_count() as u32).map(|v| find(&mut parent, v)).collect())
}

/// The welded 1-ring of every welded vertex, ascending.
fn welded_neighbours(weld: &Weld) -> Vec<Vec<u32>> {
    let mut rings = vec![Vec::new(); weld.welded_count()];
    for f in &weld.faces {
        for i in 0..3 {
            rings[f[i] as usize].push(f[(i + 1) % 3]);
            rings[f[i] as usize].push(f[(i + 2) % 3]);
        }
    }
    for r in &mut rings {
        r.sort_unstable();
        r.dedup();
    }
    rings
}

/// Weights for a vertex at `x` mapped to `welded`: the refit over the joints of `welded`
/// and its ring, or `welded`'s own `limit` largest weights when they fit better. Returns
/// the weights and whether they are the refit.
fn refit_vertex(
    mesh: &SkinnedMesh,
    weld: &Weld,
    neighbours: &[Vec<u32>],
    welded: usize,
    x: &Vec3,
    targets: &PoseTargets,
    limit: usize,
) -> (Vec<(u16, f32)>, bool) {
    let representative = weld.copies_of(welded)[0] as usize;
    let mut candidates: Vec<usize> = mesh.influences.of(representative).map(|(j, _)| j).collect();
    for &n in &neighbours[welded] {
        candidates.extend(mesh.influences.of(weld.copies_of(n as usize)[0] as usize).map(|(j, _)| j));
    }
    candidates.sort_unstable();
    candidates.dedup();
    let y: Vec<Vec3> = targets.positions.iter().map(|p| p[welded]).collect();
    let own = largest_normalised(
        mesh.influences.of(representative).map(|(j, w)| (j, f64::from(w))).collect(),
        limit,
    );
    let own_residual = residual(x, &own, targets.joints, &y);
    let (weights, refitted) = match fit_weights(x, &candidates, targets.joints, &y, limit) {
        Some((fit, r)) if r < own_residual => (fit, true),
        _ => (own, false),
    };
    (to_f32_weights(&weights), refitted)
}

/// At most `limit` of the split vertex `representative`'s own joints (welded vertex
/// `welded`), weighted to skin it as closely as they can to where all its joints put it
/// over the poses of `targets`: the non-negative least-squares refit over its own joints
/// ([`fit_weights`]) when it skins closer than its `limit` largest weights renormalised
/// (which it never does only when they are already the best), else those.
fn capped_weights(
    mesh: &SkinnedMesh,
    representative: usize,
    welded: usize,
    targets: &PoseTargets,
    limit: usize,
) -> Vec<(u16, f32)> {
    let own: Vec<(usize, f64)> = mesh.influences.of(representative).map(|(j, w)| (j, f64::from(w))).collect();
    let largest = largest_normalised(own.clone(), limit);
    let p = mesh.positions[representative];
    let x = Vec3::new(p[0].into(), p[1].into(), p[2].into());
    let y: Vec<Vec3> = targets.positions.iter().map(|pose| pose[welded]).collect();
    let joints: Vec<usize> = own.iter().map(|w| w.0).collect();
    let largest_residual = residual(&x, &largest, targets.joints, &y);
    let weights = match fit_weights(&x, &joints, targets.joints, &y, limit) {
        Some((fit, r)) if r < largest_residual => fit,
        _ => largest,
    };
    to_f32_weights(&weights)
}

/// The `limit` largest weights, renormalised.
fn largest_normalised(mut weights: Vec<(usize, f64)>, limit: usize) -> Vec<(usize, f64)> {
    weights.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    weights.truncate(limit);
    weights.sort_by_key(|w| w.0);
    let total: f64 = weights.iter().map(|w| w.1).sum();
    weights.iter().map(|&(j, w)| (j, w / total)).collect()
}

/// `f32` weights whose `f32` sum is as close to 1 as rounding allows: the largest takes
/// the remainder.
pub fn to_f32_weights(weights: &[(usize, f64)]) -> Vec<(u16, f32)> {
    let mut out: Vec<(u16, f32)> =
        weights.iter().map(|&(j, w)| (j as u16, w as f32)).filter(|w| w.1 > 0.0).collect();
    if let Some(largest) = (0..out.len()).max_by(|&a, &b| out[a].1.total_cmp(&out[b].1).then(b.cmp(&a))) {
        let rest: f32 = out.iter().enumerate().filter(|(i, _)| *i != largest).map(|(_, w)| w.1).sum();
        out[largest].1 = 1.0 - rest;
    }
    out
}
