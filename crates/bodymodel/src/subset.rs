//! A smaller model of the same kind: the model restricted to a subset of its vertices
//! (a simplification with subset placement, where every kept vertex is a model vertex),
//! with new triangles, a joint regressor solved so that the joints stay where the full
//! model puts them, and landmark embeddings moved onto the new triangles.
//!
//! The story, in [`subset_model`]:
//! 1. every per-vertex array (`v_template`, `shapedirs` and the expression directions,
//!    `posedirs`, `weights`) keeps the rows of the kept vertices, in `simp_idx` order;
//! 2. `J_regressor`, per joint (`solve_joint_row`): SMPL regresses the rest joints from
//!    the shaped surface, `J = R (T + Σ_k β_k S_k)`, so the joints of the smaller model
//!    equal the full model's for *every* shape (and expression) exactly when each row `w`
//!    over the kept vertices reproduces the full row `r` on every column of the basis
//!    `B = [T, S_1 … S_K]`, all three coordinates: `w · B_kept = r · B_full`, plus
//!    `Σ w = Σ r`, so that a translated body moves its joints with it. These are
//!    `3 (K + 1) + 1` equations; the support has more unknowns, so the system is
//!    underdetermined and we take the solution closest to a prior `w₀` — the full row's
//!    weights moved to the nearest kept vertex — through the SVD's pseudo-inverse:
//!    `w = w₀ + A⁺ (b − A w₀)`. The support is the prior's plus the kept vertices nearest
//!    the joint, doubled until the residual is under [`SubsetConfig::tolerance`] (or
//!    every kept vertex is in), so rows stay local and sparse-ish. The template column is
//!    taken relative to the joint (equivalent under `Σ w = Σ r`, better conditioned);
//! 3. landmark embeddings ([`LANDMARK_KEYS`]: a face index and barycentric coordinates
//!    per landmark, SMPL-X's and FLAME's): each landmark, placed on the full template, goes
//!    to its closest point on the smaller template;
//! 4. every other key is kept as it came (MANO's `hands_components`, the mean hand poses,
//!    `kintree_table`, `J`, …); those with an axis of the full model's vertex or face
//!    count still describe the full model and are listed in the report.
//!
//! Outside the basis (a surface no `β` produces, such as a registered scan) the joints of
//! the two models differ by what the kept vertices cannot see; [`SubsetReport`] gives the
//! residual inside it.
//!
//! Cost: one SVD of `(3 (K + 1) + 1) × support` per joint and support size, joints in
//! parallel. On this machine (2 cores, `examples/subset_timing.rs`, 1487 kept vertices of
//! the fixture): 0.1 s at 10 components, 7 s at 50, 17 s at 100; a 300-component basis
//! (SMPL 1.1) needs a support of at least 904 vertices and some minutes.

use desal_io::npz::{AnyArray, AnyData, decode_npy_any};
use desal_measures::closest_point::closest_point_on_triangle;
use desal_measures::{SurfaceIndex, VertexIndex};
use desal_mesh::{TriMesh, Vec3};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use serde::Serialize;

use crate::error::BodyModelError;
use crate::model::{BodyModel, ExtraEntry, SparseRows};

/// The landmark embeddings the SMPL family's files carry, as `(face indices, barycentric
/// coordinates)` key pairs: SMPL-X's static and dynamic (contour) landmarks, FLAME's
/// static embedding as its `.pkl` names it.
pub const LANDMARK_KEYS: [(&str, &str); 3] = [
    ("lmk_faces_idx", "lmk_bary_coords"),
    ("dynamic_lmk_faces_idx", "dynamic_lmk_bary_coords"),
    ("lmk_face_idx", "lmk_b_coords"),
];

/// A solved weight at most this far from zero is zero.
const ZERO_WEIGHT: f64 = 1e-13;

/// How the joint regressor is solved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SubsetConfig {
    /// A row is solved again on twice the support while its residual (m per unit
    /// coefficient) is above this. Default 1e-9 m: a thousand times under the f32
    /// rounding of a model's own arrays at 1 m.
    pub tolerance: f64,
    /// Singular values below this fraction of the largest are treated as zero: a
    /// direction of the basis the support barely sees is not chased with large weights of
    /// both signs, the support grows instead. Default 1e-6: on the CC0 fixture at 1 in 7
    /// vertices, 1e-10 gave one row (an ankle) negative weights summing to −4.3 and a
    /// 15 mm joint error under 1 cm of per-vertex noise; 1e-6 gives −1.3 and 4 mm, with
    /// every residual still under the tolerance.
    pub rcond: f64,
}

