//! Where a method spends its vertex budget — the claim of the paper's Figs. 4–5: the
//! saliency-weighted cost keeps small faces where the body bends (joints) and lets
//! faces grow on rigid, detailed parts (head, hands, feet), where QSlim does the
//! opposite.
//!
//! Regions, decided on the full-resolution template:
//! - **joints**: within [`JOINT_RADIUS`] × the template's bounding-box diagonal of a
//!   part-border vertex (a vertex with an edge to another part): the bands where
//!   SCAPE's parts meet and the body bends;
//! - **head/hands/feet**: otherwise, a part whose name contains `head`, `hand`, `foot`
//!   or `feet` (SCAPE's and the sample's names). Labels whose names name none of these
//!   (ids only, or discovered parts) have no such region: the table is joints vs other;
//! - **other**: the rest (limb shafts, torso).
//!
//! A simplified face belongs to the region of its template centroid (joints) or of its
//! majority part (the model's rule, ties to the lowest id); a vertex to that of its
//! position or its part.

use desal_measures::VertexIndex;
use desal_mesh::{EdgeTopology, PartLabels, TriMesh, Vec3};
use serde::Serialize;

/// Half-width of a joint band, as a fraction of the template's bounding-box diagonal
/// (SCAPE: 2.5 % of 2.1 m ≈ 5 cm, about a limb's radius).
pub const JOINT_RADIUS: f64 = 0.025;

/// Region names, in table order.
pub const REGIONS: [&str; 3] = ["joints", "head/hands/feet", "other"];

/// The classifier, built once from the full-resolution template.
#[derive(Debug)]
pub struct Regions {
    border: VertexIndex,
    /// Squared band half-width, in squared input units.
    radius_sq: f64,
    /// Per part id: is it the head, a hand or a foot?
    extremity: Vec<bool>,
    /// Whether any part is (the extremities region exists).
    has_extremities: bool,
    /// The band half-width, input units (for the report).
    pub radius: f64,
}

/// Faces, vertices and face areas of one region of one simplified template.
#[derive(Debug, Clone, Serialize)]
pub struct RegionStats {
    pub region: &'static str,
    pub faces: usize,
    pub vertices: usize,
    /// Share of the simplified template's vertices in this region, percent.
    pub vertex_percent: f64,
    /// Mean face area, squared input units (NaN without faces).
    pub mean_face_area: f64,
    /// Total face area, squared input units.
    pub total_area: f64,
}

impl Regions {
    pub fn new(template: &TriMesh, labels: &PartLabels) -> Self {
        let topology = EdgeTopology::new(&template.faces);
        let mut on_border = vec![false; template.vertex_count()];
        for &[a, b] in &topology.edges {
            if labels.labels[a as usize] != labels.labels[b as usize] {
                on_border[a as usize] = true;
                on_border[b as usize] = true;
            }
        }
        let border: Vec<Vec3> =
            template.positions.iter().zip(&on_border).filter(|(_, b)| **b).map(|(p, _)| *p).collect();
        let extremity: Vec<bool> = labels
            .names
            .iter()
            .map(|n| {
                let n = n.to_ascii_lowercase();
                ["head", "hand", "foot", "feet"].iter().any(|k| n.contains(k))
            })
            .collect();
        let radius = JOINT_RADIUS * template.diagonal();
        let has_extremities = extremity.iter().any(|&e| e);
        Self {
            border: VertexIndex::new(&border),
            radius_sq: radius * radius,
            extremity,
            has_extremities,
            radius,
        }
    }

    /// Region index (into [`REGIONS`]) of a point of part `part`.
    fn classify(&self, point: &Vec3, part: u32) -> usize {
        if self.border.nearest(point).is_some_and(|(_, d)| d <= self.radius_sq) {
            0
        } else if self.extremity[part as usize] {
            1
        } else {
            2
        }
    }

    /// The regions in table order: all three, or joints and other when no part is an
    /// extremity (indices into [`REGIONS`]).
    pub fn present(&self) -> Vec<usize> {
        if self.has_extremities { vec![0, 1, 2] } else { vec![0, 2] }
    }

