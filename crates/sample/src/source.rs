//! The CC0 MakeHuman source assets, read as shipped in `data-samples/source/`: the base
//! mesh (`base.obj`), the `cmu_mb` rig, its skinning weights and the base mesh's named
//! vertex groups.
//!
//! Everything here is in the OBJ's own frame and units (decimetres, Y up, the body
//! facing +Z, its left side at +X). The rig's `default_position` numbers are in
//! Blender's Z-up frame and are deliberately never read: joints are placed from the
//! base mesh's joint cubes instead (see `skeleton.rs`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use desal_mesh::TriMesh;
use serde::Deserialize;

use crate::error::SampleError;

/// File names of the assets inside a source folder.
pub const BASE_MESH_FILE: &str = "base.obj";
pub const RIG_FILE: &str = "rig.cmu_mb.json";
pub const WEIGHTS_FILE: &str = "weights.cmu_mb.json";
pub const GROUPS_FILE: &str = "basemesh_vertex_groups.json";
/// The folder of the face units (`<name>.target` files).
pub const FACE_UNITS_DIR: &str = "faceunits";

/// The face units the avatar sample carries as morph targets, in target order: the
/// file names in [`FACE_UNITS_DIR`] (MakeHuman's ARKit-named `faceunits01`) and the names
/// in the avatar's `extras.targetNames`.
pub const FACE_UNITS: [&str; 5] =
    ["eyeBlinkLeft", "eyeBlinkRight", "jawOpen", "mouthSmileLeft", "mouthSmileRight"];

/// Where a joint (a bone's head or tail) sits in the rest pose.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum JointSpec {
    /// The centroid of a named vertex group of the base mesh (a "joint cube").
    Group(String),
    /// The mean of these base-mesh vertices.
    Mean(Vec<u32>),
}

/// One bone of the rig as the file describes it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RigBone {
    /// Parent bone name; empty for the root.
    pub parent: String,
    pub head: JointSpec,
    pub tail: JointSpec,
}

/// All source assets, parsed. Maps are ordered by name, so every iteration over them
/// is deterministic.
#[derive(Debug, Clone)]
pub struct SourceAssets {
    /// The whole base mesh (body, helper geometry and joint cubes), fan-triangulated, in
    /// OBJ vertex order and units (decimetres).
    pub base: TriMesh,
    /// Bones by name.
    pub rig: BTreeMap<String, RigBone>,
    /// Skinning weights: bone name → `(base-mesh vertex, weight)` in file order.
    pub weights: BTreeMap<String, Vec<(u32, f64)>>,
    /// Vertex groups: name → inclusive `[first, last]` base-mesh vertex ranges.
    pub groups: BTreeMap<String, Vec<[u32; 2]>>,
    /// The base mesh's texture coordinates and the UV corners of its triangles.
    pub uvs: ObjUvs,
    /// Face units ([`FACE_UNITS`]): name → `(base-mesh vertex, delta)` in file order, in
    /// OBJ units.
    pub face_units: BTreeMap<String, Vec<(u32, [f64; 3])>>,
}

impl SourceAssets {
    /// Reads the four asset files from `dir` (see the `*_FILE` constants).
    pub fn load(dir: &Path) -> Result<Self, SampleError> {
        let base = desal_io::read_mesh(&dir.join(BASE_MESH_FILE))?;
        let uvs = parse_obj_uvs(&read_text(&dir.join(BASE_MESH_FILE))?, &dir.join(BASE_MESH_FILE))?;
        let rig = parse_rig(&read_text(&dir.join(RIG_FILE))?, &dir.join(RIG_FILE))?;
        let weights = parse_weights(&read_text(&dir.join(WEIGHTS_FILE))?, &dir.join(WEIGHTS_FILE))?;
        let groups = parse_groups(&read_text(&dir.join(GROUPS_FILE))?, &dir.join(GROUPS_FILE))?;
        let mut face_units = BTreeMap::new();
        for name in FACE_UNITS {
            let path = dir.join(FACE_UNITS_DIR).join(format!("{name}.target"));
            face_units.insert(name.to_owned(), parse_target(&read_text(&path)?, &path)?);
        }
        Ok(Self { base, rig, weights, groups, uvs, face_units })
    }

    /// The base-mesh vertex indices of group `name`, ascending as listed (`None` when
    /// there is no such group).
    pub fn group_vertices(&self, name: &str) -> Option<Vec<u32>> {
        let ranges = self.groups.get(name)?;
        Some(ranges.iter().flat_map(|&[first, last]| first..=last).collect())
    }
}

fn read_text(path: &Path) -> Result<String, SampleError> {
    std::fs::read_to_string(path)
        .map_err(|cause| SampleError::Io(desal_io::IoError::Io { path: path.to_owned(), cause }))
}

fn json_error(path: &Path, e: impl std::fmt::Display) -> SampleError {
    SampleError::Json { path: path.to_owned(), reason: e.to_string() }
}

/// The rig file's per-bone record; fields this generator does not use (roll,
/// `default_position`, Blender flags) are ignored.
#[derive(Deserialize)]
struct RigBoneJson {
    parent: String,
    head: JointJson,
    tail: JointJson,
}

#[derive(Deserialize)]
struct JointJson {
    cube_name: Option<String>,
    vertex_indices: Option<Vec<u32>>,
}

#[derive(Deserialize)]
struct WeightsJson {
    weights: BTreeMap<String, Vec<(u32, f64)>>,
}

