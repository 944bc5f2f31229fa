//! The paper's deformation errors (§4): v2f (Eq. 6) and v2v (Eq. 7), plus the per-vertex
//! arrays behind them for heat maps.
//!
//! Units: every figure is a *squared* distance in the input's units (m² for SCAPE).
//! Distances are exact: point-to-triangle by Ericson's closest-point test
//! ([`crate::closest_point`]), point-to-point by coordinates, both found through a BVH
//! ([`crate::bvh`]). Queries run in parallel over query vertices with order-preserving
//! collects, and every sum is taken in vertex order afterwards, so results are identical
//! for any thread count.
//!
//! Empty inputs: a mean over zero vertices is NaN; a distance to a surface with no
//! faces (or a cloud with no points) is +∞.
//!
//! Ordering: when every vertex of the target is used by one of its faces, a vertex's
//! distance to the target surface never exceeds its distance to the nearest target
//! vertex, so the deformed → target half of v2f is at most v2v (tested). Unreferenced
//! target vertices count for v2v but not for the surface.

use desal_mesh::{Face, Real, TriMesh, Vec3, VertexFaces};
use rayon::prelude::*;

use crate::bvh::{Aabb, Bvh};
use crate::closest_point::point_triangle_distance_sq;
use crate::grid::Grid;

/// A triangle surface prepared for point-to-surface queries. Build it once per target
/// mesh and query it with many point sets (several methods, several poses).
#[derive(Debug, Clone)]
pub struct SurfaceIndex {
    triangles: Vec<[Vec3; 3]>,
    bvh: Bvh,
    /// For seeded queries ([`SurfaceIndex::nearest_seeded`]); `None` without faces.
    grid: Option<Grid>,
    /// For queries near the indexed mesh's own vertices
    /// ([`SurfaceIndex::with_vertex_rings`]).
    rings: Option<VertexRings>,
}

/// Each vertex of an indexed mesh with its faces and its *clearance*: how far every
/// other face is from it. A point within `δ` of vertex `v` is farther than
/// `clearance[v] − δ` from every face not using `v` (the triangle inequality), so when
/// one of `v`'s own faces is nearer than that, it is the answer, found from a handful
/// of exact tests and no search.
#[derive(Debug, Clone)]
struct VertexRings {
    /// Each vertex's faces, in increasing order.
    faces: VertexFaces,
    positions: Vec<Vec3>,
    /// The exact distance from vertex `v` to the nearest face not using it, shrunk far
    /// beyond its rounding (+∞ when every face uses `v`, 0 when none does: such a
    /// vertex never certifies anything).
    clearance: Vec<Real>,
}

impl SurfaceIndex {
    /// Indexes every face of `mesh` (unreferenced vertices play no part).
    pub fn new(mesh: &TriMesh) -> Self {
        let triangles: Vec<[Vec3; 3]> = (0..mesh.face_count()).map(|f| mesh.corners(f)).collect();
        let boxes: Vec<Aabb> = triangles.iter().map(|t| Aabb::of_points(t)).collect();
        Self { bvh: Bvh::build(&boxes), grid: surface_grid(&boxes), triangles, rings: None }
    }

