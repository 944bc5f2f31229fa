//! Phase 1 of the engine, as functions over explicit arrays: the face quadrics and input
//! normals, the vertex normals, and per vertex its flags (boundary, non-manifold, part
//! border, seam) and its quadric (face planes plus boundary, part-border and seam
//! constraint planes, per pose). meshoptimizer's `fillFaceQuadrics`, `fillEdgeQuadrics`
//! and `classifyVertices`.
//!
//! Seam vertices, as meshoptimizer classifies them: a vertex with exactly two seam edges
//! and no boundary edge is `SEAM` (meshoptimizer's `Kind_Seam`: it may collapse along its
//! seam only); any other vertex on a seam — a seam's end, a junction of three or more
//! seam edges, a seam meeting the boundary — is `PINNED` (`Kind_Locked`).

use desal_mesh::Vec3;
use rayon::prelude::*;

use crate::config::{PartBorders, SimplifyConfig};
use crate::face_lists::FaceLists;
use crate::quadric::{FacePlane, Quadric};
use crate::seams::SeamGraph;

/// Vertex flags, one byte per slot: the slot holds a vertex with faces.
pub(crate) const ALIVE: u8 = 1;
/// The vertex is on a boundary edge (an edge with one face).
pub(crate) const BOUNDARY: u8 = 2;
/// Input non-manifold vertex (pinched fans, or an edge with more than two faces): no
/// incident edge is ever collapsed.
pub(crate) const FROZEN: u8 = 4;
/// The vertex keeps its position and is never removed; it may absorb neighbours.
pub(crate) const PINNED: u8 = 8;
/// The vertex is inside a seam (exactly two seam edges, not on the boundary): it is
/// removed only along one of its seam edges, and it may absorb neighbours.
pub(crate) const SEAM: u8 = 16;

/// Weight of the seam constraint planes, as [`SimplifyConfig::boundary_weight`] weighs
/// the boundary's (× edge length², one plane per face along the edge). meshoptimizer's
/// `kEdgeWeightSeam`: 1 where its boundary weight is 10, since the collapse rules already
/// keep a seam a polyline and the planes only have to keep its shape, not its place on
/// an open edge.
pub(crate) const SEAM_WEIGHT: f64 = 1.0;

/// Vertices (or faces, or edges) per work item of the parallel passes.
pub(crate) const CHUNK: usize = 2048;

/// One value per face, filled in parallel a chunk of `CHUNK` faces at a time by
/// `chunk(values, faces)` (a loop per chunk, in one of the clones of
/// `with_avx2_clone!`, where a closure per face was).
fn per_face<T: Clone + Send>(
    faces: &[[u32; 3]],
    empty: T,
    chunk: impl Fn(&mut [T], &[[u32; 3]]) + Sync,
) -> Vec<T> {
    let mut values = vec![empty; faces.len()];
    values
        .par_chunks_mut(CHUNK)
        .zip(faces.par_chunks(CHUNK))
        .for_each(|(values, faces)| chunk(values, faces));
    values
}

/// The plane of every face of one pose (whose quadric is the face's), in face order.
pub(crate) fn fill_face_planes(faces: &[[u32; 3]], positions: &[Vec3]) -> Vec<FacePlane> {
    per_face(faces, FacePlane::default(), |planes, faces| face_planes_chunk(planes, faces, positions))
}

with_avx2_clone! {
    /// [`fill_face_planes`] for one chunk of faces, compiled twice (`with_avx2_clone!`):
    /// a loop per chunk where a closure per face was (BENCHMARKS.md "Issue 40").
    fn face_planes_chunk(planes: &mut [FacePlane], faces: &[[u32; 3]], positions: &[Vec3]) {
        for (plane, f) in planes.iter_mut().zip(faces) {
            let [a, b, c] = corners(f, positions);
            *plane = FacePlane::of_triangle(&a, &b, &c);
        }
    }
}

/// The unnormalised normal of every face (template pose, input coordinates): what the
/// fold-over safeguard compares surviving faces with. Its length is recomputed where
/// it is needed (the same value, bit for bit): storing it took 8 of 32 bytes per face.
pub(crate) fn compute_input_normals(faces: &[[u32; 3]], positions: &[Vec3]) -> Vec<Vec3> {
    per_face(faces, Vec3::zeros(), |normals, faces| input_normals_chunk(normals, faces, positions))
}

with_avx2_clone! {
    /// [`compute_input_normals`] for one chunk of faces, compiled twice
    /// (`with_avx2_clone!`): a loop per chunk where a closure per face was.
    fn input_normals_chunk(normals: &mut [Vec3], faces: &[[u32; 3]], positions: &[Vec3]) {
        for (normal, f) in normals.iter_mut().zip(faces) {
            let [a, b, c] = corners(f, positions);
            *normal = (b - a).cross(&(c - a));
        }
    }
}

