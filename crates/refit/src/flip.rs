//! `desal-refit`'s last step: edge flips that make the simplified mesh's triangles follow
//! the full surface in every pose; and [`unspike`], a rig's LOD levels' last step: edge
//! flips that leave fewer faces turned over in the poses.
//!
//! Subset placement keeps original vertices, so in every pose each coarse vertex lies
//! exactly on the full surface; what is left to choose is how the triangles span them,
//! and stage 3 chose that on the template alone. An interior edge `(a, b)` between the
//! faces `[a, b, c]` and `[b, a, d]` can be replaced by `(c, d)`, giving `[c, a, d]` and
//! `[d, b, c]`. The flip is kept when the full vertices near the two faces — those whose
//! nearest coarse face on the template is one of them — are closer to the flipped pair
//! than to the old one, their squared distances summed over the poses stage 2 saw.
//!
//! A round costs every edge and takes the flips by decreasing gain, none touching a face
//! another flip of the round has changed; the nearest faces are then found again. A face
//! pair's gain is reused from the round before while neither face nor the full vertices
//! nearest them changed, so later rounds cost little (SCAPE: 2.9 → 1.9 s). Rounds
//! stop when one flips nothing, after at most [`ROUNDS`] (on `desal`'s SCAPE mesh at 2500
//! vertices: 795, 183, 35, 6, then 2 a round flipping back and forth as the nearest faces
//! move).
//!
//! Safeguards: an edge shared by other than two faces, whose flipped edge exists already,
//! or whose two ends are both on a rig's attribute seams is never flipped; nor is one
//! whose flipped faces are slivers or turn on the template by more than
//! [`MAX_TURN_DEG`] against the old pair's normal or against each other (so no face
//! folds over on the template; the poses are not checked).

use std::collections::{HashMap, HashSet};

use desal_measures::SurfaceIndex;
use desal_measures::closest_point::point_triangle_distance_sq;
use desal_mesh::{Face, PoseSet, Real, TriMesh, Vec3};
use rayon::prelude::*;

/// At most this many rounds.
pub const ROUNDS: usize = 8;

/// A flip is kept when it lowers its faces' error by at least this fraction.
const MIN_GAIN: Real = 1e-3;

/// How far a flipped face may turn on the template (degrees).
pub const MAX_TURN_DEG: Real = 60.0;

/// Flips edges of `faces` where the full surface `truth` is followed better over its
/// poses `poses`. The faces index coarse vertices, coarse vertex `i` being the original
/// vertex `kept[i]` (subset placement); an edge between two vertices marked in `pinned`
/// (one entry per coarse vertex: a rig's seam vertices) is never flipped. Returns the
/// number of flips, a flip undone by a later round counting twice.
pub fn flip_edges(
    faces: &mut [Face],
    kept: &[u32],
    truth: &PoseSet,
    poses: &[usize],
    pinned: &[bool],
) -> usize {
    // The coarse set in every pose: its vertices sit on the original ones.
    let coarse: Vec<Vec<Vec3>> =
        truth.poses.iter().map(|pose| kept.iter().map(|&o| pose[o as usize]).collect()).collect();
    let template = &coarse[truth.template];
    let max_turn = MAX_TURN_DEG.to_radians().cos();
    let mut flips = 0;
    // Each face pair's gain from the round before, reused while neither face nor the
    // full vertices nearest them changed (the same sums, so the same flips).
    let mut known: HashMap<(usize, usize), Option<Real>> = HashMap::new();
    let mut previous: Option<(Vec<Vec<u32>>, Vec<bool>)> = None;
    for _ in 0..ROUNDS {
        let near = nearest_faces(faces, template, &truth.poses[truth.template]);
        let dirty: Vec<bool> = match &previous {
            None => vec![true; faces.len()],
            Some((near_before, changed)) => {
                (0..faces.len()).map(|f| changed[f] || near[f] != near_before[f]).collect()
            }
        };
        let edges = interior_edges(faces);
        let mut exists: HashSet<(u32, u32)> =
            faces.iter().flat_map(|f| (0..3).map(move |i| undirected(f[i], f[(i + 1) % 3]))).collect();
        let evaluated: Vec<(usize, Option<Real>)> = edges
            .par_iter()
            .enumerate()
            .filter_map(|(k, e)| {
                let (old, new) = e.flippable(&exists, pinned, template, max_turn)?;
                if !dirty[e.f0]
                    && !dirty[e.f1]
                    && let Some(&gain) = known.get(&(e.f0, e.f1))
                {
                    return Some((k, gain));
                }
                let vertices: Vec<u32> = near[e.f0].iter().chain(&near[e.f1]).copied().collect();
                let (mut before, mut after) = (0.0, 0.0);
                for &p in poses {
                    for &v in &vertices {
                        let x = &truth.poses[p][v as usize];
                        before += pair_distance_sq(x, &coarse[p], old);
                        after += pair_distance_sq(x, &coarse[p], new);
                    }
                }
                let gain =
                    (!vertices.is_empty() && after < before * (1.0 - MIN_GAIN)).then_some(before - after);
                Some((k, gain))
            })
            .collect();
        known = evaluated.iter().map(|&(k, gain)| ((edges[k].f0, edges[k].f1), gain)).collect();
        let mut gains: Vec<(Real, usize)> =
            evaluated.into_iter().filter_map(|(k, gain)| gain.map(|g| (g, k))).collect();
        // Largest gain first; ties in edge order (the sort is stable).
        gains.sort_by(|x, y| y.0.total_cmp(&x.0));
        let (round, changed) =
            apply_flips(faces, &edges, gains.into_iter().map(|(_, k)| k), &mut exists, |_| {});
        flips += round;
        if round == 0 {
            break;
        }
        previous = Some((near, changed));
    }
    flips
}

