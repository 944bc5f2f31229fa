//! Morph targets' `POSITION` deltas as a rig's split vertices see them, for measuring
//! them (issue 42, item 9: each target's error, the simplified mesh against the full one
//! at weight 1). Writing does not need them: [`crate::edit`] copies every target's
//! accessors element by element. Sparse targets are read as any accessor is
//! ([`crate::accessor`]), with every check.

use crate::RigError;
use crate::accessor::{Accessors, Semantic};
use crate::edit::SourceDocument;
use crate::model::Rig;

/// One morph target of one mesh of a rig.
#[derive(Debug, Clone, PartialEq)]
pub struct MorphTarget {
    /// The mesh: an index into [`Rig::meshes`].
    pub part: usize,
    /// The target's index in its mesh (every primitive of a glTF mesh has the same
    /// targets, in the same order).
    pub index: usize,
    /// The mesh's `extras.targetNames[index]`, else `target <index>`.
    pub name: String,
    /// One delta per split vertex of the mesh (`Rig::meshes[part].vertices`, in order), in
    /// the bind space of [`Rig::mesh`]'s positions (a rigid mesh's deltas turned by its
    /// `to_bind`); zero where a primitive has no `POSITION` delta.
    pub deltas: Vec<[f32; 3]>,
}

/// Every morph target of every mesh of `rig`, read from `source` (the document `rig` was
/// read from: [`crate::read_rig_and_document`]), mesh by mesh and target by target.
///
/// Errors: a target accessor that breaks the specification, or whose count is not its
/// primitive's vertex count, named by mesh, primitive and target.
pub fn morph_targets(rig: &Rig, source: &SourceDocument) -> Result<Vec<MorphTarget>, RigError> {
    let accessors = Accessors {
        path: &source.path,
        buffers: &source.buffers,
        quantized: source.quantized,
        real_size: source.real_size,
    };
    let mut targets = Vec::new();
    for (p, part) in rig.meshes.iter().enumerate() {
        let Some(mesh) = source.document.meshes().nth(part.mesh) else { continue };
        let count = mesh.primitives().map(|primitive| primitive.morph_targets().count()).max().unwrap_or(0);
        let names = &source.json["meshes"][part.mesh]["extras"]["targetNames"];
        let linear = part.to_bind.map(|m| m.fixed_view::<3, 3>(0, 0).into_owned());
        for t in 0..count {
            let mut deltas = vec![[0.0f32; 3]; part.vertices.len()];
            let spans = rig.mesh.primitives.iter().filter(|s| {
                s.mesh == part.mesh
                    && part.vertices.start <= s.vertices.start
                    && s.vertices.end <= part.vertices.end
            });
            for span in spans {
                let Some(primitive) = mesh.primitives().nth(span.primitive) else { continue };
                let Some(accessor) = primitive.morph_targets().nth(t).and_then(|target| target.positions())
                else {
                    continue;
                };
                let used_by = format!("mesh '{}' primitive {} morph target {t}", part.name, span.primitive);
                let values = accessors.floats(&accessor, Semantic::Position, &used_by)?;
                if values.len() != 3 * span.vertices.len() {
                    return Err(RigError::Primitive {
                        path: source.path.clone(),
                        mesh: part.name.clone(),
                        primitive: span.primitive,
                        reason: format!(
                            "morph target {t} POSITION has {} elements for {} vertices",
                            values.len() / 3,
                            span.vertices.len()
                        ),
                    });
                }
                let first = (span.vertices.start - part.vertices.start) as usize;
                for (out, d) in deltas[first..].iter_mut().zip(values.chunks_exact(3)) {
                    *out = match &linear {
                        None => [d[0], d[1], d[2]],
                        Some(m) => {
                            let turned = m * nalgebra::Vector3::new(d[0].into(), d[1].into(), d[2].into());
                            [turned.x as f32, turned.y as f32, turned.z as f32]
                        }
                    };
                }
            }
            let name = names[t].as_str().map_or_else(|| format!("target {t}"), str::to_owned);
            targets.push(MorphTarget { part: p, index: t, name, deltas });
        }
    }
    Ok(targets)
}
