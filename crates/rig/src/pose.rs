//! Posing a rig: sampling its animations (glTF's STEP, LINEAR with quaternion slerp,
//! CUBICSPLINE), random joint rotations within a limit, the nodes' world matrices, and
//! linear blend skinning (Magnenat-Thalmann et al. 1988): `p' = Σ_j w_j · G_j · B_j · p`
//! with `G_j` the joint node's world matrix and `B_j` its inverse bind matrix, as the
//! glTF 2.0 specification defines it (§3.7.3; the mesh node's own transform is ignored).

use desal_mesh::Vec3;
use desal_mesh::math::{Mat4, UnitQuat};
use rand::{Rng, SeedableRng};

use crate::RigError;
use crate::model::{Animation, Channel, Influences, Interpolation, LocalTransform, Path, Rig};

/// A node's local pose: translation, rotation, scale (or a fixed matrix).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LocalPose {
    Trs { translation: Vec3, rotation: UnitQuat, scale: Vec3 },
    Matrix(Mat4),
}

impl LocalPose {
    fn of(transform: &LocalTransform) -> Self {
        match *transform {
            LocalTransform::Trs { translation, rotation, scale } => LocalPose::Trs {
                translation: to_vec3(translation),
                rotation: quat(rotation.map(f64::from)),
                scale: to_vec3(scale),
            },
            LocalTransform::Matrix(m) => LocalPose::Matrix(Mat4::from_column_slice(&m.map(f64::from))),
        }
    }

    fn matrix(&self) -> Mat4 {
        match self {
            LocalPose::Trs { translation, rotation, scale } => {
                let mut m = rotation.to_homogeneous();
                for c in 0..3 {
                    for r in 0..3 {
                        m[(r, c)] *= scale[c];
                    }
                }
                m[(0, 3)] = translation.x;
                m[(1, 3)] = translation.y;
                m[(2, 3)] = translation.z;
                m
            }
            LocalPose::Matrix(m) => *m,
        }
    }
}

/// The rest local pose of every node (the file's node transforms).
pub fn rest_locals(rig: &Rig) -> Vec<LocalPose> {
    rig.nodes.iter().map(|n| LocalPose::of(&n.transform)).collect()
}

/// The local poses of every node at `time` seconds of `animation`; nodes it does not
/// animate keep their rest pose. Times outside a channel's range clamp to its ends.
pub fn animated_locals(rig: &Rig, animation: &Animation, time: f64) -> Vec<LocalPose> {
    let mut locals = rest_locals(rig);
    for channel in &animation.channels {
        if let LocalPose::Trs { translation, rotation, scale } = &mut locals[channel.node] {
            let value = sample_channel(channel, time);
            match channel.path {
                Path::Translation => *translation = Vec3::new(value[0], value[1], value[2]),
                Path::Scale => *scale = Vec3::new(value[0], value[1], value[2]),
                Path::Rotation => *rotation = quat([value[0], value[1], value[2], value[3]]),
            }
        }
    }
    locals
}

