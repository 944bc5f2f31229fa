//! Deformation saliency (paper §3.1): per vertex, the sum over the poses of the residual
//! distance left by the per-part rigid fit, normalised to `[0, 1]`, and the stage-3
//! weight derived from it.
//!
//! The story:
//! 1. choose the contributing poses (all but the template and the excluded ones);
//! 2. sum each vertex's residuals (or squared residuals) over those poses: `raw`;
//! 3. pick the normaliser: the largest sum, or a high percentile of the sums, which is
//!    robust to one broken pose inflating a handful of vertices;
//! 4. `saliency = min(raw / normaliser, 1)`, or all zero when the set is rigid;
//! 5. `weight = floor + (1 − floor) · saliency`.
//!
//! Dividing by the normaliser (rather than min–max scaling) keeps zero meaningful:
//! saliency 0 means "moves perfectly rigidly with its part in every pose".

use desal_mesh::math::Real;
use rayon::prelude::*;

use crate::error::SaliencyError;

/// Default [`SaliencyConfig::weight_floor`]: the weight of a vertex with zero saliency,
/// relative to the most salient vertex's weight of 1. Chosen by measurement
/// (docs/KNOBS.md): the lowest floor at which the skinned sample's held-out deformation
/// errors stay level with plain QSlim's (lower floors thin out its rigid hands: floor 0
/// costs +12 % to +20 % v2f there), keeping most of SCAPE's gain from low floors.
pub const DEFAULT_WEIGHT_FLOOR: Real = 0.05;

/// The stage-3 weight of a vertex of saliency `saliency` under `floor`:
/// `floor + (1 − floor) · saliency` (the one place this formula is written).
pub fn weight(saliency: Real, floor: Real) -> Real {
    floor + (1.0 - floor) * saliency
}

/// A borrowed view of stage 1's residual table, so that this crate needs no dependency
/// on `desal-fit`.
#[derive(Debug, Clone, Copy)]
pub struct ResidualTable<'a> {
    /// Residual distances in mesh units, row-major by pose:
    /// `values[pose * vertex_count + vertex]`.
    pub values: &'a [f32],
    /// Vertices per pose.
    pub vertex_count: usize,
    /// One name per pose, in pose order.
    pub pose_names: &'a [String],
    /// The template pose, which never contributes (it fits itself exactly); `None` when
    /// the template is not one of the rows.
    pub template: Option<usize>,
    /// A characteristic length of the mesh in mesh units (e.g. the template's
    /// bounding-box diagonal); [`SaliencyConfig::rigid_tolerance`] is relative to it.
    pub length_scale: Real,
}

/// What is summed per vertex and pose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Distance {
    /// The residual distance `‖R v_T + t − v_X‖` (the paper). Raw sums in mesh units.
    #[default]
    Plain,
    /// The squared residual distance: stresses large deviations. Raw sums in squared
    /// mesh units.
    Squared,
}

/// How the raw sums are scaled into `[0, 1]`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Normalisation {
    /// Divide by the largest raw sum (the paper).
    #[default]
    Max,
    /// Divide by this percentile (in `(0, 100]`, nearest-rank definition) of the raw
    /// sums and clamp to 1. `Percentile(99.0)` keeps one broken pose, which inflates a
    /// few vertices, from squashing everyone else's saliency towards 0.
    Percentile(Real),
}

/// Parameters of stage 2.
#[derive(Debug, Clone, PartialEq)]
pub struct SaliencyConfig {
    /// Plain or squared distances; default [`Distance::Plain`] (the paper).
    pub distance: Distance,
    /// Normaliser; default [`Normalisation::Max`] (the paper).
    pub normalisation: Normalisation,
    /// Names of poses to leave out (e.g. a broken scan). Default: none. Naming a pose
    /// that does not exist is an error, so a typo cannot pass silently.
    pub exclude_poses: Vec<String>,
    /// Weight of a zero-saliency vertex, in `[0, 1]`: `w = floor + (1 − floor) · s`.
    /// Default [`DEFAULT_WEIGHT_FLOOR`] (0.05). A floor of 0 would make collapses among
    /// rigid vertices free, so stage 3 would erase rigid regions first and at any cost.
    pub weight_floor: Real,
    /// The pose set counts as rigid — saliency 0 everywhere, every weight equal to the
    /// floor — when the normaliser, as a per-pose distance, is at most this fraction of
    /// [`ResidualTable::length_scale`]. Default `1e-6`: above `f32` rounding of the
    /// input coordinates, far below any real deformation, so that floating-point noise
    /// is never normalised up into a full-range saliency map.
    pub rigid_tolerance: Real,
}

