//! Structural mutations of glTF rigs, in both containers. Byte mutations of a `.gltf` or
//! `.glb` mostly break the JSON or the container, which the parser refuses at once; the
//! defects that matter sit behind a well-formed file whose numbers lie (issue 39: a
//! `byteStride` smaller than its element, a forbidden component type, a sparse count of
//! 2e9, a node chain 30 000 deep, a buffer `uri` outside the file's folder). So most
//! mutants here are parsed, edited as JSON (the numbers of accessors, buffer views,
//! sparse blocks, nodes and animation samplers, chosen by the name of the field) and
//! written back well formed, with the binary buffer edited too; the container's header
//! and chunk lengths are edited last, and a few mutants get byte mutations on top.

use rand::Rng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use serde_json::{Value, json};

use crate::corpus::rig::{COMPONENT_TYPES, base64, glb, split_glb, unbase64};

/// Numbers that break glTF's length, stride and index arithmetic: element sizes and
/// their neighbours, the spec's stride limits (4..=252), and counts past any real buffer.
const NUMBERS: [i64; 24] = [
    0,
    1,
    2,
    3,
    4,
    5,
    6,
    8,
    11,
    12,
    16,
    24,
    63,
    64,
    252,
    253,
    255,
    65535,
    65536,
    0x7fff_ffff,
    2_000_000_000,
    0xffff_ffff,
    1 << 32,
    -1,
];

const TYPES: [&str; 8] = ["SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4", "VEC5"];
const INTERPOLATIONS: [&str; 4] = ["LINEAR", "STEP", "CUBICSPLINE", "SPLINE"];
const CHANNEL_PATHS: [&str; 5] = ["translation", "rotation", "scale", "weights", "matrix"];
const ATTRIBUTES: [&str; 9] = [
    "POSITION",
    "NORMAL",
    "TEXCOORD_0",
    "JOINTS_0",
    "WEIGHTS_0",
    "JOINTS_1",
    "WEIGHTS_1",
    "TANGENT",
    "COLOR_0",
];
/// Buffer URIs a hostile file gives (issue 39 D4): devices, files outside the glTF's
/// folder, percent-encoding, and broken `data:` URIs. Reading them is harmless (nothing is
/// ever written); `/dev/zero` is read until the worker's memory limit stops it.
const URIS: [&str; 10] = [
    "/dev/zero",
    "/etc/passwd",
    "../../Cargo.toml",
    "%2e%2e/%2e%2e/Cargo.toml",
    "missing.bin",
    "file:///etc/passwd",
    "data:application/octet-stream;base64,",
    "data:application/octet-stream;base64,A",
    "data:,plain",
    "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAAAAAA==",
];
/// Fields whose numbers the reader trusts: three in four leaf edits pick one of these.
const KEY_FIELDS: [&str; 18] = [
    "count",
    "byteStride",
    "byteOffset",
    "byteLength",
    "componentType",
    "type",
    "bufferView",
    "buffer",
    "children",
    "input",
    "output",
    "interpolation",
    "joints",
    "inverseBindMatrices",
    "indices",
    "node",
    "sampler",
    "normalized",
];

/// A mutant of the `.gltf` `seed` (its buffers as `data:` URIs); `donor` is another seed.
pub fn mutate_gltf(rng: &mut ChaCha8Rng, seed: &[u8], donor: &[u8]) -> Vec<u8> {
    if rng.gen_bool(0.15) {
        return super::mutate(rng, seed, donor);
    }
    let Ok(mut document) = serde_json::from_slice::<Value>(seed) else {
        return super::mutate(rng, seed, donor);
    };
    edit_document(rng, &mut document);
    if rng.gen_bool(0.4) {
        edit_data_uri(rng, &mut document);
    }
    let bytes = serde_json::to_vec(&document).expect("a JSON value serialises");
    if rng.gen_bool(0.1) { super::mutate(rng, &bytes, donor) } else { bytes }
}

