//! The seed inputs each target mutates, built from the repository's own files: the
//! sample's PLY poses and labels (`data-samples/`), the frozen artifact fixtures
//! (`tests/fixtures/*.dsa`), the rig sample (`data-samples/rig.glb`), and small
//! generated inputs: conversions of a cropped sample mesh to ASCII and big-endian PLY,
//! OBJ and OFF (so that header and text mutations hit small inputs fast), labels whose
//! part names are in several scripts, a tiny rig ([`rig`]) in both glTF containers, and
//! `hierarchy.npz` files written by desal-io's own writer, and the pickle fixtures of
//! desal-io's unpickler (`crates/io/tests/fixtures/*.pkl`). Nothing here comes from
//! `../shared`.

pub mod rig;

use std::path::{Path, PathBuf};

use desal_io::npz::{CooArrays, HierarchyArrays};
use desal_io::ply::{PlyEncoding, PlyWriteOptions, write_ply};
use desal_mesh::{Face, TriMesh, Vec3};

use crate::Target;

/// One seed input.
#[derive(Debug, Clone)]
pub struct Seed {
    /// Where it came from, for the report.
    pub name: String,
    pub bytes: Vec<u8>,
}

/// The checkout this crate was built in (the corpus root by default).
pub fn default_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The seeds of `target`, read from the checkout at `root`. Fails when a file the
/// corpus needs is missing (a fuzz run on an empty corpus would prove nothing).
pub fn seeds(target: Target, root: &Path) -> Result<Vec<Seed>, String> {
    let read = |rel: &str| -> Result<Seed, String> {
        let path = root.join(rel);
        let bytes = std::fs::read(&path).map_err(|e| format!("corpus file {}: {e}", path.display()))?;
        Ok(Seed { name: rel.to_owned(), bytes })
    };
    let sample = || -> Result<TriMesh, String> {
        let path = root.join("data-samples/poses/00_rest.ply");
        desal_io::read_mesh(&path).map_err(|e| format!("corpus: {e}"))
    };
    Ok(match target {
        Target::Ply => {
            let mut seeds = vec![read("data-samples/poses/00_rest.ply")?];
            for (name, mesh) in [("cropped sample", crop(&sample()?, 60)), ("octahedron", octahedron())] {
                for encoding in
                    [PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian, PlyEncoding::BinaryBigEndian]
                {
                    seeds.push(Seed {
                        name: format!("{name} ({encoding:?})"),
                        bytes: ply_bytes(&mesh, encoding)?,
                    });
                }
            }
            seeds
        }
        Target::Obj => vec![
            Seed {
                name: "cropped sample".into(),
                bytes: obj_text(&crop(&sample()?, 60), false).into_bytes(),
            },
            Seed {
                name: "octahedron, relative indices".into(),
                bytes: obj_text(&octahedron(), true).into_bytes(),
            },
        ],
        Target::Off => vec![
            Seed { name: "cropped sample".into(), bytes: off_text(&crop(&sample()?, 60)).into_bytes() },
            Seed { name: "octahedron".into(), bytes: off_text(&octahedron()).into_bytes() },
        ],
        Target::LabelsText => {
            // The sample's comment lines (they name 16 parts) and two vertices per part:
            // small, and accepted (every named part is used).
            let full = read("data-samples/labels.txt")?;
            let text = std::str::from_utf8(&full.bytes).map_err(|e| e.to_string())?;
            let mut small: String =
                text.lines().filter(|l| l.starts_with('#')).map(|l| format!("{l}\n")).collect();
            small.extend((0..32).map(|k| format!("{}\n", k % 16)));
            let ids: Vec<String> =
                UNICODE_PART_NAMES.iter().enumerate().map(|(k, n)| format!("{k}={n}")).collect();
            let parts =
                UNICODE_PART_NAMES.iter().map(|n| n.replace(char::is_whitespace, "_")).collect::<Vec<_>>();
            let ids_per_vertex: String = (0..2 * UNICODE_PART_NAMES.len())
                .map(|k| format!("{}\n", k % UNICODE_PART_NAMES.len()))
                .collect();
            vec![
                Seed { name: "labels.txt comments, 32 vertices".into(), bytes: small.into_bytes() },
                full,
                Seed {
                    name: "unicode part names (# ids:)".into(),
                    bytes: format!("# ids: {}\n{ids_per_vertex}", ids.join(", ")).into_bytes(),
                },
                Seed {
                    name: "unicode part names (# parts:)".into(),
                    bytes: format!("# parts: {}\n{ids_per_vertex}", parts.join(" ")).into_bytes(),
                },
            ]
        }
        Target::LabelsJson => {
            let labels: Vec<usize> =
                (0..2 * UNICODE_PART_NAMES.len()).map(|k| k % UNICODE_PART_NAMES.len()).collect();
            let unicode = serde_json::json!({"parts": UNICODE_PART_NAMES, "labels": labels});
            vec![
                read("data-samples/labels.json")?,
                Seed {
                    name: "small labels.json".into(),
                    bytes: br#"{"parts": ["head", "hand", "foot"], "labels": [0, 1, 2, 2, 1, 0, 0]}"#
                        .to_vec(),
                },
                Seed {
                    name: "unicode part names".into(),
                    bytes: serde_json::to_vec(&unicode).map_err(|e| e.to_string())?,
                },
            ]
        }
        Target::Artifact => {
            ["fit", "floor", "hierarchy-level", "labels", "map", "pose-set", "saliency", "simplified"]
                .iter()
                .map(|kind| read(&format!("tests/fixtures/{kind}-v1.dsa")))
                .collect::<Result<_, _>>()?
        }
        Target::GltfJson | Target::GltfGlb => {
            let sample = read("data-samples/rig.glb")?;
            let (json, bin) =
                rig::split_glb(&sample.bytes).ok_or("corpus: data-samples/rig.glb is not a GLB")?;
            let sample_json: serde_json::Value =
                serde_json::from_slice(json).map_err(|e| format!("corpus: rig.glb: {e}"))?;
            let (small, small_bin) = rig::small_rig();
            let two_buffers = with_second_buffer(&small, &small_bin);
            let (written, written_bin) = desal_written(&small, &small_bin)?;
            let flavours = [
                ("small rig", &small, &small_bin[..]),
                ("small rig, animation in a second (data: URI) buffer", &two_buffers, &small_bin[..]),
                ("small rig as desal-rig writes it", &written, &written_bin[..]),
                ("data-samples/rig.glb", &sample_json, bin),
            ];
            flavours
                .into_iter()
                .map(|(name, document, bin)| {
                    let bytes = if target == Target::GltfJson {
                        rig::gltf_with_data_uri(document, bin)
                    } else {
                        let json =
                            serde_json::to_vec(&without_first_uri(document)).map_err(|e| e.to_string())?;
                        rig::glb(&json, bin)
                    };
                    Ok(Seed { name: name.into(), bytes })
                })
                .collect::<Result<_, String>>()?
        }
        Target::Npz => [("2 levels", vec![7, 3]), ("3 levels", vec![12, 6, 3])]
            .into_iter()
            .map(|(name, levels)| {
                let arrays = small_hierarchy(&levels).to_arrays()?;
                let bytes = desal_io::npz::encode_npz(&arrays)?;
                Ok(Seed { name: format!("hierarchy.npz, {name}"), bytes })
            })
            .collect::<Result<_, String>>()?,
        Target::Pickle => ["py2_chumpy.pkl", "py3_protocol2.pkl", "py3_protocol4.pkl"]
            .into_iter()
            .map(|name| read(&format!("crates/io/tests/fixtures/{name}")))
            .collect::<Result<_, String>>()?,
        Target::CanaryGltfStride => seeds(Target::GltfGlb, root)?,
        Target::CanaryNpzShape => seeds(Target::Npz, root)?,
        Target::CanaryPanic
        | Target::CanaryAbort
        | Target::CanaryHang
        | Target::CanaryOom
        | Target::CanaryMemory => {
            vec![Seed { name: "canary".into(), bytes: b"canary".to_vec() }]
        }
    })
}

