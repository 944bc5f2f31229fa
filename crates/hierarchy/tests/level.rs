//! The hand-made-mesh tests of one level step: D is a selection consistent with
//! the map, the maps nest, U rows sum to 1, the fitted U reproduces affine training poses
//! exactly, the barycentric U equals a brute-force closest-point computation; plus input
//! errors and thread-count independence.

use desal_hierarchy::barycentric::projection_row;
use desal_hierarchy::{
    ChainLevel, CsrMatrix, FALLBACK_NEIGHBOURS, FALLBACK_RIDGE, FittedConfig, HierarchyError, Knob,
    LevelInput, NEIGHBOUR_GRID, Neighbourhood, RIDGE_GRID, Settled, Upsampler, adjacency, build_level,
    composed_upsamplers, composed_upsamplers_per_mask, nest, upsampling_error,
};
use desal_measures::closest_point::point_triangle_distance_sq;
use desal_mesh::{Face, Mat3, PoseSet, TriMesh, Vec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// An `n × n` grid over `[0, 1]²` lifted onto a non-planar bump, so that any handful of
/// nearby vertices spans 3D (needed for affine reproduction).
fn bumpy_grid(n: usize) -> TriMesh {
    let mut positions = Vec::new();
    for y in 0..n {
        for x in 0..n {
            let (u, v) = (x as f64 / (n - 1) as f64, y as f64 / (n - 1) as f64);
            positions.push(Vec3::new(u, v, 0.3 * (3.0 * u).sin() * (2.0 * v).cos() + 0.2 * u * v));
        }
    }
    TriMesh { positions, faces: grid_faces(n, 1) }
}

/// Faces of the grid of every `step`-th vertex of an `n × n` grid, in the indices of
/// that coarse grid (row-major, `(n − 1)/step + 1` per side).
fn grid_faces(n: usize, step: usize) -> Vec<Face> {
    let m = (n - 1) / step + 1;
    let mut faces = Vec::new();
    for y in 0..m - 1 {
        for x in 0..m - 1 {
            let i = (y * m + x) as u32;
            let m = m as u32;
            faces.push([i, i + 1, i + m + 1]);
            faces.push([i, i + m + 1, i + m]);
        }
    }
    faces
}

/// The vertices of the every-`step`-th coarse grid, as fine vertex indices.
fn grid_subset(n: usize, step: usize) -> Vec<u32> {
    let mut out = Vec::new();
    for y in (0..n).step_by(step) {
        for x in (0..n).step_by(step) {
            out.push((y * n + x) as u32);
        }
    }
    out
}

/// Poses that are affine images of the template: `A_p x + t_p` with random `A_p` near
/// the identity.
fn affine_poses(template: &TriMesh, count: usize, seed: u64) -> PoseSet {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut poses = vec![template.positions.clone()];
    for _ in 1..count {
        let a = Mat3::identity() + Mat3::from_fn(|_, _| rng.gen_range(-0.3..0.3));
        let t = Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
        poses.push(template.positions.iter().map(|p| a * p + t).collect());
    }
    let names = (0..count).map(|p| format!("pose{p}")).collect();
    PoseSet::try_new(names, poses, template.faces.clone(), 0).unwrap()
}

/// Poses with non-affine, per-vertex smooth deformations (a twist and a bend).
fn bent_poses(template: &TriMesh, count: usize) -> PoseSet {
    let mut poses = Vec::new();
    for p in 0..count {
        let s = p as f64 / count as f64;
        poses.push(
            template
                .positions
                .iter()
                .map(|q| {
                    let angle = s * q.x;
                    let (sin, cos) = angle.sin_cos();
                    Vec3::new(q.x, cos * q.y - sin * q.z, sin * q.y + cos * q.z + s * q.x * q.x)
                })
                .collect(),
        );
    }
    let names = (0..count).map(|p| format!("pose{p}")).collect();
    PoseSet::try_new(names, poses, template.faces.clone(), 0).unwrap()
}

const N: usize = 9;

fn input<'a>(fine: &'a PoseSet, coarse: &'a [u32], faces: &'a [Face], mask: &'a [bool]) -> LevelInput<'a> {
    LevelInput { fine, coarse_to_fine: coarse, coarse_faces: faces, training: mask }
}

/// D has exactly one stored 1 per row, in the column the map names.
#[test]
fn down_is_a_selection_consistent_with_the_map() {
    let fine = bent_poses(&bumpy_grid(N), 4);
    let (coarse, faces) = (grid_subset(N, 2), grid_faces(N, 2));
    let mask = vec![true; 4];
    let level = build_level(&input(&fine, &coarse, &faces, &mask), &Upsampler::Barycentric).unwrap();
    assert_eq!((level.down.rows, level.down.cols), (coarse.len(), N * N));
    for (coarse_idx, &fine_idx) in coarse.iter().enumerate() {
        let (cols, vals) = level.down.row(coarse_idx);
        assert_eq!((cols, vals), (&[fine_idx][..], &[1.0][..]), "row {coarse_idx}");
    }
}

/// Two level steps on the grid (every 2nd vertex, then every 2nd of those): `orig2` is
/// `orig1[map2]`, and it names the every-4th vertices of the original grid, which is
/// what the two selections compose to (D1 · D0 selects them too).
#[test]
fn maps_nest() {
    let full = bent_poses(&bumpy_grid(N), 3);
    let map1 = grid_subset(N, 2); // 5 × 5 of the 9 × 9
    let orig1 = nest(&(0..(N * N) as u32).collect::<Vec<_>>(), &map1);
    let map2 = grid_subset(5, 2); // 3 × 3 of the 5 × 5
    let orig2 = nest(&orig1, &map2);
    assert_eq!(orig2, grid_subset(N, 4));

    let mask = vec![true; 3];
    let level0 =
        build_level(&input(&full, &map1, &grid_faces(N, 2), &mask), &Upsampler::Barycentric).unwrap();
    let level1_poses = PoseSet::try_new(
        full.names.clone(),
        full.poses.iter().map(|p| orig1.iter().map(|&o| p[o as usize]).collect()).collect(),
        grid_faces(N, 2),
        0,
    )
    .unwrap();
    let level1 =
        build_level(&input(&level1_poses, &map2, &grid_faces(N, 4), &mask), &Upsampler::Barycentric).unwrap();
    let composed = level1.down.mul(&level0.down).unwrap();
    for (i, &o) in orig2.iter().enumerate() {
        assert_eq!(composed.row(i), (&[o][..], &[1.0][..]));
    }
}

/// Every row of U sums to 1 (to rounding), for both upsamplers, on poses that are not
/// affine (so the fitted rows are really fitted).
#[test]
fn up_rows_sum_to_one() {
    let fine = bent_poses(&bumpy_grid(N), 6);
    let (coarse, faces) = (grid_subset(N, 2), grid_faces(N, 2));
    let mask = vec![true; 6];
    let geodesic = FittedConfig { neighbourhood: Neighbourhood::Geodesic, ..FittedConfig::default() };
    for up in [
        Upsampler::Barycentric,
        Upsampler::default(),
        Upsampler::Fitted(geodesic),
        Upsampler::Fitted(FittedConfig::given(5, 0.0)),
    ] {
        let level = build_level(&input(&fine, &coarse, &faces, &mask), &up).unwrap();
        assert_eq!((level.up.rows, level.up.cols), (N * N, coarse.len()));
        for (row, sum) in level.up.row_sums().iter().enumerate() {
            assert!((sum - 1.0).abs() < 1e-12, "{}: row {row} sums to {sum}", up.name());
        }
        assert!(level.report.up_max_row_sum_error < 1e-12);
    }
}

/// A coarse vertex's own row is exactly a 1 on itself, whatever the upsampler: D · U = I.
#[test]
fn coarse_vertices_upsample_to_themselves() {
    let fine = bent_poses(&bumpy_grid(N), 5);
    let (coarse, faces) = (grid_subset(N, 2), grid_faces(N, 2));
    let mask = vec![true; 5];
    for up in [Upsampler::Barycentric, Upsampler::default()] {
        let level = build_level(&input(&fine, &coarse, &faces, &mask), &up).unwrap();
        let du = level.down.mul(&level.up).unwrap();
        assert_eq!(du, desal_hierarchy::CsrMatrix::identity(coarse.len()), "{}", up.name());
    }
}

/// With training poses that are affine images of the template, the fitted U (ridge 0)
/// reproduces every training pose exactly (to the rounding of f32, the precision the fit
/// reads the coarse trajectories at: these synthetic poses are not f32 values, so the
/// fit sees them off by ~1e-8), and every other affine pose too; the barycentric U does
/// not (the fine vertices are off the coarse surface), so the test can fail.
#[test]
fn fitted_reproduces_affine_training_poses() {
    let poses = affine_poses(&bumpy_grid(N), 8, 3);
    let (coarse, faces) = (grid_subset(N, 2), grid_faces(N, 2));
    let mask = vec![true, true, true, true, true, false, false, false];
    let bary = build_level(&input(&poses, &coarse, &faces, &mask), &Upsampler::Barycentric).unwrap();
    let all: Vec<usize> = (0..8).collect();
    for neighbourhood in [Neighbourhood::Euclidean, Neighbourhood::Geodesic] {
        let fitted = Upsampler::Fitted(FittedConfig { neighbourhood, ..FittedConfig::given(8, 0.0) });
        let level = build_level(&input(&poses, &coarse, &faces, &mask), &fitted).unwrap();
        let fitted_error = upsampling_error(&poses, &level.up, &coarse, &all).unwrap();
        for e in &fitted_error.per_pose {
            assert!(
                e.mse < 1e-14,
                "{neighbourhood:?} pose {} (training: {}): mse {}",
                e.pose,
                mask[e.pose],
                e.mse
            );
        }
    }
    let bary_error = upsampling_error(&poses, &bary.up, &coarse, &all).unwrap();
    assert!(bary_error.mse > 1e-5, "barycentric mse {}", bary_error.mse);
}

/// The default fit chooses its knobs by held-out error: the chosen grid point is the
/// lowest of the grid, its U is the one fitted with those knobs given (to rounding), and it beats the
/// fallback knobs on poses it never saw; too few poses for two folds fall back, and
/// given knobs are used as given.
#[test]
fn held_out_knobs_are_the_grids_best_and_fall_back_without_folds() {
    let fine = bent_poses(&bumpy_grid(N), 12);
    let (coarse, faces) = (grid_subset(N, 2), grid_faces(N, 2));
    let mask: Vec<bool> = (0..12).map(|p| p < 9).collect();
    let chosen = build_level(&input(&fine, &coarse, &faces, &mask), &Upsampler::default()).unwrap();
    let knobs = chosen.report.knobs.clone().expect("a fitted level");
    let Settled::HeldOut { folds, rows, grid } = &knobs.settled else { panic!("{knobs:?}") };
    assert_eq!((*folds, grid.len()), (5, NEIGHBOUR_GRID.len() * RIDGE_GRID.len()));
    assert_eq!(*rows, N * N - coarse.len(), "every free row of a small level");
    let best = grid.iter().map(|p| p.sse).fold(f64::INFINITY, f64::min);
    let at = grid.iter().find(|p| p.neighbours == knobs.neighbours && p.ridge == knobs.ridge).unwrap();
    assert_eq!(at.sse, best);
    let given = Upsampler::Fitted(FittedConfig::given(knobs.neighbours, knobs.ridge));
    let same = build_level(&input(&fine, &coarse, &faces, &mask), &given).unwrap();
    // The same rows, up to the rounding of the sums over poses (summed per tuning fold).
    assert_eq!((&same.up.row_ptr, &same.up.col_idx), (&chosen.up.row_ptr, &chosen.up.col_idx));
    let worst = same.up.values.iter().zip(&chosen.up.values).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(worst < 1e-9, "{worst:e}");
    assert_eq!(same.report.knobs.unwrap().settled, Settled::Given);
    let unseen: Vec<usize> = (9..12).collect();
    let fallback = Upsampler::Fitted(FittedConfig::given(FALLBACK_NEIGHBOURS, FALLBACK_RIDGE));
    let fixed = build_level(&input(&fine, &coarse, &faces, &mask), &fallback).unwrap();
    let error = |up: &CsrMatrix| upsampling_error(&fine, up, &coarse, &unseen).unwrap().mse;
    assert!(error(&chosen.up) < error(&fixed.up), "{} vs {}", error(&chosen.up), error(&fixed.up));

    let two: Vec<bool> = (0..12).map(|p| p < 2).collect();
    let few = build_level(&input(&fine, &coarse, &faces, &two), &Upsampler::default()).unwrap();
    let knobs = few.report.knobs.unwrap();
    assert_eq!(
        (knobs.neighbours, knobs.ridge, knobs.settled),
        (FALLBACK_NEIGHBOURS, FALLBACK_RIDGE, Settled::TooFewPoses)
    );
}

/// A large ridge pulls the fitted rows onto the barycentric ones.
#[test]
fn large_ridge_gives_the_barycentric_rows() {
    let fine = bent_poses(&bumpy_grid(N), 6);
    let (coarse, faces) = (grid_subset(N, 2), grid_faces(N, 2));
    let mask = vec![true; 6];
    let bary = build_level(&input(&fine, &coarse, &faces, &mask), &Upsampler::Barycentric).unwrap();
    let stiff = Upsampler::Fitted(FittedConfig::given(8, 1e9));
    let fitted = build_level(&input(&fine, &coarse, &faces, &mask), &stiff).unwrap();
    for r in 0..N * N {
        let (cols, vals) = fitted.up.row(r);
        for (&c, &v) in cols.iter().zip(vals) {
            assert!((v - bary.up.get(r, c)).abs() < 1e-6, "row {r} col {c}: {v} vs {}", bary.up.get(r, c));
        }
    }
}

/// The barycentric rows equal a brute-force computation: for random points around a
/// coarse mesh, scan every face for the smallest squared distance (lowest index on
/// ties) and take the barycentric coordinates of the closest point on it.
#[test]
fn barycentric_equals_brute_force() {
    let fine_mesh = bumpy_grid(17);
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    // Fine positions: the grid plus random points above, below and beside it, so every
    // Voronoi region of the triangles (faces, edges, corners) is hit.
    let mut positions = fine_mesh.positions.clone();
    positions
        .extend((0..400).map(|_| {
            Vec3::new(rng.gen_range(-0.2..1.2), rng.gen_range(-0.2..1.2), rng.gen_range(-0.6..0.6))
        }));
    let coarse = grid_subset(17, 4);
    let faces = grid_faces(17, 4);
    let coarse_mesh =
        TriMesh { positions: coarse.iter().map(|&i| positions[i as usize]).collect(), faces: faces.clone() };
    let set =
        PoseSet::try_new(vec!["t".into()], vec![positions.clone()], point_faces(positions.len()), 0).unwrap();
    let level = build_level(&input(&set, &coarse, &faces, &[true]), &Upsampler::Barycentric).unwrap();
    for (i, p) in positions.iter().enumerate() {
        let (face, _) = (0..faces.len())
            .map(|f| {
                let [a, b, c] = coarse_mesh.corners(f);
                (f, point_triangle_distance_sq(p, &a, &b, &c))
            })
            .min_by(|x, y| x.1.total_cmp(&y.1).then(x.0.cmp(&y.0)))
            .unwrap();
        let mut want = if let Some(j) = coarse.iter().position(|&c| c as usize == i) {
            vec![(j as u32, 1.0)]
        } else {
            projection_row(&coarse_mesh, faces[face], p)
        };
        want.sort_by_key(|&(j, _)| j); // U stores a row by column

        let (cols, vals) = level.up.row(i);
        let got: Vec<(u32, f64)> = cols.iter().copied().zip(vals.iter().copied()).collect();
        assert_eq!(got, want, "fine vertex {i}");
    }
}

/// Faces over the first vertices only, so a pose set can carry free points.
fn point_faces(n: usize) -> Vec<Face> {
    assert!(n >= 3);
    vec![[0, 1, 2]]
}

/// A 2-triangle square: 5 edges, so 10 stored 1s, none on the diagonal.
#[test]
fn adjacency_of_a_square() {
    let a = adjacency(4, &[[0, 1, 2], [0, 2, 3]]).unwrap();
    let coo = a.to_coo();
    assert_eq!(coo.row, vec![0, 0, 0, 1, 1, 2, 2, 2, 3, 3]);
    assert_eq!(coo.col, vec![1, 2, 3, 0, 2, 0, 1, 3, 0, 2]);
    assert!(coo.data.iter().all(|&v| v == 1.0));
}

/// Same input, one thread or two: the same matrices.
#[test]
fn thread_count_does_not_change_the_result() {
    let fine = bent_poses(&bumpy_grid(N), 6);
    let (coarse, faces) = (grid_subset(N, 2), grid_faces(N, 2));
    let mask = vec![true; 6];
    let run = |threads| {
        rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(|| {
            let mut level =
                build_level(&input(&fine, &coarse, &faces, &mask), &Upsampler::default()).unwrap();
            level.report.seconds = 0.0;
            level
        })
    };
    assert_eq!(run(1), run(2));
}

/// The folds' upsamplers built together (shared candidates, `DᵀD` summed from groups of
/// poses) equal each fold's own to rounding, for overlapping and nested training sets,
/// the geodesic neighbourhood and no ridge (the pseudo-inverse path) alike; a bad mask
/// among them is refused as on its own.
#[test]
fn per_mask_upsamplers_equal_each_masks_own() {
    let fine = bent_poses(&bumpy_grid(N), 7);
    let (coarse, faces) = (grid_subset(N, 2), grid_faces(N, 2));
    let chain = [ChainLevel { coarse_to_fine: &coarse, coarse_faces: &faces }];
    let masks: Vec<Vec<bool>> = vec![
        vec![true, false, true, true, false, true, true],
        vec![true, true, false, true, true, false, true],
        vec![true, true, true, false, false, true, true],
        vec![true, false, false, false, false, false, true],
    ];
    let refs: Vec<&[bool]> = masks.iter().map(|m| m.as_slice()).collect();
    let configs = [
        FittedConfig::default(),
        FittedConfig { neighbourhood: Neighbourhood::Geodesic, ..FittedConfig::default() },
        FittedConfig { ridge: Knob::Given(0.0), ..FittedConfig::default() },
        FittedConfig::given(16, 3e-3),
    ];
    for config in configs {
        let up = Upsampler::Fitted(config);
        let together = composed_upsamplers_per_mask(&fine, &chain, &refs, &up).unwrap();
        assert_eq!(together.len(), masks.len());
        for (mask, built) in masks.iter().zip(&together) {
            let alone = composed_upsamplers(&fine, &chain, mask, &up).unwrap();
            let (a, b) = (&alone[0], &built[0]);
            assert_eq!((a.rows, a.cols, &a.row_ptr, &a.col_idx), (b.rows, b.cols, &b.row_ptr, &b.col_idx));
            if config.ridge != Knob::Given(0.0) {
                let worst = a.values.iter().zip(&b.values).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max);
                assert!(worst < 1e-10, "{config:?}, mask {mask:?}: differs by {worst:e}");
            } else {
                // No ridge: too few training poses leave the least squares rank deficient,
                // and rounding may pick another of its minimisers; the fit is as good.
                let training: Vec<usize> = (0..mask.len()).filter(|&p| mask[p]).collect();
                let fit = |u: &CsrMatrix| upsampling_error(&fine, u, &coarse, &training).unwrap().mse;
                let (fa, fb) = (fit(a), fit(b));
                assert!((fa - fb).abs() <= 1e-6 * fa + 1e-15, "{config:?}, mask {mask:?}: {fa:e} vs {fb:e}");
            }
        }
        // One mask: the same bits as building it alone.
        let one = composed_upsamplers_per_mask(&fine, &chain, &refs[..1], &up).unwrap();
        assert_eq!(one[0], composed_upsamplers(&fine, &chain, &masks[0], &up).unwrap());
    }
    let bad = [masks[0].as_slice(), &[true, true][..]];
    let err = composed_upsamplers_per_mask(&fine, &chain, &bad, &Upsampler::default()).unwrap_err();
    assert!(matches!(err, HierarchyError::MaskLength { mask: 2, poses: 7 }), "{err:?}");
}

