//! A CC0 body model in SMPL's layout, made from the MakeHuman assets: the fixture of
//! desal-bodymodel, loadable unchanged by body-models' `SMPL` class.
//!
//! The story, in [`smpl_layout_model`]:
//! 1. the body (vertices `0..13380`, triangles) in metres is `v_template`;
//! 2. the 31 `cmu_mb` bones fold into SMPL's 24 joints ([`SMPL_JOINT_BONES`]: the hip-joint
//!    bones into the pelvis, `Neck1` into the neck, fingers and thumb into the hand joint),
//!    so `kintree_table` is SMPL's own tree; `weights` are the folded skinning weights;
//! 3. `J_regressor`: per joint, non-negative weights on nearby surface vertices, summing
//!    to 1, that reproduce the joint's rig position ([`regress_joint`]);
//! 4. `shapedirs`: 10 synthetic, smooth directions ([`SHAPE_DIRECTIONS`]) built from the
//!    skinning weights and bones — not a statistical shape space;
//! 5. `posedirs`: small synthetic correctives around each joint (a bulge growing with the
//!    bend, and two asymmetric shears that pin down the `vec(R − I)` order), nonzero only
//!    where a joint and its parent share weight.
//!
//! Values are rounded to float32 (as body-models loads them), so a reader in f64 and
//! body-models see the same numbers. The bytes are deterministic: [`SmplLayoutModel::npz`]
//! writes SMPL 1.1's npz keys, [`SmplLayoutModel::pkl`] a Python 2 style chumpy pickle like
//! SMPL 1.0's `.pkl` (`v_template` and `shapedirs` as `chumpy.ch.Ch`, `J_regressor` a
//! scipy CSC matrix).
//!
//! Licence of the model: CC0 1.0, like the MakeHuman / MPFB2 assets it is made from
//! (`data-samples/source/LICENSE.md`). No part of a licensed SMPL-family model is used:
//! only SMPL's key names, array layout and joint tree.

use desal_io::npz::{AnyArray, AnyData, NpzEntry, encode_npy_any, encode_npz_entries};
use desal_mesh::Vec3;
use desal_mesh::math::Mat4;

use crate::error::SampleError;
use crate::skeleton::Skeleton;
use crate::skinning::SkinWeights;
use crate::source::SourceAssets;
use crate::{SampleConfig, extract_body};

/// SMPL's joints in order, each with the `cmu_mb` bones folded into it; the first bone's
/// head is the joint's position.
pub const SMPL_JOINT_BONES: [(&str, &[&str]); 24] = [
    ("pelvis", &["Hips", "LHipJoint", "RHipJoint"]),
    ("left_hip", &["LeftUpLeg"]),
    ("right_hip", &["RightUpLeg"]),
    ("spine1", &["LowerBack"]),
    ("left_knee", &["LeftLeg"]),
    ("right_knee", &["RightLeg"]),
    ("spine2", &["Spine"]),
    ("left_ankle", &["LeftFoot"]),
    ("right_ankle", &["RightFoot"]),
    ("spine3", &["Spine1"]),
    ("left_foot", &["LeftToeBase"]),
    ("right_foot", &["RightToeBase"]),
    ("neck", &["Neck", "Neck1"]),
    ("left_collar", &["LeftShoulder"]),
    ("right_collar", &["RightShoulder"]),
    ("head", &["Head"]),
    ("left_shoulder", &["LeftArm"]),
    ("right_shoulder", &["RightArm"]),
    ("left_elbow", &["LeftForeArm"]),
    ("right_elbow", &["RightForeArm"]),
    ("left_wrist", &["LeftHand"]),
    ("right_wrist", &["RightHand"]),
    ("left_hand", &["LeftFingerBase", "LeftHandFinger1", "LThumb"]),
    ("right_hand", &["RightFingerBase", "RightHandFinger1", "RThumb"]),
];

/// SMPL's tree: the parent of each joint (joint 0 the root).
pub const SMPL_PARENTS: [usize; 24] =
    [0, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 9, 9, 12, 13, 14, 16, 17, 18, 19, 20, 21];

