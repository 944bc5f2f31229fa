//! Regression tests for issue 12's reader rows (D4, D5, D9, D15, D16, D17), each named
//! after its row, plus the four hand-made reproductions in `../shared/reliability`
//! (read in place under the shared-data skip policy; nothing is copied from there).

use std::path::{Path, PathBuf};

use desal_io::artifact::{self, FitV1, LabelsV1, MapV1, PoseSetV2, Producer, SaliencyV1, SimplifiedV1};
use desal_io::ply::{PlyEncoding, PlyWriteOptions, write_ply};
use desal_io::{IoError, read_mesh, read_mesh_from};
use desal_mesh::{TriMesh, Vec3};

/// `../shared/reliability/<name>` beside the checkout, or `None` after printing why the
/// caller skips; with `DESAL_REQUIRE_SHARED_DATA` set a missing folder fails instead
/// (the policy of `desal_testdata::shared_dataset`, for a folder outside `datasets/`).
fn reliability_file(name: &str) -> Option<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/reliability");
    if dir.is_dir() {
        return Some(dir.join(name));
    }
    assert!(
        std::env::var_os(desal_testdata::REQUIRE_VAR).is_none(),
        "{} is missing but {} is set",
        dir.display(),
        desal_testdata::REQUIRE_VAR
    );
    eprintln!("skipped: {} is absent", dir.display());
    None
}

fn tetra() -> TriMesh {
    TriMesh {
        positions: vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
        ],
        faces: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
    }
}

/// The tetrahedron as PLY bytes in `encoding`.
fn tetra_ply(encoding: PlyEncoding) -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("t.ply");
    write_ply(&path, &tetra(), &PlyWriteOptions { encoding, ..PlyWriteOptions::default() }).unwrap();
    std::fs::read(path).unwrap()
}

fn ascii_ply(header_extra: &str, body: &str) -> Vec<u8> {
    format!(
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n{header_extra}element face 4\nproperty list uchar int vertex_indices\nend_header\n{body}"
    )
    .into_bytes()
}

const TETRA_BODY: &str = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";

fn err_text(path: &str, bytes: &[u8]) -> String {
    read_mesh_from(Path::new(path), bytes).unwrap_err().to_string()
}

// ---- D4: counts checked against the file's size before any allocation ----

/// hugev.off claims 10^12 vertices (it aborted with a 24 TB allocation), hugef.off 10^18
/// faces (a capacity-overflow panic): both are refused naming the file and the element.
#[test]
fn d4_off_counts_checked_against_file_size() {
    let tail = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";
    let text = err_text("hugev.off", format!("OFF\n1000000000000 4 0\n{tail}").as_bytes());
    assert!(text.starts_with("hugev.off: ") && text.contains("1000000000000 vertices"), "{text}");
    let text = err_text("hugef.off", format!("OFF\n4 1000000000000000000 0\n{tail}").as_bytes());
    assert!(text.starts_with("hugef.off: ") && text.contains("1000000000000000000 faces"), "{text}");
    // A face count whose number total overflows is refused, not wrapped.
    let text = err_text("w.off", format!("OFF\n4 {} 0\n{tail}", usize::MAX / 2).as_bytes());
    assert!(text.contains("faces") && text.contains("more than 2^64"), "{text}");
    // Exactly enough numbers still reads.
    assert_eq!(
        read_mesh_from(Path::new("ok.off"), format!("OFF\n4 4 0\n{tail}").as_bytes()).unwrap(),
        tetra()
    );
}

