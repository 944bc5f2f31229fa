//! A stable-Rust mutation fuzzer for desal's readers: PLY, OBJ, OFF, text and JSON part
//! labels, and the binary artifacts (every kind, with the checksum recomputed after
//! most mutations so that the payload decoder is what gets attacked).
//!
//! Each target mutates its seeds ([`corpus`]) with [`mutate`] and hands the bytes to the
//! reader's in-memory entry point (`desal_io::read_mesh_from`, `labels::read_labels_from`,
//! `artifact::decode_artifact`). A reader may refuse an input — that is its job — but it
//! must never panic, abort, or hang. Input `i` of a run depends only on `(seed, target,
//! i)`, so a finding can be regenerated and is saved by the supervisor
//! ([`supervise`]), which runs each target in a child process (an abort, or an
//! allocation past the child's memory limit, kills only the child) under a watchdog.
//!
//! After a successful artifact decode the target also uses the body the way desal's
//! stages do (indexing names by ids, positions by faces, converting to the in-memory
//! types): a decoded body that passed validation but panics in its user is a finding too.

pub mod corpus;
pub mod mutate;
pub mod supervise;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use desal_io::artifact::{
    self, ArtifactBody, ArtifactKind, FitV1, FloorV1, HEADER_LEN, HierarchyLevelV1, LabelsV1, MapV1,
    PoseSetV1, SaliencyV1, SimplifiedV1,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// What a fuzz target feeds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    Ply,
    Obj,
    Off,
    LabelsText,
    LabelsJson,
    Artifact,
    /// Panics on iteration 2: proves the harness catches and saves a panic.
    CanaryPanic,
    /// Aborts on iteration 2: proves the supervisor catches an abort.
    CanaryAbort,
    /// Hangs on iteration 2: proves the watchdog catches a hang.
    CanaryHang,
    /// Reserves 64 GiB on iteration 2: proves the memory limit turns a huge allocation
    /// (which overcommit might grant) into an abort.
    CanaryOom,
}

impl Target {
    /// The real targets, in the order a run visits them.
    pub const ALL: [Target; 6] =
        [Target::Ply, Target::Obj, Target::Off, Target::LabelsText, Target::LabelsJson, Target::Artifact];

    pub fn name(self) -> &'static str {
        match self {
            Target::Ply => "ply",
            Target::Obj => "obj",
            Target::Off => "off",
            Target::LabelsText => "labels-text",
            Target::LabelsJson => "labels-json",
            Target::Artifact => "artifact",
            Target::CanaryPanic => "canary-panic",
            Target::CanaryAbort => "canary-abort",
            Target::CanaryHang => "canary-hang",
            Target::CanaryOom => "canary-oom",
        }
    }

    pub fn from_name(name: &str) -> Option<Target> {
        Self::ALL
            .into_iter()
            .chain([Target::CanaryPanic, Target::CanaryAbort, Target::CanaryHang, Target::CanaryOom])
            .find(|t| t.name() == name)
    }

    /// The file name the reader is told it reads (its extension picks the format).
    pub fn file_name(self) -> &'static str {
        match self {
            Target::Ply => "fuzz.ply",
            Target::Obj => "fuzz.obj",
            Target::Off => "fuzz.off",
            Target::LabelsText => "fuzz-labels.txt",
            Target::LabelsJson => "fuzz-labels.json",
            Target::Artifact => "fuzz.dsa",
            _ => "canary.bin",
        }
    }

    fn code(self) -> u64 {
        self as u64 + 1
    }
}

