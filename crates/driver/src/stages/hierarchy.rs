//! The hierarchy stage (`[dataset.hierarchy]`, `desal hierarchy`): one cached stage per
//! level step k → k+1, each simplified from the registered pose set of the level above
//! with the dataset's stage-1–4 settings (subset placement, so every coarse vertex is a
//! vertex of the level above and the maps nest), then D, U and A from `desal-hierarchy`.
//!
//! Saliency is recomputed on each level's own pose set (`desal-hierarchy`'s crate docs:
//! measured on SCAPE slightly better with the fitted U than carrying level 0's down).
//! `[saliency] exclude` poses stay out of the fitted upsampler's training mask.
//!
//! Each level's summary also holds the held-out upsampling error (m²) of the fitted and
//! the barycentric U, composed to full resolution: [`HELDOUT_FOLDS`] folds by pose index,
//! or, when the pose set has groups, up to [`GROUP_FOLDS`] folds over whole groups (no
//! group of a measured pose is among its fold's training poses); U of every level up to
//! this one refitted on each fold's training poses only. The levels' kept vertices are
//! chosen once, from every pose.
//!
//! Index spaces: `fine_idx` (level k), `coarse_idx` (level k+1), `orig_idx` (level 0).

use std::borrow::Cow;

use anyhow::{Result, bail};
use desal_hierarchy::{
    ChainLevel, Coarse, CsrMatrix, FittedConfig, Knob, Knobs, Level, LevelInput, Neighbourhood, Settled,
    Upsampled, Upsampler, V2f, adjacency, build_level, level_poses, nest, selection, upsamplers_per_mask,
    upsampling_errors,
};
use desal_io::artifact::{ArtifactKind, ContentHash, HierarchyLevelV1};
use desal_io::npz::{CooArrays, HierarchyArrays};
use desal_mesh::{PartLabels, PoseSet, Progress};
use desal_simplify::Placement;
use serde::{Deserialize, Serialize};
use serde_json::json;

use crate::cache::{StageKey, canonical_json};
use crate::stages::chain::{ChainInput, ChainSettings, chain};
use crate::stages::runner::{Scratch, Stage, StageOutput, Staged, Store};
use crate::stages::saliency::SaliencyParams;
use crate::stages::simplify::{Method, SimplifyParams};

/// Folds of the held-out upsampling error: fold `f` measures the poses with
/// `index % HELDOUT_FOLDS == f` and fits on the others (even/odd, as the crate measured).
pub const HELDOUT_FOLDS: usize = 2;

/// Folds of the held-out upsampling error over a pose set with groups: k-fold over whole
/// groups, k = min(5, groups − 1).
pub const GROUP_FOLDS: usize = 5;

/// `upsampler` in `[dataset.hierarchy]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum UpsamplerName {
    /// Pose-aware least squares over the training poses (the default).
    #[default]
    Fitted,
    /// COMA's rule: barycentric coordinates in the template pose.
    Barycentric,
}

/// `neighbourhood` in `[dataset.hierarchy]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum NeighbourhoodName {
    Euclidean,
    Geodesic,
}

/// `[dataset.hierarchy]`: the coarse levels and their upsampler.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct HierarchyParams {
    /// Coarse vertex counts, strictly decreasing, each >= 4 (level 0 is the input).
    pub levels: Vec<usize>,
    #[serde(default)]
    pub upsampler: UpsamplerName,
    /// Fitted only: candidate coarse vertices per fine vertex (default: chosen per fit
    /// by held-out error from `desal_hierarchy::NEIGHBOUR_GRID`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub neighbours: Option<usize>,
    /// Fitted only: relative ridge toward the barycentric row (default: chosen per fit by
    /// held-out error from `desal_hierarchy::RIDGE_GRID`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ridge: Option<f64>,
    /// Fitted only: `euclidean` (default) or `geodesic` candidates.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub neighbourhood: Option<NeighbourhoodName>,
    /// Also measure the held-out upsampling error by v2f (default false: its surface
    /// queries take seconds per level on SCAPE; `desal eval` always measures it).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub heldout_v2f: bool,
}