/// The same for PLY, in every encoding: a vertex count the body cannot hold is refused
/// by the header check, naming the element, before the PLY crate reads anything.
#[test]
fn d4_ply_counts_checked_against_file_size() {
    for encoding in [PlyEncoding::Ascii, PlyEncoding::BinaryLittleEndian, PlyEncoding::BinaryBigEndian] {
        let bytes = tetra_ply(encoding);
        let text =
            String::from_utf8_lossy(&bytes).replacen("element vertex 4", "element vertex 1000000000000", 1);
        let forged: Vec<u8> = {
            // The header is ASCII; splice the edited header onto the original body.
            let end = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
            let header_end = text.find("end_header\n").unwrap() + 11;
            [text.as_bytes()[..header_end].to_vec(), bytes[end..].to_vec()].concat()
        };
        let err = err_text("huge.ply", &forged);
        assert!(
            err.starts_with("huge.ply: ") && err.contains("1000000000000 'vertex' elements"),
            "{encoding:?}: {err}"
        );
    }
}

/// An element with entries but no properties would make the binary reader loop over
/// 10^18 empty elements: refused by the header check.
#[test]
fn d4_ply_element_without_properties_is_refused() {
    let bytes = ascii_ply("element nothing 1000000000000000000\n", TETRA_BODY);
    let err = err_text("e.ply", &bytes);
    assert!(err.contains("'nothing' has 1000000000000000000 entries but no properties"), "{err}");
}

#[test]
#[cfg_attr(not(desal_shared_data), ignore = "needs ../shared beside the checkout (development and CI only)")]
fn d4_shared_reliability_off_files() {
    for (name, element) in [("hugev.off", "vertices"), ("hugef.off", "faces")] {
        let Some(path) = reliability_file(name) else { return };
        let err = read_mesh(&path).unwrap_err();
        let text = err.to_string();
        assert!(matches!(err, IoError::BadMesh { .. }), "{text}");
        assert!(text.contains(name) && text.contains(element), "{text}");
    }
}

// ---- D5: OBJ indices range-checked before narrowing ----

/// Index 4294967297 used to wrap to 1 and the file was accepted.
#[test]
fn d5_obj_index_beyond_u32_is_refused_naming_the_face() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 4294967297 4 3\n";
    let err = err_text("tet_wrap.obj", obj.as_bytes());
    assert!(err.starts_with("tet_wrap.obj:8: face 3: '4294967297'"), "{err}");
    // In u32 range but past the last vertex: named by face and line too.
    let err = err_text("t.obj", obj.replace("4294967297", "5").as_bytes());
    assert!(err.starts_with("t.obj:8: face 3 references vertex 5"), "{err}");
    // Too long for any integer: out of range, not "not an index".
    let err = err_text("t.obj", obj.replace("4294967297", "99999999999999999999999").as_bytes());
    assert!(err.contains("out of the range of vertex indices"), "{err}");
}

#[test]
#[cfg_attr(not(desal_shared_data), ignore = "needs ../shared beside the checkout (development and CI only)")]
fn d5_shared_reliability_obj_file() {
    let Some(path) = reliability_file("tet_wrap.obj") else { return };
    let text = read_mesh(&path).unwrap_err().to_string();
    assert!(text.contains("tet_wrap.obj:8: face 3"), "{text}");
}

// ---- D9: forged artifacts (valid checksum) are errors naming the path ----

fn producer() -> Producer {
    Producer {
        stage: "map".into(),
        stage_version: 1,
        tool_version: "test".into(),
        parameters: "{}".into(),
        inputs: vec![],
    }
}

/// `bytes` with its header's payload length and checksum recomputed, as a forger would.
fn reseal(mut bytes: Vec<u8>) -> Vec<u8> {
    let payload_len = (bytes.len() - artifact::HEADER_LEN) as u64;
    bytes[16..24].copy_from_slice(&payload_len.to_le_bytes());
    let hash = desal_io::ContentHash::of(&bytes[artifact::HEADER_LEN..]);
    bytes[24..56].copy_from_slice(&hash.0);
    bytes
}

fn map_body() -> MapV1 {
    MapV1 {
        simp_to_orig: vec![3, 0, 2, 1],
        faces: vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        mode: "greedy".into(),
        displacement_mean: 0.0,
        displacement_max: 0.0,
    }
}

