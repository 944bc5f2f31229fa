//! The upsampling error: how well a level, with its upsampler, brings a pose back to full
//! resolution, independently of any pose model.
//!
//! For each measured pose `p`: take the level-k ground truth (the full-resolution pose at
//! `orig{k}`), apply the composed upsampler `U_0 · … · U_{k−1}` (`n_0 × n_k`), and
//! compare with the full-resolution pose: the mean squared vertex distance (vertex `i`
//! against vertex `i`) and the symmetric v2f of the paper's Eq. 6 (upsampled mesh with
//! the full faces against the full mesh), both in squared input units (m² for SCAPE).
//! Measure on poses the upsampler was not fitted on to report it held out.

use desal_measures::{SurfaceIndex, metrics::mean, v2f_halves_same_faces, vertex_faces};
use desal_mesh::{PoseSet, Real, TriMesh, Vec3};
use rayon::prelude::*;

use crate::error::HierarchyError;
use crate::sparse::CsrMatrix;

/// Poses measured at once by [`upsampling_errors`]: enough to keep every thread busy,
/// few enough that their per-vertex distances stay small beside the pose set.
const MEASURED_CHUNK: usize = 64;

/// One pose's upsampling error, m².
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseError {
    pub pose: usize,
    /// Mean over full-resolution vertices of `‖(U c)_i − x_i‖²`.
    pub mse: Real,
    /// Symmetric v2f between the upsampled and the full mesh; `None` when skipped
    /// ([`V2f::Skip`]).
    pub v2f: Option<Real>,
}

/// The upsampling error over a set of poses.
#[derive(Debug, Clone, PartialEq)]
pub struct UpsamplingError {
    /// Per measured pose, in the order given.
    pub per_pose: Vec<PoseError>,
    /// Means over the measured poses, m² (`v2f`: `None` when skipped).
    pub mse: Real,
    pub v2f: Option<Real>,
    /// Per full-resolution vertex (`orig_idx`), the squared distance averaged over the
    /// measured poses, m²: the per-vertex error map.
    pub vertex_mse: Vec<Real>,
}

/// What one upsampled mesh starts from, per measured pose.
#[derive(Debug, Clone, Copy)]
pub enum Coarse<'a> {
    /// The level-k ground truth: the full-resolution pose at `orig{k}` (`coarse_to_orig`,
    /// length `n_k`). This is the upsampling error proper.
    GroundTruth(&'a [u32]),
    /// Level-k positions given per measured pose (`[k]` for `poses[k]`, each of length
    /// `n_k`), e.g. a pose model's deformation of the coarse mesh.
    Given(&'a [Vec<Vec3>]),
}

/// Whether [`upsampling_errors`] measures v2f: its surface queries are most of the cost
/// (about 35 ms per SCAPE pose and candidate, against well under 1 ms for the MSE).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum V2f {
    Measure,
    Skip,
}

/// One candidate of [`upsampling_errors`]: an upsampler from level k to full resolution
/// and what it upsamples.
#[derive(Debug, Clone, Copy)]
pub struct Upsampled<'a> {
    /// The chain of U's from level k up to level 0, level 1's first (`n_0 × n_1`) and
    /// level k's last, applied last to first; a composed U (`n_0 × n_k`) is a chain of
    /// one. Applying the chain needs no composed matrix, whose rows hold the union of
    /// every level's neighbourhoods.
    pub up_to_full: &'a [CsrMatrix],
    pub coarse: Coarse<'a>,
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
    let candidate = Upsampled {
        up_to_full: std::slice::from_ref(up_to_full),
        coarse: Coarse::GroundTruth(coarse_to_orig),
    };
    Ok(upsampling_errors(full, poses, &[candidate], V2f::Measure)?.remove(0))
}

/// [`upsampling_error`] of several candidates on the same `poses`, one result per
/// candidate in order, with or without v2f: each full-resolution pose's surface index is
/// built once and shared by every candidate.
///
/// Errors: as [`upsampling_error`], and a [`Coarse::Given`] with other than one position
/// set of `n_k` points per measured pose.
pub fn upsampling_errors(
    full: &PoseSet,
    poses: &[usize],
    candidates: &[Upsampled],
    v2f: V2f,
) -> Result<Vec<UpsamplingError>, HierarchyError> {
    upsampling_errors_with(full, poses, candidates, v2f, None)
}

