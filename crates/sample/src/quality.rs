//! Checks that a posed body is still a clean surface: how much triangles shrink or
//! grow, whether any turned inside out, and whether the surface passes through itself.
//!
//! Self-intersection is found edge against triangle (a triangle pair that crosses has
//! an edge of one piercing the other): every mesh edge is tested, Möller–Trumbore
//! style (Möller & Trumbore 1997, "Fast, minimum storage ray-triangle intersection"),
//! against the triangles near it in a uniform grid, skipping triangles that share a
//! vertex with the edge.

use std::collections::HashMap;

use desal_mesh::math::{Mat3, triangle_area, triangle_cross};
use desal_mesh::{EdgeTopology, Face, Vec3};

use crate::skeleton::BoneTransform;
use crate::skinning::SkinWeights;

/// How a posed mesh compares with the rest mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseQuality {
    /// Smallest and largest ratio of posed to rest triangle area.
    pub min_area_ratio: f64,
    pub max_area_ratio: f64,
    /// Faces whose posed normal points against the rest normal carried by the faces'
    /// blended bone rotations: turned inside out.
    pub inverted_faces: usize,
    /// Distinct (edge, triangle) pairs where an edge pierces a triangle it does not touch.
    pub self_intersections: usize,
}

/// Measures `posed` against `rest` (same vertex order, triangles `faces`), with the
/// weights and bone transforms that produced it.
pub fn measure_pose(
    rest: &[Vec3],
    posed: &[Vec3],
    faces: &[Face],
    weights: &SkinWeights,
    transforms: &[BoneTransform],
) -> PoseQuality {
    let (min_area_ratio, max_area_ratio) = area_ratio_range(rest, posed, faces);
    PoseQuality {
        min_area_ratio,
        max_area_ratio,
        inverted_faces: count_inverted_faces(rest, posed, faces, weights, transforms),
        self_intersections: count_self_intersections(posed, faces),
    }
}

/// `(min, max)` over faces of posed area / rest area; faces of zero rest area are
/// skipped.
pub fn area_ratio_range(rest: &[Vec3], posed: &[Vec3], faces: &[Face]) -> (f64, f64) {
    let corners = |p: &[Vec3], f: &Face| [p[f[0] as usize], p[f[1] as usize], p[f[2] as usize]];
    let mut range = (f64::INFINITY, f64::NEG_INFINITY);
    for f in faces {
        let [a, b, c] = corners(rest, f);
        let rest_area = triangle_area(&a, &b, &c);
        if rest_area > 0.0 {
            let [a, b, c] = corners(posed, f);
            let ratio = triangle_area(&a, &b, &c) / rest_area;
            range = (range.0.min(ratio), range.1.max(ratio));
        }
    }
    range
}

/// Faces whose posed normal has a non-positive dot product with the rest normal turned
/// by the average of its corners' blended bone rotations.
pub fn count_inverted_faces(
    rest: &[Vec3],
    posed: &[Vec3],
    faces: &[Face],
    weights: &SkinWeights,
    transforms: &[BoneTransform],
) -> usize {
    inverted_faces(rest, posed, faces, weights, transforms).len()
}

/// The faces counted by [`count_inverted_faces`], ascending.
pub fn inverted_faces(
    rest: &[Vec3],
    posed: &[Vec3],
    faces: &[Face],
    weights: &SkinWeights,
    transforms: &[BoneTransform],
) -> Vec<u32> {
    let blended_rotation = |v: usize| -> Mat3 {
        weights.of(v).map(|(bone, w)| transforms[bone].rotation * w).fold(Mat3::zeros(), |acc, m| acc + m)
    };
    (0..faces.len() as u32)
        .filter(|&f| {
            let [a, b, c] = faces[f as usize].map(|i| i as usize);
            let rest_normal = triangle_cross(&rest[a], &rest[b], &rest[c]);
            let carried = (blended_rotation(a) + blended_rotation(b) + blended_rotation(c)) * rest_normal;
            let posed_normal = triangle_cross(&posed[a], &posed[b], &posed[c]);
            rest_normal.norm() > 0.0 && posed_normal.dot(&carried) <= 0.0
        })
        .collect()
}

