//! On-disk payload structs, one per artifact kind and format version. They use plain
//! arrays (no math-library types) so that the byte format depends on nothing but this
//! file; conversions to the in-memory types live beside them.
//!
//! **Invariant:** changing a field here is a format change: bump that kind's version in
//! `ArtifactKind::current_version`, freeze the old struct, add a fixture under
//! `tests/fixtures/` and a test that it still loads or is refused clearly.

use desal_mesh::math::{vec3_from_f32, vec3_to_f32};
use desal_mesh::{MeshError, PartLabels, PoseSet, Vec3};
use serde::{Deserialize, Serialize};

use super::{ArtifactBody, ArtifactKind, Producer};

/// A validated pose set. Positions are stored as f32 (the precision of the source files).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PoseSetV2 {
    pub names: Vec<String>,
    pub template: u32,
    pub faces: Vec<[u32; 3]>,
    /// `positions[pose][vertex]`.
    pub positions: Vec<Vec<[f32; 3]>>,
    /// One group id per pose (`PoseSet::groups`), or empty for none.
    pub groups: Vec<u32>,
}

/// Format version 1 of the pose set, frozen: [`PoseSetV2`] without groups. Read only,
/// by [`PoseSetV2`]'s `decode_older`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PoseSetV1 {
    pub names: Vec<String>,
    pub template: u32,
    pub faces: Vec<[u32; 3]>,
    pub positions: Vec<Vec<[f32; 3]>>,
}

impl ArtifactBody for PoseSetV2 {
    const KIND: ArtifactKind = ArtifactKind::PoseSet;

    fn decode_older(version: u16, payload: &[u8]) -> Result<(Producer, Self), String> {
        debug_assert_eq!(version, 1, "the oldest readable pose set");
        let (producer, old): (Producer, PoseSetV1) = crate::codec::decode(payload)?;
        let PoseSetV1 { names, template, faces, positions } = old;
        Ok((producer, PoseSetV2 { names, template, faces, positions, groups: Vec::new() }))
    }

    fn validate(&self) -> Result<(), String> {
        let poses = self.positions.len();
        expect_len("names", self.names.len(), "poses", poses)?;
        if !self.groups.is_empty() {
            expect_len("groups", self.groups.len(), "poses", poses)?;
        }
        if self.template as usize >= poses {
            return Err(format!("template index {} is out of range for {poses} poses", self.template));
        }
        let vertices = self.positions[self.template as usize].len();
        if vertices == 0 || self.faces.is_empty() {
            return Err(format!("the pose set is empty ({vertices} vertices, {} faces)", self.faces.len()));
        }
        for (pose, p) in self.positions.iter().enumerate() {
            expect_len(&format!("positions of pose {pose}"), p.len(), "template vertices", vertices)?;
            if let Some(v) = p.iter().position(|q| !q.iter().all(|c| c.is_finite())) {
                return Err(format!("vertex {v} of pose {pose} has a non-finite coordinate"));
            }
        }
        check_faces(&self.faces, vertices)
    }
}

impl PoseSetV2 {
    pub fn from_pose_set(set: &PoseSet) -> Self {
        PoseSetV2 {
            names: set.names.clone(),
            template: set.template as u32,
            faces: set.faces.clone(),
            positions: set.poses.iter().map(|p| positions_to_f32(p)).collect(),
            groups: set.groups.clone().unwrap_or_default(),
        }
    }

    /// [`Self::from_pose_set`], consuming the set pose by pose: each pose's f64 array is
    /// freed as its f32 one is made, so a large set is never held at both precisions.
    pub fn from_owned_pose_set(set: PoseSet) -> Self {
        let PoseSet { names, poses, faces, template, groups } = set;
        PoseSetV2 {
            names,
            template: template as u32,
            faces,
            positions: poses.into_iter().map(|p| positions_to_f32(&p)).collect(),
            groups: groups.unwrap_or_default(),
        }
    }

    pub fn to_pose_set(&self) -> Result<PoseSet, MeshError> {
        let poses = self.positions.iter().map(|p| positions_from_f32(p)).collect();
        let groups = (!self.groups.is_empty()).then(|| self.groups.clone());
        PoseSet::try_new(self.names.clone(), poses, self.faces.clone(), self.template as usize)?
            .with_groups(groups)
    }

