//! A hand-made two-joint limb (a tube bent at its middle joint) whose UV layout has a
//! seam along the limb (where the unwrap closes) and one across it (two charts, upper
//! and lower), so every seam case of the weld and of the output is met: the round trip
//! through a `.glb`, welding, posing by LBS, part labels, the simplified rig with seams
//! kept (subset and optimal placement) and every refused input.

#![allow(clippy::needless_range_loop)] // Index loops read as the rings and segments they build.

use std::path::Path;

use desal_mesh::{EdgeTopology, TriMesh, Vec3};
use desal_rig::model::{Path as ChannelPath, SkinnedMesh};
use desal_rig::pose::{animated_locals, sample_channel};
use desal_rig::{
    Animation, Channel, FrameConfig, Influences, Interpolation, LocalTransform, Node, PartsConfig,
    PoseSource, PoseTargets, PrimitiveSpan, ReadOptions, Rig, RigError, SimplifiedInput, Skin,
    dominant_joint_parts, joint_matrices, pose_rig, read_rig_from, sample_frames, simplified_rig,
    skin_points, write_glb,
};

/// Rings along the limb (y from 0 to 2) and segments around it.
const RINGS: usize = 17;
const SEGMENTS: usize = 12;
/// The ring at the joint (y = 1), where the upper and lower charts meet.
const MID: usize = RINGS / 2;

fn ring_y(r: usize) -> f32 {
    2.0 * r as f32 / (RINGS - 1) as f32
}

/// The limb: joint 0 "upper" at the origin, joint 1 "lower" at y = 1 (its child); the
/// mesh node is a separate root. One animation bends the lower joint 90° about z over
/// one second.
fn limb() -> Rig {
    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    let mut influences = Influences::new();
    // Split vertices: chart 0 holds rings 0..=MID, chart 1 rings MID..RINGS; each ring has
    // SEGMENTS + 1 columns, the last repeating the first with u = 1.
    let mut index = vec![vec![[0u32; 2]; SEGMENTS + 1]; RINGS];
    for chart in 0..2 {
        let rings = if chart == 0 { 0..=MID } else { MID..=RINGS - 1 };
        for r in rings {
            for s in 0..=SEGMENTS {
                let angle = std::f32::consts::TAU * (s % SEGMENTS) as f32 / SEGMENTS as f32;
                let y = ring_y(r);
                positions.push([0.2 * angle.cos(), y, 0.2 * angle.sin()]);
                let v = if chart == 0 { 0.5 * y / 2.0 } else { 0.55 + 0.45 * (y - 1.0) };
                uvs.push([s as f32 / SEGMENTS as f32, v]);
                let t = ((y - 0.7) / 0.6).clamp(0.0, 1.0);
                let lower = t * t * (3.0 - 2.0 * t);
                let row: Vec<(u16, f32)> =
                    [(0, 1.0 - lower), (1, lower)].into_iter().filter(|w| w.1 > 0.0).collect();
                influences.push_row(row);
                index[r][s][chart] = (positions.len() - 1) as u32;
            }
        }
    }
    let mut triangles = Vec::new();
    for r in 0..RINGS - 1 {
        let chart = usize::from(r >= MID);
        for s in 0..SEGMENTS {
            let (a, b) = (index[r][s][chart], index[r][s + 1][chart]);
            let (c, d) = (index[r + 1][s][chart], index[r + 1][s + 1][chart]);
            triangles.push([a, c, b]);
            triangles.push([b, c, d]);
        }
    }
    let normals = Some(
        positions
            .iter()
            .map(|p| {
                let n = (p[0] * p[0] + p[2] * p[2]).sqrt();
                [p[0] / n, 0.0, p[2] / n]
            })
            .collect(),
    );
    let mesh = SkinnedMesh {
        name: "limb".into(),
        positions,
        normals,
        uvs: Some(uvs),
        influences,
        triangles,
        primitives: Vec::new(),
        sources: Vec::new(),
    };
    let mut lower_ibm = identity();
    lower_ibm[13] = -1.0;
    let quarter = std::f32::consts::FRAC_PI_4.sin();
    Rig {
        weight_sums: Default::default(),
        nodes: vec![
            Node { name: Some("upper".into()), children: vec![1], transform: LocalTransform::IDENTITY },
            Node {
                name: Some("lower".into()),
                children: vec![],
                transform: LocalTransform::Trs {
                    translation: [0.0, 1.0, 0.0],
                    rotation: [0.0, 0.0, 0.0, 1.0],
                    scale: [1.0; 3],
                },
            },
            Node { name: Some("body".into()), children: vec![], transform: LocalTransform::IDENTITY },
        ],
        scenes: vec![vec![0, 2]],
        scene: Some(0),
        mesh_node: 2,
        meshes: Vec::new(),
        skin: Skin {
            name: Some("skin".into()),
            joints: vec![0, 1],
            inverse_bind: vec![identity(), lower_ibm],
            skeleton: Some(0),
        },
        animations: vec![Animation {
            name: Some("bend".into()),
            channels: vec![Channel {
                node: 1,
                path: ChannelPath::Rotation,
                interpolation: Interpolation::Linear,
                times: vec![0.0, 1.0],
                values: vec![0.0, 0.0, 0.0, 1.0, 0.0, 0.0, quarter, quarter],
            }],
        }],
        mesh,
    }
}

fn identity() -> [f32; 16] {
    let mut m = [0.0; 16];
    for i in 0..4 {
        m[5 * i] = 1.0;
    }
    m
}

fn read(bytes: &[u8]) -> Result<Rig, RigError> {
    read_rig_from(Path::new("limb.glb"), bytes, &ReadOptions::default())
}

#[test]
fn a_rig_survives_a_round_trip_through_glb_bit_for_bit() {
    let rig = limb();
    let bytes = write_glb(&rig).unwrap();
    let back = read(&bytes).unwrap();
    let (vertices, triangles) = (rig.mesh.vertex_count() as u32, rig.mesh.triangles.len() as u32);
    let one = PrimitiveSpan { mesh: 0, primitive: 0, vertices: 0..vertices, triangles: 0..triangles };
    assert_eq!(back.mesh.primitives, [one], "the reader says where the vertices come from");
    assert_eq!(without_provenance(back.clone()), rig);
    // Same rig, same bytes.
    assert_eq!(write_glb(&back).unwrap(), bytes);
}

#[test]
fn the_weld_closes_both_seams_and_keeps_only_the_ends_open() {
    let rig = limb();
    let posed = pose_rig(&rig, &[]).unwrap();
    // Split: two charts of (rings) x (SEGMENTS + 1); welded: one vertex per ring and segment.
    assert_eq!(rig.mesh.vertex_count(), (RINGS + 1) * (SEGMENTS + 1));
    assert_eq!(posed.weld.welded_count(), RINGS * SEGMENTS);
    let topology = EdgeTopology::new(&posed.weld.faces);
    // Only the two end rings are open: the seams are neither cracks nor boundaries.
    assert_eq!(topology.boundary_edge_count(), 2 * SEGMENTS);
    assert_eq!(topology.non_manifold_edge_count(), 0);
    // Split mesh, for contrast: both seams are boundaries.
    let split = EdgeTopology::new(&rig.mesh.triangles);
    assert_eq!(split.boundary_edge_count(), 2 * SEGMENTS + 2 * (RINGS - 1) + 2 * SEGMENTS);
}