/// The value of `channel` at `time` (3 or 4 components).
pub fn sample_channel(channel: &Channel, time: f64) -> Vec<f64> {
    let width = channel.width();
    let cubic = channel.interpolation == Interpolation::CubicSpline;
    let stride = if cubic { 3 * width } else { width };
    // The value (not a tangent) of keyframe k.
    let value = |k: usize| -> Vec<f64> {
        let start = k * stride + if cubic { width } else { 0 };
        channel.values[start..start + width].iter().map(|&x| f64::from(x)).collect()
    };
    let times = &channel.times;
    let last = times.len() - 1;
    if time <= f64::from(times[0]) {
        return value(0);
    }
    if time >= f64::from(times[last]) {
        return value(last);
    }
    // The keyframe interval holding `time`: times[k] <= time < times[k + 1].
    let k = times.partition_point(|&t| f64::from(t) <= time) - 1;
    let (t0, t1) = (f64::from(times[k]), f64::from(times[k + 1]));
    let dt = t1 - t0;
    let s = (time - t0) / dt;
    let (a, b) = (value(k), value(k + 1));
    let mut out: Vec<f64> = match channel.interpolation {
        Interpolation::Step => a,
        Interpolation::Linear if channel.path == Path::Rotation => {
            let q = quat([a[0], a[1], a[2], a[3]]).slerp(&quat([b[0], b[1], b[2], b[3]]), s);
            let c = q.coords;
            vec![c.x, c.y, c.z, c.w]
        }
        Interpolation::Linear => a.iter().zip(&b).map(|(x, y)| x + s * (y - x)).collect(),
        Interpolation::CubicSpline => {
            let out_tangent = |k: usize| -> Vec<f64> {
                let start = k * stride + 2 * width;
                channel.values[start..start + width].iter().map(|&x| f64::from(x)).collect()
            };
            let in_tangent = |k: usize| -> Vec<f64> {
                let start = k * stride;
                channel.values[start..start + width].iter().map(|&x| f64::from(x)).collect()
            };
            let (m0, m1) = (out_tangent(k), in_tangent(k + 1));
            let (s2, s3) = (s * s, s * s * s);
            (0..width)
                .map(|i| {
                    (2.0 * s3 - 3.0 * s2 + 1.0) * a[i]
                        + (s3 - 2.0 * s2 + s) * dt * m0[i]
                        + (-2.0 * s3 + 3.0 * s2) * b[i]
                        + (s3 - s2) * dt * m1[i]
                })
                .collect()
        }
    };
    if channel.path == Path::Rotation {
        let norm = out.iter().map(|x| x * x).sum::<f64>().sqrt();
        out.iter_mut().for_each(|x| *x /= norm);
    }
    out
}

/// World matrices of every node for the local poses `locals`: `W_n = W_parent · L_n`,
/// computed parents first without recursion, so a chain of any depth fits the stack.
pub fn world_matrices(rig: &Rig, locals: &[LocalPose]) -> Vec<Mat4> {
    let parents = rig.parents();
    let mut world = vec![Mat4::identity(); rig.nodes.len()];
    for n in Rig::parents_first(&parents) {
        let local = locals[n].matrix();
        world[n] = match parents[n] {
            Some(p) => world[p] * local,
            None => local,
        };
    }
    world
}

/// The skinning matrix `G_j · B_j` of every joint for the local poses `locals`.
pub fn joint_matrices(rig: &Rig, locals: &[LocalPose]) -> Vec<Mat4> {
    skinning_matrices(rig, &world_matrices(rig, locals))
}

fn skinning_matrices(rig: &Rig, world: &[Mat4]) -> Vec<Mat4> {
    rig.skin.joints.iter().enumerate().map(|(j, &n)| world[n] * rig.skin.inverse_bind_matrix(j)).collect()
}

/// How flat a 3×3 linear part may be before it counts as singular: its determinant
/// over the product of its column lengths (1 for orthogonal columns, 0 for a zero
/// scale). `f32` rounding of a truly singular matrix leaves about 1e-7.
pub const SINGULAR_VOLUME_RATIO: f64 = 1e-6;

/// Whether the linear (upper-left 3×3) part of `m` collapses space onto a plane, a line
/// or a point ([`SINGULAR_VOLUME_RATIO`]); scale-invariant, so tiny or huge but
/// well-shaped matrices are not singular.
pub fn is_singular(m: &Mat4) -> bool {
    let a = m.fixed_view::<3, 3>(0, 0);
    let lengths = a.column(0).norm() * a.column(1).norm() * a.column(2).norm();
    lengths == 0.0 || a.determinant().abs() <= SINGULAR_VOLUME_RATIO * lengths
}

/// Linear blend skinning of `rest` (one row of `influences` per point) with the joint
/// matrices `joints`.
pub fn skin_points(rest: &[Vec3], influences: &Influences, joints: &[Mat4]) -> Vec<Vec3> {
    rest.iter()
        .enumerate()
        .map(|(v, p)| {
            let mut out = Vec3::zeros();
            for (j, w) in influences.of(v) {
                out += f64::from(w) * transform_point(&joints[j], p);
            }
            out
        })
        .collect()
}