impl Default for SaliencyConfig {
    fn default() -> Self {
        Self {
            distance: Distance::Plain,
            normalisation: Normalisation::Max,
            exclude_poses: Vec::new(),
            weight_floor: DEFAULT_WEIGHT_FLOOR,
            rigid_tolerance: 1e-6,
        }
    }
}

/// Per-vertex saliency and stage-3 weights. Every vector is indexed by vertex (the
/// template's vertex index space).
#[derive(Debug, Clone, PartialEq)]
pub struct Saliency {
    /// Normalised saliency in `[0, 1]`.
    pub saliency: Vec<Real>,
    /// Stage-3 weights `floor + (1 − floor) · saliency`, in `[floor, 1]`.
    pub weights: Vec<Real>,
    /// Raw per-vertex sums over the contributing poses: mesh units for
    /// [`Distance::Plain`], squared mesh units for [`Distance::Squared`].
    pub raw: Vec<Real>,
    /// The value `raw` was divided by (same units as `raw`).
    pub normaliser: Real,
    /// Parameters and summary figures, for the artifact's sidecar.
    pub report: SaliencyReport,
}

/// What was done and what came out, for reports.
#[derive(Debug, Clone, PartialEq)]
pub struct SaliencyReport {
    pub distance: Distance,
    pub normalisation: Normalisation,
    pub weight_floor: Real,
    /// Names of the poses that were summed, in pose order.
    pub poses_used: Vec<String>,
    /// Names of the poses left out on request, in pose order (the template is not listed).
    pub poses_excluded: Vec<String>,
    /// Smallest, largest and mean raw sum (units of `raw`).
    pub raw_min: Real,
    pub raw_max: Real,
    pub raw_mean: Real,
    /// Vertices whose raw sum exceeds the normaliser and were clamped to saliency 1
    /// (always 0 with [`Normalisation::Max`]).
    pub saturated_vertices: usize,
    /// True when the set was judged rigid (see [`SaliencyConfig::rigid_tolerance`]).
    pub rigid: bool,
}

/// Computes per-vertex deformation saliency and stage-3 weights from stage 1's
/// residuals (stage 2).
///
/// Output vectors have `table.vertex_count` entries. Errors: a table of the wrong size,
/// a non-finite or negative residual, an unknown excluded pose, no pose left, or an
/// option out of range.
pub fn compute_saliency(table: &ResidualTable, config: &SaliencyConfig) -> Result<Saliency, SaliencyError> {
    config.validate()?;
    let poses = pick_contributing_poses(table, &config.exclude_poses)?;
    check_residuals(table, &poses)?;

    let raw = sum_residuals(table, &poses, config.distance);
    let normaliser = pick_normaliser(&raw, config.normalisation);
    let rigid = is_rigid(normaliser, poses.len(), table.length_scale, config);
    let saliency: Vec<Real> =
        if rigid { vec![0.0; raw.len()] } else { raw.iter().map(|&r| (r / normaliser).min(1.0)).collect() };
    let floor = config.weight_floor;
    let weights = saliency.iter().map(|&s| weight(s, floor)).collect();

    let report = SaliencyReport {
        distance: config.distance,
        normalisation: config.normalisation,
        weight_floor: floor,
        poses_used: poses.iter().map(|&p| table.pose_names[p].clone()).collect(),
        poses_excluded: (0..table.pose_names.len())
            .filter(|&p| config.exclude_poses.contains(&table.pose_names[p]))
            .map(|p| table.pose_names[p].clone())
            .collect(),
        raw_min: raw.iter().copied().fold(Real::INFINITY, Real::min),
        raw_max: raw.iter().copied().fold(0.0, Real::max),
        raw_mean: raw.iter().sum::<Real>() / raw.len().max(1) as Real,
        saturated_vertices: if rigid { 0 } else { raw.iter().filter(|&&r| r > normaliser).count() },
        rigid,
    };
    Ok(Saliency { saliency, weights, raw, normaliser, report })
}

