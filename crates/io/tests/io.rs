//! Round trips and refusals of every format desal-io reads and writes.

use std::path::PathBuf;

use desal_io::artifact::{self, LabelsV1, PoseSetV2, Producer};
use desal_io::ply::{PlyEncoding, PlyWriteOptions, read_ply_full, write_ply};
use desal_io::{IoError, read_mesh};
use desal_mesh::{PartLabels, PoseSet, TriMesh, Vec3};

fn scape_dir() -> Option<PathBuf> {
    desal_testdata::scape_dir()
}

fn tetra() -> TriMesh {
    TriMesh {
        positions: vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.5),
        ],
        faces: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    }
}

#[test]
fn ply_round_trips_in_every_encoding_with_extras() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = tetra();
    for encoding in [PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian, PlyEncoding::BinaryBigEndian] {
        let path = dir.path().join(format!("{encoding:?}.ply"));
        let options = PlyWriteOptions {
            encoding,
            colors: Some(vec![[255, 0, 0], [0, 255, 0], [0, 0, 255], [1, 2, 3]]),
            scalars: vec![("saliency".into(), vec![0.0, 0.25, 0.5, 1.0])],
            comments: vec!["test".into()],
        };
        write_ply(&path, &mesh, &options).unwrap();
        let back = read_ply_full(&path).unwrap();
        assert_eq!(back.mesh, mesh, "{encoding:?}");
        let saliency = back.scalars.iter().find(|(n, _)| n == "saliency").expect("saliency property");
        assert_eq!(saliency.1, vec![0.0, 0.25, 0.5, 1.0]);
        // red/green/blue are read back as extra scalars too, in header order.
        assert_eq!(back.scalars[0].0, "red");
        assert_eq!(back.scalars[0].1, vec![255.0, 0.0, 0.0, 1.0]);
    }
}

#[test]
fn truncated_binary_ply_is_refused_with_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.ply");
    write_ply(&path, &tetra(), &PlyWriteOptions::default()).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    std::fs::write(&path, &bytes[..bytes.len() - 7]).unwrap();
    let err = read_mesh(&path).unwrap_err();
    let text = err.to_string();
    assert!(matches!(err, IoError::BadMesh { .. }), "{text}");
    assert!(text.contains("t.ply") && text.contains("face"), "{text}");
}

#[test]
fn data_after_the_last_element_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    for ascii in [false, true] {
        let path = dir.path().join("t.ply");
        let encoding = if ascii { PlyEncoding::Ascii } else { PlyEncoding::BinaryLittleEndian };
        write_ply(&path, &tetra(), &PlyWriteOptions { encoding, ..PlyWriteOptions::default() }).unwrap();
        let mut bytes = std::fs::read(&path).unwrap();
        bytes.extend_from_slice(b"\n \n");
        std::fs::write(&path, &bytes).unwrap();
        // Trailing whitespace is harmless in ASCII, not in binary.
        assert_eq!(read_mesh(&path).is_ok(), ascii, "ascii {ascii}");
        bytes.extend_from_slice(b"garbage");
        std::fs::write(&path, &bytes).unwrap();
        let text = read_mesh(&path).unwrap_err().to_string();
        assert!(text.contains("t.ply") && text.contains("follow the last element"), "{text}");
    }
}

#[test]
fn non_mesh_and_point_cloud_files_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let junk = dir.path().join("junk.ply");
    std::fs::write(&junk, b"hello world\n").unwrap();
    assert!(matches!(read_mesh(&junk).unwrap_err(), IoError::BadMesh { .. }));
    let cloud = dir.path().join("cloud.ply");
    std::fs::write(&cloud, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n").unwrap();
    assert!(read_mesh(&cloud).unwrap_err().to_string().contains("no 'face' element"));
    let other = dir.path().join("mesh.stl");
    std::fs::write(&other, b"solid").unwrap();
    assert!(matches!(read_mesh(&other).unwrap_err(), IoError::UnsupportedFormat { .. }));
}

#[test]
fn ply_with_nan_or_bad_index_names_the_element() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nan.ply");
    let header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    // NaN cannot be spelled in ASCII PLY; write it in binary.
    let mut mesh = tetra();
    mesh.positions[1].y = f64::NAN;
    write_ply(&path, &mesh, &PlyWriteOptions::default()).unwrap();
    let text = read_mesh(&path).unwrap_err().to_string();
    assert!(text.contains("nan.ply") && text.contains("vertex 1"), "{text}");
    std::fs::write(&path, format!("{header}0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n")).unwrap();
    let text = read_mesh(&path).unwrap_err().to_string();
    assert!(text.contains("face 0") && text.contains("vertex 7"), "{text}");
}