    /// [`Self::to_pose_set`], consuming the body pose by pose: each pose's f32 array is
    /// freed as its f64 one is made, so a large set is never held at both precisions.
    pub fn into_pose_set(self) -> Result<PoseSet, MeshError> {
        let PoseSetV2 { names, template, faces, positions, groups } = self;
        let poses = positions.into_iter().map(|p| positions_from_f32(&p)).collect();
        let groups = (!groups.is_empty()).then_some(groups);
        PoseSet::try_new(names, poses, faces, template as usize)?.with_groups(groups)
    }
}

fn positions_to_f32(pose: &[Vec3]) -> Vec<[f32; 3]> {
    pose.iter().map(vec3_to_f32).collect()
}

fn positions_from_f32(pose: &[[f32; 3]]) -> Vec<Vec3> {
    pose.iter().map(|&q| vec3_from_f32(q)).collect()
}

/// Part labels validated against a pose set.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct LabelsV1 {
    pub names: Vec<String>,
    pub labels: Vec<u32>,
}

impl ArtifactBody for LabelsV1 {
    const KIND: ArtifactKind = ArtifactKind::Labels;

    fn validate(&self) -> Result<(), String> {
        let parts = self.names.len();
        match self.labels.iter().position(|&p| p as usize >= parts) {
            Some(v) => Err(format!("vertex {v} has part id {}, but there are {parts} parts", self.labels[v])),
            None => Ok(()),
        }
    }
}

impl LabelsV1 {
    pub fn from_labels(labels: &PartLabels) -> Self {
        LabelsV1 { names: labels.names.clone(), labels: labels.labels.clone() }
    }

    pub fn to_labels(&self) -> Result<PartLabels, MeshError> {
        PartLabels::try_new(self.labels.clone(), self.names.clone())
    }
}

/// Stage 1's result: per pose and part, the fitted transform and its residual figures,
/// and every per-vertex residual distance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitV1 {
    /// `rigid` or `affine`.
    pub model: String,
    pub pose_names: Vec<String>,
    pub part_names: Vec<String>,
    pub template: u32,
    pub vertex_count: u32,
    /// Per `(pose, part)`, pose-major (`pose * parts + part`): the 3x3 linear part, row-major.
    pub linear: Vec<[f64; 9]>,
    /// Per `(pose, part)`: the translation.
    pub translation: Vec<[f64; 3]>,
    /// Per `(pose, part)`: RMS, mean and max residual distance (mesh units).
    pub rms: Vec<f64>,
    pub mean: Vec<f64>,
    pub max: Vec<f64>,
    /// Per `(pose, vertex)`, pose-major: residual distance `|R v_T + t - v_X|`.
    pub residuals: Vec<f32>,
    /// Per part, worst first: `(part, mean, max, worst pose)`.
    pub worst_parts: Vec<(u32, f64, f64, u32)>,
    /// Per pose, worst first: `(pose, mean, max, worst part)`.
    pub worst_poses: Vec<(u32, f64, f64, u32)>,
}

impl ArtifactBody for FitV1 {
    const KIND: ArtifactKind = ArtifactKind::Fit;

    fn validate(&self) -> Result<(), String> {
        let poses = self.pose_names.len();
        let parts = self.part_names.len();
        if poses > 0 && self.template as usize >= poses {
            return Err(format!("template index {} is out of range for {poses} poses", self.template));
        }
        let fits = product(poses, parts)?;
        expect_len("linear", self.linear.len(), "poses x parts", fits)?;
        expect_len("translation", self.translation.len(), "poses x parts", fits)?;
        expect_len("rms", self.rms.len(), "poses x parts", fits)?;
        expect_len("mean", self.mean.len(), "poses x parts", fits)?;
        expect_len("max", self.max.len(), "poses x parts", fits)?;
        let residuals = product(poses, self.vertex_count as usize)?;
        expect_len("residuals", self.residuals.len(), "poses x vertices", residuals)?;
        for (k, &(part, _, _, pose)) in self.worst_parts.iter().enumerate() {
            check_index(&format!("worst_parts[{k}]"), "part", part, parts)?;
            check_index(&format!("worst_parts[{k}]"), "pose", pose, poses)?;
        }
        for (k, &(pose, _, _, part)) in self.worst_poses.iter().enumerate() {
            check_index(&format!("worst_poses[{k}]"), "pose", pose, poses)?;
            check_index(&format!("worst_poses[{k}]"), "part", part, parts)?;
        }
        Ok(())
    }
}

