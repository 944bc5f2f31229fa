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
            .map_err(|source| IoError::InvalidMesh { path: path.to_owned(), source });
    }
    let mut labels = Vec::new();
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
    }
    let mut result = PartLabels::from_ids(labels);
    for (id, name) in names {
        if let Some(slot) = result.names.get_mut(id as usize) {
            *slot = name;
        }
    }
    Ok(result)
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
    let mut text = String::with_capacity(labels.labels.len() * 3 + 64);
    text.push_str("# one line per vertex, value = part id\n# ids: ");
    let names: Vec<String> = labels.names.iter().enumerate().map(|(k, n)| format!("{k}={n}")).collect();
    text.push_str(&names.join(", "));
    text.push('\n');
    for id in &labels.labels {
        text.push_str(&id.to_string());
        text.push('\n');
    }
    crate::atomic::write_atomic(path, text.as_bytes())
}

/// Writes labels as JSON.
pub fn write_labels_json(path: &Path, labels: &PartLabels) -> Result<(), IoError> {
    crate::atomic::write_json(
        path,
        &LabelsJson { parts: labels.names.clone(), labels: labels.labels.clone() },
    )
}
