//! The one error type of `desal-rig`. Every variant names the file and the glTF element
//! (mesh, primitive, accessor, vertex, joint) at fault, and says how to fix it.

use std::path::{Path, PathBuf};

/// Why a rig could not be read, posed or written.
#[derive(Debug, thiserror::Error)]
pub enum RigError {
    /// The rig file or a buffer it names could not be read: not a regular file, a buffer
    /// URI outside the rig's folder, or an OS error (the message names the path).
    #[error(transparent)]
    File(#[from] desal_io::IoError),
    #[error("{path}: not a valid glTF 2.0 file: {cause}")]
    Gltf { path: PathBuf, cause: gltf::Error },
    #[error(
        "{path}: its meshes are compressed ({extension}), which desal does not decode: decompress it first, e.g. `gltfpack -i IN -o OUT -noq` for meshopt compression, or glTF-Transform for Draco"
    )]
    Compressed { path: PathBuf, extension: String },
    /// The `gltf` crate panicked on the file: a gap in desal's checks; report it.
    #[error("{path}: the glTF reader failed on this file ({message}); please report it with the file")]
    Panic { path: PathBuf, message: String },
    /// An accessor breaks the glTF 2.0 specification for what reads it (type, component
    /// type, layout within its buffer view, sparse indices).
    #[error("{path}: accessor {accessor} ({semantic} of {used_by}): {reason}")]
    Accessor { path: PathBuf, accessor: usize, semantic: String, used_by: String, reason: String },
    /// An element of the document refers to one the file lacks, or holds a value the
    /// specification does not list; `element` names it by index and name (`animation 0
    /// 'wave' channel 2`, `mesh 1 'body' primitive 0`, `accessor 4`).
    #[error("{path}: {element}: {reason}")]
    Structure { path: PathBuf, element: String, reason: String },
    #[error("{path}: buffer {buffer}: {reason}")]
    Buffer { path: PathBuf, buffer: usize, reason: String },
    #[error("{path}: no skinned mesh (no node has both a mesh and a skin); desal needs a rigged body")]
    NoSkin { path: PathBuf },
    #[error(
        "{path}: mesh = '{wanted}' names no skinned mesh or mesh below a bone (by mesh name, node name or mesh index); the meshes are: {names}"
    )]
    NoSuchMesh { path: PathBuf, wanted: String, names: String },
    /// A `[dataset.rig.meshes."NAME"]` whose name is none of the simplified meshes'.
    #[error(
        "{path}: rig.meshes names '{wanted}', which is no mesh desal simplifies here (by mesh name, node name or mesh index); the meshes are: {names}"
    )]
    NoSuchMeshOverride { path: PathBuf, wanted: String, names: String },
    #[error("{path}: mesh '{mesh}' primitive {primitive}: {reason}")]
    Primitive { path: PathBuf, mesh: String, primitive: usize, reason: String },
    #[error(
        "{path}: mesh '{mesh}' vertex {vertex}: every skinning weight is zero (JOINTS_n/WEIGHTS_n), so no joint moves it; weight it in the exporter"
    )]
    NoWeight { path: PathBuf, mesh: String, vertex: usize },
    #[error(
        "{path}: mesh '{mesh}' vertex {vertex}: joint {joint} has weight {weight}, but skin '{skin}' has only {joint_count} joints"
    )]
    JointOutOfRange {
        path: PathBuf,
        mesh: String,
        vertex: usize,
        joint: usize,
        weight: f64,
        skin: String,
        joint_count: usize,
    },
    #[error("{path}: mesh '{mesh}' vertex {vertex}: {what} is not a finite, non-negative number")]
    BadValue { path: PathBuf, mesh: String, vertex: usize, what: String },
    #[error("{path}: skin '{skin}': {reason}")]
    Skin { path: PathBuf, skin: String, reason: String },
    #[error("{path}: animation '{animation}' channel {channel}: {reason}")]
    Animation { path: PathBuf, animation: String, channel: usize, reason: String },
    /// `label` is `node 3 'hip'` (or `node 3` when unnamed).
    #[error("{path}: {label}: {reason}")]
    Node { path: PathBuf, node: usize, label: String, reason: String },
    /// A sampled frame that cannot be posed: a joint that moves vertices collapses or
    /// overflows there; the reason names the joint, the node and the animation.
    #[error("{path}: pose '{pose}': {reason}")]
    Pose { path: PathBuf, pose: String, reason: String },
    /// A posed position beyond `f32` (the caller adds the file).
    #[error("pose '{pose}': welded vertex {vertex} {reason}")]
    Posed { pose: String, vertex: usize, reason: String },
    #[error(
        "{path}: poses = \"animations\" asks for frames of the file's animations, but it has none; use poses = \"random\""
    )]
    NoAnimations { path: PathBuf },
    #[error("pose settings: {0}")]
    Settings(String),
    #[error("simplified rig: {0}")]
    Output(String),
    /// The local three.js package asked for an offline `view.html` (`DESAL_THREE`) lacks a
    /// file the page uses, or holds another version's: `problem` names the file.
    #[error(
        "offline view.html: {problem}; it inlines npm three {version} from {dir}: run `npm install three@{version}` and give its node_modules/three folder"
    )]
    Three { dir: PathBuf, version: String, problem: String },
}

/// `read()`, with a panic turned into [`RigError::Panic`] naming `path`.
pub(crate) fn without_panics<T>(
    path: &Path,
    read: impl FnOnce() -> Result<T, RigError>,
) -> Result<T, RigError> {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(read)).unwrap_or_else(|panic| {
        let message = panic
            .downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "no message".into());
        Err(RigError::Panic { path: path.to_owned(), message })
    })
}
