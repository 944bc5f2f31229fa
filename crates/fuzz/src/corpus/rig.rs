//! A tiny skinned glTF rig for the glTF targets' seeds, built by hand so that every field
//! the reader trusts is present to be mutated: an interleaved buffer view with a
//! `byteStride`, sparse accessors (one over a buffer view, one without any), `u8`, `u16`,
//! `i16` and `f32` components, normalised integers, two joints, and one animation with a
//! STEP, a LINEAR and a CUBICSPLINE sampler. Seven vertices (a seam: vertex 6 is vertex 2
//! with another UV), four triangles: an iteration takes microseconds.
//!
//! Names are in several scripts, with an emoji and a combining mark, because they become
//! part names (the labels) and reach the outputs and the viewer page.
//!
//! [`glb`] and [`gltf_with_data_uri`] put one (JSON, binary buffer) pair in either
//! container; [`split_glb`] takes a `.glb` apart again (the sample rig's seed for the
//! `.gltf` target, and the structure the GLB mutations edit).

use serde_json::{Value, json};

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const BYTE: u32 = 5120;
const UNSIGNED_BYTE: u32 = 5121;
const SHORT: u32 = 5122;
const UNSIGNED_SHORT: u32 = 5123;
const FLOAT: u32 = 5126;

/// The rig's glTF JSON (its one buffer without a `uri`) and that buffer's bytes.
pub fn small_rig() -> (Value, Vec<u8>) {
    let mut bin = Bin::default();
    // Vertices 0..6: a ladder of three rows up the y axis; vertex 5 is stored as the
    // origin and moved to its place by the sparse accessor; vertex 6 is a seam copy of 2.
    let positions: [[f32; 3]; 7] = [
        [-0.5, 0.0, 0.0],
        [0.5, 0.0, 0.0],
        [-0.5, 1.0, 0.0],
        [0.5, 1.0, 0.0],
        [-0.5, 2.0, 0.0],
        [0.0, 0.0, 0.0],
        [-0.5, 1.0, 0.0],
    ];
    let mut interleaved = Vec::new();
    for p in positions {
        interleaved.extend(floats(&p));
        interleaved.extend(floats(&[0.0, 0.0, 1.0]));
    }
    let vertices = bin.view(&interleaved, Some(24), Some(ARRAY_BUFFER));
    let joints = bin.view(
        &[0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0],
        Some(4),
        Some(ARRAY_BUFFER),
    );
    // u8 normalised: 255 is 1.0, 128 + 127 is 1.0 (the reader allows 1e-3).
    let weights = bin.view(
        &[
            255, 0, 0, 0, 255, 0, 0, 0, 128, 127, 0, 0, 128, 127, 0, 0, 255, 0, 0, 0, 255, 0, 0, 0, 128, 127,
            0, 0,
        ],
        Some(4),
        Some(ARRAY_BUFFER),
    );
    let indices: Vec<u8> =
        [0u16, 1, 3, 0, 3, 2, 6, 3, 5, 6, 5, 4].iter().flat_map(|i| i.to_le_bytes()).collect();
    let indices = bin.view(&indices, None, Some(ELEMENT_ARRAY_BUFFER));
    let mut inverse_bind = floats(&identity());
    let mut child = identity();
    child[13] = -1.0;
    inverse_bind.extend(floats(&child));
    let inverse_bind = bin.view(&inverse_bind, None, None);
    let sparse_position_index = bin.view(&[5], None, None);
    let sparse_position_value = bin.view(&floats(&[0.5, 2.0, 0.0]), None, None);
    let sparse_uv_index = bin.view(&[2, 4, 6], None, None);
    let uv: Vec<u8> = [0u16, 65535, 65535, 65535, 32768, 0].iter().flat_map(|x| x.to_le_bytes()).collect();
    let sparse_uv_value = bin.view(&uv, None, None);
    let times = bin.view(&floats(&[0.0, 0.5, 1.0]), None, None);
    let (s, c) = (15f32.to_radians().sin(), 15f32.to_radians().cos());
    let rotations = bin.view(&floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, s, c, 0.0, 0.0, 0.0, 1.0]), None, None);
    let steps = bin.view(&floats(&[0.0, 1.0, 0.0, 0.0, 1.1, 0.0, 0.0, 1.0, 0.0]), None, None);
    let mut cubic = Vec::new();
    for scale in [1.0, 1.2, 1.0] {
        cubic.extend([0.0; 3]); // in-tangent
        cubic.extend([scale; 3]);
        cubic.extend([0.0; 3]); // out-tangent
    }
    let cubic = bin.view(&floats(&cubic), None, None);
    let quarter = (i16::MAX as f32 * std::f32::consts::FRAC_1_SQRT_2) as i16;
    let short_rotations: Vec<u8> = [0i16, 0, 0, i16::MAX, 0, quarter, 0, quarter, 0, 0, 0, i16::MAX]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let short_rotations = bin.view(&short_rotations, None, None);

    let document = json!({
        "asset": {"version": "2.0", "generator": "desal-fuzz seed"},
        "extensionsUsed": [],
        "scene": 0,
        "scenes": [{"nodes": [0, 2]}],
        "nodes": [
            {"name": "Wurzel ルート", "children": [1]},
            {"name": "ребёнок-יד", "translation": [0.0, 1.0, 0.0]},
            {"name": "ボディ 🧍", "mesh": 0, "skin": 0},
        ],
        "skins": [{"name": "skin", "joints": [0, 1], "inverseBindMatrices": 6, "skeleton": 0}],
        "meshes": [{
            "name": "body",
            "primitives": [{
                "attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2, "JOINTS_0": 3, "WEIGHTS_0": 4},
                "indices": 5,
                "mode": 4,
            }],
        }],
        "accessors": [
            {
                "bufferView": vertices, "byteOffset": 0, "componentType": FLOAT, "count": 7, "type": "VEC3",
                "min": [-0.5, 0.0, 0.0], "max": [0.5, 2.0, 0.0],
                "sparse": {
                    "count": 1,
                    "indices": {"bufferView": sparse_position_index, "componentType": UNSIGNED_BYTE},
                    "values": {"bufferView": sparse_position_value},
                },
            },
            {"bufferView": vertices, "byteOffset": 12, "componentType": FLOAT, "count": 7, "type": "VEC3"},
            {
                "componentType": UNSIGNED_SHORT, "normalized": true, "count": 7, "type": "VEC2",
                "sparse": {
                    "count": 3,
                    "indices": {"bufferView": sparse_uv_index, "componentType": UNSIGNED_BYTE},
                    "values": {"bufferView": sparse_uv_value},
                },
            },
            {"bufferView": joints, "componentType": UNSIGNED_BYTE, "count": 7, "type": "VEC4"},
            {"bufferView": weights, "componentType": UNSIGNED_BYTE, "normalized": true, "count": 7, "type": "VEC4"},
            {"bufferView": indices, "componentType": UNSIGNED_SHORT, "count": 12, "type": "SCALAR"},
            {"bufferView": inverse_bind, "componentType": FLOAT, "count": 2, "type": "MAT4"},
            {"bufferView": times, "componentType": FLOAT, "count": 3, "type": "SCALAR", "min": [0.0], "max": [1.0]},
            {"bufferView": rotations, "componentType": FLOAT, "count": 3, "type": "VEC4"},
            {"bufferView": steps, "componentType": FLOAT, "count": 3, "type": "VEC3"},
            {"bufferView": cubic, "componentType": FLOAT, "count": 9, "type": "VEC3"},
            {"bufferView": short_rotations, "componentType": SHORT, "normalized": true, "count": 3, "type": "VEC4"},
        ],
        "bufferViews": bin.views,
        "buffers": [{"byteLength": bin.bytes.len()}],
        "animations": [{
            "name": "Wave 👋 موجة",
            "samplers": [
                {"input": 7, "output": 8, "interpolation": "LINEAR"},
                {"input": 7, "output": 9, "interpolation": "STEP"},
                {"input": 7, "output": 10, "interpolation": "CUBICSPLINE"},
                {"input": 7, "output": 11, "interpolation": "LINEAR"},
            ],
            "channels": [
                {"sampler": 0, "target": {"node": 1, "path": "rotation"}},
                {"sampler": 1, "target": {"node": 1, "path": "translation"}},
                {"sampler": 2, "target": {"node": 0, "path": "scale"}},
                {"sampler": 3, "target": {"node": 0, "path": "rotation"}},
            ],
        }],
    });
    (document, bin.bytes)
}

