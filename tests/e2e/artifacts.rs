//! Artifacts: frozen fixtures of every format version still load, and `inspect`
//! describes them.

use std::path::Path;

use desal_io::artifact::{
    self, FitV1, FloorV1, HierarchyLevelV1, LabelsV1, MapV1, PoseSetV2, SaliencyV1, SimplifiedV1,
};

use crate::support::desal;

fn fixture(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures").join(name)
}

/// The v1 fixtures were written once by `write_fixtures` below and committed; a change
/// of the byte format (bincode config, field order, envelope) breaks this test.
#[test]
fn frozen_v1_fixtures_still_load() {
    // Pose set 1 (no groups) is still read, as a pose set without groups.
    let (producer, poses, _) = artifact::read_artifact::<PoseSetV2>(&fixture("pose-set-v1.dsa")).unwrap();
    assert_eq!(producer.stage, "ingest");
    assert_eq!(poses, PoseSetV2 { groups: vec![], ..fixture_pose_set() });
    assert_eq!(poses.to_pose_set().unwrap().groups, None);
    let (_, poses, _) = artifact::read_artifact::<PoseSetV2>(&fixture("pose-set-v2.dsa")).unwrap();
    assert_eq!(poses, fixture_pose_set());
    assert_eq!(poses.to_pose_set().unwrap().groups, Some(vec![0, 1]));
    let (_, labels, _) = artifact::read_artifact::<LabelsV1>(&fixture("labels-v1.dsa")).unwrap();
    assert_eq!(labels, LabelsV1 { names: vec!["lower".into(), "upper".into()], labels: vec![0, 0, 1, 1] });
    let (producer, fit, _) = artifact::read_artifact::<FitV1>(&fixture("fit-v1.dsa")).unwrap();
    assert_eq!(producer.stage, "fit");
    assert_eq!(fit, fixture_fit());
    let (_, saliency, _) = artifact::read_artifact::<SaliencyV1>(&fixture("saliency-v1.dsa")).unwrap();
    assert_eq!(saliency, fixture_saliency());
    let (_, simplified, _) = artifact::read_artifact::<SimplifiedV1>(&fixture("simplified-v1.dsa")).unwrap();
    assert_eq!(simplified, fixture_simplified());
    let (_, map, _) = artifact::read_artifact::<MapV1>(&fixture("map-v1.dsa")).unwrap();
    assert_eq!(map, fixture_map());
    let (producer, level, _) =
        artifact::read_artifact::<HierarchyLevelV1>(&fixture("hierarchy-level-v1.dsa")).unwrap();
    assert_eq!(producer.stage, "hierarchy-1");
    assert_eq!(level, fixture_hierarchy_level());
    let (producer, floor, _) = artifact::read_artifact::<FloorV1>(&fixture("floor-v1.dsa")).unwrap();
    assert_eq!(producer.stage, "floor");
    assert_eq!(floor, fixture_floor());
}

/// A floor of the fixture pose set's one non-template pose.
fn fixture_floor() -> FloorV1 {
    FloorV1 {
        model: "scape".into(),
        poses: 1,
        folds: 2,
        in_sample_v2v: 0.0625,
        in_sample_v2f: 0.03125,
        held_out_v2v: 0.25,
        held_out_v2f: 0.125,
    }
}

/// A level of the fixture pose set: vertices 0, 1, 2 kept (one triangle); vertex 3 is
/// upsampled as 1/4, 1/2, 1/4 of them.
fn fixture_hierarchy_level() -> HierarchyLevelV1 {
    HierarchyLevelV1 {
        fine_vertices: 4,
        coarse_to_fine: vec![0, 1, 2],
        coarse_to_orig: vec![0, 1, 2],
        faces: vec![[0, 1, 2]],
        upsampler: "barycentric".into(),
        up_row: vec![0, 1, 2, 3, 3, 3],
        up_col: vec![0, 1, 2, 0, 1, 2],
        up_data: vec![1.0, 1.0, 1.0, 0.25, 0.5, 0.25],
    }
}

/// Stage 1 on the fixture pose set: pose 1 is pose 0 moved by +0.5 along x.
fn fixture_fit() -> FitV1 {
    let identity = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    FitV1 {
        model: "rigid".into(),
        pose_names: vec!["rest".into(), "moved".into()],
        part_names: vec!["lower".into(), "upper".into()],
        template: 0,
        vertex_count: 4,
        linear: vec![identity; 4],
        translation: vec![[0.0; 3], [0.0; 3], [0.5, 0.0, 0.0], [0.5, 0.0, 0.0]],
        rms: vec![0.0, 0.0, 0.25, 0.125],
        mean: vec![0.0, 0.0, 0.25, 0.125],
        max: vec![0.0, 0.0, 0.5, 0.25],
        residuals: vec![0.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.25, 0.0],
        worst_parts: vec![(0, 0.25, 0.5, 1), (1, 0.125, 0.25, 1)],
        worst_poses: vec![(1, 0.1875, 0.5, 0), (0, 0.0, 0.0, 0)],
    }
}