/// Flips edges of the faces that turn over against the full surface in some pose — the
/// spikes `desal eval` counts — where the flipped pair turns over in fewer (face, pose)
/// pairs over `poses` than the pair it replaces (a rig's LOD levels: `stages::lods`). A
/// coarse face stands for the full face nearest its centroid on the template, and turns
/// over in a pose where its normal points away from that face's normal there: one
/// search per face, not one per pose (the avatar sample's three levels take 0.3 s with
/// it). `mesh_of` gives each full vertex's mesh for a rig of several meshes (empty: one),
/// so that a face stands for a face of its own mesh, as the eval judges it. Arguments and
/// safeguards otherwise as [`flip_edges`]; the flips of a round are taken by decreasing
/// gain, none touching a face another has changed, for at most [`ROUNDS`] rounds.
/// Returns the number of flips.
pub fn unspike(
    faces: &mut [Face],
    kept: &[u32],
    truth: &PoseSet,
    poses: &[usize],
    pinned: &[bool],
    mesh_of: &[u32],
) -> usize {
    let coarse: Vec<Vec<Vec3>> =
        truth.poses.iter().map(|pose| kept.iter().map(|&o| pose[o as usize]).collect()).collect();
    let template = &coarse[truth.template];
    let max_turn = MAX_TURN_DEG.to_radians().cos();
    let mesh = |full_vertex: u32| if mesh_of.is_empty() { 0 } else { mesh_of[full_vertex as usize] as usize };
    let meshes = mesh_of.iter().max().map_or(1, |&m| m as usize + 1);
    // Per mesh, its full faces and their index on the template: a coarse face stands for
    // the full face nearest its centroid there, and turns over in a pose where its normal
    // points away from that face's.
    let parts: Vec<Vec<Face>> =
        (0..meshes).map(|m| truth.faces.iter().filter(|f| mesh(f[0]) == m).copied().collect()).collect();
    let trees: Vec<SurfaceIndex> = parts
        .iter()
        .map(|faces| {
            SurfaceIndex::new(&TriMesh {
                positions: truth.poses[truth.template].clone(),
                faces: faces.clone(),
            })
        })
        .collect();
    let normal_of = |positions: &[Vec3], [a, b, c]: Face| {
        let [a, b, c] = [a, b, c].map(|v| positions[v as usize]);
        (b - a).cross(&(c - a))
    };
    // Poses in which `face` turns over.
    let turned = |face: Face| -> usize {
        let m = mesh(kept[face[0] as usize]);
        let [a, b, c] = face.map(|v| template[v as usize]);
        let Some((f, _)) = trees[m].nearest(&((a + b + c) / 3.0)) else { return 0 };
        let full_face = parts[m][f as usize];
        poses
            .iter()
            .filter(|&&p| {
                let normal = normal_of(&coarse[p], face);
                normal.norm_squared() > 0.0 && normal.dot(&normal_of(&truth.poses[p], full_face)) < 0.0
            })
            .count()
    };
    let mut flips = 0;
    let mut spiked: Vec<usize> = faces.par_iter().map(|&f| turned(f)).collect();
    for _ in 0..ROUNDS {
        let edges = interior_edges(faces);
        let mut exists: HashSet<(u32, u32)> =
            faces.iter().flat_map(|f| (0..3).map(move |i| undirected(f[i], f[(i + 1) % 3]))).collect();
        let mut gains: Vec<(usize, usize)> = edges
            .par_iter()
            .enumerate()
            .filter_map(|(k, e)| {
                let before = spiked[e.f0] + spiked[e.f1];
                if before == 0 {
                    return None;
                }
                let (_, new) = e.flippable(&exists, pinned, template, max_turn)?;
                let after = turned(new[0]) + turned(new[1]);
                (after < before).then(|| (before - after, k))
            })
            .collect();
        // Largest gain first; ties in edge order.
        gains.sort_by(|x, y| y.0.cmp(&x.0).then(x.1.cmp(&y.1)));
        let (round, _) = apply_flips(faces, &edges, gains.into_iter().map(|(_, k)| k), &mut exists, |e| {
            let (_, new) = e.pairs();
            (spiked[e.f0], spiked[e.f1]) = (turned(new[0]), turned(new[1]));
        });
        flips += round;
        if round == 0 {
            break;
        }
    }
    flips
}

