//! The desal driver library: pipeline files, ingest, stage adapters, the artifact cache,
//! batch runs and `inspect`. The binaries in `src/main.rs` and `src/bin/` are thin
//! wrappers over it.
//!
//! **Invariant:** this package is the only place that knows paths, the cache, the CLI and
//! progress bars; the stage crates see data and config structs only.

pub mod cache;
pub mod cli;
pub mod evaluate;
pub mod inspect;
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
