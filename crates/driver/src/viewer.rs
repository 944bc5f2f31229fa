//! `view.html` of a rig dataset: the full (input) rig and `simplified.glb` side by side in
//! a self-contained three.js page (`desal_rig::viewer`), and the vendored three.js files
//! written beside it as `viewer/three/...` (its sources and MIT licence).
//!
//! The full rig is the input as desal read it (the skinned mesh named by `rig.mesh`, its
//! skeleton and animations), written by the one rig writer, `desal_rig::write_glb`: so
//! the page shows exactly what desal posed, whatever else the input file holds, and a
//! `.gltf` input with external buffers needs no second loader.

use anyhow::{Context, Result};
use desal_rig::viewer::{VENDORED, ViewInput, view_html};
use desal_rig::{ReadOptions, Weld};

use crate::stages::rig::{RigSource, SimplifiedRigSummary};

/// The page's file name in the output folder.
pub const VIEW_HTML: &str = "view.html";

/// `(relative path, bytes)` of `view.html` and of every vendored file beside it.
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
    let page =
        view_html(&ViewInput { title: &title, full_glb: &full_glb, simplified_glb, caption: &caption });
    let mut files = vec![(VIEW_HTML.to_owned(), page.into_bytes())];
    files.extend(VENDORED.iter().map(|f| (format!("viewer/three/{}", f.path), f.bytes.to_vec())));
    Ok(files)
}