/// The shape directions, in `shapedirs` order (metres per unit beta).
pub const SHAPE_DIRECTIONS: [&str; 10] = [
    "stature: up by 5 % of the height above the soles",
    "girth: out from every bone by 15 % of the distance",
    "arm length: arm joints out along the arm by 8 % of their distance from the shoulder",
    "leg length: leg joints out along the leg by 8 % of their distance from the hip",
    "shoulder width: arms and collars 4 cm outward",
    "belly: the front of the torso forward by 30 % of its depth ahead of the spine",
    "head size: head 10 % larger about the head joint",
    "hip width: pelvis and hips 15 % wider about the midline",
    "torso length: the chest, arms, neck and head 4 cm up",
    "muscle: limbs out from their bones by 20 % mid-segment, none at the joints",
];

/// The model's arrays, float32 values, SMPL's layout (row-major).
#[derive(Debug, Clone, PartialEq)]
pub struct SmplLayoutModel {
    pub v_template: Vec<[f32; 3]>,
    pub faces: Vec<[u32; 3]>,
    /// `(V, 24)`.
    pub weights: Vec<f32>,
    /// `(24, V)`, dense.
    pub j_regressor: Vec<f32>,
    /// `(V, 3, 10)`.
    pub shapedirs: Vec<f32>,
    /// `(V, 3, 207)`.
    pub posedirs: Vec<f32>,
    /// The rig's joint positions (metres), SMPL's `J`.
    pub joints: Vec<[f32; 3]>,
}

const JOINTS: usize = 24;
const SHAPES: usize = 10;
const POSE_FEATURES: usize = 9 * (JOINTS - 1);

/// Builds the model from the assets (see the module doc).
pub fn smpl_layout_model(assets: &SourceAssets) -> Result<SmplLayoutModel, SampleError> {
    let config = SampleConfig::default();
    let body = extract_body(&assets.base, config.body_vertex_count)?;
    let skeleton = Skeleton::from_assets(assets)?;
    let (skin, _) = SkinWeights::from_bone_lists(&skeleton, &assets.weights, body.vertex_count())?;
    let scale = config.scale;
    let positions: Vec<Vec3> = body.positions.iter().map(|p| round_vec(p * scale)).collect();
    let vertex_count = positions.len();

    let joint_of_bone = fold_bones(&skeleton)?;
    let segments: Vec<(Vec3, Vec3)> = SMPL_JOINT_BONES
        .iter()
        .map(|(_, bones)| {
            let b = &skeleton.bones[skeleton.index_of(bones[0]).expect("checked by fold_bones")];
            (b.head * scale, b.tail * scale)
        })
        .collect();
    let heads: Vec<Vec3> = segments.iter().map(|s| round_vec(s.0)).collect();

    let mut weights = vec![0.0f64; vertex_count * JOINTS];
    for v in 0..vertex_count {
        let (start, end) = (skin.offsets[v] as usize, skin.offsets[v + 1] as usize);
        for k in start..end {
            weights[v * JOINTS + joint_of_bone[skin.bones[k] as usize]] += skin.weights[k];
        }
    }

    let mut j_regressor = vec![0.0f32; JOINTS * vertex_count];
    for (j, head) in heads.iter().enumerate() {
        let row = regress_joint(&positions, head).ok_or_else(|| SampleError::UnmappedBone {
            bone: format!("{} (no joint regressor)", SMPL_JOINT_BONES[j].0),
        })?;
        for (v, w) in row {
            j_regressor[j * vertex_count + v] = w as f32;
        }
    }

    let w = |v: usize, j: usize| weights[v * JOINTS + j];
    let shapedirs = shape_directions(&positions, &w, &heads, &segments);
    let posedirs = pose_correctives(&positions, &w, &heads);

    Ok(SmplLayoutModel {
        v_template: positions.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect(),
        faces: body.faces.clone(),
        weights: weights.iter().map(|&x| x as f32).collect(),
        j_regressor,
        shapedirs: shapedirs.iter().map(|&x| x as f32).collect(),
        posedirs: posedirs.iter().map(|&x| x as f32).collect(),
        joints: heads.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect(),
    })
}

fn round_vec(p: Vec3) -> Vec3 {
    p.map(|x| f64::from(x as f32))
}

