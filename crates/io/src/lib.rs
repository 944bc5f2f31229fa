//! Every byte in or out of desal: PLY, OBJ, part labels, and the versioned artifact
//! envelope with its bincode codec.
//!
//! **Invariant:** this is the only crate that knows file formats, magic numbers and
//! format versions.
