//! The content-addressed artifact cache.
//!
//! A stage run is identified by a key, the BLAKE3 hash of the canonical JSON of:
//!
//! | field            | what                                                            |
//! |------------------|-----------------------------------------------------------------|
//! | `stage`          | stage id: `ingest`, `labels`, `rig-ingest`, `rig-labels`, `model-ingest`, `model-labels`, `parts`, `fit`, `saliency`, `simplify`, `map`, `hierarchy-<k>` (one per level), and `desal eval`'s `floor` |
//! | `stage_version`  | version of the stage's algorithm (bumped when output changes)   |
//! | `format_version` | format version of the artifact kind it writes                   |
//! | `parameters`     | the parameters the user set, canonical JSON (sorted keys); also recorded in the artifact's producer |
//! | `resolved`       | the stage's *resolved* library configuration, every field, canonical JSON: changing a default invalidates without anyone bumping a version |
//! | `inputs`         | `(role, content hash)` of every input: file bytes for source files, payload hashes for artifacts |
//!
//! What never goes in: paths, file names, modification times, the dataset's name, the
//! output folder, thread counts. Two datasets with the same content share entries.
//!
//! Layout: `<cache>/<stage>/<key>/artifact.dsa` plus `summary.json` (what a person wants
//! to read). An entry is built in a temp folder beside it (`.tmp-<key>-<pid>-<n>`) and
//! renamed into place, so a killed run leaves no entry behind, only a temp folder that no
//! lookup ever reads. An entry whose artifact fails its checksum is reported, deleted
//! and recomputed, never used. Runs sharing a cache (shards) may replace an entry while
//! another reads it: a lookup that finds the entry half gone is a plain miss, and a file
//! read later (an output copy, a body decoded on first use) waits for the entry to be
//! stored again ([`read_entry_file`]).
//!
//! Why an entry missed: after each stage run, its key's components are recorded under
//! `<cache>/explain/<dataset>/<stage>.json`; a miss compares the new components with that
//! record and names what changed (cargo's fingerprint side files are the model).

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use desal_io::artifact::{self, ArtifactBody, ContentHash, InputRef, Producer};
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

/// How long a reader waits for a cache entry's file that another run is replacing.
const REPLACED_ENTRY_WAIT: Duration = Duration::from_secs(30);

/// `read(path)` of a file in a cache entry that another run may be replacing.
///
/// Runs sharing a cache (shards) can replace an entry while this run still reads it.
/// A `--force` run, or one that rejected the entry, evicts the entry and stores it
/// again at once, with the same content by the key's construction. So while the file
/// is missing, the read is tried again, for up to [`REPLACED_ENTRY_WAIT`]. Any other
/// failure, or a file still missing after that, is the error.
pub fn read_entry_file<R, E>(path: &Path, read: impl FnMut(&Path) -> Result<R, E>) -> Result<R, E> {
    read_entry_file_within(path, REPLACED_ENTRY_WAIT, read)
}

fn read_entry_file_within<R, E>(
    path: &Path,
    wait: Duration,
    mut read: impl FnMut(&Path) -> Result<R, E>,
) -> Result<R, E> {
    let start = Instant::now();
    loop {
        match read(path) {
            Err(_) if !path.exists() && start.elapsed() < wait => {
                std::thread::sleep(Duration::from_millis(10));
            }
            done => return done,
        }
    }
}

/// Canonical JSON of a parameter struct: sorted keys, no whitespace. This is the form
/// that enters cache keys and artifact producers.
pub fn canonical_json<T: Serialize>(value: &T) -> String {
    // serde_json's Map is a BTreeMap (no `preserve_order` feature), so keys come out sorted.
    let v = serde_json::to_value(value).expect("parameters serialise");
    serde_json::to_string(&v).expect("a JSON value serialises")
}

/// Serde through an enum's `Display`/`FromStr` (`#[serde(with = "crate::cache::by_name")]`):
/// the stage crates own each enum's one spelling table, and pipeline files, keys and
/// reports all read and write it.
pub mod by_name {
    use std::fmt::Display;
    use std::str::FromStr;

    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<T: Display, S: Serializer>(value: &T, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_str(value)
    }

