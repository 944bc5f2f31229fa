//! `desal-saliency`: stage 2 alone (deformation saliency), on artifacts. Same as
//! `desal saliency`.
use clap::Parser;

#[derive(Debug, Parser)]
#[command(name = "desal-saliency", version, about = "Stage 2: per-vertex deformation saliency from the fit")]
struct Cli {
    #[command(flatten)]
    args: desal_driver::commands::SaliencyArgs,
}

fn main() -> std::process::ExitCode {
    match desal_driver::commands::saliency(&Cli::parse().args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => desal_driver::report_error(&e),
    }
}