/// The SMPL joint of every `cmu_mb` bone, checking that each joint's first bone hangs
/// from a bone of the joint's SMPL parent (so the folded tree is SMPL's).
fn fold_bones(skeleton: &Skeleton) -> Result<Vec<usize>, SampleError> {
    let mut joint_of_bone = vec![usize::MAX; skeleton.bone_count()];
    for (joint, (_, bones)) in SMPL_JOINT_BONES.iter().enumerate() {
        for name in *bones {
            let bone = skeleton
                .index_of(name)
                .ok_or_else(|| SampleError::UnknownWeightBone { bone: name.to_string() })?;
            joint_of_bone[bone] = joint;
        }
    }
    if let Some(b) = joint_of_bone.iter().position(|&j| j == usize::MAX) {
        return Err(SampleError::UnmappedBone { bone: skeleton.bones[b].name.clone() });
    }
    for (joint, (_, bones)) in SMPL_JOINT_BONES.iter().enumerate().skip(1) {
        let bone = skeleton.index_of(bones[0]).expect("found above");
        let parent = skeleton.bones[bone].parent.map(|p| joint_of_bone[p]);
        if parent != Some(SMPL_PARENTS[joint]) {
            return Err(SampleError::UnmappedBone {
                bone: format!("{} (does not hang from SMPL's parent)", bones[0]),
            });
        }
    }
    Ok(joint_of_bone)
}

/// Non-negative weights summing to 1 on surface vertices around `joint` whose weighted
/// mean is `joint`. The support surrounds the joint: the vertices are binned by their
/// direction from it (the 26 directions of a cube's faces, edges and corners) and the `m`
/// nearest of each bin kept (`m` = 4, doubled up to 64 if needed). The weights are the
/// ones closest to uniform that satisfy the four affine constraints; while one is
/// negative, the most negative vertex leaves the support and the rest is solved again.
pub fn regress_joint(positions: &[Vec3], joint: &Vec3) -> Option<Vec<(usize, f64)>> {
    let directions: Vec<Vec3> = (0..27)
        .filter(|&k| k != 13)
        .map(|k| {
            Vec3::new((k % 3) as f64 - 1.0, ((k / 3) % 3) as f64 - 1.0, (k / 9) as f64 - 1.0).normalize()
        })
        .collect();
    let mut bins: Vec<Vec<(f64, usize)>> = vec![Vec::new(); directions.len()];
    for (v, p) in positions.iter().enumerate() {
        let offset = p - joint;
        let bin = (0..directions.len())
            .max_by(|&a, &b| {
                offset.dot(&directions[a]).total_cmp(&offset.dot(&directions[b])).then(b.cmp(&a))
            })
            .expect("26 directions");
        bins[bin].push((offset.norm(), v));
    }
    bins.iter_mut().for_each(|b| b.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1))));
    let mut m = 4;
    while m <= 64 {
        let mut support: Vec<usize> = bins.iter().flat_map(|b| b.iter().take(m).map(|&(_, v)| v)).collect();
        support.sort_unstable();
        while support.len() >= 4 {
            let w = affine_weights(positions, &support, joint)?;
            let (worst, &lowest) = w.iter().enumerate().min_by(|a, b| a.1.total_cmp(b.1)).expect("non-empty");
            if lowest >= 0.0 {
                return Some(support.into_iter().zip(w).filter(|&(_, x)| x > 0.0).collect());
            }
            support.remove(worst);
        }
        m *= 2;
    }
    None
}

/// `w = u + Aᵀ (A Aᵀ)⁻¹ (b − A u)`: the weights nearest the uniform `u` with
/// `Σ wᵢ pᵢ = target` and `Σ wᵢ = 1` (rows of `A`: x, y, z, 1).
fn affine_weights(positions: &[Vec3], support: &[usize], target: &Vec3) -> Option<Vec<f64>> {
    let n = support.len() as f64;
    let column = |v: usize| nalgebra::Vector4::new(positions[v].x, positions[v].y, positions[v].z, 1.0);
    let mut gram = Mat4::zeros();
    let mut mean = nalgebra::Vector4::zeros();
    for &v in support {
        gram += column(v) * column(v).transpose();
        mean += column(v) / n;
    }
    let residual = nalgebra::Vector4::new(target.x, target.y, target.z, 1.0) - mean;
    let lambda = gram.lu().solve(&residual)?;
    Some(support.iter().map(|&v| 1.0 / n + column(v).dot(&lambda)).collect())
}

