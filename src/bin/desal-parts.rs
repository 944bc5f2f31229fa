//! `desal-parts`: near-rigid parts discovered from a pose-set artifact, written as a
//! labels artifact (what `labels = "auto"` runs). Same as `desal parts`.
use clap::Parser;

#[derive(Debug, Parser)]
#[command(
    name = "desal-parts",
    version,
    about = "Discover near-rigid body parts from a pose set (labels = \"auto\")"
)]
struct Cli {
    #[command(flatten)]
    args: desal_driver::commands::PartsArgs,
}

fn main() -> std::process::ExitCode {
    match desal_driver::commands::parts(&Cli::parse().args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => desal_driver::report_error(&e),
    }
}