/// Parses a rig file (`rig.cmu_mb.json`): bone name → parent, head, tail. `path` only
/// names the file in errors.
pub fn parse_rig(text: &str, path: &Path) -> Result<BTreeMap<String, RigBone>, SampleError> {
    let raw: BTreeMap<String, RigBoneJson> = serde_json::from_str(text).map_err(|e| json_error(path, e))?;
    raw.into_iter()
        .map(|(name, bone)| {
            let head = joint_spec(&name, bone.head)?;
            let tail = joint_spec(&name, bone.tail)?;
            Ok((name, RigBone { parent: bone.parent, head, tail }))
        })
        .collect()
}

fn joint_spec(bone: &str, joint: JointJson) -> Result<JointSpec, SampleError> {
    match (joint.cube_name, joint.vertex_indices) {
        (Some(group), _) => Ok(JointSpec::Group(group)),
        (None, Some(vertices)) if !vertices.is_empty() => Ok(JointSpec::Mean(vertices)),
        _ => Err(SampleError::UnknownJointStrategy { bone: bone.to_owned() }),
    }
}

/// Parses a weights file (`weights.cmu_mb.json`, key `weights`: bone → `[[vertex,
/// weight], ...]`).
pub fn parse_weights(text: &str, path: &Path) -> Result<BTreeMap<String, Vec<(u32, f64)>>, SampleError> {
    let raw: WeightsJson = serde_json::from_str(text).map_err(|e| json_error(path, e))?;
    Ok(raw.weights)
}

/// Parses a vertex-group file (`basemesh_vertex_groups.json`: name → `[[first, last],
/// ...]`, inclusive ranges).
pub fn parse_groups(text: &str, path: &Path) -> Result<BTreeMap<String, Vec<[u32; 2]>>, SampleError> {
    serde_json::from_str(text).map_err(|e| json_error(path, e))
}

/// Parses a MakeHuman target file: one `vertex dx dy dz` line per moved vertex (OBJ
/// units); `#` lines are comments.
pub fn parse_target(text: &str, path: &Path) -> Result<Vec<(u32, [f64; 3])>, SampleError> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = line.split_whitespace().collect();
        let parsed = match fields.as_slice() {
            [v, x, y, z] => v.parse::<u32>().ok().zip(
                [x, y, z]
                    .iter()
                    .map(|f| f.parse::<f64>().ok().filter(|d| d.is_finite()))
                    .collect::<Option<Vec<_>>>(),
            ),
            _ => None,
        };
        let (v, d) =
            parsed.ok_or_else(|| json_error(path, format!("line {}: expected `vertex dx dy dz`", i + 1)))?;
        out.push((v, [d[0], d[1], d[2]]));
    }
    Ok(out)
}

/// The source folder shipped in this repository (`data-samples/source`), located from
/// this crate's manifest at compile time.
pub fn repository_source_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data-samples/source")
}

/// Texture coordinates of the base mesh: `uvs[vt]`, and per triangle of the
/// fan-triangulated faces (in `desal_io::read_mesh`'s order), the `vt` index of each
/// corner.
#[derive(Debug, Clone, PartialEq)]
pub struct ObjUvs {
    pub uvs: Vec<[f32; 2]>,
    pub triangles: Vec<[u32; 3]>,
    /// The vertex index of each corner (to check against the mesh's own faces).
    pub vertex_triangles: Vec<[u32; 3]>,
}

/// Reads the `vt` lines and the `v/vt` corners of the `f` lines of an OBJ file.
pub fn parse_obj_uvs(text: &str, path: &Path) -> Result<ObjUvs, SampleError> {
    let bad = |line: usize, reason: &str| SampleError::Json {
        path: path.to_owned(),
        reason: format!("line {line}: {reason}"),
    };
    let mut out = ObjUvs { uvs: Vec::new(), triangles: Vec::new(), vertex_triangles: Vec::new() };
    for (i, raw) in text.lines().enumerate() {
        let mut fields = raw.split_whitespace();
        match fields.next() {
            Some("vt") => {
                let mut uv = [0.0f32; 2];
                for slot in &mut uv {
                    *slot = fields
                        .next()
                        .and_then(|f| f.parse().ok())
                        .ok_or_else(|| bad(i + 1, "a texture coordinate needs two numbers"))?;
                }
                // OBJ's v runs up from the bottom of the image, glTF's down from the top.
                out.uvs.push([uv[0], 1.0 - uv[1]]);
            }
            Some("f") => {
                let mut corners: Vec<(u32, u32)> = Vec::new();
                for field in fields {
                    let mut parts = field.split('/');
                    let index = |p: Option<&str>| -> Option<u32> { p?.parse::<u32>().ok()?.checked_sub(1) };
                    let v = index(parts.next());
                    let t = index(parts.next());
                    match (v, t) {
                        (Some(v), Some(t)) => corners.push((v, t)),
                        _ => return Err(bad(i + 1, "every face corner needs positive v/vt indices")),
                    }
                }
                for k in 1..corners.len().saturating_sub(1) {
                    let tri = [corners[0], corners[k], corners[k + 1]];
                    out.vertex_triangles.push(tri.map(|c| c.0));
                    out.triangles.push(tri.map(|c| c.1));
                }
            }
            _ => {}
        }
    }
    if let Some(t) = out.triangles.iter().flatten().find(|&&t| t as usize >= out.uvs.len()) {
        return Err(bad(0, &format!("texture coordinate {} is not defined", t + 1)));
    }
    Ok(out)
}