    pub fn deserialize<'de, T, D>(deserializer: D) -> Result<T, D::Error>
    where
        T: FromStr<Err = String>,
        D: Deserializer<'de>,
    {
        let text = String::deserialize(deserializer)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

/// The components of a stage run's cache key.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StageKey {
    pub stage: String,
    pub stage_version: u32,
    pub format_version: u16,
    /// Canonical JSON of the parameters the user set (what the producer records).
    pub parameters: String,
    /// Canonical JSON of the resolved library configuration, every field (see the module
    /// table). Built by each stage's `key()` from an exhaustive destructuring, so a
    /// config field left out of it does not compile.
    pub resolved: String,
    /// `(role, hash)` of every input, in a fixed order per stage.
    pub inputs: Vec<(String, ContentHash)>,
}

impl StageKey {
    /// The key: BLAKE3 of the canonical JSON of the components.
    pub fn hash(&self) -> ContentHash {
        ContentHash::of(canonical_json(self).as_bytes())
    }

    /// The producer record an artifact made under this key carries. `hints` gives a
    /// human-readable name per input role (never part of the key).
    pub fn producer(&self, hints: &[(String, String)]) -> Producer {
        let hint =
            |role: &str| hints.iter().find(|(r, _)| r == role).map(|(_, h)| h.clone()).unwrap_or_default();
        Producer {
            stage: self.stage.clone(),
            stage_version: self.stage_version,
            tool_version: env!("CARGO_PKG_VERSION").to_owned(),
            parameters: self.parameters.clone(),
            inputs: self
                .inputs
                .iter()
                .map(|(role, hash)| InputRef { role: role.clone(), hash: *hash, hint: hint(role) })
                .collect(),
        }
    }

    /// What differs from `old`, in words; empty when nothing does.
    pub fn differences(&self, old: &StageKey) -> Vec<String> {
        let mut out = Vec::new();
        if self.stage_version != old.stage_version {
            out.push(format!("stage version {} -> {}", old.stage_version, self.stage_version));
        }
        if self.format_version != old.format_version {
            out.push(format!("format version {} -> {}", old.format_version, self.format_version));
        }
        if self.parameters != old.parameters {
            out.push(parameter_differences(&old.parameters, &self.parameters));
        } else if self.resolved != old.resolved {
            out.push(format!("resolved {}", parameter_differences(&old.resolved, &self.resolved)));
        }
        let old_roles: Vec<&String> = old.inputs.iter().map(|(r, _)| r).collect();
        let new_roles: Vec<&String> = self.inputs.iter().map(|(r, _)| r).collect();
        if old_roles != new_roles {
            out.push(format!(
                "the input list changed ({} -> {} inputs)",
                old.inputs.len(),
                self.inputs.len()
            ));
        } else {
            let changed: Vec<&str> = self
                .inputs
                .iter()
                .zip(&old.inputs)
                .filter(|(a, b)| a.1 != b.1)
                .map(|(a, _)| a.0.as_str())
                .collect();
            if !changed.is_empty() {
                let shown: Vec<&str> = changed.iter().take(5).copied().collect();
                let more = if changed.len() > 5 {
                    format!(" and {} more", changed.len() - 5)
                } else {
                    String::new()
                };
                out.push(format!("input content changed: {}{more}", shown.join(", ")));
            }
        }
        out
    }
}

fn parameter_differences(old: &str, new: &str) -> String {
    let (Ok(serde_json::Value::Object(a)), Ok(serde_json::Value::Object(b))) =
        (serde_json::from_str::<serde_json::Value>(old), serde_json::from_str::<serde_json::Value>(new))
    else {
        return format!("parameters {old} -> {new}");
    };
    let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
    keys.sort();
    keys.dedup();
    let changes: Vec<String> = keys
        .into_iter()
        .filter(|k| a.get(*k) != b.get(*k))
        .map(|k| {
            let show = |v: Option<&serde_json::Value>| v.map_or("(unset)".to_owned(), |v| v.to_string());
            format!("{k} {} -> {}", show(a.get(k)), show(b.get(k)))
        })
        .collect();
    format!("parameter {}", changes.join(", "))
}

/// A cache rooted at a folder.
#[derive(Debug, Clone)]
pub struct Cache {
    root: PathBuf,
}

/// A summary as the cache stores it in `summary.json`: the stage's fields plus the note.
#[derive(Debug, Serialize, Deserialize)]
pub struct StoredSummary<S> {
    #[serde(flatten)]
    pub summary: S,
    pub note: String,
}

/// What [`Cache::serve`] found or stored.
#[derive(Debug)]
pub struct Served<T, S> {
    /// The artifact's content hash and file.
    pub hash: ContentHash,
    pub artifact: PathBuf,
    pub stored: StoredSummary<S>,
    /// The body when it was computed; a hit's is decoded from `artifact` on demand.
    pub body: Option<T>,
    /// Why the cache missed; `None` on a hit.
    pub miss_reason: Option<String>,
}

/// A cache entry found, with its envelope verified (magic, kind, version, length,
/// checksum). The body is decoded later, only if something needs it.
#[derive(Debug)]
pub struct Hit {
    pub hash: ContentHash,
    /// The bytes of the entry's `summary.json` (parsed, typed, by [`Cache::serve`]).
    pub summary: Vec<u8>,
}

impl Cache {
    pub fn new(root: impl Into<PathBuf>) -> Self {
        Cache { root: root.into() }
    }

