//! Validation helpers: finiteness, face index ranges, and the removal of degenerate
//! and duplicate faces (which is reported, never silent).

use crate::error::MeshError;
use crate::math::Vec3;

/// Fails on the first non-finite coordinate, naming the pose and vertex.
pub fn check_finite(positions: &[Vec3], pose: &str) -> Result<(), MeshError> {
    match positions.iter().position(|p| !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite())) {
        None => Ok(()),
        Some(vertex) => {
            let p = positions[vertex];
            Err(MeshError::NonFiniteVertex { pose: pose.to_owned(), vertex, x: p.x, y: p.y, z: p.z })
        }
    }
}

/// Fails on the first face index that is `>= vertex_count`.
pub fn check_face_indices(faces: &[[u32; 3]], vertex_count: usize) -> Result<(), MeshError> {
    for (face, f) in faces.iter().enumerate() {
        if let Some(&vertex) = f.iter().find(|&&v| v as usize >= vertex_count) {
            return Err(MeshError::FaceIndexOutOfRange { face, vertex, vertex_count });
        }
    }
    Ok(())
}

/// Fails when `pose_faces` differs from `template_faces`, naming the first differing
/// face (or the first face one list has and the other lacks).
pub fn check_same_faces(
    template_faces: &[[u32; 3]],
    pose_faces: &[[u32; 3]],
    pose: &str,
) -> Result<(), MeshError> {
    let n = template_faces.len().max(pose_faces.len());
    for face in 0..n {
        let expected = template_faces.get(face).copied();
        let found = pose_faces.get(face).copied();
        if expected != found {
            return Err(MeshError::FaceMismatch { pose: pose.to_owned(), face, expected, found });
        }
    }
    Ok(())
}

/// What [`clean_faces`] removed, by original face index, so callers can warn with
/// specifics.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct FaceCleanup {
    /// Faces with a repeated vertex index (zero area by construction).
    pub degenerate: Vec<usize>,
    /// Faces with the same vertex set as an earlier face (either orientation); the
    /// earlier one is kept.
    pub duplicate: Vec<usize>,
}

impl FaceCleanup {
    pub fn is_empty(&self) -> bool {
        self.degenerate.is_empty() && self.duplicate.is_empty()
    }
}

/// The vertices (of `vertex_count`) that `faces` use, in index order, and `faces`
/// renumbered onto them.
pub fn used_vertices(vertex_count: usize, faces: &[[u32; 3]]) -> (Vec<u32>, Vec<[u32; 3]>) {
    let mut new_index = vec![u32::MAX; vertex_count];
    for &v in faces.iter().flatten() {
        new_index[v as usize] = 0;
    }
    let mut kept = Vec::new();
    for (v, slot) in new_index.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = kept.len() as u32;
            kept.push(v as u32);
        }
    }
    (kept, faces.iter().map(|f| f.map(|v| new_index[v as usize])).collect())
}

/// Removes faces with a repeated vertex and faces that repeat an earlier face's vertex
/// set, keeping the order of the rest. Returns the kept faces and what was removed.
pub fn clean_faces(faces: &[[u32; 3]]) -> (Vec<[u32; 3]>, FaceCleanup) {
    let mut report = FaceCleanup::default();
    let mut keys: Vec<([u32; 3], usize)> = faces
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let mut k = *f;
            k.sort_unstable();
            (k, i)
        })
        .collect();
    keys.sort_unstable();
    let mut drop = vec![false; faces.len()];
    for w in keys.windows(2) {
        if w[0].0 == w[1].0 {
            drop[w[1].1] = true;
        }
    }
    let mut kept = Vec::with_capacity(faces.len());
    for (i, f) in faces.iter().enumerate() {
        if f[0] == f[1] || f[1] == f[2] || f[0] == f[2] {
            report.degenerate.push(i);
        } else if drop[i] {
            report.duplicate.push(i);
        } else {
            kept.push(*f);
        }
    }
    (kept, report)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [u32; 3] 1 repeats face 0 reversed, face 2 repeats a vertex: both go, in order.
    #[test]
    fn clean_faces_reports_degenerate_and_duplicate() {
        let (kept, report) = clean_faces(&[[0, 1, 2], [2, 1, 0], [3, 3, 1], [1, 2, 3]]);
        assert_eq!(kept, vec![[0, 1, 2], [1, 2, 3]]);
        assert_eq!(report.degenerate, vec![2]);
        assert_eq!(report.duplicate, vec![1]);
    }

    #[test]
    fn first_differing_face_is_named() {
        let err = check_same_faces(&[[0, 1, 2], [1, 2, 3]], &[[0, 1, 2], [1, 3, 2]], "p").unwrap_err();
        assert!(matches!(err, MeshError::FaceMismatch { face: 1, .. }));
    }
}
