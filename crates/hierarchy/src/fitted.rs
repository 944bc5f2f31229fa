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

/// Fits every fine vertex's row once per training set: `barycentric[i]` is fine vertex
/// `i`'s barycentric row, `coarse_to_fine[coarse_idx]` its fine vertex, `trainings[k]`
/// the pose indices of set `k` (each non-empty). One result per set, in order, its rows
/// in `fine_idx` order with entries `(coarse_idx, weight)`. Held-out evaluation needs one
/// upsampler per fold, so what does not depend on the poses is done once per fine vertex
/// (its candidates), and each set's `DᵀD` is summed from partial sums over groups of
/// poses (the poses that the same sets hold), each computed once: for the folds of a
/// cross-validation that is the work of one fit over every pose instead of one per fold.
/// A set's rows equal those of a fit on that set alone up to the rounding of that sum
/// (one set is one group: bit for bit).
pub fn fitted_rows_per_training(
    fine: &PoseSet,
    coarse_to_fine: &[u32],
    barycentric: &[Row],
    trainings: &[&[usize]],
    config: &FittedConfig,
) -> Vec<(Vec<Row>, FitCounts)> {
    debug_assert!(trainings.iter().all(|t| !t.is_empty()));
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

    let groups = PoseGroups::new(trainings);
    let trajectories = Trajectories::new(fine, coarse_to_fine, &groups.poses);
    let solved: Vec<Vec<(Row, Solve)>> = (0..fine.vertex_count())
        .into_par_iter()
        .map_init(
            || Scratch::new(fine.vertex_count()),
            |scratch, fine_idx| {
                if fine_to_coarse[fine_idx] != u32::MAX {
                    return vec![(vec![(fine_to_coarse[fine_idx], 1.0)], Solve::Exact); trainings.len()];
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
                let own = trajectories.gather(fine, fine_idx);
                let row = FineRow { own: &own, candidates: &candidates, barycentric: &barycentric[fine_idx] };
                fit_rows(&trajectories, &groups, &row, config.ridge)
            },
        )
        .collect();

    let mut out: Vec<(Vec<Row>, FitCounts)> =
        trainings.iter().map(|_| (Vec::with_capacity(solved.len()), FitCounts::default())).collect();
    for per_set in solved {
        for ((rows, counts), (row, how)) in out.iter_mut().zip(per_set) {
            match how {
                Solve::Exact => counts.exact_rows += 1,
                Solve::Cholesky => counts.cholesky_rows += 1,
                Solve::PseudoInverse => counts.pseudo_inverse_rows += 1,
            }
            rows.push(row);
        }
    }
    out
}

/// The poses of several training sets, grouped by which sets hold them: a set's `DᵀD`
/// is the sum of its groups' partial sums. Poses keep the order in which the sets list
/// them (first listing first), so one set is one group in its own order.
struct PoseGroups {
    /// Every listed pose once, group by group.
    poses: Vec<usize>,
    /// Group `g` is `poses[bounds[g]..bounds[g + 1]]`.
    bounds: Vec<usize>,
    /// Per training set: its groups, ascending, and its pose count.
    members: Vec<(Vec<usize>, usize)>,
}

impl PoseGroups {
    fn new(trainings: &[&[usize]]) -> Self {
        let mut listed: Vec<usize> = Vec::new();
        for &p in trainings.iter().flat_map(|t| t.iter()) {
            if !listed.contains(&p) {
                listed.push(p);
            }
        }
        let holders = |p: usize| -> Vec<bool> { trainings.iter().map(|t| t.contains(&p)).collect() };
        // Groups in the order of their first pose, each listing its poses in order.
        let mut signatures: Vec<Vec<bool>> = Vec::new();
        let mut grouped: Vec<Vec<usize>> = Vec::new();
        for &p in &listed {
            let signature = holders(p);
            match signatures.iter().position(|s| *s == signature) {
                Some(g) => grouped[g].push(p),
                None => {
                    signatures.push(signature);
                    grouped.push(vec![p]);
                }
            }
        }
        let mut bounds = vec![0];
        for g in &grouped {
            bounds.push(bounds.last().expect("starts at 0") + g.len());
        }
        let members = (0..trainings.len())
            .map(|set| {
                let groups: Vec<usize> = (0..grouped.len()).filter(|&g| signatures[g][set]).collect();
                let poses = groups.iter().map(|&g| grouped[g].len()).sum();
                (groups, poses)
            })
            .collect();
        Self { poses: grouped.concat(), bounds, members }
    }
}

/// The coarse vertices' coordinates over the given poses, vertex-major (`[x, y, z]` per
/// pose): a row's solve reads its candidates' blocks contiguously instead of striding
/// across one array per pose. Only the coarse vertices are held (a fifth of the fine
/// ones or fewer): every fine vertex's own trajectory is read once, by its own row
/// ([`Trajectories::gather`]), so a copy of the whole pose set is never made.
struct Trajectories {
    poses: Vec<usize>,
    coords: Vec<Real>,
}

impl Trajectories {
    fn new(fine: &PoseSet, coarse_to_fine: &[u32], poses: &[usize]) -> Self {
        let width = 3 * poses.len();
        let mut coords = vec![0.0; coarse_to_fine.len() * width];
        coords.par_chunks_mut(width).zip(coarse_to_fine).for_each(|(block, &fine_idx)| {
            Self::fill(fine, fine_idx as usize, poses, block);
        });
        Self { poses: poses.to_vec(), coords }
    }

    /// Fine vertex `fine_idx`'s coordinates over the poses into `block` (`3 × poses`).
    fn fill(fine: &PoseSet, fine_idx: usize, poses: &[usize], block: &mut [Real]) {
        for (slot, &p) in block.chunks_exact_mut(3).zip(poses) {
            let q = fine.poses[p][fine_idx];
            slot.copy_from_slice(&[q.x, q.y, q.z]);
        }
    }

    /// Coarse vertex `coarse_idx`'s trajectory.
    fn of(&self, coarse_idx: usize) -> &[Real] {
        let width = 3 * self.poses.len();
        &self.coords[coarse_idx * width..(coarse_idx + 1) * width]
    }

    /// Fine vertex `fine_idx`'s trajectory over the same poses, laid out as [`Self::of`]'s.
    fn gather(&self, fine: &PoseSet, fine_idx: usize) -> Vec<Real> {
        let mut block = vec![0.0; 3 * self.poses.len()];
        Self::fill(fine, fine_idx, &self.poses, &mut block);
        block
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

/// One fine vertex to fit: its trajectory (laid out as the candidates'), its candidates
/// (ascending `coarse_idx`) and barycentric row.
struct FineRow<'a> {
    own: &'a [Real],
    candidates: &'a [u32],
    barycentric: &'a Row,
}

/// Solves one fine vertex's constrained ridge least squares (module docs) once per
/// training set of `groups`, in order.
fn fit_rows(
    trajectories: &Trajectories,
    groups: &PoseGroups,
    row: &FineRow,
    ridge: Real,
) -> Vec<(Row, Solve)> {
    let candidates = row.candidates;
    let m = candidates.len();
    if m == 1 {
        return vec![(vec![(candidates[0], 1.0)], Solve::Exact); groups.members.len()];
    }
    let b = DenseVec::from_iterator(
        m,
        candidates.iter().map(|j| row.barycentric.iter().find(|(c, _)| c == j).map_or(0.0, |&(_, w)| w)),
    );

    // G = (1/|P|) DᵀD, with D the 3|P| × m offsets of the candidates from the vertex
    // over the training poses (column j: candidate j's trajectory minus the vertex's),
    // here over every group's poses, column by column: plain slices, which the compiler
    // vectorises (the matrix's column iterators cost ~20 instructions an entry), and no
    // zero fill first.
    let own = row.own;
    let mut d: Vec<Real> = Vec::with_capacity(own.len() * m);
    for &c in candidates {
        let theirs = trajectories.of(c as usize);
        d.extend(theirs.iter().zip(own).map(|(t, o)| t - o));
    }
    let columns: Vec<&[Real]> = d.chunks_exact(own.len()).collect();
    let partial: Vec<Vec<Real>> =
        groups.bounds.windows(2).map(|poses| upper_gram(&columns, 3 * poses[0]..3 * poses[1])).collect();
    groups
        .members
        .iter()
        .map(|(members, poses)| {
            let g = summed_gram(&partial, members, m, *poses as Real);
            solve_row(&g, &b, ridge, candidates)
        })
        .collect()
}

/// The row of `candidates` from `G` and the barycentric weights `b`.
fn solve_row(g: &Dense, b: &DenseVec, ridge: Real, candidates: &[u32]) -> (Row, Solve) {
    let m = candidates.len();
    let lambda = ridge * g.trace() / m as Real;
    let (w, how) = match solve_kkt(g, b, lambda) {
        Some(w) => (w, Solve::Cholesky),
        None => {
            let n = sum_free_basis(m);
            let reduced = n.transpose() * g * &n;
            let rhs = -(n.transpose() * (g * b));
            (b + n * pseudo_inverse_solve(reduced, rhs, lambda), Solve::PseudoInverse)
        }
    };
    let row =
        candidates.iter().zip(w.iter()).filter(|&(_, &wj)| wj != 0.0).map(|(&j, &wj)| (j, wj)).collect();
    (row, how)
}

/// The upper half of `DᵀD` over the rows `rows` of `D`'s columns, row-major `m × m`
/// (the lower half left 0): each entry a dot product of two contiguous runs with four
/// accumulators (a fixed summation order, so the result does not depend on the
/// machine's vector width).
fn upper_gram(columns: &[&[Real]], rows: std::ops::Range<usize>) -> Vec<Real> {
    let m = columns.len();
    let mut g = vec![0.0; m * m];
    for r in 0..m {
        for c in r..m {
            g[r * m + c] = dot(&columns[r][rows.clone()], &columns[c][rows.clone()]);
        }
    }
    g
}

/// `(Σ_{g ∈ members} partial[g]) / scale`, mirrored: the groups summed in order, the
/// first taken as it is (so one group is its own sum, bit for bit).
fn summed_gram(partial: &[Vec<Real>], members: &[usize], m: usize, scale: Real) -> Dense {
    let mut g = Dense::zeros(m, m);
    for r in 0..m {
        for c in r..m {
            let k = r * m + c;
            let mut sum = partial[members[0]][k];
            for &group in &members[1..] {
                sum += partial[group][k];
            }
            let v = sum / scale;
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
