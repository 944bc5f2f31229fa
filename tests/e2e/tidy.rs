//! Tidy: cheap conventions of the whole workspace, checked on every test run (after
//! rust-analyzer's `tidy.rs`).

use std::path::{Path, PathBuf};

fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every `.rs` file of the workspace (not `target/`, not hidden folders).
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if name.starts_with('.') || name == "target" || name == "node_modules" {
            continue;
        }
        if path.is_dir() {
            rust_files(&path, out);
        } else if name.ends_with(".rs") {
            out.push(path);
        }
    }
}

fn all_rust_files() -> Vec<PathBuf> {
    let mut files = Vec::new();
    for top in ["src", "crates", "tests", "benches", "examples"] {
        let dir = workspace().join(top);
        if dir.is_dir() {
            rust_files(&dir, &mut files);
        }
    }
    assert!(files.len() > 50, "the walk found only {} files", files.len());
    files
}

/// STYLE.md 2: every file says its role in a `//!` doc at the top.
#[test]
fn every_rust_file_opens_with_a_module_doc() {
    let missing: Vec<String> = all_rust_files()
        .into_iter()
        .filter(|f| !std::fs::read_to_string(f).unwrap().starts_with("//!"))
        .map(|f| f.strip_prefix(workspace()).unwrap().display().to_string())
        .collect();
    assert!(missing.is_empty(), "these files do not open with a `//!` doc: {missing:?}");
}

/// Summaries are typed structs: a figure read back by string key with a silent zero
/// default (`unwrap_or(0)`) is how a corrupt summary once reported "0 poses".
#[test]
fn no_silent_zero_defaults_in_the_driver() {
    let needle = ["unwrap_or", "(0)"].concat();
    let mut files = Vec::new();
    for dir in ["src", "crates/driver/src", "crates/experiment/src"] {
        rust_files(&workspace().join(dir), &mut files);
    }
    let offenders: Vec<String> = files
        .into_iter()
        .filter(|f| std::fs::read_to_string(f).unwrap().contains(&needle))
        .map(|f| f.strip_prefix(workspace()).unwrap().display().to_string())
        .collect();
    assert!(offenders.is_empty(), "{needle} in {offenders:?}: read a typed summary instead");
}
