//! Forward kinematics, skinning, pose resolution, part cleanup and the intersection test
//! on tiny hand-built skeletons and meshes with exact expectations.

use std::collections::BTreeMap;
use std::path::Path;

use desal_mesh::math::UnitQuat;
use desal_mesh::{PartLabels, Vec3};
use desal_sample::poses::{Axis, PoseSpec, both, local_rotations, turn};
use desal_sample::quality::{count_self_intersections, segment_crosses_triangle};
use desal_sample::skeleton::Bone;
use desal_sample::{SampleError, Skeleton, SkinWeights, skin};
use proptest::prelude::*;

/// root at the origin pointing up (+Y) to (0,1,0); `arm` from (0,1,0) to (1,1,0);
/// `hand` from (1,1,0) to (2,1,0); `leg` from the origin down to (0,-1,0).
fn toy_skeleton() -> Skeleton {
    let bone = |name: &str, parent, head: [f64; 3], tail: [f64; 3]| Bone {
        name: name.to_owned(),
        parent,
        head: Vec3::from(head),
        tail: Vec3::from(tail),
    };
    Skeleton {
        bones: vec![
            bone("root", None, [0.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
            bone("arm", Some(0), [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]),
            bone("hand", Some(1), [1.0, 1.0, 0.0], [2.0, 1.0, 0.0]),
            bone("leg", Some(0), [0.0, 0.0, 0.0], [0.0, -1.0, 0.0]),
        ],
    }
}

fn weights_of(lists: &[(&str, &[(u32, f64)])], skeleton: &Skeleton, n: usize) -> SkinWeights {
    let map: BTreeMap<String, Vec<(u32, f64)>> =
        lists.iter().map(|(b, l)| (b.to_string(), l.to_vec())).collect();
    SkinWeights::from_bone_lists(skeleton, &map, n).unwrap().0
}

fn assert_close(a: &Vec3, b: &Vec3) {
    assert!((a - b).norm() < 1e-12, "{a:?} != {b:?}");
}

#[test]
fn turning_a_parent_carries_its_children_about_its_head() {
    let skeleton = toy_skeleton();
    let mut local = vec![UnitQuat::identity(); 4];
    // +90° about Z at the arm's head (0,1,0): the arm, pointing +X, now points +Y.
    local[1] = UnitQuat::from_scaled_axis(Vec3::z() * std::f64::consts::FRAC_PI_2);
    let world = skeleton.forward_kinematics(&local);
    assert_close(&world[2].apply(&Vec3::new(2.0, 1.0, 0.0)), &Vec3::new(0.0, 3.0, 0.0));
    assert_close(&world[1].apply(&Vec3::new(1.0, 1.0, 0.0)), &Vec3::new(0.0, 2.0, 0.0));
    // Siblings and the root are untouched, exactly.
    assert_eq!(world[0], desal_sample::BoneTransform::identity());
    assert_eq!(world[3], desal_sample::BoneTransform::identity());
}

#[test]
fn a_child_turn_composes_after_its_parents() {
    let skeleton = toy_skeleton();
    let mut local = vec![UnitQuat::identity(); 4];
    local[1] = UnitQuat::from_scaled_axis(Vec3::z() * std::f64::consts::FRAC_PI_2);
    local[2] = UnitQuat::from_scaled_axis(Vec3::z() * std::f64::consts::FRAC_PI_2);
    let world = skeleton.forward_kinematics(&local);
    // Arm up to (0,2,0); the hand turns another 90° about its moved head: points -X.
    assert_close(&world[2].apply(&Vec3::new(2.0, 1.0, 0.0)), &Vec3::new(-1.0, 2.0, 0.0));
}

#[test]
fn skinning_with_identity_transforms_returns_the_input_bit_for_bit() {
    let skeleton = toy_skeleton();
    // Weights that do not sum to exactly 1 after normalisation rounding.
    let w = weights_of(&[("arm", &[(0, 0.1), (1, 0.7)]), ("hand", &[(0, 0.2), (1, 0.3)])], &skeleton, 2);
    let rest = vec![Vec3::new(0.1, -0.0, 1e-300), Vec3::new(1.0 / 3.0, 2.0 / 7.0, -5.5)];
    let world = skeleton.forward_kinematics(&[UnitQuat::identity(); 4]);
    let posed = skin(&rest, &w, &world);
    for (p, q) in rest.iter().zip(&posed) {
        for k in 0..3 {
            assert_eq!(p[k].to_bits(), q[k].to_bits());
        }
    }
}

#[test]
fn a_turned_bone_moves_only_vertices_it_or_its_descendants_influence() {
    let skeleton = toy_skeleton();
    // v0 on the root, v1 on the leg, v2 on the hand, v3 half arm half root.
    let w = weights_of(
        &[("root", &[(0, 1.0), (3, 0.5)]), ("leg", &[(1, 1.0)]), ("hand", &[(2, 1.0)]), ("arm", &[(3, 0.5)])],
        &skeleton,
        4,
    );
    let rest: Vec<Vec3> = (0..4).map(|i| Vec3::new(1.5, 1.0 + i as f64 * 0.1, 0.25)).collect();
    let mut local = vec![UnitQuat::identity(); 4];
    local[1] = UnitQuat::from_scaled_axis(Vec3::y() * 0.3);
    let posed = skin(&rest, &w, &skeleton.forward_kinematics(&local));
    assert_eq!(posed[0], rest[0]);
    assert_eq!(posed[1], rest[1]);
    assert_ne!(posed[2], rest[2], "the hand is a child of the turned arm");
    // Half weight on the arm: exactly the midpoint of the two rigid images.
    let full = skeleton.forward_kinematics(&local)[1].apply(&rest[3]);
    assert_close(&posed[3], &((full + rest[3]) / 2.0));
}

#[test]
fn weights_are_summed_normalised_and_unweighted_vertices_go_to_the_root() {
    let skeleton = toy_skeleton();
    let map: BTreeMap<String, Vec<(u32, f64)>> = [
        ("arm".to_owned(), vec![(0, 1.0), (0, 1.0), (9, 1.0), (1, 0.0)]),
        ("hand".to_owned(), vec![(0, 2.0)]),
    ]
    .into();
    let (w, report) = SkinWeights::from_bone_lists(&skeleton, &map, 3).unwrap();
    assert_eq!(w.of(0).collect::<Vec<_>>(), vec![(1, 0.5), (2, 0.5)]);
    assert_eq!(w.of(1).collect::<Vec<_>>(), vec![(0, 1.0)]);
    assert_eq!(report.unweighted_vertices, vec![1, 2]);
    assert_eq!(report.entries_outside, 1);
    assert_eq!(report.zero_entries, 1);
    // A 0.5/0.5 tie goes to the lower bone index.
    assert_eq!(w.dominant_bone(0), 1);
}

#[test]
fn weights_naming_an_unknown_bone_are_refused() {
    let map: BTreeMap<String, Vec<(u32, f64)>> = [("tail".to_owned(), vec![(0, 1.0)])].into();
    let err = SkinWeights::from_bone_lists(&toy_skeleton(), &map, 1).unwrap_err();
    assert!(matches!(err, SampleError::UnknownWeightBone { ref bone } if bone == "tail"), "{err}");
}

#[test]
fn a_positive_hinge_turn_bends_the_joint_further() {
    let mut skeleton = toy_skeleton();
    // Bend the hand 45° down at rest so the arm–hand hinge is defined.
    skeleton.bones[2].tail = Vec3::new(2.0, 0.0, 0.0);
    let pose = PoseSpec::new("bend", vec![turn("hand", Axis::Hinge, 30.0)]);
    let world = skeleton.forward_kinematics(&local_rotations(&skeleton, &pose).unwrap());
    let tip = world[2].apply(&skeleton.bones[2].tail) - skeleton.bones[2].head;
    let bend = tip.angle(&skeleton.direction(1)).to_degrees();
    assert!((bend - 75.0).abs() < 1e-9, "bend {bend}");
}

#[test]
fn mirrored_turns_give_mirrored_motion() {
    // A symmetric skeleton: left arm to +X, right arm to -X, both slightly forward.
    let bone = |name: &str, parent, tail: [f64; 3]| Bone {
        name: name.to_owned(),
        parent,
        head: Vec3::zeros(),
        tail: Vec3::from(tail),
    };
    let skeleton = Skeleton {
        bones: vec![
            bone("root", None, [0.0, 1.0, 0.0]),
            bone("L", Some(0), [1.0, -0.5, 0.3]),
            bone("R", Some(0), [-1.0, -0.5, 0.3]),
        ],
    };
    let mirror = |p: Vec3| Vec3::new(-p.x, p.y, p.z);
    for axis in [Axis::X, Axis::Y, Axis::Z] {
        let pose = PoseSpec::new("p", both("L", "R", axis, 37.0));
        let world = skeleton.forward_kinematics(&local_rotations(&skeleton, &pose).unwrap());
        let left_tip = world[1].apply(&skeleton.bones[1].tail);
        let right_tip = world[2].apply(&skeleton.bones[2].tail);
        assert_close(&mirror(left_tip), &right_tip);
    }
}

#[test]
fn a_pose_naming_an_unknown_bone_is_refused() {
    let pose = PoseSpec::new("wave", vec![turn("wing", Axis::X, 10.0)]);
    let err = local_rotations(&toy_skeleton(), &pose).unwrap_err();
    assert!(err.to_string().contains("'wave'") && err.to_string().contains("'wing'"), "{err}");
}

#[test]
fn a_hinge_on_a_straight_joint_is_refused() {
    let pose = PoseSpec::new("p", vec![turn("hand", Axis::Hinge, 10.0)]);
    let err = local_rotations(&toy_skeleton(), &pose).unwrap_err();
    assert!(matches!(err, SampleError::NoHinge { .. }), "{err}");
}

#[test]
fn rig_errors_name_the_bone() {
    let path = Path::new("rig.json");
    let rig = |text: &str| desal_sample::source::parse_rig(text, path);
    let joint = r#"{"cube_name": "joint-a"}"#;
    let one = |name: &str, parent: &str| {
        format!(r#""{name}": {{"parent": "{parent}", "head": {joint}, "tail": {joint}}}"#)
    };
    assert!(rig(&format!("{{{}}}", one("a", ""))).is_ok());
    let assets = |text: &str| desal_sample::SourceAssets {
        base: desal_mesh::TriMesh { positions: vec![Vec3::zeros()], faces: vec![] },
        rig: rig(text).unwrap(),
        weights: BTreeMap::new(),
        groups: [("joint-a".to_owned(), vec![[0, 0]])].into(),
        uvs: desal_sample::rig::ObjUvs { uvs: vec![], triangles: vec![], vertex_triangles: vec![] },
        face_units: BTreeMap::new(),
    };
    let err =
        Skeleton::from_assets(&assets(&format!("{{{}, {}}}", one("a", ""), one("b", "zz")))).unwrap_err();
    assert!(matches!(err, SampleError::UnknownParent { ref bone, .. } if bone == "b"), "{err}");
    let err =
        Skeleton::from_assets(&assets(&format!("{{{}, {}}}", one("a", "b"), one("b", "a")))).unwrap_err();
    assert!(matches!(err, SampleError::NotATree { roots: 0, unreachable: 2 }), "{err}");
    let mut missing = assets(&format!("{{{}}}", one("a", "")));
    missing.groups.clear();
    let err = Skeleton::from_assets(&missing).unwrap_err();
    assert!(matches!(err, SampleError::MissingJointGroup { ref group, .. } if group == "joint-a"), "{err}");
}

#[test]
fn a_segment_through_a_triangle_crosses_it_and_one_beside_it_does_not() {
    let (x, y, z) = (Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0));
    let through = (Vec3::new(0.2, 0.2, -1.0), Vec3::new(0.2, 0.2, 1.0));
    assert!(segment_crosses_triangle(&through.0, &through.1, &x, &y, &z));
    let beside = (Vec3::new(0.8, 0.8, -1.0), Vec3::new(0.8, 0.8, 1.0));
    assert!(!segment_crosses_triangle(&beside.0, &beside.1, &x, &y, &z));
    let short = (Vec3::new(0.2, 0.2, 0.5), Vec3::new(0.2, 0.2, 1.0));
    assert!(!segment_crosses_triangle(&short.0, &short.1, &x, &y, &z));
}

#[test]
fn two_interlocked_triangles_intersect_and_a_cube_does_not() {
    // Triangle A in z = 0; triangle B in x = 0.25 piercing A's interior with one edge.
    let positions = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.25, 0.25, -1.0),
        Vec3::new(0.25, 0.25, 1.0),
        Vec3::new(0.25, 3.0, 0.0),
    ];
    // B's edge 3–4 pierces A; A's edge 0–1 (y = 0) misses B (B spans y ≥ 0.25); A's edge
    // 1–2 passes x = 0.25 at y = 0.75, inside B. Two pairs.
    assert_eq!(count_self_intersections(&positions, &[[0, 1, 2], [3, 4, 5]]), 2);
    // A closed cube: every edge is tested against the faces it does not touch.
    let cube: Vec<Vec3> =
        (0..8).map(|i| Vec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, (i >> 2) as f64)).collect();
    let quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]];
    let faces: Vec<[u32; 3]> = quads.iter().flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]).collect();
    assert_eq!(count_self_intersections(&cube, &faces), 0);
    // Pushing one corner through the opposite face makes its edges pierce it.
    let mut dented = cube.clone();
    dented[7] = Vec3::new(0.5, 0.5, -0.5);
    assert!(count_self_intersections(&dented, &faces) > 0);
}

