//! Build-script side of the skip policy for tests that need `../shared/datasets`
//! (SCAPE; development and CI only, never in a user's clone).
//!
//! A crate with such tests calls [`emit_cfg`] from its `build.rs` and marks each of them
//! `#[cfg_attr(not(desal_shared_data), ignore = "...")]`, so that on a clone without the
//! data the harness reports them as *ignored*, with the reason, instead of passed. When
//! `DESAL_REQUIRE_SHARED_DATA` is set (`.ci/run` sets it), a missing dataset fails the
//! build instead, so CI can never skip them.

use std::path::{Path, PathBuf};

/// The environment variable that turns absence into a failure.
pub const REQUIRE_VAR: &str = "DESAL_REQUIRE_SHARED_DATA";

/// The reason every such test's `ignore` attribute gives.
pub const REASON: &str = "needs ../shared/datasets beside the checkout (development and CI only)";

/// `<workspace>/../shared/datasets`, found from the crate being built.
pub fn datasets_dir(manifest_dir: &Path) -> PathBuf {
    let root = manifest_dir.ancestors().find(|dir| dir.join("Cargo.lock").is_file()).unwrap_or(manifest_dir);
    root.join("../shared/datasets")
}

/// Emits `cargo::rustc-cfg=desal_shared_data` when the SCAPE dataset is present; panics
/// (failing the build) when it is absent and [`REQUIRE_VAR`] is set.
pub fn emit_cfg() {
    println!("cargo::rustc-check-cfg=cfg(desal_shared_data)");
    println!("cargo::rerun-if-env-changed={REQUIRE_VAR}");
    let manifest_dir =
        PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("run from a build script"));
    let scape = datasets_dir(&manifest_dir).join("scape");
    println!("cargo::rerun-if-changed={}", scape.display());
    if scape.is_dir() {
        println!("cargo::rustc-cfg=desal_shared_data");
    } else if std::env::var_os(REQUIRE_VAR).is_some() {
        panic!("{} is missing but {REQUIRE_VAR} is set: CI must run the tests that need it", scape.display());
    }
}
