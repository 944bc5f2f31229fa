//! Times the sampler: `cargo run --release -p desal-bodymodel --example sample_timing --
//! [MODEL.npz|MODEL.pkl|-] [SAMPLES] [VERTICES]`. Without a model (or `-`), the CC0
//! fixture is built from `data-samples/source`. `VERTICES` keeps only the model's first
//! vertices (a smaller model of the same kind, for timing at a given size). Prints the
//! time to read, and per sample (one shape per 8 poses, as the default configuration
//! streams them), single-threaded.

use std::path::PathBuf;
use std::time::Instant;

use desal_bodymodel::{BodyModel, SampleConfig, Sampler};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().filter(|a| a != "-").map(PathBuf::from);
    let samples: usize = args.next().map_or(Ok(256), |s| s.parse())?;
    let keep: Option<usize> = args.next().map(|s| s.parse()).transpose()?;
    let start = Instant::now();
    let model = match &path {
        Some(path) => BodyModel::read(path)?,
        None => {
            let assets = desal_sample::SourceAssets::load(&desal_sample::source::repository_source_dir())?;
            let npz = desal_sample::smpl_layout::smpl_layout_model(&assets)?.npz()?;
            BodyModel::from_npz_bytes(std::path::Path::new("fixture.npz"), &npz)?
        }
    };
    let read = start.elapsed();
    let model = match keep {
        Some(n) => first_vertices(model, n),
        None => model,
    };
    let poses = 8;
    let config = SampleConfig { shapes: samples.div_ceil(poses), poses, ..SampleConfig::default() };
    let start = Instant::now();
    let mut checksum = 0.0;
    let mut count = 0;
    for (_, vertices) in Sampler::new(&model, config)?.take(samples + 1) {
        checksum += vertices[0].x;
        count += 1;
    }
    let per = start.elapsed().as_secs_f64() / count as f64;
    println!(
        "{} model, {} vertices, {} joints: read in {:.2} s; {count} samples, {:.2} ms per sample (checksum {checksum:.6})",
        model.kind.name(),
        model.vertex_count(),
        model.joint_count(),
        read.as_secs_f64(),
        per * 1e3
    );
    Ok(())
}

/// `model` cut to its first `n` vertices: every per-vertex array's first rows, the faces
/// among them, the regressor's columns among them (not renormalised: for timing only).
fn first_vertices(mut model: BodyModel, n: usize) -> BodyModel {
    let n = n.min(model.vertex_count());
    model.v_template.truncate(n);
    model.faces.retain(|f| f.iter().all(|&v| (v as usize) < n));
    model.shapedirs.truncate(n * 3 * model.shape_count);
    model.exprdirs.truncate(n * 3 * model.expression_count);
    model.posedirs.truncate(n * 3 * model.pose_feature_count());
    let end = model.weights.offsets[n];
    model.weights.offsets.truncate(n + 1);
    model.weights.cols.truncate(end);
    model.weights.values.truncate(end);
    let mut regressor =
        desal_bodymodel::SparseRows { offsets: vec![0], cols: Vec::new(), values: Vec::new() };
    for j in 0..model.joint_count() {
        for (v, w) in model.joint_regressor.row(j).filter(|&(v, _)| v < n) {
            regressor.cols.push(v as u32);
            regressor.values.push(w);
        }
        regressor.offsets.push(regressor.values.len());
    }
    model.joint_regressor = regressor;
    model
}
