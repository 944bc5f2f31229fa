//! The error type of mesh construction and validation. Variants carry the offending
//! pose, vertex, face or part so that callers (which add the file path) can say exactly
//! what to fix.

use thiserror::Error;

/// What is wrong with a mesh, a pose set or a set of part labels.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MeshError {
    /// The mesh has no vertices or no faces. Usually a wrong or empty file.
    #[error("the mesh is empty ({vertices} vertices, {faces} faces)")]
    Empty { vertices: usize, faces: usize },

    /// A pose set was built from zero poses. Check the pose list or glob.
    #[error("the pose list is empty: give at least one pose file")]
    NoPoses,

    /// A face references a vertex that does not exist.
    #[error("face {face} references vertex {vertex}, but there are only {vertex_count} vertices")]
    FaceIndexOutOfRange { face: usize, vertex: u32, vertex_count: usize },

    /// A coordinate is NaN or infinite.
    #[error("vertex {vertex} of pose '{pose}' has a non-finite coordinate ({x}, {y}, {z})")]
    NonFiniteVertex { pose: String, vertex: usize, x: f64, y: f64, z: f64 },

    /// A pose does not have the template's vertex count, so it is not registered.
    #[error(
        "pose '{pose}' has {found} vertices but the template '{template}' has {expected}; all poses must be registered (same vertex count and order)"
    )]
    VertexCountMismatch { pose: String, template: String, expected: usize, found: usize },

    /// A pose's own triangle list differs from the template's.
    #[error(
        "pose '{pose}' has a different triangle list from the template: first difference at face {face} ({} vs the template's {}); set `ignore_pose_faces = true` to use the template's triangles for every pose",
        describe_face(found),
        describe_face(expected)
    )]
    FaceMismatch { pose: String, face: usize, expected: Option<[u32; 3]>, found: Option<[u32; 3]> },

    /// The template index is not one of the poses.
    #[error("template index {template} is out of range for {poses} poses")]
    TemplateOutOfRange { template: usize, poses: usize },

    /// The group ids do not cover the poses one to one.
    #[error("there are {groups} group ids for {poses} poses; give one group id per pose, in pose order")]
    GroupCountMismatch { groups: usize, poses: usize },

    /// The labels do not cover the mesh's vertices one to one.
    #[error(
        "the part labels have {labels} entries but the mesh has {vertices} vertices; give one part id per vertex"
    )]
    LabelCountMismatch { labels: usize, vertices: usize },

    /// A vertex carries a part id with no part name.
    #[error("vertex {vertex} has part id {part}, but only {part_count} parts are named")]
    UnknownPart { vertex: usize, part: u32, part_count: usize },

    /// A part cannot support a rigid fit: fewer than 3 vertices, or all collinear.
    #[error(
        "part {part} ('{name}') has {vertices} vertices that do not span a plane (fewer than 3, or all collinear); a rigid fit needs 3 non-collinear vertices per part — merge it into a neighbouring part"
    )]
    DegeneratePart { part: u32, name: String, vertices: usize },
    /// A part tree that is not a tree over the labels' parts (`PartLabels::with_parents`).
    #[error("the part tree is not a tree over the parts: {reason}")]
    PartTree { reason: String },
}

/// `[a, b, c]`, or `no face` past the end of a shorter list.
fn describe_face(face: &Option<[u32; 3]>) -> String {
    match face {
        Some([a, b, c]) => format!("[{a}, {b}, {c}]"),
        None => "no face".into(),
    }
}
