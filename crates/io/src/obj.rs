//! Wavefront OBJ reading: `v` and `f` lines only. Polygons are fan-triangulated,
//! normals, texture coordinates, groups and materials are ignored, vertex order is kept.

use std::path::Path;

use desal_mesh::{Face, TriMesh, Vec3};

use crate::error::IoError;

/// Reads an OBJ file. Face corners may be `v`, `v/vt`, `v//vn` or `v/vt/vn`, with
/// 1-based or negative (relative) indices.
pub fn read_obj(path: &Path) -> Result<TriMesh, IoError> {
    let text = std::fs::read_to_string(path).map_err(|e| IoError::io(path, e))?;
    let mut positions: Vec<Vec3> = Vec::new();
    let mut faces: Vec<Face> = Vec::new();
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
                corners.clear();
                for field in fields {
                    let index = field.split('/').next().unwrap_or("");
                    let k: i64 = index
                        .parse()
                        .map_err(|_| bad(line_no, format!("'{field}' is not a vertex index")))?;
                    let resolved = match k {
                        k if k > 0 => k - 1,
                        k if k < 0 => positions.len() as i64 + k,
                        _ => return Err(bad(line_no, "vertex index 0 (OBJ indices start at 1)".into())),
                    };
                    if resolved < 0 {
                        return Err(bad(
                            line_no,
                            format!("relative index {k} points before the first vertex"),
                        ));
                    }
                    corners.push(resolved as u32);
                }
                if corners.len() < 3 {
                    return Err(bad(line_no, format!("face with {} corners", corners.len())));
                }
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
    TriMesh::try_new(positions, faces, &path.display().to_string())
        .map_err(|cause| IoError::InvalidMesh { path: path.to_owned(), cause })
}
