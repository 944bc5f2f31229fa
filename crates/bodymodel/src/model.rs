//! The in-memory body model: SMPL's arrays in f64, the joint regressor and skinning
//! weights as sparse rows, the kind, and every other key of the file kept as it came.
//!
//! Index spaces: `vertex` in `0..vertex_count()` (the file's vertex order), `joint` in
//! `0..joint_count()` (the order of `kintree_table`, parents first), `shape` and
//! `expression` components in the order of their blend shapes.

use desal_io::npz::{AnyArray, Dtype};
use desal_io::pickle::PyValue;
use desal_mesh::Vec3;

/// The member of the SMPL family a file holds, found from its joint count.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ModelKind {
    /// 24 joints: the body with one joint per hand.
    Smpl,
    /// 52 joints: SMPL's 22 body joints and 15 per hand.
    SmplH,
    /// 55 joints: SMPL-H's with jaw and eyes (22 jaw, 23–24 eyes, 25–54 hands); expression
    /// blend shapes after the shape ones.
    SmplX,
    /// 16 joints: one hand (wrist and 15 finger joints).
    Mano,
    /// 5 joints (root, neck, jaw, eyes): a head; expression blend shapes after the shape
    /// ones.
    Flame,
}

impl ModelKind {
    /// The kind with `joints` joints.
    pub fn from_joint_count(joints: usize) -> Option<Self> {
        Some(match joints {
            24 => ModelKind::Smpl,
            52 => ModelKind::SmplH,
            55 => ModelKind::SmplX,
            16 => ModelKind::Mano,
            5 => ModelKind::Flame,
            _ => return None,
        })
    }

    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Smpl => "SMPL",
            ModelKind::SmplH => "SMPL-H",
            ModelKind::SmplX => "SMPL-X",
            ModelKind::Mano => "MANO",
            ModelKind::Flame => "FLAME",
        }
    }

    /// Whether the file's `shapedirs` may carry expression blend shapes after the shape
    /// ones.
    pub fn has_expressions(self) -> bool {
        matches!(self, ModelKind::SmplX | ModelKind::Flame)
    }

    /// The joint names of the kind, in joint order (as the official code names them).
    pub fn joint_names(self) -> Vec<String> {
        let mut names: Vec<String> = Vec::new();
        let hand = |side: &str| {
            ["index", "middle", "pinky", "ring", "thumb"]
                .iter()
                .flat_map(move |finger| (1..=3).map(move |k| format!("{side}{finger}{k}")))
                .collect::<Vec<_>>()
        };
        match self {
            ModelKind::Smpl => names.extend(SMPL_BODY.iter().map(|s| s.to_string())),
            ModelKind::SmplH => {
                names.extend(SMPL_BODY[..22].iter().map(|s| s.to_string()));
                names.extend(hand("left_"));
                names.extend(hand("right_"));
            }
            ModelKind::SmplX => {
                names.extend(SMPL_BODY[..22].iter().map(|s| s.to_string()));
                names.extend(["jaw", "left_eye", "right_eye"].map(String::from));
                names.extend(hand("left_"));
                names.extend(hand("right_"));
            }
            ModelKind::Mano => {
                names.push("wrist".into());
                names.extend(hand(""));
            }
            ModelKind::Flame => {
                names.extend(["root", "neck", "jaw", "left_eye", "right_eye"].map(String::from))
            }
        }
        names
    }

    /// What each joint is, for the sampler's spreads (see the crate docs).
    pub fn joint_class(self, joint: usize) -> JointClass {
        match (self, joint) {
            (_, 0) => JointClass::Root,
            (ModelKind::Smpl, 22 | 23) => JointClass::Hand,
            (ModelKind::SmplH, 22..) => JointClass::Hand,
            (ModelKind::SmplX, 22..=24) => JointClass::Face,
            (ModelKind::SmplX, 25..) => JointClass::Hand,
            (ModelKind::Mano, _) => JointClass::Hand,
            (ModelKind::Flame, 2..) => JointClass::Face,
            _ => JointClass::Body,
        }
    }
}

/// SMPL's 24 joints; the first 22 are SMPL-H's and SMPL-X's body joints.
const SMPL_BODY: [&str; 24] = [
    "pelvis",
    "left_hip",
    "right_hip",
    "spine1",
    "left_knee",
    "right_knee",
    "spine2",
    "left_ankle",
    "right_ankle",
    "spine3",
    "left_foot",
    "right_foot",
    "neck",
    "left_collar",
    "right_collar",
    "head",
    "left_shoulder",
    "right_shoulder",
    "left_elbow",
    "right_elbow",
    "left_wrist",
    "right_wrist",
    "left_hand",
    "right_hand",
];

/// A joint's role, which sets its spread when poses are sampled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointClass {
    /// Joint 0: the whole model's orientation.
    Root,
    Body,
    /// Finger joints (and SMPL's two hand joints).
    Hand,
    /// Jaw and eyes.
    Face,
}

/// A sparse matrix in compressed rows: row `r` holds `(cols[k], values[k])` for `k` in
/// `offsets[r]..offsets[r + 1]`, columns ascending.
#[derive(Debug, Clone, PartialEq)]
pub struct SparseRows {
    pub offsets: Vec<usize>,
    pub cols: Vec<u32>,
    pub values: Vec<f64>,
}

