//! Measurement driver for the peers' harness while the `desal-simplify` binary is not
//! wired into the root package: same flags (`--input --output --target-faces N
//! [--target-vertices N] [--ratio R] [--placement optimal|subset] [--metric quadric|lt]
//! [--repeat R]`, plus
//! `--max-rotation DEG --max-corner-normal DEG --max-distance K` for tuning), prints
//! the one-line report to stderr and `SIMPLIFY_SECONDS=<best>` (simplification alone).
//! Run: `cargo run --release -p desal-simplify --example simplify_file -- --input ...`.

use std::path::PathBuf;
use std::time::Instant;

use desal_io::ply::{PlyWriteOptions, write_ply};
use desal_simplify::{Metric, Placement, SimplifyConfig, SimplifyInput, Target, simplify};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |flag: &str| args.iter().position(|a| a == flag).and_then(|i| args.get(i + 1)).cloned();
    let input = PathBuf::from(value("--input").ok_or("--input is required")?);
    let output = PathBuf::from(value("--output").ok_or("--output is required")?);
    let target = if let Some(n) = value("--target-faces") {
        Target::Faces(n.parse()?)
    } else if let Some(n) = value("--target-vertices") {
        Target::Vertices(n.parse()?)
    } else {
        Target::Ratio(value("--ratio").ok_or("give a target")?.parse()?)
    };
    let placement = match value("--placement").as_deref() {
        Some("subset") => Placement::Subset,
        _ => Placement::Optimal,
    };
    let repeat: usize = value("--repeat").map_or(Ok(1), |r| r.parse())?;
    let mesh = desal_io::read_mesh(&input)?;
    let mut config = SimplifyConfig { placement, ..SimplifyConfig::qslim(target) };
    match value("--metric").as_deref() {
        None | Some("quadric") => {}
        Some("lt") => config.metric = Metric::LindstromTurk,
        Some(other) => return Err(format!("--metric {other}: use quadric or lt").into()),
    }
    if let Some(x) = value("--max-corner-normal") {
        config.max_corner_normal_deg = x.parse()?;
    }
    if let Some(x) = value("--max-rotation") {
        config.max_normal_rotation_deg = x.parse()?;
    }
    if let Some(x) = value("--max-distance") {
        config.max_placement_distance = x.parse()?;
    }
    let mut best = f64::INFINITY;
    let mut result = None;
    for _ in 0..repeat.max(1) {
        let started = Instant::now();
        let simplified = simplify(&SimplifyInput::new(&mesh), &config)?;
        best = best.min(started.elapsed().as_secs_f64());
        result = Some(simplified);
    }
    let simplified = result.expect("at least one run");
    eprintln!("{}  refusals {:?}", simplified.report, simplified.report.refusals);
    write_ply(&output, &simplified.mesh, &PlyWriteOptions::default())?;
    println!("SIMPLIFY_SECONDS={best}");
    Ok(())
}
