//! `PartLabels`: one body-part id per vertex, plus the parts' names.

use crate::error::MeshError;
use crate::math::Vec3;

/// Per-vertex body-part labels. Part ids are `0..names.len()`.
///
/// **Invariant** (after [`PartLabels::try_new`]): every label is `< names.len()`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PartLabels {
    /// Part id of each vertex, in the mesh's vertex index space.
    pub labels: Vec<u32>,
    /// Name of each part, indexed by part id.
    pub names: Vec<String>,
}

impl PartLabels {
    /// Builds labels, checking every id against `names`.
    pub fn try_new(labels: Vec<u32>, names: Vec<String>) -> Result<Self, MeshError> {
        if let Some((vertex, &part)) = labels.iter().enumerate().find(|&(_, &p)| p as usize >= names.len()) {
            return Err(MeshError::UnknownPart { vertex, part, part_count: names.len() });
        }
        Ok(Self { labels, names })
    }

    /// Labels whose names are generated (`part0`, `part1`, …) from the largest id, for
    /// label files that carry ids only.
    pub fn from_ids(labels: Vec<u32>) -> Self {
        let count = labels.iter().copied().max().map_or(0, |m| m as usize + 1);
        let names = (0..count).map(|k| format!("part{k}")).collect();
        Self { labels, names }
    }

    pub fn part_count(&self) -> usize {
        self.names.len()
    }

    pub fn vertex_count(&self) -> usize {
        self.labels.len()
    }

    /// Vertex indices of every part, `members[part]`, each list ascending.
    pub fn members(&self) -> Vec<Vec<u32>> {
        let mut members = vec![Vec::new(); self.names.len()];
        for (v, &p) in self.labels.iter().enumerate() {
            members[p as usize].push(v as u32);
        }
        members
    }

    /// Checks that the labels match a mesh of `vertex_count` vertices.
    pub fn check_vertex_count(&self, vertex_count: usize) -> Result<(), MeshError> {
        if self.labels.len() != vertex_count {
            return Err(MeshError::LabelCountMismatch { labels: self.labels.len(), vertices: vertex_count });
        }
        Ok(())
    }

    /// Checks that every part spans a plane in `positions` (at least three
    /// non-collinear vertices), so that a rigid fit per part is well posed.
    ///
    /// Collinearity is judged relative to the part's own extent: the part is degenerate
    /// when its second-largest principal spread is below `1e-9` of its largest.
    pub fn check_parts_fittable(&self, positions: &[Vec3]) -> Result<(), MeshError> {
        for (part, verts) in self.members().iter().enumerate() {
            if !spans_plane(verts, positions) {
                return Err(MeshError::DegeneratePart {
                    part: part as u32,
                    name: self.names[part].clone(),
                    vertices: verts.len(),
                });
            }
        }
        Ok(())
    }
}

/// True when the points `verts` (indices into `positions`) are not all collinear.
fn spans_plane(verts: &[u32], positions: &[Vec3]) -> bool {
    if verts.len() < 3 {
        return false;
    }
    let n = verts.len() as f64;
    let centroid = verts.iter().map(|&v| positions[v as usize]).sum::<Vec3>() / n;
    let mut cov = crate::math::Mat3::zeros();
    for &v in verts {
        let d = positions[v as usize] - centroid;
        cov += d * d.transpose();
    }
    let mut eig: Vec<f64> = cov.symmetric_eigenvalues().iter().copied().collect();
    eig.sort_by(|a, b| b.total_cmp(a));
    eig[0] > 0.0 && eig[1] > 1e-18 * eig[0]
}