/// The producer's first string ("map") gets a length prefix of 2^41: it aborted with a
/// 2 TB allocation; now the decoder's limit refuses it, and the message names the path.
#[test]
fn d9_forged_string_length_is_an_error_naming_the_path() {
    let (bytes, _) = artifact::encode_artifact(&producer(), &map_body());
    let at = artifact::HEADER_LEN;
    assert_eq!(&bytes[at..at + 4], b"\x03map", "the payload starts with the stage string");
    let mut forged = bytes[..at].to_vec();
    forged.push(253); // varint marker: a u64 length follows
    forged.extend_from_slice(&(1u64 << 41).to_le_bytes());
    forged.extend_from_slice(&bytes[at + 1..]);
    let forged = reseal(forged);
    let path = Path::new("out/forged-map.dsa");
    for err in [
        artifact::decode_artifact::<MapV1>(path, &forged).unwrap_err(),
        artifact::decode_producer(path, &forged).unwrap_err(),
    ] {
        let text = err.to_string();
        assert!(matches!(err, IoError::Decode { .. }), "{text}");
        assert!(text.starts_with("out/forged-map.dsa: ") && text.contains("claims more data"), "{text}");
    }
}

/// Every kind's body, encoded with a valid checksum but contradicting itself, is refused
/// at decode with the path and the offending entry, instead of panicking in its user.
#[test]
fn d9_decodable_but_inconsistent_bodies_are_refused() {
    fn refused<T: artifact::ArtifactBody + std::fmt::Debug>(body: &T, expect: &str) {
        let (bytes, _) = artifact::encode_artifact(&producer(), body);
        let err = artifact::decode_artifact::<T>(Path::new("x/forged.dsa"), &bytes).unwrap_err();
        let text = err.to_string();
        assert!(matches!(err, IoError::InvalidArtifact { .. }), "{text}");
        assert!(text.starts_with("x/forged.dsa: ") && text.contains(expect), "{text}");
    }
    // A map face beyond the map, and a map that is not one to one.
    let mut map = map_body();
    map.faces[2] = [1, 2, 4];
    refused(&map, "face 2 references vertex 4");
    let mut map = map_body();
    map.simp_to_orig[3] = 0;
    refused(&map, "original vertex 0 is mapped to twice");
    // A pose set with one name too few (PoseSet::try_new asserted on it: a panic).
    let poses = PoseSetV2 {
        names: vec!["a".into()],
        template: 0,
        faces: vec![[0, 1, 2]],
        positions: vec![vec![[0.0; 3]; 3], vec![[0.0; 3]; 3]],
        groups: vec![],
    };
    refused(&poses, "names has 1 entries, but there are 2 poses");
    refused(
        &PoseSetV2 { names: vec!["a".into(), "b".into()], groups: vec![0, 1, 1], ..poses.clone() },
        "groups has 3 entries, but there are 2 poses",
    );
    let poses = PoseSetV2 { names: vec!["a".into(), "b".into()], template: 5, ..poses };
    refused(&poses, "template index 5");
    // Empty: `to_pose_set` would refuse it without the path.
    refused(
        &PoseSetV2 { template: 0, faces: vec![], ..poses },
        "the pose set is empty (3 vertices, 0 faces)",
    );
    refused(&LabelsV1 { names: vec!["a".into()], labels: vec![0, 1] }, "vertex 1 has part id 1");
    let fit = FitV1 {
        model: "rigid".into(),
        pose_names: vec!["p0".into(), "p1".into()],
        part_names: vec!["a".into()],
        template: 0,
        vertex_count: 2,
        linear: vec![[0.0; 9]; 2],
        translation: vec![[0.0; 3]; 2],
        rms: vec![0.0; 2],
        mean: vec![0.0; 2],
        max: vec![0.0; 2],
        residuals: vec![0.0; 4],
        worst_parts: vec![(0, 0.0, 0.0, 1)],
        worst_poses: vec![(1, 0.0, 0.0, 0)],
    };
    artifact::decode_artifact::<FitV1>(Path::new("f.dsa"), &artifact::encode_artifact(&producer(), &fit).0)
        .expect("the consistent fit decodes");
    refused(&FitV1 { residuals: vec![0.0; 3], ..fit.clone() }, "residuals has 3 entries");
    refused(&FitV1 { worst_parts: vec![(1, 0.0, 0.0, 1)], ..fit.clone() }, "worst_parts[0] names part 1");
    refused(&FitV1 { worst_poses: vec![(0, 0.0, 0.0, 7)], ..fit }, "worst_poses[0] names part 7");
    let saliency = SaliencyV1 {
        saliency: vec![0.0; 3],
        weights: vec![0.0; 3],
        raw: vec![0.0; 2],
        normaliser: 1.0,
        distance: "plain".into(),
        normalisation: "max".into(),
        weight_floor: 0.1,
        poses_used: vec![],
        poses_excluded: vec![],
        rigid: false,
    };
    refused(&saliency, "raw has 2 entries");
    let simplified = SimplifiedV1 {
        positions: vec![[0.0; 3]; 3],
        faces: vec![[0, 1, 2]],
        simp_to_orig: vec![Some(0), None, Some(9)],
        placement: "subset".into(),
        input_vertices: 5,
        input_faces: 6,
        collapses: 2,
        stop: "target".into(),
        max_error: 0.0,
        mean_error: 0.0,
        edge_length_mean: 0.0,
        edge_length_variance: 0.0,
    };
    refused(&simplified, "simp_to_orig[2] names original vertex 9");
}

