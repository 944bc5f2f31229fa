//! Lindstrom and Turk's memoryless collapse cost and placement (Lindstrom and Turk 1998,
//! "Fast and memory efficient polygonal simplification"; 1999, "Evaluation of
//! memoryless simplification"), following CGAL 5.5's `LindstromTurk_core` (weights
//! volume 0.5, boundary 0.5, shape 0; constraints kept when at least 1° apart).
//!
//! Everything is a quadratic function of the new position `x`, built from the faces
//! around the edge as they are *now*: the volume term sums `(Nₜ·x − Lₜ)²` over the
//! faces `t` incident to either endpoint (`Nₜ` their unnormalised normal, `Lₜ = Nₜ·p₀`:
//! six times the signed volume of the tetrahedron `x` sweeps with `t`), the boundary term
//! sums `|dₑ × (x − tₑ)|²` over the boundary edges `e` at either endpoint (four times the
//! squared area swept). The placement solves up to three linear constraints in order:
//! preserve the volume, preserve the boundary's area vector, minimise the cost, minimise
//! the squared distances to the link vertices.

use desal_mesh::{Mat3, Vec3};

use crate::classify::BOUNDARY;
use crate::face_lists::FaceLists;
use crate::quadric::Quadric;

/// Weight of the volume term in the cost (CGAL's default).
const VOLUME_WEIGHT: f64 = 0.5;
/// Weight of the boundary term, multiplied by the squared edge length (CGAL's default).
const BOUNDARY_WEIGHT: f64 = 0.5;
/// A constraint is used only when it is at least this far, in degrees, from the span
/// of the ones already chosen (Lindstrom–Turk's α-compatibility).
const ALPHA_DEG: f64 = 1.0;

/// The quadratic terms of one candidate collapse, accumulated from its neighbourhood.
#[derive(Debug, Default)]
pub(crate) struct Neighbourhood {
    /// `Σ (Nₜ·x − Lₜ)²` over the faces around the edge.
    volume: Quadric,
    /// `Σ Nₜ` and `Σ Lₜ`: the volume is preserved when `(Σ Nₜ)·x = Σ Lₜ`.
    normal_sum: Vec3,
    offset_sum: f64,
    /// `Σ |dₑ × (x − tₑ)|²` over the boundary edges at the endpoints.
    boundary: Quadric,
    /// `Σ dₑ` and `Σ tₑ × sₑ`: the boundary's area vector, for its preservation.
    direction_sum: Vec3,
    moment_sum: Vec3,
    boundary_edges: usize,
}

impl Neighbourhood {
    /// The neighbourhood of edge `(a, b)` as the mesh is now: the faces incident to `a`
    /// or `b` (each once) and the boundary edges at either (`flags` tells which slots are
    /// on the boundary; positions are by slot).
    pub(crate) fn gather(a: u32, b: u32, lists: &FaceLists, positions: &[Vec3], flags: &[u8]) -> Self {
        let mut n = Self::default();
        let p = |v: u32| &positions[v as usize];
        for (v, other) in [(a, b), (b, a)] {
            for &f in lists.of(v) {
                let face = lists.face(f);
                // Faces on the edge are in both lists: count them with `a`.
                if v == b && face.contains(&other) {
                    continue;
                }
                n.add_triangle(p(face[0]), p(face[1]), p(face[2]));
            }
        }
        for (v, other) in [(a, b), (b, a)] {
            if flags[v as usize] & BOUNDARY == 0 {
                continue;
            }
            for &f in lists.of(v) {
                let face = lists.face(f);
                let i = face.iter().position(|&x| x == v).expect("face of v");
                for (s, t) in [(face[i], face[(i + 1) % 3]), (face[(i + 2) % 3], face[i])] {
                    let x = if s == v { t } else { s };
                    if v == b && x == other {
                        continue;
                    }
                    let sharing = lists.of(v).iter().filter(|&&g| lists.face(g).contains(&x)).count();
                    if sharing == 1 {
                        n.add_boundary_edge(p(s), p(t));
                    }
                }
            }
        }
        n
    }

    /// Positions of the vertices adjacent to `a` or `b`, other than `a` and `b`, in
    /// index order: the shape term of [`Self::placement`].
    pub(crate) fn link_positions(a: u32, b: u32, lists: &FaceLists, positions: &[Vec3]) -> Vec<Vec3> {
        let mut link: Vec<u32> = [a, b]
            .iter()
            .flat_map(|&v| lists.of(v).iter().flat_map(|&f| lists.face(f)))
            .filter(|&x| x != a && x != b)
            .collect();
        link.sort_unstable();
        link.dedup();
        link.iter().map(|&x| positions[x as usize]).collect()
    }