/// The closest point of segment `(a, b)` to `p`, and its parameter in `[0, 1]`.
fn closest_on_segment(p: &Vec3, (a, b): &(Vec3, Vec3)) -> (Vec3, f64) {
    let d = b - a;
    let t = if d.norm_squared() > 0.0 { ((p - a).dot(&d) / d.norm_squared()).clamp(0.0, 1.0) } else { 0.0 };
    (a + d * t, t)
}

/// `(V, 3, 10)` row-major: [`SHAPE_DIRECTIONS`], each linear in the weights.
fn shape_directions(
    positions: &[Vec3],
    w: &dyn Fn(usize, usize) -> f64,
    heads: &[Vec3],
    segments: &[(Vec3, Vec3)],
) -> Vec<f64> {
    let floor = positions.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    let (left_arm, right_arm) = ([16, 18, 20, 22], [17, 19, 21, 23]);
    let (left_leg, right_leg) = ([4, 7, 10], [5, 8, 11]);
    let limbs: Vec<usize> =
        left_arm.iter().chain(&right_arm).chain(&left_leg).chain(&right_leg).copied().collect();
    let upper = [9, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23];
    let mut out = vec![0.0; positions.len() * 3 * SHAPES];
    for (v, p) in positions.iter().enumerate() {
        let sum_w = |joints: &[usize]| joints.iter().map(|&j| w(v, j)).sum::<f64>();
        let radial = |j: usize| p - closest_on_segment(p, &segments[j]).0;
        let chain = |joints: &[usize], base: usize| {
            joints.iter().fold(Vec3::zeros(), |a, &j| a + (heads[j] - heads[base]) * w(v, j))
        };
        let dirs: [Vec3; SHAPES] = [
            Vec3::y() * 0.05 * (p.y - floor),
            (0..JOINTS).fold(Vec3::zeros(), |a, j| a + radial(j) * w(v, j)) * 0.15,
            (chain(&left_arm, 16) + chain(&right_arm, 17)) * 0.08,
            (chain(&left_leg, 1) + chain(&right_leg, 2)) * 0.08,
            Vec3::x() * 0.04 * (sum_w(&left_arm) + 0.5 * w(v, 13) - sum_w(&right_arm) - 0.5 * w(v, 14)),
            Vec3::z()
                * [0, 3, 6, 9].iter().map(|&j| w(v, j) * 0.3 * (p.z - heads[j].z).max(0.0)).sum::<f64>(),
            (p - heads[15]) * 0.1 * (w(v, 15) + 0.5 * w(v, 12)),
            Vec3::x() * 0.15 * (p.x - heads[0].x) * sum_w(&[0, 1, 2]),
            Vec3::y() * 0.04 * (sum_w(&upper) + 0.5 * w(v, 6)),
            limbs.iter().fold(Vec3::zeros(), |a, &j| {
                let (_, t) = closest_on_segment(p, &segments[j]);
                a + radial(j) * (w(v, j) * 0.2 * (std::f64::consts::PI * t).sin())
            }),
        ];
        for axis in 0..3 {
            for (s, d) in dirs.iter().enumerate() {
                out[(v * 3 + axis) * SHAPES + s] = d[axis];
            }
        }
    }
    out
}

/// `(V, 3, 207)` row-major: per joint `j ≥ 1`, on vertices where it and its parent share
/// weight (`b = 4 w_j w_parent`): a bulge away from the joint of 1 cm per unit of
/// `−trace(R − I) = 2 (1 − cos θ)` (columns of entries (0,0), (1,1), (2,2)), and shears of
/// 3 mm along x per unit of entry (0,1) and 2 mm along z per unit of entry (1,2).
fn pose_correctives(positions: &[Vec3], w: &dyn Fn(usize, usize) -> f64, heads: &[Vec3]) -> Vec<f64> {
    let mut out = vec![0.0; positions.len() * 3 * POSE_FEATURES];
    for (v, p) in positions.iter().enumerate() {
        for j in 1..JOINTS {
            let b = 4.0 * w(v, j) * w(v, SMPL_PARENTS[j]);
            if b == 0.0 {
                continue;
            }
            let away = (p - heads[j]).try_normalize(1e-12).unwrap_or_else(Vec3::zeros);
            let column = |entry: usize| (j - 1) * 9 + entry;
            for axis in 0..3 {
                let row = (v * 3 + axis) * POSE_FEATURES;
                for entry in [0, 4, 8] {
                    out[row + column(entry)] = -0.01 * b * away[axis];
                }
                out[row + column(1)] = 0.003 * b * Vec3::x()[axis];
                out[row + column(5)] = 0.002 * b * Vec3::z()[axis];
            }
        }
    }
    out
}

