//! Reading a skinned glTF 2.0 file (`.glb` or `.gltf` with its buffers) into a [`Rig`],
//! through the `gltf` crate, which parses and validates the JSON (every index in range)
//! and reads accessors of any component type, stride and normalisation.
//!
//! What is read: the node tree and scenes; the one skinned mesh (the mesh of a node that
//! has a skin; when there are several, [`ReadOptions::mesh`] picks one by mesh or node
//! name) with `POSITION`, `NORMAL`, `TEXCOORD_0` and every `JOINTS_n`/`WEIGHTS_n` set, its
//! triangle primitives concatenated; its skin; the animations' translation, rotation and
//! scale channels. What is refused, with the file and the element: no skin, an ambiguous
//! skinned mesh, morph targets, weights that do not sum to 1, weights on joints the skin
//! does not have, non-triangle primitives, non-finite values. Other meshes, materials,
//! cameras and extensions are not read (and so not written back).

use std::path::{Path, PathBuf};

use gltf::Document;
use gltf::animation::util::ReadOutputs;

use crate::RigError;
use crate::model::{
    Animation, Channel, Influences, Interpolation, LocalTransform, Node, Path as ChannelPath, Rig, Skin,
    SkinnedMesh,
};

/// How far a vertex's weights may sum from 1 before the file is refused. Exporters
/// write `f32` or quantised weights; 1e-3 passes 8-bit normalised weights and catches
/// weights that were never normalised.
pub const WEIGHT_SUM_TOLERANCE: f64 = 1e-3;

/// Options of [`read_rig`].
#[derive(Debug, Clone, Default)]
pub struct ReadOptions {
    /// Which skinned mesh, by mesh name or node name, when the file has several.
    pub mesh: Option<String>,
}

/// Reads the rig in `path` (`.glb`, or `.gltf` whose buffers are beside it or embedded).
pub fn read_rig(path: &Path, options: &ReadOptions) -> Result<Rig, RigError> {
    let bytes = std::fs::read(path).map_err(|cause| RigError::Io { path: path.to_owned(), cause })?;
    read_rig_from(path, &bytes, options)
}

/// Reads a rig from `bytes`; `path` names it in errors and locates external buffers.
pub fn read_rig_from(path: &Path, bytes: &[u8], options: &ReadOptions) -> Result<Rig, RigError> {
    let gltf =
        gltf::Gltf::from_slice(bytes).map_err(|cause| RigError::Gltf { path: path.to_owned(), cause })?;
    let buffers = load_buffers(path, &gltf.document, gltf.blob.as_deref())?;
    let reader = Reader { path: path.to_owned(), document: &gltf.document, buffers };
    reader.read(options)
}

struct Reader<'a> {
    path: PathBuf,
    document: &'a Document,
    buffers: Vec<Vec<u8>>,
}

