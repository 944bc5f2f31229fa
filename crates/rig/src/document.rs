//! A glTF file's bytes (`.glb` or `.gltf`) into the `gltf` crate's validated
//! [`gltf::Document`], with the JSON read once as a [`serde_json::Value`] and made fit
//! for the crate first:
//!
//! - **`extras`** may be any JSON value (glTF 2.0 §3.2 "extras"), but the crate, built
//!   without its `extras` feature, accepts only objects and would refuse the whole file;
//!   desal never reads `extras`, so every `extras` that is not an object is dropped.
//! - **Application-specific attributes** (`_BATCHID`, glTF 2.0 §3.7.2.1: names starting
//!   with `_`) are valid glTF, but the crate, without its `extras` feature, refuses the
//!   whole file for one; desal never reads them, so they are dropped from each primitive.
//! - **Extensions desal reads itself** ([`HANDLED_EXTENSIONS`]: `KHR_mesh_quantization`,
//!   whose integer attributes [`crate::accessor`] converts) are taken out of
//!   `extensionsRequired`, which the crate refuses for any extension it does not know.
//!
//! - **Compressed meshes** ([`COMPRESSION_EXTENSIONS`]: Draco, meshopt) are refused
//!   before anything else, with how to decompress the file first.
//!
//! - **Structure** ([`crate::structure`]): every reference between elements in range and
//!   every enumerated value valid, checked here, since the crate's validation misses
//!   some and panics on others.
//!
//! [`crate::read::read_rig_from`] catches any panic of the crate (none is expected).

use std::path::Path;

use serde_json::Value;

use crate::RigError;

/// The most bytes a file's buffers may hold together (the GLB chunk, `data:` URIs and
/// files beside it): 2 GiB, far above any avatar, and checked as each buffer is read, so
/// a small glTF naming one file thousands of times is refused instead of reading it each
/// time.
pub const MAX_BUFFER_BYTES: u64 = 1 << 31;

/// Extensions that desal implements, so a file may require them.
pub const HANDLED_EXTENSIONS: &[&str] = &["KHR_mesh_quantization"];

/// Mesh compression extensions: the data desal would read is in a form it does not
/// decode, so a file that declares one is refused, saying how to decompress it.
pub const COMPRESSION_EXTENSIONS: &[&str] =
    &["KHR_draco_mesh_compression", "EXT_meshopt_compression", "KHR_meshopt_compression"];

/// A parsed, validated glTF file.
pub struct Parsed {
    pub document: gltf::Document,
    /// The GLB binary chunk, if any.
    pub blob: Option<Vec<u8>>,
    /// The names in `extensionsUsed` and `extensionsRequired`.
    pub extensions: Vec<String>,
    /// The JSON as the file holds it, before anything above was dropped for the crate:
    /// what [`crate::edit`] writes back.
    pub original: Value,
}

/// Parses `bytes` (GLB or JSON glTF); `path` names the file in errors.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<Parsed, RigError> {
    let gltf_error = |cause: gltf::Error| RigError::Gltf { path: path.to_owned(), cause };
    let (json, blob) = if bytes.starts_with(b"glTF") {
        // The crate subtracts the header's 12 bytes from its length field unchecked.
        if let Some(length) = bytes.get(8..12).map(|l| u32::from_le_bytes([l[0], l[1], l[2], l[3]]))
            && length < 12
        {
            let error = gltf::binary::Error::Length { length, length_read: bytes.len() };
            return Err(gltf_error(gltf::Error::Binary(error)));
        }
        let glb = gltf::binary::Glb::from_slice(bytes).map_err(gltf_error)?;
        (glb.json.into_owned(), glb.bin.map(|b| b.into_owned()))
    } else {
        (bytes.to_vec(), None)
    };
    let mut value: Value =
        serde_json::from_slice(&json).map_err(|e| gltf_error(gltf::Error::Deserialize(e)))?;
    let extensions = declared_extensions(&value);
    if let Some(extension) = extensions.iter().find(|e| COMPRESSION_EXTENSIONS.contains(&e.as_str())) {
        return Err(RigError::Compressed { path: path.to_owned(), extension: extension.clone() });
    }
    let original = value.clone();
    drop_non_object_extras(&mut value);
    drop_application_attributes(&mut value);
    crate::structure::check(path, &value)?;
    if let Some(Value::Array(required)) = value.get_mut("extensionsRequired") {
        required.retain(|e| !e.as_str().is_some_and(|e| HANDLED_EXTENSIONS.contains(&e)));
    }
    let root: gltf::json::Root =
        serde_json::from_value(value).map_err(|e| gltf_error(gltf::Error::Deserialize(e)))?;
    let document = gltf::Document::from_json(root).map_err(gltf_error)?;
    Ok(Parsed { document, blob, extensions, original })
}

/// The extension names the file declares (`extensionsUsed` and `extensionsRequired`).
fn declared_extensions(value: &Value) -> Vec<String> {
    ["extensionsUsed", "extensionsRequired"]
        .iter()
        .filter_map(|key| value.get(key)?.as_array())
        .flatten()
        .filter_map(|e| e.as_str().map(str::to_owned))
        .collect()
}

/// Removes the application-specific attributes (names starting with `_`) of every mesh
/// primitive, and of its morph targets.
fn drop_application_attributes(value: &mut Value) {
    let Some(Value::Array(meshes)) = value.get_mut("meshes") else { return };
    let primitives = meshes.iter_mut().filter_map(|m| m.get_mut("primitives")?.as_array_mut()).flatten();
    for primitive in primitives {
        let Some(primitive) = primitive.as_object_mut() else { continue };
        if let Some(Value::Object(attributes)) = primitive.get_mut("attributes") {
            attributes.retain(|name, _| !name.starts_with('_'));
        }
        if let Some(Value::Array(targets)) = primitive.get_mut("targets") {
            for target in targets.iter_mut().filter_map(Value::as_object_mut) {
                target.retain(|name, _| !name.starts_with('_'));
            }
        }
    }
}

/// Removes every `extras` whose value is not an object, at any depth (not descending
/// into `extras` themselves: what lies inside is the application's, never parsed).
fn drop_non_object_extras(value: &mut Value) {
    // Iterative, so a deeply nested file cannot overflow the stack here (serde_json
    // already refuses nesting deeper than 128).
    let mut stack = vec![value];
    while let Some(v) = stack.pop() {
        match v {
            Value::Object(map) => {
                if map.get("extras").is_some_and(|e| !e.is_object()) {
                    map.remove("extras");
                }
                stack.extend(map.iter_mut().filter(|(k, _)| k.as_str() != "extras").map(|(_, v)| v));
            }
            Value::Array(items) => stack.extend(items.iter_mut()),
            _ => {}
        }
    }
}