impl HierarchyParams {
    /// The levels, checked: non-empty, strictly decreasing, each >= 4, and below
    /// `vertex_count` when it is known.
    pub fn check_levels(&self, vertex_count: Option<usize>) -> Result<()> {
        if self.levels.is_empty() {
            bail!("hierarchy: levels is empty: give at least one coarse vertex count");
        }
        if let Some(&n) = self.levels.iter().find(|&&n| n < 4) {
            bail!("hierarchy: level of {n} vertices is too small: the simplest closed surface has 4");
        }
        if let Some(w) = self.levels.windows(2).find(|w| w[1] >= w[0]) {
            bail!("hierarchy: levels must be strictly decreasing, but {} is followed by {}", w[0], w[1]);
        }
        if let Some(n) = vertex_count
            && self.levels[0] >= n
        {
            bail!("hierarchy: the first level ({}) must be below the input's {n} vertices", self.levels[0]);
        }
        Ok(())
    }

    /// The upsampler these parameters resolve to, validated (the fitted-only keys are
    /// refused with `barycentric`).
    pub fn config(&self) -> Result<Upsampler> {
        self.check_levels(None)?;
        let up = match self.upsampler {
            UpsamplerName::Barycentric => {
                if self.neighbours.is_some() || self.ridge.is_some() || self.neighbourhood.is_some() {
                    bail!(
                        "hierarchy: neighbours, ridge and neighbourhood apply to the fitted upsampler only"
                    );
                }
                Upsampler::Barycentric
            }
            UpsamplerName::Fitted => {
                let d = FittedConfig::default();
                Upsampler::Fitted(FittedConfig {
                    neighbours: self.neighbours.map_or(d.neighbours, Knob::Given),
                    ridge: self.ridge.map_or(d.ridge, Knob::Given),
                    neighbourhood: match self.neighbourhood {
                        None => d.neighbourhood,
                        Some(NeighbourhoodName::Euclidean) => Neighbourhood::Euclidean,
                        Some(NeighbourhoodName::Geodesic) => Neighbourhood::Geodesic,
                    },
                })
            }
        };
        up.validate().map_err(|e| anyhow::anyhow!("hierarchy: {e}"))?;
        Ok(up)
    }
}

/// The dataset's settings a level is simplified with.
#[derive(Debug, Clone, Copy)]
pub struct LevelSettings<'a> {
    /// Stages 1–3, as for level 0.
    pub chain: ChainSettings<'a>,
    pub hierarchy: &'a HierarchyParams,
}

impl LevelSettings<'_> {
    /// Stage 3's parameters for level `step + 1`: the dataset's, with this level's target
    /// and subset placement (a `<cost>-optimal` method becomes its `<cost>-subset`).
    fn simplify_params(&self, step: usize) -> SimplifyParams {
        let method = match self.chain.simplify.method {
            Some(Method::Quadric { cost, .. }) => {
                Some(Method::Quadric { cost, placement: Placement::Subset })
            }
            method => method,
        };
        SimplifyParams {
            target_vertices: Some(self.hierarchy.levels[step]),
            target_faces: None,
            ratio: None,
            placement: Placement::Subset,
            method,
            ..self.chain.simplify.clone()
        }
    }

    /// The cache key of level step `step` (→ level `step + 1`): the pose set and labels,
    /// the parent level's artifact (for `step > 0`), this level's target, the resolved
    /// stage-1/2/3 settings it is simplified with, and the resolved upsampler.
    pub fn key(
        &self,
        step: usize,
        poses: ContentHash,
        labels: ContentHash,
        parent: Option<ContentHash>,
    ) -> Result<StageKey> {
        let simplify = self.simplify_params(step).key(poses, poses, labels)?;
        let fit = self.chain.fit.key(poses, labels);
        let saliency = self.chain.saliency.key(poses, poses)?;
        let mut inputs = vec![("poses".to_owned(), poses), ("labels".to_owned(), labels)];
        if let Some(parent) = parent {
            inputs.push(("parent".into(), parent));
        }
        Ok(StageKey {
            // One name per level: the cache records the last key per stage name, so
            // `--explain` compares level k with level k's last run, not with level k−1.
            stage: format!("hierarchy-{}", step + 1),
            stage_version: desal_hierarchy::VERSION,
            format_version: ArtifactKind::HierarchyLevel.current_version(),
            parameters: canonical_json(&json!({
                "level": step + 1,
                "vertices": self.hierarchy.levels[step],
                "upsampler": self.hierarchy.upsampler,
                "neighbours": self.hierarchy.neighbours,
                "ridge": self.hierarchy.ridge,
                "neighbourhood": self.hierarchy.neighbourhood,
                "heldout_v2f": self.hierarchy.heldout_v2f,
            })),
            resolved: canonical_json(&json!({
                "level": step + 1,
                "upsampler": upsampler_json(&self.hierarchy.config()?),
                "heldout_folds": HELDOUT_FOLDS,
                "heldout_v2f": self.hierarchy.heldout_v2f,
                "fit": fit.resolved,
                "saliency": saliency.resolved,
                "simplify": simplify.resolved,
            })),
            inputs,
        })
    }
}