impl Reader<'_> {
    fn read(&self, options: &ReadOptions) -> Result<Rig, RigError> {
        let (mesh_node, mesh, skin) = self.pick_skinned_mesh(options)?;
        let skin = self.read_skin(&skin)?;
        let mesh = self.read_mesh(&mesh, &skin)?;
        let nodes = self.document.nodes().map(|n| self.read_node(&n)).collect();
        let scenes = self.document.scenes().map(|s| s.nodes().map(|n| n.index()).collect()).collect();
        let scene = self.document.default_scene().map(|s| s.index());
        let animations =
            self.document.animations().map(|a| self.read_animation(&a)).collect::<Result<_, _>>()?;
        let rig = Rig { nodes, scenes, scene, mesh_node, skin, animations, mesh };
        check_tree(&self.path, &rig)?;
        Ok(rig)
    }

    /// The node carrying the skinned mesh, the mesh and its skin.
    fn pick_skinned_mesh(
        &self,
        options: &ReadOptions,
    ) -> Result<(usize, gltf::Mesh<'_>, gltf::Skin<'_>), RigError> {
        let skinned: Vec<(gltf::Node, gltf::Mesh, gltf::Skin)> =
            self.document.nodes().filter_map(|n| Some((n.clone(), n.mesh()?, n.skin()?))).collect();
        let label = |(n, m, _): &(gltf::Node, gltf::Mesh, gltf::Skin)| {
            format!("'{}' (node '{}')", mesh_name(m), n.name().unwrap_or("unnamed"))
        };
        let names = skinned.iter().map(label).collect::<Vec<_>>().join(", ");
        let chosen = match &options.mesh {
            None if skinned.is_empty() => return Err(RigError::NoSkin { path: self.path.clone() }),
            None if skinned.len() > 1 => {
                return Err(RigError::SeveralSkinnedMeshes {
                    path: self.path.clone(),
                    count: skinned.len(),
                    names,
                });
            }
            None => 0,
            Some(wanted) => skinned
                .iter()
                .position(|(n, m, _)| m.name() == Some(wanted) || n.name() == Some(wanted))
                .ok_or_else(|| {
                    if skinned.is_empty() {
                        RigError::NoSkin { path: self.path.clone() }
                    } else {
                        RigError::NoSuchMesh { path: self.path.clone(), wanted: wanted.clone(), names }
                    }
                })?,
        };
        let (node, mesh, skin) = skinned.into_iter().nth(chosen).expect("in range");
        Ok((node.index(), mesh, skin))
    }

    /// The bytes of a buffer, for the `gltf` crate's accessor readers.
    fn data<'s>(&'s self) -> impl Clone + Fn(gltf::Buffer<'_>) -> Option<&'s [u8]> {
        let buffers: &'s [Vec<u8>] = &self.buffers;
        move |b: gltf::Buffer<'_>| buffers.get(b.index()).map(Vec::as_slice)
    }

    fn read_skin(&self, skin: &gltf::Skin<'_>) -> Result<Skin, RigError> {
        let name = skin.name().map(str::to_owned);
        let joints: Vec<usize> = skin.joints().map(|n| n.index()).collect();
        let skin_error = |reason: String| RigError::Skin {
            path: self.path.clone(),
            skin: name.clone().unwrap_or_else(|| format!("skin {}", skin.index())),
            reason,
        };
        if joints.is_empty() || joints.len() > usize::from(u16::MAX) {
            return Err(skin_error(format!("has {} joints; a skin needs 1 to 65535", joints.len())));
        }
        let inverse_bind: Vec<[f32; 16]> = match skin.reader(self.data()).read_inverse_bind_matrices() {
            None if skin.inverse_bind_matrices().is_some() => {
                return Err(skin_error("inverseBindMatrices lie outside their buffer".into()));
            }
            None => vec![identity_matrix(); joints.len()],
            Some(iter) => iter.map(flatten_matrix).collect(),
        };
        if inverse_bind.len() != joints.len() {
            return Err(skin_error(format!(
                "has {} joints but {} inverse bind matrices",
                joints.len(),
                inverse_bind.len()
            )));
        }
        if let Some(j) = inverse_bind.iter().position(|m| !m.iter().all(|x| x.is_finite())) {
            return Err(skin_error(format!("inverse bind matrix {j} is not finite")));
        }
        Ok(Skin { name, joints, inverse_bind, skeleton: skin.skeleton().map(|n| n.index()) })
    }

    fn read_mesh(&self, mesh: &gltf::Mesh<'_>, skin: &Skin) -> Result<SkinnedMesh, RigError> {
        let name = mesh_name(mesh);
        let mut out = SkinnedMesh {
            name: name.clone(),
            positions: Vec::new(),
            normals: Some(Vec::new()),
            uvs: Some(Vec::new()),
            influences: Influences::new(),
            triangles: Vec::new(),
        };
        for primitive in mesh.primitives() {
            let p = primitive.index();
            let bad = |reason: &str| RigError::Primitive {
                path: self.path.clone(),
                mesh: name.clone(),
                primitive: p,
                reason: reason.to_owned(),
            };
            let targets = primitive.morph_targets().len();
            if targets > 0 {
                return Err(RigError::MorphTargets {
                    path: self.path.clone(),
                    mesh: name.clone(),
                    primitive: p,
                    targets,
                });
            }
            if primitive.mode() != gltf::mesh::Mode::Triangles {
                return Err(bad(&format!("mode {:?}: only triangle lists are supported", primitive.mode())));
            }
            let reader = primitive.reader(self.data());
            let positions: Vec<[f32; 3]> = reader
                .read_positions()
                .ok_or_else(|| bad("has no POSITION (or it lies outside its buffer)"))?
                .collect();
            let base = out.positions.len();
            let count = positions.len();
            if let Some(v) = positions.iter().position(|p| !p.iter().all(|x| x.is_finite())) {
                return Err(RigError::BadValue {
                    path: self.path.clone(),
                    mesh: name.clone(),
                    vertex: base + v,
                    what: "POSITION".into(),
                });
            }
            out.positions.extend(positions);
            // An attribute is kept only when every primitive has it.
            match (reader.read_normals(), &mut out.normals) {
                (Some(n), Some(all)) => all.extend(n),
                _ => out.normals = None,
            }
            match (reader.read_tex_coords(0), &mut out.uvs) {
                (Some(t), Some(all)) => all.extend(t.into_f32()),
                _ => out.uvs = None,
            }
            let mut joints: Vec<Vec<[u16; 4]>> = Vec::new();
            let mut weights: Vec<Vec<[f32; 4]>> = Vec::new();
            for set in 0.. {
                match (reader.read_joints(set), reader.read_weights(set)) {
                    (Some(j), Some(w)) => {
                        joints.push(j.into_u16().collect());
                        weights.push(w.into_f32().collect());
                    }
                    (None, None) => break,
                    _ => return Err(bad(&format!("JOINTS_{set} and WEIGHTS_{set} must come together"))),
                }
                if joints.last().map(Vec::len) != Some(count) || weights.last().map(Vec::len) != Some(count) {
                    return Err(bad(&format!("JOINTS_{set}/WEIGHTS_{set} do not have one entry per vertex")));
                }
            }
            if joints.is_empty() {
                return Err(bad("has no JOINTS_0/WEIGHTS_0: the mesh is not skinned"));
            }
            self.read_influences(&joints, &weights, base, &name, skin, &mut out.influences)?;
            let indices: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None if primitive.indices().is_some() => return Err(bad("indices lie outside their buffer")),
                None => (0..count as u32).collect(),
            };
            if !indices.len().is_multiple_of(3) {
                return Err(bad(&format!("{} indices is not a whole number of triangles", indices.len())));
            }
            if let Some(i) = indices.iter().find(|&&i| i as usize >= count) {
                return Err(bad(&format!("index {i} is out of range: the primitive has {count} vertices")));
            }
            out.triangles.extend(indices.chunks(3).map(|t| [t[0], t[1], t[2]].map(|i| i + base as u32)));
        }
        let lengths = [out.normals.as_ref().map(Vec::len), out.uvs.as_ref().map(Vec::len)];
        if lengths.iter().flatten().any(|&l| l != out.positions.len()) {
            return Err(RigError::Primitive {
                path: self.path.clone(),
                mesh: name,
                primitive: 0,
                reason: "NORMAL or TEXCOORD_0 has a different count from POSITION".into(),
            });
        }
        if out.positions.is_empty() || out.triangles.is_empty() {
            return Err(RigError::Primitive {
                path: self.path.clone(),
                mesh: name,
                primitive: 0,
                reason: "the skinned mesh has no triangles".into(),
            });
        }
        Ok(out)
    }

    /// Checks and appends the influences of one primitive's vertices (`base..`).
    fn read_influences(
        &self,
        joints: &[Vec<[u16; 4]>],
        weights: &[Vec<[f32; 4]>],
        base: usize,
        mesh: &str,
        skin: &Skin,
        out: &mut Influences,
    ) -> Result<(), RigError> {
        let count = joints[0].len();
        let skin_name = skin.name.clone().unwrap_or_else(|| "unnamed".into());
        for v in 0..count {
            let mut row = Vec::with_capacity(4 * joints.len());
            let mut sum = 0.0f64;
            for (js, ws) in joints.iter().zip(weights) {
                for (&j, &w) in js[v].iter().zip(&ws[v]) {
                    if !(w.is_finite() && w >= 0.0) {
                        return Err(RigError::BadValue {
                            path: self.path.clone(),
                            mesh: mesh.to_owned(),
                            vertex: base + v,
                            what: format!("weight {w} of joint {j}"),
                        });
                    }
                    if w == 0.0 {
                        continue;
                    }
                    if usize::from(j) >= skin.joints.len() {
                        return Err(RigError::JointOutOfRange {
                            path: self.path.clone(),
                            mesh: mesh.to_owned(),
                            vertex: base + v,
                            joint: j.into(),
                            weight: w.into(),
                            skin: skin_name.clone(),
                            joint_count: skin.joints.len(),
                        });
                    }
                    sum += f64::from(w);
                    row.push((j, w));
                }
            }
            if (sum - 1.0).abs() > WEIGHT_SUM_TOLERANCE {
                return Err(RigError::WeightsNotNormalised {
                    path: self.path.clone(),
                    mesh: mesh.to_owned(),
                    vertex: base + v,
                    sum,
                });
            }
            out.push_row(row);
        }
        Ok(())
    }

    fn read_node(&self, node: &gltf::Node<'_>) -> Node {
        let transform = match node.transform() {
            gltf::scene::Transform::Matrix { matrix } => LocalTransform::Matrix(flatten_matrix(matrix)),
            gltf::scene::Transform::Decomposed { translation, rotation, scale } => {
                LocalTransform::Trs { translation, rotation, scale }
            }
        };
        Node {
            name: node.name().map(str::to_owned),
            children: node.children().map(|c| c.index()).collect(),
            transform,
        }
    }

    fn read_animation(&self, animation: &gltf::Animation<'_>) -> Result<Animation, RigError> {
        let name = animation.name().map(str::to_owned);
        let mut channels = Vec::new();
        for (c, channel) in animation.channels().enumerate() {
            let bad = |reason: &str| RigError::Animation {
                path: self.path.clone(),
                animation: name.clone().unwrap_or_else(|| format!("animation {}", animation.index())),
                channel: c,
                reason: reason.to_owned(),
            };
            let reader = channel.reader(self.data());
            let times: Vec<f32> =
                reader.read_inputs().ok_or_else(|| bad("input lies outside its buffer"))?.collect();
            let (path, values): (ChannelPath, Vec<f32>) =
                match reader.read_outputs().ok_or_else(|| bad("output lies outside its buffer"))? {
                    ReadOutputs::Translations(t) => (ChannelPath::Translation, t.flatten().collect()),
                    ReadOutputs::Rotations(r) => (ChannelPath::Rotation, r.into_f32().flatten().collect()),
                    ReadOutputs::Scales(s) => (ChannelPath::Scale, s.flatten().collect()),
                    // Morph target weights: the mesh has no morph targets (they are refused).
                    ReadOutputs::MorphTargetWeights(_) => continue,
                };
            let interpolation = match channel.sampler().interpolation() {
                gltf::animation::Interpolation::Step => Interpolation::Step,
                gltf::animation::Interpolation::Linear => Interpolation::Linear,
                gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
            };
            let channel =
                Channel { node: channel.target().node().index(), path, interpolation, times, values };
            let per_key = channel.width() * if interpolation == Interpolation::CubicSpline { 3 } else { 1 };
            if channel.times.is_empty() || channel.values.len() != channel.times.len() * per_key {
                return Err(bad("needs one output value per keyframe time"));
            }
            if !channel.times.windows(2).all(|w| w[0] < w[1]) || !channel.times.iter().all(|t| t.is_finite())
            {
                return Err(bad("keyframe times must be finite and strictly increasing"));
            }
            if !channel.values.iter().all(|x| x.is_finite()) {
                return Err(bad("has a value that is not finite"));
            }
            if matches!(
                self.document.nodes().nth(channel.node).map(|n| n.transform()),
                Some(gltf::scene::Transform::Matrix { .. })
            ) {
                return Err(bad("animates a node whose transform is a matrix (glTF forbids it)"));
            }
            channels.push(channel);
        }
        Ok(Animation { name, channels })
    }
}