    /// Adds face `(p0, p1, p2)` (in its orientation) incident to an endpoint.
    #[inline]
    pub(crate) fn add_triangle(&mut self, p0: &Vec3, p1: &Vec3, p2: &Vec3) {
        let n = (p1 - p0).cross(&(p2 - p0));
        let l = n.dot(p0);
        self.volume += &Quadric::from_plane(&n, -l, 1.0, 0.0);
        self.normal_sum += n;
        self.offset_sum += l;
    }

    /// Adds boundary edge `s → t` (in its face's orientation) at an endpoint.
    #[inline]
    pub(crate) fn add_boundary_edge(&mut self, s: &Vec3, t: &Vec3) {
        let d = t - s;
        self.boundary += &Quadric::from_line(t, &d);
        self.direction_sum += d;
        self.moment_sum += t.cross(s);
        self.boundary_edges += 1;
    }

    /// The cost of placing the merged vertex at `x`, for an edge of squared length
    /// `squared_length`: `½ Σ vol² + ½ l² Σ area²`.
    #[inline]
    pub(crate) fn cost(&self, x: &Vec3, squared_length: f64) -> f64 {
        let volume = self.volume.eval(x).max(0.0) / 36.0;
        let boundary =
            if self.boundary_edges > 0 { self.boundary.eval(x).max(0.0) / 4.0 * squared_length } else { 0.0 };
        VOLUME_WEIGHT * volume + BOUNDARY_WEIGHT * boundary
    }

    /// The Lindstrom–Turk placement, or `None` when even the link's centroid leaves a
    /// direction free (degenerate neighbourhood). `link` lists the positions of the
    /// vertices adjacent to either endpoint; it is called only when needed.
    pub(crate) fn placement(&self, squared_length: f64, link: impl FnOnce() -> Vec<Vec3>) -> Option<Vec3> {
        let mut constraints = Constraints::default();
        if self.boundary_edges > 0 {
            let e1 = self.direction_sum;
            let rows = line_rows(&e1);
            constraints.add_from_gradient(&rows, &e1.cross(&self.moment_sum));
        }
        if constraints.n < 3 {
            constraints.add_if_alpha_compatible(self.normal_sum, self.offset_sum);
        }
        if constraints.n < 3 {
            let combined = if self.boundary_edges > 0 {
                self.volume.scaled(VOLUME_WEIGHT)
                    + self.boundary.scaled(9.0 * BOUNDARY_WEIGHT * squared_length)
            } else {
                self.volume
            };
            let (rows, b) = combined.gradient_parts();
            constraints.add_from_gradient(&rows, &b);
        }
        if constraints.n < 3 {
            let points = link();
            let mut shape = Quadric::default();
            for p in &points {
                shape += &Quadric::from_point(p);
            }
            let (rows, b) = shape.gradient_parts();
            constraints.add_from_gradient(&rows, &b);
        }
        constraints.solve()
    }
}

/// The rows of `|u|² I − u uᵀ` (the quadratic part of `|u × x|²`).
fn line_rows(u: &Vec3) -> [Vec3; 3] {
    let l = u.norm_squared();
    [
        Vec3::new(l - u.x * u.x, -u.x * u.y, -u.x * u.z),
        Vec3::new(-u.x * u.y, l - u.y * u.y, -u.y * u.z),
        Vec3::new(-u.x * u.z, -u.y * u.z, l - u.z * u.z),
    ]
}

/// Up to three linear constraints `rows[i]·x = rhs[i]` (unit rows).
#[derive(Debug, Default)]
struct Constraints {
    rows: [Vec3; 3],
    rhs: [f64; 3],
    n: usize,
}

impl Constraints {
    /// Adds `a·x = b` unless `a` is zero or within α of the span of the rows so far.
    fn add_if_alpha_compatible(&mut self, a: Vec3, b: f64) {
        let la = a.norm_squared();
        if self.n >= 3 || !la.is_finite() || la == 0.0 || !b.is_finite() {
            return;
        }
        let alpha = ALPHA_DEG.to_radians();
        let compatible = match self.n {
            1 => {
                let r0 = self.rows[0];
                let d = r0.dot(&a);
                d * d <= r0.norm_squared() * la * alpha.cos().powi(2)
            }
            2 => {
                let normal = self.rows[0].cross(&self.rows[1]);
                let d = normal.dot(&a);
                d * d > normal.norm_squared() * la * alpha.sin().powi(2)
            }
            _ => true,
        };
        if compatible {
            let l = la.sqrt();
            self.rows[self.n] = a / l;
            self.rhs[self.n] = b / l;
            self.n += 1;
        }
    }

