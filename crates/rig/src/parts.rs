//! Part labels of a rig: each welded vertex goes to its heaviest joint, and joints with
//! too few vertices give theirs to the parent joint (bottom-up, so a chain of small
//! joints such as finger bones ends in the hand), so that every part can carry stage 1's
//! rigid fit. A root part that stays too small goes to its largest child part.

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
    PartLabels::try_new(labels, names).expect("every part id names a kept joint with vertices")
}