/// Every node has at most one parent and the graph has no cycle.
fn check_tree(path: &Path, rig: &Rig) -> Result<(), RigError> {
    let mut parent_count = vec![0usize; rig.nodes.len()];
    for node in &rig.nodes {
        for &c in &node.children {
            parent_count[c] += 1;
        }
    }
    if let Some(n) = parent_count.iter().position(|&c| c > 1) {
        return Err(RigError::Node {
            path: path.to_owned(),
            node: n,
            reason: "has more than one parent".into(),
        });
    }
    let parents = rig.parents();
    for start in 0..rig.nodes.len() {
        let mut current = parents[start];
        let mut steps = 0;
        while let Some(p) = current {
            steps += 1;
            if steps > rig.nodes.len() {
                return Err(RigError::Node {
                    path: path.to_owned(),
                    node: start,
                    reason: "lies on a cycle".into(),
                });
            }
            current = parents[p];
        }
    }
    Ok(())
}

fn mesh_name(mesh: &gltf::Mesh<'_>) -> String {
    mesh.name().map_or_else(|| format!("mesh {}", mesh.index()), str::to_owned)
}

fn identity_matrix() -> [f32; 16] {
    let mut m = [0.0; 16];
    for i in 0..4 {
        m[i * 5] = 1.0;
    }
    m
}

