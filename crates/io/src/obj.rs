//! Wavefront OBJ reading: `v` and `f` lines only. Polygons are fan-triangulated,
//! normals, texture coordinates, groups and materials are ignored, vertex order is kept.
//!
//! Face numbers in messages are the file's own: face `k` is the `k`-th `f` line (from 0),
//! whatever triangulation makes of the faces before it, and the line number is given too.

use std::path::Path;

use desal_mesh::{Face, TriMesh, Vec3};

use crate::error::IoError;

/// Reads an OBJ file (a regular file only). Face corners may be `v`, `v/vt`, `v//vn` or
/// `v/vt/vn`, with 1-based or negative (relative) indices.
pub fn read_obj(path: &Path) -> Result<TriMesh, IoError> {
    read_obj_from(path, &crate::file::read_regular_file(path)?)
}

/// Parses OBJ content; `path` is for messages only.
pub fn read_obj_from(path: &Path, bytes: &[u8]) -> Result<TriMesh, IoError> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| IoError::NotText { path: path.to_owned(), offset: e.valid_up_to() })?;
    let mut positions: Vec<Vec3> = Vec::new();
    let mut faces: Vec<Face> = Vec::new();
    // Per file face: (line number, index of its first triangle in `faces`), so that a
    // bad triangle found after the whole file is read is reported as the file's face.
    let mut polygons: Vec<(usize, usize)> = Vec::new();
    let bad = |line: usize, reason: String| IoError::BadLine { path: path.to_owned(), line, reason };
    let mut corners: Vec<u32> = Vec::with_capacity(8);
    for (i, raw) in text.lines().enumerate() {
        let line_no = i + 1;
        let mut fields = raw.split_whitespace();
        match fields.next() {
            Some("v") => {
                let mut c = [0.0f64; 3];
                for slot in &mut c {
                    let field = fields
                        .next()
                        .ok_or_else(|| bad(line_no, "vertex with fewer than 3 coordinates".into()))?;
                    *slot = field.parse().map_err(|_| bad(line_no, format!("'{field}' is not a number")))?;
                }
                positions.push(Vec3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let face_no = polygons.len();
                corners.clear();
                for field in fields {
                    let index = field.split('/').next().unwrap_or("");
                    corners.push(
                        resolve_index(index, positions.len())
                            .map_err(|reason| bad(line_no, format!("face {face_no}: '{field}' {reason}")))?,
                    );
                }
                if corners.len() < 3 {
                    return Err(bad(
                        line_no,
                        format!("face {face_no} has {} corners (a face needs 3 or more)", corners.len()),
                    ));
                }
                polygons.push((line_no, faces.len()));
                for k in 1..corners.len() - 1 {
                    faces.push([corners[0], corners[k], corners[k + 1]]);
                }
            }
            _ => {}
        }
    }
    if faces.is_empty() {
        return Err(IoError::bad_mesh(path, "no faces ('f' lines): not a mesh"));
    }
    // Positive indices may name vertices defined further down, so ranges are checked
    // once every vertex is known.
    let vertex_count = positions.len();
    if let Some(t) = faces.iter().position(|f| f.iter().any(|&v| v as usize >= vertex_count)) {
        let face_no = polygons.partition_point(|&(_, first)| first <= t) - 1;
        let vertex = faces[t].iter().copied().find(|&v| v as usize >= vertex_count).expect("a bad corner");
        return Err(bad(
            polygons[face_no].0,
            format!(
                "face {face_no} references vertex {} (1-based), but the file has only {vertex_count} vertices",
                u64::from(vertex) + 1
            ),
        ));
    }
    TriMesh::try_new(positions, faces, &path.display().to_string())
        .map_err(|cause| IoError::InvalidMesh { path: path.to_owned(), cause })
}

/// The 0-based vertex index of an OBJ corner index (`k > 0` absolute, `k < 0` relative to
/// the `defined` vertices so far), range-checked before it is narrowed to `u32`.
fn resolve_index(index: &str, defined: usize) -> Result<u32, String> {
    let k: i64 = index.parse().map_err(|e: std::num::ParseIntError| match e.kind() {
        std::num::IntErrorKind::PosOverflow | std::num::IntErrorKind::NegOverflow => {
            "is out of the range of vertex indices".to_owned()
        }
        _ => "is not a vertex index".to_owned(),
    })?;
    let resolved = match k {
        k if k > 0 => k - 1,
        k if k < 0 => i64::try_from(defined).unwrap_or(i64::MAX).saturating_add(k),
        _ => return Err("is vertex index 0 (OBJ indices start at 1)".into()),
    };
    if resolved < 0 {
        return Err(format!(
            "is a relative index pointing before the first vertex ({defined} defined so far)"
        ));
    }
    u32::try_from(resolved)
        .map_err(|_| format!("is beyond the largest vertex index desal reads ({})", u32::MAX))
}
