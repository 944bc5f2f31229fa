//! The pose-fitted upsampler: each fine vertex's row of U is fitted by least squares
//! over the training poses, so that the weighted coarse vertices land where the fine
//! vertex is in every pose, not only in the template.
//!
//! For fine vertex `i` with candidate coarse vertices `j ∈ N(i)` (its `k` nearest in the
//! template pose — straight-line by default, or along the fine mesh's edges, see
//! [`Neighbourhood`] — plus
//! the corners of its barycentric row `b`), training poses `P`, and
//! `d_jp = c_jp − x_ip` (coarse vertex `j` relative to the fine vertex, in pose `p`):
//!
//! ```text
//! min_w  (1/|P|) Σ_p ‖Σ_j w_j d_jp‖²  +  λ ‖w − b‖²     subject to  Σ_j w_j = 1
//! ```
//!
//! Because the row sums to 1, `Σ_j w_j c_jp − x_ip = Σ_j w_j d_jp`: the residual is
//! translation-free per pose, and working in offsets keeps the system well scaled. With
//! `G = (1/|P|) Σ_p D_pᵀD_p` and `λ = ridge · trace(G)/m` (the ridge is relative to the
//! mean squared offset, so one value serves every level), the KKT conditions are
//! `(G + λI) w = λ b − ν 1` with `ν` fixed by `Σ w = 1`: one Cholesky and two solves.
//! With `ridge = 0` (or a failed factorisation) the constraint is eliminated instead with
//! an orthonormal basis `N` of `{z : Σ z = 0}` (the last `m − 1` columns of the
//! Householder reflection taking `e_0` to `1/√m`), `w = b + N y`, and
//! `(NᵀGN + λI) y = −NᵀG b` is solved by pseudo-inverse (eigenvalues below `1e-12` of the
//! largest dropped): the least-squares row nearest to `b`, which reproduces training
//! poses exactly when they are affine images of the template and the candidates span 3D.
//!
//! A fine vertex that *is* a coarse vertex gets weight 1 on itself (its exact answer).

use desal_mesh::{PoseSet, Real, Vec3};
use rayon::prelude::*;

use crate::barycentric::Row;
use crate::geodesic::{EdgeGraph, Scratch, nearest_marked};
use crate::knn::PointGrid;

/// Dense small matrices for the per-row solves (a few to a few dozen unknowns).
type Dense = nalgebra::DMatrix<Real>;
type DenseVec = nalgebra::DVector<Real>;

/// How "nearest" candidates are found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Neighbourhood {
    /// Straight-line distance in the template pose (a uniform grid). The default: on
    /// SCAPE within 0.003 of geodesic candidates in held-out error ratio, and 30 % faster.
    #[default]
    Euclidean,
    /// Shortest paths along the fine mesh's edges in the template pose (Dijkstra): never
    /// reaches across a gap to another body part.
    Geodesic,
}

/// The fitted upsampler's knobs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FittedConfig {
    /// How many nearest coarse vertices (template pose) each fine vertex may use, before
    /// the barycentric corners are added. Default [`DEFAULT_NEIGHBOURS`] (see the crate
    /// docs for the held-out curve that chose it).
    pub neighbours: usize,
    /// How nearness is measured. Default [`Neighbourhood::Euclidean`].
    pub neighbourhood: Neighbourhood,
    /// Ridge toward the barycentric row, relative to the mean squared offset of the
    /// candidates (dimensionless, `>= 0`). Default [`DEFAULT_RIDGE`].
    pub ridge: Real,
}

impl Default for FittedConfig {
    fn default() -> Self {
        Self { neighbours: DEFAULT_NEIGHBOURS, neighbourhood: Neighbourhood::default(), ridge: DEFAULT_RIDGE }
    }
}

/// Default neighbour count, chosen on SCAPE by held-out error (crate docs).
pub const DEFAULT_NEIGHBOURS: usize = 16;
/// Default relative ridge, chosen on SCAPE by held-out error (crate docs).
pub const DEFAULT_RIDGE: Real = 3e-3;

/// Counts of how rows were solved, for the report.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FitCounts {
    /// Fine vertices that are coarse vertices: weight 1 on themselves.
    pub exact_rows: usize,
    /// Rows solved by Cholesky (`λ > 0`).
    pub cholesky_rows: usize,
    /// Rows solved by pseudo-inverse (`λ = 0`, or a Cholesky that failed).
    pub pseudo_inverse_rows: usize,
}

