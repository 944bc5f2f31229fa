//! K-fold splits over poses for held-out evaluation of the deformation model, and the
//! check of a model's training poses.

use desal_mesh::PoseSet;

use crate::error::EvalError;

/// Splits the non-template poses of a `pose_count`-pose set into `k` test folds.
///
/// Returns, per fold, the ascending pose indices to *test* on; train on every other pose
/// ([`training_poses`]). The non-template poses are dealt round-robin in index order
/// (the `i`-th non-template pose goes to fold `i mod k`), so consecutive poses — often
/// similar in a capture sequence — land in different folds; fold sizes differ by at most
/// one. The template is never a test pose (the model is always trained on it).
///
/// `k` is clamped to `1..=pose_count - 1` so that no fold is empty; a pose set with only
/// the template yields no folds.
pub fn folds(pose_count: usize, template: usize, k: usize) -> Vec<Vec<usize>> {
    let others: Vec<usize> = (0..pose_count).filter(|&p| p != template).collect();
    if others.is_empty() {
        return Vec::new();
    }
    let k = k.clamp(1, others.len());
    let mut folds = vec![Vec::new(); k];
    for (i, pose) in others.into_iter().enumerate() {
        folds[i % k].push(pose);
    }
    folds
}

/// Splits whole groups into `k` test folds: the groups other than the template's, in
/// order of first appearance, are dealt round-robin (the `i`-th group to fold
/// `i mod k`), and a fold tests every pose of its groups. The template's group is never
/// tested (the model is always trained on it), so no pose of a test group is ever in its
/// fold's training poses. `k` is clamped to `1..=groups - 1`; a pose set whose poses are
/// all in the template's group yields no folds.
///
/// # Panics
/// When `groups` does not have one id per pose or `template` is out of range.
pub fn group_folds(groups: &[u32], template: usize, k: usize) -> Vec<Vec<usize>> {
    let trained = groups[template];
    let mut order: Vec<u32> = Vec::new();
    for &g in groups {
        if g != trained && !order.contains(&g) {
            order.push(g);
        }
    }
    if order.is_empty() {
        return Vec::new();
    }
    let k = k.clamp(1, order.len());
    let mut folds = vec![Vec::new(); k];
    for (pose, g) in groups.iter().enumerate() {
        if let Some(i) = order.iter().position(|o| o == g) {
            folds[i % k].push(pose);
        }
    }
    folds
}

/// The test folds of `set`: over whole groups when it has groups ([`group_folds`]),
/// over single poses otherwise ([`folds`]).
pub fn pose_set_folds(set: &PoseSet, k: usize) -> Vec<Vec<usize>> {
    match &set.groups {
        Some(groups) => group_folds(groups, set.template, k),
        None => folds(set.pose_count(), set.template, k),
    }
}

/// Every pose some fold tests, ascending: the poses a held-out evaluation reports (all
/// but the template, or with groups all but the template's group).
pub fn tested_poses(folds: &[Vec<usize>]) -> Vec<usize> {
    let mut tested = folds.concat();
    tested.sort_unstable();
    tested
}

/// The complement of `test` in `0..pose_count`, ascending: the training poses of a fold.
pub fn training_poses(pose_count: usize, test: &[usize]) -> Vec<usize> {
    let mut is_test = vec![false; pose_count];
    for &p in test {
        is_test[p] = true;
    }
    (0..pose_count).filter(|&p| !is_test[p]).collect()
}

/// Checks a model's training poses against a `pose_count`-pose set: at least one,
/// each in range, none twice (it would silently weigh double).
pub(crate) fn check_training_poses(pose_count: usize, training_poses: &[usize]) -> Result<(), EvalError> {
    if training_poses.is_empty() {
        return Err(EvalError::NoTrainingPoses);
    }
    let mut seen = vec![false; pose_count];
    for &pose in training_poses {
        if pose >= pose_count {
            return Err(EvalError::TrainingPoseOutOfRange { pose, pose_count });
        }
        if std::mem::replace(&mut seen[pose], true) {
            return Err(EvalError::DuplicateTrainingPose { pose });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// 71 SCAPE-like poses into 5 folds: sizes 14 or 15, template 0 absent.
    #[test]
    fn scape_sized_split() {
        let f = folds(71, 0, 5);
        assert_eq!(f.iter().map(Vec::len).collect::<Vec<_>>(), vec![14, 14, 14, 14, 14]);
        assert_eq!(f[0][..3], [1, 6, 11]);
        assert_eq!(training_poses(6, &[1, 4]), vec![0, 2, 3, 5]);
    }

    #[test]
    fn only_the_template_gives_no_folds() {
        assert!(folds(1, 0, 5).is_empty());
    }

    proptest! {
        /// Folds never hold the template, are disjoint, cover every other pose, and
        /// their training sets never contain a test pose.
        #[test]
        fn folds_partition_the_non_template_poses(pose_count in 1usize..40, t in 0usize..40, k in 0usize..12) {
            let template = t % pose_count;
            let f = folds(pose_count, template, k);
            let mut seen = vec![0u32; pose_count];
            for fold in &f {
                prop_assert!(!fold.is_empty());
                prop_assert!(!fold.contains(&template));
                let train = training_poses(pose_count, fold);
                prop_assert!(train.contains(&template));
                prop_assert!(fold.iter().all(|p| !train.contains(p)));
                for &p in fold {
                    seen[p] += 1;
                }
            }
            for (p, &n) in seen.iter().enumerate() {
                prop_assert_eq!(n, u32::from(p != template));
            }
        }
    }
}

#[cfg(test)]
mod group_tests {
    use super::*;

    /// No group is ever in both a fold's test poses and its training poses, the
    /// template's group always trains, and every other pose is tested exactly once.
    #[test]
    fn no_group_is_in_both_training_and_test() {
        let groups = [0, 3, 3, 1, 0, 2, 1, 4, 4, 2, 3, 5];
        for k in 1..8 {
            let folds = group_folds(&groups, 0, k);
            assert_eq!(folds.len(), k.min(5), "k = {k}: five groups besides the template's");
            let mut tested = vec![0; groups.len()];
            for test in &folds {
                let train = training_poses(groups.len(), test);
                for &t in test {
                    tested[t] += 1;
                    assert!(
                        train.iter().all(|&p| groups[p] != groups[t]),
                        "k = {k}: group {} on both sides",
                        groups[t]
                    );
                }
                assert!(train.contains(&0) && train.contains(&4), "the template's group trains");
            }
            let expected: Vec<usize> = groups.iter().map(|&g| usize::from(g != 0)).collect();
            assert_eq!(tested, expected, "k = {k}");
        }
        assert!(group_folds(&[2, 2, 2], 1, 5).is_empty());
    }
}
