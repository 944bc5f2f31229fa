//! The seed inputs each target mutates, built from the repository's own files: the
//! sample's PLY poses and labels (`data-samples/`), the frozen artifact fixtures
//! (`tests/fixtures/*.dsa`), and small conversions of a cropped sample mesh to ASCII and
//! big-endian PLY, OBJ and OFF (so that header and text mutations hit small inputs
//! fast). Nothing here comes from `../shared`.

use std::path::{Path, PathBuf};

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
            vec![Seed { name: "labels.txt comments, 32 vertices".into(), bytes: small.into_bytes() }, full]
        }
        Target::LabelsJson => vec![
            read("data-samples/labels.json")?,
            Seed {
                name: "small labels.json".into(),
                bytes: br#"{"parts": ["head", "hand", "foot"], "labels": [0, 1, 2, 2, 1, 0, 0]}"#.to_vec(),
            },
        ],
        Target::Artifact => {
            ["fit", "floor", "hierarchy-level", "labels", "map", "pose-set", "saliency", "simplified"]
                .iter()
                .map(|kind| read(&format!("tests/fixtures/{kind}-v1.dsa")))
                .collect::<Result<_, _>>()?
        }
        Target::CanaryPanic | Target::CanaryAbort | Target::CanaryHang | Target::CanaryOom => {
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
