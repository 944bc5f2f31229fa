//! A stable-Rust mutation fuzzer for desal's readers: PLY, OBJ, OFF, text and JSON part
//! labels (names in any script), the binary artifacts (every kind, with the checksum
//! recomputed after most mutations so that the payload decoder is what gets attacked),
//! skinned glTF rigs in both containers (`.gltf` with `data:` URI buffers, `.glb`),
//! body-model pickles (the restricted unpickler, `pickle::unpickle`), and
//! `hierarchy.npz`; the last three are mutated structurally ([`mutate::gltf`],
//! [`mutate::npz`]) so that well-formed files with lying numbers reach the decoders.
//!
//! Each target mutates its seeds ([`corpus`]) with [`mutate`] and hands the bytes to the
//! reader's in-memory entry point (`desal_io::read_mesh_from`, `labels::read_labels_from`,
//! `artifact::decode_artifact`, `desal_rig::read_rig_from`, `npz::decode_npz` then
//! `HierarchyArrays::from_arrays`). A reader may refuse an input — that is its job — but it
//! must never panic, abort, or hang. Input `i` of a run depends only on `(seed, target,
//! i)`, so a finding can be regenerated and is saved by the supervisor
//! ([`supervise`]), which runs each target in a child process (an abort, or an
//! allocation past the child's memory limit, kills only the child) under a watchdog.
//!
//! After a successful decode the target also uses the result the way desal does: an
//! artifact body is indexed by its ids and converted to the in-memory types; a rig is
//! posed at a few frames, welded, labelled and, when small, written as the simplified
//! rig and read back ([`use_rig`]); a hierarchy is turned back into arrays and encoded,
//! as the Python package's `read_hierarchy_npz` and `write_hierarchy_npz` do. A result
//! that passed validation but panics in its user is a finding too.

pub mod canary;
pub mod corpus;
pub mod mutate;
pub mod supervise;

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use desal_io::artifact::{
    self, ArtifactBody, ArtifactKind, FitV1, FloorV1, HEADER_LEN, HierarchyLevelV1, LabelsV1, MapV1,
    PoseSetV2, SaliencyV1, SimplifiedV1,
};
use desal_io::npz::HierarchyArrays;
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
    /// A `.gltf` rig, its buffers as base64 `data:` URIs.
    GltfJson,
    /// A `.glb` rig (JSON and BIN chunks).
    GltfGlb,
    /// `hierarchy.npz`.
    Npz,
    /// A body-model `.pkl` through the restricted unpickler.
    Pickle,
    /// Panics on iteration 2: proves the harness catches and saves a panic.
    CanaryPanic,
    /// Aborts on iteration 2: proves the supervisor catches an abort.
    CanaryAbort,
    /// Hangs on iteration 2: proves the watchdog catches a hang.
    CanaryHang,
    /// Reserves 64 GiB on iteration 2: proves the memory limit turns a huge allocation
    /// (which overcommit might grant) into an abort.
    CanaryOom,
    /// Fills 1.1 GiB on iteration 2 and frees it: proves the peak-memory check catches a
    /// reader that stays under the limit only because the limit stopped it.
    CanaryMemory,
    /// The `gltf-glb` target's inputs fed to a reader with issue 39's D1 planted: it
    /// panics on an accessor whose buffer view's `byteStride` is smaller than its element.
    /// Proves the structural mutations produce that input and the harness saves it,
    /// whatever the real reader does with it.
    CanaryGltfStride,
    /// The `npz` target's inputs fed to a reader that trusts the npy `shape`: it panics
    /// when the shape does not match the data's length. Proves the npy header edits reach
    /// a decoder with valid CRCs, and the harness saves the input.
    CanaryNpzShape,
}