/// The unit area-weighted normal of every vertex (zero for an isolated vertex): the
/// surface's orientation where the vertex came from.
pub(crate) fn compute_vertex_normals(lists: &FaceLists, input_normals: &[Vec3]) -> Vec<Vec3> {
    let mut normals = vec![Vec3::zeros(); lists.slot_count()];
    normals.par_chunks_mut(CHUNK).enumerate().for_each(|(chunk, normals)| {
        vertex_normals_chunk(normals, (chunk * CHUNK) as u32, lists, input_normals)
    });
    normals
}

with_avx2_clone! {
    /// [`compute_vertex_normals`] for the slots from `first` on, compiled twice
    /// (`with_avx2_clone!`): a loop per chunk where a closure per slot was.
    fn vertex_normals_chunk(
        normals: &mut [Vec3],
        first: u32,
        lists: &FaceLists,
        input_normals: &[Vec3],
    ) {
        for (v, normal) in (first..).zip(normals.iter_mut()) {
            let sum: Vec3 = lists.of(v).iter().map(|&f| input_normals[f as usize]).sum();
            let length = sum.norm();
            *normal = if length > 0.0 { sum / length } else { Vec3::zeros() };
        }
    }
}

/// What the per-vertex classification reads.
pub(crate) struct ClassifyInput<'a> {
    pub(crate) lists: &'a FaceLists,
    /// Local positions, `[pose][vertex]`.
    pub(crate) poses: &'a [Vec<Vec3>],
    /// The plane of every face, when there is one pose (several poses: each face's
    /// plane is computed where it is summed, per pose).
    pub(crate) face_planes: Option<&'a [FacePlane]>,
    pub(crate) part_labels: Option<&'a [u32]>,
    pub(crate) seams: Option<&'a SeamGraph>,
    pub(crate) config: &'a SimplifyConfig,
}

/// Flags of every vertex, and its quadrics `[slot * pose_count + pose]`, in one
/// parallel pass writing in place (no per-chunk copies: on a million faces those
/// would be the run's peak memory).
pub(crate) fn classify_vertices(input: &ClassifyInput<'_>) -> (Vec<u8>, Vec<Quadric>) {
    let n = input.lists.slot_count();
    let pose_count = input.poses.len();
    let mut flags = vec![0u8; n];
    let mut quadrics = vec![Quadric::default(); n * pose_count];
    flags
        .par_chunks_mut(CHUNK)
        .zip(quadrics.par_chunks_mut(CHUNK * pose_count))
        .enumerate()
        .for_each(|(chunk, (flags, quadrics))| classify_chunk(input, chunk * CHUNK, flags, quadrics));
    (flags, quadrics)
}

/// [`classify_vertices`] for the vertices from `first` on, one per entry of `flags`. A
/// function of its own, not the body of the parallel closure: its outputs are then
/// reference arguments, which LLVM may assume alias nothing else (BENCHMARKS.md
/// "Issue 40").
#[inline(never)]
fn classify_chunk(input: &ClassifyInput<'_>, first: usize, flags: &mut [u8], quadrics: &mut [Quadric]) {
    let pose_count = input.poses.len();
    let mut link = Link::default();
    for (i, (vertex_flags, vertex_quadrics)) in
        flags.iter_mut().zip(quadrics.chunks_exact_mut(pose_count)).enumerate()
    {
        let v = (first + i) as u32;
        link.gather(input.lists, v);
        let constraints;
        (*vertex_flags, constraints) = classify_vertex(input, &link, v);
        fill_vertex_quadrics(input, &link, v, &constraints, vertex_quadrics);
    }
}

/// The constraint weights that apply at one vertex.
#[derive(Debug, Clone, Copy)]
struct Constraints {
    /// Boundary edges at the vertex are held with this weight.
    boundary: Option<f64>,
    /// Part-border edges at the vertex are held with this weight.
    part_border: Option<f64>,
    /// Seam edges at the vertex are held with [`SEAM_WEIGHT`].
    seam: bool,
}

