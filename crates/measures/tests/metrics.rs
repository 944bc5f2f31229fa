//! v2f and v2v against brute-force references on small random meshes, and the ordering
//! between them that the paper's Table 1 contradicts.

use desal_measures::{SurfaceIndex, VertexIndex, v2f, v2f_halves, v2v, vertex_errors, vertex_faces};
use desal_mesh::{TriMesh, Vec3};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Squared point–triangle distance computed a different way from the library: project
/// onto the plane, keep the projection if its barycentric coordinates are all
/// non-negative, otherwise take the nearest of the three edges.
fn reference_distance_sq(p: &Vec3, [a, b, c]: [Vec3; 3]) -> f64 {
    let segment = |s: &Vec3, t: &Vec3| {
        let d = t - s;
        let u =
            if d.norm_squared() == 0.0 { 0.0 } else { ((p - s).dot(&d) / d.norm_squared()).clamp(0.0, 1.0) };
        (p - (s + d * u)).norm_squared()
    };
    let edges = segment(&a, &b).min(segment(&b, &c)).min(segment(&c, &a));
    let n = (b - a).cross(&(c - a));
    if n.norm_squared() == 0.0 {
        return edges;
    }
    let q = p - n * ((p - a).dot(&n) / n.norm_squared());
    let inside = [(a, b), (b, c), (c, a)].iter().all(|(s, t)| (t - s).cross(&(q - s)).dot(&n) >= 0.0);
    if inside { (p - q).norm_squared() } else { edges }
}

fn brute_to_surface(points: &[Vec3], surface: &TriMesh) -> Vec<f64> {
    points
        .iter()
        .map(|p| {
            (0..surface.face_count())
                .map(|f| reference_distance_sq(p, surface.corners(f)))
                .fold(f64::INFINITY, f64::min)
        })
        .collect()
}

