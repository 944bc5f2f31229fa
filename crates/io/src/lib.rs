//! Every byte in or out of desal: PLY and OBJ meshes, part labels, JSON reports, the
//! versioned artifact envelope with its bincode codec, and the numpy files (`npz.rs`) and
//! restricted pickles (`pickle.rs`) that parametric body models come in.
//!
//! **Invariant:** this is the only crate that knows file formats, magic numbers and
//! format versions. Every error names the file it is about; every write is atomic
//! (temp file in the same directory, then rename), so a killed run never leaves a
//! half-written file behind.

pub mod artifact;
pub mod atomic;
pub mod codec;
pub mod confine;
pub mod dir;
pub mod error;
pub mod file;
pub mod groups;
pub mod labels;
pub mod npz;
pub mod obj;
pub mod off;
pub mod pickle;
pub mod ply;

use std::path::Path;

pub use artifact::{ArtifactKind, ContentHash, Producer};
pub use atomic::{write_atomic, write_json};
pub use dir::{create_dir_once, replace_dir};
pub use error::IoError;

use desal_mesh::TriMesh;

/// Reads a triangle mesh from a PLY (ASCII or binary), OBJ or ASCII OFF file, chosen by
/// extension.
/// Polygons are fan-triangulated; vertex order is kept. Validates face index ranges (by
/// the file's own face numbers) and finite coordinates. Anything but a regular file is
/// refused before it is opened (a FIFO would block).
pub fn read_mesh(path: &Path) -> Result<TriMesh, IoError> {
    let format = mesh_format(path)?;
    read_mesh_bytes(path, format, &file::read_regular_file(path)?)
}

/// Parses the mesh file content `bytes`, in the format `path`'s extension names; `path`
/// is for messages only. What [`read_mesh`] does after reading the file.
pub fn read_mesh_from(path: &Path, bytes: &[u8]) -> Result<TriMesh, IoError> {
    read_mesh_bytes(path, mesh_format(path)?, bytes)
}

#[derive(Clone, Copy)]
enum MeshFormat {
    Ply,
    Obj,
    Off,
}

fn mesh_format(path: &Path) -> Result<MeshFormat, IoError> {
    match extension(path).as_str() {
        "ply" => Ok(MeshFormat::Ply),
        "obj" => Ok(MeshFormat::Obj),
        "off" => Ok(MeshFormat::Off),
        other => Err(IoError::UnsupportedFormat { path: path.to_owned(), extension: other.to_owned() }),
    }
}

fn read_mesh_bytes(path: &Path, format: MeshFormat, bytes: &[u8]) -> Result<TriMesh, IoError> {
    match format {
        MeshFormat::Ply => ply::read_ply_from(path, bytes).map(|m| m.mesh),
        MeshFormat::Obj => obj::read_obj_from(path, bytes),
        MeshFormat::Off => off::read_off_from(path, bytes),
    }
}

/// The lower-case extension of `path` ("" when there is none).
pub(crate) fn extension(path: &Path) -> String {
    path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase()
}