fn fixture_saliency() -> SaliencyV1 {
    SaliencyV1 {
        saliency: vec![0.0, 1.0, 0.5, 0.0],
        weights: vec![0.05, 1.0, 0.525, 0.05],
        raw: vec![0.0, 0.5, 0.25, 0.0],
        normaliser: 0.5,
        distance: "plain".into(),
        normalisation: "max".into(),
        weight_floor: 0.05,
        poses_used: vec!["moved".into()],
        poses_excluded: vec![],
        rigid: false,
    }
}

fn fixture_simplified() -> SimplifiedV1 {
    SimplifiedV1 {
        positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.25, 0.5, 0.5]],
        faces: vec![[0, 1, 2]],
        simp_to_orig: vec![Some(0), Some(1), None],
        placement: "optimal".into(),
        input_vertices: 4,
        input_faces: 4,
        collapses: 1,
        stop: "no-valid-collapse".into(),
        max_error: 0.125,
        mean_error: 0.125,
        edge_length_mean: 0.875,
        edge_length_variance: 0.0625,
    }
}

fn fixture_map() -> MapV1 {
    MapV1 {
        simp_to_orig: vec![0, 1, 2],
        faces: vec![[0, 1, 2]],
        mode: "greedy".into(),
        displacement_mean: 0.25,
        displacement_max: 0.75,
    }
}

fn fixture_pose_set() -> PoseSetV2 {
    PoseSetV2 {
        names: vec!["rest".into(), "moved".into()],
        template: 0,
        faces: vec![[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]],
        positions: vec![
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            vec![[0.5, 0.0, 0.0], [1.5, 0.0, 0.0], [0.5, 1.0, 0.0], [0.5, 0.0, 1.0]],
        ],
        groups: vec![0, 1],
    }
}

/// Regenerates the fixtures; run by hand only when adding a new format version:
/// `cargo test --test e2e write_fixtures -- --ignored`.
#[test]
#[ignore]
fn write_fixtures() {
    let producer = artifact::Producer {
        stage: "ingest".into(),
        stage_version: 1,
        tool_version: "0.1.0".into(),
        parameters: "{}".into(),
        inputs: vec![],
    };
    // Pose set 1 is frozen: pose-set-v1.dsa was written by the pose-set-1 build.
    artifact::write_artifact(&fixture("pose-set-v2.dsa"), &producer, &fixture_pose_set()).unwrap();
    let labels = LabelsV1 { names: vec!["lower".into(), "upper".into()], labels: vec![0, 0, 1, 1] };
    let producer = artifact::Producer { stage: "labels".into(), ..producer };
    artifact::write_artifact(&fixture("labels-v1.dsa"), &producer, &labels).unwrap();
    let producer = artifact::Producer { stage: "fit".into(), ..producer };
    artifact::write_artifact(&fixture("fit-v1.dsa"), &producer, &fixture_fit()).unwrap();
    let producer = artifact::Producer { stage: "saliency".into(), ..producer };
    artifact::write_artifact(&fixture("saliency-v1.dsa"), &producer, &fixture_saliency()).unwrap();
    let producer = artifact::Producer { stage: "simplify".into(), ..producer };
    artifact::write_artifact(&fixture("simplified-v1.dsa"), &producer, &fixture_simplified()).unwrap();
    let producer = artifact::Producer { stage: "map".into(), ..producer };
    artifact::write_artifact(&fixture("map-v1.dsa"), &producer, &fixture_map()).unwrap();
    let producer = artifact::Producer { stage: "hierarchy-1".into(), ..producer };
    let level = fixture_hierarchy_level();
    artifact::write_artifact(&fixture("hierarchy-level-v1.dsa"), &producer, &level).unwrap();
    let producer = artifact::Producer { stage: "floor".into(), ..producer };
    artifact::write_artifact(&fixture("floor-v1.dsa"), &producer, &fixture_floor()).unwrap();
}

#[test]
fn inspect_describes_an_artifact_and_refuses_a_foreign_file() {
    let out = desal(&["inspect", fixture("pose-set-v1.dsa").to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success());
    assert!(
        text.contains("pose-set (format version 1)") && text.contains("poses 2, vertices 4, faces 4"),
        "{text}"
    );
    let out = desal(&["inspect", fixture("pose-set-v2.dsa").to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("pose-set (format version 2)") && text.contains("groups 2"), "{text}");
    for kind in ["labels", "fit", "saliency", "simplified", "map", "hierarchy-level", "floor"] {
        let out = desal(&["inspect", fixture(&format!("{kind}-v1.dsa")).to_str().unwrap()]);
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success() && text.contains(&format!("{kind} (format version 1)")),
            "{kind}: {text}"
        );
    }
    let out = desal(&["inspect", file!()]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a desal artifact"));
}