impl SmplLayoutModel {
    fn vertex_count(&self) -> usize {
        self.v_template.len()
    }

    /// The arrays under SMPL's keys, plus `J`, `bs_style` and `bs_type` as SMPL's files
    /// carry them.
    pub fn arrays(&self) -> Vec<(&'static str, AnyArray)> {
        let v = self.vertex_count();
        let f32s = |shape: Vec<usize>, data: Vec<f32>| AnyArray { shape, data: AnyData::F32(data) };
        let mut parents: Vec<i64> = SMPL_PARENTS.iter().map(|&p| p as i64).collect();
        parents[0] = i64::from(u32::MAX); // as in SMPL's own files
        let kintree: Vec<i64> = parents.into_iter().chain(0..JOINTS as i64).collect();
        vec![
            ("v_template", f32s(vec![v, 3], self.v_template.iter().flatten().copied().collect())),
            (
                "f",
                AnyArray {
                    shape: vec![self.faces.len(), 3],
                    data: AnyData::U32(self.faces.iter().flatten().copied().collect()),
                },
            ),
            ("weights", f32s(vec![v, JOINTS], self.weights.clone())),
            ("J_regressor", f32s(vec![JOINTS, v], self.j_regressor.clone())),
            ("shapedirs", f32s(vec![v, 3, SHAPES], self.shapedirs.clone())),
            ("posedirs", f32s(vec![v, 3, POSE_FEATURES], self.posedirs.clone())),
            ("kintree_table", AnyArray { shape: vec![2, JOINTS], data: AnyData::I64(kintree) }),
            ("J", f32s(vec![JOINTS, 3], self.joints.iter().flatten().copied().collect())),
            ("bs_style", AnyArray { shape: vec![], data: AnyData::Unicode(vec!["lbs".into()]) }),
            ("bs_type", AnyArray { shape: vec![], data: AnyData::Unicode(vec!["lrotmin".into()]) }),
        ]
    }

    /// The model as an npz (stored entries), byte-deterministic.
    pub fn npz(&self) -> Result<Vec<u8>, String> {
        let entries = self
            .arrays()
            .into_iter()
            .map(|(name, a)| Ok(NpzEntry { name: name.to_owned(), npy: encode_npy_any(&a)? }))
            .collect::<Result<Vec<_>, String>>()?;
        encode_npz_entries(&entries)
    }

    /// The model as a Python 2 style chumpy pickle (protocol 2), byte-deterministic.
    pub fn pkl(&self) -> Vec<u8> {
        let mut p = py2::Pickle::start();
        p.out.extend_from_slice(b"}(");
        for (name, array) in self.arrays() {
            p.string(name.as_bytes());
            match name {
                "v_template" | "shapedirs" => p.chumpy(&array),
                "J_regressor" => p.csc(&array),
                "bs_style" | "bs_type" => match &array.data {
                    AnyData::Unicode(s) => p.string(s[0].as_bytes()),
                    _ => unreachable!("written as strings above"),
                },
                _ => p.array(&array),
            }
        }
        p.out.extend_from_slice(b"u.");
        p.out
    }
}

/// The few Python 2 pickle constructs SMPL's files use, written opcode by opcode.
mod py2 {
    use desal_io::npz::{AnyArray, AnyData};

    pub struct Pickle {
        pub out: Vec<u8>,
    }

    impl Pickle {
        pub fn start() -> Self {
            Self { out: vec![0x80, 2] }
        }

