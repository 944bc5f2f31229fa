//! Hostile rig files (issue 39, rows D1–D4, D8–D10, D12 and the rig's part of D17): each
//! test builds a small valid skinned glTF — a square of two triangles on a two-joint
//! skeleton with one animation — breaks one thing in it, and checks the error names the
//! file and the glTF element. Valid variants (quantised attributes, sparse accessors,
//! odd `extras`, a deep node chain) must load with exact values.

use std::path::{Path, PathBuf};

use serde_json::{Value, json};

use desal_rig::{
    FrameConfig, PoseSource, ReadOptions, Rig, RigError, pose_rig, read_rig, read_rig_from, sample_frames,
};

const BYTE: u32 = 5120;
const UNSIGNED_BYTE: u32 = 5121;
const SHORT: u32 = 5122;
const UNSIGNED_SHORT: u32 = 5123;
const UNSIGNED_INT: u32 = 5125;
const FLOAT: u32 = 5126;

/// Accessor indices of [`Fixture::square`].
const POSITION: usize = 0;
const NORMAL: usize = 1;
const TEXCOORD: usize = 2;
const JOINTS: usize = 3;
const WEIGHTS: usize = 4;
const INDICES: usize = 5;
const INVERSE_BIND: usize = 6;
const TIMES: usize = 7;
const ROTATIONS: usize = 8;
const SCALES: usize = 10;

/// A glTF under construction: its JSON (without `buffers`) and its one buffer's bytes.
#[derive(Clone)]
struct Fixture {
    json: Value,
    bin: Vec<u8>,
}

fn f32_bytes(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn u16_bytes(values: &[u16]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

impl Fixture {
    /// The unit square in z = 0 (vertices 0, 1 on joint 0 "root", 2, 3 on joint 1
    /// "child" one unit up), its normals and UVs, and animation "wave": channel 0 turns
    /// the child 90° about z, channel 1 moves the root, channel 2 scales the child by 1.
    fn square() -> Self {
        let mut f = Fixture {
            json: json!({
                "asset": {"version": "2.0"},
                "scene": 0,
                "scenes": [{"nodes": [0, 2]}],
                "nodes": [
                    {"name": "root", "children": [1]},
                    {"name": "child", "translation": [0.0, 1.0, 0.0]},
                    {"name": "body", "mesh": 0, "skin": 0}
                ],
                "meshes": [{"name": "body", "primitives": [{
                    "attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2, "JOINTS_0": 3, "WEIGHTS_0": 4},
                    "indices": 5
                }]}],
                "skins": [{"name": "skin", "joints": [0, 1], "inverseBindMatrices": 6}],
                "animations": [{
                    "name": "wave",
                    "samplers": [
                        {"input": 7, "output": 8},
                        {"input": 7, "output": 9},
                        {"input": 7, "output": 10}
                    ],
                    "channels": [
                        {"sampler": 0, "target": {"node": 1, "path": "rotation"}},
                        {"sampler": 1, "target": {"node": 0, "path": "translation"}},
                        {"sampler": 2, "target": {"node": 1, "path": "scale"}}
                    ]
                }],
                "bufferViews": [],
                "accessors": []
            }),
            bin: Vec::new(),
        };
        let p =
            f.accessor(f32_bytes(&[0., 0., 0., 1., 0., 0., 0., 1., 0., 1., 1., 0.]), FLOAT, "VEC3", 4, false);
        f.json["accessors"][p]["min"] = json!([0.0, 0.0, 0.0]);
        f.json["accessors"][p]["max"] = json!([1.0, 1.0, 0.0]);
        f.accessor(f32_bytes(&[0., 0., 1., 0., 0., 1., 0., 0., 1., 0., 0., 1.]), FLOAT, "VEC3", 4, false);
        f.accessor(f32_bytes(&[0., 0., 1., 0., 0., 1., 1., 1.]), FLOAT, "VEC2", 4, false);
        f.accessor(
            u16_bytes(&[0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0]),
            UNSIGNED_SHORT,
            "VEC4",
            4,
            false,
        );
        f.accessor(
            f32_bytes(&[1., 0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0., 1., 0., 0., 0.]),
            FLOAT,
            "VEC4",
            4,
            false,
        );
        f.accessor(u16_bytes(&[0, 1, 2, 2, 1, 3]), UNSIGNED_SHORT, "SCALAR", 6, false);
        let mut child_ibm = identity();
        child_ibm[13] = -1.0;
        f.accessor(f32_bytes(&[identity(), child_ibm].concat()), FLOAT, "MAT4", 2, false);
        f.accessor(f32_bytes(&[0.0, 1.0]), FLOAT, "SCALAR", 2, false);
        let half = std::f32::consts::FRAC_1_SQRT_2;
        f.accessor(f32_bytes(&[0., 0., 0., 1., 0., 0., half, half]), FLOAT, "VEC4", 2, false);
        f.accessor(f32_bytes(&[0., 0., 0., 0., 0.5, 0.]), FLOAT, "VEC3", 2, false);
        f.accessor(f32_bytes(&[1., 1., 1., 1., 1., 1.]), FLOAT, "VEC3", 2, false);
        f
    }

    /// Appends `bytes` as a new buffer view (4-byte aligned) and returns its index.
    fn view(&mut self, bytes: &[u8]) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let views = self.json["bufferViews"].as_array_mut().unwrap();
        views.push(json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()}));
        self.bin.extend_from_slice(bytes);
        views.len() - 1
    }

    /// Appends an accessor over a new view of `bytes` and returns its index.
    fn accessor(
        &mut self,
        bytes: Vec<u8>,
        component: u32,
        kind: &str,
        count: usize,
        normalized: bool,
    ) -> usize {
        let view = self.view(&bytes);
        let accessors = self.json["accessors"].as_array_mut().unwrap();
        let mut accessor =
            json!({"bufferView": view, "componentType": component, "count": count, "type": kind});
        if normalized {
            accessor["normalized"] = true.into();
        }
        accessors.push(accessor);
        accessors.len() - 1
    }

    /// Points accessor `a` at new data of another component type.
    fn retype(&mut self, a: usize, bytes: Vec<u8>, component: u32, normalized: bool) {
        let view = self.view(&bytes);
        let accessor = &mut self.json["accessors"][a];
        accessor["bufferView"] = view.into();
        accessor["componentType"] = component.into();
        accessor["normalized"] = normalized.into();
    }

    fn with_buffer(&self, buffer: Value) -> Value {
        let mut json = self.json.clone();
        json["buffers"] = json!([buffer]);
        json
    }

    /// The file as a `.glb`.
    fn glb(&self) -> Vec<u8> {
        let json = serde_json::to_vec(&self.with_buffer(json!({"byteLength": self.bin.len()}))).unwrap();
        let header = gltf::binary::Header { magic: *b"glTF", version: 2, length: 0 };
        gltf::binary::Glb { header, json: json.into(), bin: Some(self.bin.clone().into()) }.to_vec().unwrap()
    }

    /// The file as a `.gltf` with the buffer in a base64 `data:` URI.
    fn embedded(&self) -> Vec<u8> {
        let data = base64(&self.bin);
        let uri = format!("data:application/octet-stream;base64,{data}");
        serde_json::to_vec(&self.with_buffer(json!({"byteLength": self.bin.len(), "uri": uri}))).unwrap()
    }

    /// The file as a `.gltf` whose buffer is the file `uri` (not written here).
    fn external(&self, uri: &str) -> Vec<u8> {
        serde_json::to_vec(&self.with_buffer(json!({"byteLength": self.bin.len(), "uri": uri}))).unwrap()
    }
}

