//! The artifact header's fixed numbers, in a module of their own so that `error.rs` can
//! quote them without importing the artifact module that imports it.

/// First eight bytes of every artifact.
pub const MAGIC: [u8; 8] = *b"DESALART";
/// Size of the fixed header before the payload.
pub const HEADER_LEN: usize = 56;
