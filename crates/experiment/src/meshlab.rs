//! MeshLab's quadric edge collapse (VCG) through pymeshlab, as the baselines a user
//! would assemble in five minutes: plain, and with stage 2's saliency weights as vertex
//! quality (`qualityweight`, the paper's Eq. 3 imitated with an existing tool).
//!
//! The Python script (`meshlab_qec.py`) is embedded in the binary and written, with the
//! template (binary PLY) and the weights (text), into a temporary folder per run. The
//! interpreter is `$DESAL_PYTHON`, else `python3`; it needs `pip install pymeshlab`.
//! MeshLab places vertices optimally, so its result is mapped by stage 4's greedy rule,
//! like an external mesh. It targets a face count: the one that keeps the template's
//! Euler characteristic and boundary at the target vertex count (`F − 2V` is constant
//! under edge collapse of a manifold), so that it reaches the same vertex budget as the
//! other methods; the count it reached is reported.

use std::path::PathBuf;
use std::process::Command;

use anyhow::{Context, Result, bail};
use desal_io::ply::{PlyWriteOptions, write_ply};
use desal_mesh::TriMesh;

/// The embedded pymeshlab driver.
const SCRIPT: &str = include_str!("meshlab_qec.py");

/// The environment variable naming the Python interpreter with pymeshlab.
pub const PYTHON_VAR: &str = "DESAL_PYTHON";

/// Which MeshLab run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variant {
    Plain,
    Saliency,
}

impl Variant {
    pub const ALL: [Variant; 2] = [Variant::Plain, Variant::Saliency];

    pub fn name(self) -> &'static str {
        match self {
            Variant::Plain => "meshlab",
            Variant::Saliency => "meshlab-saliency",
        }
    }
}

/// The interpreter `desal eval` runs the script with.
pub fn python() -> PathBuf {
    std::env::var_os(PYTHON_VAR).map_or_else(|| PathBuf::from("python3"), PathBuf::from)
}

/// The face count that keeps `template`'s `F − 2V` at `vertices` vertices.
pub fn face_target(template: &TriMesh, vertices: usize) -> usize {
    let excess = template.face_count() as i64 - 2 * template.vertex_count() as i64;
    (2 * vertices as i64 + excess).max(1) as usize
}

/// Simplifies `template` with MeshLab to `face_target(template, vertices)` faces;
/// `weights` are stage 2's per-vertex weights (read by [`Variant::Saliency`]). Returns
/// the simplified mesh as MeshLab wrote it and the seconds MeshLab itself reported.
pub fn simplify(
    template: &TriMesh,
    weights: &[f64],
    variant: Variant,
    vertices: usize,
) -> Result<(TriMesh, f64)> {
    let name = variant.name();
    let dir = tempfile::tempdir().context("a temporary folder for MeshLab")?;
    let (script, input, weights_path, output) = (
        dir.path().join("meshlab_qec.py"),
        dir.path().join("template.ply"),
        dir.path().join("weights.txt"),
        dir.path().join("simplified.ply"),
    );
    std::fs::write(&script, SCRIPT)?;
    write_ply(&input, template, &PlyWriteOptions::default())?;
    let text: String = weights.iter().map(|w| format!("{w:.17e}\n")).collect();
    std::fs::write(&weights_path, text)?;
    let python = python();
    let mut command = Command::new(&python);
    command.arg(&script).arg(&input).arg(&weights_path).arg(&output);
    command.arg(face_target(template, vertices).to_string());
    if variant == Variant::Plain {
        command.arg("--plain");
    }
    let out = command.output().with_context(|| {
        format!("{name}: cannot run {} (set {PYTHON_VAR} to a Python with pymeshlab)", python.display())
    })?;
    if !out.status.success() {
        let stderr = String::from_utf8_lossy(&out.stderr);
        let hint = if stderr.contains("No module named 'pymeshlab'") {
            format!(" ({} has no pymeshlab: pip install pymeshlab, or set {PYTHON_VAR})", python.display())
        } else {
            String::new()
        };
        bail!("{name}: MeshLab failed{hint}: {}", stderr.trim());
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    let seconds = stdout
        .lines()
        .find_map(|l| l.strip_prefix("SIMPLIFY_SECONDS="))
        .and_then(|s| s.trim().parse::<f64>().ok())
        .with_context(|| format!("{name}: the script printed no SIMPLIFY_SECONDS: {stdout}"))?;
    let mesh = desal_io::read_mesh(&output).with_context(|| format!("{name}: reading MeshLab's output"))?;
    Ok((mesh, seconds))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_face_target_keeps_the_euler_characteristic_and_boundary() {
        // A closed genus-0 mesh: F = 2V − 4 (the sample), and SCAPE's F = 2V − 2.
        let mesh = |v: usize, f: usize| TriMesh {
            positions: vec![desal_mesh::Vec3::zeros(); v],
            faces: vec![[0, 1, 2]; f],
        };
        assert_eq!(face_target(&mesh(13380, 26756), 2500), 4996);
        assert_eq!(face_target(&mesh(12500, 24998), 2500), 4998);
    }
}
