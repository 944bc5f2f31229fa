//! The one error type of `desal-rig`. Every variant names the file and the glTF element
//! (mesh, primitive, accessor, vertex, joint) at fault, and says how to fix it.

use std::path::PathBuf;

/// Why a rig could not be read, posed or written.
#[derive(Debug, thiserror::Error)]
pub enum RigError {
    #[error("{path}: cannot read: {cause}")]
    Io { path: PathBuf, cause: std::io::Error },
    #[error("{path}: not a valid glTF 2.0 file: {cause}")]
    Gltf { path: PathBuf, cause: gltf::Error },
    #[error("{path}: buffer {buffer}: {reason}")]
    Buffer { path: PathBuf, buffer: usize, reason: String },
    #[error("{path}: no skinned mesh (no node has both a mesh and a skin); desal needs a rigged body")]
    NoSkin { path: PathBuf },
    #[error("{path}: {count} skinned meshes ({names}); name one with `mesh = \"...\"` in [dataset.rig]")]
    SeveralSkinnedMeshes { path: PathBuf, count: usize, names: String },
    #[error("{path}: no skinned mesh or node is called '{wanted}'; the skinned meshes are: {names}")]
    NoSuchMesh { path: PathBuf, wanted: String, names: String },
    #[error("{path}: mesh '{mesh}' primitive {primitive}: {reason}")]
    Primitive { path: PathBuf, mesh: String, primitive: usize, reason: String },
    #[error(
        "{path}: mesh '{mesh}' primitive {primitive} has {targets} morph target(s); rigs with morph targets are not supported yet: remove them (e.g. bake or delete the shape keys) and export again"
    )]
    MorphTargets { path: PathBuf, mesh: String, primitive: usize, targets: usize },
    #[error(
        "{path}: mesh '{mesh}' vertex {vertex}: skinning weights sum to {sum} (JOINTS_n/WEIGHTS_n), not 1; normalise the weights in the exporter"
    )]
    WeightsNotNormalised { path: PathBuf, mesh: String, vertex: usize, sum: f64 },
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
    #[error("{path}: node {node}: {reason}")]
    Node { path: PathBuf, node: usize, reason: String },
    #[error(
        "{path}: poses = \"animations\" asks for frames of the file's animations, but it has none; use poses = \"random\""
    )]
    NoAnimations { path: PathBuf },
    #[error("pose settings: {0}")]
    Settings(String),
    #[error("simplified rig: {0}")]
    Output(String),
}
