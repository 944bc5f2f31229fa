//! desal's driver: pipeline files, the stage adapters and their chain, the
//! content-addressed artifact cache, batch runs, the output folder, and the in-memory
//! runs the Python package makes. The `desal` binary (the root package) is a thin front
//! end over it; `desal eval` (desal-experiment) builds on it.
//!
//! **Invariant:** this crate is the only place that knows paths, the cache and pipeline
//! files; the algorithm crates see data and config structs only. It links no terminal
//! UI and no C/C++: progress goes through [`progress::Console`], and the argument types
//! of the single-stage commands derive clap's traits only with the `cli` feature.
//!
//! Dependency order: `cache` ← `stages` ← {`outputs`, `pipeline`} ← `run`, with
//! `memory` (no cache) beside `run` and `commands` (one stage at a time) beside them; no
//! module imports a later one.

pub mod cache;
pub mod commands;
pub mod memory;
pub mod outputs;
pub mod pictures;
pub mod pipeline;
pub mod progress;
pub mod run;
pub mod stages;
pub mod viewer;

/// Writes `text` to standard output, the one way desal prints results. A closed pipe
/// (`desal inspect … | head`) ends the output quietly; any other failure (`> /dev/full`)
/// is an error naming standard output, never a panic (as `println!` would be).
pub fn print_out(text: &str) -> anyhow::Result<()> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(anyhow::anyhow!("cannot write to standard output: {e}"))
        }
        _ => Ok(()),
    }
}

/// Prints an error chain the way every desal binary does, and returns the exit code.
pub fn report_error(error: &anyhow::Error) -> std::process::ExitCode {
    eprintln!("error: {error}");
    for cause in error.chain().skip(1) {
        eprintln!("  caused by: {cause}");
    }
    std::process::ExitCode::from(1)
}
