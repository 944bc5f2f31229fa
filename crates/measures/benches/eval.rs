//! Benchmarks of the deformation model and the metrics on SCAPE at full resolution
//! (71 poses × 12500 vertices): model fit, synthesis of one pose and of all poses, v2f
//! and v2v of a synthesised pose against its ground truth. The SCAPE part is skipped
//! with a message when SCAPE is absent; a 2500-vertex synthetic tube gives the cost at
//! the paper's simplified size.
//!
//! Run: `cargo bench -p desal-measures --bench eval`.

#[path = "../tests/common/mod.rs"]
mod common;

use criterion::Criterion;
use desal_measures::{ModelConfig, fit_model, v2f, v2v};
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
    // The realistic pair: a synthesised pose against its ground truth (errors of about a
    // centimetre). Distant pairs (two different poses) prune far less and run slower.
    let target = s.poses.pose_mesh(1);
    let deformed = desal_mesh::TriMesh {
        positions: model.synthesize(&s.rotations[1], s.centroids[1]).unwrap(),
        faces: s.poses.faces.clone(),
    };
    group.bench_function("v2f_synthesised_vs_truth", |b| b.iter(|| v2f(&deformed, &target)));
    group.bench_function("v2v_synthesised_vs_truth", |b| b.iter(|| v2v(&deformed, &target)));
    group.finish();
}

/// The same model work at the paper's simplified size, on a synthetic skinned tube of
/// 2500 vertices and 71 poses (a SCAPE subsample needs stage 3, which this crate does
/// not depend on). Runs without SCAPE.
fn bench_model_2500(c: &mut Criterion) {
    let tube = common::Tube::new(125, 20);
    let poses = tube.pose_set(70, 1);
    let rotations = common::part_rotations(&poses, &tube.labels);
    let centroids: Vec<Vec3> = poses.poses.iter().map(|p| common::centroid(p)).collect();
    let all: Vec<usize> = (0..poses.pose_count()).collect();
    let config = ModelConfig::default();
    let mut group = c.benchmark_group("tube_2500");
    group.sample_size(10);
    group.bench_function("fit_model_71_poses", |b| {
        b.iter(|| fit_model(&poses, &tube.labels, &rotations, &all, &config).unwrap())
    });
    let model = fit_model(&poses, &tube.labels, &rotations, &all, &config).unwrap();
    group.bench_function("synthesize_71_poses", |b| {
        b.iter(|| model.synthesize_many(&rotations, &centroids).unwrap())
    });
    group.finish();
}

fn main() {
    let mut c = Criterion::default().configure_from_args();
    bench_model_2500(&mut c);
    let Some(dir) = common::scape_dir() else {
        c.final_summary();
        return;
    };
    let (poses, labels) = common::load_scape(&dir);
    let rotations = common::part_rotations(&poses, &labels);
    let centroids = poses.poses.iter().map(|p| common::centroid(p)).collect();
    let scape = Scape { poses, labels, rotations, centroids };
    bench_model(&mut c, &scape);
    c.final_summary();
}
