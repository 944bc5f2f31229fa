//! Hierarchy speed on SCAPE, levels [2500, 625], fitted on all 71 poses (issue 13 asks
//! for < 1 s): the D/U/A matrices of both level steps alone (`matrices/…`), and the whole
//! hierarchy — the paper's stage 1–2 saliency, both subset simplifications, the pose
//! sets of each level and the matrices (`whole/…`). Skips without SCAPE.
//!
//! Run: `cargo bench -p desal-hierarchy --bench hierarchy`.

#[path = "../tests/common/mod.rs"]
mod common;

use std::hint::black_box;

use common::{Method, SaliencyPerLevel, build_geometry, build_levels};
use criterion::{Criterion, criterion_group, criterion_main};
use desal_hierarchy::Upsampler;

const LEVELS: [usize; 2] = [2500, 625];

fn scape(c: &mut Criterion) {
    let Some((full, labels)) = desal_testdata::scape() else { return };
    let all: Vec<usize> = (0..full.pose_count()).collect();
    let geometry = build_geometry(&full, &labels, &LEVELS, Method::Paper, SaliencyPerLevel::Recompute);
    let mut group = c.benchmark_group("scape [2500, 625]");
    group.sample_size(10);
    for up in [Upsampler::Barycentric, Upsampler::default()] {
        group.bench_function(format!("matrices/{}", up.name()), |b| {
            b.iter(|| build_levels(black_box(&full), black_box(&geometry), &all, &up))
        });
    }
    group.bench_function("whole/fitted", |b| {
        b.iter(|| {
            let geometry =
                build_geometry(&full, &labels, &LEVELS, Method::Paper, SaliencyPerLevel::Recompute);
            build_levels(&full, &geometry, &all, &Upsampler::default())
        })
    });
    group.finish();
}

criterion_group!(benches, scape);
criterion_main!(benches);
