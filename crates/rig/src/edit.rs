//! Writing a simplified rig back *into the document it was read from* (issue 42, item 1):
//! the input's JSON, as the file holds it, with only what simplification must change
//! changed. The `gltf` crate's typed JSON drops unknown extensions and `extras`, so the
//! document is kept as a [`serde_json::Value`] and edited.
//!
//! What changes:
//! - **The simplified primitives' accessors.** Each primitive desal simplified (a
//!   [`PrimitiveSpan`] of the simplified mesh) gets new `POSITION`, `JOINTS_n`/`WEIGHTS_n`
//!   and `indices` accessors from the rig, and every other attribute it has (`NORMAL`,
//!   `TEXCOORD_n`, `COLOR_n`, `TANGENT`, application attributes) and every morph target
//!   delta copied element by element, in its own type, from the input vertex each output
//!   vertex copies ([`SkinnedMesh::sources`]). The primitive's other keys (material,
//!   mode, extensions, extras) stay.
//! - **Accessor slots.** Skins and animations name accessors by index, so no kept
//!   accessor moves: the new accessors take the slots of the accessors only the
//!   simplified primitives used, in ascending order, then go at the end. A freed slot
//!   left over (the new primitives need fewer accessors, e.g. no `JOINTS_1` once
//!   influences are capped at 4) becomes a one-element accessor of one zero (one 4-byte
//!   view shared by all such slots): valid, unused.
//! - **Buffer views and buffers.** Every buffer view is copied, in order, into one new
//!   binary chunk (4-byte aligned), and `buffers` becomes that one chunk. No kept view
//!   moves either (images, and extensions desal does not know, name views by index): the
//!   new accessors' views take the slots of views only freed accessors used, then go at
//!   the end; a freed view slot left over holds four zero bytes. Views nothing names are
//!   kept (an extension may name them).
//! - **Nothing else.** Nodes, names, scenes, skins, animations, materials, textures,
//!   samplers, images (their bytes move within the chunk, their view stays), cameras, extensions (`KHR_*`, `VRM`, `VRMC_*`), `extensionsUsed` and
//!   `extras` are the input's values. An image given by a URI keeps it: its bytes, read
//!   inside the input's folder ([`desal_io::confine::read_inside`]), come back in
//!   [`EditedGlb::images`] for the caller to write beside the output under the same
//!   relative path, so a URI that climbs (`..`) is refused.
//!
//! The output is a binary glTF (`.glb`; a `.vrm` is a `.glb` with VRM extensions, so
//! [`SourceDocument::output_extension`] keeps `.vrm`).

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};

use serde_json::{Map, Value, json};

use crate::RigError;
use crate::accessor::{Accessors, Elements, Semantic};
use crate::model::{PrimitiveSpan, Rig};

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_SHORT: u32 = 5123;
const UNSIGNED_INT: u32 = 5125;

/// A glTF document as read: its JSON as the file holds it, every buffer's bytes and the
/// `gltf` crate's view of it (through which [`crate::accessor`] reads accessors).
pub struct SourceDocument {
    /// The file, for messages and for the images its URIs name.
    pub path: PathBuf,
    pub(crate) json: Value,
    pub(crate) document: gltf::Document,
    pub(crate) buffers: Vec<Vec<u8>>,
    pub(crate) quantized: bool,
    pub(crate) real_size: usize,
}

impl std::fmt::Debug for SourceDocument {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SourceDocument").field("path", &self.path).finish_non_exhaustive()
    }
}

impl SourceDocument {
    /// The document's JSON as the file holds it.
    pub fn json(&self) -> &Value {
        &self.json
    }

    /// `"vrm"` for a VRM avatar (a `.vrm` file, which is a `.glb`), else `"glb"`.
    pub fn output_extension(&self) -> &'static str {
        let vrm = self.path.extension().is_some_and(|e| e.eq_ignore_ascii_case("vrm"));
        if vrm { "vrm" } else { "glb" }
    }

    fn accessors(&self) -> Accessors<'_> {
        Accessors {
            path: &self.path,
            buffers: &self.buffers,
            quantized: self.quantized,
            real_size: self.real_size,
        }
    }
}

/// The edited document: the `.glb` bytes and the external images it names.
#[derive(Debug, Clone, PartialEq)]
pub struct EditedGlb {
    pub bytes: Vec<u8>,
    pub images: Vec<ExternalImage>,
}

/// An image the document names by a relative URI: to be written at `path` (relative,
/// plain folder and file names only) beside the output.
#[derive(Debug, Clone, PartialEq)]
pub struct ExternalImage {
    pub path: PathBuf,
    pub bytes: Vec<u8>,
}