/// Per coarse face, the full vertices (`full`, template positions) whose nearest coarse
/// face on the template (`positions`) it is.
fn nearest_faces(faces: &[Face], positions: &[Vec3], full: &[Vec3]) -> Vec<Vec<u32>> {
    let index = SurfaceIndex::new(&TriMesh { positions: positions.to_vec(), faces: faces.to_vec() });
    let nearest: Vec<Option<u32>> = full.par_iter().map(|p| index.nearest(p).map(|(f, _)| f)).collect();
    let mut near = vec![Vec::new(); faces.len()];
    for (v, f) in nearest.iter().enumerate() {
        if let Some(f) = f {
            near[*f as usize].push(v as u32);
        }
    }
    near
}

/// An interior edge: `a → b` in face `f0` (`[a, b, c]` up to rotation), `b → a` in
/// face `f1` (`[b, a, d]`).
struct Edge {
    a: u32,
    b: u32,
    c: u32,
    d: u32,
    f0: usize,
    f1: usize,
}

impl Edge {
    /// The two faces now, and after the flip (same orientation).
    fn pairs(&self) -> ([Face; 2], [Face; 2]) {
        let (a, b, c, d) = (self.a, self.b, self.c, self.d);
        ([[a, b, c], [b, a, d]], [[c, a, d], [d, b, c]])
    }
}

impl Edge {
    /// The pair now and flipped, when the flip is allowed: the faces differ in their third
    /// vertex, the flipped edge does not exist yet, not both ends are `pinned`, and the
    /// flipped faces keep their orientation on `template` ([`keeps_orientation`]).
    fn flippable(
        &self,
        exists: &HashSet<(u32, u32)>,
        pinned: &[bool],
        template: &[Vec3],
        max_turn: Real,
    ) -> Option<([Face; 2], [Face; 2])> {
        let allowed = self.c != self.d
            && !exists.contains(&undirected(self.c, self.d))
            && !(pinned[self.a as usize] && pinned[self.b as usize]);
        let (old, new) = self.pairs();
        (allowed && keeps_orientation(template, old, new, max_turn)).then_some((old, new))
    }
}

/// Makes the flips of `edges` in `order` (best first), skipping one that touches a face
/// an earlier flip of the round changed or whose flipped edge exists; `made` sees each
/// flip made. Returns the number of flips and which faces changed.
fn apply_flips(
    faces: &mut [Face],
    edges: &[Edge],
    order: impl IntoIterator<Item = usize>,
    exists: &mut HashSet<(u32, u32)>,
    mut made: impl FnMut(&Edge),
) -> (usize, Vec<bool>) {
    let mut changed = vec![false; faces.len()];
    let mut flips = 0;
    for k in order {
        let e = &edges[k];
        if changed[e.f0] || changed[e.f1] || exists.contains(&undirected(e.c, e.d)) {
            continue;
        }
        let (_, new) = e.pairs();
        (faces[e.f0], faces[e.f1]) = (new[0], new[1]);
        (changed[e.f0], changed[e.f1]) = (true, true);
        exists.remove(&undirected(e.a, e.b));
        exists.insert(undirected(e.c, e.d));
        made(e);
        flips += 1;
    }
    (flips, changed)
}

