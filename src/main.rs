//! `desal`: the driver binary.
fn main() {}
