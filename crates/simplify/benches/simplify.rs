//! Criterion benchmark of stage 3 (filled in by the simplifier work).
fn main() {}