/// The reproduction of the issue: a map artifact with a mutated payload and a recomputed
/// checksum (it panicked with "capacity overflow" in `desal inspect`).
#[test]
#[cfg_attr(not(desal_shared_data), ignore = "needs ../shared beside the checkout (development and CI only)")]
fn d9_shared_reliability_forged_map_artifact() {
    let Some(path) = reliability_file("panic_dsafix-map_s2_1527.dsa") else { return };
    let name = "panic_dsafix-map_s2_1527.dsa";
    let text = artifact::read_producer(&path).map(|_| ()).err().map(|e| e.to_string());
    let body = artifact::read_artifact::<MapV1>(&path).unwrap_err().to_string();
    eprintln!("{body}");
    assert!(body.contains(name), "{body}");
    if let Some(text) = text {
        assert!(text.contains(name), "{text}");
    }
}

// ---- D15: label checks agree ----

/// A trailing part named in the comment but used by no vertex was dropped silently in
/// text and refused in JSON; both now refuse it with the same error, naming it.
#[test]
fn d15_empty_trailing_part_is_treated_the_same_in_text_and_json() {
    let txt =
        desal_io::labels::read_labels_from(Path::new("l.txt"), b"# ids: 0=head, 1=hand, 2=foot\n0\n1\n1\n");
    let json = desal_io::labels::read_labels_from(
        Path::new("l.json"),
        br#"{"parts": ["head", "hand", "foot"], "labels": [0, 1, 1]}"#,
    );
    for (err, file) in [(txt.unwrap_err(), "l.txt"), (json.unwrap_err(), "l.json")] {
        let text = err.to_string();
        assert!(matches!(err, IoError::EmptyPart { part: 2, .. }), "{text}");
        assert!(text.starts_with(&format!("{file}: part 2 ('foot') has no vertices")), "{text}");
    }
    // An empty part in the middle is refused the same way.
    let err =
        desal_io::labels::read_labels_from(Path::new("l.txt"), b"# ids: 0=head, 1=hand, 2=foot\n0\n2\n")
            .unwrap_err();
    assert!(matches!(err, IoError::EmptyPart { part: 1, .. }), "{err}");
    // A comment naming a part id far beyond the vertex count is refused before the names
    // are allocated.
    let err =
        desal_io::labels::read_labels_from(Path::new("l.txt"), b"# ids: 0=a, 4000000000=b\n0\n").unwrap_err();
    assert!(matches!(err, IoError::EmptyPart { part: 1, .. }), "{err}");
}