#[test]
fn animation_frames_bend_the_lower_limb_by_slerp() {
    let rig = limb();
    let config = FrameConfig { source: PoseSource::Animations, frames: 3, ..FrameConfig::default() };
    let frames = sample_frames(&rig, &config, Path::new("limb.glb")).unwrap();
    assert_eq!(frames.len(), 3);
    let posed = pose_rig(&rig, &frames).unwrap();
    assert_eq!(posed.poses.pose_count(), 4);
    assert_eq!(posed.poses.names[0], "bind");
    // Bind pose and frame 0 (no bend) agree.
    for (p, q) in posed.poses.poses[0].iter().zip(&posed.poses.poses[1]) {
        // Not bit-equal: the f32 weights sum to 1 only up to rounding.
        assert!((p - q).norm() < 1e-6);
    }
    // The tip ring is weighted to "lower" only: at t = 1 it has turned 90° about z around
    // (0, 1, 0), so (x, y, z) goes to (-(y - 1), 1 + x, z).
    let tip = posed.poses.poses[0].len() - SEGMENTS;
    for v in tip..tip + SEGMENTS {
        let p = posed.poses.poses[0][v];
        let expected = Vec3::new(-(p.y - 1.0), 1.0 + p.x, p.z);
        assert!((posed.poses.poses[3][v] - expected).norm() < 1e-6, "{v}");
    }
    // At t = 0.5 slerp gives exactly 45°.
    let q = sample_channel(&rig.animations[0].channels[0], 0.5);
    assert!((q[3] - (std::f64::consts::PI / 8.0).cos()).abs() < 1e-7, "{q:?}");
    let locals = animated_locals(&rig, &rig.animations[0], 0.5);
    let m = joint_matrices(&rig, &locals);
    let tip_rest = posed.poses.poses[0][tip];
    let moved = desal_rig::pose::transform_point(&m[1], &tip_rest);
    let angle = ((moved - Vec3::new(0.0, 1.0, 0.0))
        .normalize()
        .dot(&(tip_rest - Vec3::new(0.0, 1.0, 0.0)).normalize()))
    .acos();
    assert!((angle.to_degrees() - 45.0).abs() < 1e-4, "{}", angle.to_degrees());
}

#[test]
fn random_frames_are_seeded_and_stay_within_the_limit() {
    let rig = limb();
    let config = FrameConfig { source: PoseSource::Random, frames: 20, seed: 7, max_degrees: 25.0 };
    let a = sample_frames(&rig, &config, Path::new("limb.glb")).unwrap();
    let b = sample_frames(&rig, &config, Path::new("limb.glb")).unwrap();
    let c = sample_frames(&rig, &FrameConfig { seed: 8, ..config }, Path::new("limb.glb")).unwrap();
    assert_eq!(format!("{:?}", a[5].locals), format!("{:?}", b[5].locals));
    assert_ne!(format!("{:?}", a[5].locals), format!("{:?}", c[5].locals));
    let mut largest: f64 = 0.0;
    for frame in &a {
        for &node in &rig.skin.joints {
            if let desal_rig::pose::LocalPose::Trs { rotation, .. } = frame.locals[node] {
                largest = largest.max(rotation.angle().to_degrees());
            }
        }
    }
    assert!(largest <= 25.0 + 1e-9 && largest > 15.0, "{largest}");
    // "both" is the animation frames then the random ones.
    let both =
        sample_frames(&rig, &FrameConfig { source: PoseSource::Both, ..config }, Path::new("x")).unwrap();
    assert_eq!(both.len(), 40);
}

#[test]
fn dominant_joint_parts_split_the_limb_at_its_joint() {
    let rig = limb();
    let posed = pose_rig(&rig, &[]).unwrap();
    let labels = dominant_joint_parts(&rig, &posed.influences, &PartsConfig { min_part_vertices: 50 });
    assert_eq!(labels.names, ["upper", "lower"]);
    let y = |v: usize| posed.poses.poses[0][v].y;
    for v in 0..labels.vertex_count() {
        // The blend is symmetric about y = 1; the tie at y = 1 goes to the lower joint index.
        let expected = u32::from(y(v) > 1.0 + 1e-6);
        assert_eq!(labels.labels[v], expected, "vertex {v} at y = {}", y(v));
    }
    // A part below the minimum joins its parent.
    let merged = dominant_joint_parts(&rig, &posed.influences, &PartsConfig { min_part_vertices: 150 });
    assert_eq!(merged.names, ["upper"]);
}

/// Simplifies the welded limb to `target` vertices with stage 3 (its seams kept when
/// `seams` is true) and maps it with stage 4.
fn simplify_limb(
    rig: &Rig,
    placement: desal_simplify::Placement,
    target: usize,
    seams: bool,
) -> (desal_rig::PosedRig, TriMesh, Vec<u32>) {
    let config = FrameConfig { source: PoseSource::Both, frames: 6, seed: 1, max_degrees: 30.0 };
    let frames = sample_frames(rig, &config, Path::new("limb.glb")).unwrap();
    let posed = pose_rig(rig, &frames).unwrap();
    let template = posed.poses.template_mesh();
    let simplify_config = desal_simplify::SimplifyConfig {
        target: desal_simplify::Target::Vertices(target),
        placement,
        ..desal_simplify::SimplifyConfig::default()
    };
    let seam_edges = desal_rig::seam_edges(&rig.mesh, &posed.weld);
    let mut input = desal_simplify::SimplifyInput::new(&template);
    if seams {
        input = input.with_seams(&seam_edges);
    }
    let simplified = desal_simplify::simplify(&input, &simplify_config).unwrap();
    let labels = desal_mesh::PartLabels::from_ids(vec![0; template.vertex_count()]);
    let mode = match simplified.subset_indices() {
        Some(_) => "subset",
        None => "greedy",
    };
    let kept = simplified.subset_indices();
    let map_mode = match (&kept, mode) {
        (Some(k), "subset") => desal_map::MapMode::Subset { kept_orig: k },
        _ => desal_map::MapMode::Greedy,
    };
    let mapped = desal_map::map_pose_set(
        &desal_map::MapConfig::default(),
        map_mode,
        &simplified.mesh,
        &posed.poses,
        &labels,
    )
    .unwrap();
    (posed, simplified.mesh, mapped.map.simp_to_orig)
}

/// The chart of a UV: 0 (upper, v <= 0.5) or 1 (lower, v >= 0.55).
fn chart(uv: [f32; 2]) -> u8 {
    assert!(uv[1] <= 0.5 || uv[1] >= 0.55, "{uv:?} lies between the charts");
    u8::from(uv[1] >= 0.55)
}