/// Input `iteration` of a run of `target` with `seed`: a mutant of one seed, a function
/// of the three numbers alone.
pub fn input(target: Target, seeds: &[corpus::Seed], seed: u64, iteration: u64) -> Vec<u8> {
    let mixed = seed ^ target.code().rotate_left(56) ^ iteration.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let mut rng = ChaCha8Rng::seed_from_u64(mixed);
    let base = &seeds[rng.gen_range(0..seeds.len())].bytes;
    let donor = &seeds[rng.gen_range(0..seeds.len())].bytes;
    let mut bytes = mutate::mutate(&mut rng, base, donor);
    // Most artifact mutants get a valid length and checksum, as a forger would give
    // them: without that the checksum refuses nearly everything before the decoder runs.
    if target == Target::Artifact && bytes.len() >= HEADER_LEN && rng.gen_bool(0.85) {
        reseal(&mut bytes);
    }
    bytes
}

/// Recomputes an artifact's payload length and checksum fields.
pub fn reseal(bytes: &mut [u8]) {
    let payload_len = (bytes.len() - HEADER_LEN) as u64;
    bytes[16..24].copy_from_slice(&payload_len.to_le_bytes());
    let hash = desal_io::ContentHash::of(&bytes[HEADER_LEN..]);
    bytes[24..56].copy_from_slice(&hash.0);
}

/// Runs one input through `target`'s reader: `true` when the reader accepted it,
/// `false` when it refused it with an error. A panic propagates (the caller catches it).
pub fn execute(target: Target, iteration: u64, bytes: &[u8]) -> bool {
    let path = Path::new(target.file_name());
    match target {
        Target::Ply => match desal_io::ply::read_ply_from(path, bytes) {
            Ok(full) => {
                check_mesh(&full.mesh);
                assert!(full.scalars.iter().all(|(_, values)| values.len() == full.mesh.vertex_count()));
                true
            }
            Err(e) => message_names_file(&e, path),
        },
        Target::Obj | Target::Off => match desal_io::read_mesh_from(path, bytes) {
            Ok(mesh) => {
                check_mesh(&mesh);
                true
            }
            Err(e) => message_names_file(&e, path),
        },
        Target::LabelsText | Target::LabelsJson => match desal_io::labels::read_labels_from(path, bytes) {
            Ok(labels) => {
                let members = labels.members();
                assert!(members.iter().all(|m| !m.is_empty()), "an empty part was accepted");
                true
            }
            Err(e) => message_names_file(&e, path),
        },
        Target::Artifact => execute_artifact(path, bytes),
        Target::CanaryPanic => {
            assert!(iteration != 2, "canary panic");
            false
        }
        Target::CanaryAbort => {
            if iteration == 2 {
                std::process::abort();
            }
            false
        }
        Target::CanaryHang => {
            if iteration == 2 {
                loop {
                    std::thread::sleep(std::time::Duration::from_secs(1));
                }
            }
            false
        }
        Target::CanaryOom => {
            if iteration == 2 {
                let reserved: Vec<u8> = Vec::with_capacity(64 << 30);
                std::hint::black_box(&reserved);
            }
            false
        }
    }
}

/// The mesh invariants every stage relies on (indices in range, finite coordinates).
fn check_mesh(mesh: &desal_mesh::TriMesh) {
    assert!(
        mesh.faces.iter().flatten().all(|&v| (v as usize) < mesh.vertex_count()),
        "a face index out of range"
    );
    assert!(mesh.positions.iter().all(|p| p.iter().all(|c| c.is_finite())), "a non-finite coordinate");
}

/// Every reader error must name the file (the readers' invariant): a message without
/// it is a finding, reported as a panic.
fn message_names_file(error: &desal_io::IoError, path: &Path) -> bool {
    let text = error.to_string();
    assert!(text.contains(&*path.to_string_lossy()), "an error without the path: {text}");
    false
}

