//! `desal-saliency`: stage 2 alone (deformation saliency), on artifacts. Same as
//! `desal saliency`.
use clap::Parser;

#[derive(Debug, Parser)]
#[command(name = "desal-saliency", version, about = "Stage 2: per-vertex deformation saliency from the fit")]
struct Cli {
    #[command(flatten)]
    args: desal::cli::SaliencyArgs,
}

fn main() -> std::process::ExitCode {
    match desal::cli::saliency(&Cli::parse().args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => desal::report_error(&e),
    }
}