    /// The cache at `cache_dir`, or by default `<out_root>/.cache` (`--cache-dir`'s rule
    /// for `desal run`, `desal eval` and `desal cache gc`).
    pub fn for_output(cache_dir: Option<&Path>, out_root: &Path) -> Self {
        Cache::new(cache_dir.map_or_else(|| out_root.join(".cache"), Path::to_path_buf))
    }

    pub fn root(&self) -> &Path {
        &self.root
    }

    /// The folder of the entry for `key`.
    pub fn entry_dir(&self, key: &StageKey) -> PathBuf {
        self.root.join(&key.stage).join(key.hash().to_hex())
    }

    /// Looks up `key`, verifying the entry's envelope and checksum but not decoding its
    /// body. A corrupt entry is reported on stderr, removed, and treated as a miss.
    pub fn lookup<T: ArtifactBody>(&self, key: &StageKey) -> Option<Hit> {
        let dir = self.entry_dir(key);
        let path = dir.join("artifact.dsa");
        let bytes = desal_io::file::read_regular_file(&path).ok()?;
        match artifact::check_artifact::<T>(&path, &bytes).map_err(|e| e.to_string()).and_then(|header| {
            self.check_identity(key, &dir, &bytes)?;
            Ok(header)
        }) {
            Ok(header) => match desal_io::file::read_regular_file(&dir.join("summary.json")) {
                Ok(summary) => Some(Hit { hash: header.checksum, summary }),
                // Gone with its artifact: another run is replacing the entry, a miss.
                Err(_) if !path.exists() => None,
                Err(e) => {
                    self.reject(key, &format!("{}: {e}", dir.join("summary.json").display()));
                    None
                }
            },
            Err(_) if !path.exists() => None,
            Err(e) => {
                self.reject(key, &e);
                None
            }
        }
    }

    /// An entry is served only under its own key: its `key.json` and the producer inside
    /// its artifact must both be this key's (an artifact copied in from another entry, or
    /// a hand-edited one with a valid checksum, is refused).
    fn check_identity(&self, key: &StageKey, dir: &Path, bytes: &[u8]) -> Result<(), String> {
        let key_file = dir.join("key.json");
        let stored: StageKey = desal_io::atomic::read_json(&key_file).map_err(|e| e.to_string())?;
        if &stored != key {
            return Err(format!("{} is another key's entry", key_file.display()));
        }
        let path = dir.join("artifact.dsa");
        let (producer, _) = desal_io::codec::decode_prefix::<Producer>(&bytes[artifact::HEADER_LEN..])
            .map_err(|e| format!("{}: {e}", path.display()))?;
        let expected = key.producer(&[]);
        let same_inputs = producer.inputs.len() == expected.inputs.len()
            && producer
                .inputs
                .iter()
                .zip(&expected.inputs)
                .all(|(a, b)| a.role == b.role && a.hash == b.hash);
        if producer.stage != expected.stage
            || producer.stage_version != expected.stage_version
            || producer.parameters != expected.parameters
            || !same_inputs
        {
            return Err(format!("{}: its producer is not the key it is filed under", path.display()));
        }
        Ok(())
    }

