//! Runs stages 1 and 2 on a directory of registered PLY poses (sorted by name, the first
//! one the template) with a label file, prints the timings, and writes the saliency heat
//! map as a PNG — the paper's Fig. 1. For looking at the result by eye; the real
//! pipeline writes `saliency.png` through the driver.
//!
//! `cargo run --release -p desal-saliency --example saliency_heatmap -- DIR LABELS OUT.png [PERCENTILE]`
//!
//! With `PERCENTILE` (e.g. 99), saliency is normalised by that percentile instead of
//! the maximum.

use std::path::{Path, PathBuf};
use std::time::Instant;

use desal_fit::{FitConfig, fit_pose_set};
use desal_mesh::{NoProgress, PoseSet};
use desal_saliency::{Normalisation, ResidualTable, SaliencyConfig, compute_saliency};
use desal_viz::{RenderConfig, Scalar, encode_png, render_heatmap};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (dir, labels, out, percentile) = match &args[..] {
        [dir, labels, out] => (dir, labels, out, None),
        [dir, labels, out, p] => (dir, labels, out, Some(p.parse::<f64>().expect("percentile"))),
        _ => {
            eprintln!("usage: saliency_heatmap POSE_DIR LABELS OUT.png [PERCENTILE]");
            std::process::exit(2);
        }
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("pose directory")
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "ply" || e == "obj"))
        .collect();
    files.sort();
    let meshes: Vec<_> = files.iter().map(|f| desal_io::read_mesh(f).expect("pose file")).collect();
    let names = files.iter().map(|f| f.file_stem().unwrap().to_string_lossy().into_owned()).collect();
    let faces = meshes[0].faces.clone();
    let poses = PoseSet::try_new(names, meshes.into_iter().map(|m| m.positions).collect(), faces, 0)
        .expect("registered poses");
    let labels = desal_io::labels::read_labels(Path::new(labels)).expect("label file");

    let start = Instant::now();
    let fit = fit_pose_set(&poses, &labels, &FitConfig::default(), &NoProgress).expect("fit");
    let fitted = start.elapsed();
    let table = ResidualTable {
        values: &fit.residuals,
        vertex_count: fit.vertex_count,
        pose_names: &fit.pose_names,
        template: Some(fit.template),
        length_scale: poses.template_mesh().diagonal(),
    };
    let normalisation = percentile.map_or(Normalisation::Max, Normalisation::Percentile);
    let config = SaliencyConfig { normalisation, ..SaliencyConfig::default() };
    let saliency = compute_saliency(&table, &config).expect("saliency");
    let total = start.elapsed();
    println!(
        "{} poses x {} vertices: fit {:.2} ms, saliency {:.2} ms",
        poses.pose_count(),
        poses.vertex_count(),
        fitted.as_secs_f64() * 1e3,
        (total - fitted).as_secs_f64() * 1e3
    );
    print!("{}", fit.summary.describe(5, 1.0, "units"));

    let config = RenderConfig {
        title: "deformation saliency".into(),
        units: "0-1".into(),
        range: Some((0.0, 1.0)),
        ..RenderConfig::default()
    };
    let image = render_heatmap(&poses.template_mesh(), Scalar::PerVertex(&saliency.saliency), &config)
        .expect("render");
    std::fs::write(out, encode_png(&image).expect("png")).expect("write png");
    println!("wrote {out}");
}
