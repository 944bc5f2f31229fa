//! Benchmarks of the deformation model and the metrics on SCAPE at full resolution
//! (71 poses × 12500 vertices): model fit, synthesis of one pose and of all poses, v2f
//! and v2v of one pair. Skipped with a message when SCAPE is absent.
//!
//! Run: `cargo bench -p desal-eval --bench eval`.

#[path = "../tests/common/mod.rs"]
mod common;

use criterion::Criterion;
use desal_eval::{ModelConfig, fit_model, v2f, v2v};
use desal_mesh::{Mat3, PartLabels, PoseSet, Vec3};

struct Scape {
    poses: PoseSet,
    labels: PartLabels,
    rotations: Vec<Vec<Mat3>>,
    centroids: Vec<Vec3>,
}

fn bench_model(c: &mut Criterion, s: &Scape) {
    let all: Vec<usize> = (0..s.poses.pose_count()).collect();
    let config = ModelConfig::default();
    let mut group = c.benchmark_group("scape_12500");
    group.sample_size(10);
    group.bench_function("fit_model_71_poses", |b| {
        b.iter(|| fit_model(&s.poses, &s.labels, &s.rotations, &all, &config).unwrap())
    });
    let model = fit_model(&s.poses, &s.labels, &s.rotations, &all, &config).unwrap();
    group.bench_function("synthesize_one_pose", |b| {
        b.iter(|| model.synthesize(&s.rotations[1], s.centroids[1]).unwrap())
    });
    group.bench_function("synthesize_71_poses", |b| {
        b.iter(|| model.synthesize_many(&s.rotations, &s.centroids).unwrap())
    });
    let (deformed, target) = (s.poses.pose_mesh(1), s.poses.pose_mesh(2));
    group.bench_function("v2f_one_pair", |b| b.iter(|| v2f(&deformed, &target)));
    group.bench_function("v2v_one_pair", |b| b.iter(|| v2v(&deformed, &target)));
    group.finish();
}

fn main() {
    let Some(dir) = common::scape_dir() else { return };
    let (poses, labels) = common::load_scape(&dir);
    let rotations = common::part_rotations(&poses, &labels);
    let centroids = poses.poses.iter().map(|p| common::centroid(p)).collect();
    let scape = Scape { poses, labels, rotations, centroids };
    let mut c = Criterion::default().configure_from_args();
    bench_model(&mut c, &scape);
    c.final_summary();
}
