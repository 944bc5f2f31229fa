//! Applying a map to a pose set: subset mode reproduces a subset simplification exactly,
//! every simplified pose carries the simplified triangles and vertex count, labels come
//! along, greedy mode recovers a perturbed subset, and bad inputs are refused with the
//! offending indices.

use desal_map::{MapConfig, MapError, MapMode, VertexMap, apply_map, map_pose_set};
use desal_mesh::{Face, MeshError, PartLabels, PoseSet, TriMesh, Vec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A registered pose set over a 10×10 grid: pose 0 (the template) flat, the others
/// randomly displaced, plus four part labels by quadrant.
fn grid_pose_set(rng: &mut ChaCha8Rng, pose_count: usize) -> (PoseSet, PartLabels) {
    let (nx, ny) = (10u32, 10u32);
    let template: Vec<Vec3> =
        (0..nx * ny).map(|v| Vec3::new((v % nx) as f64, (v / nx) as f64, 0.0)).collect();
    let poses: Vec<Vec<Vec3>> = (0..pose_count)
        .map(|p| {
            if p == 0 {
                template.clone()
            } else {
                template.iter().map(|t| t + Vec3::new(rng.r#gen(), rng.r#gen(), rng.r#gen())).collect()
            }
        })
        .collect();
    let names = (0..pose_count).map(|p| format!("pose{p}")).collect();
    let pose_set = PoseSet::try_new(names, poses, desal_testdata::golden::grid_faces(nx, ny), 0).unwrap();
    let labels: Vec<u32> =
        (0..nx * ny).map(|v| u32::from(v % nx >= 5) + 2 * u32::from(v / nx >= 5)).collect();
    let labels = PartLabels::try_new(labels, ["a", "b", "c", "d"].map(String::from).to_vec()).unwrap();
    (pose_set, labels)
}

/// What a subset simplification (stage 3, half-edge collapses) hands over: kept original
/// vertices in some order, the template at those vertices, triangles over them.
fn subset_simplification(rng: &mut ChaCha8Rng, original_count: u32) -> (Vec<u32>, Vec<Face>) {
    let mut kept: Vec<u32> = (0..original_count).filter(|_| rng.gen_bool(0.3)).collect();
    // Stage 3 need not keep them in original order.
    kept.reverse();
    let n = kept.len() as u32;
    let faces = (0..n.saturating_sub(2)).map(|s| [s, s + 1, s + 2]).collect();
    (kept, faces)
}

#[test]
fn subset_mode_reproduces_the_subset_simplification_exactly() {
    let mut rng = ChaCha8Rng::seed_from_u64(10);
    let (poses, labels) = grid_pose_set(&mut rng, 4);
    let (kept, faces) = subset_simplification(&mut rng, poses.vertex_count() as u32);
    let simplified = TriMesh {
        positions: kept.iter().map(|&o| poses.template_positions()[o as usize]).collect(),
        faces: faces.clone(),
    };

    let out = map_pose_set(
        &MapConfig::default(),
        MapMode::Subset { kept_orig: &kept },
        &simplified,
        &poses,
        &labels,
    )
    .unwrap();

    assert_eq!(out.map.simp_to_orig, kept);
    // Applied to the template, the map gives stage 3's positions bit for bit.
    assert_eq!(out.poses.template_positions(), simplified.positions.as_slice());
    assert_eq!(out.report.displacement.max, 0.0);
    assert_eq!(out.poses.names, poses.names);
    assert_eq!(out.poses.template, poses.template);
    for (p, pose) in out.poses.poses.iter().enumerate() {
        assert_eq!(pose.len(), kept.len());
        for (simp_idx, &orig_idx) in kept.iter().enumerate() {
            assert_eq!(pose[simp_idx], poses.poses[p][orig_idx as usize]);
        }
    }
    assert_eq!(out.poses.faces, faces);
    for (simp_idx, &orig_idx) in kept.iter().enumerate() {
        assert_eq!(out.labels.labels[simp_idx], labels.labels[orig_idx as usize]);
    }
    assert_eq!(out.labels.names, labels.names);
    assert_eq!(out.report.simplified_vertices, kept.len());
    assert_eq!(out.report.original_vertices, 100);
    assert_eq!(out.report.poses, 4);
    assert_eq!(out.report.mode, "subset");
}

/// Greedy mode on the subset simplification with its positions jittered by less than
/// half the grid spacing: the map is the subset, every pose is registered through it,
/// and the displacement is the jitter.
#[test]
fn greedy_mode_recovers_a_jittered_subset() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let (poses, labels) = grid_pose_set(&mut rng, 3);
    let (kept, faces) = subset_simplification(&mut rng, poses.vertex_count() as u32);
    let jitter = Vec3::new(0.1, -0.2, 0.2);
    let simplified = TriMesh {
        positions: kept.iter().map(|&o| poses.template_positions()[o as usize] + jitter).collect(),
        faces,
    };

    let out = map_pose_set(&MapConfig::default(), MapMode::Greedy, &simplified, &poses, &labels).unwrap();

    assert_eq!(out.map.simp_to_orig, kept);
    // In greedy mode the simplified template is replaced by the mapped original vertices.
    for (simp_idx, &orig_idx) in kept.iter().enumerate() {
        assert_eq!(out.poses.template_positions()[simp_idx], poses.template_positions()[orig_idx as usize]);
    }
    assert!((out.report.displacement.mean - 0.3).abs() < 1e-12);
    assert!((out.report.displacement.max - 0.3).abs() < 1e-12);
    assert_eq!(out.report.mode, "greedy");
}

#[test]
fn every_simplified_pose_has_the_simplified_triangles() {
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let (poses, labels) = grid_pose_set(&mut rng, 5);
    let (kept, faces) = subset_simplification(&mut rng, poses.vertex_count() as u32);
    let map = VertexMap::from_subset(&kept, poses.vertex_count()).unwrap();
    let (simplified, simplified_labels) = apply_map(&poses, &labels, &faces, &map).unwrap();
    assert_eq!(simplified.pose_count(), 5);
    for p in 0..simplified.pose_count() {
        let mesh = simplified.pose_mesh(p);
        assert_eq!(mesh.faces, faces);
        assert_eq!(mesh.positions.len(), kept.len());
    }
    assert_eq!(simplified_labels.vertex_count(), kept.len());
}

/// A hand-made case with exact values: two poses of five vertices, keep 4, 0, 2.
#[test]
fn tiny_apply_with_exact_values() {
    let template: Vec<Vec3> = (0..5).map(|i| Vec3::new(i as f64, 0.0, 0.0)).collect();
    let moved: Vec<Vec3> = (0..5).map(|i| Vec3::new(i as f64, 10.0, 0.0)).collect();
    let poses = PoseSet::try_new(
        vec!["rest".into(), "moved".into()],
        vec![template, moved],
        vec![[0, 1, 2], [2, 3, 4]],
        0,
    )
    .unwrap();
    let labels = PartLabels::try_new(vec![0, 0, 1, 1, 2], vec!["x".into(), "y".into(), "z".into()]).unwrap();
    let map = VertexMap::from_subset(&[4, 0, 2], 5).unwrap();
    let (simplified, simplified_labels) = apply_map(&poses, &labels, &[[0, 1, 2]], &map).unwrap();
    assert_eq!(
        simplified.poses[1],
        vec![Vec3::new(4.0, 10.0, 0.0), Vec3::new(0.0, 10.0, 0.0), Vec3::new(2.0, 10.0, 0.0)]
    );
    assert_eq!(simplified_labels.labels, vec![2, 0, 1]);
}

#[test]
fn empty_parts_are_reported() {
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    let (poses, labels) = grid_pose_set(&mut rng, 2);
    // Keep only vertices of the first row (x < 5 → part 0, x ≥ 5 → part 1).
    let kept: Vec<u32> = (0..10).collect();
    let simplified = TriMesh {
        positions: kept.iter().map(|&o| poses.template_positions()[o as usize]).collect(),
        faces: vec![[0, 1, 2]],
    };
    let out = map_pose_set(
        &MapConfig::default(),
        MapMode::Subset { kept_orig: &kept },
        &simplified,
        &poses,
        &labels,
    )
    .unwrap();
    assert_eq!(out.report.empty_parts, vec![2, 3]);
    assert!(out.report.to_string().contains("parts without vertices: [2, 3]"));
}

#[test]
fn bad_inputs_are_refused_with_their_indices() {
    let mut rng = ChaCha8Rng::seed_from_u64(14);
    let (poses, labels) = grid_pose_set(&mut rng, 2);
    let map = VertexMap::from_subset(&[5, 6, 7], 100).unwrap();

    assert_eq!(
        apply_map(&poses, &labels, &[[0, 1, 3]], &map).unwrap_err(),
        MapError::FaceIndexOutOfRange { face: 0, simp_idx: 3, simplified_count: 3 }
    );

    let short_labels = PartLabels::try_new(vec![0; 99], labels.names.clone()).unwrap();
    assert_eq!(
        apply_map(&poses, &short_labels, &[[0, 1, 2]], &map).unwrap_err(),
        MapError::Mesh(MeshError::LabelCountMismatch { labels: 99, vertices: 100 })
    );

    // A map made for a bigger mesh, bypassing validation through the public field.
    let foreign = VertexMap { simp_to_orig: vec![0, 100, 2] };
    assert_eq!(
        apply_map(&poses, &labels, &[[0, 1, 2]], &foreign).unwrap_err(),
        MapError::OrigIndexOutOfRange { simp_idx: 1, orig_idx: 100, original_count: 100 }
    );
    let repeated = VertexMap { simp_to_orig: vec![9, 8, 9] };
    assert_eq!(
        apply_map(&poses, &labels, &[[0, 1, 2]], &repeated).unwrap_err(),
        MapError::DuplicateOrigIndex { orig_idx: 9, first_simp_idx: 0, second_simp_idx: 2 }
    );

    // No triangles left: refused by the pose set itself.
    assert!(matches!(apply_map(&poses, &labels, &[], &map), Err(MapError::Mesh(MeshError::Empty { .. }))));

    // Subset mode: kept indices that do not match the simplified vertex count.
    let simplified = TriMesh { positions: vec![Vec3::zeros(); 4], faces: vec![[0, 1, 2]] };
    assert_eq!(
        map_pose_set(
            &MapConfig::default(),
            MapMode::Subset { kept_orig: &[1, 2, 3] },
            &simplified,
            &poses,
            &labels
        )
        .unwrap_err(),
        MapError::MapLengthMismatch { positions: 4, map: 3 }
    );
}

/// `map_template` is `map_pose_set` without the simplified poses: the same map, labels
/// and report but for the apply time, in both modes (greedy from a perturbed template),
/// and the same error for an empty triangle list.
#[test]
fn map_template_is_map_pose_set_without_the_poses() {
    use desal_map::map_template;
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let (poses, labels) = grid_pose_set(&mut rng, 5);
    let (kept, faces) = subset_simplification(&mut rng, poses.vertex_count() as u32);
    let simplified = TriMesh {
        positions: kept
            .iter()
            .map(|&o| poses.template_positions()[o as usize] + Vec3::new(0.01, 0.0, 0.0))
            .collect(),
        faces,
    };
    for mode in [MapMode::Subset { kept_orig: &kept }, MapMode::Greedy] {
        let config = MapConfig::default();
        let full = map_pose_set(&config, mode, &simplified, &poses, &labels).unwrap();
        let mut only = map_template(&config, mode, &simplified, &poses, &labels).unwrap();
        assert_eq!(only.map, full.map, "{}", mode.name());
        assert_eq!(only.labels, full.labels);
        only.report.map_seconds = full.report.map_seconds;
        only.report.apply_seconds = full.report.apply_seconds;
        assert_eq!(only.report, full.report);
    }
    let no_faces = TriMesh { faces: Vec::new(), ..simplified };
    let mode = MapMode::Subset { kept_orig: &kept };
    assert_eq!(
        map_template(&MapConfig::default(), mode, &no_faces, &poses, &labels).unwrap_err(),
        map_pose_set(&MapConfig::default(), mode, &no_faces, &poses, &labels).unwrap_err(),
    );
}
