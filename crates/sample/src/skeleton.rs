//! The rest skeleton and forward kinematics.
//!
//! Joint rest positions are the centroids of the base mesh's joint vertex groups (the
//! "joint cubes" a bone's head or tail names), or the mean of listed vertices, in the
//! OBJ's own frame and units. Bones are stored parents first (depth-first from the root,
//! children in name order), so one forward pass computes every world transform.
//!
//! Rotations are local to each bone and expressed in the rest frame: a bone's rotation
//! turns it (and, through the chain, its descendants) about its own head, and composes
//! after its parent's. In the rest pose every bone's frame is the OBJ frame, so "a turn
//! about X" means about the OBJ X axis as carried along by the parent chain.

use std::collections::BTreeMap;

use desal_mesh::Vec3;
use desal_mesh::math::{Mat3, UnitQuat};

use crate::error::SampleError;
use crate::source::{JointSpec, RigBone, SourceAssets};

/// One bone in the rest pose.
#[derive(Debug, Clone, PartialEq)]
pub struct Bone {
    pub name: String,
    /// Index of the parent in [`Skeleton::bones`]; `None` for the root. Always smaller
    /// than this bone's own index.
    pub parent: Option<usize>,
    /// Rest position of the head (the pivot of the bone's rotation), in OBJ units.
    pub head: Vec3,
    /// Rest position of the tail, in OBJ units.
    pub tail: Vec3,
}

/// A rest skeleton, bones ordered parents first. Bone 0 is the root.
#[derive(Debug, Clone, PartialEq)]
pub struct Skeleton {
    pub bones: Vec<Bone>,
}

/// A rigid motion `p ↦ rotation · p + translation` taking rest positions to posed ones.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoneTransform {
    pub rotation: Mat3,
    pub translation: Vec3,
}

impl BoneTransform {
    /// The identity: the exact identity matrix and a zero translation, so applying it
    /// returns the input bit for bit.
    pub fn identity() -> Self {
        Self { rotation: Mat3::identity(), translation: Vec3::zeros() }
    }

    #[inline]
    pub fn apply(&self, p: &Vec3) -> Vec3 {
        self.rotation * p + self.translation
    }

    /// This motion after `inner`: `self ∘ inner`.
    fn compose(&self, inner: &BoneTransform) -> BoneTransform {
        BoneTransform {
            rotation: self.rotation * inner.rotation,
            translation: self.rotation * inner.translation + self.translation,
        }
    }
}

impl Skeleton {
    /// Builds the rest skeleton of `assets.rig`, placing joints on `assets.base`.
    pub fn from_assets(assets: &SourceAssets) -> Result<Self, SampleError> {
        let order = parents_first_order(&assets.rig)?;
        let index: BTreeMap<&str, usize> = order.iter().enumerate().map(|(i, n)| (n.as_str(), i)).collect();
        let mut bones = Vec::with_capacity(order.len());
        for name in &order {
            let rig_bone: &RigBone = &assets.rig[name];
            let parent = (!rig_bone.parent.is_empty()).then(|| index[rig_bone.parent.as_str()]);
            bones.push(Bone {
                name: name.clone(),
                parent,
                head: joint_position(assets, name, &rig_bone.head)?,
                tail: joint_position(assets, name, &rig_bone.tail)?,
            });
        }
        Ok(Self { bones })
    }

    pub fn bone_count(&self) -> usize {
        self.bones.len()
    }

    /// Index of the bone called `name`.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.bones.iter().position(|b| b.name == name)
    }

    /// True when `bone` is `ancestor` or lies below it in the tree.
    pub fn is_in_subtree(&self, bone: usize, ancestor: usize) -> bool {
        let mut current = Some(bone);
        while let Some(b) = current {
            if b == ancestor {
                return true;
            }
            current = self.bones[b].parent;
        }
        false
    }

    /// Unit rest direction of `bone`, head to tail (zero when head and tail coincide).
    pub fn direction(&self, bone: usize) -> Vec3 {
        let b = &self.bones[bone];
        (b.tail - b.head).try_normalize(0.0).unwrap_or_else(Vec3::zeros)
    }

    /// World transforms of every bone for local rotations `local[bone]` (one per bone,
    /// in bone order). Bones whose rotation and ancestors' rotations are all the
    /// identity get exactly [`BoneTransform::identity`].
    pub fn forward_kinematics(&self, local: &[UnitQuat]) -> Vec<BoneTransform> {
        assert_eq!(local.len(), self.bones.len(), "one local rotation per bone");
        let mut world: Vec<BoneTransform> = Vec::with_capacity(self.bones.len());
        for (bone, rotation) in self.bones.iter().zip(local) {
            let about_head = rotation_about(bone.head, rotation);
            let transform = match bone.parent {
                // Parents come first, so the parent's world transform is already known.
                Some(p) => world[p].compose(&about_head),
                None => about_head,
            };
            world.push(transform);
        }
        world
    }
}

/// The rotation `rotation` about the point `pivot`: `p ↦ R (p − pivot) + pivot`, written
/// as `R p + (pivot − R pivot)` so that the identity gives an exactly zero translation.
fn rotation_about(pivot: Vec3, rotation: &UnitQuat) -> BoneTransform {
    if *rotation == UnitQuat::identity() {
        return BoneTransform::identity();
    }
    let r = rotation.to_rotation_matrix().into_inner();
    BoneTransform { rotation: r, translation: pivot - r * pivot }
}

/// Bone names in depth-first order from the single root, children in name order.
fn parents_first_order(rig: &BTreeMap<String, RigBone>) -> Result<Vec<String>, SampleError> {
    let mut children: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
    let mut roots = Vec::new();
    for (name, bone) in rig {
        if bone.parent.is_empty() {
            roots.push(name.as_str());
        } else if !rig.contains_key(&bone.parent) {
            return Err(SampleError::UnknownParent { bone: name.clone(), parent: bone.parent.clone() });
        } else {
            // `rig` iterates in name order, so each child list is sorted by name.
            children.entry(bone.parent.as_str()).or_default().push(name.as_str());
        }
    }
    let mut order = Vec::with_capacity(rig.len());
    let mut stack: Vec<&str> = roots.iter().rev().copied().collect();
    while let Some(name) = stack.pop() {
        order.push(name.to_owned());
        if let Some(kids) = children.get(name) {
            stack.extend(kids.iter().rev());
        }
    }
    if roots.len() != 1 || order.len() != rig.len() {
        return Err(SampleError::NotATree { roots: roots.len(), unreachable: rig.len() - order.len() });
    }
    Ok(order)
}

/// Rest position of a joint: the centroid of its vertex group, or the mean of its
/// listed vertices, on the base mesh.
fn joint_position(assets: &SourceAssets, bone: &str, joint: &JointSpec) -> Result<Vec3, SampleError> {
    let vertices = match joint {
        JointSpec::Group(group) => assets
            .group_vertices(group)
            .filter(|v| !v.is_empty())
            .ok_or_else(|| SampleError::MissingJointGroup { bone: bone.to_owned(), group: group.clone() })?,
        JointSpec::Mean(vertices) => vertices.clone(),
    };
    let positions = &assets.base.positions;
    let mut sum = Vec3::zeros();
    for &v in &vertices {
        let p = positions.get(v as usize).ok_or(SampleError::JointVertexOutOfRange {
            bone: bone.to_owned(),
            vertex: v,
            vertex_count: positions.len(),
        })?;
        sum += p;
    }
    Ok(sum / vertices.len() as f64)
}