/// `m · (p, 1)`, dropping the homogeneous coordinate (skinning matrices are affine).
#[inline]
pub fn transform_point(m: &Mat4, p: &Vec3) -> Vec3 {
    Vec3::new(
        m[(0, 0)] * p.x + m[(0, 1)] * p.y + m[(0, 2)] * p.z + m[(0, 3)],
        m[(1, 0)] * p.x + m[(1, 1)] * p.y + m[(1, 2)] * p.z + m[(1, 3)],
        m[(2, 0)] * p.x + m[(2, 1)] * p.y + m[(2, 2)] * p.z + m[(2, 3)],
    )
}

/// Where the pose set's frames come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PoseSource {
    /// Frames of the file's animations.
    Animations,
    /// Seeded random joint rotations within [`FrameConfig::max_degrees`].
    Random,
    /// `frames` of each.
    Both,
}

/// Most frames [`sample_frames`] makes of one source (`frames` in [`FrameConfig`]).
/// Each frame holds a local pose per node and becomes a pose of the pose set; 65 536 is
/// far above any pose set desal simplifies (the SCAPE set has 71 poses).
pub const MAX_FRAMES: usize = 1 << 16;

/// Most vertex positions a posed rig may hold: poses (the bind pose included) × welded
/// vertices, refused by [`crate::pose_rig`] before anything is allocated. A whole `desal
/// run` peaks near 69 bytes a position (the rig sample at `frames = 2000`, 2001 × 13 380
/// positions: 1.84 GB maximum resident, `/usr/bin/time -v`), so 2^25 positions stay near
/// 2.3 GB (the rig sample at up to 2506 frames; SCAPE is 0.9 M).
pub const MAX_POSE_VERTICES: usize = 1 << 25;

/// Most node local poses the sampled frames may hold: frames × nodes, refused by
/// [`sample_frames`] before sampling. 2^23 local poses are about 1.1 GiB.
pub const MAX_POSE_NODES: usize = 1 << 23;

/// How [`sample_frames`] picks the frames.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrameConfig {
    pub source: PoseSource,
    /// Frames to sample (per source for [`PoseSource::Both`]). At least 1.
    pub frames: usize,
    /// Seed of the random rotations.
    pub seed: u64,
    /// Largest random turn of one joint from its rest rotation, in degrees.
    pub max_degrees: f64,
}

impl Default for FrameConfig {
    fn default() -> Self {
        Self { source: PoseSource::Animations, frames: 60, seed: 0, max_degrees: 30.0 }
    }
}

/// One sampled frame: a name and the local pose of every node.
#[derive(Debug, Clone)]
pub struct Frame {
    pub name: String,
    pub locals: Vec<LocalPose>,
}

/// The frames of `config`. Animation frames are spread evenly over the animations'
/// concatenated timeline, both ends included (so the keyframes of an animation with
/// `frames` evenly spaced keys are hit exactly); random frames turn every joint about a
/// uniformly random axis by a uniformly random angle up to the limit, after its rest
/// rotation.
pub fn sample_frames(
    rig: &Rig,
    config: &FrameConfig,
    path: &std::path::Path,
) -> Result<Vec<Frame>, RigError> {
    if config.frames == 0 {
        return Err(RigError::Settings("frames must be at least 1".into()));
    }
    if !(config.max_degrees.is_finite() && (0.0..=180.0).contains(&config.max_degrees)) {
        return Err(RigError::Settings(format!("max_degrees {} must lie in 0..=180", config.max_degrees)));
    }
    if config.frames > MAX_FRAMES {
        return Err(RigError::Settings(format!(
            "frames = {} is more than desal's limit of {MAX_FRAMES} (desal_rig::MAX_FRAMES)",
            config.frames
        )));
    }
    let sources = if config.source == PoseSource::Both { 2 } else { 1 };
    let local_poses = (config.frames * sources).saturating_mul(rig.nodes.len());
    if local_poses > MAX_POSE_NODES {
        return Err(RigError::Settings(format!(
            "{} frames of a rig with {} nodes are {local_poses} node poses, more than desal's limit of \
             {MAX_POSE_NODES} (desal_rig::MAX_POSE_NODES); lower frames",
            config.frames * sources,
            rig.nodes.len()
        )));
    }
    let mut frames = Vec::new();
    if matches!(config.source, PoseSource::Animations | PoseSource::Both) {
        frames.extend(animation_frames(rig, config.frames, path)?);
    }
    if matches!(config.source, PoseSource::Random | PoseSource::Both) {
        frames.extend(random_frames(rig, config.frames, config.seed, config.max_degrees));
    }
    check_frames(rig, &frames, path)?;
    Ok(frames)
}