    /// [`SurfaceIndex::new`] that also answers [`SurfaceIndex::distances_sq_near_vertices`]
    /// from each vertex's own faces: for a mesh many point sets are measured against,
    /// each point near a vertex of it (a full-resolution pose against its upsamplings
    /// and deformations). The build costs about one seeded query per vertex.
    pub fn with_vertex_rings(mesh: &TriMesh) -> Self {
        let mut index = Self::new(mesh);
        let faces = VertexFaces::new(mesh.vertex_count(), &mesh.faces);
        let scale = mesh.positions.iter().map(|p| p.abs().max()).fold(0.0, Real::max);
        let margin = 1e-12 * scale.max(Real::MIN_POSITIVE);
        let clearance: Vec<Real> = (0..mesh.vertex_count() as u32)
            .into_par_iter()
            .map(|v| {
                let ring = faces.of(v);
                if ring.is_empty() {
                    return 0.0;
                }
                let p = &mesh.positions[v as usize];
                let other = |f: u32| {
                    if ring.binary_search(&f).is_ok() { Real::INFINITY } else { index.distance_sq(p, f) }
                };
                // The search starts from a face of a neighbour that does not use `v`: it
                // bounds the answer to about an edge, which the grid proves in a few
                // cells (the tree's unseeded search cost a third more: 88 against 67 M
                // instructions for a SCAPE pose's 12500 vertices).
                let seed = ring
                    .iter()
                    .flat_map(|&f| mesh.faces[f as usize])
                    .filter(|&u| u != v)
                    .flat_map(|u| faces.of(u).iter().copied())
                    .find(|f| ring.binary_search(f).is_err())
                    .map(|f| (f, other(f)));
                match grid_then_tree(index.grid.as_ref(), &index.bvh, p, seed, true, other) {
                    Some((_, d)) if d.is_finite() => (d.sqrt() * (1.0 - 1e-9) - margin).max(0.0),
                    Some(_) | None => Real::INFINITY,
                }
            })
            .collect();
        index.rings = Some(VertexRings { faces, positions: mesh.positions.clone(), clearance });
        index
    }

    /// The index of `mesh`, which has as many faces as the indexed mesh (typically the
    /// same faces in another pose, or a deformation of them): this index's tree with
    /// every box recomputed, no build. Same answers as `SurfaceIndex::new(mesh)`, and as
    /// fast while `mesh` is near the indexed one. Panics on another face count.
    pub fn refit(&self, mesh: &TriMesh) -> Self {
        let triangles: Vec<[Vec3; 3]> = (0..mesh.face_count()).map(|f| mesh.corners(f)).collect();
        let boxes: Vec<Aabb> = triangles.iter().map(|t| Aabb::of_points(t)).collect();
        Self { bvh: self.bvh.refitted(&boxes), grid: surface_grid(&boxes), triangles, rings: None }
    }

    /// Squared distance from `p` to the surface, with the index of a nearest face (the
    /// lowest index among equally near faces); `None` when the surface has no faces.
    pub fn nearest(&self, p: &Vec3) -> Option<(u32, Real)> {
        self.bvh.nearest(p, |f| {
            let [a, b, c] = &self.triangles[f as usize];
            point_triangle_distance_sq(p, a, b, c)
        })
    }

    /// Squared distance from each of `points` to the surface, in `points`' order.
    pub fn distances_sq(&self, points: &[Vec3]) -> Vec<Real> {
        points.par_iter().map(|p| self.nearest(p).map_or(Real::INFINITY, |(_, d)| d)).collect()
    }

    /// [`SurfaceIndex::nearest`] from a guess: `seed` is a face likely near `p` (for a
    /// vertex of a mesh lying near the indexed one, a face of the corresponding vertex).
    /// The same answer whatever the seed (an out-of-range seed is no seed); a near seed
    /// makes it several times faster.
    pub fn nearest_seeded(&self, p: &Vec3, seed: u32) -> Option<(u32, Real)> {
        let best = ((seed as usize) < self.triangles.len()).then(|| (seed, self.distance_sq(p, seed)));
        self.nearest_from(p, best)
    }

    fn distance_sq(&self, p: &Vec3, f: u32) -> Real {
        let [a, b, c] = &self.triangles[f as usize];
        point_triangle_distance_sq(p, a, b, c)
    }

    /// The nearest face from `best`, a face and its exact distance: the grid, then the
    /// tree if the bound is too loose for the grid.
    fn nearest_from(&self, p: &Vec3, best: Option<(u32, Real)>) -> Option<(u32, Real)> {
        self.nearest_from_with(p, best, |f: u32| self.distance_sq(p, f))
    }

    /// [`SurfaceIndex::nearest_from`] with the exact distance given (one that answers
    /// +∞ for faces known not to beat `best`).
    fn nearest_from_with(
        &self,
        p: &Vec3,
        best: Option<(u32, Real)>,
        distance: impl Fn(u32) -> Real,
    ) -> Option<(u32, Real)> {
        grid_then_tree(self.grid.as_ref(), &self.bvh, p, best, true, distance)
    }