/// Stage 2's result, per template vertex.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SaliencyV1 {
    /// Normalised saliency in [0, 1].
    pub saliency: Vec<f64>,
    /// Stage-3 weights in [floor, 1].
    pub weights: Vec<f64>,
    /// Raw per-vertex sums (mesh units, or squared units when `distance` is `squared`).
    pub raw: Vec<f64>,
    pub normaliser: f64,
    /// `plain` or `squared`.
    pub distance: String,
    /// `max` or `p<percentile>`.
    pub normalisation: String,
    pub weight_floor: f64,
    pub poses_used: Vec<String>,
    pub poses_excluded: Vec<String>,
    pub rigid: bool,
}

impl ArtifactBody for SaliencyV1 {
    const KIND: ArtifactKind = ArtifactKind::Saliency;

    fn validate(&self) -> Result<(), String> {
        let vertices = self.saliency.len();
        expect_len("weights", self.weights.len(), "saliency values", vertices)?;
        expect_len("raw", self.raw.len(), "saliency values", vertices)
    }
}

/// Stage 3's result: the simplified template as the simplifier left it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimplifiedV1 {
    /// Positions in `simp_idx` order (f64: optimal placements are new points).
    pub positions: Vec<[f64; 3]>,
    pub faces: Vec<[u32; 3]>,
    /// Per `simp_idx`, the `orig_idx` whose exact position it has (`None`: moved by
    /// optimal placement).
    pub simp_to_orig: Vec<Option<u32>>,
    /// `optimal`, `subset` or `multipose`.
    pub placement: String,
    pub input_vertices: u32,
    pub input_faces: u32,
    pub collapses: u32,
    /// `target` or `no-valid-collapse` (safeguards stopped it above the target).
    pub stop: String,
    pub max_error: f64,
    pub mean_error: f64,
    pub edge_length_mean: f64,
    pub edge_length_variance: f64,
}

impl ArtifactBody for SimplifiedV1 {
    const KIND: ArtifactKind = ArtifactKind::Simplified;

    fn validate(&self) -> Result<(), String> {
        let vertices = self.positions.len();
        expect_len("simp_to_orig", self.simp_to_orig.len(), "positions", vertices)?;
        if let Some(v) = self.positions.iter().position(|q| !q.iter().all(|c| c.is_finite())) {
            return Err(format!("simplified vertex {v} has a non-finite coordinate"));
        }
        for (simp_idx, orig_idx) in self.simp_to_orig.iter().enumerate() {
            if let Some(orig_idx) = *orig_idx {
                let what = format!("simp_to_orig[{simp_idx}]");
                check_index(&what, "original vertex", orig_idx, self.input_vertices as usize)?;
            }
        }
        check_faces(&self.faces, vertices)
    }
}

/// Stage 4's result: each simplified vertex's original vertex, and the simplified
/// triangles (in `simp_idx` space). Applying it to a pose set is a gather.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapV1 {
    /// `simp_to_orig[simp_idx] = orig_idx`, all distinct.
    pub simp_to_orig: Vec<u32>,
    pub faces: Vec<[u32; 3]>,
    /// `greedy` or `subset`.
    pub mode: String,
    /// Distance between the simplified template's positions and the mapped original
    /// vertices (mesh units): mean and max.
    pub displacement_mean: f64,
    pub displacement_max: f64,
}

impl ArtifactBody for MapV1 {
    const KIND: ArtifactKind = ArtifactKind::Map;

    fn validate(&self) -> Result<(), String> {
        let mut sorted = self.simp_to_orig.clone();
        sorted.sort_unstable();
        if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
            return Err(format!("original vertex {} is mapped to twice (the map must be one to one)", w[0]));
        }
        check_faces(&self.faces, self.simp_to_orig.len())
    }
}

/// `Err` unless the array `what` has `len` entries, as many as `of` (`expected`).
fn expect_len(what: &str, len: usize, of: &str, expected: usize) -> Result<(), String> {
    if len == expected {
        return Ok(());
    }
    Err(format!("{what} has {len} entries, but there are {expected} {of}"))
}

/// `Err` unless `index` (the `role` of entry `what`) is below `count`.
fn check_index(what: &str, role: &str, index: u32, count: usize) -> Result<(), String> {
    if (index as usize) < count {
        return Ok(());
    }
    Err(format!("{what} names {role} {index}, but there are only {count}"))
}

/// `a × b` for array sizes, refusing an overflow (only a forged count can overflow).
fn product(a: usize, b: usize) -> Result<usize, String> {
    a.checked_mul(b).ok_or_else(|| format!("{a} x {b} entries overflow"))
}

/// Every face index below `vertices`, named by face (the file's own face numbers).
fn check_faces(faces: &[[u32; 3]], vertices: usize) -> Result<(), String> {
    desal_mesh::validate::check_face_indices(faces, vertices).map_err(|e| e.to_string())
}