/// The fitted upsampler that held-out measurements (here and in `desal eval`) compare
/// with COMA's: the dataset's fitted configuration, or the default one when the dataset
/// has no hierarchy or uses the barycentric upsampler.
pub fn measured_fitted(params: Option<&HierarchyParams>) -> Result<Upsampler> {
    Ok(match params.map(HierarchyParams::config).transpose()? {
        Some(Upsampler::Fitted(c)) => Upsampler::Fitted(c),
        _ => Upsampler::default(),
    })
}

/// Every field of the upsampler configuration, destructured exhaustively.
fn upsampler_json(up: &Upsampler) -> serde_json::Value {
    match up {
        Upsampler::Barycentric => json!("barycentric"),
        Upsampler::Fitted(FittedConfig { neighbours, neighbourhood, ridge }) => json!({
            "fitted": {
                "neighbours": knob_json(neighbours),
                "ridge": knob_json(ridge),
                "neighbourhood": match neighbourhood {
                    Neighbourhood::Euclidean => "euclidean",
                    Neighbourhood::Geodesic => "geodesic",
                },
            }
        }),
    }
}

/// A given knob's value, or `"held-out"` (chosen per fit).
fn knob_json<T: Serialize>(knob: &Knob<T>) -> serde_json::Value {
    match knob {
        Knob::Given(v) => json!(v),
        Knob::HeldOut => json!("held-out"),
    }
}

/// The fitted upsampler's knobs as a level's U used them, and how they were settled.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct KnobsSummary {
    pub neighbours: usize,
    pub ridge: f64,
    /// `given`, `held-out` (the grid point of lowest held-out error on the level's
    /// training poses) or `fallback` (too few poses or groups for two folds).
    pub settled: String,
    /// Held out only: the folds, the fine vertices measured and every grid point tried,
    /// its held-out error relative to the chosen point's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub folds: Option<usize>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rows: Option<usize>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub grid: Vec<KnobPoint>,
}

/// One grid point of [`KnobsSummary`].
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct KnobPoint {
    pub neighbours: usize,
    pub ridge: f64,
    /// Its held-out error over the chosen point's (1 at the chosen point).
    pub relative_error: f64,
}

impl KnobsSummary {
    fn of(knobs: &Knobs) -> Self {
        let (settled, folds, rows, grid) = match &knobs.settled {
            Settled::Given => ("given", None, None, Vec::new()),
            Settled::TooFewPoses => ("fallback", None, None, Vec::new()),
            Settled::HeldOut { folds, rows, grid } => {
                let best = grid
                    .iter()
                    .find(|p| p.neighbours == knobs.neighbours && p.ridge == knobs.ridge)
                    .map_or(1.0, |p| p.sse);
                let points = grid
                    .iter()
                    .map(|p| KnobPoint {
                        neighbours: p.neighbours,
                        ridge: p.ridge,
                        relative_error: if best > 0.0 { p.sse / best } else { 1.0 },
                    })
                    .collect();
                ("held-out", Some(*folds), Some(*rows), points)
            }
        };
        Self { neighbours: knobs.neighbours, ridge: knobs.ridge, settled: settled.into(), folds, rows, grid }
    }
}

/// Held-out upsampling error of one upsampler, composed to full resolution, m².
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct HeldOutError {
    /// Means over every measured pose (`v2f`: `None` unless `heldout_v2f`).
    pub mse: f64,
    pub v2f: Option<f64>,
    pub folds: Vec<FoldError>,
    /// Per full-resolution vertex, the squared distance averaged over every measured
    /// pose (each in its own fold), m²: the map of `upsampling-error.png`. Kept in the
    /// cached summary, left out of `hierarchy.json` (see [`HierarchyReport`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub vertex_mse: Vec<f32>,
}