#[test]
fn the_simplified_limb_keeps_its_uv_seams_and_exact_weights_with_subset_placement() {
    let rig = limb();
    let (posed, mesh, simp_to_welded) = simplify_limb(&rig, desal_simplify::Placement::Subset, 60, false);
    let input = SimplifiedInput {
        positions: &mesh.positions,
        faces: &mesh.faces,
        simp_to_welded: &simp_to_welded,
        subset: true,
    };
    let targets = PoseTargets { joints: &posed.joints, positions: &posed.poses.poses };
    let (out, report) = simplified_rig(&rig, &posed.weld, &input, &targets).unwrap();
    assert_eq!(report.simplified_vertices, mesh.vertex_count());
    assert_eq!(report.output_faces, mesh.face_count());
    // Both seams survive: vertices on them are written once per side.
    assert!(report.seam_vertices > 0 && report.output_vertices > report.simplified_vertices, "{report:?}");
    let uvs = out.mesh.uvs.as_ref().unwrap();
    let split_uvs = rig.mesh.uvs.as_ref().unwrap();
    let mut straddling = 0;
    for (f, t) in out.mesh.triangles.iter().enumerate() {
        let corners = t.map(|v| uvs[v as usize]);
        // One chart per face whenever the corners' copies allow it: a face that the
        // simplification stretched across the seam ring (corners only in the upper chart
        // and only in the lower one) cannot be helped here, and is counted.
        let charts_of = |c: usize| -> Vec<u8> {
            let welded = simp_to_welded[mesh.faces[f][c] as usize] as usize;
            posed.weld.copies_of(welded).iter().map(|&s| chart(split_uvs[s as usize])).collect()
        };
        let common = (0..2u8).any(|k| (0..3).all(|c| charts_of(c).contains(&k)));
        if common {
            assert!(corners.iter().all(|&uv| chart(uv) == chart(corners[0])), "face {f}: {corners:?}");
        } else {
            straddling += 1;
        }
        let us = corners.map(|uv| uv[0]);
        let span = us.iter().cloned().fold(f32::MIN, f32::max) - us.iter().cloned().fold(f32::MAX, f32::min);
        assert!(span < 0.5, "face {f} crosses the wrap seam: {corners:?}");
    }
    assert_eq!(straddling, report.cross_chart_faces, "{report:?}");
    // Every written vertex is a split input vertex: same position, weights and attributes.
    for v in 0..out.mesh.vertex_count() {
        let same = (0..rig.mesh.vertex_count()).any(|s| {
            rig.mesh.positions[s] == out.mesh.positions[v]
                && rig.mesh.uvs.as_ref().unwrap()[s] == uvs[v]
                && rig.mesh.influences.of(s).eq(out.mesh.influences.of(v))
        });
        assert!(same, "output vertex {v} is not an input vertex");
    }
    // Skeleton, inverse bind matrices and animations are the input's.
    assert_eq!((&out.nodes, &out.skin, &out.animations), (&rig.nodes, &rig.skin, &rig.animations));
    // And it is a file the reader takes back.
    let back = read(&write_glb(&out).unwrap()).unwrap();
    assert_eq!(without_provenance(back), without_provenance(out));
}

/// `rig` without what says where its mesh came from (its primitives, its source vertices).
fn without_provenance(mut rig: Rig) -> Rig {
    rig.mesh.primitives.clear();
    rig.meshes.clear();
    rig.mesh.sources.clear();
    rig
}

/// The weld's seam edges are exactly the two seams: the wrap seam along the limb (its
/// `RINGS - 1` edges at segment 0) and the chart seam around it (the `SEGMENTS` edges of
/// ring `MID`).
#[test]
fn the_seam_edges_are_the_wrap_seam_and_the_chart_seam() {
    let rig = limb();
    let posed = pose_rig(&rig, &[]).unwrap();
    let seams = desal_rig::seam_edges(&rig.mesh, &posed.weld);
    let at = |v: u32| posed.poses.poses[0][v as usize];
    let mut wrap = 0;
    let mut around = 0;
    for &[a, b] in &seams {
        let (pa, pb) = (at(a), at(b));
        if pa.z.abs() < 1e-6 && pb.z.abs() < 1e-6 && pa.x > 0.0 && pb.x > 0.0 {
            wrap += 1;
        } else if (pa.y - 1.0).abs() < 1e-6 && (pb.y - 1.0).abs() < 1e-6 {
            around += 1;
        }
    }
    assert_eq!((wrap, around, seams.len()), (RINGS - 1, SEGMENTS, RINGS - 1 + SEGMENTS), "{seams:?}");
}

/// With its seams kept, the simplified limb has no face stretched across a UV chart
/// (subset and optimal placement); without them, the same simplification has some.
#[test]
fn with_seams_kept_no_simplified_face_crosses_a_chart() {
    let rig = limb();
    let cross_chart = |placement, seams| {
        let (posed, mesh, simp_to_welded) = simplify_limb(&rig, placement, 60, seams);
        let input = SimplifiedInput {
            positions: &mesh.positions,
            faces: &mesh.faces,
            simp_to_welded: &simp_to_welded,
            subset: placement == desal_simplify::Placement::Subset,
        };
        let targets = PoseTargets { joints: &posed.joints, positions: &posed.poses.poses };
        let (_, report) = simplified_rig(&rig, &posed.weld, &input, &targets).unwrap();
        assert_eq!(report.simplified_vertices, 60);
        report.cross_chart_faces
    };
    assert_eq!(cross_chart(desal_simplify::Placement::Subset, true), 0);
    assert_eq!(cross_chart(desal_simplify::Placement::Optimal, true), 0);
    assert!(cross_chart(desal_simplify::Placement::Subset, false) > 0);
}

#[test]
fn optimal_placement_refits_at_most_four_normalised_weights() {
    let rig = limb();
    let (posed, mesh, simp_to_welded) = simplify_limb(&rig, desal_simplify::Placement::Optimal, 60, false);
    let input = SimplifiedInput {
        positions: &mesh.positions,
        faces: &mesh.faces,
        simp_to_welded: &simp_to_welded,
        subset: false,
    };
    let targets = PoseTargets { joints: &posed.joints, positions: &posed.poses.poses };
    let (out, report) = simplified_rig(&rig, &posed.weld, &input, &targets).unwrap();
    assert!(report.max_influences <= 4);
    assert!(report.refitted_vertices > 0, "{report:?}");
    for v in 0..out.mesh.vertex_count() {
        let sum: f32 = out.mesh.influences.of(v).map(|(_, w)| w).sum();
        assert!((sum - 1.0).abs() < 1e-6, "vertex {v}: {sum}");
        assert!(out.mesh.influences.of(v).all(|(_, w)| w > 0.0));
    }
    // The refit is at least as good, over the pose set, as each mapped vertex's own weights.
    let rest: Vec<Vec3> =
        out.mesh.positions.iter().map(|p| Vec3::new(p[0].into(), p[1].into(), p[2].into())).collect();
    let mut own = Influences::new();
    let mut target_of = Vec::new();
    let mut seen = std::collections::HashMap::new();
    for (f, t) in out.mesh.triangles.iter().enumerate() {
        for (c, &v) in t.iter().enumerate() {
            seen.entry(v).or_insert(mesh.faces[f][c]);
        }
    }
    for v in 0..out.mesh.vertex_count() as u32 {
        let welded = simp_to_welded[seen[&v] as usize] as usize;
        own.push_row(posed.influences.of(welded).map(|(j, w)| (j as u16, w)));
        target_of.push(welded);
    }
    let (mut refit_error, mut own_error) = (0.0, 0.0);
    for (k, joints) in posed.joints.iter().enumerate() {
        let a = skin_points(&rest, &out.mesh.influences, joints);
        let b = skin_points(&rest, &own, joints);
        for v in 0..rest.len() {
            let y = posed.poses.poses[k][target_of[v]];
            refit_error += (a[v] - y).norm_squared();
            own_error += (b[v] - y).norm_squared();
        }
    }
    assert!(refit_error <= own_error * (1.0 + 1e-6) + 1e-10, "refit {refit_error} vs own {own_error}");
    read(&write_glb(&out).unwrap()).unwrap();
}

