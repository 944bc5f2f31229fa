//! The sample as a skinned glTF rig (`data-samples/rig.glb`): the same body, the
//! `cmu_mb` skeleton as a node tree, the same skinning weights, the base mesh's UVs (so
//! the mesh is split along its UV seams, as real rigs are), and one animation whose
//! keyframes are the sample's poses, one per second.
//!
//! The node tree mirrors [`Skeleton`]: node `b` is bone `b`, its rest translation the
//! bone's head relative to its parent's head (the root's: its head), its rest rotation
//! the identity, so that a bone's local rotation in the pose table is exactly the node's
//! rotation, and its inverse bind matrix is the translation by minus its head. The
//! skinned mesh hangs on a separate root node. The root's translation keyframes carry
//! each pose's ground shift. Welded by position and weights (`desal_rig::Weld`), the
//! mesh is the PLY sample's template vertex for vertex; posed at the keyframes by glTF's
//! LBS, it is the PLY sample's poses (to `f32` rounding).

use desal_mesh::Vec3;
use desal_mesh::math::UnitQuat;
use desal_rig::model::{Path as ChannelPath, SkinnedMesh};
use desal_rig::{Animation, Channel, Influences, Interpolation, LocalTransform, Node, Rig, Skin};

use crate::error::SampleError;
use crate::skeleton::Skeleton;
use crate::skinning::SkinWeights;
pub use crate::source::{ObjUvs, parse_obj_uvs};

/// Name of the sample's skinned mesh and of its animation.
pub const MESH_NAME: &str = "Body";
pub const ANIMATION_NAME: &str = "poses";

/// The inputs of [`build_rig`]: the body and its rig, in OBJ units, and the poses.
#[derive(Debug, Clone, Copy)]
pub struct RigInputs<'a> {
    /// The body's faces (over body vertices `0..n`), as [`crate::extract_body`] gives them.
    pub body_faces: &'a [desal_mesh::Face],
    /// The body's rest positions in OBJ units.
    pub body_positions: &'a [Vec3],
    pub uvs: &'a ObjUvs,
    pub skeleton: &'a Skeleton,
    pub weights: &'a SkinWeights,
    /// Per pose: one local rotation per bone, and the vertical ground shift in OBJ units.
    pub poses: &'a [(Vec<UnitQuat>, f64)],
    /// OBJ units to output units.
    pub scale: f64,
}