impl Default for SubsetConfig {
    fn default() -> Self {
        Self { tolerance: 1e-9, rcond: 1e-6 }
    }
}

/// One joint's solved regressor row.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct JointFit {
    pub joint: String,
    /// Kept vertices the row may use, and those it uses (nonzero weights).
    pub support: usize,
    pub nonzeros: usize,
    /// The full model's row: its nonzeros.
    pub full_nonzeros: usize,
    /// `max |w · B_kept − r · B_full|` over the basis columns and coordinates: metres for
    /// the template, metres per unit coefficient for a blend shape.
    pub residual_m: f64,
    /// The largest |weight| and the sum of the negative weights (the full rows of SMPL
    /// are non-negative; a solved row may not be).
    pub max_abs_weight: f64,
    pub negative_sum: f64,
}

/// One landmark embedding moved onto the smaller template.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LandmarkFit {
    /// The key of the face indices.
    pub key: String,
    pub landmarks: usize,
    /// How far a landmark moved, full template to its closest point on the smaller one
    /// (m): mean and max.
    pub moved_mean_m: f64,
    pub moved_max_m: f64,
}

/// What [`subset_model`] did, per joint and landmark key.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SubsetReport {
    pub vertices: usize,
    pub faces: usize,
    /// Columns of the basis the regressor holds on: the template, shape and expression
    /// directions.
    pub basis_columns: usize,
    pub joints: Vec<JointFit>,
    /// The largest residual of any joint (see [`JointFit::residual_m`]).
    pub max_residual_m: f64,
    pub landmarks: Vec<LandmarkFit>,
    /// Keys kept unchanged with an axis of the full model's vertex or face count: they
    /// still describe the full model (texture faces `ft`, priors, symmetry maps).
    pub full_size_extras: Vec<String>,
}

/// `model` restricted to `kept_orig` (`simp_to_orig`: per simplified vertex, the model
/// vertex it is; all distinct) with triangles `faces` (in `simp_idx` space), its joint
/// regressor solved and its landmarks moved (see the module docs). The result keeps the
/// input's kind, key order and element types ([`crate::model::FileLayout`]), except the
/// solved `J_regressor`, which is float64 so that its exactness is not rounded away.
pub fn subset_model(
    model: &BodyModel,
    kept_orig: &[u32],
    faces: &[[u32; 3]],
    config: &SubsetConfig,
) -> Result<(BodyModel, SubsetReport), BodyModelError> {
    check_subset(model, kept_orig, faces)?;
    let kept: Vec<usize> = kept_orig.iter().map(|&v| v as usize).collect();

    let basis = Basis::of(model);
    let rows = solve_joint_regressor(model, &basis, &kept, config);
    let (regressor, joints): (Vec<Vec<f64>>, Vec<JointFit>) = rows.into_iter().unzip();
    let max_residual_m = joints.iter().map(|j| j.residual_m).fold(0.0, f64::max);

    let v_template: Vec<Vec3> = kept.iter().map(|&v| model.v_template[v]).collect();
    let small = TriMesh { positions: v_template.clone(), faces: faces.to_vec() };
    let (extras, landmarks) = move_landmarks(model, &small)?;
    let full_size_extras = full_size_extras(&extras, model.vertex_count(), model.faces.len());

    let mut layout = model.layout.clone();
    layout.dtypes.retain(|(k, _)| k != "J_regressor");
    layout.dtypes.push(("J_regressor".into(), desal_io::npz::Dtype::F64));
    let subset = BodyModel {
        kind: model.kind,
        v_template,
        faces: faces.to_vec(),
        shape_count: model.shape_count,
        shapedirs: gather_rows(&model.shapedirs, 3 * model.shape_count, &kept),
        expression_count: model.expression_count,
        exprdirs: gather_rows(&model.exprdirs, 3 * model.expression_count, &kept),
        posedirs: gather_rows(&model.posedirs, 3 * model.pose_feature_count(), &kept),
        weights: gather_sparse_rows(&model.weights, &kept),
        parents: model.parents.clone(),
        joint_regressor: SparseRows::from_dense(&regressor.concat(), model.joint_count(), kept.len()),
        pose_mean: model.pose_mean.clone(),
        extras,
        layout,
    };
    let report = SubsetReport {
        vertices: kept.len(),
        faces: faces.len(),
        basis_columns: basis.columns,
        joints,
        max_residual_m,
        landmarks,
        full_size_extras,
    };
    Ok((subset, report))
}

