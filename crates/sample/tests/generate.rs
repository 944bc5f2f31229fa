//! The generator on the real, shipped MakeHuman assets (`data-samples/source`): the
//! committed sample regenerates byte for byte, the template is the base body exactly,
//! every pose is registered and clean, every part is a usable patch.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use desal_mesh::math::UnitQuat;
use desal_mesh::{EdgeTopology, TriMesh};
use desal_sample::{Sample, SampleConfig, Skeleton, SkinWeights, SourceAssets, generate, standard_poses};

fn data_samples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data-samples")
}

fn assets() -> &'static SourceAssets {
    static ASSETS: OnceLock<SourceAssets> = OnceLock::new();
    ASSETS.get_or_init(|| SourceAssets::load(&data_samples().join("source")).expect("shipped source assets"))
}

fn sample() -> &'static Sample {
    static SAMPLE: OnceLock<Sample> = OnceLock::new();
    SAMPLE.get_or_init(|| generate(assets(), &standard_poses(), &SampleConfig::default()).expect("generate"))
}

#[test]
fn the_committed_sample_regenerates_byte_for_byte() {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("desal-sample-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let written = desal_sample::write_sample(&out, sample()).unwrap();
    for path in &written {
        let relative = path.strip_prefix(&out).unwrap();
        let committed = data_samples().join(relative);
        let expected = std::fs::read(&committed).unwrap_or_else(|e| {
            panic!("{}: {e}; regenerate the sample (see data-samples/README.md)", committed.display())
        });
        let found = std::fs::read(path).unwrap();
        assert!(
            expected == found,
            "{} differs from the generator's output; regenerate it",
            relative.display()
        );
    }
    // No stale pose files: the committed poses are exactly the generated ones.
    let listing = |dir: &Path| {
        let mut names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    };
    assert_eq!(listing(&data_samples().join("poses")), listing(&out.join("poses")));
    std::fs::remove_dir_all(&out).unwrap();
}

#[test]
fn the_body_is_a_closed_manifold_of_26756_triangles() {
    let body = desal_sample::extract_body(&assets().base, 13380).unwrap();
    assert_eq!(body.vertex_count(), 13380);
    assert_eq!(body.face_count(), 26756);
    let topology = EdgeTopology::new(&body.faces);
    assert_eq!(topology.boundary_edge_count(), 0);
    assert_eq!(topology.non_manifold_edge_count(), 0);
}

#[test]
fn the_template_is_the_base_body_in_metres_exactly() {
    let sample = sample();
    assert_eq!(sample.poses.template, 0);
    assert_eq!(sample.poses.names[0], "00_rest");
    let body = &assets().base.positions[..13380];
    for (v, (p, q)) in body.iter().zip(&sample.poses.poses[0]).enumerate() {
        assert!(*q == p * 0.1, "vertex {v}: {q:?} is not {p:?} x 0.1");
    }
    // And on disk, as f32.
    let rest = desal_io::read_mesh(&data_samples().join("poses/00_rest.ply")).unwrap();
    for (p, q) in body.iter().zip(&rest.positions) {
        assert_eq!(q.map(|c| c as f32), (p * 0.1).map(|c| c as f32));
    }
}

#[test]
fn identity_rotations_reproduce_the_body_exactly() {
    let skeleton = Skeleton::from_assets(assets()).unwrap();
    let body = &assets().base.positions[..13380];
    let (weights, report) = SkinWeights::from_bone_lists(&skeleton, &assets().weights, 13380).unwrap();
    assert!(report.unweighted_vertices.is_empty());
    let world = skeleton.forward_kinematics(&vec![UnitQuat::identity(); skeleton.bone_count()]);
    assert_eq!(desal_sample::skin(body, &weights, &world), body);
}

#[test]
fn turning_one_bone_moves_exactly_the_vertices_of_its_subtree() {
    let skeleton = Skeleton::from_assets(assets()).unwrap();
    let body = &assets().base.positions[..13380];
    let (weights, _) = SkinWeights::from_bone_lists(&skeleton, &assets().weights, 13380).unwrap();
    let forearm = skeleton.index_of("LeftForeArm").unwrap();
    let mut local = vec![UnitQuat::identity(); skeleton.bone_count()];
    local[forearm] = UnitQuat::from_scaled_axis(desal_mesh::Vec3::x() * 0.5);
    let posed = desal_sample::skin(body, &weights, &skeleton.forward_kinematics(&local));
    let mut moved = 0;
    for v in 0..body.len() {
        let influenced = weights.of(v).any(|(b, _)| skeleton.is_in_subtree(b, forearm));
        if influenced {
            moved += 1;
            assert_ne!(posed[v], body[v], "vertex {v} is weighted to the forearm chain but did not move");
        } else {
            assert_eq!(posed[v], body[v], "vertex {v} is not weighted to the forearm chain but moved");
        }
    }
    // The forearm, hand and fingers: a few thousand vertices, not the whole body.
    assert!((1000..4000).contains(&moved), "{moved} vertices moved");
}

#[test]
fn every_committed_pose_is_registered_to_the_template() {
    let poses_dir = data_samples().join("poses");
    let template: TriMesh = desal_io::read_mesh(&poses_dir.join("00_rest.ply")).unwrap();
    for name in &sample().poses.names {
        let mesh = desal_io::read_mesh(&poses_dir.join(format!("{name}.ply"))).unwrap();
        assert_eq!(mesh.vertex_count(), template.vertex_count(), "{name}");
        assert_eq!(mesh.faces, template.faces, "{name}");
    }
    assert!(sample().poses.names.len() >= 10);
}

#[test]
fn every_pose_is_clean_and_on_the_ground() {
    let report = &sample().report;
    assert_eq!(report.rest_self_intersections, 0);
    let floor = |p: &[desal_mesh::Vec3]| p.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    let rest_floor = floor(&sample().poses.poses[0]);
    for (pose, positions) in report.poses.iter().zip(&sample().poses.poses) {
        assert_eq!(pose.quality.inverted_faces, 0, "{}", pose.name);
        assert_eq!(pose.quality.self_intersections, 0, "{}", pose.name);
        assert!(pose.quality.min_area_ratio > 0.05, "{}: {:?}", pose.name, pose.quality);
        assert!((floor(positions) - rest_floor).abs() < 1e-12, "{}", pose.name);
        if pose.name != "00_rest" {
            assert!(pose.max_displacement > 0.05, "{} barely moves", pose.name);
        }
    }
}

#[test]
fn the_committed_labels_have_16_single_patch_parts() {
    let labels = desal_io::labels::read_labels(&data_samples().join("labels.json")).unwrap();
    assert_eq!(labels, sample().labels);
    assert_eq!(labels.vertex_count(), 13380);
    assert_eq!(labels.names, desal_sample::parts::PART_NAMES.map(String::from).to_vec());
    let counts: Vec<usize> = labels.members().iter().map(Vec::len).collect();
    assert!(counts.iter().all(|&n| n >= 100), "{counts:?}");
    assert_eq!(desal_sample::parts::part_pieces(&labels, &sample().poses.faces), vec![1; 16]);
    labels.check_parts_fittable(&sample().poses.poses[0]).unwrap();
    // The text form says the same.
    let text = desal_io::labels::read_labels(&data_samples().join("labels.txt")).unwrap();
    assert_eq!(text, labels);
}

#[test]
fn the_committed_rig_welds_to_the_template_and_its_keyframes_are_the_poses() {
    use desal_rig::{FrameConfig, PoseSource, ReadOptions};
    let path = data_samples().join(desal_sample::RIG_FILE);
    let rig = desal_rig::read_rig(&path, &ReadOptions::default()).unwrap();
    assert_eq!(rig.skin.joints.len(), 31);
    // The UV seams split the mesh; welding by position and weights gives the body back.
    assert!(rig.mesh.vertex_count() > 13380, "{}", rig.mesh.vertex_count());
    let frames = FrameConfig {
        source: PoseSource::Animations,
        frames: sample().poses.pose_count(),
        ..FrameConfig::default()
    };
    let frames = desal_rig::sample_frames(&rig, &frames, &path).unwrap();
    let posed = desal_rig::pose_rig(&rig, &frames).unwrap();
    assert_eq!(posed.weld.welded_count(), 13380);
    assert_eq!(posed.poses.faces, sample().poses.faces);
    // Pose 0 of the rig is the bind pose, then one frame per keyframe: each is the PLY
    // sample's pose, up to f32 rounding of the weights, rotations and offsets.
    let mut worst: f64 = 0.0;
    for (k, expected) in sample().poses.poses.iter().enumerate() {
        for (p, q) in posed.poses.poses[k + 1].iter().zip(expected) {
            worst = worst.max((p - q).norm());
        }
    }
    assert!(worst < 1e-5, "largest difference {worst} m");
    for (p, q) in posed.poses.poses[0].iter().zip(&sample().poses.poses[0]) {
        assert!((p - q).norm() < 1e-6);
    }
}

/// The committed avatar as desal reads it: three meshes on one skin, in node order, at
/// most 4 influences, the body welding to the template's 13380 vertices, the face units
/// named, the textures PNG, and under 2 MB.
#[test]
fn the_avatar_is_three_textured_meshes_on_one_skin() {
    let path = data_samples().join(desal_sample::avatar::AVATAR_FILE);
    let bytes = std::fs::read(&path).unwrap();
    assert!(bytes.len() < 2_000_000, "{} bytes", bytes.len());
    let options = desal_rig::ReadOptions::default();
    let (rig, document) = desal_rig::read_rig_and_document(&path, &bytes, &options).unwrap();
    let names: Vec<&str> = rig.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["Body", "Eyes", "Hair"]);
    assert!(rig.meshes.iter().all(|m| m.skin == Some(0)), "one shared skin");
    assert!(rig.mesh.influences.max_influences() <= 4);
    let body_options = desal_rig::ReadOptions { mesh: Some(vec!["Body".into()]) };
    let body = desal_rig::read_rig_from(&path, &bytes, &body_options).unwrap();
    assert_eq!(desal_rig::Weld::new(&body.mesh).welded_count(), 13380, "the body welds to the template");
    let json = document.json();
    assert_eq!(
        json["meshes"][0]["extras"]["targetNames"],
        serde_json::json!(desal_sample::source::FACE_UNITS)
    );
    for image in json["images"].as_array().unwrap() {
        let view = &json["bufferViews"][image["bufferView"].as_u64().unwrap() as usize];
        assert_eq!(image["mimeType"], "image/png", "{view}");
    }
    assert_eq!(json["materials"].as_array().unwrap().len(), 3);
    let wave = &rig.animations[0];
    assert_eq!(wave.name.as_deref(), Some("wave"));
    assert_eq!(wave.channels[0].times, [0.0, 1.0, 2.0, 3.0]);
}