fn flatten_matrix(m: [[f32; 4]; 4]) -> [f32; 16] {
    let mut out = [0.0; 16];
    for (c, column) in m.iter().enumerate() {
        out[c * 4..c * 4 + 4].copy_from_slice(column);
    }
    out
}

/// The bytes of every buffer: the GLB's binary chunk, a file beside `path`, or a
/// base64 `data:` URI.
fn load_buffers(path: &Path, document: &Document, blob: Option<&[u8]>) -> Result<Vec<Vec<u8>>, RigError> {
    let mut out = Vec::new();
    for buffer in document.buffers() {
        let bad = |reason: String| RigError::Buffer { path: path.to_owned(), buffer: buffer.index(), reason };
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => {
                blob.ok_or_else(|| bad("refers to the GLB binary chunk, which is missing".into()))?.to_vec()
            }
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                let (_, encoded) =
                    uri.split_once(";base64,").ok_or_else(|| bad("data URI is not base64".into()))?;
                decode_base64(encoded).ok_or_else(|| bad("data URI is not valid base64".into()))?
            }
            gltf::buffer::Source::Uri(uri) => {
                if uri.contains("://") {
                    return Err(bad(format!(
                        "URI '{uri}' is not a file beside the glTF; only relative file paths are read"
                    )));
                }
                let file = path.parent().unwrap_or(Path::new(".")).join(uri);
                std::fs::read(&file).map_err(|e| bad(format!("cannot read {}: {e}", file.display())))?
            }
        };
        if data.len() < buffer.length() {
            return Err(bad(format!("declares {} bytes but holds {}", buffer.length(), data.len())));
        }
        out.push(data);
    }
    Ok(out)
}

/// Standard base64 (RFC 4648, with or without padding); `None` on any other byte.
fn decode_base64(text: &str) -> Option<Vec<u8>> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let bytes = text.trim_end_matches('=').as_bytes();
    let mut out = Vec::with_capacity(bytes.len() * 3 / 4);
    for chunk in bytes.chunks(4) {
        if chunk.len() == 1 {
            return None;
        }
        let mut acc = 0u32;
        for (i, &c) in chunk.iter().enumerate() {
            acc |= value(c)? << (18 - 6 * i);
        }
        out.extend(&acc.to_be_bytes()[1..chunk.len()]);
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::decode_base64;

    #[test]
    fn base64_decodes_padded_and_unpadded_text() {
        assert_eq!(decode_base64("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(decode_base64("aGVsbG8").unwrap(), b"hello");
        assert_eq!(decode_base64("AAECAw==").unwrap(), [0, 1, 2, 3]);
        assert!(decode_base64("a$==").is_none());
    }
}