/// Refuses a frame in which a joint that moves vertices has a skinning matrix that is
/// not finite (a transform chain that overflows) or singular (a zero scale, which glTF
/// allows — engines use it to hide things — but which crushes the vertices the joint
/// moves, while desal fits parts that keep their shape). The error names the frame, the
/// joint and the node whose transform does it, and the animation channel that sets it.
fn check_frames(rig: &Rig, frames: &[Frame], path: &std::path::Path) -> Result<(), RigError> {
    let mut moved = vec![0usize; rig.skin.joints.len()];
    for (&j, &w) in rig.mesh.influences.joints.iter().zip(&rig.mesh.influences.weights) {
        if w > 0.0 {
            moved[usize::from(j)] += 1;
        }
    }
    let parents = rig.parents();
    for frame in frames {
        let world = world_matrices(rig, &frame.locals);
        let skinning = skinning_matrices(rig, &world);
        let Some((j, m)) = skinning
            .iter()
            .enumerate()
            .find(|&(j, m)| moved[j] > 0 && (!m.iter().all(|x| x.is_finite()) || is_singular(m)))
        else {
            continue;
        };
        let joint_node = rig.skin.joints[j];
        // The joint's node and its ancestors, root first.
        let mut chain = vec![joint_node];
        while let Some(p) = parents[*chain.last().expect("non-empty")] {
            chain.push(p);
        }
        chain.reverse();
        let joint = format!("joint {j} ({}) moves {} vertices", node_label(rig, joint_node), moved[j]);
        let reason = if !m.iter().all(|x| x.is_finite()) {
            let culprit = chain.iter().copied().find(|&n| !world[n].iter().all(|x| x.is_finite()));
            match culprit {
                Some(n) => format!(
                    "{joint}, but the transform of {} ({}) overflows to a non-finite world matrix here",
                    node_label(rig, n),
                    describe_local(&frame.locals[n])
                ),
                None => format!("{joint}, but its skinning matrix is not finite here"),
            }
        } else {
            match chain.iter().copied().find(|&n| is_singular(&frame.locals[n].matrix())) {
                Some(n) => format!(
                    "{joint}, but {} has {} here, which collapses them (a zero scale is valid glTF, used \
                     to hide things, but desal fits body parts that keep their shape){}",
                    node_label(rig, n),
                    describe_local(&frame.locals[n]),
                    scale_channels(rig, n)
                ),
                None => format!("{joint}, but its skinning matrix is singular here"),
            }
        };
        return Err(RigError::Pose { path: path.to_owned(), pose: frame.name.clone(), reason });
    }
    Ok(())
}

/// `node 3 'hip'` (or `node 3` when unnamed).
pub fn node_label(rig: &Rig, node: usize) -> String {
    match &rig.nodes[node].name {
        Some(name) => format!("node {node} '{name}'"),
        None => format!("node {node}"),
    }
}

/// A local pose for messages: its translation and scale, or "a matrix".
fn describe_local(local: &LocalPose) -> String {
    match local {
        LocalPose::Trs { translation: t, scale: s, .. } => {
            format!("translation [{}, {}, {}], scale [{}, {}, {}]", t.x, t.y, t.z, s.x, s.y, s.z)
        }
        LocalPose::Matrix(_) => "a fixed matrix".into(),
    }
}