impl SparseRows {
    pub fn row_count(&self) -> usize {
        self.offsets.len() - 1
    }

    /// The entries of row `r`.
    pub fn row(&self, r: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let range = self.offsets[r]..self.offsets[r + 1];
        self.cols[range.clone()].iter().map(|&c| c as usize).zip(self.values[range].iter().copied())
    }

    /// The rows as a dense row-major `rows × cols` matrix (the inverse of
    /// [`SparseRows::from_dense`]).
    pub fn to_dense(&self, rows: usize, cols: usize) -> Vec<f64> {
        let mut out = vec![0.0; rows * cols];
        for r in 0..rows {
            for (c, x) in self.row(r) {
                out[r * cols + c] = x;
            }
        }
        out
    }

    /// The nonzeros of a dense row-major `rows × cols` matrix.
    pub fn from_dense(dense: &[f64], rows: usize, cols: usize) -> Self {
        debug_assert_eq!(dense.len(), rows * cols);
        let mut out = SparseRows { offsets: vec![0], cols: Vec::new(), values: Vec::new() };
        for row in dense.chunks_exact(cols.max(1)).take(rows) {
            for (c, &v) in row.iter().enumerate() {
                if v != 0.0 {
                    out.cols.push(c as u32);
                    out.values.push(v);
                }
            }
            out.offsets.push(out.values.len());
        }
        out.offsets.resize(rows + 1, out.values.len());
        out
    }
}

/// A key of the file that the model does not interpret, kept as it came so that a writer
/// can copy it unchanged.
#[derive(Debug, Clone, PartialEq)]
pub enum ExtraEntry {
    /// An npz entry's `.npy` bytes, unparsed.
    Npy(Vec<u8>),
    /// A pickle's array.
    Array(AnyArray),
    /// Any other pickle value (strings, dicts, chumpy or scipy objects with their state).
    Pickled(PyValue),
}

/// How the file stored SMPL's keys, so that a writer gives a model back in the file's own
/// form ([`BodyModel::to_npz`]): the key order, each array's element type, and the two
/// layouts some files use.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FileLayout {
    /// Every key of the file, in file order (SMPL's and the extras).
    pub keys: Vec<String>,
    /// The element type of each of SMPL's keys the file stored (for a pickle, of the array
    /// inside the chumpy object or of a CSC matrix's data). A key not listed is written as
    /// float64 (int32 for `f`).
    pub dtypes: Vec<(String, Dtype)>,
    /// `shapedirs` was stored flattened, `(V·3·S,)` (some MANO files).
    pub shapedirs_flat: bool,
    /// `kintree_table` as stored (SMPL's files put 4294967295 or −1 at the root's parent),
    /// written back unchanged; `None` for a model built in code.
    pub kintree_table: Option<AnyArray>,
}

impl FileLayout {
    /// The element type the file stored `key` in.
    pub fn dtype(&self, key: &str) -> Option<Dtype> {
        self.dtypes.iter().find(|(k, _)| k == key).map(|&(_, d)| d)
    }
}

/// A parametric body model in SMPL's layout, every array in f64.
///
/// Layouts (row-major, the file's own):
/// - `v_template[vertex]`;
/// - `shapedirs[(vertex * 3 + axis) * shape_count + component]`, likewise `exprdirs`
///   with `expression_count` and `posedirs` with `pose_feature_count() = 9 (J − 1)`;
/// - `weights`: per vertex, `(joint, weight)` — the file's nonzeros;
/// - `joint_regressor`: per joint, `(vertex, weight)`.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyModel {
    pub kind: ModelKind,
    pub v_template: Vec<Vec3>,
    pub faces: Vec<[u32; 3]>,
    pub shape_count: usize,
    pub shapedirs: Vec<f64>,
    pub expression_count: usize,
    pub exprdirs: Vec<f64>,
    pub posedirs: Vec<f64>,
    pub weights: SparseRows,
    /// `parents[joint]`: `None` for joint 0, else an earlier joint.
    pub parents: Vec<Option<usize>>,
    pub joint_regressor: SparseRows,
    /// The mean pose the official code adds to sampled hand poses (`hands_mean`,
    /// `hands_meanl`/`hands_meanr`), per joint as an axis-angle; zero elsewhere.
    pub pose_mean: Vec<Vec3>,
    /// Every key the model does not interpret, in file order.
    pub extras: Vec<(String, ExtraEntry)>,
    /// How the file stored the model.
    pub layout: FileLayout,
}

impl BodyModel {
    pub fn vertex_count(&self) -> usize {
        self.v_template.len()
    }

    pub fn joint_count(&self) -> usize {
        self.parents.len()
    }

    /// The length of the pose feature `(R(θ_j) − I)` for joints 1.., flattened.
    pub fn pose_feature_count(&self) -> usize {
        9 * (self.joint_count() - 1)
    }

    /// The joints of the kinematic tree below `joint` (its children), ascending.
    pub fn children(&self, joint: usize) -> Vec<usize> {
        (0..self.joint_count()).filter(|&j| self.parents[j] == Some(joint)).collect()
    }
}
