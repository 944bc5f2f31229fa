//! The fast greedy mapping against its brute-force reference on hundreds of seeded
//! random inputs: uniform points, integer grids and duplicated points (exact ties),
//! tight clusters, and points far from the origin (rounding). The brute force itself is
//! checked against the literal O(n²·m) rule on small inputs.

use desal_map::{
    MapConfig, MapError, VertexMap, greedy_map, greedy_map_brute_force, greedy_map_with, squared_distance,
};
use desal_mesh::Vec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The rule as the paper states it, with our tie-break: n times, scan every free pair
/// and take the smallest `(dist2, simp_idx, orig_idx)`.
fn literal_greedy(simplified: &[Vec3], original: &[Vec3]) -> Vec<u32> {
    let mut simp_to_orig = vec![u32::MAX; simplified.len()];
    let mut orig_taken = vec![false; original.len()];
    for _ in 0..simplified.len() {
        let mut best: Option<(f64, usize, usize)> = None;
        for (s, sp) in simplified.iter().enumerate() {
            if simp_to_orig[s] != u32::MAX {
                continue;
            }
            for (o, op) in original.iter().enumerate() {
                if orig_taken[o] {
                    continue;
                }
                let d = squared_distance(sp, op);
                // Scanning s then o ascending, a strictly smaller distance wins: the first
                // pair found at the minimum distance has the lowest (s, o).
                if best.is_none_or(|(bd, _, _)| d < bd) {
                    best = Some((d, s, o));
                }
            }
        }
        let (_, s, o) = best.unwrap();
        simp_to_orig[s] = o as u32;
        orig_taken[o] = true;
    }
    simp_to_orig
}

/// A generator of point clouds of one kind.
type Cloud = fn(&mut ChaCha8Rng, usize) -> Vec<Vec3>;