/// Distinct (edge, triangle) pairs of `faces` where the edge crosses the triangle and
/// shares no vertex with it.
pub fn count_self_intersections(positions: &[Vec3], faces: &[Face]) -> usize {
    self_intersections(positions, faces).len()
}

/// The (edge, face) pairs counted by [`count_self_intersections`], sorted.
pub fn self_intersections(positions: &[Vec3], faces: &[Face]) -> Vec<([u32; 2], u32)> {
    let edges = EdgeTopology::new(faces).edges;
    if edges.is_empty() {
        return Vec::new();
    }
    let cell = grid_cell_size(positions, &edges);
    let grid = bin_faces(positions, faces, cell);
    let mut hits: Vec<([u32; 2], u32)> = Vec::new();
    for (e, &[p, q]) in edges.iter().enumerate() {
        let (a, b) = (positions[p as usize], positions[q as usize]);
        for key in cells_of_box(&a.inf(&b), &a.sup(&b), cell) {
            let Some(candidates) = grid.get(&key) else { continue };
            for &f in candidates {
                let face = faces[f as usize];
                if face.contains(&p) || face.contains(&q) {
                    continue;
                }
                let [x, y, z] = face.map(|i| positions[i as usize]);
                if segment_crosses_triangle(&a, &b, &x, &y, &z) {
                    hits.push((edges[e], f));
                }
            }
        }
    }
    // A pair met in several cells counts once.
    hits.sort_unstable();
    hits.dedup();
    hits
}

/// Twice the mean edge length: cells hold a handful of triangles each.
fn grid_cell_size(positions: &[Vec3], edges: &[[u32; 2]]) -> f64 {
    let total: f64 = edges.iter().map(|&[p, q]| (positions[p as usize] - positions[q as usize]).norm()).sum();
    (2.0 * total / edges.len() as f64).max(f64::MIN_POSITIVE)
}

type CellKey = [i64; 3];

fn cell_of(p: &Vec3, cell: f64) -> CellKey {
    [(p.x / cell).floor() as i64, (p.y / cell).floor() as i64, (p.z / cell).floor() as i64]
}

fn cells_of_box(lo: &Vec3, hi: &Vec3, cell: f64) -> impl Iterator<Item = CellKey> {
    let (l, h) = (cell_of(lo, cell), cell_of(hi, cell));
    (l[0]..=h[0]).flat_map(move |i| (l[1]..=h[1]).flat_map(move |j| (l[2]..=h[2]).map(move |k| [i, j, k])))
}

/// Each face listed in every grid cell its bounding box overlaps. Only looked up by
/// key, never iterated, so the map's order cannot leak into results.
fn bin_faces(positions: &[Vec3], faces: &[Face], cell: f64) -> HashMap<CellKey, Vec<u32>> {
    let mut grid: HashMap<CellKey, Vec<u32>> = HashMap::new();
    for (f, face) in faces.iter().enumerate() {
        let [a, b, c] = face.map(|i| positions[i as usize]);
        for key in cells_of_box(&a.inf(&b).inf(&c), &a.sup(&b).sup(&c), cell) {
            grid.entry(key).or_default().push(f as u32);
        }
    }
    grid
}

/// True when segment `a`–`b` crosses triangle `(x, y, z)` at one point strictly inside
/// both (parallel and coplanar configurations count as not crossing).
pub fn segment_crosses_triangle(a: &Vec3, b: &Vec3, x: &Vec3, y: &Vec3, z: &Vec3) -> bool {
    let d = b - a;
    let (e1, e2) = (y - x, z - x);
    let h = d.cross(&e2);
    let det = e1.dot(&h);
    if det.abs() <= 1e-12 * d.norm_squared().max(e1.norm_squared()).max(e2.norm_squared()).powf(1.5) {
        return false;
    }
    let inv = 1.0 / det;
    let s = a - x;
    let u = inv * s.dot(&h);
    if u <= 0.0 || u >= 1.0 {
        return false;
    }
    let q = s.cross(&e1);
    let v = inv * d.dot(&q);
    if v <= 0.0 || u + v >= 1.0 {
        return false;
    }
    let t = inv * e2.dot(&q);
    t > 0.0 && t < 1.0
}