/// One fold of [`HeldOutError`].
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FoldError {
    pub fold: usize,
    pub training_poses: usize,
    pub measured_poses: usize,
    pub mse: f64,
    pub v2f: Option<f64>,
}

/// `hierarchy.json`'s entry for one level step k → k+1 (the stage's summary).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LevelSummary {
    /// k + 1.
    pub level: usize,
    pub fine_vertices: usize,
    pub vertices: usize,
    pub faces: usize,
    pub upsampler: String,
    /// Poses U was fitted on (0 for barycentric).
    pub training_poses: usize,
    pub up_nnz: usize,
    pub down_nnz: usize,
    pub adjacency_nnz: usize,
    pub up_mean_row_nnz: f64,
    /// Largest `|row sum − 1|` of U.
    pub up_max_row_sum_error: f64,
    /// The fitted upsampler's knobs (`None` for barycentric).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub knobs: Option<KnobsSummary>,
    /// Wall time of simplify + map + saliency + U of this level, seconds (held-out
    /// measurement excluded).
    pub seconds: f64,
    /// Of which building D, U and A.
    pub matrices_seconds: f64,
    /// Wall time of the held-out measurement (every fold's U refitted, both upsamplers
    /// measured), seconds.
    pub heldout_seconds: f64,
    /// Held out, composed to full resolution: the fitted U (the dataset's fitted
    /// configuration, or the default one when the dataset uses barycentric) and COMA's.
    pub heldout_fitted: HeldOutError,
    pub heldout_barycentric: HeldOutError,
    /// `heldout_fitted.mse / heldout_barycentric.mse`.
    pub heldout_mse_ratio: f64,
}

impl LevelSummary {
    /// The level's line in the run's table and on `desal hierarchy`'s stderr.
    pub fn note(&self) -> String {
        format!(
            "level {}: {} -> {} vertices, {} U ({}{} nnz), held-out MSE fitted {:.3e} / barycentric {:.3e} m² = {:.3}, {:.2} s (+ {:.2} s held out)",
            self.level,
            self.fine_vertices,
            self.vertices,
            self.upsampler,
            self.knobs.as_ref().map_or(String::new(), |k| format!(
                "{} neighbours, ridge {:e} ({}), ",
                k.neighbours, k.ridge, k.settled
            )),
            self.up_nnz,
            self.heldout_fitted.mse,
            self.heldout_barycentric.mse,
            self.heldout_mse_ratio,
            self.seconds,
            self.heldout_seconds
        )
    }
}

/// Level `parents.len()`'s registered pose set and labels, gathered from level 0 at its
/// `coarse_to_orig` (level 0 itself, borrowed, when `parents` is empty: a model source's
/// pose set can be gigabytes).
fn level_pose_set<'a>(
    full: &'a PoseSet,
    labels: &'a PartLabels,
    parent: Option<&HierarchyLevelV1>,
) -> Result<(Cow<'a, PoseSet>, Cow<'a, PartLabels>)> {
    let Some(p) = parent else { return Ok((Cow::Borrowed(full), Cow::Borrowed(labels))) };
    let set = level_poses(full, &p.coarse_to_orig, &p.faces)?;
    let labels = PartLabels {
        labels: p.coarse_to_orig.iter().map(|&o| labels.labels[o as usize]).collect(),
        names: labels.names.clone(),
        parents: labels.parents.clone(),
    };
    Ok((Cow::Owned(set), Cow::Owned(labels)))
}

/// The training mask of the output U: every pose but `[saliency] exclude`'s.
fn training_mask(set: &PoseSet, saliency: &SaliencyParams) -> Vec<bool> {
    set.names.iter().map(|n| !saliency.exclude.contains(n)).collect()
}

fn upsampler_matrix(level: &HierarchyLevelV1) -> Result<CsrMatrix> {
    let mut rows: Vec<Vec<(u32, f64)>> = vec![Vec::new(); level.fine_vertices as usize];
    for ((&r, &c), &v) in level.up_row.iter().zip(&level.up_col).zip(&level.up_data) {
        rows[r as usize].push((c, v));
    }
    Ok(CsrMatrix::from_rows(level.coarse_to_fine.len(), rows)?)
}