    /// Reports a broken entry on stderr and evicts it, so the stage is recomputed.
    pub fn reject(&self, key: &StageKey, why: &str) {
        eprintln!("warning: cache entry rejected, recomputing: {why}");
        self.evict(key);
    }

    /// Removes the entry for `key`, if any: renamed out of its place first, then deleted,
    /// so a run killed halfway leaves a stray folder that no lookup reads, never a
    /// half-deleted entry under its key.
    pub fn evict(&self, key: &StageKey) {
        let dir = self.entry_dir(key);
        let parent = dir.parent().expect("entry has a parent");
        static EVICTED: AtomicU64 = AtomicU64::new(0);
        let n = EVICTED.fetch_add(1, Ordering::Relaxed);
        // Named as desal_io's leftovers are, so a kill between the two steps leaves
        // something the next store in this folder removes.
        let trash = parent.join(format!(".{}.old-{}-{n}", key.hash().to_hex(), std::process::id()));
        if fs::rename(&dir, &trash).is_ok() {
            let _ = fs::remove_dir_all(&trash);
        }
    }

    /// Stores an artifact and its summary under `key`, atomically (temp folder, rename;
    /// [`desal_io::create_dir_once`]: the first complete writer wins).
    /// Returns the artifact's content hash.
    pub fn store<T: ArtifactBody>(
        &self,
        key: &StageKey,
        producer: &Producer,
        body: &T,
        summary: &impl Serialize,
    ) -> Result<ContentHash> {
        let dir = self.entry_dir(key);
        self.mark()?;
        let mut hash = None;
        desal_io::create_dir_once(&dir, |tmp| -> Result<()> {
            hash = Some(artifact::write_artifact(&tmp.join("artifact.dsa"), producer, body)?);
            fault_point(&key.stage);
            desal_io::write_json(&tmp.join("summary.json"), summary)?;
            desal_io::write_json(&tmp.join("key.json"), key)?;
            Ok(())
        })
        .with_context(|| format!("cannot store cache entry {}", dir.display()))?;
        // When another run (a shard) stored the same key first, its entry is used: both
        // are equal by the key's construction, and the entry's own checksum says so.
        let hash = match hash {
            Some(hash) => hash,
            None => {
                let path = dir.join("artifact.dsa");
                let bytes = desal_io::file::read_regular_file(&path)?;
                artifact::check_artifact::<T>(&path, &bytes)?.checksum
            }
        };
        Ok(hash)
    }

    fn explain_path(&self, dataset: &str, stage: &str) -> PathBuf {
        self.root.join("explain").join(sanitize(dataset)).join(format!("{stage}.json"))
    }

    /// Why `key` missed for `dataset`, compared with the last run recorded for it.
    pub fn explain_miss(&self, dataset: &str, key: &StageKey) -> String {
        let path = self.explain_path(dataset, &key.stage);
        let Ok(old) = desal_io::atomic::read_json::<StageKey>(&path) else {
            return "no earlier run of this stage recorded for this dataset".into();
        };
        let diffs = key.differences(&old);
        if diffs.is_empty() {
            "same key as the last run, but its entry is gone (deleted, corrupt, or --force)".into()
        } else {
            diffs.join("; ")
        }
    }

    /// Serves one stage of `dataset`: the entry under `key` when there is one whose
    /// summary parses as `S` (unless `forced`), else `compute`d and stored, after
    /// `on_miss` is told why the cache missed. Records `key` as the stage's last run
    /// either way. An entry whose summary does not parse is corrupt: it is evicted and
    /// recomputed, like one that fails its checksum.
    pub fn serve<T: ArtifactBody, S: Serialize + DeserializeOwned>(
        &self,
        dataset: &str,
        key: &StageKey,
        hints: &[(String, String)],
        forced: bool,
        on_miss: impl FnOnce(&str),
        compute: impl FnOnce() -> Result<(T, StoredSummary<S>)>,
    ) -> Result<Served<T, S>> {
        let artifact = self.entry_dir(key).join("artifact.dsa");
        if !forced && let Some(hit) = self.lookup::<T>(key) {
            match serde_json::from_slice::<StoredSummary<S>>(&hit.summary) {
                Ok(stored) => {
                    self.record(dataset, key)?;
                    return Ok(Served { hash: hit.hash, artifact, stored, body: None, miss_reason: None });
                }
                Err(e) => {
                    self.reject(key, &format!("{}: {e}", artifact.with_file_name("summary.json").display()))
                }
            }
        }
        let reason =
            if forced { "forced (--force or --from)".to_owned() } else { self.explain_miss(dataset, key) };
        on_miss(&reason);
        let (body, stored) = compute()?;
        if forced {
            self.evict(key);
        }
        let hash = self.store(key, &key.producer(hints), &body, &stored)?;
        self.record(dataset, key)?;
        Ok(Served { hash, artifact, stored, body: Some(body), miss_reason: Some(reason) })
    }

