//! `IoError`: every failure to read or write a file, naming the file and, where it
//! applies, the element (line, vertex, face) at fault.

use std::path::PathBuf;

use desal_mesh::MeshError;
use thiserror::Error;

use crate::artifact::layout::HEADER_LEN;

#[derive(Debug, Error)]
pub enum IoError {
    /// The OS refused to open, read or write the file. (`cause`, not `source`: the
    /// message already carries it, so an error chain must not print it twice.)
    #[error("{path}: {cause}")]
    Io { path: PathBuf, cause: std::io::Error },

    /// The path is a directory, FIFO, socket or device: refused before opening, since
    /// opening a FIFO would block until a writer appears.
    #[error("{path}: is {what}, not a regular file; desal reads regular files only")]
    NotAFile { path: PathBuf, what: &'static str },

    /// A text format (OBJ, OFF, ASCII labels, JSON) holds bytes that are not UTF-8.
    #[error("{path}: not a text file: invalid UTF-8 at byte {offset}")]
    NotText { path: PathBuf, offset: usize },

    /// The extension is not one desal reads.
    #[error("{path}: unsupported mesh format '.{extension}' (desal reads .ply, .obj and .off)")]
    UnsupportedFormat { path: PathBuf, extension: String },

    /// An output path that desal may not replace: a directory, FIFO, socket or block
    /// device (a character device is written through; see `confine::write_target`).
    #[error(
        "{path}: is {what}; desal replaces only regular files (and writes through to a character device such as /dev/null)"
    )]
    NotWritable { path: PathBuf, what: &'static str },

    /// The file is not a well-formed mesh file (bad header, truncated payload, missing
    /// properties).
    #[error("{path}: not a readable mesh: {reason}")]
    BadMesh { path: PathBuf, reason: String },

    /// The file parsed but its content is invalid (face index out of range, NaN, ...).
    #[error("{path}: {cause}")]
    InvalidMesh { path: PathBuf, cause: MeshError },

    /// A line of a text file (OBJ, labels) could not be parsed.
    #[error("{path}:{line}: {reason}")]
    BadLine { path: PathBuf, line: usize, reason: String },

    /// The file does not start with the desal artifact magic.
    #[error("{path}: not a desal artifact (wrong magic bytes); expected a file written by a desal stage")]
    NotAnArtifact { path: PathBuf },

    /// The artifact is of another kind than the reader expects.
    #[error("{path}: is a '{found}' artifact, but a '{expected}' artifact is needed here")]
    WrongKind { path: PathBuf, expected: &'static str, found: String },

    /// Written by a newer desal with a format this build cannot read.
    #[error(
        "{path}: '{kind}' artifact format version {found} was written by a newer desal (this build reads up to version {supported}); upgrade desal or re-run the stage with this version"
    )]
    NewerVersion { path: PathBuf, kind: &'static str, found: u16, supported: u16 },

    /// Written by an older desal whose format this build no longer reads.
    #[error(
        "{path}: '{kind}' artifact format version {found} is older than this build reads (the oldest it reads is version {supported}); re-run the stage that produced it to regenerate it"
    )]
    OlderVersion { path: PathBuf, kind: &'static str, found: u16, supported: u16 },

    /// The reserved header bytes are not zero: corrupt, or an unknown extension.
    #[error("{path}: corrupt artifact header (reserved bytes are not zero)")]
    BadHeader { path: PathBuf },

    /// The file is shorter than its header says.
    #[error(
        "{path}: truncated artifact: the header announces {expected} payload bytes, the file holds {found}; the write was interrupted or the copy is incomplete — re-run the stage"
    )]
    Truncated { path: PathBuf, expected: u64, found: u64 },

    /// The file ends inside the fixed-size header.
    #[error(
        "{path}: truncated artifact: the file ends after {found} bytes, inside the {HEADER_LEN}-byte header; the write was interrupted or the copy is incomplete — re-run the stage"
    )]
    TruncatedHeader { path: PathBuf, found: u64 },

    /// The file is longer than its header says.
    #[error(
        "{path}: corrupt artifact: the header announces {expected} payload bytes, but {found} follow it; something was appended to the file — re-run the stage"
    )]
    TrailingBytes { path: PathBuf, expected: u64, found: u64 },

    /// The kind code is not one this build knows.
    #[error(
        "{path}: unknown artifact kind code {code}: written by a newer desal, or corrupt; upgrade desal or re-run the stage"
    )]
    UnknownKind { path: PathBuf, code: u16 },

    /// The payload does not match its checksum.
    #[error("{path}: artifact checksum mismatch: the file is corrupt; delete it and re-run the stage")]
    Checksum { path: PathBuf },

    /// The payload passed its checksum but does not decode (a bug, or a forged header).
    #[error("{path}: artifact payload does not decode: {reason}")]
    Decode { path: PathBuf, reason: String },

    /// A part of a labels file has no vertex (see `labels`' module doc for the rule).
    #[error(
        "{path}: part {part} ('{name}') has no vertices; every part needs at least 3 non-collinear vertices for its rigid fit — label vertices with it, or remove it and renumber the parts after it"
    )]
    EmptyPart { path: PathBuf, part: u32, name: String },

    /// The payload decoded, but its content contradicts itself (an index out of range,
    /// arrays of disagreeing lengths): a forged or corrupt file whose checksum was
    /// recomputed, or a bug in the desal that wrote it.
    #[error("{path}: '{kind}' artifact is inconsistent: {reason}; delete it and re-run the stage")]
    InvalidArtifact { path: PathBuf, kind: &'static str, reason: String },

    /// A path found inside a file (a glTF buffer or image URI) that desal will not follow:
    /// outside the folder of the file that names it, a URL, or not a regular file.
    #[error("{path}: {element}: URI '{uri}' {reason}")]
    Confined { path: PathBuf, element: String, uri: String, reason: String },

    /// JSON could not be read or written.
    #[error("{path}: {reason}")]
    Json { path: PathBuf, reason: String },
}

impl IoError {
    pub(crate) fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        IoError::Io { path: path.to_owned(), cause: source }
    }

    pub(crate) fn bad_mesh(path: &std::path::Path, reason: impl Into<String>) -> Self {
        IoError::BadMesh { path: path.to_owned(), reason: reason.into() }
    }
}
