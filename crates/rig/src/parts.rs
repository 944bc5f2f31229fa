//! Part labels of a rig: each welded vertex goes to its heaviest joint, and joints with
//! too few vertices give theirs to the parent joint (bottom-up, so a chain of small
//! joints such as finger bones ends in the hand), so that every part can carry stage 1's
//! rigid fit. A root part that stays too small goes to its largest child part.
//!
//! The labels carry their parts' tree (each part's parent is the part of its joint's
//! nearest ancestor joint that has one), so that a part a simplification leaves without
//! three non-collinear vertices joins its parent instead of failing the fit
//! (`PartLabels::merge_unfittable_parts`, issue 42, item 8). A labels artifact stores no
//! tree: [`with_part_tree`] gives it back from the rig and the part names.

use desal_mesh::PartLabels;

use crate::model::{Influences, Rig};

/// Settings of [`dominant_joint_parts`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PartsConfig {
    /// Fewest vertices a part may have. Default 50.
    pub min_part_vertices: usize,
}

impl Default for PartsConfig {
    fn default() -> Self {
        Self { min_part_vertices: 50 }
    }
}

/// Labels of the welded vertices whose influences are `influences` (one row per welded
/// vertex): part ids `0..K` in joint order, named after their joint.
pub fn dominant_joint_parts(rig: &Rig, influences: &Influences, config: &PartsConfig) -> PartLabels {
    let joint_count = rig.skin.joints.len();
    let parents = rig.joint_parents();
    let dominant: Vec<usize> = (0..influences.vertex_count()).map(|v| influences.dominant_joint(v)).collect();
    let mut owner: Vec<usize> = (0..joint_count).collect();
    let mut count = vec![0usize; joint_count];
    for &j in &dominant {
        count[j] += 1;
    }
    // Children before parents: deepest joints first (depths found parents first, in
    // linear time, since a joint chain may be thousands deep).
    let mut depth = vec![0usize; joint_count];
    for j in Rig::parents_first(&parents) {
        depth[j] = parents[j].map_or(0, |p| depth[p] + 1);
    }
    let mut order: Vec<usize> = (0..joint_count).collect();
    order.sort_by_key(|&j| (std::cmp::Reverse(depth[j]), j));
    for &j in &order {
        if count[j] > 0
            && count[j] < config.min_part_vertices
            && let Some(p) = parents[j]
        {
            count[p] += count[j];
            count[j] = 0;
            owner[j] = p;
        }
    }
    // Resolve chains of merges to the joint that keeps its part.
    let resolve = |mut j: usize, owner: &[usize]| {
        while owner[j] != j {
            j = owner[j];
        }
        j
    };
    // A root left too small joins its largest remaining child part.
    for root in (0..joint_count).filter(|&j| parents[j].is_none()) {
        if count[root] > 0 && count[root] < config.min_part_vertices {
            let largest = (0..joint_count)
                .filter(|&c| {
                    c != root
                        && owner[c] == c
                        && count[c] > 0
                        && resolve(parents[c].unwrap_or(c), &owner) == root
                })
                .max_by_key(|&c| (count[c], std::cmp::Reverse(c)));
            if let Some(c) = largest {
                count[c] += count[root];
                count[root] = 0;
                owner[root] = c;
            }
        }
    }
    let keeps: Vec<usize> = (0..joint_count).filter(|&j| owner[j] == j && count[j] > 0).collect();
    let mut part_of_joint = vec![u32::MAX; joint_count];
    for (k, &j) in keeps.iter().enumerate() {
        part_of_joint[j] = k as u32;
    }
    let labels = dominant.iter().map(|&j| part_of_joint[resolve(j, &owner)]).collect();
    let names = keeps.iter().map(|&j| rig.joint_name(j)).collect();
    PartLabels::try_new(labels, names)
        .and_then(|l| l.with_parents(tree_of_joints(rig, &keeps)))
        .expect("every part id names a kept joint with vertices, and joints form a tree")
}

/// `labels` (a rig's dominant-joint parts, e.g. read back from a labels artifact) with
/// their tree: part `k` is the joint of the `k`-th part name, found in joint order (part
/// ids follow joint order, so the names are a subsequence of the joint names; with two
/// joints of one name the first unused one is taken). Labels whose names are not such a
/// subsequence come back without a tree, as a user's labels.
pub fn with_part_tree(rig: &Rig, labels: PartLabels) -> PartLabels {
    let mut joints = Vec::with_capacity(labels.part_count());
    let mut next = 0;
    for name in &labels.names {
        match (next..rig.skin.joints.len()).find(|&j| rig.joint_name(j) == *name) {
            Some(j) => {
                joints.push(j);
                next = j + 1;
            }
            None => return labels,
        }
    }
    let tree = tree_of_joints(rig, &joints);
    labels.clone().with_parents(tree).unwrap_or(labels)
}

/// The parent part of each part whose joint is `joints[k]`: the part of the nearest
/// ancestor joint that has one, `None` for a part with none above it.
fn tree_of_joints(rig: &Rig, joints: &[usize]) -> Vec<Option<u32>> {
    let parents = rig.joint_parents();
    let mut part_of_joint = vec![None; rig.skin.joints.len()];
    for (k, &j) in joints.iter().enumerate() {
        part_of_joint[j] = Some(k as u32);
    }
    joints
        .iter()
        .map(|&j| {
            let mut at = parents[j];
            // A joint chain has no cycle (`check_tree`), so the walk ends at a root.
            while let Some(a) = at {
                if let Some(part) = part_of_joint[a] {
                    return Some(part);
                }
                at = parents[a];
            }
            None
        })
        .collect()
}