/// Kept vertices distinct and in range, faces over the kept vertices.
fn check_subset(model: &BodyModel, kept_orig: &[u32], faces: &[[u32; 3]]) -> Result<(), BodyModelError> {
    let bad = |reason: String| Err(BodyModelError::BadSubset { reason });
    if kept_orig.is_empty() {
        return bad("no vertex is kept".into());
    }
    let mut seen = vec![false; model.vertex_count()];
    for (simp, &orig) in kept_orig.iter().enumerate() {
        match seen.get_mut(orig as usize) {
            None => {
                return bad(format!(
                    "kept vertex {simp} is model vertex {orig}, past the model's {}",
                    model.vertex_count()
                ));
            }
            Some(true) => return bad(format!("model vertex {orig} is kept twice (kept vertex {simp})")),
            Some(s) => *s = true,
        }
    }
    if let Some((f, face)) =
        faces.iter().enumerate().find(|(_, f)| f.iter().any(|&c| c as usize >= kept_orig.len()))
    {
        return bad(format!("face {f} {face:?} names a vertex past the {} kept", kept_orig.len()));
    }
    Ok(())
}

/// The rows `kept` of a row-major array of `width` values per vertex.
fn gather_rows(values: &[f64], width: usize, kept: &[usize]) -> Vec<f64> {
    kept.iter().flat_map(|&v| values[v * width..(v + 1) * width].iter().copied()).collect()
}

fn gather_sparse_rows(rows: &SparseRows, kept: &[usize]) -> SparseRows {
    let mut out = SparseRows { offsets: vec![0], cols: Vec::new(), values: Vec::new() };
    for &v in kept {
        for (c, w) in rows.row(v) {
            out.cols.push(c as u32);
            out.values.push(w);
        }
        out.offsets.push(out.values.len());
    }
    out
}

// ---- the joint regressor ----

/// The basis the joints are regressed from, per vertex and coordinate: the template,
/// then the shape and expression directions (`columns` = 1 + S + E).
struct Basis<'a> {
    model: &'a BodyModel,
    columns: usize,
}

impl<'a> Basis<'a> {
    fn of(model: &'a BodyModel) -> Self {
        Self { model, columns: 1 + model.shape_count + model.expression_count }
    }

    /// Column `k` of vertex `v`, coordinate `axis`; column 0 relative to `origin`.
    fn value(&self, v: usize, axis: usize, k: usize, origin: &Vec3) -> f64 {
        let m = self.model;
        match k {
            0 => m.v_template[v][axis] - origin[axis],
            k if k <= m.shape_count => m.shapedirs[(v * 3 + axis) * m.shape_count + k - 1],
            k => m.exprdirs[(v * 3 + axis) * m.expression_count + k - 1 - m.shape_count],
        }
    }
}

/// Every joint's row over the kept vertices (dense, `simp_idx` order) and its fit;
/// joints in parallel, in joint order.
fn solve_joint_regressor(
    model: &BodyModel,
    basis: &Basis,
    kept: &[usize],
    config: &SubsetConfig,
) -> Vec<(Vec<f64>, JointFit)> {
    let kept_positions: Vec<Vec3> = kept.iter().map(|&v| model.v_template[v]).collect();
    let nearest_kept = VertexIndex::new(&kept_positions);
    let names = model.kind.joint_names();
    (0..model.joint_count())
        .into_par_iter()
        .map(|j| {
            let full: Vec<(usize, f64)> = model.joint_regressor.row(j).collect();
            let (row, mut fit) = solve_joint_row(basis, &full, kept, &kept_positions, &nearest_kept, config);
            fit.joint = names[j].clone();
            (row, fit)
        })
        .collect()
}

