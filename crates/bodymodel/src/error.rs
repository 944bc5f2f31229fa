//! `BodyModelError`: every way a body-model file can be refused, or a parameter set or
//! sampling configuration rejected, naming the key, joint or parameter at fault.

use std::path::PathBuf;

use thiserror::Error;

#[derive(Debug, Error)]
pub enum BodyModelError {
    /// The file could not be read, or is not a well-formed npz or pickle (the I/O layer's
    /// message names the file and the entry or opcode).
    #[error(transparent)]
    Io(#[from] desal_io::IoError),

    /// The file parsed but is not a body model in SMPL's layout: a key is missing, has
    /// the wrong type, shape or values. `path` is the file (or `<bytes>`).
    #[error("{path}: '{key}' {reason}")]
    BadKey { path: PathBuf, key: String, reason: String },

    /// The kinematic tree has a joint count of none of the known kinds.
    #[error(
        "{path}: {joints} joints in 'kintree_table' match no known model (SMPL 24, SMPL-H 52, SMPL-X 55, MANO 16, FLAME 5)"
    )]
    UnknownKind { path: PathBuf, joints: usize },

    /// A joint's parent is not an earlier joint (the SMPL family orders parents first).
    #[error(
        "{path}: joint {joint}'s parent {parent} is not an earlier joint; 'kintree_table' must list parents first"
    )]
    BadParent { path: PathBuf, joint: usize, parent: i64 },

    /// Evaluation parameters that do not fit the model.
    #[error("{what}: {given} given, the model has {available}")]
    BadParameters { what: &'static str, given: usize, available: usize },

    /// A vertex subset or its triangles that do not fit the model ([`crate::subset_model`]).
    #[error("model subset: {reason}")]
    BadSubset { reason: String },

    /// A model that cannot be written as an npz ([`crate::BodyModel::to_npz`]).
    #[error("writing the model: {reason}")]
    Write { reason: String },

    /// A sampling setting out of range.
    #[error("sampling setting '{name}': {reason}")]
    BadSetting { name: &'static str, reason: String },
}