impl Target {
    /// The real targets, in the order a run visits them.
    pub const ALL: [Target; 10] = [
        Target::Ply,
        Target::Obj,
        Target::Off,
        Target::LabelsText,
        Target::LabelsJson,
        Target::Artifact,
        Target::GltfJson,
        Target::GltfGlb,
        Target::Npz,
        Target::Pickle,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Target::Ply => "ply",
            Target::Obj => "obj",
            Target::Off => "off",
            Target::LabelsText => "labels-text",
            Target::LabelsJson => "labels-json",
            Target::Artifact => "artifact",
            Target::GltfJson => "gltf-json",
            Target::GltfGlb => "gltf-glb",
            Target::Npz => "npz",
            Target::Pickle => "pickle",
            Target::CanaryPanic => "canary-panic",
            Target::CanaryAbort => "canary-abort",
            Target::CanaryHang => "canary-hang",
            Target::CanaryOom => "canary-oom",
            Target::CanaryMemory => "canary-memory",
            Target::CanaryGltfStride => "canary-gltf-stride",
            Target::CanaryNpzShape => "canary-npz-shape",
        }
    }

    /// The canaries: targets that crash on purpose, one per kind of detection.
    pub const CANARIES: [Target; 7] = [
        Target::CanaryPanic,
        Target::CanaryAbort,
        Target::CanaryHang,
        Target::CanaryOom,
        Target::CanaryMemory,
        Target::CanaryGltfStride,
        Target::CanaryNpzShape,
    ];

    pub fn from_name(name: &str) -> Option<Target> {
        Self::ALL.into_iter().chain(Self::CANARIES).find(|t| t.name() == name)
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
            Target::GltfJson => "fuzz.gltf",
            Target::GltfGlb => "fuzz.glb",
            Target::Npz => "hierarchy.npz",
            Target::Pickle => "model.pkl",
            Target::CanaryGltfStride => "canary.glb",
            Target::CanaryNpzShape => "canary.npz",
            _ => "canary.bin",
        }
    }

    /// Whether an input may make the reader allocate without bound (a glTF buffer URI of
    /// `/dev/zero`, a forged sparse count), so that it must only run in a child under
    /// the supervisor's memory limit, never in a test process.
    pub fn needs_memory_limit(self) -> bool {
        matches!(self, Target::GltfJson | Target::GltfGlb | Target::CanaryOom | Target::CanaryMemory)
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
    let mut bytes = match target {
        Target::GltfJson => mutate::gltf::mutate_gltf(&mut rng, base, donor),
        Target::GltfGlb | Target::CanaryGltfStride => mutate::gltf::mutate_glb(&mut rng, base, donor),
        Target::Npz | Target::CanaryNpzShape => mutate::npz::mutate_npz(&mut rng, base, donor),
        _ => mutate::mutate(&mut rng, base, donor),
    };
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
                // Outputs write these labels as text (`simplified/parts.txt`); desal must
                // read that file back as the same labels, whatever the names hold.
                let text = desal_io::labels::labels_txt(&labels);
                match desal_io::labels::read_labels_from(Path::new("parts.txt"), text.as_bytes()) {
                    Ok(back) => assert!(
                        back == labels,
                        "parts.txt written from these labels reads back as other labels: names {:?} -> {:?}",
                        labels.names,
                        back.names
                    ),
                    Err(e) => panic!("parts.txt written from these labels is refused: {e}"),
                }
                true
            }
            Err(e) => message_names_file(&e, path),
        },
        Target::Artifact => execute_artifact(path, bytes),
        Target::GltfJson | Target::GltfGlb => {
            match desal_rig::read_rig_from(path, bytes, &desal_rig::ReadOptions::default()) {
                Ok(rig) => {
                    use_rig(path, &rig);
                    true
                }
                // The reader's panic guard turns a panic inside the `gltf` crate into an
                // error; for the fuzzer it is still a finding (an accessor check missed).
                Err(desal_rig::RigError::Panic { message, .. }) => {
                    panic!("caught by the rig reader: {message}")
                }
                Err(e) => {
                    let text = e.to_string();
                    assert!(text.contains(&*path.to_string_lossy()), "an error without the path: {text}");
                    false
                }
            }
        }
        Target::Npz => {
            match desal_io::npz::decode_npz(bytes).and_then(|a| HierarchyArrays::from_arrays(&a)) {
                Ok(hierarchy) => {
                    // What the Python package does with it (`read_hierarchy_npz` hands
                    // `to_arrays` to numpy) and what its writer does with those arrays.
                    if let Ok(arrays) = hierarchy.to_arrays() {
                        let _ = desal_io::npz::encode_npz(&arrays);
                    }
                    true
                }
                Err(_) => false,
            }
        }
        // What desal-bodymodel does with a pickle: walk the value for its arrays.
        Target::Pickle => match desal_io::pickle::unpickle(bytes) {
            Ok(value) => {
                let mut arrays = 0;
                walk_pickle(&value, &mut arrays);
                true
            }
            Err(_) => false,
        },
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
        Target::CanaryMemory => {
            if iteration == 2 {
                let filled = vec![1u8; 1100 << 20];
                std::hint::black_box(&filled);
            }
            false
        }
        Target::CanaryGltfStride => {
            if let Some((accessor, stride, element)) = canary::short_stride(bytes) {
                panic!("canary: accessor {accessor} has byteStride {stride} < its {element}-byte element");
            }
            false
        }
        Target::CanaryNpzShape => {
            if let Some((entry, shape, len)) = canary::shape_mismatch(bytes) {
                panic!("canary: npy entry {entry} has shape {shape} but {len} data bytes");
            }
            false
        }
    }
}

