//! Test-only access to the datasets in `../shared/datasets` beside the checkout, with
//! one skip policy for every test and bench that reads them.
//!
//! A user's clone has no `../shared`: tests that need it are marked
//! `#[cfg_attr(not(desal_shared_data), ignore = ...)]` (see `desal-shared-data`), so the
//! harness reports them as ignored with the reason. CI always has it, and `.ci/run` sets
//! `DESAL_REQUIRE_SHARED_DATA=1`, under which a missing dataset is a failure instead.
//! The loaders below still return `None` when the data is absent (benches use that).
//!
//! Used only as a dev-dependency.

pub mod golden;

use std::path::{Path, PathBuf};

use desal_mesh::{PartLabels, PoseSet};

/// The environment variable that turns a skip into a failure.
pub const REQUIRE_VAR: &str = "DESAL_REQUIRE_SHARED_DATA";

/// `../shared/datasets/<name>` beside the workspace, or `None` after printing why the
/// caller skips. Panics when the dataset is missing and [`REQUIRE_VAR`] is set.
pub fn shared_dataset(name: &str) -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/datasets").join(name);
    if dir.is_dir() {
        return Some(dir);
    }
    assert!(
        std::env::var_os(REQUIRE_VAR).is_none(),
        "{} is missing but {REQUIRE_VAR} is set (CI must run it)",
        dir.display()
    );
    eprintln!(
        "skipped: {} is absent (it sits beside the checkout in development and CI only)",
        dir.display()
    );
    None
}

/// The SCAPE folder (see [`shared_dataset`]).
pub fn scape_dir() -> Option<PathBuf> {
    shared_dataset("scape")
}

/// The SCAPE pose files, sorted (`mesh000.ply`, the template, first).
pub fn scape_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("SCAPE folder is readable")
        .map(|e| e.expect("SCAPE entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "ply"))
        .collect();
    files.sort();
    files
}

/// All 71 SCAPE poses (template `mesh000`, index 0) and the 16-part labels, or `None`
/// when SCAPE is absent (see [`shared_dataset`]).
pub fn scape() -> Option<(PoseSet, PartLabels)> {
    let dir = scape_dir()?;
    let files = scape_files(&dir);
    let meshes: Vec<_> = files.iter().map(|f| desal_io::read_mesh(f).expect("SCAPE pose reads")).collect();
    let names = files.iter().map(|f| f.file_stem().unwrap().to_string_lossy().into_owned()).collect();
    let faces = meshes[0].faces.clone();
    let poses = meshes.into_iter().map(|m| m.positions).collect();
    let set = PoseSet::try_new(names, poses, faces, 0).expect("SCAPE is a valid pose set");
    let labels =
        desal_io::labels::read_labels(&dir.join("vertex_part_labels_16.txt")).expect("SCAPE labels read");
    Some((set, labels))
}
