//! `desal-map`: stage 4 alone (greedy mapping + apply to every pose), on artifacts or on
//! another tool's simplified mesh; with `--glb OUT.glb --rig IN.glb`, on a rig run's pose
//! set, it also writes the simplified rig. Same as `desal map`.
use clap::Parser;

#[derive(Debug, Parser)]
#[command(
    name = "desal-map",
    version,
    about = "Stage 4: map a simplified template to original vertices and apply it to every pose"
)]
struct Cli {
    #[command(flatten)]
    args: desal_driver::commands::MapArgs,
}

fn main() -> std::process::ExitCode {
    match desal_driver::commands::map(&Cli::parse().args) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => desal_driver::report_error(&e),
    }
}