/// Every coarse level of `settings.hierarchy`, level 1 first, each one stage of `store`
/// simplified from the level above (the level loop of `desal run`, `desal hierarchy`
/// and the Python package). `input` is level 0's pose set and labels (its seams are not
/// used: a level is simplified without them).
pub fn levels(
    store: &mut impl Store,
    settings: &LevelSettings,
    input: &ChainInput,
    progress: &dyn Progress,
) -> Result<Vec<Staged<HierarchyLevelV1, LevelSummary>>> {
    let mut levels: Vec<Staged<HierarchyLevelV1, LevelSummary>> = Vec::new();
    for step in 0..settings.hierarchy.levels.len() {
        let level = store.stage(
            Stage::Hierarchy,
            || {
                let (poses, labels) = input.hashes()?;
                let parent = levels.last().map(|l| l.hash()).transpose()?;
                settings.key(step, poses, labels, parent)
            },
            &[],
            || {
                let parents = levels.iter().map(|l| l.body()).collect::<Result<Vec<_>>>()?;
                compute_level(settings, (input.set)()?, (input.labels)()?, &parents, progress)
            },
        )?;
        levels.push(level);
    }
    Ok(levels)
}

/// Computes level step `parents.len()` (→ level `parents.len() + 1`); `parents` are the
/// artifacts of levels 1..=k, in order.
pub fn compute_level(
    settings: &LevelSettings,
    full: &PoseSet,
    labels: &PartLabels,
    parents: &[&HierarchyLevelV1],
    progress: &dyn Progress,
) -> Result<StageOutput<HierarchyLevelV1, LevelSummary>> {
    let start = std::time::Instant::now();
    let step = parents.len();
    settings.hierarchy.check_levels(Some(full.vertex_count()))?;
    let (body, level) = build_coarse_level(settings, step, full, labels, parents.last().copied(), progress)?;
    let seconds = start.elapsed().as_secs_f64();

    let mut levels: Vec<&HierarchyLevelV1> = parents.to_vec();
    levels.push(&body);
    let fitted = measured_fitted(Some(settings.hierarchy))?;
    let heldout_start = std::time::Instant::now();
    let v2f = if settings.hierarchy.heldout_v2f { V2f::Measure } else { V2f::Skip };
    let [heldout_fitted, heldout_barycentric] =
        heldout(full, &levels, [&fitted, &Upsampler::Barycentric], settings.chain.saliency, v2f)?;
    let r = &level.report;
    let summary = LevelSummary {
        level: step + 1,
        fine_vertices: r.fine_vertices,
        vertices: r.coarse_vertices,
        faces: r.coarse_faces,
        upsampler: r.upsampler.into(),
        training_poses: r.training_poses,
        up_nnz: r.up_nnz,
        down_nnz: level.down.nnz(),
        adjacency_nnz: level.coarse_adjacency.nnz(),
        up_mean_row_nnz: r.up_mean_row_nnz,
        up_max_row_sum_error: r.up_max_row_sum_error,
        knobs: r.knobs.as_ref().map(KnobsSummary::of),
        seconds,
        matrices_seconds: r.seconds,
        heldout_seconds: heldout_start.elapsed().as_secs_f64(),
        heldout_mse_ratio: heldout_fitted.mse / heldout_barycentric.mse,
        heldout_fitted,
        heldout_barycentric,
    };
    let note = summary.note();
    Ok(StageOutput { body, summary, note })
}

