//! Artifacts: frozen fixtures of every format version still load, and `inspect`
//! describes them.

use std::path::Path;

use desal_io::artifact::{self, LabelsV1, PoseSetV1};

use crate::support::desal;

fn fixture(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures").join(name)
}

/// The v1 fixtures were written once by `write_fixtures` below and committed; a change
/// of the byte format (bincode config, field order, envelope) breaks this test.
#[test]
fn frozen_v1_fixtures_still_load() {
    let (producer, poses, _) = artifact::read_artifact::<PoseSetV1>(&fixture("pose-set-v1.dsa")).unwrap();
    assert_eq!(producer.stage, "ingest");
    assert_eq!(poses, fixture_pose_set());
    let (_, labels, _) = artifact::read_artifact::<LabelsV1>(&fixture("labels-v1.dsa")).unwrap();
    assert_eq!(labels, LabelsV1 { names: vec!["lower".into(), "upper".into()], labels: vec![0, 0, 1, 1] });
}

fn fixture_pose_set() -> PoseSetV1 {
    PoseSetV1 {
        names: vec!["rest".into(), "moved".into()],
        template: 0,
        faces: vec![[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]],
        positions: vec![
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            vec![[0.5, 0.0, 0.0], [1.5, 0.0, 0.0], [0.5, 1.0, 0.0], [0.5, 0.0, 1.0]],
        ],
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
    artifact::write_artifact(&fixture("pose-set-v1.dsa"), &producer, &fixture_pose_set()).unwrap();
    let labels = LabelsV1 { names: vec!["lower".into(), "upper".into()], labels: vec![0, 0, 1, 1] };
    let producer = artifact::Producer { stage: "labels".into(), ..producer };
    artifact::write_artifact(&fixture("labels-v1.dsa"), &producer, &labels).unwrap();
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
    let out = desal(&["inspect", file!()]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("not a desal artifact"));
}
