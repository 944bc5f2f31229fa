//! Issue 15: rig datasets end to end — `[dataset.rig]` on the bundled rig sample writes
//! `simplified.glb` (same skeleton and animations, exact weights with subset placement,
//! at most 4 refitted weights with optimal placement), and bad rigs fail the run with the
//! file and the element named and nothing written.

use std::collections::HashSet;
use std::path::{Path, PathBuf};

use desal_rig::{ReadOptions, Rig};

use crate::support::{desal, stderr};

fn sample_rig() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data-samples/rig.glb")
}

/// A pipeline in `dir` over `rig` (copied there as `avatar.glb`) with `simplify` settings.
fn write_rig_pipeline(dir: &Path, rig: &[u8], simplify: &str) -> PathBuf {
    std::fs::write(dir.join("avatar.glb"), rig).unwrap();
    let text = format!(
        "schema = 1\nout = \"out\"\n[[dataset]]\nname = \"avatar\"\nup_axis = \"y\"\n[dataset.rig]\nfile = \"avatar.glb\"\nposes = \"animations\"\nframes = 11\n[dataset.simplify]\n{simplify}\n"
    );
    let path = dir.join("rig.toml");
    std::fs::write(&path, text).unwrap();
    path
}

fn read(path: &Path) -> Rig {
    desal_rig::read_rig(path, &ReadOptions::default()).unwrap()
}

#[test]
fn the_rig_sample_simplifies_to_a_rig_with_its_skeleton_and_exact_weights() {
    let dir = tempfile::tempdir().unwrap();
    let input = std::fs::read(sample_rig()).unwrap();
    let pipeline = write_rig_pipeline(dir.path(), &input, "target_vertices = 2676\nplacement = \"subset\"");
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let folder = dir.path().join("out/avatar");
    let report: serde_json::Value =
        serde_json::from_slice(&std::fs::read(folder.join("report.json")).unwrap()).unwrap();
    assert_eq!(report["input"]["vertices"], 13380, "welded by position and weights");
    assert_eq!(report["input"]["poses"], 12, "the bind pose and 11 frames");
    assert_eq!(report["output"]["vertices"], 2676);
    let original = read(&sample_rig());
    let simplified = read(&folder.join("simplified.glb"));
    assert_eq!(
        (&simplified.nodes, &simplified.skin, &simplified.animations),
        (&original.nodes, &original.skin, &original.animations)
    );
    let figures: serde_json::Value =
        serde_json::from_slice(&std::fs::read(folder.join("simplified-rig.json")).unwrap()).unwrap();
    assert_eq!(figures["output_vertices"].as_u64().unwrap() as usize, simplified.mesh.vertex_count());
    assert!(simplified.mesh.vertex_count() > 2676, "seams are kept: {figures}");
    // Subset placement: every written vertex is an input vertex, with its UV, exactly.
    let key = |rig: &Rig, v: usize| {
        let m = &rig.mesh;
        let mut k: Vec<u32> =
            m.positions[v].iter().chain(&m.uvs.as_ref().unwrap()[v]).map(|x| x.to_bits()).collect();
        k.extend(m.influences.of(v).flat_map(|(j, w)| [j as u32, w.to_bits()]));
        k
    };
    let inputs: HashSet<Vec<u32>> = (0..original.mesh.vertex_count()).map(|v| key(&original, v)).collect();
    assert!((0..simplified.mesh.vertex_count()).all(|v| inputs.contains(&key(&simplified, v))));
    check_viewer(&folder);
}

/// `view.html` and the vendored three.js files beside it: the files are the vendored
/// bytes, and the page loads nothing over the network (every module an inlined `data:`
/// URL, no `src`/`href` to fetch, no `http(s)://` outside the inlined base64).
fn check_viewer(folder: &Path) {
    use desal_rig::viewer::{MODULES, VENDORED};
    for file in VENDORED {
        let written = std::fs::read(folder.join("viewer/three").join(file.path)).unwrap();
        assert!(written == file.bytes, "viewer/three/{} is not the vendored file", file.path);
    }
    let html = std::fs::read_to_string(folder.join("view.html")).unwrap();
    let opening = "<script type=\"importmap\">";
    let map_start = html.find(opening).expect("an import map") + opening.len();
    let map_end = map_start + html[map_start..].find("</script>").unwrap();
    let map: serde_json::Value = serde_json::from_str(&html[map_start..map_end]).unwrap();
    let imports = map["imports"].as_object().unwrap();
    assert_eq!(imports.len(), MODULES.len());
    for (name, url) in imports {
        assert!(url.as_str().unwrap().starts_with("data:text/javascript;base64,"), "{name} is not inlined");
    }
    // Outside the base64 payloads (the import map and the rigs' JSON), the page's own text.
    let data_start = html.find("<script id=\"desal-data\"").unwrap();
    let data_end = data_start + html[data_start..].find("</script>").unwrap();
    let text = format!("{}{}{}", &html[..map_start], &html[map_end..data_start], &html[data_end..]);
    for needle in ["http://", "https://", " src=", " href=", "fetch(", "import("] {
        assert!(!text.contains(needle), "view.html contains {needle:?}");
    }
    assert!(html.contains("window.desalView"), "the test hook");
}

#[test]
fn optimal_placement_writes_at_most_four_refitted_weights() {
    let dir = tempfile::tempdir().unwrap();
    let input = std::fs::read(sample_rig()).unwrap();
    let pipeline = write_rig_pipeline(dir.path(), &input, "target_vertices = 2676\nplacement = \"optimal\"");
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let simplified = read(&dir.path().join("out/avatar/simplified.glb"));
    assert!(simplified.mesh.influences.max_influences() <= 4);
    let figures: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("out/avatar/simplified-rig.json")).unwrap())
            .unwrap();
    assert!(figures["refitted_vertices"].as_u64().unwrap() > 0, "{figures}");
}

#[test]
fn a_rig_with_unnormalised_weights_fails_naming_file_and_vertex_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let mut rig = read(&sample_rig());
    rig.mesh.influences.weights[0] = 0.25;
    let pipeline =
        write_rig_pipeline(dir.path(), &desal_rig::write_glb(&rig).unwrap(), "target_vertices = 2676");
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(err.contains("avatar.glb: mesh 'Body' vertex 0: skinning weights sum to"), "{err}");
    assert!(!dir.path().join("out/avatar").exists(), "no partial output");
}

#[test]
fn a_rig_table_and_pose_files_together_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_rig_pipeline(dir.path(), b"", "target_vertices = 100");
    let text = std::fs::read_to_string(&pipeline)
        .unwrap()
        .replace("up_axis", "poses = \"*.ply\"\nlabels = \"l.txt\"\nup_axis");
    std::fs::write(&pipeline, text).unwrap();
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("a [dataset.rig] replaces `poses` and `labels`"), "{}", stderr(&out));
}

#[test]
fn a_file_that_is_not_gltf_is_refused_with_its_path() {
    let dir = tempfile::tempdir().unwrap();
    let pipeline = write_rig_pipeline(dir.path(), b"not a rig", "target_vertices = 100");
    let out = desal(&["run", pipeline.to_str().unwrap(), "--quiet"]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("avatar.glb: not a valid glTF 2.0 file"), "{}", stderr(&out));
    assert!(!dir.path().join("out/avatar").exists());
}
