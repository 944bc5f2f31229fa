//! The glTF document's structure, checked on the raw JSON before the `gltf` crate sees
//! it: every reference from one element to another in range, and every enumerated
//! value one of the specification's.
//!
//! The crate's own validation reports most of these, but not all, and in places panics
//! instead (gltf-json 1.4: an animation channel's target node and path are never
//! validated, so `Channel::target().node()` unwraps `None` and `.property()` unwraps an
//! invalid path; the primitive validation hook indexes `accessors[POSITION]` before the
//! index is checked). So everything desal reads, and everything the crate indexes while
//! validating, is checked here first and refused with the file and the element by index
//! and name ([`RigError::Structure`]): scenes, nodes, meshes and their primitives,
//! skins, animations with their samplers and channels, accessors with their sparse
//! storage, and buffer views. Values of the wrong JSON type are left to the crate's
//! deserialiser, which refuses them; elements desal never reads (materials, textures,
//! images, cameras) are left to the crate's validation, which reports them without
//! panicking.

use std::path::Path;

use serde_json::Value;

use crate::RigError;

/// `target.path` values (glTF 2.0 §5.8.2, `animation.channel.target.path`).
const CHANNEL_PATHS: &[&str] = &["translation", "rotation", "scale", "weights"];
/// `interpolation` values (§5.10, `animation.sampler.interpolation`).
const INTERPOLATIONS: &[&str] = &["LINEAR", "STEP", "CUBICSPLINE"];
/// Accessor `type` values (§5.1).
const ACCESSOR_TYPES: &[&str] = &["SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"];
/// Accessor `componentType` values (§5.1): BYTE to FLOAT, without 5124 (INT).
const COMPONENT_TYPES: &[u64] = &[5120, 5121, 5122, 5123, 5125, 5126];
/// Sparse index `componentType` values (§5.3): UNSIGNED_BYTE, _SHORT, _INT.
const INDEX_COMPONENT_TYPES: &[u64] = &[5121, 5123, 5125];
/// The largest primitive `mode` (§5.24: POINTS 0 to TRIANGLE_FAN 6).
const MAX_MODE: u64 = 6;

/// Checks the structure of the glTF JSON `root`; `path` names the file in errors.
pub fn check(path: &Path, root: &Value) -> Result<(), RigError> {
    let c = Checker { path, root };
    c.scenes()?;
    c.nodes()?;
    c.meshes()?;
    c.skins()?;
    c.animations()?;
    c.accessors()?;
    c.buffer_views()
}

/// The kinds of element a reference may point at: the root's array, the word for one.
#[derive(Clone, Copy)]
enum Kind {
    Scene,
    Node,
    Mesh,
    Skin,
    Camera,
    Material,
    Accessor,
    BufferView,
    Buffer,
}

impl Kind {
    fn key(self) -> &'static str {
        match self {
            Kind::Scene => "scenes",
            Kind::Node => "nodes",
            Kind::Mesh => "meshes",
            Kind::Skin => "skins",
            Kind::Camera => "cameras",
            Kind::Material => "materials",
            Kind::Accessor => "accessors",
            Kind::BufferView => "bufferViews",
            Kind::Buffer => "buffers",
        }
    }

    fn singular(self) -> &'static str {
        match self {
            Kind::Scene => "scene",
            Kind::Node => "node",
            Kind::Mesh => "mesh",
            Kind::Skin => "skin",
            Kind::Camera => "camera",
            Kind::Material => "material",
            Kind::Accessor => "accessor",
            Kind::BufferView => "buffer view",
            Kind::Buffer => "buffer",
        }
    }

    fn plural(self) -> &'static str {
        match self {
            Kind::Mesh => "meshes",
            Kind::Scene => "scenes",
            Kind::Node => "nodes",
            Kind::Skin => "skins",
            Kind::Camera => "cameras",
            Kind::Material => "materials",
            Kind::Accessor => "accessors",
            Kind::BufferView => "buffer views",
            Kind::Buffer => "buffers",
        }
    }
}

/// The items of `value[key]`, none when absent or not an array (the deserialiser
/// refuses the latter).
fn items<'v>(value: &'v Value, key: &str) -> &'v [Value] {
    value.get(key).and_then(Value::as_array).map_or(&[], Vec::as_slice)
}

