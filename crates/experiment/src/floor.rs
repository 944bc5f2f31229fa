//! The model's own floor, cached: `desal_measures::model_floor` fits the deformation model
//! on the full-resolution pose set six times (in-sample and per fold) and measures 140
//! syntheses on SCAPE (6.9 s of a 20 s `desal eval pipelines/scape.toml --methods
//! qslim-optimal`, its log says), and it depends on nothing a method changes. So it is a cache entry like a stage's (`<cache>/floor/<key>`,
//! [`desal_driver::cache`]), keyed on:
//!
//! | field | what |
//! |---|---|
//! | `stage_version` | [`VERSION`], of this measurement's glue |
//! | `parameters` | the `--model` name and `--folds` |
//! | `resolved` | the model's every setting (its `Debug` form, which lists every field), the hash of desal-measures' source ([`desal_measures::SOURCE`]: any change to a model or metric) and desal-fit's version (the part motions) |
//! | `inputs` | the pose set's and the labels' content hashes |
//!
//! A corrupt or forged entry is refused and measured again, as a stage's is; a killed
//! run leaves no entry. `desal cache gc` keeps a floor entry while the pipeline still
//! uses its pose set and labels.

use std::time::Instant;

use anyhow::Result;
use desal_io::artifact::{ArtifactKind, FloorV1, read_artifact};
use desal_measures::{MeanErrors, ModelFloor, PoseModel};

use desal_driver::cache::{Cache, StageKey, canonical_json, read_entry_file};
use desal_driver::stages::DatasetStages;

/// The floor's stage id in the cache.
pub const STAGE: &str = "floor";

/// Version of what this module and `model_floor` in `super` add to desal-measures'
/// measurement (which poses, which motions): bumped when a floor figure changes.
pub const VERSION: u32 = 1;

/// The floor's cache key for `model` (named `name`) with `folds` folds on a dataset's
/// pose set and labels.
pub fn key(name: &str, model: &PoseModel, folds: usize, stages: &DatasetStages) -> Result<StageKey> {
    #[derive(serde::Serialize)]
    struct Parameters<'a> {
        model: &'a str,
        folds: usize,
    }
    #[derive(serde::Serialize)]
    struct Resolved {
        model: String,
        eval_source: &'static str,
        fit_version: u32,
    }
    Ok(StageKey {
        stage: STAGE.into(),
        stage_version: VERSION,
        format_version: ArtifactKind::Floor.current_version(),
        parameters: canonical_json(&Parameters { model: name, folds }),
        resolved: canonical_json(&Resolved {
            model: format!("{model:?}"),
            eval_source: desal_measures::SOURCE,
            fit_version: desal_fit::VERSION,
        }),
        inputs: vec![("pose_set".into(), stages.poses.hash()?), ("labels".into(), stages.labels.hash()?)],
    })
}

/// A floor, and whether it came from the cache.
#[derive(Debug, Clone, Copy)]
pub struct Floor {
    pub floor: ModelFloor,
    pub cached: bool,
    /// Wall time of the look-up, or of the measurement and the store.
    pub seconds: f64,
}

/// The floor under `key` (of the model named `name`): from the cache when its entry is
/// sound, else `measure()`d and stored.
pub fn cached(
    cache: &Cache,
    key: &StageKey,
    name: &str,
    measure: impl FnOnce() -> Result<ModelFloor>,
) -> Result<Floor> {
    let started = Instant::now();
    let entry = cache.entry_dir(key).join("artifact.dsa");
    if cache.lookup::<FloorV1>(key).is_some() {
        // A shard sharing the cache may be replacing the entry: waited for, and an entry
        // that still does not read is measured again.
        match read_entry_file(&entry, read_artifact::<FloorV1>) {
            Ok((_, body, _)) => {
                return Ok(Floor {
                    floor: from_body(&body),
                    cached: true,
                    seconds: started.elapsed().as_secs_f64(),
                });
            }
            Err(e) => cache.reject(key, &e.to_string()),
        }
    }
    let floor = measure()?;
    let body = to_body(name, &floor);
    cache.store(key, &key.producer(&[]), &body, &body)?;
    Ok(Floor { floor, cached: false, seconds: started.elapsed().as_secs_f64() })
}

fn to_body(name: &str, floor: &ModelFloor) -> FloorV1 {
    FloorV1 {
        model: name.to_owned(),
        poses: floor.pose_count as u32,
        folds: floor.fold_count as u32,
        in_sample_v2v: floor.in_sample.v2v,
        in_sample_v2f: floor.in_sample.v2f,
        held_out_v2v: floor.held_out.v2v,
        held_out_v2f: floor.held_out.v2f,
    }
}

fn from_body(body: &FloorV1) -> ModelFloor {
    ModelFloor {
        pose_count: body.poses as usize,
        fold_count: body.folds as usize,
        in_sample: MeanErrors { v2v: body.in_sample_v2v, v2f: body.in_sample_v2f },
        held_out: MeanErrors { v2v: body.held_out_v2v, v2f: body.held_out_v2f },
    }
}

/// Summary lines of a floor artifact for `desal inspect`.
pub fn describe(body: &FloorV1, out: &mut String) -> std::fmt::Result {
    use std::fmt::Write as _;
    let floor = from_body(body);
    writeln!(out, "    model {}, {} poses, {} folds", body.model, body.poses, body.folds)?;
    writeln!(out, "    in-sample  v2v {:.4e}  v2f {:.4e}", body.in_sample_v2v, body.in_sample_v2f)?;
    writeln!(
        out,
        "    held out   v2v {:.4e}  v2f {:.4e}  ({:.2}x, {:.2}x in-sample)",
        body.held_out_v2v,
        body.held_out_v2f,
        floor.v2v_ratio(),
        floor.v2f_ratio()
    )
}