    /// Records `key` as the last run of its stage for `dataset`.
    pub fn record(&self, dataset: &str, key: &StageKey) -> Result<()> {
        let path = self.explain_path(dataset, &key.stage);
        if let Some(dir) = path.parent() {
            desal_io::dir::remove_leftovers(dir);
        }
        Ok(desal_io::write_json(&path, key)?)
    }
}

/// The file that marks a folder as a desal cache: a Cache Directory Tag
/// (<https://bford.info/cachedir/>), which backup tools also honour. `desal cache gc`
/// deletes only inside a folder that has it, or that has a desal cache's layout.
pub const MARKER: &str = "CACHEDIR.TAG";
const MARKER_TEXT: &str = "Signature: 8a477f597d28d172789f06886806bc55\n\
    # This file is a cache directory tag created by desal (https://bford.info/cachedir/).\n\
    # Everything in this folder can be recomputed; `desal cache gc` tidies it.\n";

impl Cache {
    /// Writes the marker at the root, once (every store calls it). A run killed while
    /// writing it left a temp file beside it, removed first.
    fn mark(&self) -> Result<()> {
        let marker = self.root.join(MARKER);
        if !marker.is_file() {
            desal_io::dir::remove_leftovers(&self.root);
            desal_io::write_atomic(&marker, MARKER_TEXT.as_bytes())?;
        }
        Ok(())
    }

    /// Whether the root is a desal cache that [`Self::gc`] may tidy: it has the marker,
    /// does not exist yet, is empty, or has a desal cache's layout (a cache made before
    /// the marker existed, which then gets it). Anything else — a folder of user files
    /// given as `--cache-dir` by mistake — is refused with the first thing that is not
    /// a cache's, before anything is run or deleted.
    pub fn check_is_cache(&self) -> Result<()> {
        let root = &self.root;
        // The root itself is the user's path: a symlink to a folder is followed.
        match fs::metadata(root) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
            Err(e) => return Err(e).with_context(|| format!("cannot read {}", root.display())),
            Ok(meta) if !meta.is_dir() => bail!("{} is not a folder, so not a desal cache", root.display()),
            Ok(_) => {}
        }
        let marker = root.join(MARKER);
        if fs::symlink_metadata(&marker).is_ok_and(|m| m.is_file()) {
            // Other tools (cargo, borg, …) write the same standard tag: only desal's counts.
            let text = desal_io::file::read_regular_file(&marker).unwrap_or_default();
            if text.starts_with(MARKER_TEXT.as_bytes()) {
                return Ok(());
            }
            bail!(
                "{} is not a desal cache: its {MARKER} was written by another tool; `desal cache gc` deletes only \
                 inside a desal cache: check --cache-dir",
                root.display()
            );
        }
        let not_ours = |what: &Path, why: &str| {
            anyhow::anyhow!(
                "{} is not a desal cache ({MARKER} is missing and {} {why}); `desal cache gc` deletes only \
                 inside a desal cache: check --cache-dir",
                root.display(),
                what.display()
            )
        };
        let mut entries = 0;
        for stage in fs::read_dir(root).with_context(|| format!("cannot read {}", root.display()))? {
            let stage = stage.with_context(|| format!("cannot read {}", root.display()))?;
            let name = stage.file_name().to_string_lossy().into_owned();
            if name.starts_with('.') {
                continue;
            }
            if !stage.file_type().is_ok_and(|t| t.is_dir()) {
                return Err(not_ours(&stage.path(), "is not a stage folder"));
            }
            if name == "explain" {
                continue;
            }
            for entry in fs::read_dir(stage.path())
                .with_context(|| format!("cannot read {}", stage.path().display()))?
            {
                let entry = entry.with_context(|| format!("cannot read {}", stage.path().display()))?;
                if entry.file_name().to_string_lossy().starts_with('.') {
                    continue;
                }
                if entry_key(&name, &entry).is_none() {
                    return Err(not_ours(&entry.path(), "is not a cache entry"));
                }
                entries += 1;
            }
        }
        if entries > 0 {
            self.mark()?;
        }
        Ok(())
    }