/// The glTF component types, for the mutations.
pub const COMPONENT_TYPES: [u32; 6] = [BYTE, UNSIGNED_BYTE, SHORT, UNSIGNED_SHORT, 5125, FLOAT];

/// The one buffer being built, and its buffer views (4-byte aligned).
#[derive(Default)]
struct Bin {
    bytes: Vec<u8>,
    views: Vec<Value>,
}

impl Bin {
    /// Appends `data` as a new buffer view and returns its index.
    fn view(&mut self, data: &[u8], stride: Option<u32>, target: Option<u32>) -> usize {
        let offset = self.bytes.len();
        self.bytes.extend_from_slice(data);
        self.bytes.resize(self.bytes.len().next_multiple_of(4), 0);
        let mut view = json!({"buffer": 0, "byteOffset": offset, "byteLength": data.len()});
        if let Some(stride) = stride {
            view["byteStride"] = stride.into();
        }
        if let Some(target) = target {
            view["target"] = target.into();
        }
        self.views.push(view);
        self.views.len() - 1
    }
}

fn floats(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn identity() -> [f32; 16] {
    let mut m = [0.0; 16];
    for i in 0..4 {
        m[i * 5] = 1.0;
    }
    m
}

/// `.glb` bytes: the 12-byte header, the JSON chunk (padded with spaces) and, when `bin`
/// is not empty, the BIN chunk (padded with zeros), as glTF 2.0 §4.4 lays them out.
pub fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let padded = |data: &[u8], fill: u8| {
        let mut v = data.to_vec();
        v.resize(v.len().next_multiple_of(4), fill);
        v
    };
    let json = padded(json, b' ');
    let bin = padded(bin, 0);
    let total = 12 + 8 + json.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
    }
    out
}

