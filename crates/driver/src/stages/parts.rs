//! The parts stage (`labels = "auto"`): near-rigid parts discovered from the pose set by
//! `desal-parts`, in place of a labels file. Its parameters and their validation, its
//! cache key, the call into the crate and the artifact: the same `LabelsV1` a labels
//! file gives, so fit, saliency, simplify, map and eval do not know where labels came from.

use anyhow::{Result, bail};
use desal_io::artifact::{ArtifactKind, ContentHash, LabelsV1};
use desal_mesh::{PartLabels, PoseSet};
use desal_parts::PartsConfig;
use serde::{Deserialize, Deserializer, Serialize};
use serde_json::json;

use crate::cache::{StageKey, canonical_json};
use crate::stages::ingest::LabelsSummary;
use crate::stages::runner::StageOutput;

/// Part-discovery parameters: `parts = K` in a pipeline file, or a `[dataset.parts]`
/// table with `count` and the tunables; `desal parts` flags. Every field left out takes
/// [`PartsConfig::default`]'s value (documented there, with how it was measured).
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq, Default)]
#[serde(deny_unknown_fields, default)]
pub struct PartsParams {
    /// The number of parts; absent: chosen at the knee of the residual curve.
    pub count: Option<usize>,
    /// The largest count tried when `count` is absent.
    pub max_parts: Option<usize>,
    /// The smallest part, in vertices (at least 3).
    pub min_part_vertices: Option<usize>,
    /// Patches the template is first cut into (the most parts discovery can return).
    pub patches: Option<usize>,
    /// Upper bound on border-relaxation sweeps.
    pub relax_sweeps: Option<usize>,
    /// Motion below this (mean distance per vertex and pose, relative to the template's
    /// bounding-box diagonal) counts as none.
    pub rigid_tolerance: Option<f64>,
}

/// `parts = 16` or a `[dataset.parts]` table, for `#[serde(deserialize_with)]`.
pub fn count_or_table<'de, D: Deserializer<'de>>(deserializer: D) -> Result<PartsParams, D::Error> {
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum CountOrTable {
        Count(usize),
        Table(PartsParams),
    }
    Ok(match CountOrTable::deserialize(deserializer)? {
        CountOrTable::Count(count) => PartsParams { count: Some(count), ..PartsParams::default() },
        CountOrTable::Table(table) => table,
    })
}

impl PartsParams {
    /// The library configuration these parameters resolve to, checked.
    pub fn config(&self) -> Result<PartsConfig> {
        let d = PartsConfig::default();
        let config = PartsConfig {
            parts: self.count,
            max_parts: self.max_parts.unwrap_or(d.max_parts),
            min_part_vertices: self.min_part_vertices.unwrap_or(d.min_part_vertices),
            patches: self.patches.unwrap_or(d.patches),
            relax_sweeps: self.relax_sweeps.unwrap_or(d.relax_sweeps),
            rigid_tolerance: self.rigid_tolerance.unwrap_or(d.rigid_tolerance),
        };
        if let Err(e) = config.validate() {
            bail!("parts: {e}");
        }
        Ok(config)
    }

    /// The cache key of a discovery on `poses`: the resolved configuration (so a changed
    /// library default re-runs it) and the pose set's hash.
    pub fn key(&self, poses: ContentHash) -> Result<StageKey> {
        let PartsConfig { parts, max_parts, min_part_vertices, patches, relax_sweeps, rigid_tolerance } =
            self.config()?;
        Ok(StageKey {
            stage: "parts".into(),
            stage_version: desal_parts::VERSION,
            format_version: ArtifactKind::Labels.current_version(),
            parameters: canonical_json(self),
            resolved: canonical_json(&json!({
                "parts": parts,
                "max_parts": max_parts,
                "min_part_vertices": min_part_vertices,
                "patches": patches,
                "relax_sweeps": relax_sweeps,
                "rigid_tolerance": rigid_tolerance,
            })),
            inputs: vec![("poses".into(), poses)],
        })
    }
}

/// One point of the knee curve in `parts.json`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct KneePoint {
    pub parts: usize,
    /// Stage 1's mean rigid-fit residual with that many parts, in mesh units (m).
    pub mean_residual: f64,
}

/// `parts.json`: the discovery's figures.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PartsSummary {
    /// The requested count; `null` when chosen at the knee.
    pub requested: Option<usize>,
    /// Parts returned.
    pub parts: usize,
    /// Index into `curve` of the returned count.
    pub chosen: usize,
    /// Mean residual against part count, before the borders are relaxed.
    pub curve: Vec<KneePoint>,
    /// Part names (`part0`, `part1`, ...), indexed by part id.
    pub names: Vec<String>,
    /// Vertices per part, indexed by part id.
    pub part_sizes: Vec<usize>,
    /// The returned parts' mean residual after border relaxation, in mesh units (m).
    pub mean_residual: f64,
    /// True when the pose set does not move: one part per connected piece.
    pub motionless: bool,
    pub sweeps: usize,
    pub seconds: f64,
}