/// Level step `step`'s artifact and matrices: stages 1–4 on the pose set of the level
/// above (`parent`, level 0 when `None`), then D, U and A. That pose set and the stages'
/// results are dropped on return, before the held-out measurement, which reads level 0.
fn build_coarse_level(
    settings: &LevelSettings,
    step: usize,
    full: &PoseSet,
    labels: &PartLabels,
    parent: Option<&HierarchyLevelV1>,
    progress: &dyn Progress,
) -> Result<(HierarchyLevelV1, Level)> {
    let upsampler = settings.hierarchy.config()?;
    let (fine, fine_labels) = level_pose_set(full, labels, parent)?;

    // Stages 1–4 on this level's pose set, as on level 0, in memory (`Scratch`: stage
    // 1's residuals go once stage 2 has them): the level is one cached stage.
    let params = settings.simplify_params(step);
    let input = ChainInput {
        set: &|| Ok(&fine),
        labels: &|| Ok(&fine_labels),
        hashes: None,
        seams: None,
        meshes: None,
    };
    let stages =
        chain(&mut Scratch, ChainSettings { simplify: &params, ..settings.chain }, &input, progress)?;
    let coarse_to_fine = stages.map.body()?.simp_to_orig.clone();
    let faces = stages.simplified.body()?.faces.clone();
    // Only the map is read on: stage 1's residuals go back before U's fit.
    drop(stages);

    let mask = training_mask(&fine, settings.chain.saliency);
    let input =
        LevelInput { fine: &fine, coarse_to_fine: &coarse_to_fine, coarse_faces: &faces, training: &mask };
    let level = build_level(&input, &upsampler)?;
    let fine_to_orig: Vec<u32> = match parent {
        Some(p) => p.coarse_to_orig.clone(),
        None => (0..full.vertex_count() as u32).collect(),
    };
    let coo = level.up.to_coo();
    let body = HierarchyLevelV1 {
        fine_vertices: fine.vertex_count() as u32,
        coarse_to_orig: nest(&fine_to_orig, &coarse_to_fine),
        coarse_to_fine,
        faces,
        upsampler: upsampler.name().into(),
        up_row: coo.row,
        up_col: coo.col,
        up_data: coo.data,
    };
    Ok((body, level))
}

/// The poses each fold of the held-out upsampling error measures (the others train):
/// with groups, whole groups ([`GROUP_FOLDS`] folds at most, the template's group always
/// training: `desal_measures::group_folds`); without, [`HELDOUT_FOLDS`] folds by pose
/// index.
pub fn heldout_folds(full: &PoseSet) -> Vec<Vec<usize>> {
    match full.groups {
        Some(_) => desal_measures::pose_set_folds(full, GROUP_FOLDS),
        None => (0..HELDOUT_FOLDS)
            .map(|f| (0..full.pose_count()).filter(|p| p % HELDOUT_FOLDS == f).collect())
            .collect(),
    }
}

/// The held-out upsampling error of the last level of `chain` with each of `upsamplers`,
/// composed to full resolution: per fold ([`HELDOUT_FOLDS`], by pose index), every
/// level's U refitted on that fold's training poses, all upsamplers measured on the
/// fold's poses in one pass. A barycentric chain does not depend on the training poses
/// (template only), so it is built once for every fold.
fn heldout<const N: usize>(
    full: &PoseSet,
    chain: &[&HierarchyLevelV1],
    upsamplers: [&Upsampler; N],
    saliency: &SaliencyParams,
    v2f: V2f,
) -> Result<[HeldOutError; N]> {
    let all = training_mask(full, saliency);
    let levels: Vec<ChainLevel> = chain
        .iter()
        .map(|l| ChainLevel { coarse_to_fine: &l.coarse_to_fine, coarse_faces: &l.faces })
        .collect();
    let last = chain.last().expect("non-empty chain");
    let folds_measured: Vec<(usize, Vec<usize>)> =
        heldout_folds(full).into_iter().enumerate().filter(|(_, measured)| !measured.is_empty()).collect();
    let masks: Vec<Vec<bool>> = folds_measured
        .iter()
        .map(|(_, measured)| (0..full.pose_count()).map(|p| all[p] && !measured.contains(&p)).collect())
        .collect();
    let mask_refs: Vec<&[bool]> = masks.iter().map(Vec::as_slice).collect();
    // Per upsampler, per fold, every level's U (not composed: the measurement applies
    // them level by level). The folds of a fitted upsampler are fitted together, sharing
    // their sums over poses; a barycentric chain does not depend on the training poses
    // (template only), so it is built once for every fold.
    let per_fold: Vec<Vec<Vec<CsrMatrix>>> = upsamplers
        .iter()
        .map(|up| match up {
            Upsampler::Barycentric => Ok(upsamplers_per_mask(full, &levels, &[&all], up)?),
            Upsampler::Fitted(_) => Ok(upsamplers_per_mask(full, &levels, &mask_refs, up)?),
        })
        .collect::<Result<_>>()?;
    let mut folds: [Vec<FoldError>; N] = std::array::from_fn(|_| Vec::new());
    let mut vertex_sums: [Vec<f64>; N] = std::array::from_fn(|_| vec![0.0; full.vertex_count()]);
    for (slot, ((fold, measured), mask)) in folds_measured.into_iter().zip(&masks).enumerate() {
        let candidates: Vec<Upsampled> = per_fold
            .iter()
            .map(|chains| Upsampled {
                // One chain for every fold (barycentric), or one per fold.
                up_to_full: &chains[if chains.len() == 1 { 0 } else { slot }],
                coarse: Coarse::GroundTruth(&last.coarse_to_orig),
            })
            .collect();
        let errors = upsampling_errors(full, &measured, &candidates, v2f)?;
        for (k, e) in errors.iter().enumerate() {
            for (sum, v) in vertex_sums[k].iter_mut().zip(&e.vertex_mse) {
                *sum += v * measured.len() as f64;
            }
            folds[k].push(FoldError {
                fold,
                training_poses: mask.iter().filter(|&&m| m).count(),
                measured_poses: measured.len(),
                mse: e.mse,
                v2f: e.v2f,
            });
        }
    }
    let mut vertex_sums = vertex_sums.into_iter();
    Ok(folds.map(|folds| {
        let n = folds.iter().map(|f| f.measured_poses).sum::<usize>().max(1) as f64;
        let weighted = |x: f64, f: &FoldError| x * f.measured_poses as f64;
        let sums = vertex_sums.next().expect("one per upsampler");
        HeldOutError {
            mse: folds.iter().map(|f| weighted(f.mse, f)).sum::<f64>() / n,
            v2f: folds.iter().map(|f| f.v2f.map(|v| weighted(v, f))).sum::<Option<f64>>().map(|v| v / n),
            folds,
            vertex_mse: sums.iter().map(|s| (s / n) as f32).collect(),
        }
    }))
}

