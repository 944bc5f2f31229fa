//! Linear blend skinning (Magnenat-Thalmann et al. 1988; Lewis et al. 2000, "Pose
//! space deformation", §2): a posed vertex is the weight-blended image of its rest
//! position under its bones' world transforms.
//!
//! The blend is computed as a displacement, `p' = p + Σ wᵢ (Tᵢ(p) − p)`, over the bones
//! that moved: a vertex whose bones all have the identity transform is copied bit for
//! bit, whatever the rounding of its weights' sum. This is what lets the rest pose reproduce the base
//! mesh exactly and a single turned bone move only the vertices it (or a descendant)
//! influences.

use std::collections::BTreeMap;

use desal_mesh::Vec3;

use crate::error::SampleError;
use crate::skeleton::{BoneTransform, Skeleton};

/// Per-vertex skinning weights in compressed rows: the influences of vertex `v` are
/// `bones[offsets[v]..offsets[v + 1]]` (bone indices of a [`Skeleton`], ascending) with
/// `weights[...]` (positive, summing to 1 up to rounding).
#[derive(Debug, Clone, PartialEq)]
pub struct SkinWeights {
    pub offsets: Vec<u32>,
    pub bones: Vec<u32>,
    pub weights: Vec<f64>,
}

/// What [`SkinWeights::from_bone_lists`] had to fix.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WeightsReport {
    /// Vertices without any positive weight; they were bound to the root bone with
    /// weight 1 (the root carries the whole body, so they follow it rigidly).
    pub unweighted_vertices: Vec<u32>,
    /// Entries dropped because they name a vertex outside the skinned range (the base
    /// mesh's helper geometry when skinning the body only).
    pub entries_outside: usize,
    /// Entries with weight zero, dropped.
    pub zero_entries: usize,
}

impl SkinWeights {
    /// Builds per-vertex weights for vertices `0..vertex_count` from per-bone lists
    /// `bone name → (vertex, weight)`. Repeated `(bone, vertex)` entries add up; each
    /// vertex's weights are normalised to sum to 1; vertices with none go to the root.
    pub fn from_bone_lists(
        skeleton: &Skeleton,
        lists: &BTreeMap<String, Vec<(u32, f64)>>,
        vertex_count: usize,
    ) -> Result<(Self, WeightsReport), SampleError> {
        let mut report = WeightsReport::default();
        // (vertex, bone, weight) triples, then sorted: rows in vertex order, bones ascending.
        let mut triples: Vec<(u32, u32, f64)> = Vec::new();
        for (name, list) in lists {
            let bone = skeleton
                .index_of(name)
                .ok_or_else(|| SampleError::UnknownWeightBone { bone: name.clone() })?;
            for &(vertex, weight) in list {
                if !(weight.is_finite() && weight >= 0.0) {
                    return Err(SampleError::BadWeight { bone: name.clone(), vertex, weight });
                }
                if vertex as usize >= vertex_count {
                    report.entries_outside += 1;
                } else if weight == 0.0 {
                    report.zero_entries += 1;
                } else {
                    triples.push((vertex, bone as u32, weight));
                }
            }
        }
        // A stable sort keeps file order among repeats, so their sum is deterministic.
        triples.sort_by_key(|&(v, b, _)| (v, b));

        let mut result =
            SkinWeights { offsets: Vec::with_capacity(vertex_count + 1), bones: vec![], weights: vec![] };
        let mut next = 0;
        for vertex in 0..vertex_count as u32 {
            result.offsets.push(result.bones.len() as u32);
            let row_start = result.bones.len();
            while next < triples.len() && triples[next].0 == vertex {
                let (_, bone, weight) = triples[next];
                if result.bones.len() > row_start && *result.bones.last().unwrap() == bone {
                    *result.weights.last_mut().unwrap() += weight;
                } else {
                    result.bones.push(bone);
                    result.weights.push(weight);
                }
                next += 1;
            }
            if result.bones.len() == row_start {
                report.unweighted_vertices.push(vertex);
                result.bones.push(0);
                result.weights.push(1.0);
            }
            let total: f64 = result.weights[row_start..].iter().sum();
            for w in &mut result.weights[row_start..] {
                *w /= total;
            }
        }
        result.offsets.push(result.bones.len() as u32);
        Ok((result, report))
    }

    pub fn vertex_count(&self) -> usize {
        self.offsets.len() - 1
    }

    /// The `(bone, weight)` influences of vertex `v`, bones ascending.
    pub fn of(&self, v: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let range = self.offsets[v] as usize..self.offsets[v + 1] as usize;
        self.bones[range.clone()].iter().map(|&b| b as usize).zip(self.weights[range].iter().copied())
    }

    /// The bone with the largest weight on vertex `v`; ties go to the lower bone index.
    pub fn dominant_bone(&self, v: usize) -> usize {
        let mut best = (usize::MAX, f64::NEG_INFINITY);
        for (bone, weight) in self.of(v) {
            if weight > best.1 {
                best = (bone, weight);
            }
        }
        best.0
    }
}

/// Poses `rest` (in the weights' vertex index space) with the bones' world transforms
/// `transforms[bone]`. Returns the posed positions, same order and units.
pub fn skin(rest: &[Vec3], weights: &SkinWeights, transforms: &[BoneTransform]) -> Vec<Vec3> {
    assert_eq!(rest.len(), weights.vertex_count(), "one weight row per rest vertex");
    let identity = BoneTransform::identity();
    let moved: Vec<bool> = transforms.iter().map(|t| *t != identity).collect();
    rest.iter()
        .enumerate()
        .map(|(v, p)| {
            // Copied, not recomputed: even `p + 0` would turn a -0.0 coordinate into +0.0.
            if !weights.of(v).any(|(bone, _)| moved[bone]) {
                return *p;
            }
            let mut displacement = Vec3::zeros();
            for (bone, weight) in weights.of(v) {
                if moved[bone] {
                    displacement += weight * (transforms[bone].apply(p) - p);
                }
            }
            p + displacement
        })
        .collect()
}