        /// A Python 2 `str`.
        pub fn string(&mut self, s: &[u8]) {
            match u8::try_from(s.len()) {
                Ok(n) => self.out.extend_from_slice(&[b'U', n]),
                Err(_) => {
                    self.out.push(b'T');
                    self.out.extend_from_slice(&(s.len() as u32).to_le_bytes());
                }
            }
            self.out.extend_from_slice(s);
        }

        fn int(&mut self, n: i64) {
            self.out.push(b'J');
            self.out.extend_from_slice(&(n as i32).to_le_bytes());
        }

        /// `numpy.core.multiarray._reconstruct(ndarray, (0,), 'b')` built with
        /// `(1, shape, dtype, False, data)`.
        pub fn array(&mut self, a: &AnyArray) {
            let (name, data): (&[u8], Vec<u8>) = match &a.data {
                AnyData::F32(v) => (b"f4", v.iter().flat_map(|x| x.to_le_bytes()).collect()),
                AnyData::F64(v) => (b"f8", v.iter().flat_map(|x| x.to_le_bytes()).collect()),
                AnyData::U32(v) => (b"u4", v.iter().flat_map(|x| x.to_le_bytes()).collect()),
                AnyData::I32(v) => (b"i4", v.iter().flat_map(|x| x.to_le_bytes()).collect()),
                AnyData::I64(v) => (b"i8", v.iter().flat_map(|x| x.to_le_bytes()).collect()),
                other => unreachable!("the fixture pickles no {} array", other.type_name()),
            };
            self.out.extend_from_slice(b"cnumpy.core.multiarray\n_reconstruct\ncnumpy\nndarray\nK\x00\x85");
            self.string(b"b");
            self.out.extend_from_slice(b"\x87R(K\x01(");
            a.shape.iter().for_each(|&d| self.int(d as i64));
            self.out.extend_from_slice(b"tcnumpy\ndtype\n");
            self.string(name);
            self.out.extend_from_slice(b"K\x00K\x01\x87R(K\x03");
            self.string(b"<");
            self.out.extend_from_slice(b"NNN");
            self.int(-1);
            self.int(-1);
            self.out.extend_from_slice(b"K\x00tb\x89");
            self.string(&data);
            self.out.extend_from_slice(b"tb");
        }

        /// `copy_reg._reconstructor(cls, object, None)` built with `state`'s dict
        /// (written by `state` between `}(` and `u`).
        fn object(&mut self, class: &[u8], state: impl FnOnce(&mut Self)) {
            self.out.extend_from_slice(b"ccopy_reg\n_reconstructor\nc");
            self.out.extend_from_slice(class);
            self.out.extend_from_slice(b"c__builtin__\nobject\nN\x87R}(");
            state(self);
            self.out.extend_from_slice(b"ub");
        }

        /// A `chumpy.ch.Ch` holding `a` under `x`.
        pub fn chumpy(&mut self, a: &AnyArray) {
            self.object(b"chumpy.ch\nCh\n", |p| {
                p.string(b"x");
                p.array(a);
            });
        }

        /// A dense row-major `(rows, cols)` float array as a scipy CSC matrix.
        pub fn csc(&mut self, a: &AnyArray) {
            let (rows, cols) = (a.shape[0], a.shape[1]);
            let AnyData::F32(dense) = &a.data else { unreachable!("the regressor is float32") };
            let (mut data, mut indices, mut indptr) = (Vec::new(), Vec::new(), vec![0i32]);
            for c in 0..cols {
                for r in 0..rows {
                    let x = dense[r * cols + c];
                    if x != 0.0 {
                        data.push(f64::from(x));
                        indices.push(r as i32);
                    }
                }
                indptr.push(data.len() as i32);
            }
            self.object(b"scipy.sparse.csc\ncsc_matrix\n", |p| {
                p.string(b"_shape");
                p.int(rows as i64);
                p.int(cols as i64);
                p.out.push(0x86);
                for (key, values) in [
                    (&b"data"[..], AnyData::F64(data)),
                    (b"indices", AnyData::I32(indices)),
                    (b"indptr", AnyData::I32(indptr)),
                ] {
                    p.string(key);
                    p.array(&AnyArray { shape: vec![values.len()], data: values });
                }
                p.string(b"format");
                p.string(b"csc");
                p.string(b"maxprint");
                p.int(50);
            });
        }
    }
}