/// Writes `simplified` (the simplified rig of `input`, which was read from `source`) as
/// `source` edited: see the module doc for what changes. Input primitives the simplified
/// mesh has no faces for are kept as they were.
pub fn write_edited(source: &SourceDocument, input: &Rig, simplified: &Rig) -> Result<EditedGlb, RigError> {
    crate::error::without_panics(&source.path, || Editor { source, input, simplified }.write())
}

/// The extension that lists a node's lower levels of detail (Microsoft's vendor
/// extension, which Babylon.js reads).
pub const MSFT_LOD: &str = "MSFT_lod";

/// Writes the input document with every level of `levels` (simplified rigs of `input`,
/// finest first, e.g. nested levels of detail) added beside the input's own meshes, as
/// the `MSFT_lod` extension holds them: for each simplified glTF mesh and level `k`
/// (from 1), a copy of the mesh named `<name>_LOD<k>` with that level's primitives (new
/// accessors, built as [`write_edited`] builds them) and a copy of the node that carries
/// it, named `<node>_LOD<k>`, with the same skin and transform and no children, in no
/// scene; the carrying node gets `extensions.MSFT_lod.ids` (its levels' nodes, finest
/// first) and `extras.MSFT_screencoverage` (`coverage`: one value per level, the input
/// first), and the input mesh is renamed `<name>_LOD0` (the names Unity's and Unreal's
/// importers group). `MSFT_lod` joins `extensionsUsed`. Everything else is the input's;
/// no accessor or view of the input moves. A reader without `MSFT_lod` shows level 0.
pub fn write_lods(
    source: &SourceDocument,
    input: &Rig,
    levels: &[Rig],
    coverage: &[f64],
) -> Result<EditedGlb, RigError> {
    if coverage.len() != levels.len() + 1 {
        return Err(RigError::Output(format!(
            "{} screen coverages for {} levels of detail and the input",
            coverage.len(),
            levels.len()
        )));
    }
    crate::error::without_panics(&source.path, || {
        let mut json = source.json.clone();
        let mut added = Vec::new();
        let mut cache = HashMap::new();
        let mut primitives = Vec::new();
        for (k, level) in levels.iter().enumerate() {
            let editor = Editor { source, input, simplified: level };
            editor.check_sources()?;
            for span in &level.mesh.primitives {
                primitives.push((k + 1, editor.new_primitive(span, &mut added, &mut cache)?));
            }
        }
        // Nothing is replaced: the new accessors go after the input's.
        let slots = place_accessors(&mut json, &BTreeSet::new(), added.len());
        let name_of = |v: &Value, fallback: String| v["name"].as_str().map_or(fallback, str::to_owned);
        let mut copies: BTreeMap<(usize, usize), usize> = BTreeMap::new();
        for (level, p) in &primitives {
            let copy = *copies.entry((*level, p.mesh)).or_insert_with(|| {
                let mut mesh = source.json["meshes"][p.mesh].clone();
                mesh["name"] = format!("{}_LOD{level}", name_of(&mesh, format!("mesh{}", p.mesh))).into();
                let meshes = json["meshes"].as_array_mut().expect("a document with a mesh has meshes");
                meshes.push(mesh);
                meshes.len() - 1
            });
            set_primitive(&mut json["meshes"][copy]["primitives"][p.primitive], p, &slots);
        }
        for part in &input.meshes {
            let node = &source.json["nodes"][part.node];
            let node_name = name_of(node, format!("node{}", part.node));
            let mut ids = Vec::new();
            for level in 1..=levels.len() {
                let Some(&copy) = copies.get(&(level, part.mesh)) else { continue };
                let mut lod = Map::new();
                lod.insert("name".into(), format!("{node_name}_LOD{level}").into());
                lod.insert("mesh".into(), copy.into());
                // Outside the scene's tree, a level stands where its node does.
                for key in ["skin", "matrix", "translation", "rotation", "scale", "weights"] {
                    if let Some(v) = node.get(key) {
                        lod.insert(key.into(), v.clone());
                    }
                }
                let nodes = json["nodes"].as_array_mut().expect("a mesh's node is in nodes");
                nodes.push(Value::Object(lod));
                ids.push(nodes.len() - 1);
            }
            if ids.is_empty() {
                continue;
            }
            let mesh_name = name_of(&source.json["meshes"][part.mesh], format!("mesh{}", part.mesh));
            json["meshes"][part.mesh]["name"] = format!("{mesh_name}_LOD0").into();
            let node = json["nodes"][part.node].as_object_mut().expect("a node is an object");
            let extensions = node.entry("extensions").or_insert_with(|| json!({}));
            extensions[MSFT_LOD] = json!({ "ids": ids });
            let extras = node.entry("extras").or_insert_with(|| json!({}));
            if extras.is_object() {
                extras["MSFT_screencoverage"] = json!(coverage);
            }
        }
        let used = json.as_object_mut().expect("a glTF document is an object").entry("extensionsUsed");
        let used = used.or_insert_with(|| json!([]));
        if let Some(list) = used.as_array_mut()
            && !list.iter().any(|e| e == MSFT_LOD)
        {
            list.push(MSFT_LOD.into());
        }
        let editor = Editor { source, input, simplified: input };
        let bin = editor.rebuild_buffers(&mut json, &BTreeSet::new(), added, &slots)?;
        editor.finish(json, bin)
    })
}

