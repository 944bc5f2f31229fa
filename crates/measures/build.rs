//! Sets `cfg(desal_shared_data)` for the tests that need `../shared/datasets`, and
//! `DESAL_EVAL_SOURCE`: a BLAKE3 hash of this crate's `src/`, which keys `desal eval`'s
//! cached floor, so any change to the models or metrics measures it again.

use std::path::{Path, PathBuf};

fn main() {
    desal_shared_data::emit_cfg();
    println!("cargo::rerun-if-changed=src");
    let mut files = Vec::new();
    collect(Path::new("src"), &mut files);
    files.sort();
    let mut hasher = blake3::Hasher::new();
    for file in &files {
        let bytes = std::fs::read(file).unwrap_or_else(|e| panic!("cannot read {}: {e}", file.display()));
        let name = file.to_string_lossy().replace('\\', "/");
        hasher.update(&(name.len() as u64).to_le_bytes());
        hasher.update(name.as_bytes());
        hasher.update(&(bytes.len() as u64).to_le_bytes());
        hasher.update(&bytes);
    }
    println!("cargo::rustc-env=DESAL_EVAL_SOURCE={}", hasher.finalize().to_hex());
}

fn collect(dir: &Path, files: &mut Vec<PathBuf>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("cannot read {}: {e}", dir.display()));
    for entry in entries {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            collect(&path, files);
        } else {
            files.push(path);
        }
    }
}
