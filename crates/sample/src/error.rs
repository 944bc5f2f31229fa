//! The error type of the sample generator. Every variant names the source file, bone,
//! pose, vertex or part it is about, so that a broken asset or pose table can be fixed
//! from the message alone.

use std::path::PathBuf;

use thiserror::Error;

/// What went wrong while reading the MakeHuman assets, posing the body or writing the
/// sample.
#[derive(Debug, Error)]
pub enum SampleError {
    /// A source file could not be read or an output file could not be written.
    #[error(transparent)]
    Io(#[from] desal_io::IoError),

    /// The sample rig could not be built or written.
    #[error("sample rig: {0}")]
    Rig(String),

    /// A JSON source file does not have the expected structure.
    #[error("{path}: {reason}")]
    Json { path: PathBuf, reason: String },

    /// The base mesh has fewer vertices than the body range needs. Check that the
    /// source folder holds MakeHuman's `base.obj` (hm08, 19158 vertices).
    #[error("the base mesh has {found} vertices, but the body needs the first {expected}")]
    BaseMeshTooSmall { expected: usize, found: usize },

    /// A bone's head or tail names a joint vertex group that `basemesh_vertex_groups.json`
    /// does not have (or that is empty).
    #[error("bone '{bone}' names joint vertex group '{group}', which is missing or empty")]
    MissingJointGroup { bone: String, group: String },

    /// A joint is given by vertex indices, or a vertex group holds indices, beyond the
    /// base mesh.
    #[error("bone '{bone}': joint vertex {vertex} is out of range for {vertex_count} base-mesh vertices")]
    JointVertexOutOfRange { bone: String, vertex: u32, vertex_count: usize },

    /// A bone's joint is neither a `CUBE` (vertex group) nor a `MEAN` (vertex list).
    #[error("bone '{bone}': joint has neither a `cube_name` nor `vertex_indices`")]
    UnknownJointStrategy { bone: String },

    /// A bone's parent is not a bone of the rig.
    #[error("bone '{bone}' has parent '{parent}', which is not a bone of the rig")]
    UnknownParent { bone: String, parent: String },

    /// The rig does not have exactly one root bone (a bone with parent ""), or its parent
    /// links form a cycle.
    #[error(
        "the rig must be a tree with one root; found {roots} roots and {unreachable} bones not reachable from a root"
    )]
    NotATree { roots: usize, unreachable: usize },

    /// The weights name a bone that the rig does not have.
    #[error("the skinning weights name bone '{bone}', which is not a bone of the rig")]
    UnknownWeightBone { bone: String },

    /// A weight is negative or not finite.
    #[error("bone '{bone}' has weight {weight} on vertex {vertex}: weights must be finite and non-negative")]
    BadWeight { bone: String, vertex: u32, weight: f64 },

    /// A pose names a bone that the rig does not have.
    #[error("pose '{pose}' turns bone '{bone}', which is not a bone of the rig")]
    UnknownPoseBone { pose: String, bone: String },

    /// A pose asks for a bone's hinge axis, but the bone has no parent or is parallel
    /// to its parent, so the hinge is undefined.
    #[error(
        "pose '{pose}' turns bone '{bone}' about its hinge, but the bone is parallel to its parent (or has none)"
    )]
    NoHinge { pose: String, bone: String },

    /// A bone of the rig has no entry in the bone-to-part table of `parts.rs`.
    #[error("bone '{bone}' has no body part in the bone-to-part table")]
    UnmappedBone { bone: String },

    /// A body part (after merging bones) has too few vertices to be fitted.
    #[error("part {part} '{name}' has {vertices} vertices, fewer than the minimum {minimum}")]
    PartTooSmall { part: u32, name: String, vertices: usize, minimum: usize },

    /// A posed body has inverted faces or more self-intersections than the rest pose:
    /// the pose table asks for too much of linear blend skinning.
    #[error(
        "pose '{pose}' is not clean: {inverted_faces} inverted faces, {intersections} self-intersecting edge/face pairs (rest pose: {rest_intersections}); reduce its rotations"
    )]
    PoseNotClean { pose: String, inverted_faces: usize, intersections: usize, rest_intersections: usize },

    /// The posed meshes failed `PoseSet` validation (a bug in the generator).
    #[error("the generated pose set is invalid (a bug in the generator)")]
    Mesh(#[from] desal_mesh::MeshError),
}
