//! Generator of the bundled CC0 sample pose set: poses the MakeHuman base body with
//! forward kinematics and linear blend skinning on the `cmu_mb` rig.
//!
//! The story, in [`generate`]:
//! 1. cut the body out of the base mesh (vertices `0..13380`; helper geometry dropped);
//! 2. place the 31 joints at the centroids of the base mesh's joint cubes;
//! 3. normalise the skinning weights per body vertex;
//! 4. per pose of the table: local rotations → forward kinematics → skinning → keep
//!    the feet on the ground → decimetres to metres;
//! 5. label each vertex with its dominant bone's body part (SCAPE's 16 parts), and give
//!    stray islands to the part around them;
//! 6. check every pose (no inverted faces, no new self-intersections) and every part
//!    (enough vertices).
//!
//! [`write_sample`] then writes `poses/<name>.ply` (binary little-endian, f32),
//! `labels.json`, `labels.txt`, `rig.glb` and `avatar.glb` ([`avatar`]: body, eyes and
//! hair on one skin, textured, with face morph targets). Output is deterministic:
//! ordered maps only, fixed file contents, no timestamps.
//!
//! [`smpl_layout::smpl_layout_model`] makes the same body into a CC0 body model in SMPL's
//! layout (desal-bodymodel's fixture).
//!
//! Frame of the output: the OBJ's own — metres, **Y up**, the body facing **+Z**, its
//! left side at **+X**; the template is pose 0 (`00_rest`, the base mesh's A pose).

pub mod avatar;
pub mod error;
pub mod parts;
pub mod poses;
pub mod quality;
pub mod rig;
pub mod skeleton;
pub mod skinning;
pub mod smpl_layout;
pub mod source;

use std::path::{Path, PathBuf};

use desal_io::ply::{PlyWriteOptions, write_ply};
use desal_mesh::{Face, PartLabels, PoseSet, TriMesh, Vec3};

pub use error::SampleError;
pub use poses::{Axis, PoseSpec, Turn, standard_poses};
pub use quality::PoseQuality;
pub use skeleton::{BoneTransform, Skeleton};
pub use skinning::{SkinWeights, WeightsReport, skin};
pub use source::SourceAssets;

/// Settings of [`generate`]. The defaults make the committed `data-samples/`.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleConfig {
    /// Base-mesh vertices `0..body_vertex_count` are the body; faces using any other
    /// vertex are dropped. Default 13380 (MakeHuman hm08).
    pub body_vertex_count: usize,
    /// Factor from OBJ units to output units. Default 0.1 (decimetres to metres).
    pub scale: f64,
    /// Shift each posed body along Y so its lowest point stays at the rest pose's (the
    /// feet stay on the floor in a squat). Default true.
    pub keep_on_ground: bool,
    /// Fewest vertices a body part may have. Default 100.
    pub min_part_vertices: usize,
    /// Refuse a pose with inverted faces or more self-intersections than the rest pose.
    /// Default true.
    pub require_clean_poses: bool,
}

impl Default for SampleConfig {
    fn default() -> Self {
        Self {
            body_vertex_count: 13380,
            scale: 0.1,
            keep_on_ground: true,
            min_part_vertices: 100,
            require_clean_poses: true,
        }
    }
}

/// A generated sample: the registered poses (template first) and their part labels.
#[derive(Debug, Clone)]
pub struct Sample {
    pub poses: PoseSet,
    pub labels: PartLabels,
    /// The same body as a skinned glTF rig whose animation's keyframes are the poses.
    pub rig: desal_rig::Rig,
    /// The body with eyes, hair, textured materials, face morph targets and a short
    /// animation, as one skinned glTF (`avatar.glb`, see [`avatar`]).
    pub avatar: avatar::Avatar,
    pub report: SampleReport,
}