/// A mutant of the `.glb` `seed`: its JSON and BIN chunks edited and reassembled, then
/// perhaps its header and chunk lengths edited.
pub fn mutate_glb(rng: &mut ChaCha8Rng, seed: &[u8], donor: &[u8]) -> Vec<u8> {
    if rng.gen_bool(0.1) {
        return super::mutate(rng, seed, donor);
    }
    let Some((json, bin)) = split_glb(seed) else { return super::mutate(rng, seed, donor) };
    let Ok(mut document) = serde_json::from_slice::<Value>(json) else {
        return super::mutate(rng, seed, donor);
    };
    let mut bin = bin.to_vec();
    if rng.gen_bool(0.8) {
        edit_document(rng, &mut document);
    }
    if rng.gen_bool(0.4) {
        edit_binary(rng, &mut bin);
    }
    let mut json = serde_json::to_vec(&document).expect("a JSON value serialises");
    if rng.gen_bool(0.05) {
        json = super::mutate(rng, &json, b"");
    }
    let mut bytes = glb(&json, &bin);
    if rng.gen_bool(0.25) {
        edit_container(rng, &mut bytes);
    }
    if rng.gen_bool(0.05) { super::mutate(rng, &bytes, donor) } else { bytes }
}

/// One to three structural edits of a glTF document.
fn edit_document(rng: &mut ChaCha8Rng, document: &mut Value) {
    for _ in 0..rng.gen_range(1..=3) {
        match rng.gen_range(0..10) {
            0..=4 => edit_leaf(rng, document),
            5 => remove_field(rng, document),
            6 => add_field(rng, document),
            7 => edit_node_tree(rng, document),
            8 => edit_array(rng, document),
            _ => edit_uri(rng, document),
        }
    }
}

/// A JSON pointer to every value in `value`, with the key (or array index) it sits under.
fn pointers(value: &Value, at: &str, key: &str, out: &mut Vec<(String, String)>) {
    out.push((at.to_owned(), key.to_owned()));
    match value {
        Value::Object(map) => {
            for (k, v) in map {
                pointers(v, &format!("{at}/{}", k.replace('~', "~0").replace('/', "~1")), k, out);
            }
        }
        // The elements of an array of numbers share the array's key (`children`, `joints`,
        // `min`, `matrix`), so edits find them by it.
        Value::Array(items) => {
            for (i, v) in items.iter().enumerate() {
                let inner = if v.is_number() { key.to_owned() } else { i.to_string() };
                pointers(v, &format!("{at}/{i}"), &inner, out);
            }
        }
        _ => {}
    }
}

/// A pointer into `document`, three times in four to a field the reader trusts; the
/// base64 buffers are never picked (their text is edited by [`edit_data_uri`]).
fn pick(rng: &mut ChaCha8Rng, document: &Value, leaves_only: bool) -> Option<(String, String)> {
    let mut all = Vec::new();
    pointers(document, "", "", &mut all);
    all.retain(|(at, key)| {
        key != "uri"
            && !at.is_empty()
            && (!leaves_only || !document.pointer(at).is_some_and(|v| v.is_object() || v.is_array()))
    });
    let key_fields: Vec<&(String, String)> =
        all.iter().filter(|(_, k)| KEY_FIELDS.contains(&k.as_str())).collect();
    if !key_fields.is_empty() && rng.gen_bool(0.75) {
        return key_fields.choose(rng).map(|&p| p.clone());
    }
    all.choose(rng).cloned()
}

/// Fields that index a top-level array, and that array: most edits of them point at
/// another element that exists, which passes the parser's index checks and reaches the
/// reader with data of the wrong shape (an index buffer as inverse bind matrices).
const INDEX_FIELDS: [(&str, &str); 17] = [
    ("bufferView", "bufferViews"),
    ("buffer", "buffers"),
    ("input", "accessors"),
    ("output", "accessors"),
    ("indices", "accessors"),
    ("inverseBindMatrices", "accessors"),
    ("POSITION", "accessors"),
    ("NORMAL", "accessors"),
    ("TEXCOORD_0", "accessors"),
    ("JOINTS_0", "accessors"),
    ("WEIGHTS_0", "accessors"),
    ("node", "nodes"),
    ("children", "nodes"),
    ("joints", "nodes"),
    ("skeleton", "nodes"),
    ("mesh", "meshes"),
    ("skin", "skins"),
];

