//! Part label files: plain text (one integer part id per vertex, `#` comment lines, as
//! in SCAPE's `vertex_part_labels_16.txt`) or JSON (`{"parts": [names], "labels": [ids]}`).
//!
//! **One rule for both forms:** the parts are `0..N`, N being the length of the JSON
//! `parts` list, or for text the parts a `# ids: 0=name, 1=name` comment or a
//! `# parts: name0 name1 …` header names (its largest id + 1), else the largest id + 1; and **every part has at least one vertex**.
//! An empty part — trailing or not, named or not — is refused by both readers with
//! [`IoError::EmptyPart`], naming it: stage 1 needs at least three non-collinear
//! vertices per part (checked at ingest against the template), so an empty part could
//! never be used, and dropping it silently would renumber nothing but hide a mistake.

use std::path::Path;

use desal_mesh::PartLabels;
use serde::{Deserialize, Serialize};

use crate::error::IoError;

#[derive(Debug, Serialize, Deserialize)]
struct LabelsJson {
    parts: Vec<String>,
    labels: Vec<u32>,
}

/// Reads part labels (a regular file only); `.json` files are JSON, anything else is the
/// text form. Text labels get names from a `# ids: 0=name, 1=name` comment when present,
/// else `part0`, `part1`, ... See the module doc for the rule on parts.
pub fn read_labels(path: &Path) -> Result<PartLabels, IoError> {
    read_labels_from(path, &crate::file::read_regular_file(path)?)
}

/// Parses label file content, JSON when `path` ends in `.json`, else text; `path` is
/// for messages only.
pub fn read_labels_from(path: &Path, bytes: &[u8]) -> Result<PartLabels, IoError> {
    let labels = if crate::extension(path) == "json" {
        let parsed: LabelsJson = serde_json::from_slice(bytes)
            .map_err(|e| IoError::Json { path: path.to_owned(), reason: e.to_string() })?;
        PartLabels::try_new(parsed.labels, parsed.parts)
            .map_err(|cause| IoError::InvalidMesh { path: path.to_owned(), cause })?
    } else {
        let text = std::str::from_utf8(bytes)
            .map_err(|e| IoError::NotText { path: path.to_owned(), offset: e.valid_up_to() })?;
        parse_text(path, text)?
    };
    if let Some(part) = labels.first_empty_part() {
        return Err(IoError::EmptyPart {
            path: path.to_owned(),
            part,
            name: labels.names[part as usize].clone(),
        });
    }
    Ok(labels)
}

fn parse_text(path: &Path, text: &str) -> Result<PartLabels, IoError> {
    let mut labels = Vec::new();
    let mut lines = Vec::new();
    let mut names: Vec<(u32, String)> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim();
        if let Some(comment) = line.strip_prefix('#') {
            names.extend(parse_names_comment(comment));
            continue;
        }
        if line.is_empty() {
            continue;
        }
        let id: u32 = line.parse().map_err(|_| IoError::BadLine {
            path: path.to_owned(),
            line: i + 1,
            reason: format!("'{line}' is not a part id (a non-negative integer)"),
        })?;
        labels.push(id);
        lines.push(i + 1);
    }
    let part_count = check_part_ids(path, &labels, &lines, &names)?;
    let mut part_names: Vec<String> = (0..part_count).map(|k| format!("part{k}")).collect();
    for (id, name) in names {
        part_names[id as usize] = name;
    }
    Ok(PartLabels::try_new(labels, part_names).expect("ids were checked against the part count"))
}

/// Text labels carry no part count, so it is inferred and returned: the parts named in a
/// `# ids:` comment, else `0..=max id` with every id in use. An id outside that range is
/// a typo (or a foreign file) and is reported with its line, before anything is
/// allocated for it. A comment naming more parts than there are vertices names an
/// empty part, refused (by id) before its names are allocated.
fn check_part_ids(
    path: &Path,
    labels: &[u32],
    lines: &[usize],
    names: &[(u32, String)],
) -> Result<usize, IoError> {
    let bad = |k: usize, reason: String| IoError::BadLine { path: path.to_owned(), line: lines[k], reason };
    if let Some(count) = names.iter().map(|(id, _)| *id as usize + 1).max() {
        if count > labels.len() {
            // More parts than vertices: one of the first `len + 1` parts is empty.
            let mut used = vec![false; labels.len() + 1];
            for &id in labels {
                if let Some(slot) = used.get_mut(id as usize) {
                    *slot = true;
                }
            }
            let part = used.iter().position(|&u| !u).expect("more parts than vertices") as u32;
            let name = names
                .iter()
                .rev()
                .find(|(id, _)| *id == part)
                .map_or(format!("part{part}"), |(_, n)| n.clone());
            return Err(IoError::EmptyPart { path: path.to_owned(), part, name });
        }
        if let Some(k) = labels.iter().position(|&id| id as usize >= count) {
            return Err(bad(
                k,
                format!(
                    "vertex {k} has part id {}, but the '# ids:' or '# parts:' comment names parts 0..{} only",
                    labels[k],
                    count - 1
                ),
            ));
        }
        return Ok(count);
    }
    let mut used: Vec<u32> = labels.to_vec();
    used.sort_unstable();
    used.dedup();
    if let Some(gap) = used.iter().enumerate().position(|(k, &id)| id as usize != k) {
        let k = labels.iter().position(|&id| id == used[gap]).expect("a used id");
        return Err(bad(
            k,
            format!(
                "vertex {k} has part id {}, but no vertex has part id {gap}: part ids must be 0..N-1 \
                 with every part used (each part needs at least 3 non-collinear vertices for its \
                 rigid fit); renumber the parts without the gap",
                labels[k]
            ),
        ));
    }
    Ok(used.len())
}