/// Points `primitive` (its JSON in the output) at the new accessors of `p`: its
/// attributes (the input's `JOINTS_n`/`WEIGHTS_n` dropped first, as the new ones may be
/// fewer), indices and morph targets.
fn set_primitive(primitive: &mut Value, p: &NewPrimitive, slots: &[usize]) {
    let attributes = primitive["attributes"].as_object_mut().expect("read as an object");
    attributes.retain(|name, _| !name.starts_with("JOINTS_") && !name.starts_with("WEIGHTS_"));
    for (name, &a) in &p.attributes {
        attributes.insert(name.clone(), slots[a].into());
    }
    primitive["indices"] = slots[p.indices].into();
    if !p.targets.is_empty() {
        let targets: Vec<Value> = p
            .targets
            .iter()
            .map(|t| Value::Object(t.iter().map(|(n, &a)| (n.clone(), slots[a].into())).collect()))
            .collect();
        primitive["targets"] = targets.into();
    }
}

/// One accessor to add: its JSON without `bufferView`, its packed bytes, its view target.
struct NewAccessor {
    json: Map<String, Value>,
    bytes: Vec<u8>,
    /// Element size in bytes (packed).
    element: usize,
    target: Option<u32>,
}

/// The edited primitive: new accessors for its `attributes`, `indices` and `targets`
/// (numbers into the list of new accessors).
struct NewPrimitive {
    mesh: usize,
    primitive: usize,
    attributes: BTreeMap<String, usize>,
    indices: usize,
    targets: Vec<BTreeMap<String, usize>>,
}

struct Editor<'a> {
    source: &'a SourceDocument,
    input: &'a Rig,
    simplified: &'a Rig,
}

