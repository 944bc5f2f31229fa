//! Writing a [`Rig`] as a binary glTF 2.0 file (`.glb`): one buffer in the GLB's binary
//! chunk, one tightly packed buffer view per accessor (4-byte aligned), `POSITION` with
//! its bounds, `NORMAL` and `TEXCOORD_0` when present, as many `JOINTS_n` (`u16`) /
//! `WEIGHTS_n` (`f32`) sets as the widest vertex needs, `u32` indices, the inverse bind
//! matrices and every animation channel (its own sampler, keyframe times with bounds).
//! The JSON is built with `serde_json` in a fixed key order and the container by the
//! `gltf` crate, so the same rig gives the same bytes.

use serde_json::{Value, json};

use crate::RigError;
use crate::model::{Interpolation, LocalTransform, Path, Rig};

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_SHORT: u32 = 5123;
const UNSIGNED_INT: u32 = 5125;

/// The `asset.generator` string of every file desal writes.
pub const GENERATOR: &str = "desal (desal-rig)";

/// The bytes of `rig` as a `.glb`.
pub fn write_glb(rig: &Rig) -> Result<Vec<u8>, RigError> {
    let mut out = Builder::default();
    let mesh = &rig.mesh;
    let n = mesh.vertex_count();
    let mut attributes = serde_json::Map::new();
    let (lo, hi) = bounds(&mesh.positions);
    let position = out.accessor(
        floats(mesh.positions.iter().flatten()),
        n,
        FLOAT,
        "VEC3",
        Some(ARRAY_BUFFER),
        Some((lo.to_vec(), hi.to_vec())),
    );
    attributes.insert("POSITION".into(), position.into());
    if let Some(normals) = &mesh.normals {
        let a = out.accessor(floats(normals.iter().flatten()), n, FLOAT, "VEC3", Some(ARRAY_BUFFER), None);
        attributes.insert("NORMAL".into(), a.into());
    }
    if let Some(uvs) = &mesh.uvs {
        let a = out.accessor(floats(uvs.iter().flatten()), n, FLOAT, "VEC2", Some(ARRAY_BUFFER), None);
        attributes.insert("TEXCOORD_0".into(), a.into());
    }
    let sets = mesh.influences.max_influences().div_ceil(4).max(1);
    for set in 0..sets {
        let mut joints = Vec::with_capacity(8 * n);
        let mut weights = Vec::with_capacity(16 * n);
        for v in 0..n {
            let row: Vec<(usize, f32)> = mesh.influences.of(v).skip(4 * set).take(4).collect();
            for slot in 0..4 {
                let (j, w) = row.get(slot).copied().unwrap_or((0, 0.0));
                joints.extend((j as u16).to_le_bytes());
                weights.extend(w.to_le_bytes());
            }
        }
        let j = out.accessor(joints, n, UNSIGNED_SHORT, "VEC4", Some(ARRAY_BUFFER), None);
        let w = out.accessor(weights, n, FLOAT, "VEC4", Some(ARRAY_BUFFER), None);
        attributes.insert(format!("JOINTS_{set}"), j.into());
        attributes.insert(format!("WEIGHTS_{set}"), w.into());
    }
    let indices: Vec<u8> = mesh.triangles.iter().flatten().flat_map(|i| i.to_le_bytes()).collect();
    let indices = out.accessor(
        indices,
        3 * mesh.triangles.len(),
        UNSIGNED_INT,
        "SCALAR",
        Some(ELEMENT_ARRAY_BUFFER),
        None,
    );
    let ibm = out.accessor(
        floats(rig.skin.inverse_bind.iter().flatten()),
        rig.skin.joints.len(),
        FLOAT,
        "MAT4",
        None,
        None,
    );

    let mut animations = Vec::new();
    for animation in &rig.animations {
        let mut samplers = Vec::new();
        let mut channels = Vec::new();
        for channel in &animation.channels {
            let (t0, t1) = (channel.times[0], *channel.times.last().expect("non-empty"));
            let input = out.accessor(
                floats(&channel.times),
                channel.times.len(),
                FLOAT,
                "SCALAR",
                None,
                Some((vec![t0], vec![t1])),
            );
            let per_key = if channel.interpolation == Interpolation::CubicSpline { 3 } else { 1 };
            let kind = if channel.width() == 4 { "VEC4" } else { "VEC3" };
            let output =
                out.accessor(floats(&channel.values), channel.times.len() * per_key, FLOAT, kind, None, None);
            let interpolation = match channel.interpolation {
                Interpolation::Step => "STEP",
                Interpolation::Linear => "LINEAR",
                Interpolation::CubicSpline => "CUBICSPLINE",
            };
            let path = match channel.path {
                Path::Translation => "translation",
                Path::Rotation => "rotation",
                Path::Scale => "scale",
            };
            channels.push(json!({"sampler": samplers.len(), "target": {"node": channel.node, "path": path}}));
            samplers.push(json!({"input": input, "interpolation": interpolation, "output": output}));
        }
        let mut a = json!({"channels": channels, "samplers": samplers});
        if let Some(name) = &animation.name {
            a["name"] = name.clone().into();
        }
        animations.push(a);
    }

    let nodes: Vec<Value> = rig
        .nodes
        .iter()
        .enumerate()
        .map(|(i, node)| {
            let mut v = serde_json::Map::new();
            if let Some(name) = &node.name {
                v.insert("name".into(), name.clone().into());
            }
            if !node.children.is_empty() {
                v.insert("children".into(), json!(node.children));
            }
            match node.transform {
                LocalTransform::Matrix(m) => {
                    v.insert("matrix".into(), json!(m));
                }
                LocalTransform::Trs { translation, rotation, scale } => {
                    if translation != [0.0; 3] {
                        v.insert("translation".into(), json!(translation));
                    }
                    if rotation != [0.0, 0.0, 0.0, 1.0] {
                        v.insert("rotation".into(), json!(rotation));
                    }
                    if scale != [1.0; 3] {
                        v.insert("scale".into(), json!(scale));
                    }
                }
            }
            if i == rig.mesh_node {
                v.insert("mesh".into(), 0.into());
                v.insert("skin".into(), 0.into());
            }
            Value::Object(v)
        })
        .collect();
    let mut skin = json!({"inverseBindMatrices": ibm, "joints": rig.skin.joints});
    if let Some(name) = &rig.skin.name {
        skin["name"] = name.clone().into();
    }
    if let Some(root) = rig.skin.skeleton {
        skin["skeleton"] = root.into();
    }
    let scenes: Vec<Value> = rig.scenes.iter().map(|roots| json!({"nodes": roots})).collect();
    let mut root = json!({
        "asset": {"version": "2.0", "generator": GENERATOR},
        "meshes": [{"name": mesh.name, "primitives": [{"attributes": attributes, "indices": indices}]}],
        "nodes": nodes,
        "skins": [skin],
    });
    if !scenes.is_empty() {
        root["scenes"] = scenes.into();
    }
    if let Some(scene) = rig.scene {
        root["scene"] = scene.into();
    }
    if !animations.is_empty() {
        root["animations"] = animations.into();
    }
    root["accessors"] = out.accessors.into();
    root["bufferViews"] = out.views.into();
    root["buffers"] = json!([{"byteLength": out.bin.len()}]);

    let json = serde_json::to_vec(&root).map_err(|e| RigError::Output(format!("JSON: {e}")))?;
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header { magic: *b"glTF", version: 2, length: 0 },
        json: json.into(),
        bin: Some(out.bin.into()),
    };
    glb.to_vec().map_err(|e| RigError::Output(format!("GLB container: {e}")))
}

/// The binary chunk and the accessor and buffer-view lists being built.
#[derive(Default)]
struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Builder {
    /// Appends `bytes` as a buffer view with one accessor over it; returns the accessor's index.
    fn accessor(
        &mut self,
        bytes: Vec<u8>,
        count: usize,
        component: u32,
        kind: &str,
        target: Option<u32>,
        bounds: Option<(Vec<f32>, Vec<f32>)>,
    ) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut view = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if let Some(target) = target {
            view["target"] = target.into();
        }
        self.bin.extend(bytes);
        self.views.push(view);
        let mut accessor = json!({"bufferView": self.views.len() - 1, "componentType": component, "count": count, "type": kind});
        if let Some((min, max)) = bounds {
            accessor["min"] = json!(min);
            accessor["max"] = json!(max);
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }
}

fn floats<'a>(values: impl IntoIterator<Item = &'a f32>) -> Vec<u8> {
    values.into_iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// The per-axis minimum and maximum of `points` (an accessor's `min` and `max`).
pub(crate) fn bounds(points: &[[f32; 3]]) -> ([f32; 3], [f32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in points {
        for i in 0..3 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    (lo, hi)
}