/// Optional fields: what [`remove_field`] removes most of the time (removing a required
/// one only tests the parser's first check).
const OPTIONAL_FIELDS: [&str; 17] = [
    "byteStride",
    "byteOffset",
    "bufferView",
    "sparse",
    "min",
    "max",
    "normalized",
    "children",
    "indices",
    "NORMAL",
    "TEXCOORD_0",
    "inverseBindMatrices",
    "skeleton",
    "translation",
    "rotation",
    "scale",
    "target",
];

/// Replaces one value with one that its key makes interesting.
fn edit_leaf(rng: &mut ChaCha8Rng, document: &mut Value) {
    let Some((at, key)) = pick(rng, document, true) else { return };
    let elements = INDEX_FIELDS
        .iter()
        .find(|(field, _)| *field == key)
        .and_then(|(_, array)| document[*array].as_array())
        .map_or(0, Vec::len);
    let new = match key.as_str() {
        _ if elements > 0 && rng.gen_bool(0.6) => json!(rng.gen_range(0..elements)),
        "componentType" => json!(*COMPONENT_TYPES.choose(rng).expect("non-empty")),
        "type" => json!(*TYPES.choose(rng).expect("non-empty")),
        "interpolation" => json!(*INTERPOLATIONS.choose(rng).expect("non-empty")),
        "path" => json!(*CHANNEL_PATHS.choose(rng).expect("non-empty")),
        "normalized" => json!(rng.gen_bool(0.5)),
        "mode" => json!(rng.gen_range(0..8)),
        _ => interesting_number(rng, document.pointer(&at)),
    };
    if let Some(slot) = document.pointer_mut(&at) {
        *slot = new;
    }
}

/// A number from [`NUMBERS`], the old value nudged, a non-integer, a huge float, or
/// (rarely) a value of another JSON type.
fn interesting_number(rng: &mut ChaCha8Rng, old: Option<&Value>) -> Value {
    let old = old.and_then(Value::as_f64).unwrap_or(0.0);
    match rng.gen_range(0..10) {
        0..=5 => json!(*NUMBERS.choose(rng).expect("non-empty")),
        6 => json!(old as i64 + rng.gen_range(-4..=4)),
        7 => json!((old * *[0.0, -1.0, 2.0, 1000.0, 1e9].choose(rng).expect("non-empty")) as i64),
        // Rarely a value the parser refuses outright: a fraction, a huge float, another type.
        8 if rng.gen_bool(0.5) => {
            json!(
                *[0.5, -0.0, 1e300, -1e300, f64::from(f32::MAX) * 2.0, 1e-40].choose(rng).expect("non-empty")
            )
        }
        8 => [json!(null), json!("1"), json!([]), json!({}), json!(true)]
            .choose(rng)
            .cloned()
            .expect("non-empty"),
        _ => json!(*NUMBERS.choose(rng).expect("non-empty")),
    }
}

/// Removes one field or array element (a missing `bufferView` makes an accessor read
/// zeros; a missing `byteStride` makes a view tightly packed).
fn remove_field(rng: &mut ChaCha8Rng, document: &mut Value) {
    let mut all = Vec::new();
    pointers(document, "", "", &mut all);
    let optional: Vec<String> = all
        .into_iter()
        .filter(|(at, key)| {
            OPTIONAL_FIELDS.contains(&key.as_str()) && !at.ends_with(|c: char| c.is_ascii_digit())
        })
        .map(|(at, _)| at)
        .collect();
    let at = match optional.choose(rng) {
        Some(at) if rng.gen_bool(0.8) => at.clone(),
        _ => match pick(rng, document, false) {
            Some((at, _)) => at,
            None => return,
        },
    };
    let (parent, last) = at.rsplit_once('/').expect("a pointer below the root");
    match document.pointer_mut(parent) {
        Some(Value::Object(map)) => {
            map.remove(&last.replace("~1", "/").replace("~0", "~"));
        }
        Some(Value::Array(items)) => {
            if let Ok(i) = last.parse::<usize>()
                && i < items.len()
            {
                items.remove(i);
            }
        }
        _ => {}
    }
}