fn brute_to_vertex(points: &[Vec3], cloud: &[Vec3]) -> Vec<f64> {
    points
        .iter()
        .map(|p| cloud.iter().map(|q| (p - q).norm_squared()).fold(f64::INFINITY, f64::min))
        .collect()
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// A random triangle soup: `n` points in a unit cube, `m` faces of distinct random
/// corners (some vertices may be unused).
fn random_soup(rng: &mut ChaCha8Rng, n: usize, m: usize) -> TriMesh {
    let positions = (0..n).map(|_| Vec3::new(rng.r#gen(), rng.r#gen(), rng.r#gen())).collect();
    let faces = (0..m)
        .map(|_| {
            loop {
                let f = [rng.gen_range(0..n as u32), rng.gen_range(0..n as u32), rng.gen_range(0..n as u32)];
                if f[0] != f[1] && f[1] != f[2] && f[0] != f[2] {
                    break f;
                }
            }
        })
        .collect();
    TriMesh { positions, faces }
}

/// A jittered height-field grid (every vertex used by a face), like a patch of skin.
fn jittered_grid(rng: &mut ChaCha8Rng, side: usize, jitter: f64) -> TriMesh {
    let mut positions = Vec::new();
    for i in 0..side {
        for j in 0..side {
            // Inclusive: a jitter of 0 (which proptest draws) is a plain grid.
            let mut r = || rng.gen_range(-jitter..=jitter);
            positions.push(Vec3::new(
                i as f64 * 0.1 + r(),
                j as f64 * 0.1 + r(),
                0.05 * (i as f64).sin() + r(),
            ));
        }
    }
    let mut faces = Vec::new();
    for i in 0..side as u32 - 1 {
        for j in 0..side as u32 - 1 {
            let v = i * side as u32 + j;
            faces.push([v, v + side as u32, v + 1]);
            faces.push([v + 1, v + side as u32, v + side as u32 + 1]);
        }
    }
    TriMesh { positions, faces }
}

/// Equal up to rounding: relative 1e-12, plus an absolute 1e-15 for squared distances
/// near zero, where the BVH's and brute force's different operation orders leave an
/// error of a few ulps of the unit cube's squared scale (about 1e-16), not of the value.
fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(b.abs()) + 1e-15
}

/// A point above a flat unit square: v2f picks the plane distance, v2v the corner.
#[test]
fn point_over_a_square() {
    let square = TriMesh {
        positions: vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ],
        faces: vec![[0, 1, 2], [0, 2, 3]],
    };
    let lifted = TriMesh {
        positions: square.positions.iter().map(|p| p + Vec3::new(0.0, 0.0, 0.5)).collect(),
        faces: square.faces.clone(),
    };
    // Every vertex of each mesh is 0.5 from the other's plane and from its twin vertex.
    assert_eq!(v2f(&lifted, &square), 0.25);
    assert_eq!(v2v(&lifted, &square), 0.25);
    let centre = SurfaceIndex::new(&square).distances_sq(&[Vec3::new(0.3, 0.6, 2.0)]);
    assert_eq!(centre, vec![4.0]);
}

/// `index`'s distances one query at a time (not the batched, parallel path).
fn one_at_a_time(index: &SurfaceIndex, queries: &[Vec3]) -> Vec<f64> {
    queries.iter().map(|q| index.nearest(q).map_or(f64::INFINITY, |(_, d)| d)).collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Issue 6: v2f (both halves) and v2v equal brute force over every face / vertex.
    #[test]
    fn metrics_match_brute_force(seed in any::<u64>(), n in 3usize..40, m in 1usize..60) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let a = random_soup(&mut rng, n, m);
        let b = random_soup(&mut rng, n + 5, m + 3);
        let halves = v2f_halves(&a, &b);
        let a_to_b = brute_to_surface(&a.positions, &b);
        let b_to_a = brute_to_surface(&b.positions, &a);
        prop_assert!(close(halves.a_to_b, mean(&a_to_b)), "{} vs {}", halves.a_to_b, mean(&a_to_b));
        prop_assert!(close(halves.b_to_a, mean(&b_to_a)));
        let eq6 = (a_to_b.iter().sum::<f64>() + b_to_a.iter().sum::<f64>()) / (a_to_b.len() + b_to_a.len()) as f64;
        prop_assert!(close(v2f(&a, &b), eq6));
        prop_assert!(close(v2v(&a, &b), mean(&brute_to_vertex(&a.positions, &b.positions))));
        let per_vertex = vertex_errors(&a, &b);
        for (got, want) in per_vertex.to_surface.iter().zip(&a_to_b) {
            prop_assert!(close(*got, *want), "{got:e} vs {want:e}");
        }
        prop_assert_eq!(per_vertex.to_vertex, brute_to_vertex(&a.positions, &b.positions));
    }

    /// Issue 17: an index refitted to a moved mesh (even one moved far, or a different
    /// soup with as many faces) answers exactly as one built on it, nearest face
    /// included; distances are bit-identical because each is the same exact test.
    #[test]
    fn refitted_index_matches_a_fresh_one(seed in any::<u64>(), side in 2usize..12, jitter in 0.0f64..0.2) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let before = jittered_grid(&mut rng, side, 0.01);
        let after = jittered_grid(&mut rng, side, jitter);
        let scrambled = random_soup(&mut rng, 40, before.face_count());
        let queries: Vec<Vec3> =
            (0..60).map(|_| Vec3::new(rng.gen_range(-0.2..1.4), rng.gen_range(-0.2..1.4), rng.gen_range(-0.3..0.3))).collect();
        let built = SurfaceIndex::new(&before);
        for moved in [&after, &scrambled] {
            let refitted = built.refit(moved);
            let fresh = SurfaceIndex::new(moved);
            for q in &queries {
                prop_assert_eq!(refitted.nearest(q), fresh.nearest(q));
            }
            prop_assert_eq!(refitted.distances_sq(&queries), one_at_a_time(&fresh, &queries));
        }
        // A point cloud's index likewise (as many points: the grid's vertices moved, or
        // scattered anywhere): the same nearest point, seeded or not.
        let scattered: Vec<Vec3> =
            (0..before.vertex_count()).map(|_| Vec3::new(rng.r#gen(), rng.r#gen(), rng.r#gen())).collect();
        let built = VertexIndex::new(&before.positions);
        for points in [&after.positions, &scattered] {
            let (refitted, fresh) = (built.refit(points), VertexIndex::new(points));
            for (i, q) in queries.iter().enumerate() {
                prop_assert_eq!(refitted.nearest(q), fresh.nearest(q));
                prop_assert_eq!(refitted.nearest_seeded(q, i as u32), fresh.nearest(q));
            }
        }
    }

    /// Issue 17: a seeded query (the grid from a near seed, the tree from a far or
    /// missing one) answers exactly as an unseeded one, nearest face or point included,
    /// whatever the seed: the vertex's own faces, random faces, or none.
    #[test]
    fn seeded_queries_match_unseeded(seed in any::<u64>(), side in 2usize..14, jitter in 0.001f64..0.1) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let target = jittered_grid(&mut rng, side, 0.01);
        let near = jittered_grid(&mut rng, side, jitter);
        let surface = SurfaceIndex::new(&target);
        let vertices = VertexIndex::new(&target.positions);
        let own = vertex_faces(&target.faces, target.vertex_count());
        let n = near.vertex_count() as u32;
        let random: Vec<u32> = (0..n).map(|_| rng.gen_range(0..target.face_count() as u32 + 3)).collect();
        for (i, p) in near.positions.iter().enumerate() {
            for s in [own[i], random[i], u32::MAX] {
                prop_assert_eq!(surface.nearest_seeded(p, s), surface.nearest(p));
            }
            for s in [i as u32, random[i] % n, u32::MAX] {
                prop_assert_eq!(vertices.nearest_seeded(p, s), vertices.nearest(p));
            }
        }
        prop_assert_eq!(surface.distances_sq_seeded(&near.positions, &own), surface.distances_sq(&near.positions));
        // Issue 17: from each vertex's own faces where its clearance proves them nearest.
        let rings = SurfaceIndex::with_vertex_rings(&target);
        prop_assert_eq!(rings.distances_sq_near_vertices(&near.positions, &own), surface.distances_sq(&near.positions));
        prop_assert_eq!(rings.distances_sq_near_vertices(&target.positions, &own), surface.distances_sq(&target.positions));
        let refitted = surface.refit(&near);
        prop_assert_eq!(
            refitted.distances_sq_seeded(&target.positions, &own),
            SurfaceIndex::new(&near).distances_sq(&target.positions)
        );
    }

    /// Issue 6: a vertex is never farther from a surface than from that surface's
    /// nearest vertex, so the deformed → target half of v2f is at most v2v.
    #[test]
    fn surface_half_never_exceeds_v2v(seed in any::<u64>(), side in 2usize..12, jitter in 0.0f64..0.05) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let target = jittered_grid(&mut rng, side, jitter);
        let deformed = jittered_grid(&mut rng, side, jitter);
        let half = v2f_halves(&deformed, &target).a_to_b;
        prop_assert!(half <= v2v(&deformed, &target), "{half} > {}", v2v(&deformed, &target));
    }
}
