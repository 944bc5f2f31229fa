//! Shared test fixtures: a local Kabsch fit for part rotations (stage 1's job, redone
//! here so that this crate's tests do not depend on desal-fit), a synthetic articulated
//! tube posed by linear blend skinning, and the SCAPE loader.

#![allow(dead_code)]

use std::path::{Path, PathBuf};

use desal_mesh::{Face, Mat3, PartLabels, PoseSet, Vec3};

/// Least-squares rotation taking the centred `from` points onto the centred `to` points
/// (Kabsch, with the reflection fix so the result is a proper rotation).
pub fn kabsch(from: &[Vec3], to: &[Vec3]) -> Mat3 {
    let n = from.len() as f64;
    let cf = from.iter().sum::<Vec3>() / n;
    let ct = to.iter().sum::<Vec3>() / n;
    let mut h = Mat3::zeros();
    for (f, t) in from.iter().zip(to) {
        h += (f - cf) * (t - ct).transpose();
    }
    let svd = h.svd(true, true);
    let (u, v_t) = (svd.u.unwrap(), svd.v_t.unwrap());
    let d = (v_t.transpose() * u.transpose()).determinant().signum();
    v_t.transpose() * Mat3::from_diagonal(&Vec3::new(1.0, 1.0, d)) * u.transpose()
}

/// `rotations[pose][part]`: Kabsch rotation of each part from the template to each pose.
pub fn part_rotations(poses: &PoseSet, labels: &PartLabels) -> Vec<Vec<Mat3>> {
    let members = labels.members();
    let template = poses.template_positions();
    poses
        .poses
        .iter()
        .map(|pose| {
            members
                .iter()
                .map(|verts| {
                    let from: Vec<Vec3> = verts.iter().map(|&v| template[v as usize]).collect();
                    let to: Vec<Vec3> = verts.iter().map(|&v| pose[v as usize]).collect();
                    kabsch(&from, &to)
                })
                .collect()
        })
        .collect()
}

pub fn centroid(points: &[Vec3]) -> Vec3 {
    points.iter().sum::<Vec3>() / points.len() as f64
}

pub fn rotation(axis_angle: Vec3) -> Mat3 {
    *nalgebra::Rotation3::from_scaled_axis(axis_angle).matrix()
}

/// An open tube along +x, length 3, radius 0.3, `rings` rings of `ring_size` vertices,
/// split into three parts at x = 1 and x = 2.
pub struct Tube {
    pub template: Vec<Vec3>,
    pub faces: Vec<Face>,
    pub labels: PartLabels,
}

impl Tube {
    pub fn new(rings: usize, ring_size: usize) -> Self {
        let mut template = Vec::new();
        for r in 0..rings {
            let x = 3.0 * r as f64 / (rings - 1) as f64;
            for s in 0..ring_size {
                let a = std::f64::consts::TAU * s as f64 / ring_size as f64;
                template.push(Vec3::new(x, 0.3 * a.cos(), 0.3 * a.sin()));
            }
        }
        let mut faces = Vec::new();
        for r in 0..rings as u32 - 1 {
            for s in 0..ring_size as u32 {
                let n = ring_size as u32;
                let (a, b) = (r * n + s, r * n + (s + 1) % n);
                let (c, d) = (a + n, b + n);
                faces.push([a, b, d]);
                faces.push([a, d, c]);
            }
        }
        let labels = PartLabels::from_ids(template.iter().map(|p| (p.x.floor() as u32).min(2)).collect());
        Self { template, faces, labels }
    }