/// Builds the sample rig.
pub fn build_rig(inputs: &RigInputs) -> Result<Rig, SampleError> {
    let n = inputs.body_positions.len();
    // The body's triangles with their UV corners: the fan triangulation of the faces that
    // use body vertices only, which must be exactly the body's triangles.
    let (mut vertex_tris, mut uv_tris) = (Vec::new(), Vec::new());
    for (v, t) in inputs.uvs.vertex_triangles.iter().zip(&inputs.uvs.triangles) {
        if v.iter().all(|&v| (v as usize) < n) {
            vertex_tris.push(*v);
            uv_tris.push(*t);
        }
    }
    if vertex_tris != inputs.body_faces {
        return Err(SampleError::Json {
            path: "base.obj".into(),
            reason: "the v/vt corners do not triangulate to the body's faces".into(),
        });
    }
    // Split vertices, body-vertex-major: each body vertex once per distinct UV it has,
    // in order of first use, so welding gives back the body's own vertex order.
    let mut uv_lists: Vec<Vec<u32>> = vec![Vec::new(); n];
    for (v, t) in vertex_tris.iter().zip(&uv_tris) {
        for c in 0..3 {
            let list = &mut uv_lists[v[c] as usize];
            if !list.contains(&t[c]) {
                list.push(t[c]);
            }
        }
    }
    let mut first_split = Vec::with_capacity(n + 1);
    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    let mut influences = Influences::new();
    for (v, list) in uv_lists.iter().enumerate() {
        first_split.push(positions.len() as u32);
        let p = inputs.body_positions[v] * inputs.scale;
        let row = desal_rig::simplified::to_f32_weights(&inputs.weights.of(v).collect::<Vec<_>>());
        for &t in list {
            positions.push([p.x as f32, p.y as f32, p.z as f32]);
            uvs.push(inputs.uvs.uvs[t as usize]);
            influences.push_row(row.iter().copied());
        }
    }
    let triangles = vertex_tris
        .iter()
        .zip(&uv_tris)
        .map(|(v, t)| {
            std::array::from_fn(|c| {
                let k = uv_lists[v[c] as usize].iter().position(|&x| x == t[c]).expect("listed above");
                first_split[v[c] as usize] + k as u32
            })
        })
        .collect();

    let bones = &inputs.skeleton.bones;
    let head = |b: usize| bones[b].head * inputs.scale;
    let mut nodes: Vec<Node> = bones
        .iter()
        .enumerate()
        .map(|(b, bone)| {
            let offset = match bone.parent {
                Some(p) => head(b) - head(p),
                None => head(b),
            };
            Node {
                name: Some(bone.name.clone()),
                children: (0..bones.len()).filter(|&c| bones[c].parent == Some(b)).collect(),
                transform: LocalTransform::Trs {
                    translation: to_f32(&offset),
                    rotation: [0.0, 0.0, 0.0, 1.0],
                    scale: [1.0; 3],
                },
            }
        })
        .collect();
    let mesh_node = nodes.len();
    nodes.push(Node { name: Some(MESH_NAME.into()), children: vec![], transform: LocalTransform::IDENTITY });
    let inverse_bind = (0..bones.len())
        .map(|b| {
            let mut m = [0.0f32; 16];
            for i in 0..4 {
                m[5 * i] = 1.0;
            }
            m[12..15].copy_from_slice(&to_f32(&-head(b)));
            m
        })
        .collect();

    // One keyframe per pose, one second apart: every bone's rotation, and the root's
    // translation with the pose's ground shift.
    let times: Vec<f32> = (0..inputs.poses.len()).map(|k| k as f32).collect();
    let mut channels = Vec::new();
    let root = (0..bones.len()).find(|&b| bones[b].parent.is_none()).expect("a root bone");
    let root_values = inputs
        .poses
        .iter()
        .flat_map(|(_, shift)| to_f32(&(head(root) + Vec3::y() * (*shift * inputs.scale))))
        .collect();
    channels.push(Channel {
        node: root,
        path: ChannelPath::Translation,
        interpolation: Interpolation::Linear,
        times: times.clone(),
        values: root_values,
    });
    for b in 0..bones.len() {
        let values = inputs
            .poses
            .iter()
            .flat_map(|(local, _)| {
                let q = local[b].coords;
                [q.x as f32, q.y as f32, q.z as f32, q.w as f32]
            })
            .collect();
        channels.push(Channel {
            node: b,
            path: ChannelPath::Rotation,
            interpolation: Interpolation::Linear,
            times: times.clone(),
            values,
        });
    }
    Ok(Rig {
        weight_sums: Default::default(),
        nodes,
        scenes: vec![vec![root, mesh_node]],
        scene: Some(0),
        mesh_node,
        meshes: Vec::new(),
        skin: Skin {
            name: Some("cmu_mb".into()),
            joints: (0..bones.len()).collect(),
            inverse_bind,
            skeleton: Some(root),
        },
        animations: vec![Animation { name: Some(ANIMATION_NAME.into()), channels }],
        mesh: SkinnedMesh {
            name: MESH_NAME.into(),
            positions,
            normals: None,
            uvs: Some(uvs),
            influences,
            triangles,
            primitives: Vec::new(),
            sources: Vec::new(),
        },
    })
}

fn to_f32(v: &Vec3) -> [f32; 3] {
    [v.x as f32, v.y as f32, v.z as f32]
}
