//! Where a stage's output comes from: a [`Store`]. The stage chain (`chain.rs`) and the
//! hierarchy's level loop are written once over it, and run on one of two stores:
//!
//! - [`StageRunner`], the content-addressed cache (`desal run`): a hit yields the entry's
//!   typed summary and a lazily decoded body; a miss (or `--force`/`--from`) computes the
//!   stage, stores it and records why it missed, so the cache rules are written once;
//! - [`Memory`], which computes every stage and keeps nothing but the outputs it hands
//!   back (the Python package and the single-stage commands);
//! - [`Scratch`], [`Memory`] that also lets go of a body no later stage reads (stage 1's
//!   residuals once stage 2 has them): the stages inside one hierarchy or LOD level,
//!   whose caller reads only their map.

use std::cell::OnceCell;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Result, anyhow};
use desal_io::artifact::{ArtifactBody, ContentHash};
use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::cache::{Cache, StageKey, StoredSummary};
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

/// A stage's output: its summary and note, its body, and — from the cache — its content
/// hash and artifact file. A cached body is decoded from the entry only when something
/// asks for it, so a warm run that needs nothing recomputed decodes nothing.
#[derive(Debug)]
pub struct Staged<T, S> {
    body: OnceCell<T>,
    /// The cache entry: its artifact's content hash and file. `None` in [`Memory`].
    entry: Option<(ContentHash, PathBuf)>,
    pub summary: S,
    pub note: String,
}

impl<T, S> Staged<T, S> {
    /// A stage computed in memory.
    fn computed(out: StageOutput<T, S>) -> Self {
        Staged { body: OnceCell::from(out.body), entry: None, summary: out.summary, note: out.note }
    }

    /// The artifact's content hash: an input of the keys of the stages after it. Only a
    /// stage served by the cache has one, and only the cache builds keys.
    pub fn hash(&self) -> Result<ContentHash> {
        self.entry
            .as_ref()
            .map(|(hash, _)| *hash)
            .ok_or_else(|| anyhow!("a stage computed in memory has no cache key"))
    }

    /// The cache entry's artifact file (copied into the output folder).
    pub fn artifact_path(&self) -> Result<&Path> {
        self.entry
            .as_ref()
            .map(|(_, path)| path.as_path())
            .ok_or_else(|| anyhow!("a stage computed in memory has no artifact file"))
    }

    /// The same stage output with its summary converted (the parts stage's output seen
    /// as the labels stage's).
    pub fn map_summary<S2>(self, f: impl FnOnce(S) -> S2) -> Staged<T, S2> {
        Staged { body: self.body, entry: self.entry, summary: f(self.summary), note: self.note }
    }
}

impl<T: ArtifactBody, S> Staged<T, S> {
    /// The artifact body, decoded on first use.
    pub fn body(&self) -> Result<&T> {
        if let Some(body) = self.body.get() {
            return Ok(body);
        }
        let body = self.decode_entry()?;
        Ok(self.body.get_or_init(|| body))
    }

    /// The body decoded from the cache entry (which a shard sharing the cache may be
    /// replacing), not kept: for a body converted once and not read again, such as the
    /// pose set, whose f32 arrays would otherwise sit beside its f64 `PoseSet`.
    pub fn decode_entry(&self) -> Result<T> {
        let (_, body, _) =
            crate::cache::read_entry_file(self.artifact_path()?, desal_io::artifact::read_artifact::<T>)?;
        Ok(body)
    }

    /// The body held in memory (a computed stage's), taken out when the cache entry can
    /// give it again: a later [`Self::body`] decodes it from there. `None` when no body
    /// is held or the stage has no entry (computed in [`Memory`], it keeps its body).
    pub fn take_held_body(&mut self) -> Option<T> {
        self.entry.as_ref()?;
        self.body.take()
    }

    /// The body, summary and note, the body decoded if it was not yet.
    pub fn into_output(self) -> Result<StageOutput<T, S>> {
        self.body()?;
        let body = self.body.into_inner().expect("decoded above");
        Ok(StageOutput { body, summary: self.summary, note: self.note })
    }
}

