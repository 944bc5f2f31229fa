//! `VertexMap`: the one-to-one map from simplified vertices to original vertices that
//! stage 4 computes (greedy mode) or receives from stage 3 (subset mode).

use crate::error::MapError;

/// A one-to-one map from the simplified template's vertices into the original
/// template's vertices.
///
/// Index spaces: the position in `simp_to_orig` is a `simp_idx` (a vertex of the
/// simplified template, the index its triangles use); the value is an `orig_idx` (a
/// vertex of the original pose set, the same body point in every pose).
///
/// **Invariant** (after [`VertexMap::try_new`], [`VertexMap::from_subset`] or a mapping
/// function): every `orig_idx` is in range and no two simplified vertices share one.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VertexMap {
    /// `simp_to_orig[simp_idx] = orig_idx`.
    pub simp_to_orig: Vec<u32>,
}

impl VertexMap {
    /// Builds a map and checks that it is one-to-one into `0..original_count`.
    pub fn try_new(simp_to_orig: Vec<u32>, original_count: usize) -> Result<Self, MapError> {
        let map = Self { simp_to_orig };
        map.validate(original_count)?;
        Ok(map)
    }

    /// Subset mode: stage 3 collapsed every edge onto one of its endpoints, so the
    /// simplified vertex `simp_idx` *is* original vertex `kept_orig[simp_idx]` and no
    /// search is needed. Checks range and distinctness like [`VertexMap::try_new`].
    pub fn from_subset(kept_orig: &[u32], original_count: usize) -> Result<Self, MapError> {
        Self::try_new(kept_orig.to_vec(), original_count)
    }

    /// Number of simplified vertices.
    pub fn len(&self) -> usize {
        self.simp_to_orig.len()
    }

    /// True when the map covers no vertex.
    pub fn is_empty(&self) -> bool {
        self.simp_to_orig.is_empty()
    }

    /// The original vertex that simplified vertex `simp_idx` maps to.
    pub fn orig_of(&self, simp_idx: u32) -> u32 {
        self.simp_to_orig[simp_idx as usize]
    }

    /// The inverse map over `0..original_count`: `Some(simp_idx)` for mapped original
    /// vertices, `None` for the dropped ones. Call on a validated map only.
    pub fn orig_to_simp(&self, original_count: usize) -> Vec<Option<u32>> {
        let mut inverse = vec![None; original_count];
        for (simp_idx, &orig_idx) in self.simp_to_orig.iter().enumerate() {
            inverse[orig_idx as usize] = Some(simp_idx as u32);
        }
        inverse
    }

    /// Checks that every entry is `< original_count` and that the entries are distinct.
    /// Errors name the first offending simplified vertex (in `simp_idx` order).
    pub fn validate(&self, original_count: usize) -> Result<(), MapError> {
        // The first simplified vertex seen for each original vertex, to name both halves
        // of a duplicate.
        let mut seen: Vec<Option<u32>> = vec![None; original_count];
        for (simp_idx, &orig_idx) in self.simp_to_orig.iter().enumerate() {
            let simp_idx = simp_idx as u32;
            let slot = seen.get_mut(orig_idx as usize).ok_or(MapError::OrigIndexOutOfRange {
                simp_idx,
                orig_idx,
                original_count,
            })?;
            if let Some(first_simp_idx) = *slot {
                return Err(MapError::DuplicateOrigIndex {
                    orig_idx,
                    first_simp_idx,
                    second_simp_idx: simp_idx,
                });
            }
            *slot = Some(simp_idx);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn subset_map_keeps_the_given_order() {
        let map = VertexMap::from_subset(&[4, 0, 2], 5).unwrap();
        assert_eq!(map.simp_to_orig, vec![4, 0, 2]);
        assert_eq!(map.orig_to_simp(5), vec![Some(1), None, Some(2), None, Some(0)]);
    }

    #[test]
    fn out_of_range_index_names_the_simplified_vertex() {
        let err = VertexMap::from_subset(&[0, 5, 1], 5).unwrap_err();
        assert_eq!(err, MapError::OrigIndexOutOfRange { simp_idx: 1, orig_idx: 5, original_count: 5 });
    }

    #[test]
    fn duplicate_index_names_both_simplified_vertices() {
        let err = VertexMap::from_subset(&[3, 1, 2, 1], 5).unwrap_err();
        assert_eq!(err, MapError::DuplicateOrigIndex { orig_idx: 1, first_simp_idx: 1, second_simp_idx: 3 });
    }
}
