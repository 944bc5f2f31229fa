//! End-to-end tests of the real binaries: one test binary, one temp folder per test.

mod artifacts;
mod cache;
mod eval;
mod faults;
mod hierarchy;
mod hostile;
mod ingest;
mod model;
mod parts;
mod rig;
mod stages;
mod support;
mod tidy;
