//! `desal inspect FILE`: what an artifact is, who made it, from what, and its summary
//! figures.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use desal_io::artifact::{self, ArtifactKind, LabelsV1, PoseSetV2};

/// A human-readable description of the artifact at `path`.
pub fn describe(path: &Path) -> Result<String> {
    let (header, producer) = artifact::read_producer(path)?;
    let mut out = String::new();
    writeln!(out, "{}", path.display())?;
    writeln!(out, "  kind            {} (format version {})", header.kind, header.version)?;
    writeln!(out, "  content hash    {}", header.checksum)?;
    writeln!(out, "  payload         {} bytes", header.payload_len)?;
    writeln!(
        out,
        "  producer        {} v{} (desal {})",
        producer.stage, producer.stage_version, producer.tool_version
    )?;
    let params = &producer.parameters;
    if params.len() > 300 {
        writeln!(
            out,
            "  parameters      {}... ({} bytes)",
            &params[..params.floor_char_boundary(300)],
            params.len()
        )?;
    } else {
        writeln!(out, "  parameters      {params}")?;
    }
    writeln!(out, "  inputs          {}", producer.inputs.len())?;
    for input in producer.inputs.iter().take(8) {
        writeln!(out, "    {:<14} {}  {}", input.role, input.hash.short(), input.hint)?;
    }
    if producer.inputs.len() > 8 {
        writeln!(out, "    ... and {} more", producer.inputs.len() - 8)?;
    }
    writeln!(out, "  summary")?;
    match header.kind {
        ArtifactKind::PoseSet => {
            let (_, body, _) = artifact::read_artifact::<PoseSetV2>(path)?;
            let set = body.to_pose_set()?;
            let t = set.template_mesh();
            writeln!(
                out,
                "    poses {}, vertices {}, faces {}",
                set.pose_count(),
                set.vertex_count(),
                set.face_count()
            )?;
            writeln!(
                out,
                "    template '{}', bounding-box diagonal {:.4}",
                set.names[set.template],
                t.diagonal()
            )?;
            if let Some(groups) = set.group_count() {
                writeln!(out, "    groups {groups} (held-out figures hold out whole groups)")?;
            }
        }
        ArtifactKind::Labels => {
            let (_, body, _) = artifact::read_artifact::<LabelsV1>(path)?;
            let labels = body.to_labels()?;
            for (k, members) in labels.members().iter().enumerate() {
                writeln!(out, "    part {k:>2} {:<16} {} vertices", labels.names[k], members.len())?;
            }
        }
        // `desal eval`'s own entry, not a stage's.
        ArtifactKind::Floor => {
            let (_, body, _) = artifact::read_artifact::<desal_io::artifact::FloorV1>(path)?;
            desal_experiment::floor::describe(&body, &mut out)?;
        }
        _ => desal_driver::stages::describe_stage_artifact(path, header.kind, &mut out)?,
    }
    Ok(out)
}