/// `hierarchy.json`: the level counts and every level step's summary, without the
/// per-vertex error maps (those are `upsampling-error.png`/`.ply`).
#[derive(Debug, Clone, Serialize)]
pub struct HierarchyReport<'a> {
    /// Vertex count of each level, level 0 first.
    pub levels: Vec<usize>,
    pub upsampler: &'a str,
    /// Folds of the held-out figures (the first step's).
    pub heldout_folds: usize,
    /// The pose set's group count when the folds hold out whole groups.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heldout_groups: Option<usize>,
    pub steps: Vec<LevelSummary>,
}

impl<'a> HierarchyReport<'a> {
    /// `groups`: the pose set's group count, when it has groups.
    pub fn new<'s>(
        levels: Vec<usize>,
        upsampler: &'a str,
        groups: Option<usize>,
        steps: impl IntoIterator<Item = &'s LevelSummary>,
    ) -> Self {
        let steps = steps
            .into_iter()
            .map(|s| {
                let mut s = s.clone();
                s.heldout_fitted.vertex_mse.clear();
                s.heldout_barycentric.vertex_mse.clear();
                s
            })
            .collect::<Vec<LevelSummary>>();
        let heldout_folds = steps.first().map_or(HELDOUT_FOLDS, |s| s.heldout_fitted.folds.len());
        Self { levels, upsampler, heldout_folds, heldout_groups: groups, steps }
    }
}

/// The npz arrays of a hierarchy: level 0 (`full`'s vertex count and faces) and the level
/// artifacts in order.
pub fn npz_arrays(
    full_vertices: usize,
    full_faces: &[[u32; 3]],
    levels: &[&HierarchyLevelV1],
) -> Result<HierarchyArrays> {
    let coo = |m: &CsrMatrix| {
        let c = m.to_coo();
        CooArrays { shape: [c.rows, c.cols], row: c.row, col: c.col, data: c.data }
    };
    let mut h = HierarchyArrays {
        levels: vec![full_vertices],
        faces: vec![full_faces.to_vec()],
        adjacency: vec![coo(&adjacency(full_vertices, full_faces)?)],
        down: Vec::new(),
        up: Vec::new(),
        map: Vec::new(),
        orig: Vec::new(),
    };
    for level in levels {
        let n = level.coarse_to_fine.len();
        h.levels.push(n);
        h.faces.push(level.faces.clone());
        h.adjacency.push(coo(&adjacency(n, &level.faces)?));
        h.down.push(coo(&selection(&level.coarse_to_fine, level.fine_vertices as usize)?));
        h.up.push(coo(&upsampler_matrix(level)?));
        h.map.push(level.coarse_to_fine.clone());
        h.orig.push(level.coarse_to_orig.clone());
    }
    Ok(h)
}