/// One level step k → k+1 of a hierarchy (stage `hierarchy`, one artifact per level).
/// Index spaces: `fine_idx` is level k's vertex index, `coarse_idx` level k+1's,
/// `orig_idx` level 0's. D and A are not stored: they follow from `coarse_to_fine` and
/// `faces` (`desal_hierarchy::{selection, adjacency}`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HierarchyLevelV1 {
    /// `fine_vertices = n_k`.
    pub fine_vertices: u32,
    /// `coarse_to_fine[coarse_idx] = fine_idx` (`map{k+1}`), distinct.
    pub coarse_to_fine: Vec<u32>,
    /// `coarse_to_orig[coarse_idx] = orig_idx` (`orig{k+1}`).
    pub coarse_to_orig: Vec<u32>,
    /// The coarse level's triangles, in `coarse_idx`.
    pub faces: Vec<[u32; 3]>,
    /// `fitted` or `barycentric`.
    pub upsampler: String,
    /// U (`n_k × n_{k+1}`) as row-major COO triplets: `up_row` in `fine_idx`, `up_col`
    /// in `coarse_idx`.
    pub up_row: Vec<u32>,
    pub up_col: Vec<u32>,
    pub up_data: Vec<f64>,
}

impl ArtifactBody for HierarchyLevelV1 {
    const KIND: ArtifactKind = ArtifactKind::HierarchyLevel;

    /// Index ranges, one-to-one maps, matching triplet lengths, finite weights.
    fn validate(&self) -> Result<(), String> {
        let (fine, coarse) = (self.fine_vertices as usize, self.coarse_to_fine.len());
        expect_len("coarse_to_orig", self.coarse_to_orig.len(), "coarse vertices", coarse)?;
        let mut sorted = self.coarse_to_fine.clone();
        sorted.sort_unstable();
        if let Some(w) = sorted.windows(2).find(|w| w[0] == w[1]) {
            return Err(format!("fine vertex {} is kept twice (the map must be one to one)", w[0]));
        }
        for (c, &f) in self.coarse_to_fine.iter().enumerate() {
            check_index(&format!("coarse vertex {c}"), "fine vertex", f, fine)?;
        }
        check_faces(&self.faces, coarse)?;
        expect_len("up_col", self.up_col.len(), "up_row entries", self.up_row.len())?;
        expect_len("up_data", self.up_data.len(), "up_row entries", self.up_row.len())?;
        for (k, (&r, &c)) in self.up_row.iter().zip(&self.up_col).enumerate() {
            check_index(&format!("U entry {k}"), "fine row", r, fine)?;
            check_index(&format!("U entry {k}"), "coarse column", c, coarse)?;
        }
        match self.up_data.iter().position(|w| !w.is_finite()) {
            Some(k) => Err(format!("U entry {k} is not finite")),
            None => Ok(()),
        }
    }
}

/// A deformation model's own floor at full resolution (`desal eval`'s cached
/// measurement, `desal_measures::model_floor`): mean v2v and v2f of the model fitted on the
/// full-resolution pose set, in-sample and held out, in squared mesh units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FloorV1 {
    /// `scape`, `lbs`, … (the `--model` name it was measured under).
    pub model: String,
    /// The non-template poses each mean is over.
    pub poses: u32,
    /// The held-out folds used.
    pub folds: u32,
    pub in_sample_v2v: f64,
    pub in_sample_v2f: f64,
    pub held_out_v2v: f64,
    pub held_out_v2f: f64,
}

impl ArtifactBody for FloorV1 {
    const KIND: ArtifactKind = ArtifactKind::Floor;

    /// At least one pose and one fold; every error finite and not negative.
    fn validate(&self) -> Result<(), String> {
        if self.poses == 0 || self.folds == 0 {
            return Err(format!(
                "the floor is over {} poses in {} folds (neither may be 0)",
                self.poses, self.folds
            ));
        }
        let errors = [
            ("in_sample_v2v", self.in_sample_v2v),
            ("in_sample_v2f", self.in_sample_v2f),
            ("held_out_v2v", self.held_out_v2v),
            ("held_out_v2f", self.held_out_v2f),
        ];
        match errors.iter().find(|(_, e)| !(e.is_finite() && *e >= 0.0)) {
            Some((name, e)) => Err(format!("{name} is {e} (an error must be finite and not negative)")),
            None => Ok(()),
        }
    }
}