/// The first `faces` triangles of `mesh` and the vertices they use, renumbered in order
/// of first use: a small mesh with the sample's real coordinates.
fn crop(mesh: &TriMesh, faces: usize) -> TriMesh {
    let mut new_index = vec![u32::MAX; mesh.vertex_count()];
    let mut positions = Vec::new();
    let faces = mesh.faces[..faces.min(mesh.face_count())]
        .iter()
        .map(|f| {
            f.map(|v| {
                if new_index[v as usize] == u32::MAX {
                    new_index[v as usize] = positions.len() as u32;
                    positions.push(mesh.positions[v as usize]);
                }
                new_index[v as usize]
            })
        })
        .collect();
    TriMesh { positions, faces }
}

/// A closed octahedron (8 triangles).
fn octahedron() -> TriMesh {
    let positions = vec![
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(-1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, -1.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.0, 0.0, -1.0),
    ];
    let faces: Vec<Face> =
        vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
    TriMesh { positions, faces }
}

fn ply_bytes(mesh: &TriMesh, encoding: PlyEncoding) -> Result<Vec<u8>, String> {
    let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
    let path = dir.path().join("seed.ply");
    let options = PlyWriteOptions {
        encoding,
        scalars: vec![("saliency".into(), (0..mesh.vertex_count()).map(|v| v as f32 * 0.01).collect())],
        comments: vec!["desal fuzz seed".into()],
        ..PlyWriteOptions::default()
    };
    write_ply(&path, mesh, &options).map_err(|e| e.to_string())?;
    std::fs::read(&path).map_err(|e| e.to_string())
}

