//! The seeded point-to-surface queries of `desal eval`'s upsampling error, alone, for
//! instruction counts (cachegrind) of `SurfaceIndex::distances_sq_seeded`:
//!
//!     cargo build --release -p desal-measures --example seeded_queries
//!     RAYON_NUM_THREADS=1 valgrind --tool=cachegrind --cache-sim=no \
//!       target/release/examples/seeded_queries ../shared/datasets/scape/mesh001.ply 4 [rings]
//!
//! The target is the given mesh; the queries are its vertices, one in five kept in place
//! (as an upsampler keeps the coarse vertices) and the others moved by up to 3 mm on each
//! axis (a seeded generator: the same points every run), as an upsampled pose lies about
//! its truth. Each point is seeded with the lowest-index face of its vertex, as the
//! upsampling error seeds it. `ROUNDS` (default 1) repeats the queries; the printed sum
//! of distances checks that a change kept every answer. With `rings`, the index is
//! built `SurfaceIndex::with_vertex_rings` and queried by
//! `SurfaceIndex::distances_sq_near_vertices`, as `desal eval` queries its full poses.
//! It also prints the resident memory an index keeps: ten are built and kept, and the
//! growth divided by ten (Linux's `/proc/self/statm`; 0 elsewhere), so the build's
//! transient buffers, reused from one build to the next, barely count.

use std::path::PathBuf;

use desal_measures::SurfaceIndex;
use desal_mesh::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn main() {
    let mut args = std::env::args().skip(1);
    let path = PathBuf::from(args.next().expect("usage: seeded_queries MESH.ply [ROUNDS]"));
    let rounds: usize = args.next().map_or(1, |r| r.parse().expect("ROUNDS is a count"));
    let rings = args.next().is_some_and(|a| a == "rings");
    let mesh = desal_io::read_mesh(&path).expect("a readable mesh");
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let points: Vec<Vec3> = mesh
        .positions
        .iter()
        .enumerate()
        .map(|(i, v)| if i % 5 == 0 { *v } else { v + Vec3::from_fn(|_, _| rng.gen_range(-3e-3..3e-3)) })
        .collect();
    let mut seeds = vec![u32::MAX; mesh.positions.len()];
    for (f, face) in mesh.faces.iter().enumerate().rev() {
        for &v in face {
            seeds[v as usize] = f as u32;
        }
    }
    const COPIES: usize = 10;
    let before = resident_bytes();
    let indices: Vec<SurfaceIndex> = (0..COPIES)
        .map(|_| if rings { SurfaceIndex::with_vertex_rings(&mesh) } else { SurfaceIndex::new(&mesh) })
        .collect();
    let index_mb = resident_bytes().saturating_sub(before) as f64 / 1e6 / COPIES as f64;
    let index = &indices[0];
    let mut sum = 0.0;
    for _ in 0..rounds {
        let distances = if rings {
            index.distances_sq_near_vertices(&points, &seeds)
        } else {
            index.distances_sq_seeded(&points, &seeds)
        };
        sum += distances.iter().sum::<f64>();
    }
    println!("{} points × {rounds}: sum of squared distances {sum:.17e}", points.len());
    println!("each index: {index_mb:.1} MB resident");
}

/// This process's resident memory, from `/proc/self/statm` (4 KiB pages), or 0.
fn resident_bytes() -> usize {
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
    statm.split_whitespace().nth(1).and_then(|pages| pages.parse::<usize>().ok()).unwrap_or(0) * 4096
}