/// "; animation 'a' scales it (keyframe k: [0, 0, 0])", for the first animation that
/// scales `node`, or nothing.
fn scale_channels(rig: &Rig, node: usize) -> String {
    for (a, animation) in rig.animations.iter().enumerate() {
        for channel in &animation.channels {
            if channel.node != node || channel.path != Path::Scale {
                continue;
            }
            let name = animation.name.clone().unwrap_or_else(|| format!("animation {a}"));
            let cubic = channel.interpolation == Interpolation::CubicSpline;
            let (stride, first) = if cubic { (9, 3) } else { (3, 0) };
            let key = (0..channel.times.len())
                .find(|k| channel.values[k * stride + first..k * stride + first + 3].contains(&0.0));
            let key =
                key.map(|k| format!(" (keyframe {k}: {:?})", &channel.values[k * stride + first..][..3]));
            return format!("; animation '{name}' scales it{}", key.unwrap_or_default());
        }
    }
    String::new()
}

fn animation_frames(rig: &Rig, count: usize, path: &std::path::Path) -> Result<Vec<Frame>, RigError> {
    let spans: Vec<(usize, f64, f64)> = rig
        .animations
        .iter()
        .enumerate()
        .filter(|(_, a)| !a.channels.is_empty())
        .map(|(i, a)| {
            let (t0, t1) = a.time_range();
            (i, f64::from(t0), f64::from(t1))
        })
        .collect();
    if spans.is_empty() {
        return Err(RigError::NoAnimations { path: path.to_owned() });
    }
    let total: f64 = spans.iter().map(|(_, t0, t1)| t1 - t0).sum();
    let mut frames = Vec::with_capacity(count);
    for f in 0..count {
        let along = if count == 1 { 0.0 } else { total * f as f64 / (count - 1) as f64 };
        // The animation this point of the concatenated timeline falls in.
        let mut start = 0.0;
        let mut chosen = *spans.last().expect("non-empty");
        let mut local = chosen.2 - chosen.1;
        for &(i, t0, t1) in &spans {
            if along <= start + (t1 - t0) {
                chosen = (i, t0, t1);
                local = along - start;
                break;
            }
            start += t1 - t0;
        }
        let (i, t0, t1) = chosen;
        let time = (t0 + local).min(t1);
        let animation = &rig.animations[i];
        let name = format!("{}@{time:.4}", animation.name.clone().unwrap_or_else(|| format!("animation{i}")));
        frames.push(Frame { name: format!("f{f:03}_{name}"), locals: animated_locals(rig, animation, time) });
    }
    Ok(frames)
}

fn random_frames(rig: &Rig, count: usize, seed: u64, max_degrees: f64) -> Vec<Frame> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let rest = rest_locals(rig);
    (0..count)
        .map(|f| {
            let mut locals = rest.clone();
            for &node in &rig.skin.joints {
                // Drawn for every joint in joint order, so the sequence depends only on the seed.
                let z: f64 = rng.gen_range(-1.0..=1.0);
                let phi: f64 = rng.gen_range(0.0..std::f64::consts::TAU);
                let angle: f64 = rng.gen_range(0.0..=max_degrees.to_radians());
                let r = (1.0 - z * z).sqrt();
                let axis = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                if let LocalPose::Trs { rotation, .. } = &mut locals[node] {
                    *rotation *= UnitQuat::from_scaled_axis(axis * angle);
                }
            }
            Frame { name: format!("random{f:03}"), locals }
        })
        .collect()
}

fn to_vec3(v: [f32; 3]) -> Vec3 {
    Vec3::new(v[0].into(), v[1].into(), v[2].into())
}

/// A unit quaternion from glTF's `[x, y, z, w]`.
fn quat(q: [f64; 4]) -> UnitQuat {
    UnitQuat::from_quaternion(nalgebra_quat(q))
}

fn nalgebra_quat(q: [f64; 4]) -> desal_mesh::math::Quat {
    desal_mesh::math::Quat::new(q[3], q[0], q[1], q[2])
}
