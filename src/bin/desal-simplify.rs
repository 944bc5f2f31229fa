//! `desal-simplify`: stage 3 alone on a plain mesh file (same as `desal simplify`). With
//! `--repeat R` it runs the simplification R times in-process and prints
//! `SIMPLIFY_SECONDS=<best>` (simplification alone, no I/O) for the peers' harness.
use clap::Parser;

#[derive(Debug, Parser)]
#[command(
    name = "desal-simplify",
    version,
    about = "Stage 3: quadric edge collapse with the deformation-saliency cost"
)]
struct Cli {
    #[command(flatten)]
    args: desal_driver::commands::SimplifyArgs,
}

fn main() -> std::process::ExitCode {
    match desal_driver::commands::simplify(&Cli::parse().args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => desal_driver::report_error(&e),
    }
}