#[test]
fn obj_quads_and_ngons_are_fan_triangulated_in_vertex_order() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("q.obj");
    std::fs::write(
        &path,
        "# quad and pentagon\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 2 0\nvn 0 0 1\nvt 0 0\nf 1/1/1 2/1/1 3/1/1 4/1/1\nf -5 -4 -3 -1 -2\n",
    )
    .unwrap();
    let mesh = read_mesh(&path).unwrap();
    assert_eq!(mesh.vertex_count(), 5);
    assert_eq!(mesh.faces, vec![[0, 1, 2], [0, 2, 3], [0, 1, 2], [0, 2, 4], [0, 4, 3]]);
    std::fs::write(&path, "v 0 0 0\nf 1 2 x\n").unwrap();
    let text = read_mesh(&path).unwrap_err().to_string();
    assert!(text.contains("q.obj:2"), "{text}");
}

#[test]
fn off_polygons_are_fan_triangulated_and_colours_and_comments_ignored() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.off");
    // CGAL's layout, a comment, a vertex split over two lines, a face with a colour.
    std::fs::write(
        &path,
        "OFF\n5 2 0\n# vertices\n0 0 0\n1 0 0\n1 1\n0\n0 1 0\n0.5 2 0\n4 0 1 2 3 255 0 0\n3 3 2 4\n",
    )
    .unwrap();
    let mesh = read_mesh(&path).unwrap();
    assert_eq!(mesh.vertex_count(), 5);
    assert_eq!(mesh.positions[2], Vec3::new(1.0, 1.0, 0.0));
    assert_eq!(mesh.faces, vec![[0, 1, 2], [0, 2, 3], [3, 2, 4]]);
    for (text, expected) in [
        ("OFF\n5 2 0\n0 0 0\n1 0 0\n", "truncated"),
        ("COFF\n1 0 0\n", "m.off:1"),
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 x\n", "m.off:6"),
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 2\n", "after the last of 1 faces"),
        ("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "7"),
    ] {
        std::fs::write(&path, text).unwrap();
        let error = read_mesh(&path).unwrap_err().to_string();
        assert!(error.contains(expected) && error.contains("m.off"), "{text:?}: {error}");
    }
}

#[test]
fn labels_read_from_text_and_json() {
    let dir = tempfile::tempdir().unwrap();
    let txt = dir.path().join("l.txt");
    std::fs::write(&txt, "# ids: 0=head, 1=hand\n0\n1\n1\n").unwrap();
    let labels = desal_io::labels::read_labels(&txt).unwrap();
    assert_eq!(labels.labels, vec![0, 1, 1]);
    assert_eq!(labels.names, vec!["head", "hand"]);
    let json = dir.path().join("l.json");
    desal_io::labels::write_labels_json(&json, &labels).unwrap();
    assert_eq!(desal_io::labels::read_labels(&json).unwrap(), labels);
    std::fs::write(&json, r#"{"parts": ["a"], "labels": [0, 3]}"#).unwrap();
    let text = desal_io::labels::read_labels(&json).unwrap_err().to_string();
    assert!(text.contains("vertex 1") && text.contains("part id 3"), "{text}");
    std::fs::write(&txt, "0\n-1\n").unwrap();
    assert!(desal_io::labels::read_labels(&txt).unwrap_err().to_string().contains("l.txt:2"));
}

#[test]
fn text_labels_take_names_from_a_parts_header() {
    let dir = tempfile::tempdir().unwrap();
    let txt = dir.path().join("l.txt");
    std::fs::write(&txt, "# parts: head leftHand  torso\n0\n2\n1\n2\n").unwrap();
    let labels = desal_io::labels::read_labels(&txt).unwrap();
    assert_eq!(labels.labels, vec![0, 2, 1, 2]);
    assert_eq!(labels.names, vec!["head", "leftHand", "torso"]);
    // The header fixes the part count: an id beyond it names the line.
    std::fs::write(&txt, "# parts: head hand\n0\n1\n2\n").unwrap();
    let err = desal_io::labels::read_labels(&txt).unwrap_err().to_string();
    assert!(err.contains("l.txt:4") && err.contains("part id 2") && err.contains("0..1"), "{err}");
    // A named part no vertex carries is refused by name.
    std::fs::write(&txt, "# parts: head hand foot\n0\n1\n1\n").unwrap();
    let err = desal_io::labels::read_labels(&txt).unwrap_err().to_string();
    assert!(err.contains("foot"), "{err}");
}

#[test]
fn text_labels_with_an_out_of_range_id_name_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let txt = dir.path().join("l.txt");
    // Named parts: an id beyond them is refused.
    std::fs::write(&txt, "# ids: 0=head, 1=hand\n0\n1\n99\n").unwrap();
    let err = desal_io::labels::read_labels(&txt).unwrap_err().to_string();
    assert!(err.contains("l.txt:4") && err.contains("part id 99") && err.contains("0..1"), "{err}");
    // Unnamed parts: ids must be 0..N-1, all used; a huge id is refused before any
    // allocation for it.
    std::fs::write(&txt, "0\n1\n4000000000\n1\n").unwrap();
    let err = desal_io::labels::read_labels(&txt).unwrap_err().to_string();
    assert!(err.contains("l.txt:3") && err.contains("no vertex has part id 2"), "{err}");
    std::fs::write(&txt, "1\n0\n1\n").unwrap();
    assert_eq!(desal_io::labels::read_labels(&txt).unwrap().names, vec!["part0", "part1"]);
}