fn undirected(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// Every edge of exactly two faces, one in each direction, in vertex order.
fn interior_edges(faces: &[Face]) -> Vec<Edge> {
    let mut directed: HashMap<(u32, u32), Vec<(usize, u32)>> = HashMap::with_capacity(faces.len() * 3);
    for (f, face) in faces.iter().enumerate() {
        for i in 0..3 {
            directed.entry((face[i], face[(i + 1) % 3])).or_default().push((f, face[(i + 2) % 3]));
        }
    }
    let mut edges: Vec<Edge> = directed
        .iter()
        .filter(|&(&(a, b), from)| a < b && from.len() == 1)
        .filter_map(|(&(a, b), from)| {
            let back = directed.get(&(b, a)).filter(|back| back.len() == 1)?;
            Some(Edge { a, b, c: from[0].1, d: back[0].1, f0: from[0].0, f1: back[0].0 })
        })
        .collect();
    edges.sort_by_key(|e| (e.a, e.b));
    edges
}

/// Whether the flipped faces `new` stay within `max_turn` (a cosine) of the old pair's
/// summed normal and of each other on the template, neither of them degenerate.
fn keeps_orientation(positions: &[Vec3], old: [Face; 2], new: [Face; 2], max_turn: Real) -> bool {
    let normal = |f: Face| {
        let [a, b, c] = f.map(|i| positions[i as usize]);
        (b - a).cross(&(c - a))
    };
    // A face whose doubled area is below 1e-9 of its longest edge squared is a sliver:
    // its normal means nothing, and the flip is refused.
    let longest = |f: Face| {
        let [a, b, c] = f.map(|i| positions[i as usize]);
        (b - a).norm_squared().max((c - b).norm_squared()).max((a - c).norm_squared())
    };
    let sliver = |f: Face| normal(f).norm() <= 1e-9 * longest(f);
    if new.iter().any(|&f| sliver(f)) {
        return false;
    }
    let unit = |n: Vec3| n.try_normalize(0.0);
    let (Some(before), Some(n0), Some(n1)) =
        (unit(normal(old[0]) + normal(old[1])), unit(normal(new[0])), unit(normal(new[1])))
    else {
        return false;
    };
    n0.dot(&before) >= max_turn && n1.dot(&before) >= max_turn && n0.dot(&n1) >= max_turn
}

/// The squared distance of `x` to the nearer of the faces `pair` (over `positions`).
fn pair_distance_sq(x: &Vec3, positions: &[Vec3], pair: [Face; 2]) -> Real {
    pair.iter()
        .map(|f| {
            let [a, b, c] = f.map(|i| positions[i as usize]);
            point_triangle_distance_sq(x, &a, &b, &c)
        })
        .fold(Real::INFINITY, Real::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A full mesh of a unit square's four corners and its centre, flat on the template;
    /// in the second pose corners 1 and 3 and the centre rise by `rise`. The coarse
    /// faces: the corners, split along 0–2.
    fn square(rise: [Real; 3]) -> (PoseSet, Vec<Face>) {
        let flat = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.5, 0.5, 0.0),
        ];
        let mut bent = flat.clone();
        for (v, r) in [1, 3, 4].into_iter().zip(rise) {
            bent[v].z = r;
        }
        let truth = PoseSet {
            names: vec!["t".to_string(), "p".to_string()],
            poses: vec![flat, bent],
            faces: vec![[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]],
            template: 0,
            groups: None,
        };
        (truth, vec![[0, 1, 2], [0, 2, 3]])
    }

    /// The coarse vertices: the square's corners.
    const CORNERS: [u32; 4] = [0, 1, 2, 3];

    /// The turn and sliver guards: a convex quad may flip; one whose flipped faces would
    /// fold over (the new diagonal outside the quad), or one where a new face is a
    /// sliver (its corners in a line), may not.
    #[test]
    fn a_flip_that_folds_a_face_or_makes_a_sliver_is_refused() {
        let e = Edge { a: 0, b: 1, c: 2, d: 3, f0: 0, f1: 1 };
        let (old, new) = e.pairs();
        let cos = MAX_TURN_DEG.to_radians().cos();
        let quad = |c: [Real; 2], d: [Real; 2]| {
            vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(c[0], c[1], 0.0),
                Vec3::new(d[0], d[1], 0.0),
            ]
        };
        assert!(keeps_orientation(&quad([1.0, 1.0], [1.0, -1.0]), old, new, cos), "convex");
        assert!(
            !keeps_orientation(&quad([-0.5, 1.0], [-0.5, -1.0]), old, new, cos),
            "the new diagonal outside"
        );
        // c, a and d all but in a line: the face [c, a, d] faces +z, but with a doubled
        // area of 1e-13 against its longest edge squared of 8.
        assert!(!keeps_orientation(&quad([-1.0, 1.0], [1.0, -1.0 + 1e-13]), old, new, cos), "a sliver");
    }

    fn has_edge(faces: &[Face], a: u32, b: u32) -> bool {
        faces.iter().any(|f| (0..3).any(|i| undirected(f[i], f[(i + 1) % 3]) == undirected(a, b)))
    }

    /// The crease along 1–3 is followed after the flip (the full centre then lies on
    /// the coarse surface in both poses); with the centre left at the height of the 0–2
    /// diagonal instead, the old split fits it and nothing is flipped; an edge between
    /// pinned vertices is kept.
    #[test]
    fn an_edge_flips_to_follow_the_full_surface_in_every_pose() {
        let (truth, coarse) = square([1.0, 1.0, 1.0]);
        let mut faces = coarse.clone();
        assert_eq!(flip_edges(&mut faces, &CORNERS, &truth, &[0, 1], &[false; 4]), 1);
        assert!(has_edge(&faces, 1, 3) && !has_edge(&faces, 0, 2), "{faces:?}");
        // Orientation kept: both faces face +z on the template.
        for f in &faces {
            let [a, b, c] = f.map(|i| truth.poses[0][i as usize]);
            assert!((b - a).cross(&(c - a)).z > 0.0, "{faces:?}");
        }
        let (truth, coarse) = square([1.0, 1.0, 0.0]);
        let mut faces = coarse.clone();
        assert_eq!(flip_edges(&mut faces, &CORNERS, &truth, &[0, 1], &[false; 4]), 0);
        assert_eq!(faces, coarse);
        let (truth, coarse) = square([1.0, 1.0, 1.0]);
        let mut faces = coarse.clone();
        assert_eq!(flip_edges(&mut faces, &CORNERS, &truth, &[0, 1], &[true, false, true, false]), 0);
        // Pinned at one end only, the edge flips.
        let mut faces = coarse.clone();
        assert_eq!(flip_edges(&mut faces, &CORNERS, &truth, &[0, 1], &[true, false, false, false]), 1);
    }

    /// A quad folded 160° along its full diagonal 0–2 in the second pose: the coarse pair
    /// split along 1–3 turns over there, the full faces do not, and `unspike` flips the
    /// coarse diagonal onto 0–2 (once; a second call finds nothing). Pinned, it stays.
    #[test]
    fn unspike_flips_a_pair_that_turns_over_onto_the_fold() {
        let v = Vec3::new;
        let template = vec![v(0.0, 0.0, 0.0), v(2.0, 0.0, 0.0), v(1.5, 1.2, 0.0), v(0.0, 1.0, 0.0)];
        // Vertex 1 turned 160° about the axis through vertices 0 and 2.
        let (k, x, t) = (template[2].normalize(), template[1], 160f64.to_radians());
        let mut folded = template.clone();
        // Rodrigues' rotation of vertex 1 by `t` about the unit axis `k`.
        folded[1] = x * t.cos() + k.cross(&x) * t.sin() + k * k.dot(&x) * (1.0 - t.cos());
        let truth = PoseSet::try_new(
            vec!["rest".into(), "folded".into()],
            vec![template, folded],
            vec![[0, 1, 2], [0, 2, 3]],
            0,
        )
        .unwrap();
        let kept = [0, 1, 2, 3];
        let coarse = vec![[0, 1, 3], [1, 2, 3]];
        let mut faces = coarse.clone();
        assert_eq!(unspike(&mut faces, &kept, &truth, &[0, 1], &[false; 4], &[]), 1);
        let mut diagonal: Vec<u32> =
            faces.iter().flatten().copied().filter(|&x| faces.iter().all(|f| f.contains(&x))).collect();
        diagonal.sort();
        diagonal.dedup();
        assert_eq!(diagonal, [0, 2], "{faces:?}");
        assert_eq!(unspike(&mut faces, &kept, &truth, &[0, 1], &[false; 4], &[]), 0);
        let mut pinned_faces = coarse.clone();
        assert_eq!(unspike(&mut pinned_faces, &kept, &truth, &[0, 1], &[false, true, false, true], &[]), 0);
        assert_eq!(pinned_faces, coarse);
    }
}
