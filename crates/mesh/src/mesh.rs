//! `TriMesh`: an indexed triangle mesh with `f64` positions.

use crate::error::MeshError;
use crate::math::{Real, Vec3, bounding_box, triangle_area, triangle_cross};

/// A triangle: three vertex indices, counter-clockwise seen from outside.
pub type Face = [u32; 3];

/// An indexed triangle mesh. `faces` index into `positions`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TriMesh {
    pub positions: Vec<Vec3>,
    pub faces: Vec<Face>,
}

impl TriMesh {
    /// Builds a mesh, checking that every face index is in range and every coordinate is
    /// finite. `name` is used in error messages (a pose name or file stem).
    pub fn try_new(positions: Vec<Vec3>, faces: Vec<Face>, name: &str) -> Result<Self, MeshError> {
        crate::validate::check_finite(&positions, name)?;
        crate::validate::check_face_indices(&faces, positions.len())?;
        Ok(Self { positions, faces })
    }

    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    pub fn face_count(&self) -> usize {
        self.faces.len()
    }

    /// The three corner positions of face `f`.
    #[inline]
    pub fn corners(&self, f: usize) -> [Vec3; 3] {
        let [a, b, c] = self.faces[f];
        [self.positions[a as usize], self.positions[b as usize], self.positions[c as usize]]
    }

    /// Unit normal of face `f` (zero for a degenerate face).
    pub fn face_normal(&self, f: usize) -> Vec3 {
        let [a, b, c] = self.corners(f);
        triangle_cross(&a, &b, &c).try_normalize(0.0).unwrap_or_else(Vec3::zeros)
    }

    /// Area of face `f`, in squared input units.
    pub fn face_area(&self, f: usize) -> Real {
        let [a, b, c] = self.corners(f);
        triangle_area(&a, &b, &c)
    }

    /// Total surface area.
    pub fn area(&self) -> Real {
        (0..self.faces.len()).map(|f| self.face_area(f)).sum()
    }

    /// Axis-aligned bounding box `(min, max)`; `None` for an empty mesh.
    pub fn bounding_box(&self) -> Option<(Vec3, Vec3)> {
        bounding_box(&self.positions)
    }

    /// Length of the bounding-box diagonal (0 for an empty mesh). Relative errors in
    /// reports are given as fractions of this length.
    pub fn diagonal(&self) -> Real {
        self.bounding_box().map_or(0.0, |(lo, hi)| (hi - lo).norm())
    }

    /// Mean and population variance of the unique edge lengths (the paper's Fig. 3), in
    /// mesh units and squared mesh units; `(0, 0)` without edges. The one definition:
    /// stage 3's report and `desal eval` both use it.
    pub fn edge_length_stats(&self) -> (Real, Real) {
        edge_length_stats(&self.positions, &self.faces)
    }

    /// Area-weighted vertex normals (unit length; zero for isolated vertices).
    pub fn vertex_normals(&self) -> Vec<Vec3> {
        let mut normals = vec![Vec3::zeros(); self.positions.len()];
        for &[a, b, c] in &self.faces {
            let n = triangle_cross(
                &self.positions[a as usize],
                &self.positions[b as usize],
                &self.positions[c as usize],
            );
            for v in [a, b, c] {
                normals[v as usize] += n;
            }
        }
        for n in &mut normals {
            *n = n.try_normalize(0.0).unwrap_or_else(Vec3::zeros);
        }
        normals
    }
}

/// Mean and population variance of the lengths of the unique edges of `faces` over
/// `positions` (see [`TriMesh::edge_length_stats`]).
pub fn edge_length_stats(positions: &[Vec3], faces: &[Face]) -> (Real, Real) {
    let mut stats = LengthStats::default();
    for &[a, b] in &crate::EdgeTopology::new(faces).edges {
        stats.add((positions[a as usize] - positions[b as usize]).norm());
    }
    stats.mean_variance()
}

/// Running sums of lengths, for [`edge_length_stats`] and for callers that walk the
/// unique edges themselves (stage 3's report, from its own adjacency): lengths added in
/// the same order give the same figures, bit for bit.
#[derive(Debug, Clone, Copy, Default)]
pub struct LengthStats {
    count: usize,
    sum: Real,
    sum_sq: Real,
}

impl LengthStats {
    pub fn add(&mut self, length: Real) {
        self.count += 1;
        (self.sum, self.sum_sq) = (self.sum + length, self.sum_sq + length * length);
    }

    /// Mean and population variance of the lengths added; `(0, 0)` without any.
    pub fn mean_variance(&self) -> (Real, Real) {
        if self.count == 0 {
            return (0.0, 0.0);
        }
        let mean = self.sum / self.count as Real;
        (mean, (self.sum_sq / self.count as Real - mean * mean).max(0.0))
    }
}
