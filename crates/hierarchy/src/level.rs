//! One level of a hierarchy: from the fine level's pose set and the coarse level's
//! vertices (a subset of the fine ones) and faces, the selection D, the upsampler U and
//! the coarse adjacency A — COMA's `generate_transform_matrices`, one step.

use std::time::Instant;

use desal_mesh::{Face, PoseSet, Real, TriMesh};

use crate::barycentric::barycentric_rows;
use crate::error::HierarchyError;
use crate::fitted::{FineLevel, FitCounts, FittedConfig, Knob, Knobs, fitted_rows_per_training};
use crate::sparse::CsrMatrix;

/// Which upsampler fills U.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Upsampler {
    /// COMA's: barycentric coordinates of the projection onto the nearest coarse
    /// triangle, in the template pose only.
    Barycentric,
    /// Pose-aware least squares over the training poses (see [`crate::fitted`]).
    Fitted(FittedConfig),
}

impl Default for Upsampler {
    fn default() -> Self {
        Upsampler::Fitted(FittedConfig::default())
    }
}

impl Upsampler {
    /// `"barycentric"` or `"fitted"`, as pipeline files and reports spell it.
    pub fn name(&self) -> &'static str {
        match self {
            Upsampler::Barycentric => "barycentric",
            Upsampler::Fitted(_) => "fitted",
        }
    }

    /// Checks the options. Errors: a neighbour count of 0, a negative or non-finite ridge.
    pub fn validate(&self) -> Result<(), HierarchyError> {
        if let Upsampler::Fitted(c) = self {
            if c.neighbours == Knob::Given(0) {
                return Err(HierarchyError::BadOption {
                    option: "neighbours",
                    value: "0".into(),
                    expected: "at least 1",
                });
            }
            if let Knob::Given(ridge) = c.ridge
                && !(ridge.is_finite() && ridge >= 0.0)
            {
                return Err(HierarchyError::BadOption {
                    option: "ridge",
                    value: ridge.to_string(),
                    expected: "finite and >= 0",
                });
            }
        }
        Ok(())
    }
}

/// What one level is built from. Index spaces: `fine_idx` indexes `fine`'s vertices,
/// `coarse_idx` the coarse level's.
#[derive(Debug, Clone, Copy)]
pub struct LevelInput<'a> {
    /// The fine level's registered poses and faces (level k; level 0 is the input).
    pub fine: &'a PoseSet,
    /// For each `coarse_idx`, the `fine_idx` it is (stage 3's `simp_to_orig` with subset
    /// placement, or stage 4's map, taken relative to the fine level). Distinct.
    pub coarse_to_fine: &'a [u32],
    /// The coarse level's triangles, in `coarse_idx`.
    pub coarse_faces: &'a [Face],
    /// One flag per pose of `fine`: whether the fitted upsampler may fit on it (held-out
    /// and `[saliency] exclude` poses are `false`). The barycentric upsampler uses the
    /// template pose only and ignores it, but its length is still checked.
    pub training: &'a [bool],
}

/// The matrices of one level step, k → k+1.
#[derive(Debug, Clone, PartialEq)]
pub struct Level {
    /// D: `n_coarse × n_fine` selection, `D[coarse_idx, coarse_to_fine[coarse_idx]] = 1`.
    pub down: CsrMatrix,
    /// U: `n_fine × n_coarse`, rows summing to 1 (`fine_idx` rows, `coarse_idx` columns).
    pub up: CsrMatrix,
    /// A of the coarse level: `n_coarse × n_coarse`, 1 for every edge of `coarse_faces`
    /// in both directions, no diagonal.
    pub coarse_adjacency: CsrMatrix,
    pub report: LevelReport,
}

/// How a level came out, for `hierarchy.json` and log lines.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelReport {
    pub upsampler: &'static str,
    pub fine_vertices: usize,
    pub coarse_vertices: usize,
    pub coarse_faces: usize,
    /// Poses the fitted upsampler fitted on (0 for barycentric).
    pub training_poses: usize,
    /// Stored entries of U, and their mean per row.
    pub up_nnz: usize,
    pub up_mean_row_nnz: Real,
    /// Largest `|row sum − 1|` of U (rounding only).
    pub up_max_row_sum_error: Real,
    pub fit: FitCounts,
    /// The fitted upsampler's knobs and how they were settled (`None` for barycentric).
    pub knobs: Option<Knobs>,
    /// Wall time of [`build_level`], seconds.
    pub seconds: Real,
}

