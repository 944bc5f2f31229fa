//! The planted bugs of the structural canaries ([`crate::Target::CanaryGltfStride`],
//! [`crate::Target::CanaryNpzShape`]): each looks at a mutant for the defect a real
//! reader once had and reports it, so a test can prove that the mutations produce such
//! inputs and the harness saves them, without depending on a reader still having it.

use serde_json::Value;

use crate::corpus::rig::split_glb;

/// The first accessor of a `.glb` whose buffer view declares a `byteStride` smaller
/// than the accessor's element (issue 39 D1): `(accessor, stride, element bytes)`.
pub fn short_stride(glb: &[u8]) -> Option<(usize, u64, u64)> {
    let (json, _) = split_glb(glb)?;
    let document: Value = serde_json::from_slice(json).ok()?;
    let accessors = document["accessors"].as_array()?;
    accessors.iter().enumerate().find_map(|(a, accessor)| {
        let view = &document["bufferViews"][usize::try_from(accessor["bufferView"].as_u64()?).ok()?];
        let stride = view["byteStride"].as_u64()?;
        let component = match accessor["componentType"].as_u64()? {
            5120 | 5121 => 1,
            5122 | 5123 => 2,
            5125 | 5126 => 4,
            _ => return None,
        };
        let components = match accessor["type"].as_str()? {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" | "MAT2" => 4,
            "MAT3" => 9,
            "MAT4" => 16,
            _ => return None,
        };
        let element = component * components;
        (stride < element).then_some((a, stride, element))
    })
}

/// The first `.npy` entry of an npz whose header's shape does not match its data's
/// length, for the dtypes desal writes: `(entry, shape text, data bytes)`.
pub fn shape_mismatch(npz: &[u8]) -> Option<(usize, String, usize)> {
    crate::mutate::npz::entries(npz)?.into_iter().enumerate().find_map(|(k, (_, npy))| {
        let header_len = usize::from(u16::from_le_bytes(npy.get(8..10)?.try_into().ok()?));
        let header = std::str::from_utf8(npy.get(10..10 + header_len)?).ok()?;
        let item = if header.contains("'<i4'") {
            4
        } else if header.contains("'<i8'") || header.contains("'<f8'") {
            8
        } else {
            return None;
        };
        let shape = &header[header.find("'shape': (")? + 9..];
        let shape = &shape[..=shape.find(')')?];
        let count = shape
            .trim_matches(|c| c == '(' || c == ')')
            .split(',')
            .map(str::trim)
            .filter(|d| !d.is_empty())
            .try_fold(1usize, |acc, d| acc.checked_mul(d.parse().ok()?))?;
        let len = npy.len() - 10 - header_len;
        (count.checked_mul(item) != Some(len)).then(|| (k, shape.to_owned(), len))
    })
}