    /// Removes every entry whose key is not in `keep` (hex keys), each by
    /// rename-then-delete, plus dead runs' leftovers; returns `(entries kept, entries
    /// removed, bytes freed)`. `desal cache gc` passes the keys of a pipeline's stages.
    /// An entry of `derived_stage` (`desal eval`'s floor, which no pipeline key names) is
    /// kept when every input its `key.json` records is in `inputs` (content hashes).
    ///
    /// Only a desal cache is tidied ([`Self::check_is_cache`]), only an entry that proves
    /// itself one is deleted (a real folder, not a symlink, whose `key.json` is the key
    /// its stage folder and name say), and no symlink is ever followed.
    pub fn gc(
        &self,
        keep: &std::collections::BTreeSet<String>,
        derived_stage: &str,
        inputs: &std::collections::BTreeSet<ContentHash>,
    ) -> Result<(usize, usize, u64)> {
        self.check_is_cache()?;
        let (mut kept, mut removed, mut freed) = (0, 0, 0);
        let Ok(stages) = fs::read_dir(&self.root) else { return Ok((0, 0, 0)) };
        for stage in stages.flatten() {
            let stage_dir = stage.path();
            let stage_name = stage.file_name().to_string_lossy().into_owned();
            if !stage.file_type().is_ok_and(|t| t.is_dir()) || stage_name == "explain" {
                continue;
            }
            desal_io::dir::remove_leftovers(&stage_dir);
            for entry in
                fs::read_dir(&stage_dir).with_context(|| format!("cannot read {}", stage_dir.display()))?
            {
                let entry = entry.with_context(|| format!("cannot read {}", stage_dir.display()))?;
                let name = entry.file_name().to_string_lossy().into_owned();
                if name.starts_with('.') {
                    continue;
                }
                let Some(key) = entry_key(&stage_name, &entry) else { continue };
                if keep.contains(&name) || uses_only(&key, derived_stage, inputs) {
                    kept += 1;
                    continue;
                }
                let mut size = 0;
                for file in fs::read_dir(entry.path())
                    .with_context(|| format!("cannot read {}", entry.path().display()))?
                {
                    size += file
                        .and_then(|f| f.metadata())
                        .map(|m| m.len())
                        .with_context(|| format!("cannot read {}", entry.path().display()))?;
                }
                let trash = stage_dir.join(format!(".{name}.old-{}-0", std::process::id()));
                fs::rename(entry.path(), &trash)
                    .with_context(|| format!("cannot remove {}", entry.path().display()))?;
                fs::remove_dir_all(&trash).with_context(|| format!("cannot remove {}", trash.display()))?;
                removed += 1;
                freed += size;
            }
        }
        Ok((kept, removed, freed))
    }
}

/// The files a cache entry holds ([`Cache::store`]).
const ENTRY_FILES: [&str; 3] = ["artifact.dsa", "summary.json", "key.json"];

/// The key of `entry`, in the stage folder `stage`, if it is a desal cache entry: a folder
/// (not a symlink) holding only regular files that [`Cache::store`] writes, whose
/// `key.json` is a key of that stage that hashes to the entry's name.
fn entry_key(stage: &str, entry: &fs::DirEntry) -> Option<StageKey> {
    if !entry.file_type().is_ok_and(|t| t.is_dir()) {
        return None;
    }
    let dir = entry.path();
    // `DirEntry::file_type` does not follow symlinks: a link among the files is not ours.
    let ours = |f: &fs::DirEntry| {
        f.file_type().is_ok_and(|t| t.is_file()) && ENTRY_FILES.iter().any(|name| f.file_name() == *name)
    };
    if !fs::read_dir(&dir).ok()?.flatten().all(|f| ours(&f)) {
        return None;
    }
    let key = desal_io::atomic::read_json::<StageKey>(&dir.join("key.json")).ok()?;
    (key.stage == stage && key.hash().to_hex() == entry.file_name().to_string_lossy()).then_some(key)
}