/// The JSON and BIN chunks of a well-formed `.glb` (`None` for anything else).
pub fn split_glb(bytes: &[u8]) -> Option<(&[u8], &[u8])> {
    let u32_at = |at: usize| Some(u32::from_le_bytes(bytes.get(at..at + 4)?.try_into().ok()?) as usize);
    if bytes.get(..4)? != b"glTF" {
        return None;
    }
    let json_len = u32_at(12)?;
    let json = bytes.get(20..20 + json_len)?;
    let bin = match u32_at(20 + json_len) {
        Some(bin_len) => bytes.get(28 + json_len..28 + json_len + bin_len)?,
        None => &[],
    };
    Some((json, bin))
}

/// `.gltf` bytes: `document` with its first buffer's bytes `bin` as a base64 `data:` URI.
pub fn gltf_with_data_uri(document: &Value, bin: &[u8]) -> Vec<u8> {
    let mut document = document.clone();
    if let Some(buffer) = document.pointer_mut("/buffers/0") {
        buffer["uri"] = format!("data:application/octet-stream;base64,{}", base64(bin)).into();
    }
    serde_json::to_vec(&document).expect("a JSON value serialises")
}

/// Standard base64 (RFC 4648, padded), as glTF writers write `data:` URIs.
pub fn base64(bytes: &[u8]) -> String {
    use base64::Engine;
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// The inverse of [`base64`] (padding optional); `None` on any other byte.
pub fn unbase64(text: &str) -> Option<Vec<u8>> {
    use base64::Engine;
    base64::engine::general_purpose::STANDARD_NO_PAD.decode(text.trim_end_matches('=')).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips_every_length() {
        let data: Vec<u8> = (0..=255).collect();
        for len in 0..10 {
            assert_eq!(unbase64(&base64(&data[..len])).unwrap(), &data[..len]);
        }
        assert_eq!(base64(b"hello"), "aGVsbG8=");
    }

    #[test]
    fn glb_splits_into_what_it_was_built_from() {
        let bytes = glb(b"{\"a\":1}", &[1, 2, 3]);
        assert_eq!(bytes.len() % 4, 0);
        let (json, bin) = split_glb(&bytes).unwrap();
        assert_eq!(json, b"{\"a\":1} ");
        assert_eq!(bin, [1, 2, 3, 0]);
    }
}