    /// Adds the constraints that minimise `½ xᵀHx + cᵀx` (gradient `Hx + c = 0`) in
    /// the directions the rows so far leave free.
    fn add_from_gradient(&mut self, h: &[Vec3; 3], c: &Vec3) {
        let apply = |q: &Vec3| Vec3::new(h[0].dot(q), h[1].dot(q), h[2].dot(q));
        match self.n {
            0 => {
                for i in 0..3 {
                    self.add_if_alpha_compatible(h[i], -c[i]);
                }
            }
            1 => {
                let a0 = self.rows[0];
                let abs = a0.abs();
                // A vector orthogonal to a0, built from its largest component.
                let q0 = if abs.x >= abs.y && abs.x >= abs.z {
                    Vec3::new(-a0.z / a0.x, 0.0, 1.0)
                } else if abs.y >= abs.z {
                    Vec3::new(0.0, -a0.z / a0.y, 1.0)
                } else {
                    Vec3::new(1.0, 0.0, -a0.x / a0.z)
                };
                let q1 = a0.cross(&q0);
                self.add_if_alpha_compatible(apply(&q0), -q0.dot(c));
                self.add_if_alpha_compatible(apply(&q1), -q1.dot(c));
            }
            2 => {
                let q = self.rows[0].cross(&self.rows[1]);
                self.add_if_alpha_compatible(apply(&q), -q.dot(c));
            }
            _ => {}
        }
    }

    /// The point satisfying all three constraints.
    fn solve(&self) -> Option<Vec3> {
        if self.n < 3 {
            return None;
        }
        let a =
            Mat3::from_rows(&[self.rows[0].transpose(), self.rows[1].transpose(), self.rows[2].transpose()]);
        let x = a.try_inverse()? * Vec3::new(self.rhs[0], self.rhs[1], self.rhs[2]);
        x.iter().all(|v| v.is_finite()).then_some(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Collapsing the centre of a flat closed fan: every face lies in z = 0, so volume
    /// preservation fixes z = 0, the volume cost is flat in the plane, and the shape term
    /// puts the vertex at the link's centroid.
    #[test]
    fn flat_fan_places_at_link_centroid_with_zero_cost() {
        let ring: Vec<Vec3> = (0..6)
            .map(|k| {
                let t = k as f64 * std::f64::consts::TAU / 6.0;
                Vec3::new(2.0 + t.cos(), t.sin(), 0.0)
            })
            .collect();
        let centre = Vec3::new(2.3, 0.1, 0.0);
        let mut n = Neighbourhood::default();
        for k in 0..6 {
            n.add_triangle(&centre, &ring[k], &ring[(k + 1) % 6]);
        }
        let x = n.placement(1.0, || ring.clone()).expect("the link pins the plane's free directions");
        assert!((x - Vec3::new(2.0, 0.0, 0.0)).norm() < 1e-12, "{x}");
        assert!(n.cost(&x, 1.0).abs() < 1e-20);
        // Lifting the vertex sweeps volume: cost 0.5 · Σ (|Nₜ| h)² / 36.
        let lifted = x + Vec3::new(0.0, 0.0, 0.5);
        let expected: f64 = (0..6)
            .map(|k| {
                let nt = (ring[k] - centre).cross(&(ring[(k + 1) % 6] - centre));
                (nt.norm() * 0.5).powi(2)
            })
            .sum::<f64>()
            * 0.5
            / 36.0;
        assert!((n.cost(&lifted, 1.0) - expected).abs() < 1e-12);
    }

    /// A vertex on a roof ridge: the volume-preserving placement stays on the roof's
    /// plane pair, with the swept volumes cancelling.
    #[test]
    fn placement_preserves_the_swept_volume() {
        // Apex of a pyramid over the unit square, collapsed: volume preservation puts
        // the new point on the plane (Σ N)·x = Σ L, which contains the old apex.
        let apex = Vec3::new(0.1, -0.2, 1.0);
        let base = [
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ];
        let mut n = Neighbourhood::default();
        for k in 0..4 {
            n.add_triangle(&apex, &base[k], &base[(k + 1) % 4]);
        }
        let x = n.placement(1.0, || base.to_vec()).expect("placement");
        let swept: f64 = (0..4)
            .map(|k| {
                let nt = (base[k] - apex).cross(&(base[(k + 1) % 4] - apex));
                nt.dot(&(x - apex))
            })
            .sum();
        assert!(swept.abs() < 1e-12, "net swept volume {swept}");
    }
}