impl Editor<'_> {
    /// Refuses a simplified mesh that does not say where its vertices come from.
    fn check_sources(&self) -> Result<(), RigError> {
        let out = &self.simplified.mesh;
        if out.sources.len() != out.vertex_count() || out.primitives.is_empty() {
            return Err(RigError::Output(
                "the simplified mesh does not say which input vertices and primitives it comes from".into(),
            ));
        }
        Ok(())
    }

    fn write(&self) -> Result<EditedGlb, RigError> {
        self.check_sources()?;
        let out = &self.simplified.mesh;
        let mut json = self.source.json.clone();
        let mut added = Vec::new();
        let mut primitives = Vec::new();
        let mut cache = HashMap::new();
        for span in &out.primitives {
            primitives.push(self.new_primitive(span, &mut added, &mut cache)?);
        }
        let replaced: BTreeSet<(usize, usize)> = primitives.iter().map(|p| (p.mesh, p.primitive)).collect();
        let freed = freed_accessors(&json, &replaced);
        let slots = place_accessors(&mut json, &freed, added.len());
        for p in &primitives {
            set_primitive(&mut json["meshes"][p.mesh]["primitives"][p.primitive], p, &slots);
        }
        let bin = self.rebuild_buffers(&mut json, &freed, added, &slots)?;
        self.finish(json, bin)
    }

    /// The `.glb` of the edited `json` and binary chunk, and the images it names.
    fn finish(&self, json: Value, bin: Vec<u8>) -> Result<EditedGlb, RigError> {
        let images = self.external_images(&json)?;
        let json_bytes = serde_json::to_vec(&json).map_err(|e| RigError::Output(format!("JSON: {e}")))?;
        let glb = gltf::binary::Glb {
            header: gltf::binary::Header { magic: *b"glTF", version: 2, length: 0 },
            json: json_bytes.into(),
            bin: Some(bin.into()),
        };
        let bytes = glb.to_vec().map_err(|e| RigError::Output(format!("GLB container: {e}")))?;
        Ok(EditedGlb { bytes, images })
    }

    /// The new accessors of one simplified primitive, appended to `added`.
    fn new_primitive(
        &self,
        span: &PrimitiveSpan,
        added: &mut Vec<NewAccessor>,
        cache: &mut HashMap<usize, Elements>,
    ) -> Result<NewPrimitive, RigError> {
        let out = &self.simplified.mesh;
        let vertices = span.vertices.start as usize..span.vertices.end as usize;
        let original = &self.source.json["meshes"][span.mesh]["primitives"][span.primitive];
        let used_by = |what: &str| format!("mesh {} primitive {} {what}", span.mesh, span.primitive);
        let mut attributes = BTreeMap::new();
        let push = |added: &mut Vec<NewAccessor>, a: NewAccessor| {
            added.push(a);
            added.len() - 1
        };
        let part = self.input.meshes.iter().find(|m| m.mesh == span.mesh);
        // A rigid mesh (below a bone, no skin) stays rigid: its own positions, no weights.
        let rigid = part.and_then(|p| p.to_bind);
        let names = original["attributes"].as_object().map(|m| m.keys().cloned().collect::<Vec<_>>());
        for name in names.unwrap_or_default() {
            if rigid.is_none() && (name.starts_with("JOINTS_") || name.starts_with("WEIGHTS_")) {
                continue;
            }
            let accessor = match (name.as_str(), rigid) {
                ("POSITION", None) => positions(&out.positions[vertices.clone()]),
                ("POSITION", Some(to_bind)) => {
                    self.rigid_positions(span, &to_bind, cache, &used_by(&name))?
                }
                _ => self.carried(span, &["attributes", &name], cache, &used_by(&name))?,
            };
            attributes.insert(name, push(added, accessor));
        }
        if rigid.is_some() {
            return self.finish_primitive(span, attributes, added, cache);
        }
        // JOINTS_n name the joints of the mesh's own skin, not the rig's merged one.
        let mut local_joint = HashMap::new();
        for (local, &joint) in part.map(|p| p.joints.as_slice()).unwrap_or_default().iter().enumerate() {
            local_joint.entry(joint).or_insert(local as u16);
        }
        let to_local = |joint: usize| -> Result<u16, RigError> {
            match part {
                None => Ok(joint as u16),
                Some(p) => local_joint.get(&(joint as u16)).copied().ok_or_else(|| {
                    RigError::Output(format!(
                        "mesh '{}' is weighted to joint {joint}, which its skin lacks",
                        p.name
                    ))
                }),
            }
        };
        let influences = &out.influences;
        let widest = vertices.clone().map(|v| influences.of(v).count()).max().unwrap_or(0);
        for set in 0..widest.div_ceil(4).max(1) {
            let mut joints = Vec::with_capacity(8 * vertices.len());
            let mut weights = Vec::with_capacity(16 * vertices.len());
            for v in vertices.clone() {
                let row: Vec<(usize, f32)> = influences.of(v).skip(4 * set).take(4).collect();
                for slot in 0..4 {
                    let (j, w) = match row.get(slot) {
                        Some(&(j, w)) => (to_local(j)?, w),
                        None => (0, 0.0),
                    };
                    joints.extend(j.to_le_bytes());
                    weights.extend(w.to_le_bytes());
                }
            }
            let count = vertices.len();
            let j = packed(joints, count, UNSIGNED_SHORT, "VEC4", 8, Some(ARRAY_BUFFER));
            let w = packed(weights, count, FLOAT, "VEC4", 16, Some(ARRAY_BUFFER));
            attributes.insert(format!("JOINTS_{set}"), push(added, j));
            attributes.insert(format!("WEIGHTS_{set}"), push(added, w));
        }
        self.finish_primitive(span, attributes, added, cache)
    }

    /// The rest of a new primitive: its indices and morph targets.
    fn finish_primitive(
        &self,
        span: &PrimitiveSpan,
        attributes: BTreeMap<String, usize>,
        added: &mut Vec<NewAccessor>,
        cache: &mut HashMap<usize, Elements>,
    ) -> Result<NewPrimitive, RigError> {
        let out = &self.simplified.mesh;
        let original = &self.source.json["meshes"][span.mesh]["primitives"][span.primitive];
        let used_by = |what: &str| format!("mesh {} primitive {} {what}", span.mesh, span.primitive);
        let push = |added: &mut Vec<NewAccessor>, a: NewAccessor| {
            added.push(a);
            added.len() - 1
        };
        let start = span.vertices.start;
        let triangles = &out.triangles[span.triangles.start as usize..span.triangles.end as usize];
        let indices: Vec<u8> = triangles.iter().flatten().flat_map(|&i| (i - start).to_le_bytes()).collect();
        let indices =
            packed(indices, 3 * triangles.len(), UNSIGNED_INT, "SCALAR", 4, Some(ELEMENT_ARRAY_BUFFER));
        let indices = push(added, indices);
        let mut targets = Vec::new();
        let target_count = original["targets"].as_array().map_or(0, Vec::len);
        for t in 0..target_count {
            let index = t.to_string();
            let mut target = BTreeMap::new();
            let names = original["targets"][t].as_object().map(|m| m.keys().cloned().collect::<Vec<_>>());
            for name in names.unwrap_or_default() {
                let what = format!("morph target {t} {name}");
                let accessor = self.carried(span, &["targets", &index, &name], cache, &used_by(&what))?;
                target.insert(name, push(added, accessor));
            }
            targets.push(target);
        }
        Ok(NewPrimitive { mesh: span.mesh, primitive: span.primitive, attributes, indices, targets })
    }

    /// A rigid primitive's `POSITION` in its own space: the input's elements as stored
    /// when every vertex is an input vertex (subset placement), else the rig's positions
    /// taken back out of the bind space (`to_bind` inverted), as `f32`.
    fn rigid_positions(
        &self,
        span: &PrimitiveSpan,
        to_bind: &desal_mesh::math::Mat4,
        cache: &mut HashMap<usize, Elements>,
        used_by: &str,
    ) -> Result<NewAccessor, RigError> {
        let out = &self.simplified.mesh;
        let vertices = span.vertices.start as usize..span.vertices.end as usize;
        let kept =
            vertices.clone().all(|v| out.positions[v] == self.input.mesh.positions[out.sources[v] as usize]);
        if kept {
            return self.carried(span, &["attributes", "POSITION"], cache, used_by);
        }
        let back = to_bind.try_inverse().ok_or_else(|| {
            RigError::Output(format!("{used_by}: the rigid mesh's placement in the bind space is singular"))
        })?;
        let local: Vec<[f32; 3]> = out.positions[vertices]
            .iter()
            .map(|p| {
                let q = crate::pose::transform_point(
                    &back,
                    &desal_mesh::Vec3::new(p[0].into(), p[1].into(), p[2].into()),
                );
                [q.x as f32, q.y as f32, q.z as f32]
            })
            .collect();
        Ok(positions(&local))
    }

    /// The accessor at `key` (`["attributes", "TEXCOORD_0"]`, `["targets", "2",
    /// "POSITION"]`) of `span`'s primitive, one element per output vertex copied from the
    /// input vertex it copies. A vertex copied from another primitive takes that
    /// primitive's element when it has the same accessor in the same type, zeros
    /// otherwise (only a face collapsed across two primitives has one).
    fn carried(
        &self,
        span: &PrimitiveSpan,
        key: &[&str],
        cache: &mut HashMap<usize, Elements>,
        used_by: &str,
    ) -> Result<NewAccessor, RigError> {
        let out = &self.simplified.mesh;
        let input = &self.input.mesh;
        let accessor_at = |mesh: usize, primitive: usize| {
            let mut v = &self.source.json["meshes"][mesh]["primitives"][primitive];
            for k in key {
                v = match v {
                    Value::Array(items) => {
                        k.parse::<usize>().ok().and_then(|i| items.get(i)).unwrap_or(&Value::Null)
                    }
                    other => &other[*k],
                };
            }
            v.as_u64().map(|a| a as usize)
        };
        let own = accessor_at(span.mesh, span.primitive).expect("the key was read from this primitive");
        self.elements(own, cache, used_by)?;
        let mut others = HashMap::new();
        let mut bytes = Vec::new();
        let size = cache[&own].size;
        for v in span.vertices.start..span.vertices.end {
            let split = out.sources[v as usize];
            let from = input.primitive_of(split).map(|p| &input.primitives[p]).ok_or_else(|| {
                RigError::Output(format!(
                    "output vertex {v} copies input vertex {split}, which no primitive holds"
                ))
            })?;
            let local = (split - from.vertices.start) as usize;
            let accessor = if (from.mesh, from.primitive) == (span.mesh, span.primitive) {
                Some(own)
            } else {
                *others
                    .entry((from.mesh, from.primitive))
                    .or_insert_with(|| accessor_at(from.mesh, from.primitive))
            };
            if let Some(a) = accessor {
                self.elements(a, cache, used_by)?;
            }
            let theirs = accessor.map(|a| &cache[&a]);
            match theirs {
                Some(e) if same_type(e, &cache[&own]) && (local + 1) * size <= e.bytes.len() => {
                    bytes.extend_from_slice(&e.bytes[local * size..(local + 1) * size]);
                }
                _ => bytes.extend(std::iter::repeat_n(0, size)),
            }
        }
        let model = &cache[&own];
        let count = span.vertices.len();
        // Attributes and morph target deltas are both vertex data (glTF 2.0 §3.6.2.4).
        let target = if matches!(key[0], "attributes" | "targets") { Some(ARRAY_BUFFER) } else { None };
        let mut accessor =
            packed(bytes, count, model.component_code(), model.type_name(), model.size, target);
        if model.normalized {
            accessor.json.insert("normalized".into(), true.into());
        }
        let original = &self.source.json["accessors"][own];
        if original.get("min").is_some() || original.get("max").is_some() {
            let picked = Elements { bytes: std::mem::take(&mut accessor.bytes), ..model.clone() };
            let (lo, hi) = picked.bounds(0..count);
            accessor.bytes = picked.bytes;
            let float = model.data_type == gltf::accessor::DataType::F32;
            accessor.json.insert("min".into(), numbers(&lo, float));
            accessor.json.insert("max".into(), numbers(&hi, float));
        }
        Ok(accessor)
    }

    /// Reads accessor `a` into `cache` (once).
    fn elements(
        &self,
        a: usize,
        cache: &mut HashMap<usize, Elements>,
        used_by: &str,
    ) -> Result<(), RigError> {
        if cache.contains_key(&a) {
            return Ok(());
        }
        let accessor = self.source.document.accessors().nth(a).ok_or_else(|| RigError::Structure {
            path: self.source.path.clone(),
            element: format!("accessor {a}"),
            reason: format!("is named by {used_by} but the file has no such accessor"),
        })?;
        let elements = self.source.accessors().elements(&accessor, Semantic::Carried, used_by)?;
        cache.insert(a, elements);
        Ok(())
    }

    /// The new binary chunk: every kept buffer view's bytes and the new accessors' (one
    /// view each), in view order; `buffers` and `bufferViews` rewritten. No kept view
    /// moves (images and extensions name views by index): the new accessors' views take
    /// the slots of the views only freed accessors used, then go at the end, and a freed
    /// view slot left over holds four zero bytes, as do the leftover accessor slots.
    fn rebuild_buffers(
        &self,
        json: &mut Value,
        freed: &BTreeSet<usize>,
        added: Vec<NewAccessor>,
        slots: &[usize],
    ) -> Result<Vec<u8>, RigError> {
        /// What a view of the output holds.
        enum Content {
            Kept,
            New(NewAccessor),
            Zero,
        }
        let views = json["bufferViews"].as_array().cloned().unwrap_or_default();
        // A view is freed when freed accessors name it and nothing else does.
        let mut named_by_kept = vec![false; views.len()];
        let mut named_by_freed = vec![false; views.len()];
        for (a, accessor) in self.source.json["accessors"].as_array().into_iter().flatten().enumerate() {
            let named = if freed.contains(&a) { &mut named_by_freed } else { &mut named_by_kept };
            for pointer in ["/bufferView", "/sparse/indices/bufferView", "/sparse/values/bufferView"] {
                if let Some(n) =
                    accessor.pointer(pointer).and_then(Value::as_u64).and_then(|v| named.get_mut(v as usize))
                {
                    *n = true;
                }
            }
        }
        for image in json["images"].as_array().into_iter().flatten() {
            if let Some(v) = image["bufferView"].as_u64().and_then(|v| named_by_kept.get_mut(v as usize)) {
                *v = true;
            }
        }
        let free: Vec<usize> = (0..views.len()).filter(|&v| named_by_freed[v] && !named_by_kept[v]).collect();
        let mut contents: Vec<Content> = (0..views.len()).map(|_| Content::Kept).collect();
        for &v in &free {
            contents[v] = Content::Zero;
        }
        for (k, a) in added.into_iter().enumerate() {
            let v = free.get(k).copied().unwrap_or(contents.len());
            let mut accessor = Value::Object(a.json.clone());
            accessor["bufferView"] = v.into();
            json["accessors"][slots[k]] = accessor;
            if v == contents.len() {
                contents.push(Content::New(a));
            } else {
                contents[v] = Content::New(a);
            }
        }
        // Freed accessor slots left over point at a zero.
        let leftovers: Vec<usize> = freed.iter().copied().skip(slots.len()).collect();
        if !leftovers.is_empty() {
            let zero = free.get(slots.len()).copied().unwrap_or(contents.len());
            if zero == contents.len() {
                contents.push(Content::Zero);
            }
            for &a in &leftovers {
                json["accessors"][a]["bufferView"] = zero.into();
            }
        }
        let mut bin = Vec::new();
        let mut out_views = Vec::with_capacity(contents.len());
        for (v, content) in contents.into_iter().enumerate() {
            align(&mut bin);
            let offset = bin.len();
            let view = match content {
                Content::Kept => {
                    let view = &views[v];
                    let buffer = view["buffer"].as_u64().unwrap_or(0) as usize;
                    let start = view["byteOffset"].as_u64().unwrap_or(0) as usize;
                    let length = view["byteLength"].as_u64().unwrap_or(0) as usize;
                    let bytes = self
                        .source
                        .buffers
                        .get(buffer)
                        .and_then(|b| b.get(start..start.checked_add(length)?))
                        .ok_or_else(|| RigError::Structure {
                            path: self.source.path.clone(),
                            element: format!("buffer view {v}"),
                            reason: format!("bytes {start}..+{length} lie outside buffer {buffer}"),
                        })?;
                    bin.extend_from_slice(bytes);
                    let mut view = view.clone();
                    view["buffer"] = 0.into();
                    view["byteOffset"] = offset.into();
                    view
                }
                Content::New(a) => {
                    let mut view = json!({"buffer": 0, "byteOffset": offset});
                    // Vertex attribute elements start on 4-byte boundaries (glTF 2.0 §3.6.2.4).
                    let stride = match a.target {
                        Some(ARRAY_BUFFER) if !a.element.is_multiple_of(4) => a.element.next_multiple_of(4),
                        _ => a.element,
                    };
                    for (e, element) in a.bytes.chunks_exact(a.element).enumerate() {
                        if e > 0 {
                            bin.extend(std::iter::repeat_n(0, stride - a.element));
                        }
                        bin.extend_from_slice(element);
                    }
                    view["byteLength"] = (bin.len() - offset).into();
                    if let Some(target) = a.target {
                        view["target"] = target.into();
                    }
                    if stride != a.element {
                        view["byteStride"] = stride.into();
                    }
                    view
                }
                Content::Zero => {
                    bin.extend([0; 4]);
                    json!({"buffer": 0, "byteOffset": offset, "byteLength": 4})
                }
            };
            out_views.push(view);
        }
        align(&mut bin);
        json["bufferViews"] = out_views.into();
        json["buffers"] = json!([{"byteLength": bin.len()}]);
        Ok(bin)
    }

    /// The bytes of every image named by a URI other than `data:`, read inside the input's
    /// folder, to be written under the same relative path.
    fn external_images(&self, json: &Value) -> Result<Vec<ExternalImage>, RigError> {
        let mut out = Vec::new();
        for (i, image) in json["images"].as_array().into_iter().flatten().enumerate() {
            let Some(uri) = image["uri"].as_str() else { continue };
            if uri.starts_with("data:") {
                continue;
            }
            let what = format!("image {i}");
            let path = relative_output_path(uri).ok_or_else(|| RigError::Structure {
                path: self.source.path.clone(),
                element: what.clone(),
                reason: format!(
                    "its URI '{uri}' is not a plain relative path (folder and file names, no '..'); desal copies \
                     an external image beside the output under the same relative path, so it must stay below \
                     the input's folder"
                ),
            })?;
            let bytes = desal_io::confine::read_inside(
                &self.source.path,
                &what,
                uri,
                crate::document::MAX_BUFFER_BYTES,
            )?;
            out.push(ExternalImage { path, bytes });
        }
        Ok(out)
    }
}

