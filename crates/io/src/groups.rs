//! Group files: one group id per pose, in pose order (`groups = "groups.txt"` in a
//! pipeline file). A group is whatever must never be on both sides of a held-out split:
//! a person, a body model's shape, a capture session.
//!
//! The text form: one id per line, any token without white space (`alice`, `7`), blank
//! lines and `#` comment lines skipped. Ids are numbered by first appearance, so the
//! file's spelling never changes a result.

use std::path::Path;

use crate::error::IoError;

/// Reads a group file (a regular file only) for `poses` poses: one `u32` per pose,
/// numbered by first appearance.
pub fn read_groups(path: &Path, poses: usize) -> Result<Vec<u32>, IoError> {
    read_groups_from(path, &crate::file::read_regular_file(path)?, poses)
}

/// Parses group file content; `path` is for messages only.
pub fn read_groups_from(path: &Path, bytes: &[u8], poses: usize) -> Result<Vec<u32>, IoError> {
    let text = std::str::from_utf8(bytes)
        .map_err(|e| IoError::NotText { path: path.to_owned(), offset: e.valid_up_to() })?;
    let bad = |line: usize, reason: String| IoError::BadLine { path: path.to_owned(), line, reason };
    let mut names: Vec<&str> = Vec::new();
    let mut groups = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        if line.split_whitespace().nth(1).is_some() {
            return Err(bad(i + 1, format!("'{line}' is more than one id; give one group id per line")));
        }
        if groups.len() == poses {
            return Err(bad(i + 1, format!("more group ids than the {poses} poses; give one per pose")));
        }
        let id = match names.iter().position(|n| *n == line) {
            Some(id) => id,
            None => {
                names.push(line);
                names.len() - 1
            }
        };
        groups.push(id as u32);
    }
    if groups.len() != poses {
        let cause = desal_mesh::MeshError::GroupCountMismatch { groups: groups.len(), poses };
        return Err(IoError::InvalidMesh { path: path.to_owned(), cause });
    }
    Ok(groups)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str, poses: usize) -> Result<Vec<u32>, String> {
        read_groups_from(Path::new("g.txt"), text.as_bytes(), poses).map_err(|e| e.to_string())
    }

    #[test]
    fn ids_are_numbered_by_first_appearance() {
        assert_eq!(read("# people\nbob\nalice\n\nbob\n7\n", 4), Ok(vec![0, 1, 0, 2]));
    }

    #[test]
    fn wrong_counts_and_lines_are_refused_by_line() {
        assert_eq!(
            read("a\nb\nc\n", 2).unwrap_err(),
            "g.txt:3: more group ids than the 2 poses; give one per pose"
        );
        assert!(read("a\n", 2).unwrap_err().contains("there are 1 group ids for 2 poses"));
        assert!(read("a b\nc\n", 2).unwrap_err().starts_with("g.txt:1: 'a b' is more than one id"));
        assert!(
            read_groups_from(Path::new("g.txt"), b"\xff", 1)
                .unwrap_err()
                .to_string()
                .contains("not a text file")
        );
    }
}