    /// [`SurfaceIndex::distances_sq`] with a seed per point (`seeds[i]` for `points[i]`,
    /// see [`SurfaceIndex::nearest_seeded`]): the same distances.
    pub fn distances_sq_seeded(&self, points: &[Vec3], seeds: &[u32]) -> Vec<Real> {
        assert_eq!(points.len(), seeds.len(), "one seed per point");
        points
            .par_iter()
            .zip(seeds)
            .map(|(p, &s)| {
                let best = ((s as usize) < self.triangles.len()).then(|| (s, self.distance_sq(p, s)));
                // A point on its seed face (a vertex the upsampler kept in place) is at
                // distance 0, which nothing beats: no search, the same distance.
                if best.is_some_and(|(_, d)| d == 0.0) {
                    return 0.0;
                }
                self.nearest_from(p, best).map_or(Real::INFINITY, |(_, d)| d)
            })
            .collect()
    }

    /// [`SurfaceIndex::distances_sq_seeded`] of points each lying near the indexed
    /// mesh's vertex of the same index (`points[i]` near vertex `i`; `vertex_faces` is
    /// [`vertex_faces`] of its faces): with [`SurfaceIndex::with_vertex_rings`], a
    /// point whose own vertex's faces are provably nearest is answered from them alone.
    /// The same distances.
    pub fn distances_sq_near_vertices(&self, points: &[Vec3], vertex_faces: &[u32]) -> Vec<Real> {
        let Some(rings) = self.rings.as_ref().filter(|r| r.positions.len() == points.len()) else {
            return self.distances_sq_seeded(points, vertex_faces);
        };
        points.par_iter().enumerate().map(|(v, p)| self.near_vertex(rings, v, p)).collect()
    }

    fn near_vertex(&self, rings: &VertexRings, v: usize, p: &Vec3) -> Real {
        let ring = rings.faces.of(v as u32);
        // Every other face is at least `clearance − δ` away; the bound is shrunk far
        // beyond the rounding of `δ`, so a face it rules out is strictly farther than
        // the ring's best and can neither win nor tie.
        let delta = (p - rings.positions[v]).norm();
        let bound = (rings.clearance[v] - delta) * (1.0 - 1e-9) - 1e-12 * p.abs().max();
        if bound <= 0.0 {
            // Nothing can be proved from the ring (a point farther from its vertex than
            // the vertex is from the other faces: most of a deformation's points), so
            // the ring's exact tests would only tighten the search's first bound, which
            // costs more than it saves: the search from the vertex's first face.
            let best = ring.first().map(|&f| (f, self.distance_sq(p, f)));
            return self.nearest_from(p, best).map_or(Real::INFINITY, |(_, d)| d);
        }
        let mut best: Option<(u32, Real)> = None;
        for &f in ring {
            let d = self.distance_sq(p, f);
            if best.is_none_or(|(g, e)| d < e || (d == e && f < g)) {
                best = Some((f, d));
            }
        }
        if let Some((_, d)) = best
            && d < bound * bound
        {
            return d;
        }
        // The search from the ring's best: a ring face can neither beat it nor tie with
        // a lower index, so none is tested again.
        let other =
            |f: u32| if ring.binary_search(&f).is_ok() { Real::INFINITY } else { self.distance_sq(p, f) };
        self.nearest_from_with(p, best, other).map_or(Real::INFINITY, |(_, d)| d)
    }
}

/// The nearest primitive from `best` (a primitive and its exact distance): the grid,
/// then the tree if the bound is too loose for the grid, or with no grid or no `best`
/// (see [`Grid::nearest`] for `has_boxes`).
fn grid_then_tree(
    grid: Option<&Grid>,
    bvh: &Bvh,
    p: &Vec3,
    best: Option<(u32, Real)>,
    has_boxes: bool,
    distance: impl Fn(u32) -> Real,
) -> Option<(u32, Real)> {
    let distance = &distance;
    let best = match (grid, best) {
        (Some(grid), Some(best)) => match grid.nearest(p, best, has_boxes, distance) {
            Ok(found) => return Some(found),
            // Too loose a bound for the grid: the tree goes on from what it found.
            Err(so_far) => Some(so_far),
        },
        _ => best,
    };
    bvh.nearest_from(p, best, distance)
}

