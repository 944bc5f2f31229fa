//! `view.html` of a rig dataset: the full (input) rig and `simplified.glb` side by side in
//! a three.js page (`desal_rig::viewer`), which loads the pinned three.js from its CDN, or
//! inlines it from the local package `DESAL_THREE` names, for offline use.
//!
//! The full rig is the input as desal read it (the skinned mesh named by `rig.mesh`, its
//! skeleton and animations), written by the one rig writer, `desal_rig::write_glb`: so
//! the page shows exactly what desal posed, whatever else the input file holds, and a
//! `.gltf` input with external buffers needs no second loader.

use anyhow::{Context, Result};
use desal_rig::viewer::{ViewInput, three_dir_from_env, view_html};
use desal_rig::{ReadOptions, Weld};

use crate::stages::rig::{RigSource, SimplifiedRigSummary};

/// The page's file name in the output folder.
pub const VIEW_HTML: &str = "view.html";

/// `(relative path, bytes)` of `view.html`.
pub fn view_files(
    rig: &RigSource,
    simplified_glb: &[u8],
    summary: &SimplifiedRigSummary,
) -> Result<Vec<(String, Vec<u8>)>> {
    let input = desal_rig::read_rig(&rig.file, &ReadOptions { mesh: rig.params.mesh.clone() })?;
    let full_glb = desal_rig::write_glb(&input).with_context(|| format!("{}", rig.file.display()))?;
    let title = crate::stages::ingest::file_name(&rig.file);
    let caption = format!(
        "{title}: {} welded vertices simplified to {}; weights: {}. Drag to turn, scroll to zoom.",
        Weld::new(&input.mesh).welded_count(),
        summary.simplified_vertices,
        summary.weights,
    );
    let input = ViewInput { title: &title, full_glb: &full_glb, simplified_glb, caption: &caption };
    let page = view_html(&input, three_dir_from_env().as_deref())?;
    Ok(vec![(VIEW_HTML.to_owned(), page.into_bytes())])
}