/// The JSON of a `.glb` edited by `edit`, repacked.
fn edit_json(bytes: &[u8], edit: impl FnOnce(&mut serde_json::Value)) -> Vec<u8> {
    let glb = gltf::binary::Glb::from_slice(bytes).unwrap();
    let mut json: serde_json::Value = serde_json::from_slice(&glb.json).unwrap();
    edit(&mut json);
    let json = serde_json::to_vec(&json).unwrap();
    gltf::binary::Glb { header: glb.header, json: json.into(), bin: glb.bin }.to_vec().unwrap()
}

fn message(result: Result<Rig, RigError>) -> String {
    result.expect_err("must be refused").to_string()
}

#[test]
fn a_mesh_without_a_skin_is_refused() {
    let bytes = edit_json(&write_glb(&limb()).unwrap(), |j| {
        j["nodes"][2].as_object_mut().unwrap().remove("skin");
    });
    let m = message(read(&bytes));
    assert!(m.starts_with("limb.glb: no skinned mesh"), "{m}");
}

/// Issue 42, item 2: without `mesh`, every skinned mesh is read (a mesh carried by two
/// nodes once); `mesh` picks one by mesh or node name.
#[test]
fn every_skinned_mesh_is_read_and_mesh_picks_one() {
    let bytes = edit_json(&write_glb(&limb()).unwrap(), |j| {
        j["nodes"].as_array_mut().unwrap().push(serde_json::json!({"name": "body2", "mesh": 0, "skin": 0}));
        j["scenes"][0]["nodes"].as_array_mut().unwrap().push(3.into());
    });
    let one = read(&bytes).unwrap();
    assert_eq!((one.meshes.len(), one.mesh_node), (1, 2), "one mesh, from its first node");
    let picked =
        read_rig_from(Path::new("limb.glb"), &bytes, &ReadOptions { mesh: Some(vec!["body2".into()]) })
            .unwrap();
    assert_eq!(picked.mesh_node, 3);
    let m = message(read_rig_from(
        Path::new("limb.glb"),
        &bytes,
        &ReadOptions { mesh: Some(vec!["arm".into()]) },
    ));
    assert!(m.contains("limb.glb: mesh = 'arm' names no skinned mesh"), "{m}");
    let by_index = ReadOptions { mesh: Some(vec!["0".into()]) };
    assert_eq!(read_rig_from(Path::new("limb.glb"), &bytes, &by_index).unwrap().mesh_node, 2, "mesh 0");
}

/// The limb with a second skinned mesh, `sleeve`: the limb's own accessors (so the same
/// positions) on node `sleeve`, skinned by a second skin over the same joints in the
/// other order with the same inverse bind matrices.
fn limb_and_sleeve() -> Vec<u8> {
    let rig = limb();
    let glb = write_glb(&rig).unwrap();
    let parsed = gltf::binary::Glb::from_slice(&glb).unwrap();
    let mut j: serde_json::Value = serde_json::from_slice(&parsed.json).unwrap();
    let mut bin = parsed.bin.unwrap().into_owned();
    let swapped: Vec<u8> = [rig.skin.inverse_bind[1], rig.skin.inverse_bind[0]]
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let views = j["bufferViews"].as_array_mut().unwrap();
    views.push(serde_json::json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": swapped.len()}));
    let view = views.len() - 1;
    bin.extend(swapped);
    j["buffers"][0]["byteLength"] = bin.len().into();
    let accessors = j["accessors"].as_array_mut().unwrap();
    accessors
        .push(serde_json::json!({"bufferView": view, "componentType": 5126, "count": 2, "type": "MAT4"}));
    let ibm = accessors.len() - 1;
    let mut sleeve = j["meshes"][0].clone();
    sleeve["name"] = "sleeve".into();
    j["meshes"].as_array_mut().unwrap().push(sleeve);
    let mut skin = j["skins"][0].clone();
    skin["joints"] = serde_json::json!([1, 0]);
    skin["inverseBindMatrices"] = ibm.into();
    j["skins"].as_array_mut().unwrap().push(skin);
    j["nodes"].as_array_mut().unwrap().push(serde_json::json!({"name": "sleeve", "mesh": 1, "skin": 1}));
    j["scenes"][0]["nodes"].as_array_mut().unwrap().push(3.into());
    let json = serde_json::to_vec(&j).unwrap();
    gltf::binary::Glb { header: parsed.header, json: json.into(), bin: Some(bin.into()) }.to_vec().unwrap()
}

/// Issue 42, item 2: two skinned meshes are one rig: their skins merged (joints matched by
/// node and inverse bind matrix), their vertices never welded together, both simplified
/// together and written back each into its own mesh, each with its own skin's joints.
#[test]
fn issue_42_two_skinned_meshes_are_simplified_together_and_written_apart() {
    let bytes = limb_and_sleeve();
    let (rig, source) =
        desal_rig::read_rig_and_document(Path::new("limb.glb"), &bytes, &ReadOptions::default()).unwrap();
    let single = limb();
    assert_eq!(rig.skin.joints, single.skin.joints, "the second skin's joints are the first's");
    assert_eq!(rig.meshes.len(), 2);
    assert_eq!((rig.meshes[1].name.as_str(), rig.meshes[1].joints.as_slice()), ("sleeve", &[1u16, 0][..]));
    let n = single.mesh.vertex_count() as u32;
    assert_eq!((rig.meshes[0].vertices.clone(), rig.meshes[1].vertices.clone()), (0..n, n..2 * n));
    // The sleeve shares the limb's JOINTS_0, which its skin reads the other way round.
    let swapped = |v: usize| rig.mesh.influences.of(v).map(|(j, w)| (1 - j, w)).collect::<Vec<_>>();
    assert!(
        (0..n as usize).all(|v| swapped(v) == rig.mesh.influences.of(v + n as usize).collect::<Vec<_>>())
    );
    let weld = desal_rig::Weld::new(&rig.mesh);
    assert_eq!(
        weld.welded_count(),
        2 * desal_rig::Weld::new(&single.mesh).welded_count(),
        "never welded across"
    );

    let (posed, mesh, simp_to_welded) = simplify_limb(&rig, desal_simplify::Placement::Subset, 120, true);
    let input = SimplifiedInput {
        positions: &mesh.positions,
        faces: &mesh.faces,
        simp_to_welded: &simp_to_welded,
        subset: true,
    };
    let targets = PoseTargets { joints: &posed.joints, positions: &posed.poses.poses };
    let (out, _) = simplified_rig(&rig, &posed.weld, &input, &targets).unwrap();
    assert_eq!(out.mesh.primitives.iter().map(|p| p.mesh).collect::<Vec<_>>(), [0, 1], "both meshes kept");
    let edited = desal_rig::write_edited(&source, &rig, &out).unwrap();
    let (json, bin) = json_and_bin(&edited.bytes);
    assert_eq!(json["skins"], json_and_bin(&bytes).0["skins"], "both skins as they were");
    let back = read(&edited.bytes).unwrap();
    assert_eq!(back.meshes.len(), 2);
    // Each written vertex is its source vertex, with its own skin's joint numbers: the
    // sleeve's JOINTS_0 names its skin's joints ([1, 0]), so joint 0 there is the limb's 1.
    let joints_of = |m: usize| -> Vec<u16> {
        let a = &json["accessors"]
            [json["meshes"][m]["primitives"][0]["attributes"]["JOINTS_0"].as_u64().unwrap() as usize];
        view_bytes(&json, &bin, &a["bufferView"])
            .chunks_exact(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]]))
            .collect()
    };
    let (limb_joints, sleeve_joints) = (joints_of(0), joints_of(1));
    assert_eq!(out.meshes[1].vertices.start, out.meshes[0].vertices.end);
    for (part, input_part) in out.meshes.iter().zip(&rig.meshes) {
        for v in part.vertices.clone() {
            let s = out.mesh.sources[v as usize] as usize;
            assert!(input_part.vertices.contains(&(s as u32)), "vertex {v} comes from its own mesh");
            assert_eq!(out.mesh.positions[v as usize], rig.mesh.positions[s]);
        }
    }
    let first_sleeve = out.mesh.primitives[1].vertices.start as usize;
    let local = |v: usize| out.mesh.influences.of(v).map(|(j, _)| j as u16).collect::<Vec<_>>();
    assert_eq!(limb_joints[..local(0).len()], local(0)[..]);
    let sleeve_local: Vec<u16> = local(first_sleeve).iter().map(|&j| 1 - j).collect();
    assert_eq!(sleeve_joints[..sleeve_local.len()], sleeve_local[..]);
}