/// Where stages are served from: the cache ([`StageRunner`]) or memory ([`Memory`]).
pub trait Store {
    /// Stage `stage`'s output: the store's when it holds the output of `key`, else
    /// `compute`d (and kept, by a store that keeps). `key` and `hints` are used only by
    /// a store that keys its outputs.
    fn stage<T: ArtifactBody, S: Serialize + DeserializeOwned>(
        &mut self,
        stage: Stage,
        key: impl FnOnce() -> Result<StageKey>,
        hints: &[(String, String)],
        compute: impl FnOnce() -> Result<StageOutput<T, S>>,
    ) -> Result<Staged<T, S>>;

    /// Lets go of `staged`'s body, which no later stage of the chain reads: the cache's
    /// stages give it back (a later [`Staged::body`] decodes it from the entry), so do
    /// [`Scratch`]'s (a later [`Staged::body`] is an error); [`Memory`] keeps it for its
    /// caller.
    fn release<T: ArtifactBody, S>(&self, staged: &mut Staged<T, S>) {
        drop(staged.take_held_body());
    }
}

/// The store that keeps nothing: every stage is computed, no key is built.
#[derive(Debug, Clone, Copy, Default)]
pub struct Memory;

impl Store for Memory {
    fn stage<T: ArtifactBody, S: Serialize + DeserializeOwned>(
        &mut self,
        _stage: Stage,
        _key: impl FnOnce() -> Result<StageKey>,
        _hints: &[(String, String)],
        compute: impl FnOnce() -> Result<StageOutput<T, S>>,
    ) -> Result<Staged<T, S>> {
        Ok(Staged::computed(compute()?))
    }
}

/// [`Memory`] for a chain whose caller reads only its last stages (a hierarchy or LOD
/// level reads the map): a body [`Store::release`]d is dropped, so stage 1's residuals
/// (one vector per pose and vertex) are not held through stages 3 and 4.
#[derive(Debug, Clone, Copy, Default)]
pub struct Scratch;

impl Store for Scratch {
    fn stage<T: ArtifactBody, S: Serialize + DeserializeOwned>(
        &mut self,
        stage: Stage,
        key: impl FnOnce() -> Result<StageKey>,
        hints: &[(String, String)],
        compute: impl FnOnce() -> Result<StageOutput<T, S>>,
    ) -> Result<Staged<T, S>> {
        Memory.stage(stage, key, hints, compute)
    }

    fn release<T: ArtifactBody, S>(&self, staged: &mut Staged<T, S>) {
        drop(staged.body.take());
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

impl Store for StageRunner<'_> {
    /// [`Cache::serve`], recorded in `report.json`'s stage list.
    fn stage<T: ArtifactBody, S: Serialize + DeserializeOwned>(
        &mut self,
        stage: Stage,
        key: impl FnOnce() -> Result<StageKey>,
        hints: &[(String, String)],
        compute: impl FnOnce() -> Result<StageOutput<T, S>>,
    ) -> Result<Staged<T, S>> {
        let key = key()?;
        let start = Instant::now();
        let forced = self.options.force || self.options.from.is_some_and(|from| stage >= from);
        let (console, explain, dataset) = (self.console, self.options.explain, self.dataset);
        let on_miss = |reason: &str| {
            if explain {
                console.println(&format!("{dataset}: {} missed the cache: {reason}", key.stage));
            }
        };
        let served = self.cache.serve(dataset, &key, hints, forced, on_miss, || {
            let StageOutput { body, summary, note } = compute()?;
            Ok((body, StoredSummary { summary, note }))
        })?;
        self.records.push(StageRecord {
            name: key.stage.clone(),
            cached: served.miss_reason.is_none(),
            seconds: start.elapsed().as_secs_f64(),
            cache_key: key.hash().to_hex(),
            miss_reason: served.miss_reason,
            note: served.stored.note.clone(),
        });
        let body = served.body.map_or_else(OnceCell::new, OnceCell::from);
        Ok(Staged {
            body,
            entry: Some((served.hash, served.artifact)),
            summary: served.stored.summary,
            note: served.stored.note,
        })
    }
}
