//! Part labels from skinning weights: each vertex's dominant joint, merged along the
//! kinematic tree to about the number of parts asked for.
//!
//! The rule, deterministic:
//! 1. a vertex's dominant joint is the one with the largest weight, ties to the lower
//!    joint index (a vertex without weights goes to joint 0);
//! 2. every joint starts as its own part, rooted at itself;
//! 3. while there are more parts than `target_parts`, or any part other than the root's is
//!    empty, the smallest part other than the root's (fewest vertices; ties to the later
//!    root joint, so deeper joints merge first) merges into the part holding its root
//!    joint's parent;
//! 4. parts that hold vertices are numbered in the order of their root joints and named
//!    after them (`left_knee` holds the lower left leg once the ankle and foot merged in).

use desal_mesh::PartLabels;

use crate::model::BodyModel;

/// One part per group of joints, `target_parts` of them when the tree has that many
/// joints with vertices (fewer parts otherwise). `labels` are in the model's vertex
/// index space.
pub fn labels_from_weights(model: &BodyModel, target_parts: usize) -> PartLabels {
    let joint_count = model.joint_count();
    let dominant: Vec<usize> = (0..model.vertex_count())
        .map(|v| {
            model
                .weights
                .row(v)
                .fold((0, f64::NEG_INFINITY), |best, (j, w)| if w > best.1 { (j, w) } else { best })
                .0
        })
        .collect();

    // `part_of[joint]`: the root joint of the part the joint is in.
    let mut part_of: Vec<usize> = (0..joint_count).collect();
    let mut sizes = vec![0usize; joint_count];
    dominant.iter().for_each(|&j| sizes[j] += 1);
    let mut alive: Vec<bool> = vec![true; joint_count];
    loop {
        let count = alive.iter().filter(|&&a| a).count();
        let smallest =
            (1..joint_count).filter(|&j| alive[j]).min_by_key(|&j| (sizes[j], std::cmp::Reverse(j)));
        let Some(part) = smallest else { break };
        if count <= target_parts && sizes[part] > 0 {
            break;
        }
        let parent = model.parents[part].expect("only joint 0 has no parent");
        let into = part_of[parent];
        for p in part_of.iter_mut().filter(|p| **p == part) {
            *p = into;
        }
        sizes[into] += sizes[part];
        alive[part] = false;
    }

    let names = model.kind.joint_names();
    let kept: Vec<usize> = (0..joint_count).filter(|&j| alive[j] && sizes[j] > 0).collect();
    let mut id_of_root = vec![u32::MAX; joint_count];
    for (id, &root) in kept.iter().enumerate() {
        id_of_root[root] = id as u32;
    }
    let labels = dominant.iter().map(|&j| id_of_root[part_of[j]]).collect();
    let names = kept.iter().map(|&j| names.get(j).cloned().unwrap_or_else(|| format!("joint{j}"))).collect();
    PartLabels::try_new(labels, names).expect("every vertex's part holds it, so it is kept")
}
