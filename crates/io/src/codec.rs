//! The one pair of functions through which every bincode payload passes.
//!
//! bincode is pinned to exactly 2.0.1: the 2.x line is final (the project ended
//! development; 3.0.0 is a deliberate compile error), so pinning guards against any
//! accidental change of the byte format. The configuration is `standard()`
//! (little-endian, variable-length integers) and must never change without a format
//! version bump of every artifact kind.

use serde::{Serialize, de::DeserializeOwned};

/// Encodes `value` to bytes.
pub fn encode<T: Serialize>(value: &T) -> Vec<u8> {
    bincode::serde::encode_to_vec(value, bincode::config::standard())
        .expect("serialising plain in-memory artifact structs cannot fail")
}

/// Decodes a `T` from the start of `bytes`; returns it with the number of bytes used.
pub fn decode_prefix<T: DeserializeOwned>(bytes: &[u8]) -> Result<(T, usize), String> {
    bincode::serde::decode_from_slice(bytes, bincode::config::standard()).map_err(|e| e.to_string())
}

/// Decodes exactly one `T` from `bytes`; trailing bytes are an error.
pub fn decode<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, String> {
    let (value, used) = decode_prefix(bytes)?;
    if used != bytes.len() {
        return Err(format!("{} trailing bytes after the payload", bytes.len() - used));
    }
    Ok(value)
}