fn execute_artifact(path: &Path, bytes: &[u8]) -> bool {
    let Ok(header) = artifact::check_envelope(path, bytes) else { return false };
    let _ = artifact::decode_producer(path, bytes);
    match header.kind {
        ArtifactKind::PoseSet => decoded::<PoseSetV1>(path, bytes, |b| {
            let set = b.to_pose_set().expect("a validated pose set converts");
            let _ = set.template_mesh().diagonal();
        }),
        ArtifactKind::Labels => decoded::<LabelsV1>(path, bytes, |b| {
            let labels = b.to_labels().expect("validated labels convert");
            let _ = labels.members();
        }),
        ArtifactKind::Fit => decoded::<FitV1>(path, bytes, |b| {
            // What `desal inspect` prints: names by the summaries' ids, residual rows.
            for &(part, _, _, pose) in &b.worst_parts {
                let _ = (&b.part_names[part as usize], &b.pose_names[pose as usize]);
            }
            for &(pose, _, _, part) in &b.worst_poses {
                let _ = (&b.part_names[part as usize], &b.pose_names[pose as usize]);
            }
            let n = b.vertex_count as usize;
            for pose in 0..b.pose_names.len() {
                let _ = &b.residuals[pose * n..(pose + 1) * n];
                let _ = b.linear[pose * b.part_names.len()..(pose + 1) * b.part_names.len()].len();
            }
        }),
        ArtifactKind::Saliency => decoded::<SaliencyV1>(path, bytes, |b| {
            for v in 0..b.saliency.len() {
                let _ = (b.weights[v], b.raw[v]);
            }
        }),
        ArtifactKind::Simplified => decoded::<SimplifiedV1>(path, bytes, |b| {
            for f in &b.faces {
                let _ = f.map(|v| (b.positions[v as usize], b.simp_to_orig[v as usize]));
            }
        }),
        ArtifactKind::Map => decoded::<MapV1>(path, bytes, |b| {
            for f in &b.faces {
                let _ = f.map(|v| b.simp_to_orig[v as usize]);
            }
        }),
        ArtifactKind::HierarchyLevel => decoded::<HierarchyLevelV1>(path, bytes, |b| {
            // What the npz writer indexes: the maps by coarse vertex, U by its triplets.
            for f in &b.faces {
                let _ = f.map(|c| (b.coarse_to_fine[c as usize], b.coarse_to_orig[c as usize]));
            }
            for k in 0..b.up_row.len() {
                let _ = (b.up_col[k], b.up_data[k], b.coarse_to_fine[b.up_col[k] as usize]);
            }
        }),
        ArtifactKind::Floor => decoded::<FloorV1>(path, bytes, |b| {
            // What `desal inspect` prints: the ratios of validated, finite errors.
            let _ = (b.held_out_v2v / b.in_sample_v2v, b.held_out_v2f / b.in_sample_v2f);
        }),
    }
}

fn decoded<T: ArtifactBody>(path: &Path, bytes: &[u8], use_body: impl FnOnce(&T)) -> bool {
    match artifact::decode_artifact::<T>(path, bytes) {
        Ok((_, body, _)) => {
            use_body(&body);
            true
        }
        Err(e) => message_names_file(&e, path),
    }
}

/// What an in-process run found.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Tally {
    pub executions: u64,
    /// Inputs the reader accepted (the rest it refused with an error).
    pub accepted: u64,
    /// `(iteration, panic message)` of every panic.
    pub panics: Vec<(u64, String)>,
}

/// Runs iterations `range` of `target` in this process, catching panics (not aborts or
/// hangs: the supervisor covers those). For tests; `desal-fuzz` uses [`supervise`].
pub fn run_in_process(
    target: Target,
    seeds: &[corpus::Seed],
    seed: u64,
    range: std::ops::Range<u64>,
) -> Tally {
    let mut tally = Tally::default();
    for iteration in range {
        let bytes = input(target, seeds, seed, iteration);
        tally.executions += 1;
        match catch_unwind(AssertUnwindSafe(|| execute(target, iteration, &bytes))) {
            Ok(accepted) => tally.accepted += u64::from(accepted),
            Err(payload) => tally.panics.push((iteration, panic_message(&*payload))),
        }
    }
    tally
}

/// The text of a panic payload.
pub fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "a panic with a non-text payload".into())
}