/// Names from a comment like ` ids: 0=lefthand, 1=leftlowerarm`, or a header like
/// ` parts: lefthand leftlowerarm` (names by position, separated by whitespace). Names
/// are percent-decoded ([`escape_name`] is what the writer does to a name that holds a
/// separator, a line break or `%`); a `%` not followed by two hex digits stays as it is.
fn parse_names_comment(comment: &str) -> Vec<(u32, String)> {
    if let Some(list) = comment.trim().strip_prefix("parts:") {
        return list
            .split_whitespace()
            .enumerate()
            .map(|(k, name)| (k as u32, unescape_name(name)))
            .collect();
    }
    let Some(list) = comment.trim().strip_prefix("ids:") else { return Vec::new() };
    list.split(',')
        .filter_map(|item| {
            let (id, name) = item.split_once('=')?;
            Some((id.trim().parse().ok()?, unescape_name(name.trim())))
        })
        .collect()
}

/// A part name as the `# ids:` comment writes it: `%`, `,`, `=`, control characters
/// (line breaks included) and whitespace at either end are written `%XX` (UTF-8 bytes),
/// so every name reads back as it was. Other names are written unchanged.
fn escape_name(name: &str) -> String {
    let last = name.chars().count().saturating_sub(1);
    let mut out = String::with_capacity(name.len());
    for (i, c) in name.chars().enumerate() {
        let edge = (i == 0 || i == last) && c.is_whitespace();
        if edge || c.is_control() || matches!(c, '%' | ',' | '=') {
            let mut buf = [0u8; 4];
            for b in c.encode_utf8(&mut buf).bytes() {
                out.push_str(&format!("%{b:02X}"));
            }
        } else {
            out.push(c);
        }
    }
    out
}

/// The inverse of [`escape_name`], lenient: a name whose `%`s are not all valid escapes
/// of UTF-8 (a hand-written `100%`) is kept as written.
fn unescape_name(text: &str) -> String {
    crate::confine::percent_decode(text).unwrap_or_else(|| text.to_owned())
}

/// Writes labels as text: a comment naming the parts, then one id per line.
pub fn write_labels_txt(path: &Path, labels: &PartLabels) -> Result<(), IoError> {
    crate::atomic::write_atomic(path, labels_txt(labels).as_bytes())
}

/// The text [`write_labels_txt`] writes, for callers that add their own header comments.
pub fn labels_txt(labels: &PartLabels) -> String {
    let mut text = String::with_capacity(labels.labels.len() * 3 + 64);
    text.push_str("# one line per vertex, value = part id\n# ids: ");
    let names: Vec<String> =
        labels.names.iter().enumerate().map(|(k, n)| format!("{k}={}", escape_name(n))).collect();
    text.push_str(&names.join(", "));
    text.push('\n');
    for id in &labels.labels {
        text.push_str(&id.to_string());
        text.push('\n');
    }
    text
}

/// Writes labels as JSON.
pub fn write_labels_json(path: &Path, labels: &PartLabels) -> Result<(), IoError> {
    crate::atomic::write_json(
        path,
        &LabelsJson { parts: labels.names.clone(), labels: labels.labels.clone() },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// D11: joint names with line breaks, spaces, separators and `%` read back as written;
    /// ordinary names are written as before.
    #[test]
    fn d11_part_names_with_separators_and_line_breaks_read_back() {
        let names: Vec<String> =
            ["hips", "mixamorig:Left Hand", "a\nb", " padded ", "x,y=z", "50%", "%41", "名前", ""]
                .map(str::to_owned)
                .to_vec();
        let labels = PartLabels::try_new((0..names.len() as u32).collect(), names.clone()).unwrap();
        let text = labels_txt(&labels);
        assert!(text.contains("0=hips, 1=mixamorig:Left Hand, 2=a%0Ab"), "{text}");
        let back = read_labels_from(Path::new("parts.txt"), text.as_bytes()).unwrap();
        assert_eq!(back.names, names);
        assert_eq!(back.labels, labels.labels);
        // A hand-written `%` that is no escape stays.
        assert_eq!(unescape_name("100%"), "100%");
        assert_eq!(unescape_name("%zz%4"), "%zz%4");
    }
}
