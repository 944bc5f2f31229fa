//! The in-memory rig: the node tree, one skin, the animations and one skinned mesh, as
//! read from a glTF file ([`crate::read`]) or built by a generator, and as written back
//! ([`crate::write`]). Values keep the file's `f32` precision, so a rig read and written
//! again keeps its numbers bit for bit.
//!
//! Index spaces: `node` indexes [`Rig::nodes`]; `joint` indexes [`Skin::joints`] (what
//! `JOINTS_n` stores); `split` indexes the mesh's own vertices, which repeat a position
//! along UV and normal seams ([`crate::weld`] maps them to welded vertices).

use desal_mesh::math::Mat4;

/// A node's local transform.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LocalTransform {
    /// Translation, rotation (unit quaternion `[x, y, z, w]`) and scale, composed T·R·S.
    Trs { translation: [f32; 3], rotation: [f32; 4], scale: [f32; 3] },
    /// A column-major 4×4 matrix (glTF's `matrix`). It cannot be animated.
    Matrix([f32; 16]),
}

impl LocalTransform {
    pub const IDENTITY: Self =
        Self::Trs { translation: [0.0; 3], rotation: [0.0, 0.0, 0.0, 1.0], scale: [1.0; 3] };
}

/// One node of the scene graph.
#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    pub name: Option<String>,
    pub children: Vec<usize>,
    pub transform: LocalTransform,
}

/// The skin of the skinned mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct Skin {
    pub name: Option<String>,
    /// Joint `j` is node `joints[j]`.
    pub joints: Vec<usize>,
    /// One per joint, column-major as stored (glTF's `inverseBindMatrices`; identity when
    /// the file has none).
    pub inverse_bind: Vec<[f32; 16]>,
    /// The skeleton root node, when the file names one.
    pub skeleton: Option<usize>,
}

impl Skin {
    /// The inverse bind matrix of `joint` in `f64`.
    pub fn inverse_bind_matrix(&self, joint: usize) -> Mat4 {
        Mat4::from_column_slice(&self.inverse_bind[joint].map(f64::from))
    }
}

/// What an animation channel drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Path {
    Translation,
    Rotation,
    Scale,
}

/// How an animation sampler interpolates between keyframes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interpolation {
    Step,
    Linear,
    /// Hermite spline; each keyframe stores in-tangent, value, out-tangent.
    CubicSpline,
}

/// One animated property of one node.
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    pub node: usize,
    pub path: Path,
    pub interpolation: Interpolation,
    /// Keyframe times in seconds, strictly increasing.
    pub times: Vec<f32>,
    /// Keyframe values, flattened: 3 (translation, scale) or 4 (rotation) per value, and
    /// three values per keyframe for [`Interpolation::CubicSpline`].
    pub values: Vec<f32>,
}

impl Channel {
    /// Components per value: 4 for rotations, 3 otherwise.
    pub fn width(&self) -> usize {
        if self.path == Path::Rotation { 4 } else { 3 }
    }
}

/// A named animation.
#[derive(Debug, Clone, PartialEq)]
pub struct Animation {
    pub name: Option<String>,
    pub channels: Vec<Channel>,
}

impl Animation {
    /// Start and end time over all channels (`(0, 0)` when there are no keyframes).
    pub fn time_range(&self) -> (f32, f32) {
        let mut range = (f32::INFINITY, f32::NEG_INFINITY);
        for c in &self.channels {
            if let (Some(first), Some(last)) = (c.times.first(), c.times.last()) {
                range = (range.0.min(*first), range.1.max(*last));
            }
        }
        if range.0.is_finite() { range } else { (0.0, 0.0) }
    }
}

/// Per-vertex skinning influences in compressed rows: vertex `v` has joints
/// `joints[offsets[v]..offsets[v + 1]]` with `weights[...]`, in the order the file
/// lists them (zero weights dropped).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Influences {
    pub offsets: Vec<u32>,
    pub joints: Vec<u16>,
    pub weights: Vec<f32>,
}

impl Influences {
    /// An empty table, ready for [`Influences::push_row`].
    pub fn new() -> Self {
        Self { offsets: vec![0], joints: Vec::new(), weights: Vec::new() }
    }

    /// Appends one vertex's influences.
    pub fn push_row(&mut self, row: impl IntoIterator<Item = (u16, f32)>) {
        for (j, w) in row {
            self.joints.push(j);
            self.weights.push(w);
        }
        self.offsets.push(self.joints.len() as u32);
    }