/// The accessors only the simplified primitives (`replaced`) name: the others are named
/// by other primitives, skins, animation samplers or `EXT_mesh_gpu_instancing`.
fn freed_accessors(json: &Value, replaced: &BTreeSet<(usize, usize)>) -> BTreeSet<usize> {
    let mut kept = BTreeSet::new();
    let mut candidates = BTreeSet::new();
    let index = |v: &Value| v.as_u64().map(|a| a as usize);
    for (m, mesh) in json["meshes"].as_array().into_iter().flatten().enumerate() {
        for (p, primitive) in mesh["primitives"].as_array().into_iter().flatten().enumerate() {
            let set = if replaced.contains(&(m, p)) { &mut candidates } else { &mut kept };
            let attributes = primitive["attributes"].as_object().into_iter().flat_map(|a| a.values());
            let targets = primitive["targets"].as_array().into_iter().flatten();
            let target_values = targets.filter_map(Value::as_object).flat_map(|t| t.values());
            set.extend(attributes.chain(target_values).chain([&primitive["indices"]]).filter_map(index));
        }
    }
    for skin in json["skins"].as_array().into_iter().flatten() {
        kept.extend(index(&skin["inverseBindMatrices"]));
    }
    for animation in json["animations"].as_array().into_iter().flatten() {
        for sampler in animation["samplers"].as_array().into_iter().flatten() {
            kept.extend(index(&sampler["input"]).into_iter().chain(index(&sampler["output"])));
        }
    }
    for node in json["nodes"].as_array().into_iter().flatten() {
        if let Some(attributes) = node.pointer("/extensions/EXT_mesh_gpu_instancing/attributes") {
            kept.extend(attributes.as_object().into_iter().flat_map(|a| a.values()).filter_map(index));
        }
    }
    candidates.difference(&kept).copied().collect()
}

