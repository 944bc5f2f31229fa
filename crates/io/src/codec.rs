//! The one pair of functions through which every bincode payload passes.
//!
//! bincode is pinned to exactly 2.0.1: the 2.x line is final (the project ended
//! development; 3.0.0 is a deliberate compile error), so pinning guards against any
//! accidental change of the byte format. The configuration is `standard()`
//! (little-endian, variable-length integers) and must never change without a format
//! version bump of every artifact kind.
//!
//! **Decoding never trusts a length.** A string's length prefix makes bincode allocate
//! that many bytes before reading them, so a forged prefix (a checksum is no defence: it
//! can be recomputed) could ask for terabytes and abort the process. Every decode
//! therefore runs under a bincode byte limit derived from the payload's own length:
//! bincode charges each decoded value its in-memory size (a varint `u64` read from one
//! byte costs 8, a string its length) and fails with `LimitExceeded` past the limit, so
//! no allocation can exceed the limit. An honest payload costs at most
//! [`CLAIM_FACTOR`] bytes of budget per payload byte (the widest in-memory value per
//! encoded byte is an 8-byte integer read from a 1-byte varint), so the limit is the
//! smallest power of four at or above `CLAIM_FACTOR × len + MIN_BUDGET`: never refusing
//! an honest payload, never allocating more than 32× the payload (plus 256 bytes) for a
//! forged one. The limit is a const generic in bincode 2, so every rung is one more
//! instantiation of every artifact decoder: powers of four (17 rungs, 4 KiB to 16 TiB)
//! rather than of two halve that compile cost for a factor of 2 in the bound.
//! Sequences need no limit of their own: serde pre-allocates at most 1 MiB per sequence
//! whatever its prefix claims, and growing past that needs real elements.
//! The format is unchanged by the limit (it is a decoder-side check only).

use serde::{Serialize, de::DeserializeOwned};

/// Upper bound of bincode's charge per encoded payload byte (see the module doc).
pub const CLAIM_FACTOR: usize = 8;
/// Budget added to every limit, so that tiny payloads get a little slack.
const MIN_BUDGET: usize = 64;

/// Encodes `value` to bytes.
pub fn encode<T: Serialize>(value: &T) -> Vec<u8> {
    bincode::serde::encode_to_vec(value, bincode::config::standard())
        .expect("serialising plain in-memory artifact structs cannot fail")
}

/// Encodes `value` into `writer`, the bytes [`encode`] gives; returns how many there were.
/// Bincode writes each field on its own, so `writer` should buffer.
pub fn encode_into<T: Serialize>(value: &T, writer: &mut impl std::io::Write) -> std::io::Result<usize> {
    bincode::serde::encode_into_std_write(value, writer, bincode::config::standard()).map_err(|e| match e {
        bincode::error::EncodeError::Io { inner, .. } => inner,
        other => panic!("serialising plain in-memory artifact structs cannot fail: {other}"),
    })
}

/// Decodes a `T` from the start of `bytes`; returns it with the number of bytes used.
/// Allocations are bounded by a limit derived from `bytes.len()` (see the module doc).
pub fn decode_prefix<T: DeserializeOwned>(bytes: &[u8]) -> Result<(T, usize), String> {
    let budget = bytes.len().saturating_mul(CLAIM_FACTOR).saturating_add(MIN_BUDGET);
    // log2 of the smallest power of four >= budget, at least 4 KiB.
    let rung = budget.checked_next_power_of_two().map_or(u32::MAX, usize::trailing_zeros).max(12);
    let rung = rung.saturating_add(rung % 2);
    macro_rules! decode_at_rung {
        ($($k:literal)*) => {
            match rung {
                $($k => decode_limited::<T, { 1usize << $k }>(bytes),)*
                _ => Err(format!("a {}-byte payload is too large to decode", bytes.len())),
            }
        };
    }
    decode_at_rung!(12 14 16 18 20 22 24 26 28 30 32 34 36 38 40 42 44)
}

/// Decodes exactly one `T` from `bytes`; trailing bytes are an error.
pub fn decode<T: DeserializeOwned>(bytes: &[u8]) -> Result<T, String> {
    let (value, used) = decode_prefix(bytes)?;
    if used != bytes.len() {
        return Err(format!("{} trailing bytes after the payload", bytes.len() - used));
    }
    Ok(value)
}

fn decode_limited<T: DeserializeOwned, const LIMIT: usize>(bytes: &[u8]) -> Result<(T, usize), String> {
    let config = bincode::config::standard().with_limit::<LIMIT>();
    bincode::serde::decode_from_slice(bytes, config).map_err(|e| match e {
        bincode::error::DecodeError::LimitExceeded => format!(
            "a length field claims more data than the {}-byte payload can hold (forged or corrupt)",
            bytes.len()
        ),
        bincode::error::DecodeError::UnexpectedEnd { .. } => {
            "the payload ends inside a value: a length field claims more items than it holds".to_owned()
        }
        other => other.to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A string whose length prefix claims 2^41 bytes (the attack that aborted with a 2 TB
    /// allocation) is refused by the limit before anything is allocated.
    #[test]
    fn a_forged_string_length_is_refused_not_allocated() {
        let mut bytes = vec![253u8]; // varint marker: a u64 follows
        bytes.extend_from_slice(&(1u64 << 41).to_le_bytes());
        bytes.extend_from_slice(b"abc");
        let err = decode::<String>(&bytes).unwrap_err();
        assert!(err.contains("claims more data"), "{err}");
    }

    /// A prefix just past the real bytes fails as "ends inside a value", not as a limit.
    #[test]
    fn a_string_one_byte_short_ends_early() {
        let bytes = [4u8, b'a', b'b', b'c'];
        let err = decode::<String>(&bytes).unwrap_err();
        assert!(err.contains("ends inside a value"), "{err}");
    }

    /// The densest honest payload (small varints, each charged 8 bytes) still decodes.
    #[test]
    fn honest_dense_payloads_decode_under_the_limit() {
        let values: Vec<u64> = vec![1; 100_000];
        let bytes = encode(&values);
        assert_eq!(decode::<Vec<u64>>(&bytes).unwrap(), values);
        let names: Vec<String> = (0..5000).map(|k| format!("n{k}")).collect();
        assert_eq!(decode::<Vec<String>>(&encode(&names)).unwrap(), names);
    }
}