/// Figures of a generated sample.
#[derive(Debug, Clone, PartialEq)]
pub struct SampleReport {
    pub vertex_count: usize,
    pub face_count: usize,
    pub bone_count: usize,
    pub weights: WeightsReport,
    /// Vertex count of every part, by part id.
    pub part_vertices: Vec<usize>,
    /// Connected pieces of every part (1 = a single patch), by part id.
    pub part_pieces: Vec<usize>,
    /// Vertices moved from their dominant bone's part to the part around them because
    /// they formed a stray island.
    pub relabelled_vertices: usize,
    /// Self-intersecting edge/triangle pairs of the rest body (the baseline).
    pub rest_self_intersections: usize,
    /// One entry per pose, in pose order.
    pub poses: Vec<PoseReport>,
}

/// Figures of one generated pose.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseReport {
    pub name: String,
    pub quality: PoseQuality,
    /// Vertical shift applied to keep the body on the ground, in output units (m).
    pub ground_shift: f64,
    /// Largest vertex displacement from the template, in output units (m).
    pub max_displacement: f64,
}

/// Poses the body of `assets` into `poses` (the first is the template and should have
/// no turns). Positions are in output units (see [`SampleConfig::scale`]).
pub fn generate(
    assets: &SourceAssets,
    poses: &[PoseSpec],
    config: &SampleConfig,
) -> Result<Sample, SampleError> {
    let body = extract_body(&assets.base, config.body_vertex_count)?;
    let skeleton = Skeleton::from_assets(assets)?;
    let (weights, weights_report) =
        SkinWeights::from_bone_lists(&skeleton, &assets.weights, body.vertex_count())?;

    let rest_intersections = quality::count_self_intersections(&body.positions, &body.faces);
    let rest_floor = lowest_y(&body.positions);
    let mut posed_sets = Vec::with_capacity(poses.len());
    let mut keyframes = Vec::with_capacity(poses.len());
    let mut pose_reports = Vec::with_capacity(poses.len());
    for pose in poses {
        let local = poses::local_rotations(&skeleton, pose)?;
        let transforms = skeleton.forward_kinematics(&local);
        // `local` is kept for the rig's keyframes.
        let mut posed = skin(&body.positions, &weights, &transforms);
        let quality = quality::measure_pose(&body.positions, &posed, &body.faces, &weights, &transforms);
        check_clean(pose, &quality, rest_intersections, config)?;
        let shift = if config.keep_on_ground { rest_floor - lowest_y(&posed) } else { 0.0 };
        if shift != 0.0 {
            posed.iter_mut().for_each(|p| p.y += shift);
        }
        let posed = to_output_units(&posed, config.scale);
        keyframes.push((local, shift));
        pose_reports.push(PoseReport {
            name: pose.name.clone(),
            quality,
            ground_shift: shift * config.scale,
            max_displacement: 0.0,
        });
        posed_sets.push(posed);
    }
    for (report, posed) in pose_reports.iter_mut().zip(&posed_sets) {
        report.max_displacement = max_distance(&posed_sets[0], posed);
    }

    let mut labels = parts::label_parts(&skeleton, &weights)?;
    let relabelled_vertices = parts::absorb_stray_pieces(&mut labels, &body.faces);
    let part_vertices = parts::check_part_sizes(&labels, config.min_part_vertices)?;
    let part_pieces = parts::part_pieces(&labels, &body.faces);

    let rig = rig::build_rig(&rig::RigInputs {
        body_faces: &body.faces,
        body_positions: &body.positions,
        uvs: &assets.uvs,
        skeleton: &skeleton,
        weights: &weights,
        poses: &keyframes,
        scale: config.scale,
    })?;
    let names: Vec<String> = poses.iter().map(|p| p.name.clone()).collect();
    let avatar = avatar::build_avatar(assets, &rig, &names, config)?;
    let pose_set = PoseSet::try_new(names, posed_sets, body.faces.clone(), 0)?;
    let report = SampleReport {
        vertex_count: body.vertex_count(),
        face_count: body.face_count(),
        bone_count: skeleton.bone_count(),
        weights: weights_report,
        part_vertices,
        part_pieces,
        relabelled_vertices,
        rest_self_intersections: rest_intersections,
        poses: pose_reports,
    };
    Ok(Sample { poses: pose_set, labels, rig, avatar, report })
}