/// The slot of each of `count` new accessors: the freed slots ascending, then new ones at
/// the end of `accessors`; freed slots left over become one-element accessors (their
/// zero's view is added by `Editor::rebuild_buffers`).
fn place_accessors(json: &mut Value, freed: &BTreeSet<usize>, count: usize) -> Vec<usize> {
    if !json["accessors"].is_array() {
        json["accessors"] = json!([]);
    }
    let accessors = json["accessors"].as_array_mut().expect("an array");
    let mut slots: Vec<usize> = freed.iter().copied().take(count).collect();
    for &leftover in freed.iter().skip(count) {
        // Its buffer view (one zero `f32`) is added with the others.
        accessors[leftover] = json!({"componentType": FLOAT, "count": 1, "type": "SCALAR"});
    }
    while slots.len() < count {
        slots.push(accessors.len());
        accessors.push(Value::Null);
    }
    slots
}

/// `POSITION` as `f32` triples with the bounds glTF requires.
fn positions(points: &[[f32; 3]]) -> NewAccessor {
    let (lo, hi) = crate::write::bounds(points);
    let bytes = points.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
    let mut a = packed(bytes, points.len(), FLOAT, "VEC3", 12, Some(ARRAY_BUFFER));
    a.json.insert("min".into(), json!(lo));
    a.json.insert("max".into(), json!(hi));
    a
}

