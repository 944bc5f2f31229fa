//! Benchmarks of the driver on the 71 SCAPE poses: ingest from PLY, reloading the
//! ingested artifact, and the whole pipeline cold and warm. Skips (with a message) without ../shared/datasets.
//!
//! Run: `cargo bench --bench pipeline`.

use std::path::{Path, PathBuf};

use criterion::{Criterion, criterion_group, criterion_main};
use desal_driver::progress::Lines;
use desal_driver::run::RunOptions;
use desal_driver::stages::ingest;
use desal_io::artifact::{self, PoseSetV2, Producer};
use desal_mesh::NoProgress;

fn scape_files() -> Option<Vec<PathBuf>> {
    desal_testdata::scape_dir().map(|dir| desal_testdata::scape_files(&dir))
}

fn bench_ingest(c: &mut Criterion) {
    let Some(files) = scape_files() else { return };
    let mut group = c.benchmark_group("scape-71");
    group.sample_size(10);
    group.bench_function("ingest from PLY", |b| {
        b.iter(|| ingest::ingest_poses(&files, 0, false, &NoProgress).unwrap());
    });
    group.bench_function("hash pose files (cache key)", |b| {
        b.iter(|| ingest::hash_files(&files).unwrap());
    });
    let (set, _) = ingest::ingest_poses(&files, 0, false, &NoProgress).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("poses.dsa");
    let producer = Producer {
        stage: "ingest".into(),
        stage_version: 1,
        tool_version: "bench".into(),
        parameters: "{}".into(),
        inputs: vec![],
    };
    artifact::write_artifact(&path, &producer, &PoseSetV2::from_pose_set(&set)).unwrap();
    group.bench_function("reload ingested artifact", |b| {
        b.iter(|| {
            let (_, body, _) = artifact::read_artifact::<PoseSetV2>(&path).unwrap();
            body.to_pose_set().unwrap()
        });
    });
    group.finish();
}

/// Stages 1 and 2 alone on the 71 SCAPE poses (the target: together well under
/// 100 ms on 2 cores).
fn bench_fit_and_saliency(c: &mut Criterion) {
    let Some(files) = scape_files() else { return };
    let (set, _) = ingest::ingest_poses(&files, 0, false, &NoProgress).unwrap();
    let labels_path = files[0].with_file_name("vertex_part_labels_16.txt");
    let labels = ingest::ingest_labels(&labels_path, &set).unwrap();
    let fit_params = desal_driver::stages::fit::FitParams::default();
    let saliency_params = desal_driver::stages::saliency::SaliencyParams::default();
    let diagonal = set.template_mesh().diagonal();
    let mut group = c.benchmark_group("scape-71");
    group.sample_size(20);
    group.bench_function("fit (stage 1)", |b| {
        b.iter(|| desal_driver::stages::fit::compute(&fit_params, &set, &labels, &NoProgress).unwrap());
    });
    let fit = desal_driver::stages::fit::compute(&fit_params, &set, &labels, &NoProgress).unwrap().body;
    group.bench_function("saliency (stage 2)", |b| {
        b.iter(|| desal_driver::stages::saliency::compute(&saliency_params, &fit, diagonal).unwrap());
    });
    group.finish();
}

/// The whole SCAPE pipeline (ingest → fit → saliency → simplify → map, outputs
/// written): cold (empty cache, every stage computed) and warm (all cache hits).
fn bench_full_pipeline(c: &mut Criterion) {
    if scape_files().is_none() {
        return;
    }
    let pipeline_file = Path::new(env!("CARGO_MANIFEST_DIR")).join("pipelines/scape.toml");
    let dir = tempfile::tempdir().unwrap();
    let pipeline = desal_driver::pipeline::load(&pipeline_file, Some(dir.path())).unwrap();
    let quiet = RunOptions { console: std::sync::Arc::new(Lines { quiet: true }), ..RunOptions::default() };
    let mut group = c.benchmark_group("scape-pipeline");
    group.sample_size(10);
    group.bench_function("cold (empty cache)", |b| {
        b.iter(|| {
            let _ = std::fs::remove_dir_all(dir.path());
            desal_driver::run::run(&pipeline, &quiet).unwrap()
        });
    });
    desal_driver::run::run(&pipeline, &quiet).unwrap();
    group.bench_function("warm (all hits)", |b| {
        b.iter(|| desal_driver::run::run(&pipeline, &quiet).unwrap());
    });
    group.finish();
}

criterion_group!(benches, bench_ingest, bench_fit_and_saliency, bench_full_pipeline);
criterion_main!(benches);
