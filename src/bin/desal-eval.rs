//! `desal-eval`: the paper's experiment and the method comparison (`desal eval`).
use clap::Parser;

#[path = "../bars.rs"]
mod bars;

#[derive(Debug, Parser)]
#[command(
    name = "desal-eval",
    version,
    about = "Simplify with each method, fit the SCAPE deformation model on the simplified poses, and measure v2f/v2v"
)]
struct Cli {
    #[command(flatten)]
    args: desal_experiment::EvalArgs,
}

fn main() -> std::process::ExitCode {
    let args = Cli::parse().args;
    match desal_experiment::eval(&args, bars::console(args.quiet)) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => desal_driver::report_error(&e),
    }
}
