//! The upsampling error: how well a level, with its upsampler, brings a pose back to full
//! resolution, independently of any pose model.
//!
//! For each measured pose `p`: take the level-k ground truth (the full-resolution pose at
//! `orig{k}`), apply the composed upsampler `U_0 · … · U_{k−1}` (`n_0 × n_k`), and
//! compare with the full-resolution pose: the mean squared vertex distance (vertex `i`
//! against vertex `i`) and the symmetric v2f of the paper's Eq. 6 (upsampled mesh with
//! the full faces against the full mesh), both in squared input units (m² for SCAPE).
//! Measure on poses the upsampler was not fitted on to report it held out.

use desal_eval::{metrics::mean, v2f};
use desal_mesh::{PoseSet, Real, TriMesh, Vec3};
use rayon::prelude::*;

use crate::error::HierarchyError;
use crate::sparse::CsrMatrix;

/// One pose's upsampling error, m².
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseError {
    pub pose: usize,
    /// Mean over full-resolution vertices of `‖(U c)_i − x_i‖²`.
    pub mse: Real,
    /// Symmetric v2f between the upsampled and the full mesh.
    pub v2f: Real,
}

/// The upsampling error over a set of poses.
#[derive(Debug, Clone, PartialEq)]
pub struct UpsamplingError {
    /// Per measured pose, in the order given.
    pub per_pose: Vec<PoseError>,
    /// Means over the measured poses, m².
    pub mse: Real,
    pub v2f: Real,
    /// Per full-resolution vertex (`orig_idx`), the squared distance averaged over the
    /// measured poses, m²: the per-vertex error map.
    pub vertex_mse: Vec<Real>,
}

/// Measures `up_to_full` (`n_0 × n_k`, the composed upsampler of level k) on `poses` of
/// the full-resolution pose set `full`, with `coarse_to_orig` (`orig{k}`, length `n_k`)
/// giving the level-k ground truth. Poses are measured in parallel and summed in order.
///
/// Errors: a matrix whose shape is not `n_0 × coarse_to_orig.len()`, an `orig` index or a
/// pose out of range.
pub fn upsampling_error(
    full: &PoseSet,
    up_to_full: &CsrMatrix,
    coarse_to_orig: &[u32],
    poses: &[usize],
) -> Result<UpsamplingError, HierarchyError> {
    check_shapes(full, up_to_full, coarse_to_orig, poses)?;
    let n0 = full.vertex_count();
    let measured: Vec<(PoseError, Vec<Real>)> = poses
        .par_iter()
        .map(|&pose| {
            let up = upsample_pose(full, up_to_full, coarse_to_orig, pose);
            let squared = squared_errors(&up, &full.poses[pose]);
            let up_mesh = TriMesh { positions: up, faces: full.faces.clone() };
            let v2f = v2f(&up_mesh, &full.pose_mesh(pose));
            (PoseError { pose, mse: mean(&squared), v2f }, squared)
        })
        .collect();

    let mut vertex_mse = vec![0.0; n0];
    for (_, squared) in &measured {
        for (acc, s) in vertex_mse.iter_mut().zip(squared) {
            *acc += s;
        }
    }
    for v in &mut vertex_mse {
        *v /= measured.len().max(1) as Real;
    }
    let per_pose: Vec<PoseError> = measured.into_iter().map(|(e, _)| e).collect();
    let mse = mean(&per_pose.iter().map(|e| e.mse).collect::<Vec<_>>());
    let v2f = mean(&per_pose.iter().map(|e| e.v2f).collect::<Vec<_>>());
    Ok(UpsamplingError { per_pose, mse, v2f, vertex_mse })
}

/// The MSE part of [`upsampling_error`] alone, per pose in the order given (m²): no
/// surface queries, for parameter sweeps. Same errors.
pub fn upsampling_mse(
    full: &PoseSet,
    up_to_full: &CsrMatrix,
    coarse_to_orig: &[u32],
    poses: &[usize],
) -> Result<Vec<Real>, HierarchyError> {
    check_shapes(full, up_to_full, coarse_to_orig, poses)?;
    Ok(poses
        .par_iter()
        .map(|&pose| {
            let up = upsample_pose(full, up_to_full, coarse_to_orig, pose);
            mean(&squared_errors(&up, &full.poses[pose]))
        })
        .collect())
}

/// `U · (pose at orig{k})`: the level-k ground truth of `pose` at full resolution.
fn upsample_pose(full: &PoseSet, up_to_full: &CsrMatrix, coarse_to_orig: &[u32], pose: usize) -> Vec<Vec3> {
    let truth = &full.poses[pose];
    let coarse: Vec<Vec3> = coarse_to_orig.iter().map(|&o| truth[o as usize]).collect();
    up_to_full.apply(&coarse).expect("shapes checked by the caller")
}

fn squared_errors(up: &[Vec3], truth: &[Vec3]) -> Vec<Real> {
    up.iter().zip(truth).map(|(u, t)| (u - t).norm_squared()).collect()
}

fn check_shapes(
    full: &PoseSet,
    up_to_full: &CsrMatrix,
    coarse_to_orig: &[u32],
    poses: &[usize],
) -> Result<(), HierarchyError> {
    let n0 = full.vertex_count();
    if up_to_full.rows != n0 || up_to_full.cols != coarse_to_orig.len() {
        return Err(HierarchyError::ShapeMismatch {
            left: (up_to_full.rows, up_to_full.cols),
            right: (n0, coarse_to_orig.len()),
        });
    }
    if let Some((coarse_idx, &fine_idx)) = coarse_to_orig.iter().enumerate().find(|&(_, &o)| o as usize >= n0)
    {
        return Err(HierarchyError::MapOutOfRange { coarse_idx, fine_idx, fine_count: n0 });
    }
    if let Some(&pose) = poses.iter().find(|&&p| p >= full.pose_count()) {
        return Err(HierarchyError::PoseOutOfRange { pose, poses: full.pose_count() });
    }
    Ok(())
}