/// The grid of a triangle surface: cells 1.5 times the mean triangle's largest box
/// side, so a seeded query near the surface visits one to a few cells of a few dozen
/// triangles (1, 2 and 3 times took 3 %, 4 % and 22 % more instructions on a SCAPE
/// pose, under cachegrind).
fn surface_grid(boxes: &[Aabb]) -> Option<Grid> {
    let mean_side = boxes.iter().map(|b| (b.hi - b.lo).max()).sum::<Real>() / boxes.len().max(1) as Real;
    Grid::build(boxes, 1.5 * mean_side)
}

/// For each of the `vertex_count` vertices, the lowest-index face of `faces` using it
/// (`u32::MAX` for a vertex no face uses): the seeds of queries that start at a vertex
/// of a mesh with these faces.
pub fn vertex_faces(faces: &[Face], vertex_count: usize) -> Vec<u32> {
    let mut seeds = vec![u32::MAX; vertex_count];
    for (f, face) in faces.iter().enumerate().rev() {
        for &v in face {
            if let Some(s) = seeds.get_mut(v as usize) {
                *s = f as u32;
            }
        }
    }
    seeds
}

/// A point cloud prepared for nearest-point queries.
#[derive(Debug, Clone)]
pub struct VertexIndex {
    points: Vec<Vec3>,
    bvh: Bvh,
    /// For seeded queries ([`VertexIndex::nearest_seeded`]); `None` without points.
    grid: Option<Grid>,
}

impl VertexIndex {
    pub fn new(points: &[Vec3]) -> Self {
        let boxes = point_boxes(points);
        Self { bvh: Bvh::build(&boxes), grid: point_grid(points, &boxes), points: points.to_vec() }
    }

    /// The index of `points`, as many as the indexed ones (typically the same points
    /// in another pose): this index's tree with every box recomputed, no build. Same
    /// answers as `VertexIndex::new(points)`, and as fast while the points keep their
    /// neighbours. Panics on another point count.
    pub fn refit(&self, points: &[Vec3]) -> Self {
        let boxes = point_boxes(points);
        Self { bvh: self.bvh.refitted(&boxes), grid: point_grid(points, &boxes), points: points.to_vec() }
    }

    /// [`VertexIndex::nearest`] from a guess: `seed` is a point likely near `p` (for a
    /// vertex of a mesh lying near the indexed points, the corresponding point). The same
    /// answer whatever the seed (an out-of-range seed is no seed).
    pub fn nearest_seeded(&self, p: &Vec3, seed: u32) -> Option<(u32, Real)> {
        let distance = |i: u32| (self.points[i as usize] - p).norm_squared();
        let best = ((seed as usize) < self.points.len()).then(|| (seed, distance(seed)));
        grid_then_tree(self.grid.as_ref(), &self.bvh, p, best, false, distance)
    }

    /// [`VertexIndex::distances_sq`] with a seed per point (`seeds[i]` for `points[i]`):
    /// the same distances.
    pub fn distances_sq_seeded(&self, points: &[Vec3], seeds: &[u32]) -> Vec<Real> {
        assert_eq!(points.len(), seeds.len(), "one seed per point");
        points
            .par_iter()
            .zip(seeds)
            .map(|(p, &s)| self.nearest_seeded(p, s).map_or(Real::INFINITY, |(_, d)| d))
            .collect()
    }

    /// The nearest indexed point to `p` as `(index, squared distance)`, lowest index among
    /// equally near points; `None` for an empty cloud.
    pub fn nearest(&self, p: &Vec3) -> Option<(u32, Real)> {
        self.bvh.nearest(p, |i| (self.points[i as usize] - p).norm_squared())
    }

    /// Squared distance from each of `points` to its nearest indexed point.
    pub fn distances_sq(&self, points: &[Vec3]) -> Vec<Real> {
        points.par_iter().map(|p| self.nearest(p).map_or(Real::INFINITY, |(_, d)| d)).collect()
    }
}