/// Adds a field the seed lacks: a `byteStride`, a sparse block (with or without a buffer
/// view under the accessor), a `matrix` beside a node's TRS, an attribute, an `extras`
/// that is not an object, or a declared extension.
fn add_field(rng: &mut ChaCha8Rng, document: &mut Value) {
    let count = |document: &Value, key: &str| document[key].as_array().map_or(0, Vec::len);
    let (views, accessors, nodes) =
        (count(document, "bufferViews"), count(document, "accessors"), count(document, "nodes"));
    let number = |rng: &mut ChaCha8Rng| *NUMBERS.choose(rng).expect("non-empty");
    match rng.gen_range(0..7) {
        0 if views > 0 => {
            let v = rng.gen_range(0..views);
            document["bufferViews"][v]["byteStride"] = json!(number(rng));
        }
        1 if accessors > 0 && views > 0 => {
            let a = rng.gen_range(0..accessors);
            let sparse = json!({
                "count": number(rng),
                "indices": {"bufferView": rng.gen_range(0..views), "componentType": *[5121, 5123, 5125, 5126].choose(rng).expect("non-empty")},
                "values": {"bufferView": rng.gen_range(0..views)},
            });
            let accessor = &mut document["accessors"][a];
            accessor["sparse"] = sparse;
            if rng.gen_bool(0.5)
                && let Some(map) = accessor.as_object_mut()
            {
                map.remove("bufferView");
            }
        }
        2 if nodes > 0 => {
            let n = rng.gen_range(0..nodes);
            document["nodes"][n]["matrix"] =
                json!([0.0; 16].map(|_: f64| f64::from(rng.gen_range(-2i8..=2))));
        }
        3 if accessors > 0 => {
            if let Some(attributes) = document.pointer_mut("/meshes/0/primitives/0/attributes") {
                attributes[*ATTRIBUTES.choose(rng).expect("non-empty")] = json!(rng.gen_range(0..accessors));
            }
        }
        4 => {
            let Some((at, _)) = pick(rng, document, false) else { return };
            if let Some(Value::Object(map)) = document.pointer_mut(&at) {
                map.insert(
                    "extras".into(),
                    [json!(7), json!("text"), json!([1, 2]), json!(null)]
                        .choose(rng)
                        .cloned()
                        .expect("non-empty"),
                );
            }
        }
        5 => {
            let name = *["KHR_mesh_quantization", "KHR_texture_transform", "EXT_unknown"]
                .choose(rng)
                .expect("non-empty");
            for list in ["extensionsUsed", "extensionsRequired"] {
                if rng.gen_bool(0.6) {
                    match document[list].as_array_mut() {
                        Some(items) => items.push(json!(name)),
                        None => document[list] = json!([name]),
                    }
                }
            }
        }
        _ => {
            if let Some(animation) = document.pointer_mut("/animations/0")
                && let (Some(samplers), Some(channels)) =
                    (animation["samplers"].as_array(), animation["channels"].as_array())
            {
                // A channel targeting any node, through any sampler.
                let channel = json!({
                    "sampler": rng.gen_range(0..=samplers.len()),
                    "target": {"node": rng.gen_range(0..=nodes), "path": *CHANNEL_PATHS.choose(rng).expect("non-empty")},
                });
                let mut channels = channels.clone();
                channels.push(channel);
                animation["channels"] = Value::Array(channels);
            }
        }
    }
}

/// Edits the node tree: a cycle, a second parent, a child out of range, or a chain of new
/// nodes hung under a joint, as deep as 30 000 (issue 39 D3's stack overflow).
fn edit_node_tree(rng: &mut ChaCha8Rng, document: &mut Value) {
    let Some(nodes) = document["nodes"].as_array_mut() else { return };
    if nodes.is_empty() {
        return;
    }
    let n = nodes.len();
    let a = rng.gen_range(0..n);
    let child = match rng.gen_range(0..4) {
        0 => a,                       // a node its own child
        1 => rng.gen_range(0..n),     // perhaps a second parent, or a cycle
        2 => n + rng.gen_range(0..3), // out of range
        _ => {
            // Numbered root first or leaf first: a walk that memoises parents before
            // children only recurses deeply in the second order.
            let depth = *[2usize, 100, 1000, 30_000].choose(rng).expect("non-empty");
            let leaf_first = rng.gen_bool(0.5);
            for k in 0..depth {
                let children = match (leaf_first, k) {
                    (true, 0) => json!([]),
                    (true, _) => json!([n + k - 1]),
                    (false, _) if k + 1 < depth => json!([n + k + 1]),
                    (false, _) => json!([]),
                };
                nodes.push(json!({"children": children, "translation": [0.0, 0.001, 0.0]}));
            }
            if leaf_first { n + depth - 1 } else { n }
        }
    };
    match nodes[a]["children"].as_array_mut() {
        Some(children) => children.push(json!(child)),
        None => nodes[a]["children"] = json!([child]),
    }
}