    /// Linear blend skinning: bone 0 is fixed, bone 1 turns by `bend1` about the joint at
    /// x = 1, bone 2 by a further `bend2` about the joint at x = 2 (carried by bone 1);
    /// weights blend smoothly over ±0.2 around each joint, so the tube bulges and
    /// shrinks there like skin. The whole body is then moved rigidly by `global`.
    pub fn pose(&self, bend1: Vec3, bend2: Vec3, global: (Mat3, Vec3)) -> Vec<Vec3> {
        let j1 = Vec3::new(1.0, 0.0, 0.0);
        let j2 = Vec3::new(2.0, 0.0, 0.0);
        let r1 = rotation(bend1);
        let r2 = r1 * rotation(bend2);
        let t1 = j1 - r1 * j1;
        let t2 = (r1 * j2 + t1) - r2 * j2;
        let smooth = |x: f64, joint: f64| ((x - joint) / 0.2 * 0.5 + 0.5).clamp(0.0, 1.0);
        self.template
            .iter()
            .map(|p| {
                let (s1, s2) = (smooth(p.x, 1.0), smooth(p.x, 2.0));
                let (w0, w1, w2) = (1.0 - s1, s1 - s2, s2);
                let skinned = w0 * p + w1 * (r1 * p + t1) + w2 * (r2 * p + t2);
                global.0 * skinned + global.1
            })
            .collect()
    }

    /// A pose set of the template plus `count` poses with random bends (up to about
    /// 0.9 rad) and random global motions, from `seed`.
    pub fn pose_set(&self, count: usize, seed: u64) -> PoseSet {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut random_vec = |scale: f64| {
            Vec3::new(
                rng.gen_range(-scale..scale),
                rng.gen_range(-scale..scale),
                rng.gen_range(-scale..scale),
            )
        };
        let mut poses = vec![self.template.clone()];
        for _ in 0..count {
            let (b1, b2) = (random_vec(0.5), random_vec(0.5));
            let global = (rotation(random_vec(1.0)), random_vec(2.0));
            poses.push(self.pose(b1, b2, global));
        }
        let names = (0..poses.len()).map(|i| format!("pose{i}")).collect();
        PoseSet::try_new(names, poses, self.faces.clone(), 0).unwrap()
    }
}

/// The SCAPE folder, or `None` (with a printed reason) when this clone has no
/// `../shared` next to it.
pub fn scape_dir() -> Option<PathBuf> {
    desal_testdata::scape_dir()
}

/// All SCAPE poses (mesh000 is the template) and the 16-part labels.
pub fn load_scape(dir: &Path) -> (PoseSet, PartLabels) {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ply"))
        .collect();
    paths.sort();
    let meshes: Vec<_> = paths.iter().map(|p| desal_io::read_mesh(p).unwrap()).collect();
    let names = paths.iter().map(|p| p.file_stem().unwrap().to_string_lossy().into_owned()).collect();
    let faces = meshes[0].faces.clone();
    let poses = meshes.into_iter().map(|m| m.positions).collect();
    let pose_set = PoseSet::try_new(names, poses, faces, 0).unwrap();
    let labels = desal_io::labels::read_labels(&dir.join("vertex_part_labels_16.txt")).unwrap();
    (pose_set, labels)
}

/// `transforms[pose][part]`: stage 1's rigid fit (desal-fit, the real stage) of each part
/// from the template to each pose, as the models take it.
pub fn part_transforms(poses: &PoseSet, labels: &PartLabels) -> Vec<Vec<desal_measures::PartTransform>> {
    let fit =
        desal_fit::fit_pose_set(poses, labels, &desal_fit::FitConfig::default(), &desal_mesh::NoProgress)
            .expect("stage 1 fits the pose set");
    fit.part_fits
        .iter()
        .map(|parts| {
            parts
                .iter()
                .map(|f| desal_measures::PartTransform { rotation: f.linear, translation: f.translation })
                .collect()
        })
        .collect()
}

/// The bundled sample (`data-samples/`, 11 MakeHuman poses, template `00_rest`) and its
/// 16-part labels. It ships with the repository, so it is never absent.
pub fn load_sample() -> (PoseSet, PartLabels) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data-samples");
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir.join("poses"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "ply"))
        .collect();
    paths.sort();
    let meshes: Vec<_> = paths.iter().map(|p| desal_io::read_mesh(p).unwrap()).collect();
    let names = paths.iter().map(|p| p.file_stem().unwrap().to_string_lossy().into_owned()).collect();
    let faces = meshes[0].faces.clone();
    let poses = meshes.into_iter().map(|m| m.positions).collect();
    let pose_set = PoseSet::try_new(names, poses, faces, 0).unwrap();
    let labels = desal_io::labels::read_labels(&dir.join("labels.json")).unwrap();
    (pose_set, labels)
}
