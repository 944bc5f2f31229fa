//! The articulated skeleton SCAPE's pose model regresses on, derived from part labels:
//! triangle parts, joints between adjacent parts, a parent/child direction per joint,
//! joint twists per pose, and the two joints nearest each triangle.
//!
//! Anguelov et al. 2005, "SCAPE: Shape Completion and Animation of People", §3: each
//! triangle belongs to one rigid part; its non-rigid pose deformation depends on the
//! relative rotations (twists) of the joints nearest to it.
//!
//! Rules (all deterministic):
//! - **Triangle part**: the majority part of its three vertices; when all three differ,
//!   the lowest part id.
//! - **Joints**: the unordered part pairs `{p, q}`, `p ≠ q`, joined by at least one mesh
//!   edge; listed in ascending `(min, max)` order. A joint's position is the centroid of
//!   its border vertices (the endpoints of those edges) in the template.
//! - **Direction**: parts are visited breadth-first from the root (the configured root
//!   part, else the part with the most vertices, ties to the lower id), neighbours in
//!   ascending id; parts the root cannot reach start new searches, largest first. A
//!   joint's parent is the endpoint with the smaller depth, ties to the lower id — so
//!   joints closing a cycle in the part graph are directed too.
//! - **Twist** of a joint in a pose: the axis–angle vector (radians) of
//!   `R_parentᵀ R_child`, which does not change when the whole body is rotated.
//! - **Nearest joints** of a triangle: the two joints whose positions are nearest its
//!   template centroid, ties to the lower joint index.

use std::collections::VecDeque;

use desal_mesh::{EdgeTopology, Face, Mat3, PartLabels, Real, Vec3};

/// A joint between two adjacent parts.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// The part closer to the root of the part tree.
    pub parent: u32,
    pub child: u32,
    /// Centroid of the border vertices in the template, input units.
    pub position: Vec3,
    /// Number of distinct border vertices (endpoints of edges joining the two parts).
    pub border_vertex_count: usize,
}

/// The skeleton of one mesh: joints plus the per-triangle assignments the model uses.
#[derive(Debug, Clone, PartialEq)]
pub struct Skeleton {
    /// Part id of each triangle, in the mesh's face index space.
    pub triangle_parts: Vec<u32>,
    /// Joints in ascending `(min part, max part)` order.
    pub joints: Vec<Joint>,
    /// The (up to) two joints nearest each triangle, indices into `joints`, nearest
    /// first; `None` when the mesh has fewer joints.
    pub triangle_joints: Vec<[Option<u32>; 2]>,
    /// The root part of the joint tree.
    pub root: u32,
}

impl Skeleton {
    /// Derives the skeleton of a mesh with template positions `template`, triangles
    /// `faces` and per-vertex `labels` (same vertex index space). `root` overrides the
    /// root part (default: the part with the most vertices).
    pub fn new(template: &[Vec3], faces: &[Face], labels: &PartLabels, root: Option<u32>) -> Self {
        debug_assert_eq!(template.len(), labels.labels.len());
        let triangle_parts = assign_triangle_parts(faces, &labels.labels);
        let borders = find_part_borders(faces, &labels.labels);
        let root = root.unwrap_or_else(|| largest_part(labels));
        let depth = part_depths(labels, &borders, root);
        let joints: Vec<Joint> = borders
            .iter()
            .map(|border| {
                let (p, q) = (border.parts[0], border.parts[1]);
                let p_is_parent = (depth[p as usize], p) < (depth[q as usize], q);
                let (parent, child) = if p_is_parent { (p, q) } else { (q, p) };
                let position = border.vertices.iter().map(|&v| template[v as usize]).sum::<Vec3>()
                    / border.vertices.len() as Real;
                Joint { parent, child, position, border_vertex_count: border.vertices.len() }
            })
            .collect();
        let triangle_joints = find_nearest_joints(template, faces, &joints);
        Self { triangle_parts, joints, triangle_joints, root }
    }

    /// Twist of every joint for one pose's part rotations `rotations[part]`: axis–angle
    /// vectors in radians, in joint order.
    pub fn twists(&self, rotations: &[Mat3]) -> Vec<Vec3> {
        self.joints
            .iter()
            .map(|j| axis_angle(&(rotations[j.parent as usize].transpose() * rotations[j.child as usize])))
            .collect()
    }
}

