//! ASCII OFF reading (what CGAL, the peers' driver and many geometry tools write):
//! an `OFF` header, the vertex, face and edge counts, the vertices, then one polygon per
//! line (`n i0 i1 … [colour]`), fan-triangulated. `#` starts a comment anywhere; lines
//! may break anywhere between numbers, so the body is read as one token stream. Vertex
//! order is kept; extra per-vertex fields (`COFF`, `NOFF`, …) are not supported.

use std::path::Path;

use desal_mesh::{Face, TriMesh, Vec3};

use crate::error::IoError;

/// Reads an ASCII OFF file (a regular file only).
pub fn read_off(path: &Path) -> Result<TriMesh, IoError> {
    read_off_from(path, &crate::file::read_regular_file(path)?)
}

/// Parses ASCII OFF content; `path` is for messages only.
///
/// The header's counts are checked against the number of tokens the file holds before
/// anything is allocated for them: a vertex takes 3 numbers and a face at least 4, so a
/// header claiming more than the file can hold is refused, naming the element.
pub fn read_off_from(path: &Path, bytes: &[u8]) -> Result<TriMesh, IoError> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| IoError::NotText { path: path.to_owned(), offset: e.valid_up_to() })?;
    // (line number, token), comments removed.
    let tokens: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .flat_map(|(i, line)| {
            line.split('#').next().unwrap_or("").split_whitespace().map(move |t| (i + 1, t))
        })
        .collect();
    let bad = |line: usize, reason: String| IoError::BadLine { path: path.to_owned(), line, reason };
    match tokens.first() {
        Some((_, "OFF")) => {}
        Some(&(line, other)) => {
            return Err(bad(
                line,
                format!("header '{other}' is not 'OFF' (binary and COFF/NOFF files are not read)"),
            ));
        }
        None => return Err(IoError::bad_mesh(path, "empty file: not an OFF mesh")),
    }
    let mut at = 1;
    let next = |at: &mut usize, what: &str| -> Result<(usize, &str), IoError> {
        let token = tokens
            .get(*at)
            .copied()
            .ok_or_else(|| IoError::bad_mesh(path, format!("file ends before the {what}: truncated")))?;
        *at += 1;
        Ok(token)
    };
    let mut counts = [0usize; 3];
    for (slot, what) in counts.iter_mut().zip(["vertex count", "face count", "edge count"]) {
        let (line, t) = next(&mut at, what)?;
        *slot = t.parse().map_err(|_| bad(line, format!("{what} '{t}' is not a count")))?;
    }
    let [vertex_count, face_count, _] = counts;
    check_counts(path, vertex_count, face_count, tokens.len() - at)?;
    let mut positions = Vec::with_capacity(vertex_count);
    for v in 0..vertex_count {
        let mut c = [0.0f64; 3];
        for slot in &mut c {
            let (line, t) = next(&mut at, &format!("coordinates of vertex {v}"))?;
            *slot = t.parse().map_err(|_| bad(line, format!("vertex {v}: '{t}' is not a number")))?;
        }
        positions.push(Vec3::new(c[0], c[1], c[2]));
    }
    let mut faces: Vec<Face> = Vec::with_capacity(face_count);
    let mut corners: Vec<u32> = Vec::with_capacity(8);
    for f in 0..face_count {
        let (line, t) = next(&mut at, &format!("face {f}"))?;
        let n: usize = t.parse().map_err(|_| bad(line, format!("face {f}: '{t}' is not a corner count")))?;
        if n < 3 {
            return Err(bad(line, format!("face {f} has {n} corners")));
        }
        corners.clear();
        for _ in 0..n {
            let (line, t) = next(&mut at, &format!("corners of face {f}"))?;
            let v: u32 =
                t.parse().map_err(|_| bad(line, format!("face {f}: '{t}' is not a vertex index")))?;
            if v as usize >= vertex_count {
                return Err(bad(
                    line,
                    format!("face {f} references vertex {v}, but the file has only {vertex_count} vertices"),
                ));
            }
            corners.push(v);
        }
        for k in 1..n - 1 {
            faces.push([corners[0], corners[k], corners[k + 1]]);
        }
        // The rest of the face's line (an optional colour) is not geometry.
        let last = line;
        while tokens.get(at).is_some_and(|&(l, _)| l == last) {
            at += 1;
        }
    }
    if at < tokens.len() {
        return Err(bad(tokens[at].0, format!("'{}' after the last of {face_count} faces", tokens[at].1)));
    }
    if faces.is_empty() {
        return Err(IoError::bad_mesh(path, "no faces: not a mesh"));
    }
    TriMesh::try_new(positions, faces, &path.display().to_string())
        .map_err(|cause| IoError::InvalidMesh { path: path.to_owned(), cause })
}

/// Refuses header counts that need more numbers than the `available` tokens after the
/// header: 3 per vertex, at least 4 (a corner count and 3 corners) per face.
fn check_counts(
    path: &Path,
    vertex_count: usize,
    face_count: usize,
    available: usize,
) -> Result<(), IoError> {
    let too_many = |element: &str, count: usize, per: &str, needed: Option<usize>| {
        let needed = needed.map_or_else(|| "more than 2^64".to_owned(), |n| n.to_string());
        IoError::bad_mesh(
            path,
            format!(
                "the header announces {count} {element} ({per}), which needs {needed} numbers, but the file holds only {available} after the header: the counts are wrong or the file is truncated"
            ),
        )
    };
    let vertex_numbers = vertex_count.checked_mul(3);
    if vertex_numbers.is_none_or(|n| n > available) {
        return Err(too_many("vertices", vertex_count, "3 numbers each", vertex_numbers));
    }
    let face_numbers = face_count.checked_mul(4);
    let all = face_numbers.and_then(|n| n.checked_add(vertex_count * 3));
    if all.is_none_or(|n| n > available) {
        return Err(too_many("faces", face_count, "at least 4 numbers each, after the vertices", all));
    }
    Ok(())
}