    /// Per-region statistics of a simplified template `mesh` with per-vertex `labels`,
    /// one row per region of [`Regions::present`].
    pub fn stats(&self, mesh: &TriMesh, labels: &PartLabels) -> Vec<RegionStats> {
        let mut faces = [0usize; 3];
        let mut areas = [0.0f64; 3];
        for (f, &[a, b, c]) in mesh.faces.iter().enumerate() {
            let centroid = mesh.corners(f).iter().sum::<Vec3>() / 3.0;
            let part = majority_part(
                labels.labels[a as usize],
                labels.labels[b as usize],
                labels.labels[c as usize],
            );
            let region = self.classify(&centroid, part);
            faces[region] += 1;
            areas[region] += mesh.face_area(f);
        }
        let mut vertices = [0usize; 3];
        for (p, &part) in mesh.positions.iter().zip(&labels.labels) {
            vertices[self.classify(p, part)] += 1;
        }
        self.present()
            .into_iter()
            .map(|r| RegionStats {
                region: REGIONS[r],
                faces: faces[r],
                vertices: vertices[r],
                vertex_percent: 100.0 * vertices[r] as f64 / mesh.vertex_count().max(1) as f64,
                mean_face_area: areas[r] / faces[r] as f64,
                total_area: areas[r],
            })
            .collect()
    }
}

/// The majority of three part ids; all different → the lowest (the model's rule).
fn majority_part(a: u32, b: u32, c: u32) -> u32 {
    if a == b || a == c {
        a
    } else if b == c {
        b
    } else {
        a.min(b).min(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of two squares along x: part "leftHand" (x = 0) and part "arm" (x = 1, 2).
    /// The border vertices are those with an edge across: 0, 1, 3, 4. The diagonal is
    /// about 2.2, so the band is ±0.056 around those vertices and no face centroid lies
    /// in it: faces go by majority part.
    #[test]
    fn faces_near_the_border_are_joints_and_the_rest_go_by_part() {
        let v = |x: f64, y: f64| Vec3::new(x, y, 0.0);
        let mesh = TriMesh {
            positions: vec![v(0.0, 0.0), v(1.0, 0.0), v(2.0, 0.0), v(0.0, 1.0), v(1.0, 1.0), v(2.0, 1.0)],
            faces: vec![[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]],
        };
        let labels = PartLabels {
            labels: vec![0, 1, 1, 0, 1, 1],
            names: vec!["leftHand".into(), "arm".into()],
            parents: None,
        };
        let regions = Regions::new(&mesh, &labels);
        assert_eq!(regions.classify(&v(1.02, 0.01), 1), 0);
        assert_eq!(regions.classify(&v(0.2, 0.5), 0), 1);
        assert_eq!(regions.classify(&v(1.8, 0.5), 1), 2);
        let stats = regions.stats(&mesh, &labels);
        assert_eq!(stats.iter().map(|s| s.vertices).collect::<Vec<_>>(), vec![4, 0, 2]);
        // Face [0, 4, 3] is mostly hand; the other three are mostly arm.
        assert_eq!(stats.iter().map(|s| s.faces).collect::<Vec<_>>(), vec![0, 1, 3]);
        assert!((stats.iter().map(|s| s.total_area).sum::<f64>() - 2.0).abs() < 1e-12);
    }

    /// Labels without extremity names (ids only: `part0`, `part1`) give joints and other
    /// only, with every face and vertex counted and no empty row.
    #[test]
    fn unnamed_parts_give_joints_and_other_only() {
        let v = |x: f64, y: f64| Vec3::new(x, y, 0.0);
        let mesh = TriMesh {
            positions: vec![v(0.0, 0.0), v(1.0, 0.0), v(2.0, 0.0), v(0.0, 1.0), v(1.0, 1.0), v(2.0, 1.0)],
            faces: vec![[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]],
        };
        let labels = PartLabels::from_ids(vec![0, 1, 1, 0, 1, 1]);
        let stats = Regions::new(&mesh, &labels).stats(&mesh, &labels);
        assert_eq!(stats.iter().map(|s| s.region).collect::<Vec<_>>(), vec!["joints", "other"]);
        assert_eq!(stats.iter().map(|s| s.vertices).sum::<usize>(), 6);
        assert_eq!(stats.iter().map(|s| s.faces).sum::<usize>(), 4);
        assert!(stats.iter().all(|s| s.faces == 0 || s.mean_face_area.is_finite()));
    }
}