/// Standard base64 with padding (RFC 4648).
fn base64(bytes: &[u8]) -> String {
    use base64::Engine;
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

fn identity() -> Vec<f32> {
    (0..16).map(|i| if i % 5 == 0 { 1.0 } else { 0.0 }).collect()
}

fn read(bytes: &[u8]) -> Result<Rig, RigError> {
    read_rig_from(Path::new("hostile.glb"), bytes, &ReadOptions::default())
}

/// The message of a refused file, checked to name the file and every `parts`.
#[track_caller]
fn refused(result: Result<impl std::fmt::Debug, RigError>, parts: &[&str]) -> String {
    let message = result.expect_err("must be refused").to_string();
    for part in parts {
        assert!(message.contains(part), "'{part}' not in: {message}");
    }
    message
}

#[track_caller]
fn refused_glb(f: &Fixture, parts: &[&str]) -> String {
    let message = refused(read(&f.glb()), parts);
    assert!(message.starts_with("hostile.glb: "), "{message}");
    message
}

// D1: accessors the `gltf` crate panicked on.

#[test]
fn d1_stride_smaller_than_element_is_refused() {
    let mut f = Fixture::square();
    let view = f.json["accessors"][POSITION]["bufferView"].as_u64().unwrap() as usize;
    f.json["bufferViews"][view]["byteStride"] = 8.into();
    refused_glb(
        &f,
        &["accessor 0 (POSITION of mesh 'body' primitive 0)", "byteStride 8, smaller than the element's 12"],
    );
}

#[test]
fn d1_float_joints_are_refused() {
    let mut f = Fixture::square();
    f.retype(JOINTS, f32_bytes(&[0.0; 16]), FLOAT, false);
    refused_glb(&f, &["accessor 3 (JOINTS_0 of mesh 'body' primitive 0)", "component type FLOAT"]);
}

#[test]
fn d1_u32_weights_are_refused() {
    let mut f = Fixture::square();
    f.retype(WEIGHTS, vec![0; 64], UNSIGNED_INT, false);
    refused_glb(&f, &["accessor 4 (WEIGHTS_0 of mesh 'body' primitive 0)", "component type UNSIGNED_INT"]);
}

#[test]
fn d1_float_indices_are_refused() {
    let mut f = Fixture::square();
    f.retype(INDICES, f32_bytes(&[0., 1., 2., 2., 1., 3.]), FLOAT, false);
    refused_glb(&f, &["accessor 5 (indices of mesh 'body' primitive 0)", "component type FLOAT"]);
}

#[test]
fn d1_u32_rotations_are_refused() {
    let mut f = Fixture::square();
    f.retype(ROTATIONS, vec![0; 32], UNSIGNED_INT, false);
    refused_glb(&f, &["accessor 8 (rotation keyframes of animation 'wave' channel 0)", "UNSIGNED_INT"]);
}

#[test]
fn d1_an_accessor_past_the_end_of_its_view_is_refused() {
    let mut f = Fixture::square();
    f.json["accessors"][NORMAL]["byteOffset"] = 4.into();
    refused_glb(&f, &["accessor 1 (NORMAL of mesh 'body' primitive 0)", "lie outside buffer view"]);
    let mut f = Fixture::square();
    f.json["accessors"][NORMAL]["count"] = 1_000_000_000_000u64.into();
    refused_glb(&f, &["accessor 1 (NORMAL", "lie outside buffer view"]);
}

#[test]
fn d1_a_view_past_the_end_of_its_buffer_is_refused() {
    let mut f = Fixture::square();
    f.json["bufferViews"][0]["byteOffset"] = u64::MAX.into();
    refused_glb(&f, &["accessor 0 (POSITION", "buffer view 0", "lies outside buffer 0"]);
}

#[test]
fn d1_a_glb_whose_header_counts_fewer_bytes_than_itself_is_refused() {
    let mut bytes = Fixture::square().glb();
    bytes[8..12].copy_from_slice(&4u32.to_le_bytes());
    refused(read(&bytes), &["hostile.glb: not a valid glTF 2.0 file"]);
}

// D1: references and enumerated values the `gltf` crate did not validate and panicked on
// (a channel's target node and path, the POSITION accessor), and the rest of the
// document's structure, refused by name before the crate reads the file.

/// `f`, broken by `breaks`, is refused in both containers with a [`RigError::Structure`]
/// whose message holds every `parts`.
#[track_caller]
fn structure_refused(breaks: impl Fn(&mut Value), parts: &[&str]) {
    let mut f = Fixture::square();
    breaks(&mut f.json);
    for (name, bytes) in [("hostile.glb", f.glb()), ("hostile.gltf", f.embedded())] {
        let result = read_rig_from(Path::new(name), &bytes, &ReadOptions::default());
        assert!(matches!(result, Err(RigError::Structure { .. })), "{name}: {result:?}");
        let message = refused(result, parts);
        assert!(message.starts_with(&format!("{name}: ")), "{message}");
    }
}

#[test]
fn d1_a_channel_targeting_a_missing_node_is_refused() {
    for node in [3u64, 255, 4_294_967_295] {
        structure_refused(
            |json| json["animations"][0]["channels"][1]["target"]["node"] = node.into(),
            &["animation 0 'wave' channel 1: the target refers to node", "but the file has 3 nodes"],
        );
    }
}

#[test]
fn d1_a_channel_with_a_path_gltf_does_not_define_is_refused() {
    for path in ["matrix", "", "Rotation"] {
        structure_refused(
            |json| json["animations"][0]["channels"][2]["target"]["path"] = path.into(),
            &[
                "animation 0 'wave' channel 2",
                &format!("path \"{path}\" is not one of translation, rotation, scale, weights"),
            ],
        );
    }
}

#[test]
fn d1_a_channel_naming_a_missing_sampler_is_refused() {
    structure_refused(
        |json| json["animations"][0]["channels"][0]["sampler"] = 3.into(),
        &["animation 0 'wave' channel 0: sampler 3 does not exist; the animation has 3 samplers"],
    );
}

#[test]
fn d1_a_sampler_with_an_unknown_interpolation_is_refused() {
    structure_refused(
        |json| json["animations"][0]["samplers"][1]["interpolation"] = "SMOOTH".into(),
        &["animation 0 'wave' sampler 1", "interpolation \"SMOOTH\" is not one of LINEAR, STEP, CUBICSPLINE"],
    );
    structure_refused(
        |json| json["animations"][0]["samplers"][2]["output"] = 11.into(),
        &["animation 0 'wave' sampler 2: output refers to accessor 11, but the file has 11 accessors"],
    );
}

#[test]
fn d1_a_position_past_the_accessors_is_refused() {
    structure_refused(
        |json| json["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 255.into(),
        &["mesh 0 'body' primitive 0: POSITION refers to accessor 255, but the file has 11 accessors"],
    );
    // The crate indexed `accessors[POSITION]` while validating, before checking it.
    structure_refused(
        |json| json["accessors"] = json!([]),
        &["mesh 0 'body' primitive 0", "refers to accessor", "but the file has no accessors"],
    );
}

#[test]
fn d1_primitive_references_past_their_arrays_are_refused() {
    structure_refused(
        |json| json["meshes"][0]["primitives"][0]["indices"] = 11.into(),
        &["mesh 0 'body' primitive 0: indices refers to accessor 11"],
    );
    structure_refused(
        |json| json["meshes"][0]["primitives"][0]["targets"] = json!([{"NORMAL": 40}]),
        &["mesh 0 'body' primitive 0: morph target 0 NORMAL refers to accessor 40"],
    );
    structure_refused(
        |json| json["meshes"][0]["primitives"][0]["material"] = 0.into(),
        &["mesh 0 'body' primitive 0: material refers to material 0, but the file has no materials"],
    );
    structure_refused(
        |json| json["meshes"][0]["primitives"][0]["mode"] = 7.into(),
        &["mesh 0 'body' primitive 0: mode 7 is not a glTF primitive mode"],
    );
}

#[test]
fn d1_node_and_scene_references_past_their_arrays_are_refused() {
    structure_refused(
        |json| json["nodes"][0]["children"] = json!([1, 33]),
        &["node 0 'root': child 1 refers to node 33, but the file has 3 nodes"],
    );
    structure_refused(
        |json| json["nodes"][2]["mesh"] = 1.into(),
        &["node 2 'body': mesh refers to mesh 1, but the file has 1 mesh"],
    );
    structure_refused(
        |json| json["nodes"][2]["skin"] = 2.into(),
        &["node 2 'body': skin refers to skin 2, but the file has 1 skin"],
    );
    structure_refused(
        |json| json["nodes"][1]["camera"] = 0.into(),
        &["node 1 'child': camera refers to camera 0, but the file has no cameras"],
    );
    structure_refused(
        |json| json["scenes"][0]["nodes"] = json!([0, 2, 3]),
        &["scene 0: node 2 refers to node 3, but the file has 3 nodes"],
    );
    structure_refused(
        |json| json["scene"] = 1.into(),
        &["the file: scene refers to scene 1, but the file has 1 scene"],
    );
}

#[test]
fn d1_skin_references_past_their_arrays_are_refused() {
    structure_refused(
        |json| json["skins"][0]["joints"] = json!([0, 65535]),
        &["skin 0 'skin': joint 1 refers to node 65535, but the file has 3 nodes"],
    );
    structure_refused(
        |json| json["skins"][0]["inverseBindMatrices"] = 99.into(),
        &["skin 0 'skin': inverseBindMatrices refers to accessor 99"],
    );
    structure_refused(
        |json| json["skins"][0]["skeleton"] = 3.into(),
        &["skin 0 'skin': skeleton refers to node 3"],
    );
}

#[test]
fn d1_accessor_and_buffer_view_references_past_their_arrays_are_refused() {
    structure_refused(
        |json| json["accessors"][TIMES]["bufferView"] = 11.into(),
        &["accessor 7: bufferView refers to buffer view 11, but the file has 11 buffer views"],
    );
    structure_refused(
        |json| json["bufferViews"][4]["buffer"] = 1.into(),
        &["buffer view 4: buffer refers to buffer 1, but the file has 1 buffer"],
    );
    structure_refused(
        |json| {
            json["accessors"][NORMAL]["sparse"] = json!({
                "count": 1,
                "indices": {"bufferView": 20, "componentType": UNSIGNED_BYTE},
                "values": {"bufferView": 0}
            })
        },
        &["accessor 1: the sparse indices' bufferView refers to buffer view 20"],
    );
    structure_refused(
        |json| {
            json["accessors"][NORMAL]["name"] = "normals".into();
            json["accessors"][NORMAL]["sparse"] = json!({
                "count": 1,
                "indices": {"bufferView": 0, "componentType": UNSIGNED_BYTE},
                "values": {"bufferView": 12}
            })
        },
        &["accessor 1 'normals': the sparse values' bufferView refers to buffer view 12"],
    );
}

#[test]
fn d1_accessor_types_gltf_does_not_define_are_refused() {
    structure_refused(
        |json| json["accessors"][POSITION]["type"] = "VEC5".into(),
        &["accessor 0: type \"VEC5\" is not one of SCALAR, VEC2, VEC3, VEC4, MAT2, MAT3, MAT4"],
    );
    structure_refused(
        |json| json["accessors"][SCALES]["componentType"] = 5124.into(),
        &["accessor 10: componentType 5124 is not one of 5120, 5121, 5122, 5123, 5125, 5126"],
    );
    structure_refused(
        |json| {
            json["accessors"][NORMAL]["sparse"] = json!({
                "count": 1,
                "indices": {"bufferView": 0, "componentType": FLOAT},
                "values": {"bufferView": 0}
            })
        },
        &["accessor 1: the sparse indices' componentType 5126 is not one of 5121, 5123, 5125"],
    );
}

// D2: sparse accessors sized by their count, not by the file.

/// POSITION as zeros plus sparse values at `indices`, without a buffer view.
fn sparse_positions(f: &mut Fixture, count: u64, indices: &[u32], values: &[f32]) {
    let index_view = f.view(&indices.iter().flat_map(|i| i.to_le_bytes()).collect::<Vec<_>>());
    let value_view = f.view(&f32_bytes(values));
    let accessor = f.json["accessors"][POSITION].as_object_mut().unwrap();
    accessor.remove("bufferView");
    accessor.insert("count".into(), count.into());
    accessor.insert(
        "sparse".into(),
        json!({
            "count": indices.len(),
            "indices": {"bufferView": index_view, "componentType": UNSIGNED_INT},
            "values": {"bufferView": value_view}
        }),
    );
}

#[test]
fn d2_a_sparse_accessor_without_a_view_counting_past_the_file_is_refused() {
    let mut f = Fixture::square();
    sparse_positions(&mut f, 2_000_000_000, &[1], &[1., 0., 0.]);
    refused_glb(
        &f,
        &["accessor 0 (POSITION of mesh 'body' primitive 0)", "no buffer view and count 2000000000"],
    );
}

#[test]
fn d2_a_sparse_accessor_without_a_view_is_zeros_and_its_values() {
    let mut f = Fixture::square();
    sparse_positions(&mut f, 4, &[1, 2, 3], &[1., 0., 0., 0., 1., 0., 1., 1., 0.]);
    let sparse = read(&f.glb()).unwrap();
    assert_eq!(sparse, read(&Fixture::square().glb()).unwrap());
}

// D3: deep node chains.

#[test]
fn d3_a_node_chain_30000_deep_is_read_and_posed_without_recursion() {
    const DEPTH: usize = 30_000;
    let flat = Fixture::square();
    let mut deep = flat.clone();
    // The child joint moves to the end of a chain of identity nodes below "child".
    let nodes = deep.json["nodes"].as_array_mut().unwrap();
    nodes[1]["children"] = json!([3]);
    for n in 3..3 + DEPTH {
        let children = if n + 1 < 3 + DEPTH { json!([n + 1]) } else { json!([]) };
        nodes.push(json!({"children": children}));
    }
    let last = 2 + DEPTH;
    deep.json["skins"][0]["joints"] = json!([0, last]);
    let config = FrameConfig { source: PoseSource::Random, frames: 2, seed: 7, max_degrees: 40.0 };
    let pose = |f: &Fixture| {
        let rig = read(&f.glb()).unwrap();
        pose_rig(&rig, &sample_frames(&rig, &config, Path::new("hostile.glb")).unwrap()).unwrap()
    };
    // Identity nodes change no bit of the world matrices, and the random turns depend
    // only on the joints, so the chain poses exactly as the flat rig.
    assert_eq!(pose(&deep).poses.poses, pose(&flat).poses.poses);
}

// D8: the pose set's size is capped before anything big is allocated.

#[test]
fn d8_frames_past_the_cap_are_refused() {
    let rig = read(&Fixture::square().glb()).unwrap();
    let config = FrameConfig { frames: 1_000_000_000, ..FrameConfig::default() };
    let m = refused(sample_frames(&rig, &config, Path::new("hostile.glb")), &["frames = 1000000000"]);
    assert!(m.contains(&format!("limit of {}", desal_rig::MAX_FRAMES)), "{m}");
}

#[test]
fn d8_frames_times_nodes_past_the_cap_are_refused() {
    let mut rig = read(&Fixture::square().glb()).unwrap();
    let extra = desal_rig::MAX_POSE_NODES / desal_rig::MAX_FRAMES + 1;
    rig.nodes.extend((0..extra).map(|_| desal_rig::Node {
        name: None,
        children: vec![],
        transform: desal_rig::LocalTransform::IDENTITY,
    }));
    let config =
        FrameConfig { source: PoseSource::Random, frames: desal_rig::MAX_FRAMES, ..FrameConfig::default() };
    refused(sample_frames(&rig, &config, Path::new("hostile.glb")), &["MAX_POSE_NODES"]);
}

#[test]
fn d8_poses_times_vertices_past_the_cap_are_refused_before_posing() {
    let mut rig = read(&Fixture::square().glb()).unwrap();
    // 4096 distinct vertices, all on joint 0.
    let vertices = 4096;
    rig.mesh.positions = (0..vertices).map(|v| [v as f32, 0.0, 0.0]).collect();
    rig.mesh.normals = None;
    rig.mesh.uvs = None;
    rig.mesh.influences = desal_rig::Influences::new();
    for _ in 0..vertices {
        rig.mesh.influences.push_row([(0, 1.0)]);
    }
    rig.mesh.triangles = vec![[0, 1, 2]];
    let frame = sample_frames(&rig, &FrameConfig { frames: 1, ..FrameConfig::default() }, Path::new("x"))
        .unwrap()
        .remove(0);
    let frames = vec![frame; desal_rig::MAX_POSE_VERTICES / vertices];
    let m = refused(pose_rig(&rig, &frames), &["4096 welded vertices", "MAX_POSE_VERTICES"]);
    assert!(m.contains(&format!("{} poses", frames.len() + 1)), "{m}");
}

// D9: accessor types checked against the specification's table.

#[test]
fn d9_vec2_positions_are_refused() {
    let mut f = Fixture::square();
    f.json["accessors"][POSITION]["type"] = "VEC2".into();
    refused_glb(&f, &["accessor 0 (POSITION of mesh 'body' primitive 0): has type VEC2; glTF requires VEC3"]);
}

#[test]
fn d9_u16_positions_without_mesh_quantization_are_refused() {
    let mut f = Fixture::square();
    f.retype(POSITION, u16_bytes(&[0; 12]), UNSIGNED_SHORT, false);
    refused_glb(
        &f,
        &["accessor 0 (POSITION", "UNSIGNED_SHORT", "need KHR_mesh_quantization in extensionsUsed"],
    );
}

#[test]
fn d9_scalar_joints_are_refused() {
    let mut f = Fixture::square();
    f.json["accessors"][JOINTS]["type"] = "SCALAR".into();
    refused_glb(
        &f,
        &["accessor 3 (JOINTS_0 of mesh 'body' primitive 0): has type SCALAR; glTF requires VEC4"],
    );
}

#[test]
fn d9_vec4_inverse_bind_matrices_are_refused() {
    let mut f = Fixture::square();
    f.json["accessors"][INVERSE_BIND]["type"] = "VEC4".into();
    refused_glb(&f, &["accessor 6 (inverseBindMatrices of skin 'skin'): has type VEC4; glTF requires MAT4"]);
}

#[test]
fn d9_u8_keyframe_times_are_refused() {
    let mut f = Fixture::square();
    f.retype(TIMES, vec![0, 1], UNSIGNED_BYTE, false);
    refused_glb(&f, &["accessor 7 (keyframe times of animation 'wave' channel 0)", "UNSIGNED_BYTE"]);
}

#[test]
fn d9_a_sparse_index_past_the_count_is_refused() {
    let mut f = Fixture::square();
    sparse_positions(&mut f, 4, &[1, 4], &[1., 0., 0., 9., 9., 9.]);
    refused_glb(&f, &["accessor 0 (POSITION", "sparse index 1 is 4, past the accessor's count 4"]);
}

#[test]
fn d9_sparse_indices_out_of_order_are_refused() {
    let mut f = Fixture::square();
    sparse_positions(&mut f, 4, &[2, 1], &[0., 1., 0., 1., 0., 0.]);
    refused_glb(&f, &["accessor 0 (POSITION", "strictly increasing"]);
}

#[test]
fn d9_normalized_float_weights_are_refused() {
    let mut f = Fixture::square();
    f.json["accessors"][WEIGHTS]["normalized"] = true.into();
    refused_glb(&f, &["accessor 4 (WEIGHTS_0", "component type normalized FLOAT"]);
}

/// Declares `KHR_mesh_quantization` (used and required, as gltfpack writes it).
fn quantized(mut f: Fixture) -> Fixture {
    f.json["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
    f.json["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    f
}

#[test]
fn d9_mesh_quantization_positions_normals_and_uvs_load_with_their_values() {
    // Unnormalised u16 positions, normalised i8 normals, unnormalised u16 UVs.
    let mut f = quantized(Fixture::square());
    f.retype(POSITION, u16_bytes(&[0, 0, 0, 1000, 0, 0, 0, 1000, 0, 1000, 1000, 0]), UNSIGNED_SHORT, false);
    f.json["accessors"][POSITION]["max"] = json!([1000, 1000, 0]);
    f.retype(
        NORMAL,
        [0, 0, 127, 0, 0, 0, 127, 0, 0, 0, 127, 0, 0, 0, -127, 0].map(|b: i8| b as u8).to_vec(),
        BYTE,
        true,
    );
    let view = f.view(&[0, 0, 127, 0, 0, 0, 127, 0, 0, 0, 127, 0, 0, 0, 129, 0]);
    f.json["accessors"][NORMAL]["bufferView"] = view.into();
    f.json["bufferViews"][view]["byteStride"] = 4.into();
    f.retype(TEXCOORD, u16_bytes(&[0, 0, 7, 0, 0, 9, 7, 9]), UNSIGNED_SHORT, false);
    let rig = read(&f.glb()).unwrap();
    assert_eq!(rig.mesh.positions, [[0., 0., 0.], [1000., 0., 0.], [0., 1000., 0.], [1000., 1000., 0.]]);
    assert_eq!(rig.mesh.normals.unwrap(), [[0., 0., 1.], [0., 0., 1.], [0., 0., 1.], [0., 0., -1.]]);
    assert_eq!(rig.mesh.uvs.unwrap(), [[0., 0.], [7., 0.], [0., 9.], [7., 9.]]);

    // Normalised i16 positions, normalised i16 normals, normalised i8 UVs (-128 clamps to -1).
    let mut f = quantized(Fixture::square());
    f.retype(
        POSITION,
        [0i16, 0, 0, 32767, 0, 0, 0, -32767, 0, 16384, -32768, 0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect(),
        SHORT,
        true,
    );
    f.json["accessors"][POSITION]["min"] = json!([0, -32768, 0]);
    f.json["accessors"][POSITION]["max"] = json!([32767, 0, 0]);
    f.retype(
        NORMAL,
        [0i16, 0, 32767, 0, 0, 32767, 0, -32767, 0, 0, 0, -32767]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect(),
        SHORT,
        true,
    );
    f.retype(TEXCOORD, [0i8, 0, 127, 0, 0, -128, 127, -127].map(|b| b as u8).to_vec(), BYTE, true);
    let rig = read(&f.glb()).unwrap();
    let half = 16384.0 / 32767.0;
    let p = &rig.mesh.positions;
    assert_eq!(p[..3], [[0., 0., 0.], [1., 0., 0.], [0., -1., 0.]]);
    assert!((p[3][0] - half).abs() < 1e-7 && p[3][1] == -1.0, "{p:?}");
    assert_eq!(rig.mesh.normals.unwrap(), [[0., 0., 1.], [0., 0., 1.], [0., -1., 0.], [0., 0., -1.]]);
    assert_eq!(rig.mesh.uvs.unwrap(), [[0., 0.], [1., 0.], [0., -1.], [1., -1.]]);
}

#[test]
fn d9_normalised_integers_convert_bit_for_bit_as_the_gltf_crate_converts_them() {
    let mut f = Fixture::square();
    f.retype(WEIGHTS, vec![255, 0, 0, 0, 200, 55, 0, 0, 255, 0, 0, 0, 128, 127, 0, 0], UNSIGNED_BYTE, true);
    f.json["accessors"][JOINTS]["bufferView"] =
        f.view(&u16_bytes(&[0, 0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0])).into();
    f.retype(TEXCOORD, u16_bytes(&[0, 0, 65535, 1, 3, 65534, 40000, 12345]), UNSIGNED_SHORT, true);
    let rotations: Vec<u8> =
        [0i16, 0, 0, 32767, 0, 0, 23170, 23170].iter().flat_map(|v| v.to_le_bytes()).collect();
    f.retype(ROTATIONS, rotations, SHORT, true);
    let glb = f.glb();
    let rig = read(&glb).unwrap();
    let theirs = gltf::Gltf::from_slice(&glb).unwrap();
    let blob = theirs.blob.clone().unwrap();
    let data = |_: gltf::Buffer<'_>| Some(blob.as_slice());
    let primitive = theirs.meshes().next().unwrap().primitives().next().unwrap();
    let reader = primitive.reader(data);
    let uvs: Vec<[f32; 2]> = reader.read_tex_coords(0).unwrap().into_f32().collect();
    assert_eq!(format!("{uvs:?}"), format!("{:?}", rig.mesh.uvs.unwrap()));
    let weights: Vec<f32> =
        reader.read_weights(0).unwrap().into_f32().flatten().filter(|&w| w > 0.0).collect();
    assert_eq!(
        weights.iter().map(|w| w.to_bits()).collect::<Vec<_>>(),
        rig.mesh.influences.weights.iter().map(|w| w.to_bits()).collect::<Vec<_>>()
    );
    let channel = theirs.animations().next().unwrap().channels().next().unwrap();
    let gltf::animation::util::ReadOutputs::Rotations(r) = channel.reader(data).read_outputs().unwrap()
    else {
        panic!("rotations")
    };
    let rotations: Vec<f32> = r.into_f32().flatten().collect();
    assert_eq!(
        rotations.iter().map(|w| w.to_bits()).collect::<Vec<_>>(),
        rig.animations[0].channels[0].values.iter().map(|w| w.to_bits()).collect::<Vec<_>>()
    );
}

// D10: degenerate transforms named where they are.

#[test]
fn d10_a_zero_rotation_on_a_node_is_refused() {
    let mut f = Fixture::square();
    f.json["nodes"][1]["rotation"] = json!([0.0, 0.0, 0.0, 0.0]);
    refused_glb(&f, &["hostile.glb: node 1 'child': rotation [0.0, 0.0, 0.0, 0.0] has length 0"]);
}

#[test]
fn d10_a_rotation_off_by_rounding_is_normalised() {
    let mut f = Fixture::square();
    f.json["nodes"][1]["rotation"] = json!([0.0, 0.0, 0.0, 1.00001]);
    let config = FrameConfig { frames: 3, ..FrameConfig::default() };
    let pose = |f: &Fixture| {
        let rig = read(&f.glb()).unwrap();
        pose_rig(&rig, &sample_frames(&rig, &config, Path::new("hostile.glb")).unwrap()).unwrap()
    };
    let (off, unit) = (pose(&f), pose(&Fixture::square()));
    for (a, b) in off.poses.poses.iter().flatten().zip(unit.poses.poses.iter().flatten()) {
        assert!((a - b).norm() < 1e-12, "{a} vs {b}");
    }
}

#[test]
fn d10_a_zero_rotation_keyframe_is_refused() {
    let mut f = Fixture::square();
    f.retype(ROTATIONS, f32_bytes(&[0., 0., 0., 1., 0., 0., 0., 0.]), FLOAT, false);
    refused_glb(
        &f,
        &["hostile.glb: animation 'wave' channel 0: keyframe 1: rotation [0.0, 0.0, 0.0, 0.0] has length 0"],
    );
}

#[test]
fn d10_a_singular_inverse_bind_matrix_is_refused() {
    let mut f = Fixture::square();
    f.retype(INVERSE_BIND, f32_bytes(&[identity(), vec![0.0; 16]].concat()), FLOAT, false);
    refused_glb(
        &f,
        &["hostile.glb: skin 'skin': the inverse bind matrix of joint 1 (node 1 'child') is singular"],
    );
}

#[test]
fn d10_a_non_finite_inverse_bind_matrix_is_refused() {
    let mut f = Fixture::square();
    let mut m = identity();
    m[12] = f32::INFINITY;
    f.retype(INVERSE_BIND, f32_bytes(&[m, identity()].concat()), FLOAT, false);
    refused_glb(
        &f,
        &["hostile.glb: skin 'skin': the inverse bind matrix of joint 0 (node 0 'root') is not finite"],
    );
}

#[test]
fn d10_a_huge_translation_is_refused_naming_the_node() {
    // 1e39 is beyond f32: the node's translation reads as infinite.
    let mut f = Fixture::square();
    f.json["nodes"][1]["translation"] = json!([1e39, 0.0, 0.0]);
    refused_glb(&f, &["hostile.glb: node 1 'child': translation [inf, 0.0, 0.0] is not finite"]);
}

#[test]
fn d10_a_transform_chain_that_overflows_is_refused_naming_the_node() {
    // Each scale is a finite f32, their product over the chain is not a finite f64.
    let mut f = Fixture::square();
    f.json["nodes"][0]["scale"] = json!([3e38, 3e38, 3e38]);
    for n in 3..12 {
        f.json["nodes"][n - 1]["children"] = json!([n]);
        f.json["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!({"name": format!("n{n}"), "scale": [3e38, 3e38, 3e38]}));
    }
    f.json["nodes"][2]["children"] = json!([3]);
    f.json["scenes"][0]["nodes"] = json!([0, 2]);
    f.json["nodes"][2].as_object_mut().unwrap().remove("mesh");
    f.json["nodes"][2].as_object_mut().unwrap().remove("skin");
    f.json["nodes"][11]["mesh"] = 0.into();
    f.json["nodes"][11]["skin"] = 0.into();
    f.json["skins"][0]["joints"] = json!([0, 11]);
    let rig = read(&f.glb()).unwrap();
    let config = FrameConfig { source: PoseSource::Random, frames: 1, ..FrameConfig::default() };
    refused(
        sample_frames(&rig, &config, Path::new("hostile.glb")),
        &[
            "hostile.glb: pose 'random000': joint 1 (node 11 'n11') moves 2 vertices",
            "overflows to a non-finite world matrix",
        ],
    );
}

#[test]
fn d10_posed_positions_beyond_f32_are_refused_naming_the_pose_and_vertex() {
    let mut f = Fixture::square();
    f.json["nodes"][0]["translation"] = json!([3e38, 0.0, 0.0]);
    f.json["nodes"][1]["translation"] = json!([3e38, 1.0, 0.0]);
    let rig = read(&f.glb()).unwrap();
    let config =
        FrameConfig { source: PoseSource::Random, frames: 1, max_degrees: 0.0, ..FrameConfig::default() };
    let frames = sample_frames(&rig, &config, Path::new("hostile.glb")).unwrap();
    // The driver adds the file; the error names the pose, the vertex and its joint.
    refused(
        pose_rig(&rig, &frames),
        &["pose 'random000': welded vertex", "beyond the range of f32", "joint 1 (node 1 'child')"],
    );
}

#[test]
fn d10_a_zero_scale_keyframe_on_a_skinning_joint_is_refused_when_posed() {
    let mut f = Fixture::square();
    f.retype(SCALES, f32_bytes(&[1., 1., 1., 0., 0., 0.]), FLOAT, false);
    // Valid glTF (engines hide things so): the file reads.
    let rig = read(&f.glb()).unwrap();
    let config = FrameConfig { frames: 3, ..FrameConfig::default() };
    refused(
        sample_frames(&rig, &config, Path::new("hostile.glb")),
        &[
            "hostile.glb: pose 'f002_wave@1.0000': joint 1 (node 1 'child') moves 2 vertices, but node 1 'child' has",
            "scale [0, 0, 0] here",
            "animation 'wave' scales it (keyframe 1: [0.0, 0.0, 0.0])",
        ],
    );
}

#[test]
fn d10_a_zero_scale_on_a_node_that_moves_no_vertex_is_accepted() {
    let mut f = Fixture::square();
    f.json["nodes"][2]["scale"] = json!([0.0, 0.0, 0.0]);
    let rig = read(&f.glb()).unwrap();
    let frames = sample_frames(&rig, &FrameConfig::default(), Path::new("hostile.glb")).unwrap();
    pose_rig(&rig, &frames).unwrap();
}

// D12: `extras` may be any JSON value.

#[test]
fn d12_extras_that_are_not_objects_are_accepted() {
    let plain = read(&Fixture::square().glb()).unwrap();
    let mut f = Fixture::square();
    f.json["extras"] = 5.into();
    f.json["nodes"][0]["extras"] = "a string".into();
    f.json["accessors"][POSITION]["extras"] = json!([1, 2, {"extras": 3}]);
    f.json["meshes"][0]["primitives"][0]["extras"] = Value::Null;
    f.json["animations"][0]["channels"][0]["target"]["extras"] = true.into();
    f.json["asset"]["extras"] = json!({"kept": "an object"});
    assert_eq!(read(&f.glb()).unwrap(), plain);
    assert_eq!(
        read_rig_from(Path::new("hostile.gltf"), &f.embedded(), &ReadOptions::default()).unwrap(),
        plain
    );
}

/// Application-specific attributes (`_BATCHID`: names starting with `_`) are valid glTF
/// and are ignored, as `extras` are, instead of refusing the file.
#[test]
fn d12_application_specific_attributes_are_accepted() {
    let plain = read(&Fixture::square().glb()).unwrap();
    let mut f = Fixture::square();
    f.json["meshes"][0]["primitives"][0]["attributes"]["_BATCHID"] = POSITION.into();
    f.json["meshes"][0]["primitives"][0]["attributes"]["_FOO"] = 9999.into();
    assert_eq!(read(&f.glb()).unwrap(), plain);
}

// D17: the rig file itself must be a regular file.

#[cfg(unix)]
fn mkfifo(path: &Path) {
    let status = std::process::Command::new("mkfifo").arg(path).status().unwrap();
    assert!(status.success());
}

#[cfg(unix)]
#[test]
fn d17_a_fifo_or_device_as_the_rig_file_is_refused_without_hanging() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("rig.glb");
    mkfifo(&fifo);
    let m = refused(read_rig(&fifo, &ReadOptions::default()), &["not a regular file"]);
    assert!(m.starts_with(&fifo.display().to_string()), "{m}");
    refused(read_rig(Path::new("/dev/zero"), &ReadOptions::default()), &["/dev/zero", "not a regular file"]);
    refused(read_rig(dir.path(), &ReadOptions::default()), &["not a regular file"]);
}

// D4: buffer URIs only reach regular files inside the glTF's folder.

/// A folder holding `rig.gltf` whose buffer URI is `uri`, and the buffer as `rig.bin`.
fn external(uri: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let f = Fixture::square();
    std::fs::write(dir.path().join("rig.bin"), &f.bin).unwrap();
    let gltf = dir.path().join("rig.gltf");
    std::fs::write(&gltf, f.external(uri)).unwrap();
    (dir, gltf)
}

fn read_file(path: &Path) -> Result<Rig, RigError> {
    read_rig(path, &ReadOptions::default())
}

#[test]
fn d4_a_buffer_beside_the_gltf_loads() {
    let (_dir, gltf) = external("rig.bin");
    assert_eq!(read_file(&gltf).unwrap(), read(&Fixture::square().glb()).unwrap());
}

/// Buffers whose declared lengths add up past desal's limit (one buffer file named
/// thousands of times) are refused before any is read.
#[test]
fn d2_buffers_declaring_more_than_the_limit_together_are_refused_before_reading() {
    let (dir, _) = external("rig.bin");
    let gltf = dir.path().join("many.gltf");
    let mut json: Value = serde_json::from_slice(&Fixture::square().external("rig.bin")).unwrap();
    let mut buffer = json["buffers"][0].clone();
    buffer["byteLength"] = (1u64 << 30).into();
    json["buffers"] = Value::Array(vec![json["buffers"][0].clone(), buffer.clone(), buffer.clone(), buffer]);
    std::fs::write(&gltf, serde_json::to_vec(&json).unwrap()).unwrap();
    refused(read_file(&gltf), &["buffer 2", "MAX_BUFFER_BYTES"]);
}

/// Channels sharing one large keyframe accessor are counted together, before any is
/// decoded: many animations over one sampler are refused, not decoded each time.
#[test]
fn d2_keyframes_past_the_limit_over_all_channels_are_refused_before_decoding() {
    let mut f = Fixture::square();
    let animation = f.json["animations"][0].clone();
    let input = animation["samplers"][0]["input"].as_u64().unwrap() as usize;
    // A declared count the view cannot hold would be refused as such; the total is
    // checked first, from the counts alone.
    f.json["accessors"][input]["count"] = (1u64 << 20).into();
    f.json["animations"] = Value::Array(vec![animation; 70]);
    refused_glb(&f, &["animations", "MAX_KEYFRAME_VALUES"]);
}

#[test]
fn d4_a_percent_encoded_buffer_uri_is_decoded() {
    let (dir, gltf) = external("my%20rig.bin");
    std::fs::rename(dir.path().join("rig.bin"), dir.path().join("my rig.bin")).unwrap();
    assert_eq!(read_file(&gltf).unwrap(), read(&Fixture::square().glb()).unwrap());
}

#[test]
fn d4_buffer_uri_outside_folder_is_refused() {
    let (dir, _) = external("rig.bin");
    let inner = dir.path().join("inner");
    std::fs::create_dir(&inner).unwrap();
    let gltf = inner.join("rig.gltf");
    std::fs::write(&gltf, Fixture::square().external("../rig.bin")).unwrap();
    let m = refused(read_file(&gltf), &["buffer 0", "'../rig.bin'", "outside"]);
    assert!(m.starts_with(&gltf.display().to_string()), "{m}");
}

#[test]
fn d4_an_absolute_buffer_uri_is_refused_even_to_a_valid_buffer() {
    let (dir, _) = external("rig.bin");
    let absolute = dir.path().join("rig.bin").display().to_string();
    let (_other, gltf) = external(&absolute);
    let m = refused(read_file(&gltf), &["buffer 0", &absolute, "absolute"]);
    assert!(m.starts_with(&gltf.display().to_string()), "{m}");
    let (_other, gltf) = external("/etc/passwd");
    refused(read_file(&gltf), &["buffer 0", "'/etc/passwd'", "absolute"]);
    let (_other, gltf) = external("file:///etc/passwd");
    refused(read_file(&gltf), &["buffer 0", "URL"]);
}

#[cfg(unix)]
#[test]
fn d4_a_symlink_out_of_the_folder_is_refused() {
    let outside = tempfile::tempdir().unwrap();
    std::fs::write(outside.path().join("secret.bin"), Fixture::square().bin).unwrap();
    let (dir, gltf) = external("link.bin");
    std::os::unix::fs::symlink(outside.path().join("secret.bin"), dir.path().join("link.bin")).unwrap();
    let m = refused(read_file(&gltf), &["buffer 0", "'link.bin'", "outside"]);
    assert!(m.starts_with(&gltf.display().to_string()), "{m}");
}

#[cfg(unix)]
#[test]
fn d4_dev_zero_and_a_fifo_as_buffers_are_refused_without_reading() {
    let (_dir, gltf) = external("/dev/zero");
    refused(read_file(&gltf), &["buffer 0", "'/dev/zero'"]);
    let (dir, gltf) = external("zero.bin");
    std::os::unix::fs::symlink("/dev/zero", dir.path().join("zero.bin")).unwrap();
    refused(read_file(&gltf), &["buffer 0", "'zero.bin'"]);
    let (dir, gltf) = external("pipe.bin");
    mkfifo(&dir.path().join("pipe.bin"));
    let m = refused(read_file(&gltf), &["buffer 0", "'pipe.bin'", "not a regular file"]);
    assert!(m.starts_with(&gltf.display().to_string()), "{m}");
}