/// Weights off 1 (quantised, as exporters write them) are renormalised and counted, the
/// worst vertex named; weights within the tolerance are kept as written; a vertex with
/// no weight at all is refused with the vertex.
#[test]
fn weights_off_one_are_renormalised_and_counted_and_all_zero_is_refused() {
    let mut rig = limb();
    let v = rig.mesh.influences.offsets.iter().position(|&o| o > 7).unwrap() - 1;
    let row = rig.mesh.influences.offsets[v] as usize..rig.mesh.influences.offsets[v + 1] as usize;
    rig.mesh.influences.weights[7] *= 0.5;
    let sum: f64 = rig.mesh.influences.weights[row.clone()].iter().map(|&w| f64::from(w)).sum();
    let read_back = read(&write_glb(&rig).unwrap()).unwrap();
    assert_eq!(read_back.weight_sums.renormalised, 1);
    assert_eq!(read_back.weight_sums.off_by_more_than_2pct, usize::from((sum - 1.0).abs() > 0.02));
    assert_eq!(read_back.weight_sums.worst.map(|(vertex, _)| vertex), Some(v));
    let note = read_back.weight_sums.note().unwrap();
    assert!(note.contains(&format!("worst: vertex {v} summed to")), "{note}");
    let renormalised: f64 =
        read_back.mesh.influences.weights[row.clone()].iter().map(|&w| f64::from(w)).sum();
    assert!((renormalised - 1.0).abs() < 1e-6, "{renormalised}");
    // The untouched rig reads as written, with nothing renormalised.
    let as_written = read(&write_glb(&limb()).unwrap()).unwrap();
    assert_eq!(as_written.weight_sums, desal_rig::model::WeightSums::default());
    assert_eq!(as_written.weight_sums.note(), None);

    for w in &mut rig.mesh.influences.weights[row] {
        *w = 0.0;
    }
    let m = message(read(&write_glb(&rig).unwrap()));
    assert!(m.contains(&format!("mesh 'limb' vertex {v}: every skinning weight is zero")), "{m}");
}

/// A file that declares Draco or meshopt compression is refused, naming the extension
/// and how to decompress it first (issue 42, item 4).
#[test]
fn compressed_meshes_are_refused_saying_how_to_decompress() {
    for extension in ["KHR_draco_mesh_compression", "EXT_meshopt_compression"] {
        let bytes = edit_json(&write_glb(&limb()).unwrap(), |j| {
            j["extensionsUsed"] = serde_json::json!([extension]);
            j["extensionsRequired"] = serde_json::json!([extension]);
        });
        let m = message(read(&bytes));
        assert!(m.contains(&format!("compressed ({extension})")) && m.contains("decompress it first"), "{m}");
    }
}

#[test]
fn a_joint_the_skin_does_not_have_is_refused() {
    let mut rig = limb();
    rig.mesh.influences.joints[0] = 5;
    let m = message(read(&write_glb(&rig).unwrap()));
    assert!(m.contains("vertex 0: joint 5 has weight 1, but skin 'skin' has only 2 joints"), "{m}");
}

/// The limb with two morph targets: `wide` moves every vertex (dense), `blink` two of
/// them (a sparse accessor over no buffer view); named in `extras.targetNames`, with
/// default weights.
fn limb_with_morph_targets() -> Vec<u8> {
    use serde_json::json;
    let glb = write_glb(&limb()).unwrap();
    let parsed = gltf::binary::Glb::from_slice(&glb).unwrap();
    let mut j: serde_json::Value = serde_json::from_slice(&parsed.json).unwrap();
    let mut bin = parsed.bin.unwrap().into_owned();
    let n = limb().mesh.vertex_count();
    let dense: Vec<u8> = (0..n).flat_map(wide_delta).flat_map(|x| x.to_le_bytes()).collect();
    let sparse_indices: Vec<u8> = [3u16, 10].iter().flat_map(|i| i.to_le_bytes()).collect();
    let sparse_values: Vec<u8> =
        [[0.0f32, 0.0, 0.5], [0.0, 0.0, -0.5]].iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    let mut view = |bytes: &[u8]| {
        let views = j["bufferViews"].as_array_mut().unwrap();
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len()}));
        bin.extend_from_slice(bytes);
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        views.len() - 1
    };
    let (dense_view, index_view, value_view) = (view(&dense), view(&sparse_indices), view(&sparse_values));
    let accessors = j["accessors"].as_array_mut().unwrap();
    let extent = (n as f32 - 1.0) * 0.001;
    accessors.push(json!({"bufferView": dense_view, "componentType": 5126, "count": n, "type": "VEC3",
        "min": [0.0, 0.0, 0.0], "max": [extent, 0.0, 0.0]}));
    accessors.push(json!({"componentType": 5126, "count": n, "type": "VEC3", "min": [0.0, 0.0, -0.5], "max": [0.0, 0.0, 0.5],
        "sparse": {"count": 2, "indices": {"bufferView": index_view, "componentType": 5123},
                   "values": {"bufferView": value_view}}}));
    let (wide, blink) = (accessors.len() - 2, accessors.len() - 1);
    j["buffers"][0]["byteLength"] = bin.len().into();
    j["meshes"][0]["primitives"][0]["targets"] = json!([{"POSITION": wide}, {"POSITION": blink}]);
    j["meshes"][0]["weights"] = json!([0.25, 0.0]);
    j["meshes"][0]["extras"] = json!({"targetNames": ["wide", "blink"]});
    let json = serde_json::to_vec(&j).unwrap();
    gltf::binary::Glb { header: parsed.header, json: json.into(), bin: Some(bin.into()) }.to_vec().unwrap()
}

