//! The pose-fitted upsampler: each fine vertex's row of U is fitted by least squares
//! over the training poses, so that the weighted coarse vertices land where the fine
//! vertex is in every pose, not only in the template.
//!
//! For fine vertex `i` with candidate coarse vertices `j ∈ N(i)` (its `k` nearest in the
//! template pose — along the fine mesh's edges by default, see [`Neighbourhood`] — plus
//! the corners of its barycentric row `b`), training poses `P`, and
//! `d_jp = c_jp − x_ip` (coarse vertex `j` relative to the fine vertex, in pose `p`):
//!
//! ```text
//! min_w  (1/|P|) Σ_p ‖Σ_j w_j d_jp‖²  +  λ ‖w − b‖²     subject to  Σ_j w_j = 1
//! ```
//!
//! Because the row sums to 1, `Σ_j w_j c_jp − x_ip = Σ_j w_j d_jp`: the residual is
//! translation-free per pose, and working in offsets keeps the system well scaled. The
//! constraint is eliminated with an orthonormal basis `N` of `{z : Σ z = 0}` (the last
//! `m − 1` columns of the Householder reflection taking `e_0` to `1/√m`), `w = b + N y`,
//! leaving the `(m − 1)²` system `(NᵀGN + λI) y = −NᵀG b`, with `G = (1/|P|) Σ_p D_pᵀD_p`.
//! `λ = ridge · trace(G)/m`: the ridge is relative to the mean squared offset, so one
//! value serves every level. With `ridge = 0` the system is solved by pseudo-inverse
//! (eigenvalues below `1e-12` of the largest dropped): the least-squares row nearest
//! to `b`, which reproduces training poses exactly when they are affine images of the
//! template and the candidates span 3D.
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
    /// Shortest paths along the fine mesh's edges in the template pose (Dijkstra).
    #[default]
    Geodesic,
    /// Straight-line distance in the template pose.
    Euclidean,
}

/// The fitted upsampler's knobs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FittedConfig {
    /// How many nearest coarse vertices (template pose) each fine vertex may use, before
    /// the barycentric corners are added. Default [`DEFAULT_NEIGHBOURS`] (see the crate
    /// docs for the held-out curve that chose it).
    pub neighbours: usize,
    /// How nearness is measured. Default [`Neighbourhood::Geodesic`].
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
                    fine,
                    coarse_to_fine,
                    fine_idx,
                    &candidates,
                    &barycentric[fine_idx],
                    training,
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
    fine: &PoseSet,
    coarse_to_fine: &[u32],
    fine_idx: usize,
    candidates: &[u32],
    barycentric: &Row,
    training: &[usize],
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

    // G = (1/|P|) Σ_p D_pᵀ D_p, D_p the 3 × m offsets of the candidates from the vertex.
    let mut g = Dense::zeros(m, m);
    let mut offsets = vec![Vec3::zeros(); m];
    for &p in training {
        let pose = &fine.poses[p];
        let x = pose[fine_idx];
        for (o, &j) in offsets.iter_mut().zip(candidates) {
            *o = pose[coarse_to_fine[j as usize] as usize] - x;
        }
        for r in 0..m {
            for c in r..m {
                g[(r, c)] += offsets[r].dot(&offsets[c]);
            }
        }
    }
    for r in 0..m {
        for c in r..m {
            let v = g[(r, c)] / training.len() as Real;
            g[(r, c)] = v;
            g[(c, r)] = v;
        }
    }

    let n = sum_free_basis(m);
    let reduced = n.transpose() * &g * &n;
    let rhs = -(n.transpose() * (&g * &b));
    let lambda = ridge * g.trace() / m as Real;
    let (y, how) = solve_ridge(reduced, rhs, lambda);
    let w = b + n * y;
    let row =
        candidates.iter().zip(w.iter()).filter(|&(_, &wj)| wj != 0.0).map(|(&j, &wj)| (j, wj)).collect();
    (row, how)
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

/// `(A + λI) y = r` for symmetric positive semi-definite `A`: Cholesky when `λ > 0`,
/// else (or when Cholesky fails) the pseudo-inverse with relative cut-off 1e-12.
fn solve_ridge(a: Dense, r: DenseVec, lambda: Real) -> (DenseVec, Solve) {
    if lambda > 0.0 {
        let mut shifted = a.clone();
        for i in 0..shifted.nrows() {
            shifted[(i, i)] += lambda;
        }
        if let Some(chol) = shifted.cholesky() {
            return (chol.solve(&r), Solve::Cholesky);
        }
    }
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
    (y, Solve::PseudoInverse)
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
