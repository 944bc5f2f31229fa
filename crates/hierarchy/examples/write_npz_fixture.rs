//! Writes `hierarchy.npz` for a hand-made three-level hierarchy (a bumped 9 × 9 grid →
//! its every-2nd-vertex 5 × 5 grid → 3 × 3), with fitted upsamplers on four bent poses,
//! and a JSON file of the exact values every array must hold, for the numpy test in
//! `tests/python/test_hierarchy_npz.py`.
//!
//! `cargo run -p desal-hierarchy --example write_npz_fixture -- OUT.npz EXPECTED.json`

use std::path::Path;

use desal_hierarchy::{CsrMatrix, LevelInput, Upsampler, adjacency, build_level, nest};
use desal_io::npz::{CooArrays, HierarchyArrays, NpyData, write_hierarchy_npz};
use desal_mesh::{Face, PoseSet, Vec3};
use serde_json::{Value, json};

const N: usize = 9;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [npz, expected] = &args[..] else {
        eprintln!("usage: write_npz_fixture OUT.npz EXPECTED.json");
        std::process::exit(2);
    };

    let full = bent_grid(4);
    let mask = vec![true, true, true, false];
    let map1 = grid_subset(N, 2);
    let map2 = grid_subset(5, 2);
    let (faces1, faces2) = (grid_faces(N, 2), grid_faces(5, 2));
    let level0 = build_level(
        &LevelInput { fine: &full, coarse_to_fine: &map1, coarse_faces: &faces1, training: &mask },
        &Upsampler::default(),
    )
    .expect("level 1");
    let orig1 = nest(&(0..(N * N) as u32).collect::<Vec<_>>(), &map1);
    let poses1 = PoseSet::try_new(
        full.names.clone(),
        full.poses.iter().map(|p| orig1.iter().map(|&o| p[o as usize]).collect()).collect(),
        faces1.clone(),
        0,
    )
    .expect("level-1 poses");
    let level1 = build_level(
        &LevelInput { fine: &poses1, coarse_to_fine: &map2, coarse_faces: &faces2, training: &mask },
        &Upsampler::default(),
    )
    .expect("level 2");
    let orig2 = nest(&orig1, &map2);

    let hierarchy = HierarchyArrays {
        levels: vec![N * N, map1.len(), map2.len()],
        faces: vec![full.faces.clone(), faces1, faces2],
        adjacency: vec![
            coo(&adjacency(N * N, &full.faces).expect("A0")),
            coo(&level0.coarse_adjacency),
            coo(&level1.coarse_adjacency),
        ],
        down: vec![coo(&level0.down), coo(&level1.down)],
        up: vec![coo(&level0.up), coo(&level1.up)],
        map: vec![map1, map2],
        orig: vec![orig1, orig2],
    };
    write_hierarchy_npz(Path::new(npz), &hierarchy).expect("write npz");

    // The expected values come from the in-memory arrays, not from reading the file back.
    let arrays = hierarchy.to_arrays().expect("arrays");
    let expected_json: serde_json::Map<String, Value> = arrays
        .iter()
        .map(|(name, a)| {
            let (dtype, values) = match &a.data {
                NpyData::I32(v) => ("int32", json!(v)),
                NpyData::I64(v) => ("int64", json!(v)),
                NpyData::F64(v) => ("float64", json!(v)),
            };
            (name.clone(), json!({ "dtype": dtype, "shape": a.shape, "values": values }))
        })
        .collect();
    std::fs::write(expected, serde_json::to_string_pretty(&expected_json).expect("json"))
        .expect("write json");
    println!("wrote {npz} ({} arrays) and {expected}", arrays.len());
}

fn coo(m: &CsrMatrix) -> CooArrays {
    let c = m.to_coo();
    CooArrays { shape: [c.rows, c.cols], row: c.row, col: c.col, data: c.data }
}

/// Four poses of a bumped grid, bent progressively (pose 0, the template, unbent).
fn bent_grid(count: usize) -> PoseSet {
    let template: Vec<Vec3> = (0..N * N)
        .map(|i| {
            let (u, v) = ((i % N) as f64 / (N - 1) as f64, (i / N) as f64 / (N - 1) as f64);
            Vec3::new(u, v, 0.3 * (3.0 * u).sin() * (2.0 * v).cos() + 0.2 * u * v)
        })
        .collect();
    let poses = (0..count)
        .map(|p| {
            let s = p as f64 / count as f64;
            template
                .iter()
                .map(|q| {
                    let (sin, cos) = (s * q.x).sin_cos();
                    Vec3::new(q.x, cos * q.y - sin * q.z, sin * q.y + cos * q.z + s * q.x * q.x)
                })
                .collect()
        })
        .collect();
    let names = (0..count).map(|p| format!("pose{p}")).collect();
    PoseSet::try_new(names, poses, grid_faces(N, 1), 0).expect("grid poses")
}

/// Faces of the every-`step`-th grid of an `n × n` grid, in that grid's own indices.
fn grid_faces(n: usize, step: usize) -> Vec<Face> {
    let m = (n - 1) / step + 1;
    let mut faces = Vec::new();
    for y in 0..m - 1 {
        for x in 0..m - 1 {
            let (i, m) = ((y * m + x) as u32, m as u32);
            faces.push([i, i + 1, i + m + 1]);
            faces.push([i, i + m + 1, i + m]);
        }
    }
    faces
}

/// The every-`step`-th grid's vertices as indices of the `n × n` grid.
fn grid_subset(n: usize, step: usize) -> Vec<u32> {
    (0..n).step_by(step).flat_map(|y| (0..n).step_by(step).map(move |x| (y * n + x) as u32)).collect()
}
