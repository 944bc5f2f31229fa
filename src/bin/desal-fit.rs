//! `desal-fit`: stage 1 alone (per-part rigid fit), on artifacts. Same as `desal fit`.
use clap::Parser;

#[derive(Debug, Parser)]
#[command(name = "desal-fit", version, about = "Stage 1: per-part rigid fit of the template onto every pose")]
struct Cli {
    #[command(flatten)]
    args: desal_driver::commands::FitArgs,
}

fn main() -> std::process::ExitCode {
    match desal_driver::commands::fit(&Cli::parse().args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => desal_driver::report_error(&e),
    }
}