impl SaliencyConfig {
    /// Checks the options that do not depend on the data (floor, percentile, tolerance),
    /// so a driver can refuse a bad configuration before any stage runs.
    pub fn validate(&self) -> Result<(), SaliencyError> {
        check_config(self)
    }
}

fn check_config(config: &SaliencyConfig) -> Result<(), SaliencyError> {
    let floor = config.weight_floor;
    if !(0.0..=1.0).contains(&floor) {
        return Err(SaliencyError::BadOption { option: "weight_floor", value: floor, expected: "in [0, 1]" });
    }
    if let Normalisation::Percentile(p) = config.normalisation
        && !(p > 0.0 && p <= 100.0)
    {
        return Err(SaliencyError::BadOption { option: "percentile", value: p, expected: "in (0, 100]" });
    }
    if config.rigid_tolerance.is_nan() || config.rigid_tolerance < 0.0 {
        return Err(SaliencyError::BadOption {
            option: "rigid_tolerance",
            value: config.rigid_tolerance,
            expected: ">= 0",
        });
    }
    Ok(())
}

/// The poses that are summed, ascending: every pose but the template and the excluded.
fn pick_contributing_poses(table: &ResidualTable, exclude: &[String]) -> Result<Vec<usize>, SaliencyError> {
    let pose_count = table.pose_names.len();
    if table.values.len() != pose_count * table.vertex_count {
        return Err(SaliencyError::TableSize {
            len: table.values.len(),
            poses: pose_count,
            vertices: table.vertex_count,
        });
    }
    if let Some(template) = table.template
        && template >= pose_count
    {
        return Err(SaliencyError::TemplateOutOfRange { template, poses: pose_count });
    }
    if let Some(name) = exclude.iter().find(|name| !table.pose_names.contains(name)) {
        return Err(SaliencyError::UnknownPose { name: name.clone(), known: table.pose_names.join(", ") });
    }
    let poses: Vec<usize> = (0..pose_count)
        .filter(|&p| Some(p) != table.template && !exclude.contains(&table.pose_names[p]))
        .collect();
    if poses.is_empty() {
        return Err(SaliencyError::NoPosesLeft { poses: pose_count, excluded: exclude.len() });
    }
    Ok(poses)
}

/// Fails on the first residual (in pose, then vertex order) that is not a finite,
/// non-negative distance.
fn check_residuals(table: &ResidualTable, poses: &[usize]) -> Result<(), SaliencyError> {
    for &pose in poses {
        let row = &table.values[pose * table.vertex_count..(pose + 1) * table.vertex_count];
        if let Some(vertex) = row.iter().position(|r| !(r.is_finite() && *r >= 0.0)) {
            return Err(SaliencyError::BadResidual {
                pose: table.pose_names[pose].clone(),
                vertex,
                value: row[vertex],
            });
        }
    }
    Ok(())
}

/// Per-vertex sums over `poses`, in pose order (so the result is bit-identical
/// whatever the thread count).
fn sum_residuals(table: &ResidualTable, poses: &[usize], distance: Distance) -> Vec<Real> {
    const CHUNK: usize = 4096;
    let n = table.vertex_count;
    let mut raw = vec![0.0; n];
    raw.par_chunks_mut(CHUNK).enumerate().for_each(|(chunk, sums)| {
        let first = chunk * CHUNK;
        for &pose in poses {
            let row = &table.values[pose * n + first..pose * n + first + sums.len()];
            for (sum, &r) in sums.iter_mut().zip(row) {
                let r = r as Real;
                *sum += match distance {
                    Distance::Plain => r,
                    Distance::Squared => r * r,
                };
            }
        }
    });
    raw
}