fn wide_delta(v: usize) -> [f32; 3] {
    [v as f32 * 0.001, 0.0, 0.0]
}

/// Issue 42, item 3: morph targets are kept. Each kept vertex keeps its own deltas (the
/// sparse target read and written dense), and the targets' names and default weights stay.
#[test]
fn issue_42_morph_targets_are_kept_with_each_kept_vertex_s_deltas() {
    let bytes = limb_with_morph_targets();
    let path = Path::new("limb.glb");
    let (rig, source) = desal_rig::read_rig_and_document(path, &bytes, &ReadOptions::default()).unwrap();
    let (posed, mesh, simp_to_welded) = simplify_limb(&rig, desal_simplify::Placement::Subset, 60, true);
    let input = SimplifiedInput {
        positions: &mesh.positions,
        faces: &mesh.faces,
        simp_to_welded: &simp_to_welded,
        subset: true,
    };
    let targets = PoseTargets { joints: &posed.joints, positions: &posed.poses.poses };
    let (out, _) = simplified_rig(&rig, &posed.weld, &input, &targets).unwrap();
    let edited = desal_rig::write_edited(&source, &rig, &out).unwrap();
    let (json, bin) = json_and_bin(&edited.bytes);
    assert_eq!(json["meshes"][0]["weights"], serde_json::json!([0.25, 0.0]));
    assert_eq!(json["meshes"][0]["extras"]["targetNames"], serde_json::json!(["wide", "blink"]));
    let delta = |t: usize| -> Vec<[f32; 3]> {
        let a = &json["accessors"]
            [json["meshes"][0]["primitives"][0]["targets"][t]["POSITION"].as_u64().unwrap() as usize];
        assert!(a.get("sparse").is_none() && a.get("min").is_some());
        let floats: Vec<f32> = view_bytes(&json, &bin, &a["bufferView"])
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        floats.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
    };
    let (wide, blink) = (delta(0), delta(1));
    assert_eq!(wide.len(), out.mesh.vertex_count());
    let mut blinking = 0;
    for (v, &s) in out.mesh.sources.iter().enumerate() {
        assert_eq!(wide[v], wide_delta(s as usize), "vertex {v}");
        let expected = match s {
            3 => [0.0, 0.0, 0.5],
            10 => [0.0, 0.0, -0.5],
            _ => [0.0; 3],
        };
        blinking += usize::from(expected != [0.0; 3]);
        assert_eq!(blink[v], expected, "vertex {v}");
    }
    // Vertices 3 and 10 lie on the open end ring, which simplification keeps.
    assert_eq!(blinking, 2, "both blinking vertices are kept");
    // The output reads back.
    read(&edited.bytes).unwrap();
}

/// A morph target with another count than its primitive's vertices is refused at read.
#[test]
fn a_morph_target_of_the_wrong_count_is_refused() {
    let bytes = edit_json(&write_glb(&limb()).unwrap(), |j| {
        j["meshes"][0]["primitives"][0]["targets"] = serde_json::json!([{"POSITION": 5}]);
    });
    let m = message(read(&bytes));
    assert!(m.contains("mesh 'limb' primitive 0: morph target 0 POSITION has"), "{m}");
}

#[test]
fn poses_from_animations_need_an_animation() {
    let mut rig = limb();
    rig.animations.clear();
    let err = sample_frames(&rig, &FrameConfig::default(), Path::new("limb.glb")).unwrap_err();
    assert!(err.to_string().starts_with("limb.glb: poses = \"animations\""), "{err}");
}

/// The limb as an avatar document: two materials (one with an extension), textures, a
/// sampler, an embedded image and one beside the file, a camera and a light on a node, a
/// rigid visor mesh on the lower joint, VRM 0.x and 1.0 extensions, `extras` on every
/// kind of element, and a `COLOR_0` of 3-byte elements. Returns the `.vrm` bytes.
fn avatar_document(dir: &Path) -> Vec<u8> {
    use serde_json::json;
    std::fs::create_dir_all(dir.join("tex")).unwrap();
    std::fs::write(dir.join("tex/skin.png"), EXTERNAL_IMAGE).unwrap();
    let rig = limb();
    let glb = write_glb(&rig).unwrap();
    let parsed = gltf::binary::Glb::from_slice(&glb).unwrap();
    let mut j: serde_json::Value = serde_json::from_slice(&parsed.json).unwrap();
    let mut bin = parsed.bin.unwrap().into_owned();
    let mut view = |bin: &mut Vec<u8>, bytes: &[u8], stride: Option<usize>| {
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let views = j["bufferViews"].as_array_mut().unwrap();
        let mut v = json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len()});
        if let Some(stride) = stride {
            v["byteStride"] = stride.into();
        }
        views.push(v);
        bin.extend_from_slice(bytes);
        views.len() - 1
    };
    let image_view = view(&mut bin, EMBEDDED_IMAGE, None);
    let n = rig.mesh.vertex_count();
    let colours: Vec<u8> = (0..n).flat_map(|v| [v as u8, (3 * v) as u8, 7, 0]).collect();
    let colour_view = view(&mut bin, &colours[..4 * n - 1], Some(4));
    let visor: Vec<u8> = [[0.0f32, 1.5, 0.3], [0.1, 1.5, 0.3], [0.0, 1.6, 0.3]]
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let visor_view = view(&mut bin, &visor, None);
    // A second influence set of zeros, as exporters write for 8 influences: the output
    // needs one set, so two freed accessor slots are left over.
    let zeros_view = view(&mut bin, &vec![0; 16 * n], None);
    let accessors = j["accessors"].as_array_mut().unwrap();
    accessors.push(json!({"bufferView": colour_view, "componentType": 5121, "normalized": true, "count": n, "type": "VEC3"}));
    accessors.push(json!({"bufferView": visor_view, "componentType": 5126, "count": 3, "type": "VEC3",
        "min": [0.0, 1.5, 0.3], "max": [0.1, 1.6, 0.3], "name": "visor positions"}));
    accessors.push(json!({"bufferView": zeros_view, "componentType": 5123, "count": n, "type": "VEC4"}));
    accessors.push(json!({"bufferView": zeros_view, "componentType": 5126, "count": n, "type": "VEC4"}));
    let (colour, visor) = (accessors.len() - 4, accessors.len() - 3);
    let (joints_1, weights_1) = (accessors.len() - 2, accessors.len() - 1);
    j["buffers"][0]["byteLength"] = bin.len().into();
    let primitive = &mut j["meshes"][0]["primitives"][0];
    primitive["attributes"]["COLOR_0"] = colour.into();
    primitive["attributes"]["JOINTS_1"] = joints_1.into();
    primitive["attributes"]["WEIGHTS_1"] = weights_1.into();
    primitive["material"] = 0.into();
    primitive["extras"] = json!({"note": "kept"});
    j["meshes"][0]["extras"] = json!({"targetNames": []});
    j["meshes"]
        .as_array_mut()
        .unwrap()
        .push(json!({"name": "visor", "primitives": [{"attributes": {"POSITION": visor}, "material": 1}]}));
    let nodes = j["nodes"].as_array_mut().unwrap();
    nodes[1]["children"] = json!([3]);
    nodes[0]["extras"] = json!({"bone": "upper"});
    nodes.push(json!({"name": "visor", "mesh": 1, "translation": [0.0, 0.5, 0.0]}));
    nodes.push(json!({"name": "eye", "camera": 0, "extensions": {"KHR_lights_punctual": {"light": 0}}}));
    j["scenes"][0]["nodes"].as_array_mut().unwrap().push(4.into());
    j["scenes"][0]["name"] = "avatar".into();
    j["scenes"][0]["extras"] = json!({"lod": 0});
    j["skins"][0]["extras"] = json!({"rig": "limb"});
    j["animations"][0]["extras"] = json!({"loop": true});
    j["materials"] = json!([
        {"name": "skin", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}, "extras": {"shader": "toon"},
         "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2.0}}},
        {"name": "visor", "pbrMetallicRoughness": {"baseColorTexture": {"index": 1}, "metallicFactor": 0.5}}
    ]);
    j["textures"] = json!([{"sampler": 0, "source": 0}, {"sampler": 0, "source": 1, "name": "external"}]);
    j["samplers"] = json!([{"magFilter": 9729, "minFilter": 9987, "wrapS": 33648}]);
    j["images"] = json!([
        {"bufferView": image_view, "mimeType": "image/png", "name": "embedded"},
        {"uri": "tex/skin.png", "name": "beside"}
    ]);
    j["cameras"] = json!([{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01}}]);
    j["extensions"] = json!({
        "KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 3.0}]},
        "VRM": {"meta": {"title": "limb", "texture": 1}, "blendShapeMaster": {"blendShapeGroups": [{"name": "A", "binds": []}]}},
        "VRMC_vrm": {"specVersion": "1.0", "meta": {"name": "limb", "licenseUrl": "https://example.org"}}
    });
    j["extensionsUsed"] =
        json!(["KHR_lights_punctual", "KHR_materials_emissive_strength", "VRM", "VRMC_vrm"]);
    j["extras"] = json!({"author": "desal tests", "list": [1, 2, 3]});
    j["asset"]["copyright"] = "CC0".into();
    let json = serde_json::to_vec(&j).unwrap();
    gltf::binary::Glb { header: parsed.header, json: json.into(), bin: Some(bin.into()) }.to_vec().unwrap()
}

