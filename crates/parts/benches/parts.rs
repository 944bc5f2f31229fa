//! Part discovery on SCAPE (71 poses × 12500 vertices): with K = 16 given, and with K
//! chosen at the knee (discovery runs up to `max_parts` = 24). The budget is
//! 2 s. Skips with a printed reason when `../shared/datasets/scape` is absent.
//!
//! Run: `cargo bench -p desal-parts --bench parts`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use desal_parts::{PartsConfig, discover_parts};

fn scape(c: &mut Criterion) {
    let Some((poses, _)) = desal_testdata::scape() else { return };
    let mut group = c.benchmark_group("SCAPE parts");
    group.sample_size(10);
    let given = PartsConfig { parts: Some(16), ..PartsConfig::default() };
    group.bench_function("K = 16", |b| b.iter(|| discover_parts(black_box(&poses), &given).unwrap()));
    let knee = PartsConfig::default();
    group.bench_function("K at the knee", |b| b.iter(|| discover_parts(black_box(&poses), &knee).unwrap()));
    group.finish();
}

criterion_group!(benches, scape);
criterion_main!(benches);