/// [`upsampling_errors`] with v2f, each pose's surface index given by the caller
/// (`truth[pose]` must index `full.pose_mesh(pose)`): for a caller measuring many
/// candidate sets against the same poses (`desal eval`, one set per method), which
/// builds every pose's index once. The same errors.
pub fn upsampling_errors_indexed(
    full: &PoseSet,
    poses: &[usize],
    candidates: &[Upsampled],
    truth: &[SurfaceIndex],
) -> Result<Vec<UpsamplingError>, HierarchyError> {
    if let Some(&pose) = poses.iter().find(|&&p| p >= truth.len()) {
        return Err(HierarchyError::PoseOutOfRange { pose, poses: truth.len() });
    }
    upsampling_errors_with(full, poses, candidates, V2f::Measure, Some(truth))
}

/// Both of the above: `truth[pose]` is the pose's surface index, else it is built.
fn upsampling_errors_with(
    full: &PoseSet,
    poses: &[usize],
    candidates: &[Upsampled],
    v2f: V2f,
    truth_index: Option<&[SurfaceIndex]>,
) -> Result<Vec<UpsamplingError>, HierarchyError> {
    for c in candidates {
        check_candidate(full, c, poses)?;
    }
    let n0 = full.vertex_count();
    // An upsampled mesh has the truth's faces and vertex i lies near truth vertex i, so
    // every v2f query starts from a face of its own vertex.
    let seeds = if v2f == V2f::Measure { vertex_faces(&full.faces, n0) } else { Vec::new() };
    // Per pose, per candidate: the pose's error and its per-vertex squared distances,
    // measured in parallel a chunk of poses at a time and summed in pose order, so that
    // the per-vertex distances of every pose are never held at once.
    let mut per_pose: Vec<Vec<PoseError>> = vec![Vec::with_capacity(poses.len()); candidates.len()];
    let mut vertex_mse: Vec<Vec<Real>> = vec![vec![0.0; n0]; candidates.len()];
    for (chunk, chunk_poses) in poses.chunks(MEASURED_CHUNK).enumerate() {
        let measured: Vec<Vec<(PoseError, Vec<Real>)>> = chunk_poses
            .par_iter()
            .enumerate()
            .map(|(k, &pose)| {
                let slot = chunk * MEASURED_CHUNK + k;
                let truth = full.pose_mesh(pose);
                let built;
                let truth_surface = match (v2f, truth_index) {
                    (V2f::Skip, _) => None,
                    (V2f::Measure, Some(given)) => Some(&given[pose]),
                    (V2f::Measure, None) => {
                        built = SurfaceIndex::new(&truth);
                        Some(&built)
                    }
                };
                candidates
                    .iter()
                    .map(|c| {
                        let up = upsample_pose(full, c, slot, pose);
                        let squared = squared_errors(&up, &full.poses[pose]);
                        let v2f = truth_surface.as_ref().map(|surface| {
                            // The upsampled mesh has the truth's faces and lies near it, so
                            // the truth's tree refitted serves it as well as a new one.
                            let up_mesh = TriMesh { positions: up, faces: full.faces.clone() };
                            v2f_halves_same_faces(&up_mesh, &surface.refit(&up_mesh), &truth, surface, &seeds)
                                .combined()
                        });
                        (PoseError { pose, mse: mean(&squared), v2f }, squared)
                    })
                    .collect()
            })
            .collect();
        for per_candidate in measured {
            for (c, (error, squared)) in per_candidate.into_iter().enumerate() {
                for (acc, s) in vertex_mse[c].iter_mut().zip(&squared) {
                    *acc += s;
                }
                per_pose[c].push(error);
            }
        }
    }

    Ok(per_pose
        .into_iter()
        .zip(vertex_mse)
        .map(|(per_pose, mut vertex_mse)| {
            for v in &mut vertex_mse {
                *v /= per_pose.len().max(1) as Real;
            }
            let mse = mean(&per_pose.iter().map(|e| e.mse).collect::<Vec<_>>());
            let v2f = per_pose.iter().map(|e| e.v2f).collect::<Option<Vec<_>>>().map(|v| mean(&v));
            UpsamplingError { per_pose, mse, v2f, vertex_mse }
        })
        .collect())
}