#[test]
fn stray_islands_join_the_part_around_them() {
    // A 4x1 strip of quads (vertices 0..5 bottom, 5..10 top); part 0 everywhere except
    // a part-1 island at vertex 7 and a part-1 main piece at 4 and 9.
    let mut faces = Vec::new();
    for i in 0..4u32 {
        faces.push([i, i + 1, i + 6]);
        faces.push([i, i + 6, i + 5]);
    }
    let ids = vec![0, 0, 0, 0, 1, 0, 0, 1, 0, 1];
    let mut labels = PartLabels::try_new(ids, vec!["a".into(), "b".into()]).unwrap();
    assert_eq!(desal_sample::parts::part_pieces(&labels, &faces), vec![1, 2]);
    assert_eq!(desal_sample::parts::absorb_stray_pieces(&mut labels, &faces), 1);
    assert_eq!(labels.labels, vec![0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);
    assert_eq!(desal_sample::parts::part_pieces(&labels, &faces), vec![1, 1]);
}

proptest! {
    /// Rigid bodies stay rigid: a vertex bound to one bone keeps its distance to that
    /// bone's head whatever the turns.
    #[test]
    fn single_bone_vertices_move_rigidly(
        angles in proptest::collection::vec(-3.0f64..3.0, 12),
        p in proptest::array::uniform3(-2.0f64..2.0),
    ) {
        let skeleton = toy_skeleton();
        let local: Vec<UnitQuat> = (0..4)
            .map(|b| UnitQuat::from_scaled_axis(Vec3::new(angles[3 * b], angles[3 * b + 1], angles[3 * b + 2])))
            .collect();
        let world = skeleton.forward_kinematics(&local);
        let w = weights_of(&[("hand", &[(0, 1.0)])], &skeleton, 1);
        let rest = Vec3::from(p);
        let posed = skin(&[rest], &w, &world)[0];
        let head = world[2].apply(&skeleton.bones[2].head);
        prop_assert!(((posed - head).norm() - (rest - skeleton.bones[2].head).norm()).abs() < 1e-9);
    }
}