fn uniform(rng: &mut ChaCha8Rng, count: usize) -> Vec<Vec3> {
    (0..count).map(|_| Vec3::new(rng.r#gen(), rng.r#gen(), rng.r#gen())).collect()
}

/// Points on a 4×4×3 integer grid: with more points than grid nodes, many coincide, and
/// many pairs are exactly equally far apart.
fn integer_grid(rng: &mut ChaCha8Rng, count: usize) -> Vec<Vec3> {
    (0..count)
        .map(|_| {
            Vec3::new(rng.gen_range(0..4) as f64, rng.gen_range(0..4) as f64, rng.gen_range(0..3) as f64)
        })
        .collect()
}

/// Half-integer coordinates on a line: distances repeat exactly (0.25, 1, 2.25, ...).
fn half_steps_on_a_line(rng: &mut ChaCha8Rng, count: usize) -> Vec<Vec3> {
    (0..count).map(|_| Vec3::new(rng.gen_range(0..12) as f64 * 0.5, 0.0, 0.0)).collect()
}

/// A few distinct points, each repeated many times (more than a k-d tree bucket holds).
fn duplicated(rng: &mut ChaCha8Rng, count: usize) -> Vec<Vec3> {
    let distinct = [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.5)];
    (0..count).map(|_| distinct[rng.gen_range(0..distinct.len())]).collect()
}

/// Tight clusters (1e-6 across) around a few centres: most candidates of a vertex are
/// its cluster mates, so candidate sets run out and widen.
fn clustered(rng: &mut ChaCha8Rng, count: usize) -> Vec<Vec3> {
    let centres: Vec<Vec3> = (0..3).map(|_| Vec3::new(rng.r#gen(), rng.r#gen(), rng.r#gen())).collect();
    (0..count)
        .map(|_| {
            let c = centres[rng.gen_range(0..centres.len())];
            c + Vec3::new(rng.r#gen(), rng.r#gen(), rng.r#gen()) * 1e-6
        })
        .collect()
}

/// Points 1e6 from the origin, 1e-3 apart: coordinate differences round, so the tree's
/// own distances and ours can differ in the last bits.
fn far_from_origin(rng: &mut ChaCha8Rng, count: usize) -> Vec<Vec3> {
    (0..count)
        .map(|_| Vec3::new(1e6, -2e6, 3e6) + Vec3::new(rng.r#gen(), rng.r#gen(), rng.r#gen()) * 1e-3)
        .collect()
}

const CLOUDS: [(&str, Cloud); 6] = [
    ("uniform", uniform),
    ("integer grid", integer_grid),
    ("half steps on a line", half_steps_on_a_line),
    ("duplicated", duplicated),
    ("clustered", clustered),
    ("far from origin", far_from_origin),
];

/// Checks fast == brute force for `cases` random inputs of every kind, with several
/// initial candidate counts (1 forces the widening path on almost every vertex).
fn check_fast_equals_brute_force(seed: u64, cases: usize, max_original: usize) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for (kind, cloud) in CLOUDS {
        for case in 0..cases {
            let original_count = rng.gen_range(1..=max_original);
            let simplified_count = rng.gen_range(0..=original_count);
            let original = cloud(&mut rng, original_count);
            // Half the cases draw the simplified points from the same distribution, half
            // perturb a subset of the originals (the realistic stage-4 situation).
            let simplified = if case % 2 == 0 {
                cloud(&mut rng, simplified_count)
            } else {
                (0..simplified_count)
                    .map(|_| {
                        let p = original[rng.gen_range(0..original_count)];
                        if rng.gen_bool(0.5) { p } else { p + Vec3::new(rng.r#gen(), 0.0, 0.0) * 1e-3 }
                    })
                    .collect()
            };
            let reference = greedy_map_brute_force(&simplified, &original).unwrap();
            assert!(VertexMap::try_new(reference.simp_to_orig.clone(), original_count).is_ok());
            for initial_candidates in [1, 3, 8] {
                let fast =
                    greedy_map_with(&MapConfig { initial_candidates }, &simplified, &original).unwrap();
                assert_eq!(
                    fast, reference,
                    "{kind} case {case} (seed {seed}): {simplified_count} onto {original_count}, k0 = {initial_candidates}"
                );
            }
        }
    }
}

#[test]
fn fast_equals_brute_force_on_small_random_inputs() {
    check_fast_equals_brute_force(1, 60, 40);
}

#[test]
fn fast_equals_brute_force_on_larger_random_inputs() {
    check_fast_equals_brute_force(2, 15, 400);
}

#[test]
fn brute_force_equals_the_literal_rule() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for (kind, cloud) in CLOUDS {
        for case in 0..25 {
            let original_count = rng.gen_range(1..=25);
            let original = cloud(&mut rng, original_count);
            let simplified_count = rng.gen_range(0..=original_count);
            let simplified = cloud(&mut rng, simplified_count);
            let reference = greedy_map_brute_force(&simplified, &original).unwrap();
            assert_eq!(reference.simp_to_orig, literal_greedy(&simplified, &original), "{kind} case {case}");
        }
    }
}

/// All points identical: every pair ties, so the rule pairs simp_idx i with orig_idx i.
#[test]
fn all_identical_points_map_in_index_order() {
    let original = vec![Vec3::new(0.5, 0.5, 0.5); 100];
    let simplified = vec![Vec3::new(0.5, 0.5, 0.5); 70];
    let expected: Vec<u32> = (0..70).collect();
    assert_eq!(greedy_map(&simplified, &original).unwrap().simp_to_orig, expected);
}

/// A simplified set that is a perturbed subset of the originals (noise well below half
/// the spacing) maps back onto exactly that subset.
#[test]
fn perturbed_subset_maps_back_to_the_subset() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    // A 20×20×5 lattice with spacing 1.
    let original: Vec<Vec3> =
        (0..2000).map(|i| Vec3::new((i % 20) as f64, ((i / 20) % 20) as f64, (i / 400) as f64)).collect();
    let kept: Vec<u32> = (0..2000).filter(|_| rng.gen_bool(0.2)).collect();
    let simplified: Vec<Vec3> = kept
        .iter()
        .map(|&o| {
            original[o as usize] + Vec3::new(rng.r#gen(), rng.r#gen(), rng.r#gen()) * 0.2 - Vec3::repeat(0.1)
        })
        .collect();
    assert_eq!(greedy_map(&simplified, &original).unwrap().simp_to_orig, kept);
}

#[test]
fn n_equal_m_is_a_permutation() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let original = uniform(&mut rng, 300);
    let simplified = uniform(&mut rng, 300);
    let map = greedy_map(&simplified, &original).unwrap();
    assert!(VertexMap::try_new(map.simp_to_orig.clone(), 300).is_ok());
    assert_eq!(map, greedy_map_brute_force(&simplified, &original).unwrap());
}

#[test]
fn errors_on_bad_input() {
    let three = vec![Vec3::zeros(), Vec3::x(), Vec3::y()];
    assert_eq!(
        greedy_map(&three, &three[..2]).unwrap_err(),
        MapError::TooFewOriginalVertices { simplified: 3, original: 2 }
    );
    let mut nan = three.clone();
    nan[1].z = f64::NAN;
    assert!(matches!(greedy_map(&nan, &three), Err(MapError::NonFiniteSimplified { simp_idx: 1, .. })));
    assert!(matches!(greedy_map(&three, &nan), Err(MapError::NonFiniteOriginal { orig_idx: 1, .. })));
}

/// The mapping on the real SCAPE template: every 5th vertex, perturbed, onto all 12500.
#[test]
#[cfg_attr(
    not(desal_shared_data),
    ignore = "needs ../shared/datasets beside the checkout (development and CI only)"
)]
fn scape_template_decimation_fast_equals_brute_force() {
    let Some(dir) = desal_testdata::scape_dir() else { return };
    let path = dir.join("mesh000.ply");
    let template = desal_io::read_mesh(&path).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let simplified: Vec<Vec3> = template
        .positions
        .iter()
        .step_by(5)
        .map(|p| p + (Vec3::new(rng.r#gen(), rng.r#gen(), rng.r#gen()) - Vec3::repeat(0.5)) * 0.01)
        .collect();
    let fast = greedy_map(&simplified, &template.positions).unwrap();
    assert_eq!(fast.len(), 2500);
    assert_eq!(fast, greedy_map_brute_force(&simplified, &template.positions).unwrap());
}