/// A vertex's flags: non-manifold (FROZEN) when an incident edge has more than two
/// faces or its faces form more than one fan (a pinch, like SCAPE's vertex 419); on a
/// seam, `SEAM` or `PINNED` (see the module doc).
fn classify_vertex(input: &ClassifyInput<'_>, link: &Link, v: u32) -> (u8, Constraints) {
    let config = input.config;
    // A closed fan is one fan with neither boundary nor non-manifold edges. Any other
    // link has its fans (union-find roots), boundary edges (one face) and non-manifold
    // ones (more than two) counted in one walk.
    let (fans, on_boundary, non_manifold) = if link.closed_fan {
        (1, false, false)
    } else {
        let (mut fans, mut on_boundary, mut non_manifold) = (0, false, false);
        for (i, x) in link.neighbours.iter().enumerate() {
            fans += usize::from(x.parent as usize == i);
            on_boundary |= x.faces == 1;
            non_manifold |= x.faces > 2;
        }
        (fans, on_boundary, non_manifold)
    };
    let mut flags = if input.lists.of(v).is_empty() { 0 } else { ALIVE };
    if on_boundary {
        flags |= BOUNDARY;
    }
    if fans > 1 || non_manifold {
        flags |= FROZEN;
    }
    let label_of = |x: u32| input.part_labels.map(|l| l[x as usize]);
    let on_part_border =
        input.part_labels.is_some() && link.neighbours.iter().any(|x| label_of(x.vertex) != label_of(v));
    if on_part_border && config.part_borders == PartBorders::Lock {
        flags |= PINNED;
    }
    let part_border = match config.part_borders {
        PartBorders::Constrain(w) if on_part_border && w > 0.0 => Some(w),
        _ => None,
    };
    let boundary = (on_boundary && config.boundary_weight > 0.0).then_some(config.boundary_weight);
    let seam_edges = input.seams.map_or(0, |s| s.of(v).len());
    if seam_edges == 2 && !on_boundary {
        flags |= SEAM;
    } else if seam_edges > 0 {
        flags |= PINNED;
    }
    (flags, Constraints { boundary, part_border, seam: seam_edges > 0 })
}

/// Vertex `v`'s quadric in every pose, into `out` (one per pose): the planes of its
/// faces and the constraint planes of its boundary, part-border and seam edges.
fn fill_vertex_quadrics(
    input: &ClassifyInput<'_>,
    link: &Link,
    v: u32,
    constraints: &Constraints,
    out: &mut [Quadric],
) {
    let label_of = |x: u32| input.part_labels.map(|l| l[x as usize]);
    let my_faces = input.lists.of(v);
    let constrained = constraints.boundary.is_some() || constraints.part_border.is_some() || constraints.seam;
    for (pose, positions) in input.poses.iter().enumerate() {
        let mut q = Quadric::default();
        // Most vertices have no constraint plane: their quadric is the sum of their
        // faces' (the same sum, in the same order, as the loop below makes).
        if let Some(planes) = input.face_planes.filter(|_| pose == 0 && !constrained) {
            for &f in my_faces {
                q += &planes[f as usize].quadric();
            }
            out[pose] = q;
            continue;
        }
        let pv = &positions[v as usize];
        for &f in my_faces {
            let face = input.lists.face(f);
            let [p0, p1, p2] = face.map(|x| positions[x as usize]);
            match input.face_planes {
                Some(planes) if pose == 0 => q += &planes[f as usize].quadric(),
                _ => q += &Quadric::from_triangle(&p0, &p1, &p2),
            }
            if !constrained {
                continue;
            }
            let cross = (p1 - p0).cross(&(p2 - p0));
            for x in others(face, v) {
                let px = &positions[x as usize];
                if let Some(w) = constraints.boundary
                    && link.faces_shared(x) == 1
                {
                    q += &Quadric::edge_constraint(pv, px, &cross, w);
                }
                if let Some(w) = constraints.part_border
                    && label_of(x) != label_of(v)
                {
                    q += &Quadric::edge_constraint(pv, px, &cross, w);
                }
                if constraints.seam && input.seams.is_some_and(|s| s.joins(v, x)) {
                    q += &Quadric::edge_constraint(pv, px, &cross, SEAM_WEIGHT);
                }
            }
        }
        out[pose] = q;
    }
}

/// The link of one vertex: its neighbours, how many of its faces each shares, and a
/// union-find over them whose roots count the fans. One entry per neighbour (one push
/// each, where three parallel arrays took three).
#[derive(Debug, Default)]
struct Link {
    neighbours: Vec<LinkNeighbour>,
    /// Scratch of [`Link::gather_closed_fan`]: the two other corners of each face, in
    /// face order after the vertex.
    corners: Vec<[u32; 2]>,
    /// The faces are one closed fan ([`Link::gather_closed_fan`] found it).
    closed_fan: bool,
}

/// One neighbour in a [`Link`].
#[derive(Debug, Clone, Copy)]
struct LinkNeighbour {
    vertex: u32,
    /// How many of the vertex's faces this neighbour is a corner of.
    faces: u32,
    /// Union-find parent, an index into `Link::neighbours`.
    parent: u32,
}