fn packed(
    bytes: Vec<u8>,
    count: usize,
    component: u32,
    kind: &str,
    element: usize,
    target: Option<u32>,
) -> NewAccessor {
    debug_assert_eq!(bytes.len(), count * element);
    let json = json!({"componentType": component, "count": count, "type": kind});
    let Value::Object(json) = json else { unreachable!("an object") };
    NewAccessor { json, bytes, element, target }
}

fn same_type(a: &Elements, b: &Elements) -> bool {
    (a.data_type, a.normalized, a.dimensions) == (b.data_type, b.normalized, b.dimensions)
}

/// JSON numbers: `f32`s written as `f32`s (shortest, as exporters write them) for a
/// float accessor, integers for an integer one (glTF's bounds are in the components' type).
fn numbers(values: &[f64], float: bool) -> Value {
    // An `f32` goes through its shortest decimal form: JSON holds `f64`s, and 0.3f32 as
    // an `f64` would be written 0.30000001192092896.
    let shortest = |x: f64| (x as f32).to_string().parse::<f64>().unwrap_or(x);
    values.iter().map(|&x| if float { json!(shortest(x)) } else { json!(x as i64) }).collect()
}

fn align(bin: &mut Vec<u8>) {
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
}

/// The path beside the output an image URI names: its percent-decoded folder and file
/// names, or `None` when it is not made only of plain names (empty, `.`, `..`, a
/// backslash or a drive).
fn relative_output_path(uri: &str) -> Option<PathBuf> {
    let decoded = desal_io::confine::percent_decode(uri)?;
    let mut path = PathBuf::new();
    for part in decoded.split('/') {
        if part.is_empty() || part == "." || part == ".." || part.contains(['\\', ':', '\0']) {
            return None;
        }
        path.push(part);
    }
    Some(path).filter(|p| p != Path::new(""))
}

#[cfg(test)]
mod tests {
    use super::relative_output_path;
    use std::path::Path;

    #[test]
    fn image_uris_become_plain_relative_paths_or_nothing() {
        assert_eq!(relative_output_path("textures/skin%20a.png").unwrap(), Path::new("textures/skin a.png"));
        for bad in ["../skin.png", "a/../b.png", "/abs.png", "a//b.png", "./a.png", "c:\\x.png", ""] {
            assert_eq!(relative_output_path(bad), None, "{bad}");
        }
    }
}
