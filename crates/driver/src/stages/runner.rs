//! The stage runner: one stage run against the cache. A hit yields the entry's typed
//! summary and a lazily decoded body; a miss (or `--force`/`--from`) computes the
//! stage, stores it and records why it missed. Every stage of `desal run` goes through
//! [`StageRunner::stage`], so the cache rules are written once.

use std::cell::OnceCell;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use desal_io::artifact::{ArtifactBody, ContentHash};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::cache::{Cache, StageKey};
use crate::progress::Console;

/// The stages in run order. `--from` names one of them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Stage {
    Ingest,
    /// Part discovery (`labels = "auto"`); a labels file is read with ingest.
    Parts,
    Fit,
    Saliency,
    Simplify,
    Map,
    Hierarchy,
}

impl Stage {
    /// Every stage, in run order.
    pub const ALL: [Stage; 7] = [
        Stage::Ingest,
        Stage::Parts,
        Stage::Fit,
        Stage::Saliency,
        Stage::Simplify,
        Stage::Map,
        Stage::Hierarchy,
    ];

    /// The stage's name, as `--from` and the Python package spell it.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Ingest => "ingest",
            Stage::Parts => "parts",
            Stage::Fit => "fit",
            Stage::Saliency => "saliency",
            Stage::Simplify => "simplify",
            Stage::Map => "map",
            Stage::Hierarchy => "hierarchy",
        }
    }
}

impl std::str::FromStr for Stage {
    type Err = String;

    /// A stage by its name, in any case.
    fn from_str(name: &str) -> Result<Self, String> {
        Stage::ALL.into_iter().find(|s| s.name().eq_ignore_ascii_case(name)).ok_or_else(|| {
            let names: Vec<&str> = Stage::ALL.iter().map(|s| s.name()).collect();
            format!("unknown stage '{name}': use one of {}", names.join(", "))
        })
    }
}

/// What a stage computes: its artifact body, a typed summary (the JSON sidecar) and a
/// one-line note in meshoptimizer's spirit.
#[derive(Debug, Clone)]
pub struct StageOutput<T, S> {
    pub body: T,
    pub summary: S,
    pub note: String,
}

/// A summary as the cache stores it in `summary.json`: the stage's fields plus the note.
#[derive(Debug, Serialize, Deserialize)]
pub struct StoredSummary<S> {
    #[serde(flatten)]
    pub summary: S,
    pub note: String,
}

/// One stage's line in `report.json`.
#[derive(Debug, Clone, Serialize)]
pub struct StageRecord {
    pub name: String,
    pub cached: bool,
    pub seconds: f64,
    pub cache_key: String,
    /// Why the cache missed (absent on hits).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub miss_reason: Option<String>,
    /// One-line result of the stage, in meshoptimizer's spirit.
    pub note: String,
}

/// A stage's output: where its artifact is, its content hash and summary, and its body —
/// decoded from the cache entry only when something asks for it, so a warm run that
/// needs nothing recomputed decodes nothing.
#[derive(Debug)]
pub struct Staged<T, S> {
    body: OnceCell<T>,
    pub hash: ContentHash,
    pub summary: S,
    /// The cache entry's artifact file (copied into the output folder).
    pub artifact_path: PathBuf,
}

impl<T, S> Staged<T, S> {
    /// The same stage output with its summary converted (the parts stage's output seen
    /// as the labels stage's).
    pub fn map_summary<S2>(self, f: impl FnOnce(S) -> S2) -> Staged<T, S2> {
        Staged {
            body: self.body,
            hash: self.hash,
            summary: f(self.summary),
            artifact_path: self.artifact_path,
        }
    }
}

impl<T: ArtifactBody, S> Staged<T, S> {
    /// The artifact body, decoded on first use.
    pub fn body(&self) -> Result<&T> {
        if let Some(body) = self.body.get() {
            return Ok(body);
        }
        // A cache entry, which a shard sharing the cache may be replacing.
        let (_, body, _) =
            crate::cache::read_entry_file(&self.artifact_path, desal_io::artifact::read_artifact::<T>)?;
        Ok(self.body.get_or_init(|| body))
    }
}

/// What decides whether a stage may be served from the cache.
#[derive(Debug, Clone, Copy, Default)]
pub struct RunnerOptions {
    /// Recompute every stage (entries are replaced, not trusted).
    pub force: bool,
    /// Recompute this stage and the ones after it.
    pub from: Option<Stage>,
    /// Print why each stage missed the cache.
    pub explain: bool,
}

/// Runs stages of one dataset against the cache, recording each.
#[derive(Debug)]
pub struct StageRunner<'a> {
    pub cache: &'a Cache,
    pub dataset: &'a str,
    pub options: RunnerOptions,
    pub console: &'a dyn Console,
    pub records: Vec<StageRecord>,
}

impl StageRunner<'_> {
    /// Looks `key` up; on a miss (or when forced) runs `compute` and stores its result.
    /// An entry whose summary does not parse as `S` is corrupt: it is evicted and
    /// recomputed, like one that fails its checksum.
    pub fn stage<T: ArtifactBody, S: Serialize + DeserializeOwned>(
        &mut self,
        stage: Stage,
        key: StageKey,
        hints: &[(String, String)],
        compute: impl FnOnce() -> Result<StageOutput<T, S>>,
    ) -> Result<Staged<T, S>> {
        let start = Instant::now();
        let forced = self.options.force || self.options.from.is_some_and(|from| stage >= from);
        let key_hash = key.hash();
        let entry = self.cache.entry_dir(&key).join("artifact.dsa");
        if !forced && let Some(hit) = self.cache.lookup::<T>(&key) {
            match serde_json::from_slice::<StoredSummary<S>>(&hit.summary) {
                Ok(stored) => {
                    self.records.push(StageRecord {
                        name: key.stage.clone(),
                        cached: true,
                        seconds: start.elapsed().as_secs_f64(),
                        cache_key: key_hash.to_hex(),
                        miss_reason: None,
                        note: stored.note,
                    });
                    self.cache.record(self.dataset, &key)?;
                    return Ok(Staged {
                        body: OnceCell::new(),
                        hash: hit.hash,
                        summary: stored.summary,
                        artifact_path: entry,
                    });
                }
                Err(e) => self
                    .cache
                    .reject(&key, &format!("{}: {e}", entry.with_file_name("summary.json").display())),
            }
        }
        let reason = if forced {
            "forced (--force or --from)".to_owned()
        } else {
            self.cache.explain_miss(self.dataset, &key)
        };
        if self.options.explain {
            self.console.println(&format!("{}: {} missed the cache: {reason}", self.dataset, key.stage));
        }
        let StageOutput { body, summary, note } = compute()?;
        let stored = StoredSummary { summary, note };
        if forced {
            self.cache.evict(&key);
        }
        let producer = key.producer(hints);
        let hash = self.cache.store(&key, &producer, &body, &stored)?;
        self.cache.record(self.dataset, &key)?;
        self.records.push(StageRecord {
            name: key.stage.clone(),
            cached: false,
            seconds: start.elapsed().as_secs_f64(),
            cache_key: key_hash.to_hex(),
            miss_reason: Some(reason),
            note: stored.note,
        });
        Ok(Staged { body: OnceCell::from(body), hash, summary: stored.summary, artifact_path: entry })
    }
}