/// Fits every fine vertex's row. `barycentric[i]` is fine vertex `i`'s barycentric row,
/// `coarse_to_fine[coarse_idx]` its fine vertex, `training` the pose indices to fit on
/// (non-empty). Rows are in `fine_idx` order, entries `(coarse_idx, weight)`.
pub fn fitted_rows(
    fine: &PoseSet,
    coarse_to_fine: &[u32],
    barycentric: &[Row],
    training: &[usize],
    config: &FittedConfig,
) -> (Vec<Row>, FitCounts) {
    debug_assert!(!training.is_empty());
    let template = fine.template_positions();
    let coarse_template: Vec<Vec3> = coarse_to_fine.iter().map(|&f| template[f as usize]).collect();
    let search = match config.neighbourhood {
        Neighbourhood::Euclidean => Search::Grid(PointGrid::new(&coarse_template)),
        Neighbourhood::Geodesic => Search::Graph(EdgeGraph::new(template, &fine.faces)),
    };
    let mut fine_to_coarse = vec![u32::MAX; fine.vertex_count()];
    for (coarse_idx, &fine_idx) in coarse_to_fine.iter().enumerate() {
        fine_to_coarse[fine_idx as usize] = coarse_idx as u32;
    }

    let trajectories = Trajectories::new(fine, training);
    let solved: Vec<(Row, Solve)> = (0..fine.vertex_count())
        .into_par_iter()
        .map_init(
            || Scratch::new(fine.vertex_count()),
            |scratch, fine_idx| {
                if fine_to_coarse[fine_idx] != u32::MAX {
                    return (vec![(fine_to_coarse[fine_idx], 1.0)], Solve::Exact);
                }
                let nearest = match &search {
                    Search::Grid(grid) => grid
                        .nearest(&template[fine_idx], config.neighbours)
                        .into_iter()
                        .map(|(j, _)| j)
                        .collect(),
                    Search::Graph(graph) => {
                        nearest_marked(graph, &fine_to_coarse, fine_idx as u32, config.neighbours, scratch)
                    }
                };
                let candidates = candidates(nearest, &barycentric[fine_idx]);
                fit_row(
                    &trajectories,
                    coarse_to_fine,
                    fine_idx,
                    &candidates,
                    &barycentric[fine_idx],
                    config.ridge,
                )
            },
        )
        .collect();

    let mut counts = FitCounts::default();
    let rows = solved
        .into_iter()
        .map(|(row, how)| {
            match how {
                Solve::Exact => counts.exact_rows += 1,
                Solve::Cholesky => counts.cholesky_rows += 1,
                Solve::PseudoInverse => counts.pseudo_inverse_rows += 1,
            }
            row
        })
        .collect();
    (rows, counts)
}

/// Every fine vertex's coordinates over the training poses, vertex-major
/// (`[x, y, z]` per pose): a row's solve reads its candidates' blocks contiguously instead
/// of striding across one array per pose.
struct Trajectories {
    poses: usize,
    coords: Vec<Real>,
}

impl Trajectories {
    fn new(fine: &PoseSet, training: &[usize]) -> Self {
        let width = 3 * training.len();
        let mut coords = vec![0.0; fine.vertex_count() * width];
        coords.par_chunks_mut(width).enumerate().for_each(|(v, block)| {
            for (slot, &p) in block.chunks_exact_mut(3).zip(training) {
                let q = fine.poses[p][v];
                slot.copy_from_slice(&[q.x, q.y, q.z]);
            }
        });
        Self { poses: training.len(), coords }
    }

    fn of(&self, vertex: usize) -> &[Real] {
        let width = 3 * self.poses;
        &self.coords[vertex * width..(vertex + 1) * width]
    }
}

enum Search {
    Grid(PointGrid),
    Graph(EdgeGraph),
}

#[derive(Debug, Clone, Copy)]
enum Solve {
    Exact,
    Cholesky,
    PseudoInverse,
}

/// The nearest coarse vertices plus the barycentric corners, sorted by `coarse_idx`.
fn candidates(mut c: Vec<u32>, barycentric: &Row) -> Vec<u32> {
    c.extend(barycentric.iter().map(|&(j, _)| j));
    c.sort_unstable();
    c.dedup();
    c
}

/// Solves one fine vertex's constrained ridge least squares (module docs).
fn fit_row(
    trajectories: &Trajectories,
    coarse_to_fine: &[u32],
    fine_idx: usize,
    candidates: &[u32],
    barycentric: &Row,
    ridge: Real,
) -> (Row, Solve) {
    let m = candidates.len();
    let b = DenseVec::from_iterator(
        m,
        candidates.iter().map(|j| barycentric.iter().find(|(c, _)| c == j).map_or(0.0, |&(_, w)| w)),
    );
    if m == 1 {
        return (vec![(candidates[0], 1.0)], Solve::Exact);
    }

    // G = (1/|P|) DᵀD, with D the 3|P| × m offsets of the candidates from the vertex
    // over the training poses (column j: candidate j's trajectory minus the vertex's).
    let own = trajectories.of(fine_idx);
    let mut d = Dense::zeros(own.len(), m);
    // Column-major storage: column j is one contiguous run (plain slices, which the
    // compiler vectorises, where the matrix's column iterators cost ~20 instructions
    // an entry).
    for (column, &c) in d.as_mut_slice().chunks_exact_mut(own.len()).zip(candidates) {
        let theirs = trajectories.of(coarse_to_fine[c as usize] as usize);
        for ((out, t), o) in column.iter_mut().zip(theirs).zip(own) {
            *out = t - o;
        }
    }
    let g = gram(&d, trajectories.poses as Real);
    let lambda = ridge * g.trace() / m as Real;
    let w = match solve_kkt(&g, &b, lambda) {
        Some(w) => (w, Solve::Cholesky),
        None => {
            let n = sum_free_basis(m);
            let reduced = n.transpose() * &g * &n;
            let rhs = -(n.transpose() * (&g * &b));
            (&b + n * pseudo_inverse_solve(reduced, rhs, lambda), Solve::PseudoInverse)
        }
    };
    let (w, how) = w;
    let row =
        candidates.iter().zip(w.iter()).filter(|&(_, &wj)| wj != 0.0).map(|(&j, &wj)| (j, wj)).collect();
    (row, how)
}