/// Whether the entry of `key` is one of `derived_stage` whose recorded inputs are all in
/// `inputs`. A stage's own entries are kept by key only.
fn uses_only(key: &StageKey, derived_stage: &str, inputs: &std::collections::BTreeSet<ContentHash>) -> bool {
    key.stage == derived_stage
        && !key.inputs.is_empty()
        && key.inputs.iter().all(|(_, hash)| inputs.contains(hash))
}

/// Test hook: with `DESAL_FAULT_ABORT_IN_STORE=<stage>`, the process aborts halfway
/// through storing that stage's entry, as a killed run would. The end-to-end tests use it
/// to prove that a killed run leaves no entry behind.
fn fault_point(stage: &str) {
    if std::env::var("DESAL_FAULT_ABORT_IN_STORE").is_ok_and(|s| s == stage) {
        std::process::abort();
    }
}

fn sanitize(name: &str) -> String {
    name.chars().map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c } else { '_' }).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key() -> StageKey {
        StageKey {
            stage: "simplify".into(),
            stage_version: 1,
            format_version: 1,
            parameters: r#"{"placement":"optimal","target_vertices":2500}"#.into(),
            resolved: r#"{"boundary_weight":10.0}"#.into(),
            inputs: vec![("poses".into(), ContentHash([1; 32])), ("saliency".into(), ContentHash([2; 32]))],
        }
    }

    /// A shard that reads an entry's file while another replaces the entry (evicted,
    /// then stored again) gets the stored file; a file that stays missing is an error
    /// once the wait is over. (CI once failed a shard's copy of an entry another
    /// shard's `--force` run had just evicted.)
    #[test]
    fn an_entry_file_being_replaced_is_waited_for() {
        let dir = std::env::temp_dir().join(format!("desal-cache-replaced-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("artifact.dsa");
        let writer = {
            let path = path.clone();
            std::thread::spawn(move || {
                std::thread::sleep(Duration::from_millis(50));
                // As the cache stores an entry: written aside, then renamed into place
                // (a plain `fs::write` creates the file empty first, and a reader
                // polling for it could read it then: CI once did).
                let aside = path.with_extension("dsa.tmp");
                fs::write(&aside, b"stored again").unwrap();
                fs::rename(&aside, &path).unwrap();
            })
        };
        let read = read_entry_file_within(&path, Duration::from_secs(20), |p: &Path| fs::read(p));
        writer.join().unwrap();
        assert_eq!(read.unwrap(), b"stored again");
        fs::remove_file(&path).unwrap();
        let start = Instant::now();
        assert!(read_entry_file_within(&path, Duration::from_millis(30), |p: &Path| fs::read(p)).is_err());
        assert!(start.elapsed() >= Duration::from_millis(30));
        fs::remove_dir_all(&dir).unwrap();
    }

    /// Every component of the key changes the key (one test per key input).
    #[test]
    fn every_component_changes_the_key() {
        let base = key().hash();
        let mut k = key();
        k.stage = "map".into();
        assert_ne!(k.hash(), base);
        let mut k = key();
        k.stage_version = 2;
        assert_ne!(k.hash(), base);
        let mut k = key();
        k.format_version = 2;
        assert_ne!(k.hash(), base);
        let mut k = key();
        k.parameters = r#"{"placement":"subset","target_vertices":2500}"#.into();
        assert_ne!(k.hash(), base);
        let mut k = key();
        k.resolved = r#"{"boundary_weight":5.0}"#.into();
        assert_ne!(k.hash(), base, "a changed default changes the key");
        let mut k = key();
        k.inputs[1].1 = ContentHash([3; 32]);
        assert_ne!(k.hash(), base);
        let mut k = key();
        k.inputs[0].0 = "other".into();
        assert_ne!(k.hash(), base);
        assert_eq!(key().hash(), base, "the key is a pure function of its components");
    }

    #[test]
    fn differences_name_the_changed_parameter_and_input() {
        let mut k = key();
        k.parameters = r#"{"placement":"optimal","target_vertices":3000}"#.into();
        k.inputs[1].1 = ContentHash([9; 32]);
        let d = k.differences(&key()).join("; ");
        assert!(d.contains("target_vertices 2500 -> 3000"), "{d}");
        assert!(d.contains("input content changed: saliency"), "{d}");
    }
}