/// The id-gap message advised a `# ids:` comment "to allow empty ones", but an empty
/// part is refused: it no longer advises anything that is then refused.
#[test]
fn d15_id_gap_message_does_not_advise_empty_parts() {
    let err = desal_io::labels::read_labels_from(Path::new("l.txt"), b"0\n2\n2\n").unwrap_err().to_string();
    assert!(err.contains("no vertex has part id 1") && err.contains("renumber"), "{err}");
    assert!(!err.contains("ids:") && !err.contains("allow"), "{err}");
}

// ---- D16: accurate messages, strict parsing ----

/// One vertex more claimed than the file holds: the first face line is read as the last
/// vertex. ASCII names the line and the element; binary no longer says only "face 0 has
/// 0 vertices".
#[test]
fn d16_one_extra_vertex_claimed_gets_an_accurate_message() {
    let bytes =
        String::from_utf8(ascii_ply("", TETRA_BODY)).unwrap().replace("element vertex 4", "element vertex 5");
    let err = err_text("v.ply", bytes.as_bytes());
    assert!(
        err.starts_with("v.ply:14: vertex 4 has 4 values, but the header's 'vertex' properties take 3")
            && err.contains("more 'vertex' elements than the file holds"),
        "{err}"
    );
    let bytes = tetra_ply(PlyEncoding::BinaryLittleEndian);
    let end = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let header =
        String::from_utf8(bytes[..end].to_vec()).unwrap().replace("element vertex 4", "element vertex 5");
    let err = err_text("v.ply", &[header.into_bytes(), bytes[end..].to_vec()].concat());
    eprintln!("{err}");
    assert!(err.contains("element counts do not match the data"), "{err}");
}

/// The index list under another name said "face 0 has 0 vertices"; now it is named, with
/// the names desal reads.
#[test]
fn d16_index_list_under_another_name_is_named() {
    let bytes = String::from_utf8(ascii_ply("", TETRA_BODY)).unwrap().replace("vertex_indices", "vertex_idx");
    let err = err_text("n.ply", bytes.as_bytes());
    assert!(err.contains("no 'vertex_indices' list (its properties: vertex_idx)"), "{err}");
}

/// Face numbers in errors are the file's own faces, not triangles: after a quad (two
/// triangles) the bad face is still face 1, in OBJ, OFF and PLY alike.
#[test]
fn d16_face_numbers_are_the_files_own() {
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nf 1 2 7\n";
    assert!(err_text("q.obj", obj.as_bytes()).starts_with("q.obj:6: face 1 references vertex 7"));
    let off = "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n3 0 1 6\n";
    let err = err_text("q.off", off.as_bytes());
    assert!(err.starts_with("q.off:8: face 1 references vertex 6"), "{err}");
    let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n3 0 1 6\n";
    let err = err_text("q.ply", ply.as_bytes());
    assert!(err.contains("face 1 references vertex 6, but the file has only 4 vertices"), "{err}");
}

/// An extra value on an ASCII PLY line was ignored: it is refused, naming the line.
#[test]
fn d16_extra_token_on_ascii_ply_line_is_refused() {
    let err = err_text("x.ply", &ascii_ply("", &TETRA_BODY.replacen("1 0 0\n", "1 0 0 7\n", 1)));
    assert!(
        err.starts_with("x.ply:11: vertex 1 has 4 values, but the header's 'vertex' properties take 3"),
        "{err}"
    );
    let err = err_text("x.ply", &ascii_ply("", &TETRA_BODY.replacen("3 0 1 3\n", "3 0 1 3 0\n", 1)));
    assert!(err.starts_with("x.ply:15: face 1 has 5 values"), "{err}");
    // A short line is refused too, and the untouched file reads.
    let err = err_text("x.ply", &ascii_ply("", &TETRA_BODY.replacen("3 0 1 3\n", "3 0 1\n", 1)));
    assert!(
        err.starts_with("x.ply:15: face 1 has 3 values, but the header's 'face' properties take 4"),
        "{err}"
    );
    assert_eq!(read_mesh_from(Path::new("x.ply"), &ascii_ply("", TETRA_BODY)).unwrap(), tetra());
}

