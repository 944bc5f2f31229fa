//! `desal-make-sample`: regenerates the bundled sample (`data-samples/`) from the CC0
//! MakeHuman assets in its `source/` folder.
//!
//! Usage: `desal-make-sample --out DIR [--source DIR] [--allow-unclean]`. The source
//! defaults to this repository's `data-samples/source`. `--allow-unclean` writes poses
//! even when they have inverted faces or self-intersections (for tuning the pose table).

use std::path::PathBuf;
use std::process::ExitCode;

use desal_sample::{SampleConfig, SampleReport, SourceAssets, generate, standard_poses, write_sample};

const USAGE: &str = "usage: desal-make-sample --out DIR [--source DIR] [--allow-unclean]";

struct Args {
    out: PathBuf,
    source: PathBuf,
    allow_unclean: bool,
}

fn parse_args() -> Result<Args, String> {
    let mut out = None;
    let mut source = None;
    let mut allow_unclean = false;
    let mut args = std::env::args_os().skip(1);
    while let Some(arg) = args.next() {
        let slot = match arg.to_str() {
            Some("--out") => &mut out,
            Some("--source") => &mut source,
            Some("--allow-unclean") => {
                allow_unclean = true;
                continue;
            }
            Some("-h" | "--help") => return Err(USAGE.to_owned()),
            _ => return Err(format!("unexpected argument {arg:?}\n{USAGE}")),
        };
        *slot = Some(PathBuf::from(args.next().ok_or_else(|| format!("{arg:?} needs a value\n{USAGE}"))?));
    }
    Ok(Args {
        out: out.ok_or_else(|| format!("--out is required\n{USAGE}"))?,
        source: source.unwrap_or_else(desal_sample::source::repository_source_dir),
        allow_unclean,
    })
}

fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let assets = SourceAssets::load(&args.source)?;
    let config = SampleConfig { require_clean_poses: !args.allow_unclean, ..SampleConfig::default() };
    let sample = generate(&assets, &standard_poses(), &config)?;
    let written = write_sample(&args.out, &sample)?;
    print_report(&sample.report, &sample.labels.names);
    println!("wrote {} files under {}", written.len(), args.out.display());
    Ok(())
}

fn print_report(report: &SampleReport, part_names: &[String]) {
    println!(
        "body: {} vertices, {} triangles, {} bones; {} unweighted vertices bound to the root",
        report.vertex_count,
        report.face_count,
        report.bone_count,
        report.weights.unweighted_vertices.len()
    );
    println!("rest pose self-intersections (edge/triangle pairs): {}", report.rest_self_intersections);
    println!(
        "{:<16} {:>9} {:>9} {:>8} {:>6} {:>9} {:>9}",
        "pose", "min area", "max area", "inverted", "x-ing", "shift m", "max d m"
    );
    for p in &report.poses {
        println!(
            "{:<16} {:>9.3} {:>9.3} {:>8} {:>6} {:>9.4} {:>9.4}",
            p.name,
            p.quality.min_area_ratio,
            p.quality.max_area_ratio,
            p.quality.inverted_faces,
            p.quality.self_intersections,
            p.ground_shift,
            p.max_displacement
        );
    }
    println!("parts ({} vertices relabelled from stray islands):", report.relabelled_vertices);
    println!("{:>3} {:<14} {:>8} {:>6}", "id", "part", "vertices", "pieces");
    for (id, name) in part_names.iter().enumerate() {
        println!("{id:>3} {name:<14} {:>8} {:>6}", report.part_vertices[id], report.part_pieces[id]);
    }
}

fn main() -> ExitCode {
    let args = match parse_args() {
        Ok(args) => args,
        Err(message) => {
            eprintln!("{message}");
            return ExitCode::from(2);
        }
    };
    match run(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprint!("error: {error}");
            let mut source = error.source();
            while let Some(cause) = source {
                eprint!(": {cause}");
                source = cause.source();
            }
            eprintln!();
            ExitCode::FAILURE
        }
    }
}
