//! Applying a vertex map: every pose of the original pose set becomes a simplified pose
//! (its positions at the mapped original vertices, with the simplified triangles), the
//! part labels come along, and the mapping displacement is measured.

use desal_mesh::{Face, MeshError, PartLabels, PoseSet, Vec3};
use rayon::prelude::*;

use crate::error::MapError;
use crate::kdtree::squared_distance;
use crate::vertex_map::VertexMap;

/// Simplifies every pose of `poses` with `map`.
///
/// Inputs: `poses` and `labels` in the original vertex space (`orig_idx`);
/// `simp_faces` in the simplified vertex space (`simp_idx`, `0..map.len()`).
/// Output: a pose set with `map.len()` vertices per pose, vertex `simp_idx` of pose `p`
/// being vertex `map.simp_to_orig[simp_idx]` of the original pose `p`, every pose with
/// the triangles `simp_faces`, the same names and template index; and labels with
/// `labels[simp_idx] = original_labels[orig_idx]` and the same part names (a part may
/// end up with no vertex; see [`empty_parts`]) — except for labels with a part tree
/// ([`PartLabels::parents`]), whose parts left without three non-collinear simplified
/// template vertices join their parents ([`PartLabels::merge_unfittable_parts`]), so
/// fewer parts may come back.
///
/// Errors: a map entry out of range or repeated, a face index past the map, labels not
/// matching the pose set, or an empty map or face list.
pub fn apply_map(
    poses: &PoseSet,
    labels: &PartLabels,
    simp_faces: &[Face],
    map: &VertexMap,
) -> Result<(PoseSet, PartLabels), MapError> {
    let simplified_labels = map_labels(poses, labels, simp_faces, map)?;
    Ok((gather_poses(poses, simp_faces, map)?, simplified_labels))
}

/// The poses half of [`apply_map`], its inputs already checked by [`map_labels`].
pub(crate) fn gather_poses(
    poses: &PoseSet,
    simp_faces: &[Face],
    map: &VertexMap,
) -> Result<PoseSet, MapError> {
    // One gather per pose; poses are independent, collected in pose order.
    let simplified_poses: Vec<Vec<Vec3>> = poses.poses.par_iter().map(|pose| gather(pose, map)).collect();
    Ok(PoseSet::try_new(poses.names.clone(), simplified_poses, simp_faces.to_vec(), poses.template)?)
}

/// The labels half of [`apply_map`], without gathering a single pose but the template:
/// `labels` carried to the simplified vertices, exactly as [`apply_map`] returns them, for
/// a caller that needs the map's labels and not the simplified poses (a model source's
/// thousands of poses are hundreds of MB simplified).
///
/// Errors: those of [`apply_map`].
pub fn map_labels(
    poses: &PoseSet,
    labels: &PartLabels,
    simp_faces: &[Face],
    map: &VertexMap,
) -> Result<PartLabels, MapError> {
    map.validate(poses.vertex_count())?;
    labels.check_vertex_count(poses.vertex_count())?;
    check_face_indices(simp_faces, map.len())?;
    // What the simplified pose set refuses (`PoseSet::try_new`), refused without it.
    if map.is_empty() || simp_faces.is_empty() {
        return Err(MeshError::Empty { vertices: map.len(), faces: simp_faces.len() }.into());
    }
    let carried = PartLabels {
        labels: map.simp_to_orig.iter().map(|&orig_idx| labels.labels[orig_idx as usize]).collect(),
        names: labels.names.clone(),
        parents: labels.parents.clone(),
    };
    // Labels with a part tree (a rig's joints) hand a part the simplification left
    // unfittable to its parent; labels without one are carried as they are.
    let (simplified_labels, _merged) =
        carried.merge_unfittable_parts(&gather(poses.template_positions(), map));
    Ok(simplified_labels)
}

/// How far the mapping moved the simplified template's vertices, in the pose set's
/// units (metres for SCAPE): distances between `simplified[simp_idx]` and
/// `original[simp_to_orig[simp_idx]]`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Displacement {
    /// Mean distance over the simplified vertices (0 for an empty map).
    pub mean: f64,
    /// Largest distance.
    pub max: f64,
    /// The simplified vertex with the largest distance (lowest `simp_idx` among equals).
    pub max_simp_idx: u32,
}

/// Measures the mapping displacement. `simplified` is in `simp_idx` space and must have
/// one position per map entry; `original` is in `orig_idx` space and must cover the map.
pub fn displacement(
    simplified: &[Vec3],
    original: &[Vec3],
    map: &VertexMap,
) -> Result<Displacement, MapError> {
    if simplified.len() != map.len() {
        return Err(MapError::MapLengthMismatch { positions: simplified.len(), map: map.len() });
    }
    map.validate(original.len())?;
    let mut result = Displacement::default();
    let mut sum = 0.0;
    for (simp_idx, (s, &orig_idx)) in simplified.iter().zip(&map.simp_to_orig).enumerate() {
        let distance = squared_distance(s, &original[orig_idx as usize]).sqrt();
        sum += distance;
        if distance > result.max {
            result.max = distance;
            result.max_simp_idx = simp_idx as u32;
        }
    }
    if !map.is_empty() {
        result.mean = sum / map.len() as f64;
    }
    Ok(result)
}

/// Part ids that no vertex carries, ascending: parts the simplification removed
/// entirely, which a per-part fit on the simplified set cannot handle.
pub fn empty_parts(labels: &PartLabels) -> Vec<u32> {
    let mut used = vec![false; labels.part_count()];
    for &part in &labels.labels {
        used[part as usize] = true;
    }
    (0..labels.part_count() as u32).filter(|&part| !used[part as usize]).collect()
}

fn gather(pose: &[Vec3], map: &VertexMap) -> Vec<Vec3> {
    map.simp_to_orig.iter().map(|&orig_idx| pose[orig_idx as usize]).collect()
}

fn check_face_indices(simp_faces: &[Face], simplified_count: usize) -> Result<(), MapError> {
    for (face, corners) in simp_faces.iter().enumerate() {
        if let Some(&simp_idx) = corners.iter().find(|&&v| v as usize >= simplified_count) {
            return Err(MapError::FaceIndexOutOfRange { face, simp_idx, simplified_count });
        }
    }
    Ok(())
}