impl Link {
    /// Rebuilds the link of `v` from its faces.
    fn gather(&mut self, lists: &FaceLists, v: u32) {
        self.neighbours.clear();
        self.closed_fan = self.gather_closed_fan(lists, v);
        if self.closed_fan {
            return;
        }
        for &f in lists.of(v) {
            let [x, y] = others(lists.face(f), v);
            let (i, j) = (self.slot(x), self.slot(y));
            // On a slice: through the `Vec` its length is read again at every index.
            let n = self.neighbours.as_mut_slice();
            n[i].faces += 1;
            n[j].faces += 1;
            let (ri, rj) = (root(n, i), root(n, j));
            n[ri.max(rj)].parent = ri.min(rj) as u32;
        }
    }

    /// The link of `v` when its faces are one closed, consistently oriented fan, the
    /// common case: each face's second corner after `v` is the next face's first, and
    /// following that from the first face visits every face once before it returns.
    /// Then every neighbour shares exactly two faces and the link is one fan, as the
    /// union-find of [`Link::gather`] would find, at a quarter of its cost. False, with
    /// the link left empty, for any other fan.
    ///
    /// Why the walk proves it: it follows `next(i)`, the first face whose first corner
    /// is face `i`'s second. Returning to the first face after exactly as many steps as
    /// there are faces makes `next` a permutation of one cycle, so no first corner
    /// repeats (a repeated one is never the first match, and a face no step reaches
    /// breaks the cycle), and the second corners are the same vertices again.
    fn gather_closed_fan(&mut self, lists: &FaceLists, v: u32) -> bool {
        self.corners.clear();
        self.corners.extend(lists.of(v).iter().map(|&f| others(lists.face(f), v)));
        let corners = self.corners.as_slice();
        let mut at = 0;
        for step in 1..=corners.len() {
            let second = corners[at][1];
            let Some(next) = corners.iter().position(|&[first, _]| first == second) else { return false };
            if next == 0 {
                if step != corners.len() {
                    return false;
                }
                // One fan: the first entry is the only union-find root.
                self.neighbours.extend(corners.iter().map(|&[x, _]| LinkNeighbour {
                    vertex: x,
                    faces: 2,
                    parent: 0,
                }));
                return true;
            }
            at = next;
        }
        false
    }

    /// How many of the vertex's faces neighbour `x` shares (1: a boundary edge).
    fn faces_shared(&self, x: u32) -> u32 {
        self.neighbours.iter().find(|n| n.vertex == x).expect("a neighbour").faces
    }

    fn slot(&mut self, x: u32) -> usize {
        match self.neighbours.iter().position(|n| n.vertex == x) {
            Some(i) => i,
            None => {
                let i = self.neighbours.len();
                self.neighbours.push(LinkNeighbour { vertex: x, faces: 0, parent: i as u32 });
                i
            }
        }
    }
}

/// The union-find root of entry `i` of a link, halving the path on the way.
#[inline]
fn root(n: &mut [LinkNeighbour], mut i: usize) -> usize {
    while n[i].parent as usize != i {
        n[i].parent = n[n[i].parent as usize].parent;
        i = n[i].parent as usize;
    }
    i
}

/// The positions of the corners of `face`. Written out: `face.map(..)` was not inlined
/// into the per-face closures (a call and its array copies per face).
#[inline]
fn corners(face: &[u32; 3], positions: &[Vec3]) -> [Vec3; 3] {
    [positions[face[0] as usize], positions[face[1] as usize], positions[face[2] as usize]]
}

/// The two vertices of `face` other than `v`, in face order after `v`.
#[inline]
pub(crate) fn others(face: [u32; 3], v: u32) -> [u32; 2] {
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

    /// The closed-fan walk finds the link of a closed fan, and refuses the fans the
    /// union-find must count: two closed fans pinched at one vertex (each walk returns
    /// early), and an open fan (its last face has no successor).
    #[test]
    fn closed_fan_walk_takes_only_single_closed_fans() {
        // Vertex 0 with ring 1..=4 closed, and a second closed ring 5..=7 around it.
        let faces = vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1], [0, 5, 6], [0, 6, 7], [0, 7, 5]];
        let mut link = Link::default();
        let closed = FaceLists::new(8, faces[..4].to_vec());
        assert!(link.gather_closed_fan(&closed, 0));
        assert!(link.neighbours.iter().all(|n| n.faces == 2));
        let pinched = FaceLists::new(8, faces.clone());
        assert!(!link.gather_closed_fan(&pinched, 0));
        link.gather(&pinched, 0);
        assert_eq!(link.neighbours.iter().enumerate().filter(|(i, n)| n.parent as usize == *i).count(), 2);
        let open = FaceLists::new(8, faces[..3].to_vec());
        assert!(!link.gather_closed_fan(&open, 0));
    }
}