/// The largest raw sum, or the nearest-rank percentile: the smallest value with at
/// least `p` percent of the sums at or below it.
fn pick_normaliser(raw: &[Real], normalisation: Normalisation) -> Real {
    match normalisation {
        Normalisation::Max => raw.iter().copied().fold(0.0, Real::max),
        Normalisation::Percentile(p) => {
            if raw.is_empty() {
                return 0.0;
            }
            let rank = ((p / 100.0) * raw.len() as Real).ceil().max(1.0) as usize;
            let mut sorted = raw.to_vec();
            let (_, value, _) = sorted.select_nth_unstable_by(rank.min(raw.len()) - 1, Real::total_cmp);
            *value
        }
    }
}

/// True when the normaliser, as a per-pose distance in mesh units, is within the
/// rigid tolerance of the mesh size: what is left is floating-point noise.
fn is_rigid(normaliser: Real, pose_count: usize, length_scale: Real, config: &SaliencyConfig) -> bool {
    let per_pose = normaliser / pose_count as Real;
    let distance = match config.distance {
        Distance::Plain => per_pose,
        Distance::Squared => per_pose.sqrt(),
    };
    let limit = config.rigid_tolerance * length_scale;
    distance.is_nan() || distance <= limit
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(n: usize) -> Vec<String> {
        (0..n).map(|p| format!("p{p}")).collect()
    }

    fn table<'a>(values: &'a [f32], names: &'a [String], template: Option<usize>) -> ResidualTable<'a> {
        ResidualTable {
            values,
            vertex_count: values.len() / names.len(),
            pose_names: names,
            template,
            length_scale: 1.0,
        }
    }

    /// Three poses of four vertices; pose 0 is the template and must not count even
    /// though its row is (deliberately) non-zero here.
    const VALUES: [f32; 12] = [9.0, 9.0, 9.0, 9.0, 0.0, 1.0, 2.0, 0.5, 0.0, 1.0, 0.0, 3.5];

    #[test]
    fn sums_skip_the_template_and_divide_by_the_max() {
        let names = names(3);
        let s = compute_saliency(&table(&VALUES, &names, Some(0)), &SaliencyConfig::default()).unwrap();
        assert_eq!(s.raw, vec![0.0, 2.0, 2.0, 4.0]);
        assert_eq!(s.normaliser, 4.0);
        assert_eq!(s.saliency, vec![0.0, 0.5, 0.5, 1.0]);
        assert_eq!(s.weights, vec![0.05, 0.525, 0.525, 1.0]);
        assert_eq!(s.report.poses_used, vec!["p1", "p2"]);
        assert_eq!((s.report.raw_min, s.report.raw_max, s.report.raw_mean), (0.0, 4.0, 2.0));
        assert!(!s.report.rigid);
    }

    #[test]
    fn without_a_template_row_every_pose_counts() {
        let names = names(3);
        let s = compute_saliency(&table(&VALUES, &names, None), &SaliencyConfig::default()).unwrap();
        assert_eq!(s.raw, vec![9.0, 11.0, 11.0, 13.0]);
    }

    #[test]
    fn squared_distances_sum_squares() {
        let names = names(3);
        let config = SaliencyConfig { distance: Distance::Squared, ..SaliencyConfig::default() };
        let s = compute_saliency(&table(&VALUES, &names, Some(0)), &config).unwrap();
        assert_eq!(s.raw, vec![0.0, 2.0, 4.0, 12.5]);
        assert_eq!(s.saliency[3], 1.0);
        assert_eq!(s.saliency[2], 4.0 / 12.5);
    }

    #[test]
    fn excluded_poses_do_not_count_and_are_reported() {
        let names = names(3);
        let config = SaliencyConfig { exclude_poses: vec!["p2".into()], ..SaliencyConfig::default() };
        let s = compute_saliency(&table(&VALUES, &names, Some(0)), &config).unwrap();
        assert_eq!(s.raw, vec![0.0, 1.0, 2.0, 0.5]);
        assert_eq!(s.report.poses_used, vec!["p1"]);
        assert_eq!(s.report.poses_excluded, vec!["p2"]);
    }

    #[test]
    fn excluding_an_unknown_pose_or_every_pose_is_an_error() {
        let names = names(3);
        let typo = SaliencyConfig { exclude_poses: vec!["p7".into()], ..SaliencyConfig::default() };
        let err = compute_saliency(&table(&VALUES, &names, Some(0)), &typo).unwrap_err();
        assert!(matches!(err, SaliencyError::UnknownPose { ref name, .. } if name == "p7"));
        let all =
            SaliencyConfig { exclude_poses: vec!["p1".into(), "p2".into()], ..SaliencyConfig::default() };
        let err = compute_saliency(&table(&VALUES, &names, Some(0)), &all).unwrap_err();
        assert_eq!(err, SaliencyError::NoPosesLeft { poses: 3, excluded: 2 });
    }

    /// One pose, 100 vertices with residuals 1..=100: the 99th nearest-rank percentile
    /// is 99, so only vertex 99 (residual 100) saturates.
    #[test]
    fn percentile_normalisation_clamps_the_top() {
        let values: Vec<f32> = (1..=100).map(|v| v as f32).collect();
        let names = names(1);
        let config =
            SaliencyConfig { normalisation: Normalisation::Percentile(99.0), ..SaliencyConfig::default() };
        let s = compute_saliency(&table(&values, &names, None), &config).unwrap();
        assert_eq!(s.normaliser, 99.0);
        assert_eq!(s.saliency[98], 1.0);
        assert_eq!(s.saliency[99], 1.0);
        assert_eq!(s.saliency[0], 1.0 / 99.0);
        assert_eq!(s.report.saturated_vertices, 1);
        let hundred = SaliencyConfig { normalisation: Normalisation::Percentile(100.0), ..config };
        assert_eq!(compute_saliency(&table(&values, &names, None), &hundred).unwrap().normaliser, 100.0);
    }

    #[test]
    fn floating_point_noise_is_rigid_not_salient() {
        let values = [0.0, 1e-9, 3e-9, 0.0f32];
        let names = names(1);
        let s = compute_saliency(&table(&values, &names, None), &SaliencyConfig::default()).unwrap();
        assert!(s.report.rigid);
        assert!(s.saliency.iter().all(|&x| x == 0.0));
        assert!(s.weights.iter().all(|&w| w == DEFAULT_WEIGHT_FLOOR));
        // The raw sums are still reported as they are.
        assert_eq!(s.raw[2], 3e-9f32 as f64);
    }

    #[test]
    fn a_nan_residual_is_an_error_naming_pose_and_vertex() {
        let mut values = VALUES;
        values[6] = f32::NAN;
        let names = names(3);
        let err = compute_saliency(&table(&values, &names, Some(0)), &SaliencyConfig::default()).unwrap_err();
        assert!(matches!(err, SaliencyError::BadResidual { ref pose, vertex: 2, .. } if pose == "p1"));
    }

    #[test]
    fn options_out_of_range_and_a_short_table_are_errors() {
        let names = names(3);
        let floor = SaliencyConfig { weight_floor: 1.5, ..SaliencyConfig::default() };
        assert!(compute_saliency(&table(&VALUES, &names, Some(0)), &floor).is_err());
        let pct =
            SaliencyConfig { normalisation: Normalisation::Percentile(0.0), ..SaliencyConfig::default() };
        assert!(compute_saliency(&table(&VALUES, &names, Some(0)), &pct).is_err());
        let short = ResidualTable { vertex_count: 5, ..table(&VALUES, &names, Some(0)) };
        assert!(matches!(
            compute_saliency(&short, &SaliencyConfig::default()),
            Err(SaliencyError::TableSize { len: 12, poses: 3, vertices: 5 })
        ));
    }
}
