//! The entry points of stage 3: [`simplify`], [`simplify_with_progress`] and
//! [`simplify_multipose`] validate the configuration and the input here, then hand
//! them to the engine (`collapse::run_engine`).

use desal_mesh::{Progress, TriMesh, Vec3, VertexFaces};

use crate::collapse::run_engine;
use crate::config::{Placement, SimplifyConfig};
use crate::error::SimplifyError;
use crate::types::{Simplified, SimplifyInput};

/// Simplifies `input.mesh` as `config` says (quadric edge collapse, the paper's cost).
///
/// Units: positions in mesh units; errors in the report are RMS distances in mesh
/// units. When the safeguards leave no valid collapse before the target, the result is
/// larger than the target and `report.stop` says so. Deterministic: the same input and
/// config give the same output whatever the rayon thread count.
pub fn simplify(input: &SimplifyInput<'_>, config: &SimplifyConfig) -> Result<Simplified, SimplifyError> {
    simplify_with_progress(input, config, &desal_mesh::NoProgress)
}

/// [`simplify`], reporting progress (one unit per collapse) to `progress`.
pub fn simplify_with_progress(
    input: &SimplifyInput<'_>,
    config: &SimplifyConfig,
    progress: &dyn Progress,
) -> Result<Simplified, SimplifyError> {
    config.validate()?;
    check_input(input)?;
    let poses = [input.mesh.positions.as_slice()];
    run_engine(&poses, 0, input, config, progress)
}

/// Mohr and Gleicher 2003 multi-pose QEM: every vertex's quadric is kept per pose (the
/// planes of its faces *in that pose*), and keeping vertex `k` for an edge costs the
/// sum over poses of that pose's merged quadric evaluated at `k`'s position in that
/// pose. Placement is always [`Placement::Subset`] (a new position would have to be
/// invented in every pose); `config.placement` is ignored. The fold-over and
/// degeneracy safeguards look at the template pose. `weights`, `part_labels`, balance
/// and the target behave as in [`simplify`]; the output is the simplified template.
/// There are no seams.
pub fn simplify_multipose(
    poses: &desal_mesh::PoseSet,
    weights: Option<&[f64]>,
    part_labels: Option<&[u32]>,
    config: &SimplifyConfig,
) -> Result<Simplified, SimplifyError> {
    config.validate()?;
    let template = poses.template_mesh();
    let input = SimplifyInput { weights, part_labels, ..SimplifyInput::new(&template) };
    check_input(&input)?;
    let positions: Vec<&[Vec3]> = poses.poses.iter().map(|p| p.as_slice()).collect();
    let config = SimplifyConfig { placement: Placement::Subset, ..config.clone() };
    run_engine(&positions, poses.template, &input, &config, &desal_mesh::NoProgress)
}

/// Validates sizes and values the engine relies on; errors name the offending element.
fn check_input(input: &SimplifyInput<'_>) -> Result<(), SimplifyError> {
    let SimplifyInput { mesh, weights, part_labels, seams, keep_penalty } = *input;
    let n = mesh.positions.len();
    if n == 0 || mesh.faces.is_empty() {
        return Err(SimplifyError::EmptyMesh { vertices: n, faces: mesh.faces.len() });
    }
    if let Some(vertex) = mesh.positions.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
        return Err(SimplifyError::NonFinitePosition { vertex });
    }
    for (face, f) in mesh.faces.iter().enumerate() {
        if let Some(&vertex) = f.iter().find(|&&v| v as usize >= n) {
            return Err(SimplifyError::FaceIndexOutOfRange { face, vertex, vertex_count: n });
        }
    }
    if let Some(w) = weights {
        if w.len() != n {
            return Err(SimplifyError::WeightCountMismatch { weights: w.len(), vertices: n });
        }
        if let Some(vertex) = w.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
            return Err(SimplifyError::BadWeight { vertex, value: w[vertex] });
        }
    }
    if let Some(k) = keep_penalty {
        if k.len() != n {
            return Err(SimplifyError::KeepPenaltyCountMismatch { penalties: k.len(), vertices: n });
        }
        if let Some(vertex) = k.iter().position(|x| !(x.is_finite() && *x >= 0.0)) {
            return Err(SimplifyError::BadKeepPenalty { vertex, value: k[vertex] });
        }
    }
    if let Some(l) = part_labels
        && l.len() != n
    {
        return Err(SimplifyError::LabelCountMismatch { labels: l.len(), vertices: n });
    }
    if let Some(seams) = seams {
        check_seams(mesh, seams)?;
    }
    Ok(())
}

/// Every seam is an edge of the mesh: two distinct vertices in range that share a face.
fn check_seams(mesh: &TriMesh, seams: &[[u32; 2]]) -> Result<(), SimplifyError> {
    let n = mesh.positions.len();
    for (seam, &[a, b]) in seams.iter().enumerate() {
        if let Some(&vertex) = [a, b].iter().find(|&&v| v as usize >= n) {
            return Err(SimplifyError::SeamIndexOutOfRange { seam, vertex, vertex_count: n });
        }
    }
    let vertex_faces = VertexFaces::new(n, &mesh.faces);
    for (seam, &[a, b]) in seams.iter().enumerate() {
        let shared = a != b && vertex_faces.of(a).iter().any(|&f| mesh.faces[f as usize].contains(&b));
        if !shared {
            return Err(SimplifyError::SeamNotAnEdge { seam, a, b });
        }
    }
    Ok(())
}