/// Builds D, U and the coarse A of one level step (module docs; index spaces on
/// [`LevelInput`]).
///
/// Errors: a `coarse_to_fine` entry out of range or repeated, a coarse face past the
/// coarse vertex count, an empty coarse level, a training mask of the wrong length, no
/// training pose for the fitted upsampler, or an upsampler option out of range.
pub fn build_level(input: &LevelInput, upsampler: &Upsampler) -> Result<Level, HierarchyError> {
    Ok(build_level_per_mask(input, &[input.training], upsampler)?.pop().expect("one mask"))
}

/// [`build_level`] once per training mask, `masks[k]` in place of `input.training` (which
/// is not read), one level each, in order: held-out evaluation's one level per fold. The
/// fitted rows share their candidates and their sums over poses
/// ([`crate::fitted::fitted_rows_per_training`]); each level's `seconds` is the time of
/// building them all.
pub(crate) fn build_level_per_mask(
    input: &LevelInput,
    masks: &[&[bool]],
    upsampler: &Upsampler,
) -> Result<Vec<Level>, HierarchyError> {
    let fine = input.fine;
    let view = FineLevel { poses: fine, orig: None, template: fine.template_positions(), faces: &fine.faces };
    build_levels(&view, input.coarse_to_fine, input.coarse_faces, masks, upsampler)
}

/// [`build_level_per_mask`] on a level read in place ([`FineLevel`]): a chain's coarser
/// levels are never gathered into pose sets of their own.
pub(crate) fn build_levels(
    fine: &FineLevel,
    coarse_to_fine: &[u32],
    coarse_faces: &[Face],
    masks: &[&[bool]],
    upsampler: &Upsampler,
) -> Result<Vec<Level>, HierarchyError> {
    let start = Instant::now();
    upsampler.validate()?;
    let pose_count = fine.poses.pose_count();
    for &training in masks {
        check_input(fine.vertex_count(), pose_count, coarse_to_fine, coarse_faces, training)?;
    }
    let trainings: Vec<Vec<usize>> =
        masks.iter().map(|mask| (0..pose_count).filter(|&p| mask[p]).collect()).collect();

    let down = selection(coarse_to_fine, fine.vertex_count())?;
    let template = fine.template;
    let coarse_template = TriMesh {
        positions: coarse_to_fine.iter().map(|&f| template[f as usize]).collect(),
        faces: coarse_faces.to_vec(),
    };
    let barycentric = barycentric_rows(&coarse_template, template);
    let n_coarse = coarse_to_fine.len();
    let coarse_adjacency = adjacency(n_coarse, coarse_faces)?;
    let ups: Vec<(CsrMatrix, FitCounts, Option<Knobs>, usize)> = match upsampler {
        Upsampler::Barycentric => {
            let up = CsrMatrix::from_rows(n_coarse, barycentric)?;
            masks.iter().map(|_| (up.clone(), FitCounts::default(), None, 0)).collect()
        }
        Upsampler::Fitted(config) => {
            if trainings.iter().any(|t| t.is_empty()) {
                return Err(HierarchyError::NoTrainingPose);
            }
            let sets: Vec<&[usize]> = trainings.iter().map(|t| t.as_slice()).collect();
            fitted_rows_per_training(fine, coarse_to_fine, &barycentric, &sets, config)
                .into_iter()
                .zip(&trainings)
                .map(|(fit, training)| (fit.up, fit.counts, Some(fit.knobs), training.len()))
                .collect()
        }
    };
    let seconds = start.elapsed().as_secs_f64();
    Ok(ups
        .into_iter()
        .map(|(up, fit, knobs, training_poses)| {
            let up_max_row_sum_error = up.row_sums().iter().fold(0.0, |m: Real, s| m.max((s - 1.0).abs()));
            let report = LevelReport {
                upsampler: upsampler.name(),
                fine_vertices: fine.vertex_count(),
                coarse_vertices: n_coarse,
                coarse_faces: coarse_faces.len(),
                training_poses,
                up_nnz: up.nnz(),
                up_mean_row_nnz: up.nnz() as Real / up.rows.max(1) as Real,
                up_max_row_sum_error,
                fit,
                knobs,
                seconds,
            };
            Level { down: down.clone(), up, coarse_adjacency: coarse_adjacency.clone(), report }
        })
        .collect())
}