/// One joint's row: the prior `w₀` (the full row's weights at the nearest kept vertex),
/// then `w = w₀ + A⁺ (b − A w₀)` on a support that doubles until the residual is under
/// the tolerance (see the module docs).
fn solve_joint_row(
    basis: &Basis,
    full: &[(usize, f64)],
    kept: &[usize],
    kept_positions: &[Vec3],
    nearest_kept: &VertexIndex,
    config: &SubsetConfig,
) -> (Vec<f64>, JointFit) {
    let model = basis.model;
    let row_sum: f64 = full.iter().map(|&(_, w)| w).sum();
    // The joint's rest position: the origin of the template column, and where the
    // support grows from.
    let joint = full.iter().fold(Vec3::zeros(), |acc, &(v, w)| acc + model.v_template[v] * w);
    let origin = if row_sum.abs() > 1e-12 { joint / row_sum } else { joint };

    let mut prior = vec![0.0; kept.len()];
    for &(v, w) in full {
        if let Some((s, _)) = nearest_kept.nearest(&model.v_template[v]) {
            prior[s as usize] += w;
        }
    }
    // The right-hand side: `r · B_full` per (coordinate, column), then the row sum.
    let equations = 3 * basis.columns + 1;
    let mut target = DVector::<f64>::zeros(equations);
    for &(v, w) in full {
        for axis in 0..3 {
            for k in 0..basis.columns {
                target[axis * basis.columns + k] += w * basis.value(v, axis, k, &origin);
            }
        }
    }
    target[equations - 1] = row_sum;

    // Kept vertices by distance from the joint, ties by index.
    let mut by_distance: Vec<usize> = (0..kept.len()).collect();
    let distance = |s: usize| (kept_positions[s] - origin).norm_squared();
    by_distance.sort_by(|&a, &b| distance(a).total_cmp(&distance(b)).then(a.cmp(&b)));

    let mut count = (2 * equations).max(16).min(kept.len());
    loop {
        let mut support: Vec<usize> =
            prior.iter().enumerate().filter(|(_, w)| **w != 0.0).map(|(s, _)| s).collect();
        support.extend_from_slice(&by_distance[..count]);
        support.sort_unstable();
        support.dedup();

        let mut a = DMatrix::<f64>::zeros(equations, support.len());
        for (c, &s) in support.iter().enumerate() {
            for axis in 0..3 {
                for k in 0..basis.columns {
                    a[(axis * basis.columns + k, c)] = basis.value(kept[s], axis, k, &origin);
                }
            }
            a[(equations - 1, c)] = 1.0;
        }
        let w0 = DVector::from_iterator(support.len(), support.iter().map(|&s| prior[s]));
        let gap = &target - &a * &w0;
        let svd = a.clone().svd(true, true);
        let eps = config.rcond * svd.singular_values.max();
        let step = svd.solve(&gap, eps).unwrap_or_else(|_| DVector::zeros(support.len()));
        // Weights a rounding error away from zero are zero: the row stays as sparse as
        // its answer (a change of at most 1e-13 per weight, far under the tolerance).
        let w = (w0 + step).map(|x| if x.abs() <= ZERO_WEIGHT { 0.0 } else { x });
        let misfit = &a * &w - &target;
        let residual_m = misfit.rows(0, equations - 1).amax();

        if residual_m <= config.tolerance || count == kept.len() {
            let mut row = vec![0.0; kept.len()];
            for (&s, &x) in support.iter().zip(w.iter()) {
                row[s] = x;
            }
            let fit = JointFit {
                joint: String::new(),
                support: support.len(),
                nonzeros: row.iter().filter(|x| **x != 0.0).count(),
                full_nonzeros: full.len(),
                residual_m,
                max_abs_weight: row.iter().fold(0.0, |m: f64, x| m.max(x.abs())),
                negative_sum: row.iter().filter(|x| **x < 0.0).sum(),
            };
            return (row, fit);
        }
        count = (2 * count).min(kept.len());
    }
}

// ---- landmarks and the other keys ----

/// A model's extra keys, in file order.
type Extras = Vec<(String, ExtraEntry)>;

