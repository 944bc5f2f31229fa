//! `desal-eval`: the paper's experiment and the method comparison (`desal eval`).
use clap::Parser;

#[derive(Debug, Parser)]
#[command(
    name = "desal-eval",
    version,
    about = "Simplify with each method, fit the SCAPE deformation model on the simplified poses, and measure v2f/v2v"
)]
struct Cli {
    #[command(flatten)]
    args: desal::evaluate::EvalArgs,
}

fn main() -> std::process::ExitCode {
    match desal::evaluate::eval(&Cli::parse().args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => desal::report_error(&e),
    }
}