/// The blink of the left eye moves the left side of the face (the frame's +X: 89% of its
/// total displacement, the rest near the nose), the right blink the right side, and both
/// only the upper face: the face units are in the body's own frame and index space.
#[test]
fn the_left_blink_moves_the_left_eyelids() {
    let body = desal_sample::extract_body(&assets().base, 13380).unwrap();
    let left_share = |unit: &str| {
        let on_body: Vec<_> = assets().face_units[unit].iter().filter(|(v, _)| *v < 13380).collect();
        assert!(on_body.len() > 500, "{unit}: {} body vertices", on_body.len());
        let (mut left, mut total) = (0.0, 0.0);
        for (v, d) in on_body {
            let p = body.positions[*v as usize];
            assert!(p.y > 6.5, "{unit}: vertex {v} at {p:?} is below the eyes");
            let length = desal_mesh::Vec3::from(*d).norm();
            total += length;
            if p.x > 0.0 {
                left += length;
            }
        }
        left / total
    };
    assert!(left_share("eyeBlinkLeft") > 0.85, "{}", left_share("eyeBlinkLeft"));
    assert!(left_share("eyeBlinkRight") < 0.15, "{}", left_share("eyeBlinkRight"));
    let report = &sample().avatar.report;
    assert_eq!(report.targets[0], ("eyeBlinkLeft".to_owned(), 747));
    assert_eq!(report.meshes.iter().map(|m| m.0.as_str()).collect::<Vec<_>>(), ["Body", "Eyes", "Hair"]);
}