/// The MSE part of [`upsampling_error`] alone, per pose in the order given (m²): no
/// surface queries, for parameter sweeps. Same errors.
pub fn upsampling_mse(
    full: &PoseSet,
    up_to_full: &CsrMatrix,
    coarse_to_orig: &[u32],
    poses: &[usize],
) -> Result<Vec<Real>, HierarchyError> {
    let candidate = Upsampled {
        up_to_full: std::slice::from_ref(up_to_full),
        coarse: Coarse::GroundTruth(coarse_to_orig),
    };
    check_candidate(full, &candidate, poses)?;
    Ok(poses
        .par_iter()
        .enumerate()
        .map(|(slot, &pose)| {
            let up = upsample_pose(full, &candidate, slot, pose);
            mean(&squared_errors(&up, &full.poses[pose]))
        })
        .collect())
}

/// `U · c` for the candidate's level-k positions `c` of `pose` (measured in `slot`).
fn upsample_pose(full: &PoseSet, candidate: &Upsampled, slot: usize, pose: usize) -> Vec<Vec3> {
    let up = match candidate.coarse {
        Coarse::GroundTruth(coarse_to_orig) => {
            let truth = &full.poses[pose];
            let coarse: Vec<Vec3> = coarse_to_orig.iter().map(|&o| truth[o as usize]).collect();
            apply_chain(candidate.up_to_full, &coarse)
        }
        Coarse::Given(positions) => apply_chain(candidate.up_to_full, &positions[slot]),
    };
    up.expect("shapes checked by the caller")
}

/// The chain's U's applied to `coarse`, last to first.
fn apply_chain(chain: &[CsrMatrix], coarse: &[Vec3]) -> Result<Vec<Vec3>, HierarchyError> {
    let (last, rest) = chain.split_last().expect("a chain checked non-empty");
    rest.iter().rev().try_fold(last.apply(coarse)?, |positions, up| up.apply(&positions))
}

/// The shape (`rows × cols`) of the chain's product. Errors: an empty chain, neighbours
/// whose shapes do not meet.
fn chain_shape(chain: &[CsrMatrix]) -> Result<(usize, usize), HierarchyError> {
    let (first, last) = match (chain.first(), chain.last()) {
        (Some(f), Some(l)) => (f, l),
        _ => return Err(HierarchyError::EmptyCoarse { vertices: 0, faces: 0 }),
    };
    if let Some(w) = chain.windows(2).find(|w| w[0].cols != w[1].rows) {
        return Err(HierarchyError::ShapeMismatch {
            left: (w[0].rows, w[0].cols),
            right: (w[1].rows, w[1].cols),
        });
    }
    Ok((first.rows, last.cols))
}

fn squared_errors(up: &[Vec3], truth: &[Vec3]) -> Vec<Real> {
    up.iter().zip(truth).map(|(u, t)| (u - t).norm_squared()).collect()
}

fn check_candidate(full: &PoseSet, candidate: &Upsampled, poses: &[usize]) -> Result<(), HierarchyError> {
    let n0 = full.vertex_count();
    let (rows, cols) = chain_shape(candidate.up_to_full)?;
    let n_coarse = match candidate.coarse {
        Coarse::GroundTruth(coarse_to_orig) => {
            if let Some((coarse_idx, &fine_idx)) =
                coarse_to_orig.iter().enumerate().find(|&(_, &o)| o as usize >= n0)
            {
                return Err(HierarchyError::MapOutOfRange { coarse_idx, fine_idx, fine_count: n0 });
            }
            coarse_to_orig.len()
        }
        Coarse::Given(positions) => {
            if let Some(p) = positions.iter().find(|p| p.len() != cols) {
                return Err(HierarchyError::ShapeMismatch { left: (rows, cols), right: (p.len(), 3) });
            }
            if positions.len() != poses.len() {
                return Err(HierarchyError::ShapeMismatch {
                    left: (poses.len(), cols),
                    right: (positions.len(), cols),
                });
            }
            cols
        }
    };
    if rows != n0 || cols != n_coarse {
        return Err(HierarchyError::ShapeMismatch { left: (rows, cols), right: (n0, n_coarse) });
    }
    if let Some(&pose) = poses.iter().find(|&&p| p >= full.pose_count()) {
        return Err(HierarchyError::PoseOutOfRange { pose, poses: full.pose_count() });
    }
    Ok(())
}
