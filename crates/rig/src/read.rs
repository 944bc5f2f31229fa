//! Reading a skinned glTF 2.0 file (`.glb` or `.gltf` with its buffers) into a [`Rig`].
//! desal checks the JSON's structure (every reference in range, every enumerated value
//! valid: [`crate::structure`]) before the `gltf` crate parses and validates it
//! ([`crate::document`]); desal reads every accessor itself ([`crate::accessor`]), each
//! checked against the specification's table and its buffer before it is read, so a
//! hostile file is refused by name and never panics, allocates at will or is misread.
//!
//! What is read: the node tree and scenes; every skinned mesh (the mesh of a node that has
//! a skin, in node order, a mesh carried by several nodes once; [`ReadOptions::mesh`]
//! picks one by mesh or node name) with `POSITION`, `NORMAL`, `TEXCOORD_0` and every
//! `JOINTS_n`/`WEIGHTS_n` set, their triangle primitives concatenated ([`MeshPart`] says
//! where each mesh lies); their skins merged into one (a joint per node and inverse bind
//! matrix, the first mesh's skin as it is); without [`ReadOptions::mesh`], every mesh
//! without a skin on a node below a joint too, rigidly skinned to that joint; the
//! animations' translation, rotation and
//! scale channels. Morph targets (sparse ones too) and every other attribute are checked
//! (one element per vertex, layout) and carried into the output by [`crate::edit`]: each
//! kept vertex keeps its deltas. Buffers come from the GLB binary chunk, base64 `data:`
//! URIs, or regular files inside the glTF's own folder ([`desal_io::confine`]). What is
//! refused, with the file and the element: no skin, an ambiguous skinned mesh,
//! all-zero weights (sums off 1 are renormalised and counted in [`Rig::weight_sums`]),
//! weights on joints the skin does not have, non-triangle
//! primitives, non-finite values, zero-length rotations, singular inverse bind matrices,
//! accessors that break the specification. Other meshes, materials, cameras and
//! extensions are not read into the [`Rig`]; [`read_rig_and_document`] keeps the whole
//! document beside it, and [`crate::edit::write_edited`] writes them back unchanged.

use std::path::{Path, PathBuf};

use gltf::Document;

use crate::RigError;
use crate::accessor::{Accessors, Semantic};
use crate::edit::SourceDocument;
use crate::error::without_panics;
use crate::model::{
    Animation, Channel, Influences, Interpolation, LocalTransform, MeshPart, Node, Path as ChannelPath,
    PrimitiveSpan, Rig, Skin, SkinnedMesh, WEIGHT_SUM_REPORTED, WeightSums,
};

/// How far a vertex's weights may sum from 1 and be kept as written. A vertex further off
/// (quantised weights: exporters write 8-bit ones) is divided by its sum, as engines do,
/// and counted in [`crate::model::WeightSums`]; only negative, non-finite or all-zero
/// weights are refused.
pub const WEIGHT_SUM_TOLERANCE: f64 = 1e-3;

/// The shortest rotation quaternion accepted (in a node or a keyframe). glTF requires
/// unit quaternions; ones off by rounding are normalised when posed, as engines do, but
/// one this short has no direction to normalise to.
pub const MIN_ROTATION_LENGTH: f64 = 1e-6;

pub use crate::document::MAX_BUFFER_BYTES;

/// The most keyframe values (times and output components, over every channel of every
/// animation) a file may make desal decode: 2^26 `f32`s, 256 MiB. Counted from the
/// accessors' declared counts before any is decoded, since channels may share one large
/// accessor.
pub const MAX_KEYFRAME_VALUES: u64 = 1 << 26;

/// The `KHR_mesh_quantization` extension: integer positions, normals and UVs.
const MESH_QUANTIZATION: &str = "KHR_mesh_quantization";

/// Options of [`read_rig`].
#[derive(Debug, Clone, Default)]
pub struct ReadOptions {
    /// Only these meshes, each by mesh name, node name or mesh index (`"3"`): skinned
    /// meshes, and meshes below a bone (read rigid); `None`: every skinned mesh and
    /// every mesh below a bone. At least one must be skinned (its skin carries the rest).
    pub mesh: Option<Vec<String>>,
}

/// Reads the rig in `path` (`.glb`, or `.gltf` whose buffers are beside it or embedded).
/// A directory, FIFO or device is refused before it is opened.
pub fn read_rig(path: &Path, options: &ReadOptions) -> Result<Rig, RigError> {
    let bytes = desal_io::file::read_regular_file(path)?;
    read_rig_from(path, &bytes, options)
}

/// Reads a rig from `bytes`; `path` names it in errors and locates external buffers.
pub fn read_rig_from(path: &Path, bytes: &[u8], options: &ReadOptions) -> Result<Rig, RigError> {
    read_rig_and_document(path, bytes, options).map(|(rig, _)| rig)
}

/// [`read_rig_from`], keeping the whole document (its JSON as written, every buffer) for
/// [`crate::edit::write_edited`].
pub fn read_rig_and_document(
    path: &Path,
    bytes: &[u8],
    options: &ReadOptions,
) -> Result<(Rig, SourceDocument), RigError> {
    // The one place desal calls into the `gltf` crate to read: should it panic on a file
    // the checks let through, the caller gets an error naming the file, not an abort (and
    // Python no `PanicException`).
    without_panics(path, || read_checked(path, bytes, options))
}