/// `desal inspect` lines for a hierarchy-level artifact.
pub fn describe(l: &HierarchyLevelV1, out: &mut String) {
    use std::fmt::Write as _;
    let _ = writeln!(
        out,
        "    {} -> {} vertices, {} faces; {} U with {} entries",
        l.fine_vertices,
        l.coarse_to_fine.len(),
        l.faces.len(),
        l.upsampler,
        l.up_data.len()
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stages::fit::FitParams;

    fn params(levels: Vec<usize>) -> HierarchyParams {
        HierarchyParams {
            levels,
            upsampler: UpsamplerName::Fitted,
            neighbours: None,
            ridge: None,
            neighbourhood: None,
            heldout_v2f: false,
        }
    }

    /// Levels must be strictly decreasing, >= 4 and below the input: each rule refuses.
    #[test]
    fn levels_are_checked() {
        assert!(params(vec![2500, 625]).check_levels(Some(12500)).is_ok());
        let err = |p: HierarchyParams, n| p.check_levels(n).unwrap_err().to_string();
        assert!(err(params(vec![]), None).contains("empty"));
        assert!(err(params(vec![625, 625]), None).contains("strictly decreasing"));
        assert!(err(params(vec![100, 3]), None).contains("too small"));
        assert!(err(params(vec![12500]), Some(12500)).contains("below the input"));
    }

    /// The fitted-only keys are refused with the barycentric upsampler, and every resolved
    /// upsampler option changes the key.
    #[test]
    fn upsampler_options_are_checked_and_enter_the_key() {
        let bary =
            HierarchyParams { upsampler: UpsamplerName::Barycentric, ridge: Some(0.1), ..params(vec![10]) };
        assert!(bary.config().unwrap_err().to_string().contains("fitted upsampler only"));
        let (fit, sal, simp) = (FitParams::default(), SaliencyParams::default(), SimplifyParams::default());
        let h = ContentHash::of(b"poses");
        let full_key = |hp: &HierarchyParams| {
            let chain = ChainSettings { fit: &fit, saliency: &sal, simplify: &simp };
            let settings = LevelSettings { chain, hierarchy: hp };
            settings.key(0, h, h, None).unwrap()
        };
        let key = |hp: &HierarchyParams| full_key(hp).hash();
        // As for every stage, a default given explicitly resolves to the same config (it
        // is only recorded among the user's parameters).
        let explicit =
            HierarchyParams { neighbourhood: Some(NeighbourhoodName::Euclidean), ..params(vec![10]) };
        assert_eq!(
            full_key(&params(vec![10])).resolved,
            full_key(&explicit).resolved,
            "euclidean is the default"
        );
        let base = key(&params(vec![10]));
        // Neighbours and ridge are chosen by default: the former fixed values are other keys.
        assert_ne!(base, key(&HierarchyParams { neighbours: Some(16), ..params(vec![10]) }));
        assert_ne!(base, key(&HierarchyParams { ridge: Some(3e-3), ..params(vec![10]) }));
        assert_ne!(base, key(&HierarchyParams { neighbours: Some(8), ..params(vec![10]) }));
        assert_ne!(base, key(&HierarchyParams { ridge: Some(0.0), ..params(vec![10]) }));
        assert_ne!(
            base,
            key(&HierarchyParams { neighbourhood: Some(NeighbourhoodName::Geodesic), ..params(vec![10]) })
        );
        assert_ne!(base, key(&HierarchyParams { upsampler: UpsamplerName::Barycentric, ..params(vec![10]) }));
        assert_ne!(base, key(&params(vec![11])));
        assert_ne!(base, key(&HierarchyParams { heldout_v2f: true, ..params(vec![10]) }));
        // Level 1's key does not depend on later levels.
        assert_eq!(base, key(&params(vec![10, 5])));
    }
}
