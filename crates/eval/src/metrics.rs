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

use desal_mesh::{Real, TriMesh, Vec3};
use rayon::prelude::*;

use crate::bvh::{Aabb, Bvh};
use crate::closest_point::point_triangle_distance_sq;

/// A triangle surface prepared for point-to-surface queries. Build it once per target
/// mesh and query it with many point sets (several methods, several poses).
#[derive(Debug, Clone)]
pub struct SurfaceIndex {
    triangles: Vec<[Vec3; 3]>,
    bvh: Bvh,
}

impl SurfaceIndex {
    /// Indexes every face of `mesh` (unreferenced vertices play no part).
    pub fn new(mesh: &TriMesh) -> Self {
        let triangles: Vec<[Vec3; 3]> = (0..mesh.face_count()).map(|f| mesh.corners(f)).collect();
        let boxes: Vec<Aabb> = triangles.iter().map(|t| Aabb::of_points(t)).collect();
        Self { bvh: Bvh::build(&boxes), triangles }
    }

    /// The index of `mesh`, which has as many faces as the indexed mesh (typically the
    /// same faces in another pose, or a deformation of them): this index's tree with
    /// every box recomputed, no build. Same answers as `SurfaceIndex::new(mesh)`, and as
    /// fast while `mesh` is near the indexed one. Panics on another face count.
    pub fn refit(&self, mesh: &TriMesh) -> Self {
        let triangles: Vec<[Vec3; 3]> = (0..mesh.face_count()).map(|f| mesh.corners(f)).collect();
        let boxes: Vec<Aabb> = triangles.iter().map(|t| Aabb::of_points(t)).collect();
        Self { bvh: self.bvh.refitted(&boxes), triangles }
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
}

/// A point cloud prepared for nearest-point queries.
#[derive(Debug, Clone)]
pub struct VertexIndex {
    points: Vec<Vec3>,
    bvh: Bvh,
}

impl VertexIndex {
    pub fn new(points: &[Vec3]) -> Self {
        let boxes: Vec<Aabb> = points.iter().map(|p| Aabb { lo: *p, hi: *p }).collect();
        Self { bvh: Bvh::build(&boxes), points: points.to_vec() }
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