fn producer() -> Producer {
    Producer {
        stage: "ingest".into(),
        stage_version: 1,
        tool_version: "test".into(),
        parameters: "{}".into(),
        inputs: vec![],
    }
}

fn small_pose_set() -> PoseSet {
    let m = tetra();
    let moved: Vec<Vec3> = m.positions.iter().map(|p| p + Vec3::new(0.5, 0.0, 0.0)).collect();
    PoseSet::try_new(vec!["a".into(), "b".into()], vec![m.positions.clone(), moved], m.faces, 0).unwrap()
}

#[test]
fn artifact_round_trips_and_refuses_corruption() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("poses.dsa");
    let body = PoseSetV2::from_pose_set(&small_pose_set());
    let hash = artifact::write_artifact(&path, &producer(), &body).unwrap();
    let (p, back, h) = artifact::read_artifact::<PoseSetV2>(&path).unwrap();
    assert_eq!((p, &back, h), (producer(), &body, hash));
    assert_eq!(back.to_pose_set().unwrap(), small_pose_set());

    let bytes = std::fs::read(&path).unwrap();
    // The file is written header then payload, never joined in memory: the same bytes
    // as the in-memory encoding.
    assert_eq!((bytes.clone(), hash), artifact::encode_artifact(&producer(), &body));
    let refuse = |bytes: &[u8]| {
        std::fs::write(&path, bytes).unwrap();
        artifact::read_artifact::<PoseSetV2>(&path).unwrap_err()
    };
    let mut wrong_magic = bytes.clone();
    wrong_magic[0] = b'X';
    assert!(matches!(refuse(&wrong_magic), IoError::NotAnArtifact { .. }));
    let mut newer = bytes.clone();
    newer[10] = 9;
    assert!(matches!(refuse(&newer), IoError::NewerVersion { found: 9, .. }));
    let mut flipped = bytes.clone();
    let last = flipped.len() - 1;
    flipped[last] ^= 0x40;
    assert!(matches!(refuse(&flipped), IoError::Checksum { .. }));
    assert!(matches!(refuse(&bytes[..bytes.len() - 3]), IoError::Truncated { .. }));
    assert!(matches!(refuse(&bytes[..30]), IoError::TruncatedHeader { found: 30, .. }));
    let mut appended = bytes.clone();
    appended.extend_from_slice(b"xx");
    assert!(matches!(refuse(&appended), IoError::TrailingBytes { .. }));
    let mut unknown = bytes.clone();
    unknown[8] = 99;
    let err = refuse(&unknown);
    assert!(matches!(err, IoError::UnknownKind { code: 99, .. }), "{err}");
    let mut reserved = bytes.clone();
    reserved[13] = 1;
    assert!(matches!(refuse(&reserved), IoError::BadHeader { .. }));
    std::fs::write(&path, &bytes).unwrap();
    let err = artifact::read_artifact::<LabelsV1>(&path).unwrap_err();
    assert!(err.to_string().contains("is a 'pose-set' artifact, but a 'labels' artifact is needed"), "{err}");
}

#[test]
fn labels_artifact_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("labels.dsa");
    let labels = PartLabels::try_new(vec![0, 1, 1, 0], vec!["a".into(), "b".into()]).unwrap();
    artifact::write_artifact(&path, &producer(), &LabelsV1::from_labels(&labels)).unwrap();
    let (_, back, _) = artifact::read_artifact::<LabelsV1>(&path).unwrap();
    assert_eq!(back.to_labels().unwrap(), labels);
}

#[test]
#[cfg_attr(
    not(desal_shared_data),
    ignore = "needs ../shared/datasets beside the checkout (development and CI only)"
)]
fn reads_all_71_scape_poses() {
    let Some(dir) = scape_dir() else { return };
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ply"))
        .collect();
    files.sort();
    assert_eq!(files.len(), 71);
    let template = read_mesh(&files[0]).unwrap();
    for file in &files {
        let mesh = read_mesh(file).unwrap();
        assert_eq!((mesh.vertex_count(), mesh.face_count()), (12500, 24998), "{}", file.display());
        assert_eq!(mesh.faces, template.faces, "{}", file.display());
    }
    let labels = desal_io::labels::read_labels(&dir.join("vertex_part_labels_16.txt")).unwrap();
    assert_eq!(labels.vertex_count(), 12500);
    assert_eq!(labels.names[0], "lefthand");
    assert_eq!(labels.part_count(), 16);
}
