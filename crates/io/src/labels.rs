//! Part label files: plain text (one integer part id per vertex, `#` comment lines, as
//! in SCAPE's `vertex_part_labels_16.txt`) or JSON (`{"parts": [names], "labels": [ids]}`).

use std::path::Path;

use desal_mesh::PartLabels;
use serde::{Deserialize, Serialize};

use crate::error::IoError;

#[derive(Debug, Serialize, Deserialize)]
struct LabelsJson {
    parts: Vec<String>,
    labels: Vec<u32>,
}

/// Reads part labels; `.json` files are JSON, anything else is the text form. Text
/// labels get names from a `# ids: 0=name, 1=name` comment when present, else
/// `part0`, `part1`, ...
pub fn read_labels(path: &Path) -> Result<PartLabels, IoError> {
    let text = std::fs::read_to_string(path).map_err(|e| IoError::io(path, e))?;
    if crate::extension(path) == "json" {
        let parsed: LabelsJson = serde_json::from_str(&text)
            .map_err(|e| IoError::Json { path: path.to_owned(), reason: e.to_string() })?;
        return PartLabels::try_new(parsed.labels, parsed.parts)
            .map_err(|cause| IoError::InvalidMesh { path: path.to_owned(), cause });
    }
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
    check_part_ids(path, &labels, &lines, &names)?;
    let mut result = PartLabels::from_ids(labels);
    for (id, name) in names {
        if let Some(slot) = result.names.get_mut(id as usize) {
            *slot = name;
        }
    }
    Ok(result)
}

/// Text labels carry no part count, so it is inferred: the parts named in a `# ids:`
/// comment, else `0..=max id` with every id in use. An id outside that range is a typo
/// (or a foreign file) and is reported with its line, before anything is allocated for it.
fn check_part_ids(
    path: &Path,
    labels: &[u32],
    lines: &[usize],
    names: &[(u32, String)],
) -> Result<(), IoError> {
    let bad = |k: usize, reason: String| IoError::BadLine { path: path.to_owned(), line: lines[k], reason };
    if let Some(count) = names.iter().map(|(id, _)| *id as usize + 1).max() {
        if let Some(k) = labels.iter().position(|&id| id as usize >= count) {
            return Err(bad(
                k,
                format!(
                    "vertex {k} has part id {}, but the '# ids:' comment names parts 0..{} only",
                    labels[k],
                    count - 1
                ),
            ));
        }
        return Ok(());
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
                 with every id used (name the parts in a '# ids: 0=name, 1=name' comment to allow \
                 empty ones)",
                labels[k]
            ),
        ));
    }
    Ok(())
}

/// Names from a comment like ` ids: 0=lefthand, 1=leftlowerarm`.
fn parse_names_comment(comment: &str) -> Vec<(u32, String)> {
    let Some(list) = comment.trim().strip_prefix("ids:") else { return Vec::new() };
    list.split(',')
        .filter_map(|item| {
            let (id, name) = item.split_once('=')?;
            Some((id.trim().parse().ok()?, name.trim().to_owned()))
        })
        .collect()
}

/// Writes labels as text: a comment naming the parts, then one id per line.
pub fn write_labels_txt(path: &Path, labels: &PartLabels) -> Result<(), IoError> {
    crate::atomic::write_atomic(path, labels_txt(labels).as_bytes())
}

/// The text [`write_labels_txt`] writes, for callers that add their own header comments.
pub fn labels_txt(labels: &PartLabels) -> String {
    let mut text = String::with_capacity(labels.labels.len() * 3 + 64);
    text.push_str("# one line per vertex, value = part id\n# ids: ");
    let names: Vec<String> = labels.names.iter().enumerate().map(|(k, n)| format!("{k}={n}")).collect();
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