/// The extras with every landmark embedding of [`LANDMARK_KEYS`] moved onto `small`
/// (the kept template with the new triangles), and what each moved.
fn move_landmarks(model: &BodyModel, small: &TriMesh) -> Result<(Extras, Vec<LandmarkFit>), BodyModelError> {
    let mut extras = model.extras.clone();
    let mut fits = Vec::new();
    let surface = SurfaceIndex::new(small);
    for (faces_key, bary_key) in LANDMARK_KEYS {
        let (Some(fi), Some(bi)) =
            (extras.iter().position(|(k, _)| k == faces_key), extras.iter().position(|(k, _)| k == bary_key))
        else {
            continue;
        };
        let bad = |key: &str, reason: String| BodyModelError::BadKey {
            path: "<model>".into(),
            key: key.to_owned(),
            reason,
        };
        let face_array = extra_array(&extras[fi].1).map_err(|e| bad(faces_key, e))?;
        let bary_array = extra_array(&extras[bi].1).map_err(|e| bad(bary_key, e))?;
        let face_ids = face_array.data.to_i64().ok_or_else(|| {
            bad(faces_key, format!("holds {}, not face indices", face_array.data.type_name()))
        })?;
        let bary = bary_array.data.to_f64().ok_or_else(|| {
            bad(bary_key, format!("holds {}, not coordinates", bary_array.data.type_name()))
        })?;
        if bary.len() != 3 * face_ids.len() {
            return Err(bad(
                bary_key,
                format!(
                    "holds {} values for the {} landmarks of '{faces_key}' (3 each)",
                    bary.len(),
                    face_ids.len()
                ),
            ));
        }
        let mut new_faces = Vec::with_capacity(face_ids.len());
        let mut new_bary = Vec::with_capacity(bary.len());
        let mut moved = Vec::with_capacity(face_ids.len());
        for (l, (&f, b)) in face_ids.iter().zip(bary.chunks_exact(3)).enumerate() {
            let face = usize::try_from(f).ok().and_then(|f| model.faces.get(f)).ok_or_else(|| {
                bad(faces_key, format!("landmark {l} names face {f}, past the model's {}", model.faces.len()))
            })?;
            let p = face
                .iter()
                .zip(b)
                .fold(Vec3::zeros(), |acc, (&v, &w)| acc + model.v_template[v as usize] * w);
            let (nearest, _) = surface.nearest(&p).ok_or(BodyModelError::BadSubset {
                reason: "the simplified template has no faces to put landmarks on".into(),
            })?;
            let [a, b2, c] = small.corners(nearest as usize);
            let q = closest_point_on_triangle(&p, &a, &b2, &c);
            new_faces.push(f64::from(nearest));
            new_bary.extend(barycentric(&q, &a, &b2, &c));
            moved.push((q - p).norm());
        }
        let fit = LandmarkFit {
            key: faces_key.to_owned(),
            landmarks: moved.len(),
            moved_mean_m: moved.iter().sum::<f64>() / moved.len().max(1) as f64,
            moved_max_m: moved.iter().copied().fold(0.0, f64::max),
        };
        let retyped = |like: &AnyArray, values: &[f64]| AnyArray {
            shape: like.shape.clone(),
            data: AnyData::from_f64(like.data.dtype().unwrap_or(desal_io::npz::Dtype::F64), values),
        };
        extras[fi].1 = ExtraEntry::Array(retyped(&face_array, &new_faces));
        extras[bi].1 = ExtraEntry::Array(retyped(&bary_array, &new_bary));
        fits.push(fit);
    }
    Ok((extras, fits))
}

/// The array an extra holds: an npz entry parsed, a pickle's array, a chumpy object's.
pub(crate) fn extra_array(entry: &ExtraEntry) -> Result<AnyArray, String> {
    match entry {
        ExtraEntry::Npy(bytes) => decode_npy_any(bytes),
        ExtraEntry::Array(a) => Ok(a.clone()),
        ExtraEntry::Pickled(value) => crate::read::pickled_array(value),
    }
}

/// Barycentric coordinates of `q` (on the triangle's plane) in triangle `(a, b, c)`;
/// a degenerate triangle gives its first corner.
fn barycentric(q: &Vec3, a: &Vec3, b: &Vec3, c: &Vec3) -> [f64; 3] {
    let (e0, e1, d) = (b - a, c - a, q - a);
    let (d00, d01, d11) = (e0.dot(&e0), e0.dot(&e1), e1.dot(&e1));
    let (d20, d21) = (d.dot(&e0), d.dot(&e1));
    let denom = d00 * d11 - d01 * d01;
    if denom.abs() <= f64::EPSILON * d00 * d11 {
        return [1.0, 0.0, 0.0];
    }
    let v = (d11 * d20 - d01 * d21) / denom;
    let w = (d00 * d21 - d01 * d20) / denom;
    [1.0 - v - w, v, w]
}

/// The extras with an axis `vertices` or `faces` long (and longer than 3, so that no
/// coordinate axis of a tiny model counts): per-vertex or per-face arrays such as SMPL
/// 1.0's `weights_prior` `(V, J)` and `J_regressor_prior` `(J, V)`, SMPL-X's `ft`.
fn full_size_extras(extras: &[(String, ExtraEntry)], vertices: usize, faces: usize) -> Vec<String> {
    extras
        .iter()
        .filter(|(_, e)| {
            extra_array(e).is_ok_and(|a| a.shape.iter().any(|&n| n > 3 && (n == vertices || n == faces)))
        })
        .map(|(k, _)| k.clone())
        .collect()
}
