//! Building hierarchies for tests, examples and benches the way the driver will: each
//! level simplified from the registered pose set of the level above with subset
//! placement (every coarse vertex an original vertex of the level above), stage 1–2
//! saliency weights for the paper's method, then one `build_level` call per level.
#![allow(dead_code)]

use desal_fit::{FitConfig, fit_pose_set};
use desal_hierarchy::{CsrMatrix, Level, LevelInput, Upsampler, build_level, nest};
use desal_map::{VertexMap, apply_map};
use desal_mesh::{Face, NoProgress, PartLabels, PoseSet};
use desal_saliency::{ResidualTable, SaliencyConfig, compute_saliency};
use desal_simplify::{Placement, SimplifyConfig, SimplifyInput, Target, simplify};

/// The simplification methods compared: COMA's recipe (plain QSlim) and the paper's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    Qslim,
    Paper,
}

/// Whether the paper's saliency is recomputed on each level's own pose set or carried
/// down from level 0 (`weights0[orig{k}]`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SaliencyPerLevel {
    Recompute,
    CarryDown,
}

/// One coarse level's geometry: `coarse_to_fine` (`map{k+1}`), `orig` (`orig{k+1}`),
/// faces, and its registered pose set and labels.
#[derive(Debug, Clone)]
pub struct LevelGeometry {
    pub coarse_to_fine: Vec<u32>,
    pub orig: Vec<u32>,
    pub faces: Vec<Face>,
    pub poses: PoseSet,
    pub labels: PartLabels,
}

/// Stage 1–2 weights of a pose set (the driver's defaults).
pub fn saliency_weights(poses: &PoseSet, labels: &PartLabels) -> Vec<f64> {
    let fit = fit_pose_set(poses, labels, &FitConfig::default(), &NoProgress).expect("fit");
    let table = ResidualTable {
        values: &fit.residuals,
        vertex_count: fit.vertex_count,
        pose_names: &fit.pose_names,
        template: Some(fit.template),
        length_scale: poses.template_mesh().diagonal(),
    };
    compute_saliency(&table, &SaliencyConfig::default()).expect("saliency").weights
}

/// Simplifies level by level to `targets` (vertex counts) with subset placement.
pub fn build_geometry(
    full: &PoseSet,
    labels: &PartLabels,
    targets: &[usize],
    method: Method,
    saliency: SaliencyPerLevel,
) -> Vec<LevelGeometry> {
    let weights0 = (method == Method::Paper).then(|| saliency_weights(full, labels));
    let mut levels: Vec<LevelGeometry> = Vec::new();
    for &target in targets {
        let (fine, fine_labels, fine_orig): (&PoseSet, &PartLabels, Vec<u32>) = match levels.last() {
            None => (full, labels, (0..full.vertex_count() as u32).collect()),
            Some(l) => (&l.poses, &l.labels, l.orig.clone()),
        };
        let weights = match (&weights0, saliency, levels.is_empty()) {
            (None, _, _) => None,
            (Some(w), _, true) => Some(w.clone()),
            (Some(w), SaliencyPerLevel::CarryDown, false) => {
                Some(fine_orig.iter().map(|&o| w[o as usize]).collect())
            }
            (Some(_), SaliencyPerLevel::Recompute, false) => Some(saliency_weights(fine, fine_labels)),
        };
        let template = fine.template_mesh();
        let mut input = SimplifyInput::new(&template);
        if let Some(w) = &weights {
            input = input.with_weights(w);
        }
        let config = SimplifyConfig {
            target: Target::Vertices(target),
            placement: Placement::Subset,
            saliency: method == Method::Paper,
            balance: method == Method::Paper,
            ..SimplifyConfig::default()
        };
        let simplified = simplify(&input, &config).expect("simplify");
        let coarse_to_fine = simplified.subset_indices().expect("subset placement keeps input vertices");
        let map = VertexMap::from_subset(&coarse_to_fine, fine.vertex_count()).expect("subset map");
        let (poses, level_labels) =
            apply_map(fine, fine_labels, &simplified.mesh.faces, &map).expect("apply map");
        levels.push(LevelGeometry {
            orig: nest(&fine_orig, &coarse_to_fine),
            coarse_to_fine,
            faces: simplified.mesh.faces,
            poses,
            labels: level_labels,
        });
    }
    levels
}

/// One `build_level` per level step, with the training flags of `training` (pose
/// indices, shared by every level since levels keep the pose order).
pub fn build_levels(
    full: &PoseSet,
    geometry: &[LevelGeometry],
    training: &[usize],
    up: &Upsampler,
) -> Vec<Level> {
    let mut mask = vec![false; full.pose_count()];
    for &p in training {
        mask[p] = true;
    }
    (0..geometry.len())
        .map(|k| {
            let fine = if k == 0 { full } else { &geometry[k - 1].poses };
            let input = LevelInput {
                fine,
                coarse_to_fine: &geometry[k].coarse_to_fine,
                coarse_faces: &geometry[k].faces,
                training: &mask,
            };
            build_level(&input, up).expect("build level")
        })
        .collect()
}

/// `U_0 · U_1 · … · U_k`: level k+1 upsampled to full resolution.
pub fn composed(levels: &[Level], k: usize) -> CsrMatrix {
    let mut u = levels[0].up.clone();
    for level in &levels[1..=k] {
        u = u.mul(&level.up).expect("levels chain");
    }
    u
}