/// A property declared twice was collapsed into one (misreading every value after it).
#[test]
fn d16_duplicate_property_is_refused() {
    let bytes = String::from_utf8(ascii_ply("", TETRA_BODY))
        .unwrap()
        .replace("property float z\n", "property float x\n");
    let err = err_text("d.ply", bytes.as_bytes());
    assert!(err.contains("declares the property 'x' of element 'vertex' twice"), "{err}");
    let err = err_text("d.ply", &ascii_ply("element vertex 0\nproperty float x\n", TETRA_BODY));
    assert!(err.contains("declares the element 'vertex' twice"), "{err}");
}

/// `format ascii 2.0` was accepted.
#[test]
fn d16_ply_format_2_0_is_refused() {
    let bytes = String::from_utf8(ascii_ply("", TETRA_BODY)).unwrap().replace("1.0", "2.0");
    let err = err_text("f.ply", bytes.as_bytes());
    assert!(err.contains("format version 2.0 is not 1.0"), "{err}");
}

// ---- D17: non-regular files are refused, never opened ----

/// A FIFO matched by a poses glob hung the run forever (opening it blocks until a writer
/// appears). The readers check the metadata first; the read runs on a thread so that a
/// regression fails this test instead of hanging it.
#[test]
fn d17_fifo_directory_and_device_are_refused_without_hanging() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pose.ply");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if !made.is_ok_and(|s| s.success()) {
        eprintln!("skipped the FIFO case: mkfifo is not available");
    } else {
        let labels = dir.path().join("labels.txt");
        std::fs::rename(dir.path().join("pose.ply"), &labels).unwrap();
        std::process::Command::new("mkfifo").arg(&fifo).status().unwrap();
        let (tx, rx) = std::sync::mpsc::channel();
        let (f, l) = (fifo.clone(), labels.clone());
        std::thread::spawn(move || {
            let mesh = read_mesh(&f).unwrap_err();
            let labels = desal_io::labels::read_labels(&l).unwrap_err();
            let artifact = artifact::read_artifact::<MapV1>(&l).unwrap_err();
            tx.send([mesh, labels, artifact]).unwrap();
        });
        let errs = rx.recv_timeout(std::time::Duration::from_secs(20)).expect("the readers hang on a FIFO");
        for err in errs {
            assert!(matches!(err, IoError::NotAFile { what: "a FIFO (named pipe)", .. }), "{err}");
        }
    }
    let sub = dir.path().join("poses.ply");
    std::fs::create_dir(&sub).unwrap();
    let err = read_mesh(&sub).unwrap_err().to_string();
    assert!(
        err.ends_with("poses.ply: is a directory, not a regular file; desal reads regular files only"),
        "{err}"
    );
    if Path::new("/dev/null").exists() {
        let err = desal_io::labels::read_labels(Path::new("/dev/null")).unwrap_err();
        assert!(matches!(err, IoError::NotAFile { what: "a device", .. }), "{err}");
    }
}

/// The part check now uses the fit's threshold (1e-9 of the covariance's eigenvalues,
/// not 1e-18): real bodies still pass it, every part of the sample and of SCAPE.
#[test]
fn d15_real_parts_pass_the_fit_threshold() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data-samples");
    let template = read_mesh(&root.join("poses/00_rest.ply")).unwrap();
    for file in ["labels.txt", "labels.json"] {
        let labels = desal_io::labels::read_labels(&root.join(file)).unwrap();
        labels.check_parts_fittable(&template.positions).unwrap();
    }
    let Some((set, labels)) = desal_testdata::scape() else { return };
    labels.check_parts_fittable(set.template_positions()).unwrap();
}