/// OBJ text with a comment, a normal and texture coordinate per corner on the first
/// face, and (when `relative`) negative indices on every other face.
fn obj_text(mesh: &TriMesh, relative: bool) -> String {
    let mut text = String::from("# desal fuzz seed\no seed\n");
    for p in &mesh.positions {
        text.push_str(&format!("v {} {} {}\nvn 0 0 1\nvt 0.5 0.5\n", p.x, p.y, p.z));
    }
    let n = mesh.vertex_count() as i64;
    for (k, f) in mesh.faces.iter().enumerate() {
        let corner =
            |v: u32| if relative && k % 2 == 1 { (v as i64 - n).to_string() } else { (v + 1).to_string() };
        if k == 0 {
            text.push_str(&format!(
                "f {0}/{0}/{0} {1}/{1}/{1} {2}//{2}\n",
                corner(f[0]),
                corner(f[1]),
                corner(f[2])
            ));
        } else {
            text.push_str(&format!("f {} {} {}\n", corner(f[0]), corner(f[1]), corner(f[2])));
        }
    }
    text
}

fn off_text(mesh: &TriMesh) -> String {
    let mut text = format!("OFF\n# desal fuzz seed\n{} {} 0\n", mesh.vertex_count(), mesh.face_count());
    for p in &mesh.positions {
        text.push_str(&format!("{} {} {}\n", p.x, p.y, p.z));
    }
    for f in &mesh.faces {
        text.push_str(&format!("3 {} {} {} 255 0 0\n", f[0], f[1], f[2]));
    }
    text
}

/// Part names a user may give: several scripts, a combining mark, right-to-left text and
/// an override, emoji with a skin tone and a zero-width joiner, a NUL, mathematical
/// letters outside the BMP, and characters that are separators in the text form.
pub const UNICODE_PART_NAMES: [&str; 12] = [
    "Kopf",
    "рука",
    "手",
    "يد",
    "e\u{301}paule",
    "🦶🏽",
    "\u{202e}tfel",
    "👨\u{200d}👩\u{200d}👧",
    "a\u{0}b",
    "𝕳𝖊𝖆𝖉",
    "ﬁnger\u{fe0f}",
    "\u{feff}hip",
];