/// Each point as a box of its own.
fn point_boxes(points: &[Vec3]) -> Vec<Aabb> {
    points.iter().map(|p| Aabb { lo: *p, hi: *p }).collect()
}

/// The grid of a point cloud: cells of about the mean spacing of the points over their
/// box's volume.
fn point_grid(points: &[Vec3], boxes: &[Aabb]) -> Option<Grid> {
    let bounds = Aabb::of_points(points);
    let volume = (bounds.hi - bounds.lo).map(|e| e.max(Real::EPSILON)).product();
    let spacing = (volume / points.len().max(1) as Real).cbrt();
    Grid::build(boxes, spacing)
}

/// The two halves of v2f, each a mean of squared point-to-surface distances (m² for
/// SCAPE).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct V2fHalves {
    /// Mean over `a`'s vertices of the squared distance to `b`'s surface.
    pub a_to_b: Real,
    /// Mean over `b`'s vertices of the squared distance to `a`'s surface.
    pub b_to_a: Real,
    pub a_vertex_count: usize,
    pub b_vertex_count: usize,
}

impl V2fHalves {
    /// The symmetric v2f of Eq. 6: both sums over the total vertex count.
    pub fn combined(&self) -> Real {
        let (na, nb) = (self.a_vertex_count as Real, self.b_vertex_count as Real);
        // Means times counts are the sums; an empty half contributes nothing.
        let sum_a = if self.a_vertex_count == 0 { 0.0 } else { self.a_to_b * na };
        let sum_b = if self.b_vertex_count == 0 { 0.0 } else { self.b_to_a * nb };
        (sum_a + sum_b) / (na + nb)
    }
}

/// Paper Eq. 6, vertex-to-face error between `a` (e.g. the deformed mesh) and `b` (the
/// target):
/// `(Σ_{v ∈ V_a} d(v, S_b)² + Σ_{v ∈ V_b} d(v, S_a)²) / (|V_a| + |V_b|)`, in squared
/// input units (m² for SCAPE). Symmetric in `a` and `b`.
pub fn v2f(a: &TriMesh, b: &TriMesh) -> Real {
    v2f_halves(a, b).combined()
}

/// Both halves of [`v2f`] separately (each a mean over its own vertices).
pub fn v2f_halves(a: &TriMesh, b: &TriMesh) -> V2fHalves {
    v2f_halves_indexed(a, b, &SurfaceIndex::new(b))
}

/// [`v2f_halves`] with `b`'s surface index built by the caller, for a `b` measured
/// against many meshes (`b_surface` must index `b`).
pub fn v2f_halves_indexed(a: &TriMesh, b: &TriMesh, b_surface: &SurfaceIndex) -> V2fHalves {
    v2f_halves_both_indexed(a, &SurfaceIndex::new(a), b, b_surface)
}

/// [`v2f_halves`] with both surface indices built by the caller (`a_surface` must index
/// `a`, `b_surface` `b`; e.g. `a_surface = b_surface.refit(a)` for a deformation `a` of
/// `b`).
pub fn v2f_halves_both_indexed(
    a: &TriMesh,
    a_surface: &SurfaceIndex,
    b: &TriMesh,
    b_surface: &SurfaceIndex,
) -> V2fHalves {
    let a_to_b = b_surface.distances_sq(&a.positions);
    let b_to_a = a_surface.distances_sq(&b.positions);
    V2fHalves {
        a_to_b: mean(&a_to_b),
        b_to_a: mean(&b_to_a),
        a_vertex_count: a.vertex_count(),
        b_vertex_count: b.vertex_count(),
    }
}

/// [`v2f_halves_both_indexed`] of two meshes with the same faces and vertex count (`a` a
/// deformation or an upsampling of `b`, or the reverse), every query seeded by a face of
/// its own vertex: `vertex_faces` is [`vertex_faces`] of those faces. The same halves,
/// found several times faster when the meshes lie near each other.
pub fn v2f_halves_same_faces(
    a: &TriMesh,
    a_surface: &SurfaceIndex,
    b: &TriMesh,
    b_surface: &SurfaceIndex,
    vertex_faces: &[u32],
) -> V2fHalves {
    let a_to_b = b_surface.distances_sq_near_vertices(&a.positions, vertex_faces);
    let b_to_a = a_surface.distances_sq_near_vertices(&b.positions, vertex_faces);
    V2fHalves {
        a_to_b: mean(&a_to_b),
        b_to_a: mean(&b_to_a),
        a_vertex_count: a.vertex_count(),
        b_vertex_count: b.vertex_count(),
    }
}

