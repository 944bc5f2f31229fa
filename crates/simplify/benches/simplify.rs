//! Criterion benchmark of stage 3: the SCAPE template (24998 faces → 5000, plain QEM,
//! optimal and subset placement) when `../shared/datasets` is present (see `desal-testdata`
//! for the skip policy), and always a
//! synthetic closed mesh of the same size, so the bench measures something on any clone.

use criterion::{Criterion, criterion_group, criterion_main};
use desal_mesh::{TriMesh, Vec3};
use desal_simplify::{Placement, SimplifyConfig, SimplifyInput, Target, simplify};

/// A UV sphere with a bumpy radius: `rings × segments` quads, closed with two fans.
fn bumpy_sphere(rings: usize, segments: usize) -> TriMesh {
    let mut positions = vec![Vec3::new(0.0, 0.0, 1.0)];
    for r in 1..rings {
        let theta = std::f64::consts::PI * r as f64 / rings as f64;
        for s in 0..segments {
            let phi = std::f64::consts::TAU * s as f64 / segments as f64;
            let radius = 1.0 + 0.05 * (5.0 * theta).sin() * (7.0 * phi).cos();
            positions.push(radius * Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()));
        }
    }
    positions.push(Vec3::new(0.0, 0.0, -1.0));
    let ring = |r: usize, s: usize| (1 + (r - 1) * segments + s % segments) as u32;
    let south = positions.len() as u32 - 1;
    let mut faces = Vec::new();
    for s in 0..segments {
        faces.push([0, ring(1, s), ring(1, s + 1)]);
        faces.push([south, ring(rings - 1, s + 1), ring(rings - 1, s)]);
    }
    for r in 1..rings - 1 {
        for s in 0..segments {
            let (a, b, c, d) = (ring(r, s), ring(r + 1, s), ring(r + 1, s + 1), ring(r, s + 1));
            faces.push([a, b, c]);
            faces.push([a, c, d]);
        }
    }
    TriMesh { positions, faces }
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("simplify");
    group.sample_size(20);
    let mut meshes = vec![("sphere25k", bumpy_sphere(100, 125))];
    // Absent SCAPE is a skip on a user's clone and a failure in CI (desal-testdata).
    if let Some(dir) = desal_testdata::scape_dir() {
        let mesh = desal_io::read_mesh(&dir.join("mesh000.ply")).expect("SCAPE template reads");
        meshes.push(("scape_mesh000", mesh));
    }
    for (name, mesh) in &meshes {
        for (label, placement) in [("optimal", Placement::Optimal), ("subset", Placement::Subset)] {
            let config = SimplifyConfig { placement, ..SimplifyConfig::qslim(Target::Faces(5000)) };
            group.bench_function(format!("{name}/{label}/5000"), |b| {
                b.iter(|| simplify(&SimplifyInput::new(mesh), &config).expect("simplifies"))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
