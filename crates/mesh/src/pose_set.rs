//! `PoseSet`: N registered poses of one body — one shared triangle list, one position
//! array per pose, vertex `i` the same body point in every pose.

use std::borrow::Cow;

use crate::error::MeshError;
use crate::math::Vec3;
use crate::mesh::{Face, TriMesh};

/// A registered pose set. Construct it with [`PoseSet::try_new`], which enforces the
/// invariants below; the fields are public for reading and for stages that replace
/// whole arrays consistently.
///
/// **Invariants:** `names.len() == poses.len() >= 1`; every pose has the same vertex
/// count; every face index is in range; every coordinate is finite;
/// `template < poses.len()`; `groups`, when present, has one id per pose.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseSet {
    /// One name per pose (the file stem), in pose order.
    pub names: Vec<String>,
    /// Vertex positions per pose: `poses[pose][vertex]`.
    pub poses: Vec<Vec<Vec3>>,
    /// The triangle list shared by all poses.
    pub faces: Vec<Face>,
    /// Index of the template pose (the paper's "A" pose) in `poses`.
    pub template: usize,
    /// One group id per pose (a person, a shape of a body model, a capture), or `None`.
    /// Held-out figures hold out whole groups, so that no group of a test pose is ever
    /// seen in training ([`PoseSet::with_groups`]).
    pub groups: Option<Vec<u32>>,
}

impl PoseSet {
    /// Builds a pose set, checking every invariant. Errors name the offending pose and
    /// vertex or face.
    pub fn try_new(
        names: Vec<String>,
        poses: Vec<Vec<Vec3>>,
        faces: Vec<Face>,
        template: usize,
    ) -> Result<Self, MeshError> {
        if poses.is_empty() {
            return Err(MeshError::NoPoses);
        }
        assert_eq!(names.len(), poses.len(), "one name per pose");
        if template >= poses.len() {
            return Err(MeshError::TemplateOutOfRange { template, poses: poses.len() });
        }
        let expected = poses[template].len();
        if expected == 0 || faces.is_empty() {
            return Err(MeshError::Empty { vertices: expected, faces: faces.len() });
        }
        for (name, pose) in names.iter().zip(&poses) {
            if pose.len() != expected {
                return Err(MeshError::VertexCountMismatch {
                    pose: name.clone(),
                    template: names[template].clone(),
                    expected,
                    found: pose.len(),
                });
            }
            crate::validate::check_finite(pose, name)?;
        }
        crate::validate::check_face_indices(&faces, expected)?;
        Ok(Self { names, poses, faces, template, groups: None })
    }

    /// The same poses with one group id per pose (`None`: no groups).
    pub fn with_groups(self, groups: Option<Vec<u32>>) -> Result<Self, MeshError> {
        if let Some(g) = &groups
            && g.len() != self.pose_count()
        {
            return Err(MeshError::GroupCountMismatch { groups: g.len(), poses: self.pose_count() });
        }
        Ok(Self { groups, ..self })
    }

    /// How many distinct groups the poses fall in (`None` without groups).
    pub fn group_count(&self) -> Option<usize> {
        let groups = self.groups.as_ref()?;
        let mut ids = groups.clone();
        ids.sort_unstable();
        ids.dedup();
        Some(ids.len())
    }

    pub fn pose_count(&self) -> usize {
        self.poses.len()
    }

    pub fn vertex_count(&self) -> usize {
        self.poses[self.template].len()
    }

    pub fn face_count(&self) -> usize {
        self.faces.len()
    }

    /// The template's positions.
    pub fn template_positions(&self) -> &[Vec3] {
        &self.poses[self.template]
    }

    /// The poses `kept` (ascending indices, the template among them) as a pose set of
    /// their own, the template's index moved with it; `self` itself when `kept` is every
    /// pose (a copy only when some are left out).
    ///
    /// # Panics
    /// When `kept` leaves the template out or names a pose out of range.
    pub fn subset(&self, kept: &[usize]) -> Cow<'_, PoseSet> {
        if kept.len() == self.pose_count() {
            return Cow::Borrowed(self);
        }
        Cow::Owned(PoseSet {
            names: kept.iter().map(|&p| self.names[p].clone()).collect(),
            poses: kept.iter().map(|&p| self.poses[p].clone()).collect(),
            faces: self.faces.clone(),
            template: kept
                .iter()
                .position(|&p| p == self.template)
                .expect("the template is among the kept poses"),
            groups: self.groups.as_ref().map(|g| kept.iter().map(|&p| g[p]).collect()),
        })
    }

    /// The template as a standalone mesh (copies positions and faces).
    pub fn template_mesh(&self) -> TriMesh {
        self.pose_mesh(self.template)
    }

    /// Pose `pose` as a standalone mesh (copies positions and faces).
    pub fn pose_mesh(&self, pose: usize) -> TriMesh {
        TriMesh { positions: self.poses[pose].clone(), faces: self.faces.clone() }
    }

    /// Index of the pose named `name`, if any.
    pub fn pose_index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three poses of one triangle, pose `p` moved by `p` along x, the template third.
    fn three() -> PoseSet {
        let pose =
            |p: f64| vec![Vec3::new(p, 0.0, 0.0), Vec3::new(p + 1.0, 0.0, 0.0), Vec3::new(p, 1.0, 0.0)];
        let names = ["a", "b", "c"].map(String::from).to_vec();
        PoseSet::try_new(names, vec![pose(0.0), pose(1.0), pose(2.0)], vec![[0, 1, 2]], 2).unwrap()
    }

    /// A subset keeps the named poses in order and moves the template's index with
    /// them; every pose is the set itself, borrowed.
    #[test]
    fn a_subset_keeps_its_poses_and_finds_the_template_among_them() {
        let set = three();
        let sub = set.subset(&[0, 2]);
        assert!(matches!(sub, Cow::Owned(_)));
        assert_eq!(sub.names, ["a", "c"]);
        assert_eq!(sub.poses, [set.poses[0].clone(), set.poses[2].clone()]);
        assert_eq!(sub.template, 1);
        assert_eq!(sub.faces, set.faces);
        assert!(matches!(set.subset(&[0, 1, 2]), Cow::Borrowed(s) if std::ptr::eq(s, &set)));
    }

    /// Groups are one per pose, counted by distinct id, and move with a subset.
    #[test]
    fn groups_are_one_per_pose_and_follow_a_subset() {
        let err = three().with_groups(Some(vec![0, 1])).unwrap_err();
        assert_eq!(err, MeshError::GroupCountMismatch { groups: 2, poses: 3 });
        let set = three().with_groups(Some(vec![7, 3, 7])).unwrap();
        assert_eq!(set.group_count(), Some(2));
        assert_eq!(set.subset(&[1, 2]).groups, Some(vec![3, 7]));
        assert_eq!(three().group_count(), None);
    }
}
