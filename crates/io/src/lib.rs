//! Every byte in or out of desal: PLY and OBJ meshes, part labels, JSON reports, and the
//! versioned artifact envelope with its bincode codec.
//!
//! **Invariant:** this is the only crate that knows file formats, magic numbers and
//! format versions. Every error names the file it is about; every write is atomic
//! (temp file in the same directory, then rename), so a killed run never leaves a
//! half-written file behind.

pub mod artifact;
pub mod atomic;
pub mod codec;
pub mod dir;
pub mod error;
pub mod labels;
pub mod npz;
pub mod obj;
pub mod off;
pub mod ply;

use std::path::Path;

pub use artifact::{ArtifactKind, ContentHash, Producer};
pub use atomic::{write_atomic, write_json};
pub use dir::{create_dir_once, replace_dir};
pub use error::IoError;

use desal_mesh::TriMesh;

/// Reads a triangle mesh from a PLY (ASCII or binary), OBJ or ASCII OFF file, chosen by
/// extension.
/// Polygons are fan-triangulated; vertex order is kept. Validates face index ranges and
/// finite coordinates.
pub fn read_mesh(path: &Path) -> Result<TriMesh, IoError> {
    match extension(path).as_str() {
        "ply" => ply::read_ply(path),
        "obj" => obj::read_obj(path),
        "off" => off::read_off(path),
        other => Err(IoError::UnsupportedFormat { path: path.to_owned(), extension: other.to_owned() }),
    }
}

/// The lower-case extension of `path` ("" when there is none).
pub(crate) fn extension(path: &Path) -> String {
    path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase()
}
