//! Stage-4 mapping speed: the fast greedy mapping against the brute-force reference on
//! 2500 perturbed points mapped onto 12500 random points, and on the SCAPE template
//! (every 5th vertex, perturbed by up to 5 mm) when `../shared/datasets/scape` exists.
//!
//! Run: `cargo bench -p desal-map --bench map`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use desal_map::{greedy_map, greedy_map_brute_force};
use desal_mesh::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Every 5th point, moved by up to `jitter` per axis: a stand-in for a 5:1
/// simplification with optimal placement.
fn decimate_and_perturb(original: &[Vec3], jitter: f64, seed: u64) -> Vec<Vec3> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    original
        .iter()
        .step_by(5)
        .map(|p| p + (Vec3::new(rng.r#gen(), rng.r#gen(), rng.r#gen()) * 2.0 - Vec3::repeat(1.0)) * jitter)
        .collect()
}

fn bench_pair(c: &mut Criterion, name: &str, simplified: &[Vec3], original: &[Vec3]) {
    assert_eq!(
        greedy_map(simplified, original).unwrap(),
        greedy_map_brute_force(simplified, original).unwrap(),
        "fast and brute force disagree on {name}"
    );
    let mut group = c.benchmark_group(name);
    group.sample_size(10);
    group.bench_function("fast", |b| {
        b.iter(|| greedy_map(black_box(simplified), black_box(original)).unwrap())
    });
    group.bench_function("brute_force", |b| {
        b.iter(|| greedy_map_brute_force(black_box(simplified), black_box(original)).unwrap())
    });
    group.finish();
}

fn random_points(c: &mut Criterion) {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let original: Vec<Vec3> = (0..12500).map(|_| Vec3::new(rng.r#gen(), rng.r#gen(), rng.r#gen())).collect();
    let simplified = decimate_and_perturb(&original, 0.01, 2);
    bench_pair(c, "random 2500 onto 12500", &simplified, &original);
}

fn scape_template(c: &mut Criterion) {
    // Skips with a printed reason on a clone without SCAPE (desal-testdata's policy).
    let Some(dir) = desal_testdata::scape_dir() else { return };
    let template = desal_io::read_mesh(&dir.join("mesh000.ply")).unwrap();
    let simplified = decimate_and_perturb(&template.positions, 0.005, 3);
    bench_pair(c, "SCAPE mesh000 2500 onto 12500", &simplified, &template.positions);
}

criterion_group!(benches, random_points, scape_template);
criterion_main!(benches);
