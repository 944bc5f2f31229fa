//! Times the sampler: `cargo run --release -p desal-bodymodel --example sample_timing --
//! [MODEL.npz|MODEL.pkl] [SAMPLES]`. Without a model, the CC0 fixture is built from
//! `data-samples/source`. Prints the time to read, and per sample (one shape per 8 poses,
//! as the default configuration streams them).

use std::path::PathBuf;
use std::time::Instant;

use desal_bodymodel::{BodyModel, SampleConfig, Sampler};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let path = args.next().map(PathBuf::from);
    let samples: usize = args.next().map_or(Ok(256), |s| s.parse())?;
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