/// Axis–angle vector (unit axis times angle in radians, angle in `[0, π]`) of a rotation
/// matrix. The input is re-orthonormalised first, so a rotation carrying rounding error
/// still gives a faithful answer.
pub fn axis_angle(rotation: &Mat3) -> Vec3 {
    nalgebra::Rotation3::from_matrix(rotation).scaled_axis()
}

/// Majority part per triangle; all-different → lowest id.
fn assign_triangle_parts(faces: &[Face], labels: &[u32]) -> Vec<u32> {
    faces
        .iter()
        .map(|&[a, b, c]| {
            let (la, lb, lc) = (labels[a as usize], labels[b as usize], labels[c as usize]);
            if la == lb || la == lc {
                la
            } else if lb == lc {
                lb
            } else {
                la.min(lb).min(lc)
            }
        })
        .collect()
}

/// The border between two parts: its parts (ascending) and its vertices (ascending,
/// distinct).
struct PartBorder {
    parts: [u32; 2],
    vertices: Vec<u32>,
}

/// Every pair of parts joined by a mesh edge, with the endpoints of those edges.
fn find_part_borders(faces: &[Face], labels: &[u32]) -> Vec<PartBorder> {
    let mut crossings: Vec<([u32; 2], u32)> = Vec::new();
    for &[a, b] in &EdgeTopology::new(faces).edges {
        let (la, lb) = (labels[a as usize], labels[b as usize]);
        if la != lb {
            let parts = [la.min(lb), la.max(lb)];
            crossings.push((parts, a));
            crossings.push((parts, b));
        }
    }
    crossings.sort_unstable();
    crossings.dedup();
    let mut borders: Vec<PartBorder> = Vec::new();
    for (parts, v) in crossings {
        match borders.last_mut() {
            Some(last) if last.parts == parts => last.vertices.push(v),
            _ => borders.push(PartBorder { parts, vertices: vec![v] }),
        }
    }
    borders
}

/// The part with the most vertices, ties to the lower id.
fn largest_part(labels: &PartLabels) -> u32 {
    let sizes = part_sizes(labels);
    (0..sizes.len()).max_by(|&a, &b| sizes[a].cmp(&sizes[b]).then(b.cmp(&a))).unwrap_or(0) as u32
}

fn part_sizes(labels: &PartLabels) -> Vec<usize> {
    let mut sizes = vec![0usize; labels.part_count()];
    for &l in &labels.labels {
        sizes[l as usize] += 1;
    }
    sizes
}

/// Breadth-first depth of every part in the part graph, starting at `root`, then at the
/// largest unreached part, and so on (each new search restarts at depth 0).
fn part_depths(labels: &PartLabels, borders: &[PartBorder], root: u32) -> Vec<usize> {
    let part_count = labels.part_count().max(root as usize + 1);
    let mut neighbours = vec![Vec::new(); part_count];
    for b in borders {
        neighbours[b.parts[0] as usize].push(b.parts[1]);
        neighbours[b.parts[1] as usize].push(b.parts[0]);
    }
    for n in &mut neighbours {
        n.sort_unstable();
    }
    let mut sizes = part_sizes(labels);
    sizes.resize(part_count, 0);
    let mut starts: Vec<u32> = (0..part_count as u32).filter(|&p| p != root).collect();
    starts.sort_by(|&a, &b| sizes[b as usize].cmp(&sizes[a as usize]).then(a.cmp(&b)));
    starts.insert(0, root);

    let mut depth = vec![usize::MAX; part_count];
    for start in starts {
        if depth[start as usize] != usize::MAX {
            continue;
        }
        depth[start as usize] = 0;
        let mut queue = VecDeque::from([start]);
        while let Some(p) = queue.pop_front() {
            for &q in &neighbours[p as usize] {
                if depth[q as usize] == usize::MAX {
                    depth[q as usize] = depth[p as usize] + 1;
                    queue.push_back(q);
                }
            }
        }
    }
    depth
}