/// Duplicates, drops or swaps whole elements of an array of objects (accessors, views,
/// primitives, samplers...), which renumbers what the indices point at.
fn edit_array(rng: &mut ChaCha8Rng, document: &mut Value) {
    let mut all = Vec::new();
    pointers(document, "", "", &mut all);
    let arrays: Vec<String> = all
        .into_iter()
        .map(|(at, _)| at)
        .filter(|at| document.pointer(at).and_then(Value::as_array).is_some_and(|a| !a.is_empty()))
        .collect();
    let Some(at) = arrays.choose(rng) else { return };
    let Some(Value::Array(items)) = document.pointer_mut(at) else { return };
    let i = rng.gen_range(0..items.len());
    match rng.gen_range(0..3) {
        0 => {
            let copy = items[i].clone();
            items.push(copy);
        }
        1 => {
            items.remove(i);
        }
        _ => {
            let j = rng.gen_range(0..items.len());
            items.swap(i, j);
        }
    }
}

/// Points a buffer at a hostile `uri` ([`URIS`]).
fn edit_uri(rng: &mut ChaCha8Rng, document: &mut Value) {
    let Some(buffers) = document["buffers"].as_array_mut() else { return };
    if let Some(buffer) = buffers.choose_mut(rng) {
        buffer["uri"] = json!(*URIS.choose(rng).expect("non-empty"));
    }
}

/// Decodes one `data:` URI buffer, edits its bytes, and encodes it again.
fn edit_data_uri(rng: &mut ChaCha8Rng, document: &mut Value) {
    let Some(buffers) = document["buffers"].as_array_mut() else { return };
    let Some(buffer) = buffers.choose_mut(rng) else { return };
    let Some((head, encoded)) = buffer["uri"].as_str().and_then(|u| u.split_once(";base64,")) else { return };
    let Some(mut bin) = unbase64(encoded) else { return };
    edit_binary(rng, &mut bin);
    buffer["uri"] = json!(format!("{head};base64,{}", base64(&bin)));
}

