//! The desal driver library: stage adapters, pipeline files, the artifact cache, batch
//! runs. The binaries in `src/bin` are thin wrappers over it.