impl PartsSummary {
    /// What `labels.json` shows, as for a labels file.
    pub fn labels_summary(&self) -> LabelsSummary {
        LabelsSummary { parts: self.names.clone(), vertices_per_part: self.part_sizes.clone() }
    }
}

/// Discovers the parts of `set`. A motionless pose set gets one part per connected
/// piece, with a warning on stderr: its saliency will be uniform.
pub fn compute(params: &PartsParams, set: &PoseSet) -> Result<StageOutput<LabelsV1, PartsSummary>> {
    let config = params.config()?;
    let start = std::time::Instant::now();
    let (labels, report) = desal_parts::discover_parts(set, &config)?;
    let seconds = start.elapsed().as_secs_f64();
    let summary = PartsSummary {
        requested: report.requested,
        parts: report.parts,
        chosen: report.chosen,
        curve: report
            .curve
            .iter()
            .map(|p| KneePoint { parts: p.parts, mean_residual: p.mean_residual })
            .collect(),
        names: labels.names.clone(),
        part_sizes: report.part_sizes.clone(),
        mean_residual: report.mean_residual,
        motionless: report.motionless,
        sweeps: report.sweeps,
        seconds,
    };
    let how = match report.requested {
        Some(k) => format!("{k} requested"),
        None => format!("knee of {} counts", report.curve.len()),
    };
    let note = if report.motionless {
        format!("the poses do not move: {} part(s), saliency will be uniform", report.parts)
    } else {
        format!(
            "{} parts discovered ({how}), mean residual {:.2} mm, smallest part {} vertices",
            report.parts,
            report.mean_residual * 1e3,
            report.part_sizes.iter().min().unwrap_or(&0)
        )
    };
    if report.motionless {
        eprintln!("warning: labels = \"auto\": {note}");
    }
    Ok(StageOutput { body: LabelsV1::from_labels(&labels), summary, note })
}

/// `labels.txt`: a `# parts: name0 name1 ...` header line, then the labels file text
/// desal reads back (`desal_io::labels`; the header is a comment it skips).
pub fn labels_txt(labels: &PartLabels) -> String {
    format!("# parts: {}\n{}", labels.names.join(" "), desal_io::labels::labels_txt(labels))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The defaults resolve to the library's: a pipeline that says nothing runs
    /// `PartsConfig::default()`.
    #[test]
    fn empty_parameters_resolve_to_the_library_defaults() {
        assert_eq!(PartsParams::default().config().unwrap(), PartsConfig::default());
    }

    /// Every tunable is in the key: changing one changes it.
    #[test]
    fn every_parameter_changes_the_key() {
        let poses = ContentHash::of(b"poses");
        let base = PartsParams::default().key(poses).unwrap().hash();
        let changed = [
            PartsParams { count: Some(4), ..PartsParams::default() },
            PartsParams { max_parts: Some(5), ..PartsParams::default() },
            PartsParams { min_part_vertices: Some(30), ..PartsParams::default() },
            PartsParams { patches: Some(64), ..PartsParams::default() },
            PartsParams { relax_sweeps: Some(2), ..PartsParams::default() },
            PartsParams { rigid_tolerance: Some(1e-5), ..PartsParams::default() },
        ];
        for params in changed {
            assert_ne!(params.key(poses).unwrap().hash(), base, "{params:?}");
        }
        assert_ne!(PartsParams::default().key(ContentHash::of(b"other")).unwrap().hash(), base);
    }

    /// An out-of-range option is refused before anything runs, naming the option.
    #[test]
    fn bad_options_are_refused() {
        let err = PartsParams { count: Some(0), ..PartsParams::default() }.config().unwrap_err();
        assert!(err.to_string().contains("parts"), "{err}");
        let err = PartsParams { min_part_vertices: Some(2), ..PartsParams::default() }.config().unwrap_err();
        assert!(err.to_string().contains("min_part_vertices"), "{err}");
    }

    /// `labels.txt` reads back as the same labels, header and all.
    #[test]
    fn labels_txt_reads_back() {
        let labels = PartLabels::from_ids(vec![0, 0, 1, 2, 1]);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("labels.txt");
        let text = labels_txt(&labels);
        assert!(text.starts_with("# parts: part0 part1 part2\n"), "{text}");
        std::fs::write(&path, text).unwrap();
        let back = desal_io::labels::read_labels(&path).unwrap();
        assert_eq!((back.labels, back.names), (labels.labels, labels.names));
    }
}