/// The body: vertices `0..body_vertex_count` of `base` and the faces that use only
/// them, in the base mesh's order and units.
pub fn extract_body(base: &TriMesh, body_vertex_count: usize) -> Result<TriMesh, SampleError> {
    if base.vertex_count() < body_vertex_count {
        return Err(SampleError::BaseMeshTooSmall {
            expected: body_vertex_count,
            found: base.vertex_count(),
        });
    }
    let faces: Vec<Face> =
        base.faces.iter().filter(|f| f.iter().all(|&v| (v as usize) < body_vertex_count)).copied().collect();
    Ok(TriMesh { positions: base.positions[..body_vertex_count].to_vec(), faces })
}

/// The rest body in output units: exactly what the template pose holds.
pub fn rest_body(assets: &SourceAssets, config: &SampleConfig) -> Result<TriMesh, SampleError> {
    let body = extract_body(&assets.base, config.body_vertex_count)?;
    Ok(TriMesh { positions: to_output_units(&body.positions, config.scale), faces: body.faces })
}

fn check_clean(
    pose: &PoseSpec,
    quality: &PoseQuality,
    rest_intersections: usize,
    config: &SampleConfig,
) -> Result<(), SampleError> {
    if config.require_clean_poses
        && (quality.inverted_faces > 0 || quality.self_intersections > rest_intersections)
    {
        return Err(SampleError::PoseNotClean {
            pose: pose.name.clone(),
            inverted_faces: quality.inverted_faces,
            intersections: quality.self_intersections,
            rest_intersections,
        });
    }
    Ok(())
}

fn lowest_y(positions: &[Vec3]) -> f64 {
    positions.iter().map(|p| p.y).fold(f64::INFINITY, f64::min)
}

fn to_output_units(positions: &[Vec3], scale: f64) -> Vec<Vec3> {
    positions.iter().map(|p| p * scale).collect()
}

fn max_distance(a: &[Vec3], b: &[Vec3]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (p - q).norm()).fold(0.0, f64::max)
}

/// Comment lines of every pose file's PLY header (no dates or versions: the files must
/// regenerate byte for byte).
fn ply_comments(pose: &str) -> Vec<String> {
    vec![
        format!("desal sample pose {pose}: MakeHuman hm08 body posed on the cmu_mb rig"),
        "source assets CC0 1.0 (MakeHuman / MPFB2); units metres, Y up, facing +Z".to_owned(),
    ]
}

/// File name of the sample rig in the sample folder.
pub const RIG_FILE: &str = "rig.glb";

/// Writes `sample` into `out_dir`: `poses/<name>.ply` per pose, `labels.json`,
/// `labels.txt`, the rig `rig.glb` and the avatar `avatar.glb`. Returns the written paths in that order. Files of poses no longer in
/// the table are not removed.
pub fn write_sample(out_dir: &Path, sample: &Sample) -> Result<Vec<PathBuf>, SampleError> {
    let mut written = Vec::new();
    for (name, positions) in sample.poses.names.iter().zip(&sample.poses.poses) {
        let path = out_dir.join("poses").join(format!("{name}.ply"));
        let mesh = TriMesh { positions: positions.clone(), faces: sample.poses.faces.clone() };
        let options = PlyWriteOptions { comments: ply_comments(name), ..PlyWriteOptions::default() };
        write_ply(&path, &mesh, &options)?;
        written.push(path);
    }
    let json = out_dir.join("labels.json");
    desal_io::labels::write_labels_json(&json, &sample.labels)?;
    written.push(json);
    let txt = out_dir.join("labels.txt");
    desal_io::labels::write_labels_txt(&txt, &sample.labels)?;
    written.push(txt);
    let glb = out_dir.join(RIG_FILE);
    let bytes = desal_rig::write_glb(&sample.rig).map_err(|e| SampleError::Rig(e.to_string()))?;
    desal_io::atomic::write_atomic(&glb, &bytes)?;
    written.push(glb);
    let avatar = out_dir.join(avatar::AVATAR_FILE);
    desal_io::atomic::write_atomic(&avatar, &sample.avatar.glb)?;
    written.push(avatar);
    Ok(written)
}