const EMBEDDED_IMAGE: &[u8] = b"\x89PNG\r\n\x1a\n embedded, 31 bytes";
const EXTERNAL_IMAGE: &[u8] = b"\x89PNG\r\n\x1a\n beside the file";

/// The JSON and binary chunk of a `.glb`.
fn json_and_bin(glb: &[u8]) -> (serde_json::Value, Vec<u8>) {
    let glb = gltf::binary::Glb::from_slice(glb).unwrap();
    (serde_json::from_slice(&glb.json).unwrap(), glb.bin.unwrap().into_owned())
}

/// The bytes of buffer view `v`.
fn view_bytes<'a>(json: &serde_json::Value, bin: &'a [u8], v: &serde_json::Value) -> &'a [u8] {
    let view = &json["bufferViews"][v.as_u64().unwrap() as usize];
    let offset = view["byteOffset"].as_u64().unwrap_or(0) as usize;
    &bin[offset..offset + view["byteLength"].as_u64().unwrap() as usize]
}

/// Issue 42, item 1: the simplified document is the input's with the simplified
/// primitive's accessors, the buffer views and the buffer changed, and nothing else.
#[test]
fn issue_42_the_simplified_document_changes_only_the_simplified_primitive() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = avatar_document(dir.path());
    let path = dir.path().join("avatar.vrm");
    let (rig, source) = desal_rig::read_rig_and_document(&path, &bytes, &ReadOptions::default()).unwrap();
    assert_eq!(source.output_extension(), "vrm", "a .vrm comes back as a .vrm");
    let (posed, mesh, simp_to_welded) = simplify_limb(&rig, desal_simplify::Placement::Subset, 60, true);
    let input = SimplifiedInput {
        positions: &mesh.positions,
        faces: &mesh.faces,
        simp_to_welded: &simp_to_welded,
        subset: true,
    };
    let targets = PoseTargets { joints: &posed.joints, positions: &posed.poses.poses };
    let (out, _) = simplified_rig(&rig, &posed.weld, &input, &targets).unwrap();
    let edited = desal_rig::write_edited(&source, &rig, &out).unwrap();

    let (before, before_bin) = json_and_bin(&bytes);
    let (after, after_bin) = json_and_bin(&edited.bytes);
    let keys = |j: &serde_json::Value| j.as_object().unwrap().keys().cloned().collect::<Vec<_>>();
    assert_eq!(keys(&after), keys(&before));
    for key in keys(&before) {
        if !["accessors", "bufferViews", "buffers", "meshes", "images"].contains(&key.as_str()) {
            assert_eq!(after[&key], before[&key], "{key}");
        }
    }
    // Meshes: equal but for the simplified primitives' accessor numbers (the limb's and
    // the rigid visor's).
    let strip = |j: &serde_json::Value| {
        let mut meshes = j["meshes"].clone();
        let primitive = meshes[0]["primitives"][0].as_object_mut().unwrap();
        let names = keys(&primitive["attributes"]);
        primitive.remove("attributes");
        primitive.remove("indices");
        let visor = meshes[1]["primitives"][0].as_object_mut().unwrap();
        assert_eq!(keys(&visor["attributes"]), ["POSITION"], "the rigid visor stays rigid");
        visor.remove("attributes");
        visor.remove("indices");
        (meshes, names)
    };
    let (after_meshes, after_names) = strip(&after);
    let (before_meshes, mut before_names) = strip(&before);
    assert_eq!(after_meshes, before_meshes);
    before_names.retain(|n| !n.ends_with("_1"));
    assert_eq!(after_names, before_names, "one influence set is enough");
    // No accessor moved: of the two slots JOINTS_1 and WEIGHTS_1 freed, the visor's new
    // indices (it had none) take one, and the other holds one zero.
    assert_eq!(after["accessors"].as_array().unwrap().len(), before["accessors"].as_array().unwrap().len());
    let leftovers: Vec<&serde_json::Value> =
        after["accessors"].as_array().unwrap().iter().filter(|a| a["count"] == 1).collect();
    assert_eq!(leftovers.len(), 1, "{leftovers:?}");
    for a in leftovers {
        assert_eq!(view_bytes(&after, &after_bin, &a["bufferView"]), [0; 4]);
    }
    // Images: equal, their view too, which holds the same bytes; the one beside the file
    // comes back to be written beside the output.
    assert_eq!(after["images"], before["images"]);
    assert_eq!(view_bytes(&after, &after_bin, &after["images"][0]["bufferView"]), EMBEDDED_IMAGE);
    assert_eq!(
        edited.images,
        [desal_rig::ExternalImage { path: "tex/skin.png".into(), bytes: EXTERNAL_IMAGE.to_vec() }]
    );
    // Every accessor a skin or an animation names is where it was, on the same view,
    // holding the same values.
    let named = [
        before["skins"][0]["inverseBindMatrices"].clone(),
        before["animations"][0]["samplers"][0]["input"].clone(),
        before["animations"][0]["samplers"][0]["output"].clone(),
    ];
    for a in named {
        let i = a.as_u64().unwrap() as usize;
        assert_eq!(after["accessors"][i], before["accessors"][i], "accessor {i}");
        let view = &after["accessors"][i]["bufferView"];
        assert_eq!(
            view_bytes(&after, &after_bin, view),
            view_bytes(&before, &before_bin, view),
            "accessor {i}"
        );
    }
    assert_eq!(after["buffers"], serde_json::json!([{"byteLength": after_bin.len()}]));
    // The visor, a mesh without a skin on the lower joint's node, is read as rigidly
    // skinned to that joint, its vertices in the bind space (its node 0.5 above the joint,
    // the joint 1 above the origin where its inverse bind matrix puts it), and written
    // back in its own space: its three vertices kept, their positions exactly the input's.
    let visor = &rig.meshes[1];
    assert_eq!((visor.name.as_str(), visor.skin, visor.joints.as_slice()), ("visor", None, &[1u16][..]));
    assert_eq!(rig.mesh.positions[visor.vertices.start as usize], [0.0, 1.5 + 1.5, 0.3]);
    assert!(rig.mesh.influences.of(visor.vertices.start as usize).eq([(1, 1.0)]));
    // Posed by skinning, it lands where the node tree carries it: the lower joint bent
    // 90° about z takes the visor's first vertex (0, 1.5, 0.3) in its own space to
    // (-2, 1, 0.3).
    let locals = animated_locals(&rig, &rig.animations[0], 1.0);
    let world = desal_rig::pose::world_matrices(&rig, &locals);
    let bind: Vec<Vec3> =
        rig.mesh.positions.iter().map(|p| Vec3::new(p[0].into(), p[1].into(), p[2].into())).collect();
    let skinned = skin_points(&bind, &rig.mesh.influences, &joint_matrices(&rig, &locals));
    let carried =
        desal_rig::pose::transform_point(&world[visor.node], &Vec3::new(0.0, 1.5, f64::from(0.3_f32)));
    let first = skinned[visor.vertices.start as usize];
    assert!(
        (first - carried).norm() < 1e-6 && (first - Vec3::new(-2.0, 1.0, 0.3)).norm() < 1e-6,
        "{first:?}"
    );
    let position = |j: &serde_json::Value, bin: &[u8]| {
        let a = &j["accessors"]
            [j["meshes"][1]["primitives"][0]["attributes"]["POSITION"].as_u64().unwrap() as usize];
        (a["min"].clone(), a["max"].clone(), view_bytes(j, bin, &a["bufferView"]).to_vec())
    };
    assert_eq!(position(&after, &after_bin), position(&before, &before_bin));
    // The simplified primitive reads back as the simplified mesh, and its COLOR_0 (3-byte
    // elements, strided to 4) holds each vertex's source colour.
    let back =
        read_rig_from(&dir.path().join("simplified.vrm"), &edited.bytes, &ReadOptions::default()).unwrap();
    assert_eq!(without_provenance(back.clone()).mesh, without_provenance(out.clone()).mesh);
    let colour = &after["accessors"]
        [after["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"].as_u64().unwrap() as usize];
    assert_eq!((colour["componentType"].as_u64(), colour["normalized"].as_bool()), (Some(5121), Some(true)));
    let colours = view_bytes(&after, &after_bin, &colour["bufferView"]);
    assert_eq!(after["bufferViews"][colour["bufferView"].as_u64().unwrap() as usize]["byteStride"], 4);
    let limb = out.mesh.primitives[0].vertices.clone();
    assert_eq!(colour["count"], limb.len());
    for (v, &source) in out.mesh.sources[limb.start as usize..limb.end as usize].iter().enumerate() {
        let s = source as usize;
        assert_eq!(colours[4 * v..4 * v + 3], [s as u8, (3 * s) as u8, 7], "vertex {v}");
    }
    assert!(out.mesh.vertex_count() < rig.mesh.vertex_count());
}