/// Frames of a rig: its animations and random rotations, three of each, as `desal run`
/// samples them (`[dataset.rig] poses`, `frames`).
const RIG_FRAMES: desal_rig::FrameConfig =
    desal_rig::FrameConfig { source: desal_rig::PoseSource::Both, frames: 3, seed: 0, max_degrees: 30.0 };

/// Rigs with at most this many vertices are also written as a simplified rig and read
/// back (cheap for the generated seeds; the sample rig's 14 517 vertices are not).
const RIG_WRITE_LIMIT: usize = 2000;

/// Uses a rig the reader accepted as `desal run` does (`crates/driver/src/stages/rig.rs`): frames
/// sampled, the welded mesh posed, its seams found, its dominant-joint labels, and for a
/// small rig the simplified rig (here: every welded vertex kept, subset placement)
/// written as a `.glb` that desal's own reader must accept.
pub fn use_rig(path: &Path, rig: &desal_rig::Rig) {
    let frames = desal_rig::sample_frames(rig, &RIG_FRAMES, path).or_else(|_| {
        let random = desal_rig::FrameConfig { source: desal_rig::PoseSource::Random, ..RIG_FRAMES };
        desal_rig::sample_frames(rig, &random, path)
    });
    let Ok(frames) = frames else { return };
    // A refusal here (non-finite poses) is a clean error, not a finding.
    let Ok(posed) = desal_rig::pose_rig(rig, &frames) else { return };
    let _ = desal_rig::seam_edges(&rig.mesh, &posed.weld);
    let labels = desal_rig::dominant_joint_parts(
        rig,
        &posed.influences,
        &desal_rig::PartsConfig { min_part_vertices: 2 },
    );
    assert_eq!(labels.labels.len(), posed.poses.vertex_count(), "a label per welded vertex");
    if rig.mesh.vertex_count() > RIG_WRITE_LIMIT {
        return;
    }
    let welded = posed.weld.welded_count() as u32;
    let simp_to_welded: Vec<u32> = (0..welded).collect();
    let input = desal_rig::SimplifiedInput {
        positions: posed.poses.template_positions(),
        faces: &posed.weld.faces,
        simp_to_welded: &simp_to_welded,
        subset: true,
    };
    let targets = desal_rig::PoseTargets { joints: &posed.joints, positions: &posed.poses.poses };
    let Ok((out, _)) = desal_rig::simplified_rig(rig, &posed.weld, &input, &targets) else { return };
    let written = desal_rig::write_glb(&out).expect("a rig that was read can be written");
    let simplified = Path::new("simplified.glb");
    if let Err(e) = desal_rig::read_rig_from(simplified, &written, &desal_rig::ReadOptions::default()) {
        panic!("desal wrote a simplified.glb it refuses: {e}");
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
        ArtifactKind::PoseSet => decoded::<PoseSetV2>(path, bytes, |b| {
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
/// Refuses (panics on) a target that [needs the memory limit](Target::needs_memory_limit).
pub fn run_in_process(
    target: Target,
    seeds: &[corpus::Seed],
    seed: u64,
    range: std::ops::Range<u64>,
) -> Tally {
    assert!(!target.needs_memory_limit(), "{} runs only under the supervisor's memory limit", target.name());
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

/// Counts the arrays of a pickled value and checks each holds as many values as its shape
/// says, as a body-model reader relies on.
fn walk_pickle(value: &desal_io::pickle::PyValue, arrays: &mut usize) {
    use desal_io::pickle::PyValue;
    match value {
        PyValue::Array(a) => {
            *arrays += 1;
            assert_eq!(a.shape.iter().product::<usize>(), a.data.len(), "an array whose shape lies");
        }
        PyValue::List(items) | PyValue::Tuple(items) | PyValue::Set(items) => {
            items.iter().for_each(|v| walk_pickle(v, arrays))
        }
        PyValue::Dict(items) => items.iter().for_each(|(k, v)| {
            walk_pickle(k, arrays);
            walk_pickle(v, arrays);
        }),
        PyValue::Object { args, state, .. } => {
            args.iter().for_each(|v| walk_pickle(v, arrays));
            if let Some(state) = state {
                walk_pickle(state, arrays);
            }
        }
        _ => {}
    }
}
