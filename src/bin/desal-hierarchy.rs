//! `desal-hierarchy`: the hierarchy stage alone (coarse levels with D, U, A per level,
//! written as `hierarchy.npz`) on a pose-set and a labels artifact. Same as `desal hierarchy`.
use clap::Parser;

#[derive(Debug, Parser)]
#[command(
    name = "desal-hierarchy",
    version,
    about = "Coarse levels for mesh networks: selection, upsampler and adjacency per level, as hierarchy.npz"
)]
struct Cli {
    #[command(flatten)]
    args: desal_driver::commands::HierarchyArgs,
}

fn main() -> std::process::ExitCode {
    match desal_driver::commands::hierarchy(&Cli::parse().args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => desal_driver::report_error(&e),
    }
}
