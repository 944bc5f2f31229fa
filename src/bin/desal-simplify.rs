//! `desal-simplify`: stage 3 alone on a plain mesh file. Arguments → config → one
//! `desal_simplify::simplify` call → the simplified mesh written atomically. With
//! `--repeat R` it runs the simplification R times in-process and prints
//! `SIMPLIFY_SECONDS=<best>` (simplification alone, no I/O) for the peers' harness.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::{ArgGroup, Parser, ValueEnum};
use desal_io::ply::{PlyWriteOptions, read_ply_full, write_ply};
use desal_simplify::{Placement, SimplifyConfig, SimplifyInput, Target, simplify};

#[derive(Debug, Parser)]
#[command(
    name = "desal-simplify",
    version,
    about = "Quadric edge collapse with the deformation-saliency cost"
)]
#[command(group(ArgGroup::new("target").required(true).args(["target_faces", "target_vertices", "ratio"])))]
struct Args {
    /// Input mesh (PLY or OBJ).
    #[arg(long)]
    input: PathBuf,
    /// Output mesh (PLY), written atomically.
    #[arg(long)]
    output: PathBuf,
    /// Stop at this many faces.
    #[arg(long)]
    target_faces: Option<usize>,
    /// Stop at this many vertices.
    #[arg(long)]
    target_vertices: Option<usize>,
    /// Keep this fraction of the faces, in (0, 1].
    #[arg(long)]
    ratio: Option<f64>,
    /// Per-vertex saliency weights: a PLY with a float vertex property `saliency`, or a
    /// text file with one number per line (`#` comments allowed). Enables the saliency
    /// factor of the cost.
    #[arg(long)]
    saliency: Option<PathBuf>,
    /// Where a collapsed edge's vertex goes.
    #[arg(long, value_enum, default_value_t = PlacementArg::Optimal)]
    placement: PlacementArg,
    /// Drop the edge-length ("balancing") factor of the cost, which is on when
    /// `--saliency` is given (the paper's method) and off otherwise (plain QSlim).
    #[arg(long)]
    no_balance: bool,
    /// Run the simplification this many times and print SIMPLIFY_SECONDS=<best>.
    #[arg(long)]
    repeat: Option<usize>,
}

#[derive(Debug, Clone, Copy, ValueEnum)]
enum PlacementArg {
    Optimal,
    Subset,
}

fn main() -> ExitCode {
    match run(Args::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: Args) -> Result<()> {
    let mesh =
        desal_io::read_mesh(&args.input).with_context(|| format!("reading {}", args.input.display()))?;
    let weights = match &args.saliency {
        Some(path) => {
            Some(read_weights(path).with_context(|| format!("reading saliency {}", path.display()))?)
        }
        None => None,
    };
    let target = match (args.target_faces, args.target_vertices, args.ratio) {
        (Some(n), _, _) => Target::Faces(n),
        (_, Some(n), _) => Target::Vertices(n),
        (_, _, Some(r)) => Target::Ratio(r),
        _ => bail!("give one of --target-faces, --target-vertices, --ratio"),
    };
    let config = SimplifyConfig {
        target,
        placement: match args.placement {
            PlacementArg::Optimal => Placement::Optimal,
            PlacementArg::Subset => Placement::Subset,
        },
        saliency: weights.is_some(),
        balance: weights.is_some() && !args.no_balance,
        ..SimplifyConfig::default()
    };
    let mut input = SimplifyInput::new(&mesh);
    if let Some(w) = &weights {
        input = input.with_weights(w);
    }

    let mut best = f64::INFINITY;
    let mut result = None;
    for _ in 0..args.repeat.unwrap_or(1).max(1) {
        let started = Instant::now();
        let simplified = simplify(&input, &config).context("simplifying")?;
        best = best.min(started.elapsed().as_secs_f64());
        result = Some(simplified);
    }
    let simplified = result.expect("at least one run");
    eprintln!("{}", simplified.report);
    write_ply(&args.output, &simplified.mesh, &PlyWriteOptions::default())
        .with_context(|| format!("writing {}", args.output.display()))?;
    if args.repeat.is_some() {
        println!("SIMPLIFY_SECONDS={best}");
    }
    Ok(())
}

/// Per-vertex weights from a PLY's `saliency` vertex property or a text file with one
/// number per line.
fn read_weights(path: &Path) -> Result<Vec<f64>> {
    let is_ply = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    if is_ply {
        let ply = read_ply_full(path)?;
        let (_, values) = ply
            .scalars
            .iter()
            .find(|(name, _)| name == "saliency")
            .context("the PLY has no float vertex property `saliency`")?;
        return Ok(values.iter().map(|&x| x as f64).collect());
    }
    let text = std::fs::read_to_string(path)?;
    text.lines()
        .enumerate()
        .map(|(i, line)| (i, line.trim()))
        .filter(|(_, line)| !line.is_empty() && !line.starts_with('#'))
        .map(|(i, line)| {
            line.parse::<f64>().with_context(|| format!("line {}: `{line}` is not a number", i + 1))
        })
        .collect()
}