/// `kind index 'name'` (or `kind index` when the element has no string name).
fn label(kind: &str, index: usize, item: &Value) -> String {
    match item.get("name").and_then(Value::as_str) {
        Some(name) => format!("{kind} {index} '{name}'"),
        None => format!("{kind} {index}"),
    }
}

/// `n` elements, in words: "no nodes", "1 node", "3 nodes".
fn how_many(n: usize, kind: Kind) -> String {
    match n {
        0 => format!("no {}", kind.plural()),
        1 => format!("1 {}", kind.singular()),
        _ => format!("{n} {}", kind.plural()),
    }
}

struct Checker<'a> {
    path: &'a Path,
    root: &'a Value,
}

impl Checker<'_> {
    fn error(&self, element: &str, reason: String) -> RigError {
        RigError::Structure { path: self.path.to_owned(), element: element.to_owned(), reason }
    }

    /// `reference` (when an unsigned integer; other JSON the deserialiser refuses), named
    /// `what` in `element`, must index the root's `kind` array.
    fn reference(
        &self,
        element: &str,
        what: &str,
        reference: Option<&Value>,
        kind: Kind,
    ) -> Result<(), RigError> {
        let count = items(self.root, kind.key()).len();
        self.reference_within(element, what, reference, kind, count)
    }

    /// As [`Self::reference`], into an array of `count` elements (an animation's own
    /// samplers).
    fn reference_within(
        &self,
        element: &str,
        what: &str,
        reference: Option<&Value>,
        kind: Kind,
        count: usize,
    ) -> Result<(), RigError> {
        match reference.and_then(Value::as_u64) {
            Some(i) if i >= count as u64 => Err(self.error(
                element,
                format!(
                    "{what} refers to {} {i}, but the file has {}",
                    kind.singular(),
                    how_many(count, kind)
                ),
            )),
            _ => Ok(()),
        }
    }

    /// Every item of the array `value[key]`, a reference to a `kind`.
    fn references(
        &self,
        element: &str,
        what: &str,
        value: &Value,
        key: &str,
        kind: Kind,
    ) -> Result<(), RigError> {
        for (k, reference) in items(value, key).iter().enumerate() {
            self.reference(element, &format!("{what} {k}"), Some(reference), kind)?;
        }
        Ok(())
    }

    /// `value[key]`, when a string, must be one of `allowed`.
    fn one_of(&self, element: &str, value: &Value, key: &str, allowed: &[&str]) -> Result<(), RigError> {
        match value.get(key).and_then(Value::as_str) {
            Some(given) if !allowed.contains(&given) => Err(self.error(
                element,
                format!("{key} \"{}\" is not one of {}", given.escape_debug(), allowed.join(", ")),
            )),
            _ => Ok(()),
        }
    }

    fn scenes(&self) -> Result<(), RigError> {
        self.reference("the file", "scene", self.root.get("scene"), Kind::Scene)?;
        for (s, scene) in items(self.root, "scenes").iter().enumerate() {
            self.references(&label("scene", s, scene), "node", scene, "nodes", Kind::Node)?;
        }
        Ok(())
    }

    fn nodes(&self) -> Result<(), RigError> {
        for (n, node) in items(self.root, "nodes").iter().enumerate() {
            let element = label("node", n, node);
            self.references(&element, "child", node, "children", Kind::Node)?;
            self.reference(&element, "mesh", node.get("mesh"), Kind::Mesh)?;
            self.reference(&element, "skin", node.get("skin"), Kind::Skin)?;
            self.reference(&element, "camera", node.get("camera"), Kind::Camera)?;
        }
        Ok(())
    }

    fn meshes(&self) -> Result<(), RigError> {
        for (m, mesh) in items(self.root, "meshes").iter().enumerate() {
            let mesh_label = label("mesh", m, mesh);
            for (p, primitive) in items(mesh, "primitives").iter().enumerate() {
                let element = format!("{mesh_label} primitive {p}");
                if let Some(attributes) = primitive.get("attributes").and_then(Value::as_object) {
                    for (semantic, accessor) in attributes {
                        self.reference(&element, semantic, Some(accessor), Kind::Accessor)?;
                    }
                }
                self.reference(&element, "indices", primitive.get("indices"), Kind::Accessor)?;
                self.reference(&element, "material", primitive.get("material"), Kind::Material)?;
                for (t, target) in items(primitive, "targets").iter().enumerate() {
                    for semantic in ["POSITION", "NORMAL", "TANGENT"] {
                        let what = format!("morph target {t} {semantic}");
                        self.reference(&element, &what, target.get(semantic), Kind::Accessor)?;
                    }
                }
                if let Some(mode) = primitive.get("mode").and_then(Value::as_u64)
                    && mode > MAX_MODE
                {
                    return Err(self.error(
                        &element,
                        format!("mode {mode} is not a glTF primitive mode (0 to {MAX_MODE}; 4 is triangles)"),
                    ));
                }
            }
        }
        Ok(())
    }

    fn skins(&self) -> Result<(), RigError> {
        for (s, skin) in items(self.root, "skins").iter().enumerate() {
            let element = label("skin", s, skin);
            let matrices = skin.get("inverseBindMatrices");
            self.reference(&element, "inverseBindMatrices", matrices, Kind::Accessor)?;
            self.references(&element, "joint", skin, "joints", Kind::Node)?;
            self.reference(&element, "skeleton", skin.get("skeleton"), Kind::Node)?;
        }
        Ok(())
    }

    fn animations(&self) -> Result<(), RigError> {
        for (a, animation) in items(self.root, "animations").iter().enumerate() {
            let animation_label = label("animation", a, animation);
            let samplers = items(animation, "samplers");
            for (s, sampler) in samplers.iter().enumerate() {
                let element = format!("{animation_label} sampler {s}");
                self.reference(&element, "input", sampler.get("input"), Kind::Accessor)?;
                self.reference(&element, "output", sampler.get("output"), Kind::Accessor)?;
                self.one_of(&element, sampler, "interpolation", INTERPOLATIONS)?;
            }
            for (c, channel) in items(animation, "channels").iter().enumerate() {
                let element = format!("{animation_label} channel {c}");
                match channel.get("sampler").and_then(Value::as_u64) {
                    Some(s) if s >= samplers.len() as u64 => {
                        return Err(self.error(
                            &element,
                            format!(
                                "sampler {s} does not exist; the animation has {} samplers",
                                samplers.len()
                            ),
                        ));
                    }
                    _ => {}
                }
                if let Some(target) = channel.get("target") {
                    self.reference(&element, "the target", target.get("node"), Kind::Node)?;
                    self.one_of(&element, target, "path", CHANNEL_PATHS)?;
                }
            }
        }
        Ok(())
    }

    fn accessors(&self) -> Result<(), RigError> {
        for (i, accessor) in items(self.root, "accessors").iter().enumerate() {
            let element = label("accessor", i, accessor);
            self.reference(&element, "bufferView", accessor.get("bufferView"), Kind::BufferView)?;
            self.one_of(&element, accessor, "type", ACCESSOR_TYPES)?;
            self.component_type(&element, "componentType", accessor.get("componentType"), COMPONENT_TYPES)?;
            if let Some(sparse) = accessor.get("sparse") {
                if let Some(indices) = sparse.get("indices") {
                    let view = indices.get("bufferView");
                    self.reference(&element, "the sparse indices' bufferView", view, Kind::BufferView)?;
                    let what = "the sparse indices' componentType";
                    self.component_type(&element, what, indices.get("componentType"), INDEX_COMPONENT_TYPES)?;
                }
                if let Some(values) = sparse.get("values") {
                    let view = values.get("bufferView");
                    self.reference(&element, "the sparse values' bufferView", view, Kind::BufferView)?;
                }
            }
        }
        Ok(())
    }

    /// A `componentType` (when a number) must be one of `allowed`.
    fn component_type(
        &self,
        element: &str,
        what: &str,
        value: Option<&Value>,
        allowed: &[u64],
    ) -> Result<(), RigError> {
        match value.and_then(Value::as_u64) {
            Some(given) if !allowed.contains(&given) => {
                let allowed: Vec<String> = allowed.iter().map(u64::to_string).collect();
                Err(self.error(element, format!("{what} {given} is not one of {}", allowed.join(", "))))
            }
            _ => Ok(()),
        }
    }

    fn buffer_views(&self) -> Result<(), RigError> {
        for (v, view) in items(self.root, "bufferViews").iter().enumerate() {
            self.reference(&label("buffer view", v, view), "buffer", view.get("buffer"), Kind::Buffer)?;
        }
        Ok(())
    }
}