/// `DᵀD / scale`, upper half computed and mirrored, each entry a dot product of two
/// contiguous columns with four accumulators (a fixed summation order, so the result
/// does not depend on the machine's vector width).
fn gram(d: &Dense, scale: Real) -> Dense {
    let (rows, m) = d.shape();
    let columns: Vec<&[Real]> = d.as_slice().chunks_exact(rows).collect();
    let mut g = Dense::zeros(m, m);
    for r in 0..m {
        for c in r..m {
            let v = dot(columns[r], columns[c]) / scale;
            g[(r, c)] = v;
            g[(c, r)] = v;
        }
    }
    g
}

fn dot(a: &[Real], b: &[Real]) -> Real {
    let mut acc = [0.0; 4];
    let (a4, b4) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: Real = a4.remainder().iter().zip(b4.remainder()).map(|(x, y)| x * y).sum();
    for (x, y) in a4.zip(b4) {
        // Fixed-size lanes: no bounds checks in the loop, the same four sums in the
        // same order.
        let (x, y): (&[Real; 4], &[Real; 4]) =
            (x.try_into().expect("a chunk of 4"), y.try_into().expect("a chunk of 4"));
        for k in 0..4 {
            acc[k] += x[k] * y[k];
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// The constrained ridge problem through its KKT conditions when `λ > 0`:
/// `(G + λI) w = λ b − ν 1` with `ν` chosen so that `Σ w = 1`; one Cholesky, two
/// solves. `None` when `λ = 0` or the factorisation fails (then the caller uses the
/// pseudo-inverse on the reduced system).
fn solve_kkt(g: &Dense, b: &DenseVec, lambda: Real) -> Option<DenseVec> {
    if lambda <= 0.0 {
        return None;
    }
    let mut shifted = g.clone();
    for i in 0..shifted.nrows() {
        shifted[(i, i)] += lambda;
    }
    let chol = shifted.cholesky()?;
    let a = chol.solve(&(b * lambda));
    let e = chol.solve(&DenseVec::from_element(b.len(), 1.0));
    let nu = (a.sum() - 1.0) / e.sum();
    Some(a - e * nu)
}

/// The last `m − 1` columns of the Householder reflection `H = I − 2uuᵀ/uᵀu` with
/// `u = 1/√m − e_0`: `H e_0 = 1/√m`, so the other columns are an orthonormal basis of
/// the vectors summing to 0.
fn sum_free_basis(m: usize) -> Dense {
    let s = 1.0 / (m as Real).sqrt();
    let mut u = DenseVec::from_element(m, s);
    u[0] -= 1.0;
    let h = Dense::identity(m, m) - (&u * u.transpose()) * (2.0 / u.norm_squared());
    h.columns(1, m - 1).into_owned()
}

/// `(A + λI) y = r` for symmetric positive semi-definite `A` by pseudo-inverse: eigen
/// directions with `σ + λ` below `1e-12` of the largest eigenvalue are dropped.
fn pseudo_inverse_solve(a: Dense, r: DenseVec, lambda: Real) -> DenseVec {
    let eigen = a.symmetric_eigen();
    let largest = eigen.eigenvalues.iter().fold(0.0, |m: Real, &v| m.max(v));
    let mut y = DenseVec::zeros(r.len());
    for (k, &value) in eigen.eigenvalues.iter().enumerate() {
        let shifted = value + lambda;
        if shifted > 1e-12 * largest.max(Real::MIN_POSITIVE) {
            let u = eigen.eigenvectors.column(k);
            y += u * (u.dot(&r) / shifted);
        }
    }
    y
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The basis is orthonormal and every column sums to 0, for several sizes.
    #[test]
    fn sum_free_basis_is_orthonormal_and_sum_free() {
        for m in 2..8 {
            let n = sum_free_basis(m);
            let gram = n.transpose() * &n;
            assert!((gram - Dense::identity(m - 1, m - 1)).norm() < 1e-14, "m = {m}");
            for c in 0..m - 1 {
                assert!(n.column(c).sum().abs() < 1e-14, "m = {m}, column {c}");
            }
        }
    }
}
