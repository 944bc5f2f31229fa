//! `view.html` of a rig dataset: the full (input) rig and `simplified.glb` side by side in
//! a three.js page (`desal_rig::viewer`), which loads the pinned three.js from its CDN, or
//! inlines it from the local package `DESAL_THREE` names, for offline use.
//!
//! The page's levels are the input, then `simplified.glb`, then each level of a LOD chain
//! (`lods` in `[dataset.rig]`: `simplified-lod<k>.glb`), under its level selector. The input level is the input file's own bytes when it is a binary
//! glTF (`.glb`, `.vrm`): its materials, textures, every mesh and morph target, as
//! `simplified.glb` (the input document, edited) has them. A `.gltf` (JSON, maybe with
//! external buffers and images) is shown as desal read it instead (the skinned meshes, the
//! skeleton and animations, without materials), written by the one rig writer,
//! `desal_rig::write_glb`, so the page needs no second loader.

use anyhow::{Context, Result};
use desal_rig::viewer::{ViewInput, ViewLevel, three_dir_from_env, view_html};
use desal_rig::{ReadOptions, Weld};

use crate::stages::rig::{RigSource, SimplifiedRigSummary};

/// The page's file name in the output folder.
pub const VIEW_HTML: &str = "view.html";

/// `(relative path, bytes)` of `view.html`; `lods` are the LOD chain's levels, `(label,
/// glb bytes)`, finest first.
pub fn view_files(
    rig: &RigSource,
    simplified_glb: &[u8],
    lods: &[(String, Vec<u8>)],
    summary: &SimplifiedRigSummary,
) -> Result<Vec<(String, Vec<u8>)>> {
    let bytes = desal_io::file::read_regular_file(&rig.file)?;
    let input = desal_rig::read_rig_from(&rig.file, &bytes, &ReadOptions { mesh: rig.params.mesh.clone() })?;
    let full_glb = if bytes.starts_with(b"glTF") {
        bytes
    } else {
        desal_rig::write_glb(&input).with_context(|| format!("{}", rig.file.display()))?
    };
    let title = crate::stages::ingest::file_name(&rig.file);
    let caption = format!(
        "{title}: {} welded vertices simplified to {}; weights: {}. Drag to turn, scroll to zoom.",
        Weld::new(&input.mesh).welded_count(),
        summary.simplified_vertices,
        summary.weights,
    );
    let mut levels = vec![
        ViewLevel { label: "input", glb: &full_glb },
        ViewLevel { label: "simplified", glb: simplified_glb },
    ];
    levels.extend(lods.iter().map(|(label, glb)| ViewLevel { label, glb }));
    let input = ViewInput { title: &title, levels: &levels, caption: &caption };
    let page = view_html(&input, three_dir_from_env().as_deref())?;
    Ok(vec![(VIEW_HTML.to_owned(), page.into_bytes())])
}