    pub fn vertex_count(&self) -> usize {
        self.offsets.len() - 1
    }

    /// The `(joint, weight)` pairs of vertex `v`.
    pub fn of(&self, v: usize) -> impl Iterator<Item = (usize, f32)> + '_ {
        let range = self.offsets[v] as usize..self.offsets[v + 1] as usize;
        self.joints[range.clone()].iter().map(|&j| j as usize).zip(self.weights[range].iter().copied())
    }

    /// The largest number of influences of any vertex.
    pub fn max_influences(&self) -> usize {
        self.offsets.windows(2).map(|w| (w[1] - w[0]) as usize).max().unwrap_or(0)
    }

    /// The joint with the largest weight on `v`; ties go to the lower joint index.
    pub fn dominant_joint(&self, v: usize) -> usize {
        let mut best = (usize::MAX, f32::NEG_INFINITY);
        for (j, w) in self.of(v) {
            if w > best.1 || (w == best.1 && j < best.0) {
                best = (j, w);
            }
        }
        best.0
    }
}

/// One primitive of the glTF document as a run of the skinned mesh's split vertices and
/// triangles: the reader appends primitives in order, and the simplified mesh keeps one
/// run per primitive, so [`crate::edit`] writes each back in place (its material, mode
/// and extensions untouched).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PrimitiveSpan {
    /// The glTF mesh (`meshes[mesh]`).
    pub mesh: usize,
    /// The primitive within it (`meshes[mesh].primitives[primitive]`).
    pub primitive: usize,
    /// Its split vertices.
    pub vertices: std::ops::Range<u32>,
    /// Its triangles.
    pub triangles: std::ops::Range<u32>,
}

/// One glTF mesh of a rig, skinned by one glTF skin: where it lies in [`Rig::mesh`] and
/// how its skin's joints map to the rig's one [`Skin`] (the skins of every mesh merged,
/// a joint per node and inverse bind matrix).
#[derive(Debug, Clone, PartialEq)]
pub struct MeshPart {
    /// The first node carrying it.
    pub node: usize,
    /// `meshes[mesh]` in the document.
    pub mesh: usize,
    pub name: String,
    /// `skins[skin]` in the document; `None` for a rigid mesh below a bone.
    pub skin: Option<usize>,
    /// The rig joint of each joint of its skin (a rigid mesh: the one joint it follows).
    pub joints: Vec<u16>,
    /// A rigid mesh: the matrix that took its own positions into the skin's bind space
    /// (those of [`Rig::mesh`]), which [`crate::edit`] undoes for moved vertices.
    pub to_bind: Option<Mat4>,
    /// Its split vertices and triangles in [`Rig::mesh`].
    pub vertices: std::ops::Range<u32>,
    pub triangles: std::ops::Range<u32>,
}

/// The skinned mesh: one triangle list over split vertices, with their attributes.
#[derive(Debug, Clone, PartialEq)]
pub struct SkinnedMesh {
    pub name: String,
    /// Bind-pose positions, in the file's units.
    pub positions: Vec<[f32; 3]>,
    pub normals: Option<Vec<[f32; 3]>>,
    /// `TEXCOORD_0`.
    pub uvs: Option<Vec<[f32; 2]>>,
    pub influences: Influences,
    pub triangles: Vec<[u32; 3]>,
    /// The glTF primitives the vertices and triangles come from, in order, covering both
    /// (empty for a mesh built in memory, which [`crate::write_glb`] writes as one
    /// primitive).
    pub primitives: Vec<PrimitiveSpan>,
    /// For a simplified mesh, the input split vertex each vertex copies its other
    /// attributes (`TEXCOORD_n`, `COLOR_n`, `TANGENT`, ...) and morph target deltas from;
    /// empty for a mesh as read.
    pub sources: Vec<u32>,
}

impl SkinnedMesh {
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// The index in [`SkinnedMesh::primitives`] of the span holding split vertex `v`.
    pub fn primitive_of(&self, v: u32) -> Option<usize> {
        let p = self.primitives.partition_point(|span| span.vertices.end <= v);
        (p < self.primitives.len() && self.primitives[p].vertices.contains(&v)).then_some(p)
    }
}