/// Paper Eq. 7, vertex-to-vertex error: the mean over `a`'s vertices of the squared
/// distance to the nearest vertex of `b`, in squared input units (m² for SCAPE). Not
/// symmetric; `a` is the deformed mesh, `b` the target. Faces are ignored.
pub fn v2v(a: &TriMesh, b: &TriMesh) -> Real {
    mean(&VertexIndex::new(&b.positions).distances_sq(&a.positions))
}

/// Per-vertex errors of a deformed mesh against a target, in the deformed mesh's vertex
/// index space, squared input units (m² for SCAPE): the arrays behind the heat maps.
#[derive(Debug, Clone, PartialEq)]
pub struct VertexErrors {
    /// Squared distance of each deformed vertex to the target surface (its mean is the
    /// deformed → target half of v2f).
    pub to_surface: Vec<Real>,
    /// Squared distance of each deformed vertex to the nearest target vertex (its mean is
    /// v2v).
    pub to_vertex: Vec<Real>,
}

/// Per-vertex errors of `deformed` against `target`.
pub fn vertex_errors(deformed: &TriMesh, target: &TriMesh) -> VertexErrors {
    VertexErrors {
        to_surface: SurfaceIndex::new(target).distances_sq(&deformed.positions),
        to_vertex: VertexIndex::new(&target.positions).distances_sq(&deformed.positions),
    }
}

/// Arithmetic mean, summed in order (NaN for an empty slice).
pub fn mean(values: &[Real]) -> Real {
    values.iter().sum::<Real>() / values.len() as Real
}

#[cfg(test)]
mod tests {
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use super::*;

    /// Each vertex's clearance is the distance to the nearest face not using it, found by
    /// a search from a neighbour's face, bit for bit what a scan of every face gives:
    /// for a bumpy sheet, a second sheet close above it, and faces off on their own.
    #[test]
    fn clearances_are_those_of_a_scan_of_every_face() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let side = 12u32;
        let mut positions = Vec::new();
        let mut faces = Vec::new();
        for layer in 0..2 {
            let base = positions.len() as u32;
            for i in 0..side * side {
                let (x, y) = (f64::from(i % side), f64::from(i / side));
                positions.push(Vec3::new(x, y, 0.3 * f64::from(layer) + rng.gen_range(-0.2..0.2)) * 0.1);
            }
            for y in 0..side - 1 {
                for x in 0..side - 1 {
                    let v = base + y * side + x;
                    faces.push([v, v + 1, v + side]);
                    faces.push([v + 1, v + side + 1, v + side]);
                }
            }
        }
        let lone = positions.len() as u32;
        positions.extend([Vec3::new(5.0, 5.0, 5.0), Vec3::new(5.1, 5.0, 5.0), Vec3::new(5.0, 5.1, 5.0)]);
        faces.push([lone, lone + 1, lone + 2]);
        let mesh = TriMesh { positions, faces };
        let index = SurfaceIndex::with_vertex_rings(&mesh);
        let rings = index.rings.as_ref().expect("built with rings");
        let scale = mesh.positions.iter().map(|p| p.abs().max()).fold(0.0, Real::max);
        let margin = 1e-12 * scale;
        for (v, p) in mesh.positions.iter().enumerate() {
            let nearest = (0..mesh.face_count() as u32)
                .filter(|&f| !mesh.faces[f as usize].contains(&(v as u32)))
                .map(|f| index.distance_sq(p, f))
                .fold(Real::INFINITY, Real::min);
            let want = (nearest.sqrt() * (1.0 - 1e-9) - margin).max(0.0);
            assert_eq!(rings.clearance[v], want, "vertex {v}");
        }
    }
}