fn check_input(
    fine_count: usize,
    pose_count: usize,
    coarse_to_fine: &[u32],
    coarse_faces: &[Face],
    training: &[bool],
) -> Result<(), HierarchyError> {
    let coarse_count = coarse_to_fine.len();
    if coarse_count == 0 || coarse_faces.is_empty() {
        return Err(HierarchyError::EmptyCoarse { vertices: coarse_count, faces: coarse_faces.len() });
    }
    if training.len() != pose_count {
        return Err(HierarchyError::MaskLength { mask: training.len(), poses: pose_count });
    }
    let mut seen = vec![usize::MAX; fine_count];
    for (coarse_idx, &fine_idx) in coarse_to_fine.iter().enumerate() {
        let slot = seen.get_mut(fine_idx as usize).ok_or(HierarchyError::MapOutOfRange {
            coarse_idx,
            fine_idx,
            fine_count,
        })?;
        if *slot != usize::MAX {
            return Err(HierarchyError::MapRepeated { first: *slot, second: coarse_idx, fine_idx });
        }
        *slot = coarse_idx;
    }
    for (face, f) in coarse_faces.iter().enumerate() {
        if let Some(&vertex) = f.iter().find(|&&v| v as usize >= coarse_count) {
            return Err(HierarchyError::FaceOutOfRange { face, vertex, coarse_count });
        }
    }
    Ok(())
}

/// D: the `coarse_to_fine.len() × fine_count` selection with one 1 per row, at column
/// `coarse_to_fine[coarse_idx]`.
pub fn selection(coarse_to_fine: &[u32], fine_count: usize) -> Result<CsrMatrix, HierarchyError> {
    CsrMatrix::from_rows(fine_count, coarse_to_fine.iter().map(|&f| vec![(f, 1.0)]).collect())
}

/// A: the symmetric `vertex_count × vertex_count` vertex adjacency of `faces`, value 1
/// per edge and direction, no diagonal (COMA's `get_vert_connectivity` stores 2 on
/// edges shared by two faces; a plain 0/1 adjacency is what graph convolutions
/// normalise anyway, and what a reader expects of "adjacency").
pub fn adjacency(vertex_count: usize, faces: &[Face]) -> Result<CsrMatrix, HierarchyError> {
    let mut rows: Vec<Vec<(u32, Real)>> = vec![Vec::new(); vertex_count];
    for (face, f) in faces.iter().enumerate() {
        if let Some(&vertex) = f.iter().find(|&&v| v as usize >= vertex_count) {
            return Err(HierarchyError::FaceOutOfRange { face, vertex, coarse_count: vertex_count });
        }
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            if a != b {
                rows[a as usize].push((b, 1.0));
                rows[b as usize].push((a, 1.0));
            }
        }
    }
    for row in &mut rows {
        row.sort_by_key(|&(c, _)| c);
        row.dedup_by_key(|e| e.0);
    }
    CsrMatrix::from_rows(vertex_count, rows)
}

/// `orig{k+1}`: the level-0 vertex of each coarse vertex, from the fine level's
/// `orig{k}` and the coarse level's `map{k+1}` (`coarse_to_fine`). The maps nest by
/// construction: `orig{k+1}[i] = orig{k}[map{k+1}[i]]`. Panics on a `coarse_to_fine`
/// entry past `fine_to_orig` (which [`build_level`] refuses with an error first).
pub fn nest(fine_to_orig: &[u32], coarse_to_fine: &[u32]) -> Vec<u32> {
    coarse_to_fine.iter().map(|&f| fine_to_orig[f as usize]).collect()
}