/// The two joints nearest each triangle's template centroid.
fn find_nearest_joints(template: &[Vec3], faces: &[Face], joints: &[Joint]) -> Vec<[Option<u32>; 2]> {
    faces
        .iter()
        .map(|&[a, b, c]| {
            let centroid = (template[a as usize] + template[b as usize] + template[c as usize]) / 3.0;
            let mut best: [Option<(Real, u32)>; 2] = [None, None];
            for (j, joint) in joints.iter().enumerate() {
                let candidate = ((joint.position - centroid).norm_squared(), j as u32);
                // Lexicographic (distance, index) order breaks ties by joint index.
                if best[0].is_none_or(|b| candidate < b) {
                    best[1] = best[0];
                    best[0] = Some(candidate);
                } else if best[1].is_none_or(|b| candidate < b) {
                    best[1] = Some(candidate);
                }
            }
            best.map(|b| b.map(|(_, j)| j))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of four triangles over vertices 0..6 labelled 0,0,1,1,2,2:
    ///
    /// ```text
    ///   1---3---5
    ///   | / | / |
    ///   0---2---4
    /// ```
    fn strip() -> (Vec<Vec3>, Vec<Face>, PartLabels) {
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(2.0, 1.0, 0.0),
        ];
        let faces = vec![[0, 2, 1], [1, 2, 3], [2, 4, 3], [3, 4, 5]];
        let labels = PartLabels::from_ids(vec![0, 0, 1, 1, 2, 2]);
        (positions, faces, labels)
    }

    #[test]
    fn triangle_part_is_the_majority_then_the_lowest_id() {
        let labels = [4, 4, 2, 7, 9, 3];
        assert_eq!(
            assign_triangle_parts(&[[0, 1, 2], [2, 3, 1], [5, 3, 4], [2, 5, 2]], &labels),
            vec![4, 2, 3, 2]
        );
    }

    /// Parts 0-1-2 in a chain: two joints at the column centroids x = 0.5 and x = 1.5;
    /// with root 0, 0 is the parent of 1 and 1 the parent of 2.
    #[test]
    fn chain_of_three_parts_has_two_directed_joints() {
        let (positions, faces, labels) = strip();
        let skel = Skeleton::new(&positions, &faces, &labels, Some(0));
        // Face 1 = vertices (1, 2, 3) with labels (0, 1, 1): majority 1.
        assert_eq!(skel.triangle_parts, vec![0, 1, 1, 2]);
        assert_eq!(skel.joints.len(), 2);
        assert_eq!((skel.joints[0].parent, skel.joints[0].child), (0, 1));
        assert_eq!((skel.joints[1].parent, skel.joints[1].child), (1, 2));
        assert_eq!(skel.joints[0].position, Vec3::new(0.5, 0.5, 0.0));
        assert_eq!(skel.joints[1].position, Vec3::new(1.5, 0.5, 0.0));
        // Triangle 0 (centroid x = 1/3) is nearest joint 0, then joint 1.
        assert_eq!(skel.triangle_joints[0], [Some(0), Some(1)]);
        assert_eq!(skel.triangle_joints[3], [Some(1), Some(0)]);
        // Rooted at part 2 the directions flip.
        let skel = Skeleton::new(&positions, &faces, &labels, Some(2));
        assert_eq!((skel.joints[0].parent, skel.joints[0].child), (1, 0));
        assert_eq!((skel.joints[1].parent, skel.joints[1].child), (2, 1));
    }

    /// Default root: the largest part (part 1 here, with three vertices).
    #[test]
    fn default_root_is_the_largest_part() {
        let (positions, faces, _) = strip();
        let labels = PartLabels::from_ids(vec![0, 1, 1, 1, 2, 2]);
        let skel = Skeleton::new(&positions, &faces, &labels, None);
        assert_eq!(skel.root, 1);
        assert!(skel.joints.iter().all(|j| j.parent == 1));
    }

    /// The twist is that of the child relative to the parent, and rotating the whole
    /// body leaves it unchanged.
    #[test]
    fn twist_is_relative_and_invariant_to_global_rotation() {
        let (positions, faces, labels) = strip();
        let skel = Skeleton::new(&positions, &faces, &labels, Some(0));
        let rot = |axis: Vec3, angle: f64| *nalgebra::Rotation3::from_scaled_axis(axis * angle).matrix();
        let bend = rot(Vec3::z(), 0.3);
        let rotations = [Mat3::identity(), bend, bend];
        let twists = skel.twists(&rotations);
        assert!((twists[0] - Vec3::new(0.0, 0.0, 0.3)).norm() < 1e-12);
        assert!(twists[1].norm() < 1e-12);
        let global = rot(Vec3::new(1.0, 2.0, 3.0).normalize(), 1.1);
        let turned: Vec<Mat3> = rotations.iter().map(|r| global * r).collect();
        let twists_turned = skel.twists(&turned);
        assert!((twists_turned[0] - twists[0]).norm() < 1e-12);
    }
}