/// A skinned rig: the scene graph, the skin, the animations and the skinned meshes, as
/// one mesh ([`Rig::mesh`], each glTF mesh a run of it: [`Rig::meshes`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Rig {
    /// What reading did to the skinning weights (renormalised sums).
    pub weight_sums: WeightSums,
    pub nodes: Vec<Node>,
    /// Root nodes of each scene.
    pub scenes: Vec<Vec<usize>>,
    /// The scene shown by default.
    pub scene: Option<usize>,
    /// The node that carries the (first) skinned mesh.
    pub mesh_node: usize,
    /// The glTF meshes [`Rig::mesh`] holds, in node order, each a run of its vertices and
    /// triangles (empty for a rig built in memory: one mesh on [`Rig::mesh_node`]).
    pub meshes: Vec<MeshPart>,
    pub skin: Skin,
    pub animations: Vec<Animation>,
    pub mesh: SkinnedMesh,
}

/// The skinning weights read off 1 and renormalised, as engines renormalise them:
/// exporters write quantised weights (a sum of 0.996 from 8-bit weights is common).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct WeightSums {
    /// Vertices whose weights summed further from 1 than
    /// [`crate::read::WEIGHT_SUM_TOLERANCE`], divided by their sum.
    pub renormalised: usize,
    /// Of those, the vertices off by more than [`WEIGHT_SUM_REPORTED`] (2 %).
    pub off_by_more_than_2pct: usize,
    /// The vertex whose sum was furthest from 1, and that sum.
    pub worst: Option<(usize, f64)>,
}

/// How far from 1 a weight sum must be to be counted in [`WeightSums::off_by_more_than_2pct`].
pub const WEIGHT_SUM_REPORTED: f64 = 0.02;

impl WeightSums {
    /// Adds the counts of another primitive's weights.
    pub fn add(&mut self, other: WeightSums) {
        self.renormalised += other.renormalised;
        self.off_by_more_than_2pct += other.off_by_more_than_2pct;
        if let Some((vertex, sum)) = other.worst
            && self.worst.is_none_or(|(_, worst)| (sum - 1.0).abs() > (worst - 1.0).abs())
        {
            self.worst = Some((vertex, sum));
        }
    }

    /// A line for the ingest note, or `None` when no weight was renormalised.
    pub fn note(&self) -> Option<String> {
        let (vertex, sum) = self.worst?;
        Some(format!(
            "{} vertices' weights renormalised ({} off by more than 2 %; worst: vertex {vertex} summed to {sum})",
            self.renormalised, self.off_by_more_than_2pct
        ))
    }
}

impl Rig {
    /// The parent of every node (`None` for roots).
    pub fn parents(&self) -> Vec<Option<usize>> {
        let mut parents = vec![None; self.nodes.len()];
        for (n, node) in self.nodes.iter().enumerate() {
            for &c in &node.children {
                parents[c] = Some(n);
            }
        }
        parents
    }

    /// Every node once, each after its parent: the order in which a walk down the tree
    /// meets them, found without recursion (a file's node chain may be thousands deep)
    /// in time linear in the nodes. `parents` is [`Rig::parents`], which must be acyclic
    /// (as [`crate::read_rig`] checks).
    pub fn parents_first(parents: &[Option<usize>]) -> Vec<usize> {
        let mut placed = vec![false; parents.len()];
        let mut order = Vec::with_capacity(parents.len());
        let mut chain = Vec::new();
        for start in 0..parents.len() {
            // Climb to the nearest placed ancestor (or a root), then place the chain top-down.
            let mut current = Some(start);
            while let Some(n) = current.filter(|&n| !placed[n]) {
                chain.push(n);
                current = parents[n];
            }
            while let Some(n) = chain.pop() {
                placed[n] = true;
                order.push(n);
            }
        }
        order
    }

    /// The parent *joint* of every joint: the nearest ancestor node that is a joint.
    pub fn joint_parents(&self) -> Vec<Option<usize>> {
        let parents = self.parents();
        let mut joint_of_node = vec![None; self.nodes.len()];
        for (j, &n) in self.skin.joints.iter().enumerate() {
            joint_of_node[n] = Some(j);
        }
        // The nearest joint at or above every node, parents first.
        let mut nearest: Vec<Option<usize>> = vec![None; self.nodes.len()];
        for n in Self::parents_first(&parents) {
            nearest[n] = joint_of_node[n].or_else(|| parents[n].and_then(|p| nearest[p]));
        }
        self.skin.joints.iter().map(|&n| parents[n].and_then(|p| nearest[p])).collect()
    }

    /// A joint's name: its node's name, or `joint<j>`.
    pub fn joint_name(&self, joint: usize) -> String {
        self.nodes[self.skin.joints[joint]].name.clone().unwrap_or_else(|| format!("joint{joint}"))
    }
}