/// Issue 42, item 5: capping a kept vertex's influences keeps the joints that skin it
/// best, not the largest weights. Three joints weigh 0.4, 0.35 and 0.25; the first two
/// never move apart and the third slides, so the two largest (renormalised) miss the
/// slide in every pose, while the lightest joint with the first two's weight together
/// follows it exactly.
#[test]
fn issue_42_capped_influences_keep_the_joints_that_skin_best() {
    let mut influences = Influences::new();
    for _ in 0..3 {
        influences.push_row([(0, 0.4), (1, 0.35), (2, 0.25)]);
    }
    let mesh = SkinnedMesh {
        name: "tri".into(),
        positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        normals: None,
        uvs: None,
        influences,
        triangles: vec![[0, 1, 2]],
        primitives: Vec::new(),
        sources: Vec::new(),
    };
    let weld = desal_rig::Weld::new(&mesh);
    let x: Vec<Vec3> =
        mesh.positions.iter().map(|p| Vec3::new(p[0].into(), p[1].into(), p[2].into())).collect();
    let joints: Vec<Vec<desal_mesh::math::Mat4>> = (0..4)
        .map(|k| {
            let slide = desal_mesh::math::Mat4::new_translation(&Vec3::new(f64::from(k), 0.0, 0.0));
            vec![desal_mesh::math::Mat4::identity(), desal_mesh::math::Mat4::identity(), slide]
        })
        .collect();
    let positions: Vec<Vec<Vec3>> = (0..4).map(|k| skin_points(&x, &mesh.influences, &joints[k])).collect();
    let input =
        SimplifiedInput { positions: &x, faces: &[[0, 1, 2]], simp_to_welded: &[0, 1, 2], subset: true };
    let targets = PoseTargets { joints: &joints, positions: &positions };
    let options = desal_rig::WeightOptions { max_influences: Some(2) };
    let (rows, _) = desal_rig::simplified_influences(&mesh, &weld, &input, &targets, &options);
    for row in rows {
        assert_eq!(row.len(), 2, "{row:?}");
        let slide = row.iter().find(|w| w.0 == 2).expect("the sliding joint is kept");
        assert!((slide.1 - 0.25).abs() < 1e-5, "{row:?}");
        assert!((row.iter().map(|w| w.1).sum::<f32>() - 1.0).abs() < 1e-6);
    }
    // Uncapped, the weights are the exact ones.
    let (rows, _) = desal_rig::simplified_influences(&mesh, &weld, &input, &targets, &Default::default());
    assert_eq!(rows[0], [(0, 0.4), (1, 0.35), (2, 0.25)]);
}