/// The small rig with a second buffer (a `data:` URI holding the same bytes) that the
/// animation's buffer views read from: a rig with buffers in both places.
fn with_second_buffer(document: &serde_json::Value, bin: &[u8]) -> serde_json::Value {
    let mut document = document.clone();
    let uri = format!("data:application/octet-stream;base64,{}", rig::base64(bin));
    if let Some(buffers) = document["buffers"].as_array_mut() {
        buffers.push(serde_json::json!({"byteLength": bin.len(), "uri": uri}));
    }
    let animated: Vec<u64> = document["animations"][0]["samplers"]
        .as_array()
        .into_iter()
        .flatten()
        .flat_map(|s| [&s["input"], &s["output"]])
        .filter_map(|a| a.as_u64())
        .filter_map(|a| document["accessors"][a as usize]["bufferView"].as_u64())
        .collect();
    for view in animated {
        document["bufferViews"][view as usize]["buffer"] = 1.into();
    }
    document
}

/// The small rig read by desal-rig and written back by its own writer (`simplified.glb`'s
/// layout: tightly packed `f32`, `u16` joints, `u32` indices): the JSON and the buffer.
fn desal_written(document: &serde_json::Value, bin: &[u8]) -> Result<(serde_json::Value, Vec<u8>), String> {
    let json = serde_json::to_vec(&without_first_uri(document)).map_err(|e| e.to_string())?;
    let path = Path::new("small-rig.glb");
    let read = desal_rig::read_rig_from(path, &rig::glb(&json, bin), &desal_rig::ReadOptions::default())
        .map_err(|e| format!("corpus: the generated rig is refused: {e}"))?;
    let written = desal_rig::write_glb(&read).map_err(|e| format!("corpus: {e}"))?;
    let (json, bin) = rig::split_glb(&written).ok_or("corpus: desal-rig wrote a GLB it cannot split")?;
    let json = serde_json::from_slice(json).map_err(|e| format!("corpus: desal-rig's GLB JSON: {e}"))?;
    Ok((json, bin.to_vec()))
}

/// `document` with its first buffer in the GLB's binary chunk (no `uri`).
fn without_first_uri(document: &serde_json::Value) -> serde_json::Value {
    let mut document = document.clone();
    if let Some(buffer) = document.pointer_mut("/buffers/0").and_then(|b| b.as_object_mut()) {
        buffer.remove("uri");
    }
    document
}

/// A hierarchy with `levels[k]` vertices at level k: a fan of triangles per level, a
/// ring adjacency, and each step keeping every other vertex, as desal-hierarchy's arrays
/// are shaped (the values are plausible, not a real simplification).
fn small_hierarchy(levels: &[usize]) -> HierarchyArrays {
    let fan = |n: usize| (1..n as u32 - 1).map(|v| [0, v, v + 1]).collect::<Vec<_>>();
    let ring = |n: usize| {
        let row: Vec<u32> = (0..n as u32).flat_map(|v| [v, v]).collect();
        let col: Vec<u32> =
            (0..n as u32).flat_map(|v| [(v + 1) % n as u32, (v + n as u32 - 1) % n as u32]).collect();
        CooArrays { shape: [n, n], data: vec![1.0; row.len()], row, col }
    };
    let steps = levels.windows(2);
    let map: Vec<Vec<u32>> =
        steps.clone().map(|w| (0..w[1] as u32).map(|c| 2 * c % w[0] as u32).collect()).collect();
    let mut orig: Vec<Vec<u32>> = Vec::new();
    for (k, m) in map.iter().enumerate() {
        orig.push(m.iter().map(|&f| if k == 0 { f } else { orig[k - 1][f as usize] }).collect());
    }
    let down = steps
        .clone()
        .zip(&map)
        .map(|(w, m)| CooArrays {
            shape: [w[1], w[0]],
            row: (0..w[1] as u32).collect(),
            col: m.clone(),
            data: vec![1.0; w[1]],
        })
        .collect();
    let up = steps
        .zip(&map)
        .map(|(w, m)| {
            let row: Vec<u32> = (0..w[0] as u32).collect();
            let col: Vec<u32> =
                row.iter().map(|&f| m.iter().position(|&c| c == f).unwrap_or(0) as u32).collect();
            CooArrays { shape: [w[0], w[1]], data: vec![1.0; row.len()], row, col }
        })
        .collect();
    HierarchyArrays {
        levels: levels.to_vec(),
        faces: levels.iter().map(|&n| fan(n)).collect(),
        adjacency: levels.iter().map(|&n| ring(n)).collect(),
        down,
        up,
        map,
        orig,
    }
}