fn read_checked(path: &Path, bytes: &[u8], options: &ReadOptions) -> Result<(Rig, SourceDocument), RigError> {
    let parsed = crate::document::parse(path, bytes)?;
    let buffers = load_buffers(path, &parsed.document, parsed.blob.as_deref())?;
    let real_size = buffers.iter().fold(bytes.len(), |sum, b| sum.saturating_add(b.len()));
    let quantized = parsed.extensions.iter().any(|e| e == MESH_QUANTIZATION);
    let accessors = Accessors { path, buffers: &buffers, quantized, real_size };
    let reader = Reader { path: path.to_owned(), document: &parsed.document, accessors };
    let rig = reader.read(options)?;
    let source = SourceDocument {
        path: path.to_owned(),
        json: parsed.original,
        document: parsed.document,
        buffers,
        quantized,
        real_size,
    };
    Ok((rig, source))
}

struct Reader<'a> {
    path: PathBuf,
    document: &'a Document,
    accessors: Accessors<'a>,
}

impl Reader<'_> {
    fn read(&self, options: &ReadOptions) -> Result<Rig, RigError> {
        let chosen = self.pick_skinned_meshes(options)?;
        let nodes = self.document.nodes().map(|n| self.read_node(&n)).collect::<Result<Vec<_>, _>>()?;
        // One skin over every chosen mesh: the first mesh's skin as it is, then each other
        // skin's joints matched to a joint of the same node and inverse bind matrix, or
        // added (so a file with one skin gets exactly that skin).
        let mut skin: Option<Skin> = None;
        let mut weight_sums = WeightSums::default();
        let mut mesh: Option<SkinnedMesh> = None;
        let mut parts = Vec::new();
        for (node, gltf_mesh, gltf_skin) in &chosen {
            let own = self.read_skin(gltf_skin, &nodes)?;
            let joints = merge_skin(&mut skin, &own);
            let mut part = self.read_mesh(gltf_mesh, Skinning::Skin(&own), &mut weight_sums)?;
            for j in &mut part.influences.joints {
                *j = joints[usize::from(*j)];
            }
            let all = mesh.get_or_insert_with(|| SkinnedMesh { primitives: Vec::new(), ..part.clone() });
            let (vertices, triangles) = append_mesh(all, part, parts.is_empty());
            parts.push(MeshPart {
                node: *node,
                mesh: gltf_mesh.index(),
                name: mesh_name(gltf_mesh),
                skin: Some(gltf_skin.index()),
                joints,
                to_bind: None,
                vertices,
                triangles,
            });
        }
        let (skin, mesh) = (skin.expect("a mesh was chosen"), mesh.expect("a mesh was chosen"));
        let mesh_node = parts[0].node;
        let scenes = self.document.scenes().map(|s| s.nodes().map(|n| n.index()).collect()).collect();
        let scene = self.document.default_scene().map(|s| s.index());
        self.check_keyframe_total()?;
        let animations =
            self.document.animations().map(|a| self.read_animation(&a)).collect::<Result<_, _>>()?;
        let mut rig =
            Rig { weight_sums, nodes, scenes, scene, mesh_node, meshes: parts, skin, animations, mesh };
        check_tree(&self.path, &rig)?;
        self.add_rigid_meshes(&mut rig, options.mesh.as_deref())?;
        Ok(rig)
    }

    /// Adds every mesh of a node without a skin below a joint (a visor, a weapon) as
    /// rigidly skinned to its nearest joint above, its vertices moved into the skin's bind
    /// space (`MeshPart::to_bind`): in the bind pose the rig's joints are where its inverse
    /// bind matrices put them, and in every pose the mesh follows that joint as the node
    /// tree makes it. A mesh carried by a node not below a joint does not move with the
    /// skeleton and passes through unchanged, as does one already read.
    ///
    /// With `wanted` (`ReadOptions::mesh`), only the meshes it names.
    fn add_rigid_meshes(&self, rig: &mut Rig, wanted: Option<&[String]>) -> Result<(), RigError> {
        let parents = rig.parents();
        let mut joint_of_node = std::collections::HashMap::new();
        for (j, &n) in rig.skin.joints.iter().enumerate() {
            joint_of_node.entry(n).or_insert(j);
        }
        let world = crate::pose::world_matrices(rig, &crate::pose::rest_locals(rig));
        let mut seen: std::collections::BTreeSet<usize> = rig.meshes.iter().map(|m| m.mesh).collect();
        let mut weight_sums = WeightSums::default();
        for node in self.document.nodes() {
            let Some(mesh) = node.mesh().filter(|_| node.skin().is_none()) else { continue };
            let mut above = parents[node.index()];
            while let Some(n) = above.filter(|n| !joint_of_node.contains_key(n)) {
                above = parents[n];
            }
            let Some(anchor) = above else { continue };
            if wanted.is_some_and(|names| !names.iter().any(|w| names_mesh(w, &mesh, &node))) {
                continue;
            }
            if !seen.insert(mesh.index()) {
                continue;
            }
            let joint = joint_of_node[&anchor];
            // bind = B_j⁻¹ · W_anchor⁻¹ · W_node · local: where the joint's skinning
            // matrix W_anchor · B_j takes it back to W_node · local in the rest pose.
            let inverse = |m: desal_mesh::math::Mat4, what: &str| {
                m.try_inverse().ok_or_else(|| RigError::Node {
                    path: self.path.clone(),
                    node: node.index(),
                    label: crate::pose::node_label(rig, node.index()),
                    reason: format!(
                        "carries mesh '{}' below {what}, which is singular in the rest pose",
                        mesh_name(&mesh)
                    ),
                })
            };
            let to_bind = inverse(rig.skin.inverse_bind_matrix(joint), "a joint whose inverse bind matrix")?
                * inverse(world[anchor], &format!("joint node {anchor}"))?
                * world[node.index()];
            let mut part = self.read_mesh(&mesh, Skinning::Rigid(joint as u16), &mut weight_sums)?;
            for p in &mut part.positions {
                let q = crate::pose::transform_point(
                    &to_bind,
                    &desal_mesh::Vec3::new(p[0].into(), p[1].into(), p[2].into()),
                );
                *p = [q.x as f32, q.y as f32, q.z as f32];
            }
            if let Some(normals) = &mut part.normals {
                let linear = to_bind.fixed_view::<3, 3>(0, 0).into_owned();
                let normal_matrix = linear.try_inverse().map(|m| m.transpose()).unwrap_or(linear);
                for n in normals.iter_mut() {
                    let v = (normal_matrix * desal_mesh::Vec3::new(n[0].into(), n[1].into(), n[2].into()))
                        .normalize();
                    if v.iter().all(|x| x.is_finite()) {
                        *n = [v.x as f32, v.y as f32, v.z as f32];
                    }
                }
            }
            let name = mesh_name(&mesh);
            let (vertices, triangles) = append_mesh(&mut rig.mesh, part, false);
            rig.meshes.push(MeshPart {
                node: node.index(),
                mesh: mesh.index(),
                name,
                skin: None,
                joints: vec![joint as u16],
                to_bind: Some(to_bind),
                vertices,
                triangles,
            });
        }
        Ok(())
    }

    /// The skinned meshes to simplify, each with the first node that carries it and its
    /// skin, in node order: every one (a mesh carried by several nodes once), or those
    /// [`ReadOptions::mesh`] names by mesh name, node name or mesh index. A name that
    /// names neither a skinned mesh nor a mesh below a bone is refused, listing them.
    fn pick_skinned_meshes(
        &self,
        options: &ReadOptions,
    ) -> Result<Vec<(usize, gltf::Mesh<'_>, gltf::Skin<'_>)>, RigError> {
        let mut skinned: Vec<(gltf::Node, gltf::Mesh, gltf::Skin)> =
            self.document.nodes().filter_map(|n| Some((n.clone(), n.mesh()?, n.skin()?))).collect();
        if skinned.is_empty() {
            return Err(RigError::NoSkin { path: self.path.clone() });
        }
        let label = |(n, m, _): &(gltf::Node, gltf::Mesh, gltf::Skin)| {
            format!("'{}' (node '{}')", mesh_name(m), n.name().unwrap_or("unnamed"))
        };
        if let Some(wanted) = &options.mesh {
            let rigid = self.meshes_below_bones();
            let mut names = skinned.iter().map(label).collect::<Vec<_>>();
            names.extend(rigid.iter().map(|(n, m)| {
                format!("'{}' (node '{}', below a bone)", mesh_name(m), n.name().unwrap_or("unnamed"))
            }));
            let known = |w: &str| {
                skinned.iter().any(|(n, m, _)| names_mesh(w, m, n))
                    || rigid.iter().any(|(n, m)| names_mesh(w, m, n))
            };
            if let Some(unknown) = wanted.iter().find(|w| !known(w)) {
                return Err(RigError::NoSuchMesh {
                    path: self.path.clone(),
                    wanted: unknown.clone(),
                    names: names.join(", "),
                });
            }
            skinned.retain(|(n, m, _)| wanted.iter().any(|w| names_mesh(w, m, n)));
            if skinned.is_empty() {
                return Err(RigError::NoSuchMesh {
                    path: self.path.clone(),
                    wanted: format!(
                        "{} (below a bone only: list a skinned mesh too, whose skin they follow)",
                        wanted.join("', '")
                    ),
                    names: names.join(", "),
                });
            }
        }
        let mut seen = std::collections::BTreeSet::new();
        skinned.retain(|(_, m, _)| seen.insert(m.index()));
        Ok(skinned.into_iter().map(|(n, m, s)| (n.index(), m, s)).collect())
    }

    /// Every mesh carried by a node without a skin that has a skin's joint above it,
    /// with that node: the candidates of [`Self::add_rigid_meshes`].
    fn meshes_below_bones(&self) -> Vec<(gltf::Node<'_>, gltf::Mesh<'_>)> {
        let joints: std::collections::BTreeSet<usize> =
            self.document.skins().flat_map(|s| s.joints().map(|j| j.index()).collect::<Vec<_>>()).collect();
        let mut parent = vec![None; self.document.nodes().len()];
        for node in self.document.nodes() {
            for child in node.children() {
                parent[child.index()] = Some(node.index());
            }
        }
        self.document
            .nodes()
            .filter(|n| n.skin().is_none())
            .filter_map(|n| Some((n.clone(), n.mesh()?)))
            .filter(|(n, _)| {
                // `check_tree` has refused cycles by the time a rigid mesh is added, but
                // this runs before: a walk is bounded by the node count.
                let mut above = parent[n.index()];
                for _ in 0..parent.len() {
                    match above {
                        Some(a) if joints.contains(&a) => return true,
                        Some(a) => above = parent[a],
                        None => return false,
                    }
                }
                false
            })
            .collect()
    }

    fn read_skin(&self, skin: &gltf::Skin<'_>, nodes: &[Node]) -> Result<Skin, RigError> {
        let name = skin.name().map(str::to_owned);
        let joints: Vec<usize> = skin.joints().map(|n| n.index()).collect();
        let label = name.clone().unwrap_or_else(|| format!("skin {}", skin.index()));
        let skin_error =
            |reason: String| RigError::Skin { path: self.path.clone(), skin: label.clone(), reason };
        if joints.is_empty() || joints.len() > usize::from(u16::MAX) {
            return Err(skin_error(format!("has {} joints; a skin needs 1 to 65535", joints.len())));
        }
        let inverse_bind: Vec<[f32; 16]> = match skin.inverse_bind_matrices() {
            None => vec![identity_matrix(); joints.len()],
            Some(accessor) => {
                let used_by = format!("skin '{label}'");
                let values = self.accessors.floats(&accessor, Semantic::InverseBindMatrices, &used_by)?;
                values.chunks_exact(16).map(|m| m.try_into().expect("16 values")).collect()
            }
        };
        if inverse_bind.len() != joints.len() {
            return Err(skin_error(format!(
                "has {} joints but {} inverse bind matrices",
                joints.len(),
                inverse_bind.len()
            )));
        }
        let joint_label = |j: usize| {
            let n = joints[j];
            match &nodes[n].name {
                Some(node) => format!("joint {j} (node {n} '{node}')"),
                None => format!("joint {j} (node {n})"),
            }
        };
        for (j, m) in inverse_bind.iter().enumerate() {
            if !m.iter().all(|x| x.is_finite()) {
                return Err(skin_error(format!(
                    "the inverse bind matrix of {} is not finite",
                    joint_label(j)
                )));
            }
            if crate::pose::is_singular(&nalgebra::Matrix4::from_column_slice(&m.map(f64::from))) {
                return Err(skin_error(format!(
                    "the inverse bind matrix of {} is singular ({m:?}); it must invert the joint's bind \
                     transform, which a singular matrix cannot",
                    joint_label(j)
                )));
            }
        }
        Ok(Skin { name, joints, inverse_bind, skeleton: skin.skeleton().map(|n| n.index()) })
    }

    fn read_mesh(
        &self,
        mesh: &gltf::Mesh<'_>,
        skinning: Skinning<'_>,
        weight_sums: &mut WeightSums,
    ) -> Result<SkinnedMesh, RigError> {
        let name = mesh_name(mesh);
        let mut out = SkinnedMesh {
            name: name.clone(),
            positions: Vec::new(),
            normals: Some(Vec::new()),
            uvs: Some(Vec::new()),
            influences: Influences::new(),
            triangles: Vec::new(),
            primitives: Vec::new(),
            sources: Vec::new(),
        };
        for primitive in mesh.primitives() {
            let p = primitive.index();
            let bad = |reason: &str| RigError::Primitive {
                path: self.path.clone(),
                mesh: name.clone(),
                primitive: p,
                reason: reason.to_owned(),
            };
            if primitive.mode() != gltf::mesh::Mode::Triangles {
                return Err(bad(&format!("mode {:?}: only triangle lists are supported", primitive.mode())));
            }
            let used_by = format!("mesh '{name}' primitive {p}");
            let floats = |accessor: &gltf::Accessor<'_>, semantic: Semantic| {
                self.accessors.floats(accessor, semantic, &used_by)
            };
            let position = primitive.get(&gltf::Semantic::Positions).ok_or_else(|| bad("has no POSITION"))?;
            let positions: Vec<[f32; 3]> = triples(floats(&position, Semantic::Position)?);
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
            match (primitive.get(&gltf::Semantic::Normals), &mut out.normals) {
                (Some(n), Some(all)) => all.extend(triples(floats(&n, Semantic::Normal)?)),
                _ => out.normals = None,
            }
            match (primitive.get(&gltf::Semantic::TexCoords(0)), &mut out.uvs) {
                (Some(t), Some(all)) => {
                    all.extend(floats(&t, Semantic::TexCoord(0))?.chunks_exact(2).map(|c| [c[0], c[1]]));
                }
                _ => out.uvs = None,
            }
            match skinning {
                Skinning::Rigid(joint) => {
                    for _ in 0..count {
                        out.influences.push_row([(joint, 1.0)]);
                    }
                }
                Skinning::Skin(skin) => {
                    let mut joints: Vec<Vec<[u16; 4]>> = Vec::new();
                    let mut weights: Vec<Vec<[f32; 4]>> = Vec::new();
                    for set in 0.. {
                        match (
                            primitive.get(&gltf::Semantic::Joints(set)),
                            primitive.get(&gltf::Semantic::Weights(set)),
                        ) {
                            (Some(j), Some(w)) => {
                                let j = self.accessors.integers(&j, Semantic::Joints(set), &used_by)?;
                                // JOINTS_n are u8 or u16 (checked), so every value fits.
                                joints.push(
                                    j.chunks_exact(4)
                                        .map(|c| [c[0], c[1], c[2], c[3]].map(|x| x as u16))
                                        .collect(),
                                );
                                let w = floats(&w, Semantic::Weights(set))?;
                                weights.push(
                                    w.chunks_exact(4).map(|c| c.try_into().expect("4 values")).collect(),
                                );
                            }
                            (None, None) => break,
                            _ => {
                                return Err(bad(&format!(
                                    "JOINTS_{set} and WEIGHTS_{set} must come together"
                                )));
                            }
                        }
                        if joints.last().map(Vec::len) != Some(count)
                            || weights.last().map(Vec::len) != Some(count)
                        {
                            return Err(bad(&format!(
                                "JOINTS_{set}/WEIGHTS_{set} do not have one entry per vertex"
                            )));
                        }
                    }
                    if joints.is_empty() {
                        return Err(bad("has no JOINTS_0/WEIGHTS_0: the mesh is not skinned"));
                    }
                    weight_sums.add(self.read_influences(
                        &joints,
                        &weights,
                        base,
                        &name,
                        skin,
                        &mut out.influences,
                    )?);
                }
            }
            let indices: Vec<u32> = match primitive.indices() {
                Some(i) => self.accessors.integers(&i, Semantic::Indices, &used_by)?,
                None => (0..count as u32).collect(),
            };
            if !indices.len().is_multiple_of(3) {
                return Err(bad(&format!("{} indices is not a whole number of triangles", indices.len())));
            }
            if let Some(i) = indices.iter().find(|&&i| i as usize >= count) {
                return Err(bad(&format!("index {i} is out of range: the primitive has {count} vertices")));
            }
            self.check_carried(&primitive, count, &used_by, &bad)?;
            let first_triangle = out.triangles.len() as u32;
            out.triangles.extend(indices.chunks(3).map(|t| [t[0], t[1], t[2]].map(|i| i + base as u32)));
            out.primitives.push(PrimitiveSpan {
                mesh: mesh.index(),
                primitive: p,
                vertices: base as u32..(base + count) as u32,
                triangles: first_triangle..out.triangles.len() as u32,
            });
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
    /// Checks every attribute and morph target delta of `primitive` that the simplified
    /// rig carries ([`crate::edit`]): one element per vertex (`count`), each accessor's
    /// layout (sparse ones included) within its buffer, so that writing cannot fail on
    /// them. The attributes desal reads itself were checked as they were read.
    fn check_carried(
        &self,
        primitive: &gltf::Primitive<'_>,
        count: usize,
        used_by: &str,
        bad: &dyn Fn(&str) -> RigError,
    ) -> Result<(), RigError> {
        use gltf::Semantic as S;
        let read_by_desal =
            |s: &S| matches!(s, S::Positions | S::Normals | S::TexCoords(0) | S::Joints(_) | S::Weights(_));
        let targets = primitive.morph_targets().enumerate().flat_map(|(t, target)| {
            [("POSITION", target.positions()), ("NORMAL", target.normals()), ("TANGENT", target.tangents())]
                .into_iter()
                .filter_map(move |(name, a)| Some((format!("morph target {t} {name}"), a?)))
        });
        let attributes =
            primitive.attributes().map(|(semantic, a)| (read_by_desal(&semantic), semantic.to_string(), a));
        for (read, what, accessor) in attributes.chain(targets.map(|(what, a)| (false, what, a))) {
            if accessor.count() != count {
                return Err(bad(&format!(
                    "{what} has {} elements but POSITION has {count}",
                    accessor.count()
                )));
            }
            if !read {
                self.accessors.check(&accessor, Semantic::Carried, &format!("{used_by} {what}"))?;
            }
        }
        Ok(())
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
    ) -> Result<WeightSums, RigError> {
        let mut sums = WeightSums::default();
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
            if sum == 0.0 {
                return Err(RigError::NoWeight {
                    path: self.path.clone(),
                    mesh: mesh.to_owned(),
                    vertex: base + v,
                });
            }
            let off = (sum - 1.0).abs();
            if off > WEIGHT_SUM_TOLERANCE {
                for (_, w) in &mut row {
                    *w = (f64::from(*w) / sum) as f32;
                }
                sums.renormalised += 1;
                sums.off_by_more_than_2pct += usize::from(off > WEIGHT_SUM_REPORTED);
                if sums.worst.is_none_or(|(_, worst)| off > (worst - 1.0).abs()) {
                    sums.worst = Some((base + v, sum));
                }
            }
            out.push_row(row);
        }
        Ok(sums)
    }

    /// A node, its transform finite and its rotation of non-zero length (a zero scale
    /// is valid glTF and kept; [`crate::sample_frames`] refuses it where it crushes
    /// skinned vertices).
    fn read_node(&self, node: &gltf::Node<'_>) -> Result<Node, RigError> {
        let name = node.name().map(str::to_owned);
        let bad = |reason: String| RigError::Node {
            path: self.path.clone(),
            node: node.index(),
            label: match &name {
                Some(name) => format!("node {} '{name}'", node.index()),
                None => format!("node {}", node.index()),
            },
            reason,
        };
        let transform = match node.transform() {
            gltf::scene::Transform::Matrix { matrix } => LocalTransform::Matrix(flatten_matrix(matrix)),
            gltf::scene::Transform::Decomposed { translation, rotation, scale } => {
                LocalTransform::Trs { translation, rotation, scale }
            }
        };
        match &transform {
            LocalTransform::Matrix(m) if !m.iter().all(|x| x.is_finite()) => {
                return Err(bad(format!("matrix {m:?} is not finite")));
            }
            LocalTransform::Trs { translation, rotation, scale } => {
                for (what, values) in
                    [("translation", &translation[..]), ("rotation", rotation), ("scale", scale)]
                {
                    if !values.iter().all(|x| x.is_finite()) {
                        return Err(bad(format!("{what} {values:?} is not finite")));
                    }
                }
                if let Some(reason) = rotation_fault(rotation) {
                    return Err(bad(reason));
                }
            }
            LocalTransform::Matrix(_) => {}
        }
        Ok(Node { name, children: node.children().map(|c| c.index()).collect(), transform })
    }

    /// Refuses a file whose channels together would decode more than
    /// [`MAX_KEYFRAME_VALUES`] values, before any is decoded.
    fn check_keyframe_total(&self) -> Result<(), RigError> {
        let values = |a: gltf::Accessor<'_>| a.count() as u64 * a.dimensions().multiplicity() as u64;
        let total: u64 = self
            .document
            .animations()
            .flat_map(|a| a.channels())
            .map(|c| values(c.sampler().input()).saturating_add(values(c.sampler().output())))
            .fold(0u64, u64::saturating_add);
        if total > MAX_KEYFRAME_VALUES {
            return Err(RigError::Structure {
                path: self.path.clone(),
                element: "animations".into(),
                reason: format!(
                    "their channels hold {total} keyframe values together, more than desal's limit of \
                     {MAX_KEYFRAME_VALUES} (desal_rig::read::MAX_KEYFRAME_VALUES)"
                ),
            });
        }
        Ok(())
    }

    fn read_animation(&self, animation: &gltf::Animation<'_>) -> Result<Animation, RigError> {
        let name = animation.name().map(str::to_owned);
        let label = name.clone().unwrap_or_else(|| format!("animation {}", animation.index()));
        let mut channels = Vec::new();
        for (c, channel) in animation.channels().enumerate() {
            let bad = |reason: &str| RigError::Animation {
                path: self.path.clone(),
                animation: label.clone(),
                channel: c,
                reason: reason.to_owned(),
            };
            let used_by = format!("animation '{label}' channel {c}");
            let sampler = channel.sampler();
            let times = self.accessors.floats(&sampler.input(), Semantic::AnimationInput, &used_by)?;
            let (path, semantic) = match channel.target().property() {
                gltf::animation::Property::Translation => (ChannelPath::Translation, Semantic::Translation),
                gltf::animation::Property::Rotation => (ChannelPath::Rotation, Semantic::Rotation),
                gltf::animation::Property::Scale => (ChannelPath::Scale, Semantic::Scale),
                // Morph target weights: carried unchanged with the animation (desal poses by skinning only).
                gltf::animation::Property::MorphTargetWeights => {
                    self.accessors.check(&sampler.output(), Semantic::MorphWeights, &used_by)?;
                    continue;
                }
            };
            let values = self.accessors.floats(&sampler.output(), semantic, &used_by)?;
            let interpolation = match sampler.interpolation() {
                gltf::animation::Interpolation::Step => Interpolation::Step,
                gltf::animation::Interpolation::Linear => Interpolation::Linear,
                gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
            };
            let channel =
                Channel { node: channel.target().node().index(), path, interpolation, times, values };
            let cubic = interpolation == Interpolation::CubicSpline;
            let width = channel.width();
            let per_key = width * if cubic { 3 } else { 1 };
            if channel.times.is_empty() || channel.values.len() != channel.times.len() * per_key {
                return Err(bad("needs one output value per keyframe time"));
            }
            if !channel.times.windows(2).all(|w| w[0] < w[1]) || !channel.times.iter().all(|t| t.is_finite())
            {
                return Err(bad("keyframe times must be finite and strictly increasing"));
            }
            if let Some(i) = channel.values.iter().position(|x| !x.is_finite()) {
                return Err(bad(&format!("keyframe {} has a value that is not finite", i / per_key)));
            }
            if path == ChannelPath::Rotation {
                // The values, not CUBICSPLINE's tangents (which may well be zero).
                let value =
                    |k: usize| &channel.values[k * per_key + if cubic { width } else { 0 }..][..width];
                for k in 0..channel.times.len() {
                    if let Some(reason) = rotation_fault(value(k)) {
                        return Err(bad(&format!("keyframe {k}: {reason}")));
                    }
                }
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

/// Why a rotation quaternion cannot be used, if it cannot: shorter than
/// [`MIN_ROTATION_LENGTH`].
fn rotation_fault(q: &[f32]) -> Option<String> {
    let length = q.iter().map(|&x| f64::from(x).powi(2)).sum::<f64>().sqrt();
    (length < MIN_ROTATION_LENGTH).then(|| {
        format!("rotation {q:?} has length {length}; glTF requires a unit quaternion (e.g. [0, 0, 0, 1])")
    })
}

/// Every node has at most one parent and the graph has no cycle.
fn check_tree(path: &Path, rig: &Rig) -> Result<(), RigError> {
    let node_error = |node: usize, reason: &str| RigError::Node {
        path: path.to_owned(),
        node,
        label: crate::pose::node_label(rig, node),
        reason: reason.to_owned(),
    };
    let mut parent_count = vec![0usize; rig.nodes.len()];
    for node in &rig.nodes {
        for &c in &node.children {
            parent_count[c] += 1;
        }
    }
    if let Some(n) = parent_count.iter().position(|&c| c > 1) {
        return Err(node_error(n, "has more than one parent"));
    }
    // Each node's chain of parents must end at a root: walked once per node in index
    // order (linear time however deep the tree), each walk stopping at a node already
    // known to end; meeting a node of the walk itself again is a cycle.
    #[derive(Clone, Copy, PartialEq)]
    enum Seen {
        No,
        OnThisWalk,
        EndsAtRoot,
    }
    let parents = rig.parents();
    let mut seen = vec![Seen::No; rig.nodes.len()];
    let mut walk = Vec::new();
    for start in 0..rig.nodes.len() {
        let mut current = Some(start);
        while let Some(n) = current {
            match seen[n] {
                Seen::EndsAtRoot => break,
                Seen::OnThisWalk => return Err(node_error(start, "lies on a cycle")),
                Seen::No => {
                    seen[n] = Seen::OnThisWalk;
                    walk.push(n);
                    current = parents[n];
                }
            }
        }
        for n in walk.drain(..) {
            seen[n] = Seen::EndsAtRoot;
        }
    }
    Ok(())
}

/// How a mesh's vertices follow the skeleton.
#[derive(Clone, Copy)]
enum Skinning<'s> {
    /// By its skin's `JOINTS_n`/`WEIGHTS_n`.
    Skin(&'s Skin),
    /// Rigidly with this joint of the rig (a mesh below a bone, with no skin).
    Rigid(u16),
}

/// Merges `own` (a skin of one mesh) into the rig's one skin, which `own` starts when
/// there is none; returns the rig joint of each of `own`'s joints.
fn merge_skin(skin: &mut Option<Skin>, own: &Skin) -> Vec<u16> {
    let Some(skin) = skin else {
        *skin = Some(own.clone());
        return (0..own.joints.len() as u16).collect();
    };
    let key = |node: usize, m: &[f32; 16]| (node, m.map(f32::to_bits));
    let mut index: std::collections::HashMap<_, u16> = std::collections::HashMap::new();
    for (j, (&node, m)) in skin.joints.iter().zip(&skin.inverse_bind).enumerate() {
        index.entry(key(node, m)).or_insert(j as u16);
    }
    own.joints
        .iter()
        .zip(&own.inverse_bind)
        .map(|(&node, m)| {
            *index.entry(key(node, m)).or_insert_with(|| {
                skin.joints.push(node);
                skin.inverse_bind.push(*m);
                (skin.joints.len() - 1) as u16
            })
        })
        .collect()
}

/// Appends `part` (one mesh, its joints already the rig's) to `all`, which holds it
/// already when `first`; returns its vertex and triangle ranges in `all`.
fn append_mesh(
    all: &mut SkinnedMesh,
    part: SkinnedMesh,
    first: bool,
) -> (std::ops::Range<u32>, std::ops::Range<u32>) {
    if first {
        all.primitives = part.primitives;
        return (0..all.vertex_count() as u32, 0..all.triangles.len() as u32);
    }
    let (base, first_triangle) = (all.vertex_count() as u32, all.triangles.len() as u32);
    all.name = format!("{}+{}", all.name, part.name);
    all.positions.extend(&part.positions);
    // An attribute is kept only when every mesh has it.
    match (&mut all.normals, part.normals) {
        (Some(a), Some(b)) => a.extend(b),
        (normals, _) => *normals = None,
    }
    match (&mut all.uvs, part.uvs) {
        (Some(a), Some(b)) => a.extend(b),
        (uvs, _) => *uvs = None,
    }
    for v in 0..part.positions.len() {
        all.influences.push_row(part.influences.of(v).map(|(j, w)| (j as u16, w)));
    }
    all.triangles.extend(part.triangles.iter().map(|t| t.map(|i| i + base)));
    all.primitives.extend(part.primitives.into_iter().map(|p| PrimitiveSpan {
        vertices: p.vertices.start + base..p.vertices.end + base,
        triangles: p.triangles.start + first_triangle..p.triangles.end + first_triangle,
        ..p
    }));
    (base..all.vertex_count() as u32, first_triangle..all.triangles.len() as u32)
}

/// Flat `[x, y, z, x, y, z, ...]` values as triples.
fn triples(values: Vec<f32>) -> Vec<[f32; 3]> {
    values.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
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

/// The bytes of every buffer: the GLB's binary chunk, a base64 `data:` URI, or a
/// regular file inside `path`'s folder (percent-decoded, symlinks resolved; anything
/// else refused by [`desal_io::confine::read_inside`]).
fn load_buffers(path: &Path, document: &Document, blob: Option<&[u8]>) -> Result<Vec<Vec<u8>>, RigError> {
    // The declared lengths first, so that a file naming one buffer file thousands of
    // times is refused before any of them is read.
    let mut declared = 0u64;
    for buffer in document.buffers() {
        declared = declared.saturating_add(buffer.length() as u64);
        if declared > MAX_BUFFER_BYTES {
            return Err(RigError::Buffer {
                path: path.to_owned(),
                buffer: buffer.index(),
                reason: format!(
                    "the buffers up to this one declare {declared} bytes together, more than desal's limit \
                     of {MAX_BUFFER_BYTES} (desal_rig::read::MAX_BUFFER_BYTES)"
                ),
            });
        }
    }
    let mut out = Vec::new();
    let mut total = 0u64;
    for buffer in document.buffers() {
        let bad = |reason: String| RigError::Buffer { path: path.to_owned(), buffer: buffer.index(), reason };
        let room = MAX_BUFFER_BYTES.saturating_sub(total);
        let too_many = || {
            bad(format!(
                "the file's buffers hold more than {MAX_BUFFER_BYTES} bytes together, desal's limit \
                 (desal_rig::read::MAX_BUFFER_BYTES)"
            ))
        };
        if buffer.length() as u64 > room {
            return Err(too_many());
        }
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => {
                let blob =
                    blob.ok_or_else(|| bad("refers to the GLB binary chunk, which is missing".into()))?;
                if blob.len() as u64 > room {
                    return Err(too_many());
                }
                blob.to_vec()
            }
            gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                let (_, encoded) =
                    uri.split_once(";base64,").ok_or_else(|| bad("data URI is not base64".into()))?;
                decode_base64(encoded).ok_or_else(|| bad("data URI is not valid base64".into()))?
            }
            // A regular file inside the glTF's own folder, or nothing (desal_io's one rule
            // for paths found inside data).
            gltf::buffer::Source::Uri(uri) => {
                desal_io::confine::read_inside(path, &format!("buffer {}", buffer.index()), uri, room)?
            }
        };
        total += data.len() as u64;
        if total > MAX_BUFFER_BYTES {
            return Err(too_many());
        }
        if data.len() < buffer.length() {
            return Err(bad(format!("declares {} bytes but holds {}", buffer.length(), data.len())));
        }
        out.push(data);
    }
    Ok(out)
}

/// Standard base64 (RFC 4648), padded or not and with any trailing bits, as engines read
/// `data:` URIs; `None` on any other byte.
fn decode_base64(text: &str) -> Option<Vec<u8>> {
    use base64::Engine;
    use base64::engine::{DecodePaddingMode, GeneralPurpose, GeneralPurposeConfig};
    const LENIENT: GeneralPurpose = GeneralPurpose::new(
        &base64::alphabet::STANDARD,
        GeneralPurposeConfig::new()
            .with_decode_padding_mode(DecodePaddingMode::Indifferent)
            .with_decode_allow_trailing_bits(true),
    );
    LENIENT.decode(text).ok()
}

/// True when `wanted` (an entry of [`ReadOptions::mesh`]) names `mesh` carried by `node`:
/// its mesh name, its node's name, or its mesh index written in decimal.
fn names_mesh(wanted: &str, mesh: &gltf::Mesh<'_>, node: &gltf::Node<'_>) -> bool {
    mesh.name() == Some(wanted) || node.name() == Some(wanted) || wanted == mesh.index().to_string()
}

#[cfg(test)]
mod tests {
    use super::{Path, decode_base64, without_panics};

    #[test]
    fn d1_a_panic_while_reading_becomes_an_error_naming_the_file() {
        let result: Result<(), _> = without_panics(Path::new("odd.glb"), || panic!("index out of bounds"));
        let message = result.unwrap_err().to_string();
        assert!(
            message.starts_with("odd.glb: the glTF reader failed on this file (index out of bounds)"),
            "{message}"
        );
    }

    #[test]
    fn base64_decodes_padded_and_unpadded_text() {
        assert_eq!(decode_base64("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(decode_base64("aGVsbG8").unwrap(), b"hello");
        assert_eq!(decode_base64("AAECAw==").unwrap(), [0, 1, 2, 3]);
        assert!(decode_base64("a$==").is_none());
    }
}