#[test]
fn bad_inputs_are_refused_with_their_ids() {
    let fine = bent_poses(&bumpy_grid(N), 3);
    let faces = grid_faces(N, 2);
    let mut coarse = grid_subset(N, 2);
    let mask = vec![true; 3];
    coarse[3] = coarse[1];
    let err = build_level(&input(&fine, &coarse, &faces, &mask), &Upsampler::Barycentric).unwrap_err();
    assert!(matches!(err, HierarchyError::MapRepeated { first: 1, second: 3, .. }), "{err}");
    coarse[3] = 999;
    let err = build_level(&input(&fine, &coarse, &faces, &mask), &Upsampler::Barycentric).unwrap_err();
    assert!(matches!(err, HierarchyError::MapOutOfRange { coarse_idx: 3, fine_idx: 999, .. }), "{err}");
    let coarse = grid_subset(N, 2);
    let err = build_level(&input(&fine, &coarse, &faces, &[true]), &Upsampler::Barycentric).unwrap_err();
    assert!(matches!(err, HierarchyError::MaskLength { mask: 1, poses: 3 }), "{err}");
    let err = build_level(&input(&fine, &coarse, &faces, &[false; 3]), &Upsampler::default()).unwrap_err();
    assert!(matches!(err, HierarchyError::NoTrainingPose), "{err}");
    let bad_faces = vec![[0, 1, 25]];
    let err = build_level(&input(&fine, &coarse, &bad_faces, &mask), &Upsampler::Barycentric).unwrap_err();
    assert!(matches!(err, HierarchyError::FaceOutOfRange { face: 0, vertex: 25, coarse_count: 25 }), "{err}");
    let zero_k = Upsampler::Fitted(FittedConfig::given(0, 0.1));
    assert!(matches!(
        build_level(&input(&fine, &coarse, &faces, &mask), &zero_k),
        Err(HierarchyError::BadOption { option: "neighbours", .. })
    ));
}

/// A "coarse" level equal to the fine one upsamples with the identity: zero error, and
/// the per-vertex map is all zeros.
#[test]
fn identity_level_has_zero_upsampling_error() {
    let mesh = bumpy_grid(5);
    let fine = bent_poses(&mesh, 3);
    let all: Vec<u32> = (0..25).collect();
    let level = build_level(&input(&fine, &all, &mesh.faces, &[true; 3]), &Upsampler::default()).unwrap();
    let e = upsampling_error(&fine, &level.up, &all, &[0, 1, 2]).unwrap();
    assert_eq!((e.mse, e.v2f), (0.0, Some(0.0)));
    assert!(e.vertex_mse.iter().all(|&v| v == 0.0));
}