/// Writes values that break the data behind valid accessors: non-finite and huge
/// floats, out-of-range joint and index integers, at 4-byte aligned offsets mostly.
fn edit_binary(rng: &mut ChaCha8Rng, bin: &mut Vec<u8>) {
    if bin.is_empty() {
        return;
    }
    for _ in 0..rng.gen_range(1..=4) {
        let value: Vec<u8> = match rng.gen_range(0..4) {
            0 => [f32::NAN, f32::INFINITY, -f32::INFINITY, f32::MAX, -0.0, 1e-45, 1e20, -1.0, 2.0]
                .choose(rng)
                .expect("non-empty")
                .to_le_bytes()
                .to_vec(),
            1 => [0u32, 1, 2, 255, 256, 65535, 65536, u32::MAX]
                .choose(rng)
                .expect("non-empty")
                .to_le_bytes()
                .to_vec(),
            2 => [0u16, 255, 65535].choose(rng).expect("non-empty").to_le_bytes().to_vec(),
            _ => vec![rng.r#gen()],
        };
        let mut at = rng.gen_range(0..bin.len());
        if rng.gen_bool(0.7) {
            at -= at % 4;
        }
        let end = (at + value.len()).min(bin.len());
        bin[at..end].copy_from_slice(&value[..end - at]);
    }
    if rng.gen_bool(0.1) {
        bin.truncate(rng.gen_range(0..bin.len()));
    }
}

/// Edits the GLB header or a chunk header: magic, version, total length, a chunk's
/// length or type, or cuts the file.
fn edit_container(rng: &mut ChaCha8Rng, bytes: &mut Vec<u8>) {
    let json_len =
        bytes.get(12..16).map_or(0, |b| u32::from_le_bytes(b.try_into().expect("4 bytes")) as usize);
    let bin_header = 20 + json_len;
    let lie = |rng: &mut ChaCha8Rng, truth: usize| -> u32 {
        match rng.gen_range(0..4) {
            0 => (truth as u32).wrapping_add(rng.gen_range(1..=8)),
            1 => (truth as u32).wrapping_sub(rng.gen_range(1..=8)),
            2 => *[0, 1, 0x7fff_ffff, u32::MAX].choose(rng).expect("non-empty"),
            _ => (truth as u32).wrapping_mul(2),
        }
    };
    let put = |bytes: &mut Vec<u8>, at: usize, value: &[u8]| {
        if at + value.len() <= bytes.len() {
            bytes[at..at + value.len()].copy_from_slice(value);
        }
    };
    match rng.gen_range(0..7) {
        0 => put(bytes, 0, b"glTf"),
        1 => put(bytes, 4, &[1u32, 3, 0].choose(rng).expect("non-empty").to_le_bytes()),
        2 => {
            let total = bytes.len();
            put(bytes, 8, &lie(rng, total).to_le_bytes());
        }
        3 => put(bytes, 12, &lie(rng, json_len).to_le_bytes()),
        4 => {
            let bin_len = bytes.len().saturating_sub(bin_header + 8);
            put(bytes, bin_header, &lie(rng, bin_len).to_le_bytes());
        }
        5 => put(
            bytes,
            bin_header + 4,
            [b"JSON", b"BIN\x01", b"XYZW"].choose(rng).expect("non-empty").as_slice(),
        ),
        _ => {
            let cut = rng.gen_range(0..bytes.len().max(1));
            bytes.truncate(cut);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    use crate::corpus::rig::small_rig;

    /// The leaf edits reach the fields the reader trusts: over 2000 mutants of the small
    /// rig, each of these fields is changed at least once, so a defect behind any of
    /// them (issue 39 D1, D2, D9) is one the fuzzer can find.
    #[test]
    fn structural_edits_reach_the_accessor_and_view_fields() {
        let (document, bin) = small_rig();
        let seed = crate::corpus::rig::gltf_with_data_uri(&document, &bin);
        let original: Value = serde_json::from_slice(&seed).unwrap();
        let fields = [
            "/bufferViews/0/byteStride",
            "/accessors/0/count",
            "/accessors/0/byteOffset",
            "/accessors/0/componentType",
            "/accessors/0/type",
            "/accessors/0/sparse/count",
            "/accessors/2/sparse/count",
            "/nodes/0/children",
            "/animations/0/samplers/0/input",
            "/animations/0/samplers/0/output",
            "/animations/0/samplers/2/interpolation",
        ];
        let mut changed = vec![0; fields.len()];
        for k in 0..2000 {
            let mutant = mutate_gltf(&mut ChaCha8Rng::seed_from_u64(k), &seed, &seed);
            let Ok(mutant) = serde_json::from_slice::<Value>(&mutant) else { continue };
            for (f, field) in fields.iter().enumerate() {
                changed[f] += usize::from(mutant.pointer(field) != original.pointer(field));
            }
        }
        for (field, n) in fields.iter().zip(&changed) {
            assert!(*n > 0, "{field} was never changed: {changed:?}");
        }
    }

    /// Most GLB mutants keep a well-formed container with an edited JSON chunk.
    #[test]
    fn glb_mutants_stay_well_formed_mostly() {
        let (document, bin) = small_rig();
        let seed = glb(&serde_json::to_vec(&document).unwrap(), &bin);
        let well_formed = (0..400)
            .filter(|&k| {
                let mutant = mutate_glb(&mut ChaCha8Rng::seed_from_u64(k), &seed, &seed);
                split_glb(&mutant).is_some_and(|(json, _)| serde_json::from_slice::<Value>(json).is_ok())
                    && mutant != seed
            })
            .count();
        assert!(well_formed > 200, "only {well_formed} of 400 GLB mutants are well-formed edits");
    }
}
