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
//!
//! ## Choosing the knobs
//!
//! How many neighbours and how much ridge a level needs depends on how many poses and
//! people it is fitted on: one split of SCAPE's 71 poses of one man chose 16 neighbours
//! and ridge 3e-3 (the crate docs' table), while 144 ANNY samples of 24 people want 32
//! and 1e-5, and SCAPE's own five folds now pick 32 and 1e-3 (level 1) or 3e-4 (level 2),
//! 2.6 % and 7.4 % below 16 and 3e-3 in held-out error (`desal run
//! pipelines/scape-hierarchy.toml`, each step's `knobs.grid` in `hierarchy.json`). So by default
//! ([`Knob::HeldOut`]) each fit chooses them on its own training poses:
//!
//! 1. the training poses are dealt into [`TUNING_FOLDS`] folds, whole groups at a time
//!    when the pose set has groups (people), by pose otherwise; the template's group
//!    always trains;
//! 2. for [`TUNING_ROWS`] fine vertices, strided evenly over those that are not coarse
//!    vertices, every grid point ([`NEIGHBOUR_GRID`] × [`RIDGE_GRID`]) is fitted on each
//!    fold's other poses and its squared error summed on the fold's own: from the sums
//!    of `DᵀD` per group of poses, `eᵀ = wᵀ G_fold w`, so a grid point costs small solves,
//!    not passes over the poses (the widest candidate set's sums serve every narrower
//!    one, whose candidates are a subset);
//! 3. the grid point with the lowest summed error is the fit's; every row is then fitted
//!    with it on all the training poses. Fewer than two folds: [`FALLBACK_NEIGHBOURS`]
//!    and [`FALLBACK_RIDGE`].
//!
//! Each training set chooses from its own poses only, so a held-out fold's U never saw
//! the fold even through its knobs. The choice is deterministic (rows summed in order).
//! Measured on ANNY (`pytest -s crates/python/tests/test_anny.py`, unseen people, the
//! same levels), the held-out choice took the level-2 error from 0.059 (at 7445de0) to
//! 0.036 of COMA's barycentric U's, and level 1's from 0.0059 to 0.0030 (at 0390460;
//! `desal-upsample` then keeps its better run and reaches 0.0016 and 0.030);
//! `hierarchy.json`'s own held-out figures, over whole shapes, agree with the unseen ones
//! within 25 % (the test asserts it).

use desal_mesh::{PoseSet, Real, Vec3};
use rayon::prelude::*;

use crate::barycentric::Row;
use crate::geodesic::{EdgeGraph, Scratch, nearest_marked};
use crate::knn::PointGrid;
use crate::sparse::{CsrBuilder, CsrMatrix};

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

/// A setting of the fitted upsampler: a given value, or one chosen per fit by the
/// held-out error of that fit's own training poses (module docs, "Choosing the knobs").
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Knob<T> {
    /// This value, for every fit.
    Given(T),
    /// The value of its grid ([`NEIGHBOUR_GRID`], [`RIDGE_GRID`]) with the lowest
    /// held-out error.
    HeldOut,
}

impl<T: Copy> Knob<T> {
    /// The values to try: the given one, or the whole grid.
    fn values(&self, grid: &[T]) -> Vec<T> {
        match self {
            Knob::Given(v) => vec![*v],
            Knob::HeldOut => grid.to_vec(),
        }
    }

    /// The given value, or `fallback`.
    fn or(&self, fallback: T) -> T {
        match self {
            Knob::Given(v) => *v,
            Knob::HeldOut => fallback,
        }
    }
}

/// The fitted upsampler's knobs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FittedConfig {
    /// How many nearest coarse vertices (template pose) each fine vertex may use, before
    /// the barycentric corners are added. Default: chosen from [`NEIGHBOUR_GRID`].
    pub neighbours: Knob<usize>,
    /// How nearness is measured. Default [`Neighbourhood::Euclidean`].
    pub neighbourhood: Neighbourhood,
    /// Ridge toward the barycentric row, relative to the mean squared offset of the
    /// candidates (dimensionless, `>= 0`). Default: chosen from [`RIDGE_GRID`].
    pub ridge: Knob<Real>,
}

impl Default for FittedConfig {
    fn default() -> Self {
        Self { neighbours: Knob::HeldOut, neighbourhood: Neighbourhood::default(), ridge: Knob::HeldOut }
    }
}

impl FittedConfig {
    /// Both knobs given.
    pub fn given(neighbours: usize, ridge: Real) -> Self {
        Self { neighbours: Knob::Given(neighbours), ridge: Knob::Given(ridge), ..Self::default() }
    }

    fn chooses(&self) -> bool {
        self.neighbours == Knob::HeldOut || self.ridge == Knob::HeldOut
    }
}

/// The neighbour counts tried when the count is chosen.
pub const NEIGHBOUR_GRID: [usize; 4] = [8, 16, 24, 32];
/// The relative ridges tried when the ridge is chosen.
pub const RIDGE_GRID: [Real; 8] = [1e-5, 3e-5, 1e-4, 3e-4, 1e-3, 3e-3, 1e-2, 3e-2];
/// Folds of a fit's training poses that choose its knobs (whole groups when the pose set
/// has groups; fewer when there are fewer groups or poses).
pub const TUNING_FOLDS: usize = 5;
/// Fine vertices (evenly strided over those that are not coarse vertices) whose
/// held-out error chooses the knobs.
pub const TUNING_ROWS: usize = 512;
/// The neighbour count when it is to be chosen but the training poses cannot be split
/// into two folds: the value SCAPE's tuning chose (crate docs).
pub const FALLBACK_NEIGHBOURS: usize = 16;
/// Likewise the ridge.
pub const FALLBACK_RIDGE: Real = 3e-3;

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

/// The knobs one fit used, and how they were settled.
#[derive(Debug, Clone, PartialEq)]
pub struct Knobs {
    pub neighbours: usize,
    pub ridge: Real,
    pub settled: Settled,
}

/// How a fit's [`Knobs`] were settled.
#[derive(Debug, Clone, PartialEq)]
pub enum Settled {
    /// Both were given.
    Given,
    /// The grid point with the lowest held-out error over `folds` folds of the fit's
    /// training poses, measured on `rows` fine vertices; `grid` holds every point tried.
    HeldOut { folds: usize, rows: usize, grid: Vec<GridPoint> },
    /// A knob was to be chosen, but the training poses could not be split into two
    /// folds: [`FALLBACK_NEIGHBOURS`] and [`FALLBACK_RIDGE`] stand for it.
    TooFewPoses,
}

/// One grid point of a choice: its knobs and the summed held-out squared error of the
/// sampled rows (the squared units of the poses).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridPoint {
    pub neighbours: usize,
    pub ridge: Real,
    pub sse: Real,
}

/// The fine level of a fit, read in place: a pose set's own vertices (`orig` `None`),
/// or the vertices `orig` of a larger pose set (a coarser level of a chain, whose poses
/// are never gathered into a pose set of their own). `template` and `faces` are the
/// level's own.
#[derive(Debug, Clone, Copy)]
pub struct FineLevel<'a> {
    pub poses: &'a PoseSet,
    pub orig: Option<&'a [u32]>,
    pub template: &'a [Vec3],
    pub faces: &'a [desal_mesh::Face],
}

impl FineLevel<'_> {
    /// The level's vertex count.
    pub fn vertex_count(&self) -> usize {
        self.template.len()
    }

    /// Fine vertex `fine_idx` in pose `pose`.
    fn at(&self, pose: usize, fine_idx: usize) -> Vec3 {
        let vertex = self.orig.map_or(fine_idx, |o| o[fine_idx] as usize);
        self.poses.poses[pose][vertex]
    }
}

/// One training set's fit: U (`fine_idx` rows, `coarse_idx` columns), how its rows
/// were solved and the knobs used.
#[derive(Debug, Clone)]
pub struct Fit {
    pub up: CsrMatrix,
    pub counts: FitCounts,
    pub knobs: Knobs,
}

/// Fits every fine vertex's row once per training set: `barycentric[i]` is fine vertex
/// `i`'s barycentric row, `coarse_to_fine[coarse_idx]` its fine vertex, `trainings[k]`
/// the pose indices of set `k` (each non-empty). One [`Fit`] per set, in order.
/// Held-out evaluation needs one upsampler per fold, so what does not depend on the
/// poses is done once per fine vertex (its candidates), and each set's `DᵀD` is summed
/// from partial sums over groups of poses (the poses that the same sets hold), each
/// computed once: for the folds of a cross-validation that is the work of one fit over
/// every pose instead of one per fold. A set's rows equal those of a fit on that set
/// alone up to the rounding of that sum (one set with given knobs is one group: bit for
/// bit). A knob to be chosen is chosen per set, from that set's poses only.
pub fn fitted_rows_per_training(
    fine: &FineLevel,
    coarse_to_fine: &[u32],
    barycentric: &[Row],
    trainings: &[&[usize]],
    config: &FittedConfig,
) -> Vec<Fit> {
    debug_assert!(trainings.iter().all(|t| !t.is_empty()));
    // Each set's tuning folds are listed as sets too, so that the partition into groups
    // of poses gives each fold's sum as well as each set's.
    let folds: Vec<Vec<Vec<usize>>> =
        trainings.iter().map(|t| if config.chooses() { tuning_folds(fine, t) } else { Vec::new() }).collect();
    let mut sets: Vec<&[usize]> = trainings.to_vec();
    sets.extend(folds.iter().flatten().map(Vec::as_slice));
    let groups = PoseGroups::new(&sets);
    let rows = Rows::new(fine, coarse_to_fine, barycentric, &groups, config.neighbourhood);

    let knobs = choose_knobs(&rows, trainings.len(), &folds, config);
    let need = knobs.iter().map(|k| k.neighbours).max().expect("at least one training set");
    let mut built: Vec<(CsrBuilder, FitCounts)> =
        trainings.iter().map(|_| (CsrBuilder::new(coarse_to_fine.len()), FitCounts::default())).collect();
    // A chunk of rows at a time, each set's rows appended to its matrix: the rows of
    // every set are never all held at once beside the matrices.
    let vertices: Vec<usize> = (0..fine.vertex_count()).collect();
    for chunk in vertices.chunks(ROW_CHUNK) {
        let solved: Vec<Vec<(Row, Solve)>> = chunk
            .par_iter()
            .map_init(
                || Scratch::new(fine.vertex_count()),
                |scratch, &fine_idx| match rows.problem(fine_idx, need, scratch) {
                    None => vec![(vec![(rows.fine_to_coarse[fine_idx], 1.0)], Solve::Exact); trainings.len()],
                    Some(problem) => knobs
                        .iter()
                        .enumerate()
                        .map(|(set, k)| {
                            let positions = problem.positions(k.neighbours);
                            let (members, poses) = &groups.members[set];
                            let g = problem.gram(members, &positions, *poses as Real);
                            let (w, how) = solve_dense(&g, &problem.b(&positions), k.ridge);
                            (problem.row(&positions, &w), how)
                        })
                        .collect(),
                },
            )
            .collect();
        for per_set in solved {
            for ((matrix, counts), (row, how)) in built.iter_mut().zip(per_set) {
                match how {
                    Solve::Exact => counts.exact_rows += 1,
                    Solve::Cholesky => counts.cholesky_rows += 1,
                    Solve::PseudoInverse => counts.pseudo_inverse_rows += 1,
                }
                matrix.push_row(row).expect("candidates are coarse vertices");
            }
        }
    }
    built
        .into_iter()
        .zip(knobs)
        .map(|((matrix, counts), knobs)| Fit { up: matrix.finish(), counts, knobs })
        .collect()
}

/// Rows solved between two appends to the matrices.
const ROW_CHUNK: usize = 2048;

/// The test folds that choose a training set's knobs: its poses by group (by pose when
/// the set has no groups), dealt round-robin in order of first appearance into at most
/// [`TUNING_FOLDS`] folds; the template's group (the template) always trains. Fewer than
/// two folds: none (the knobs fall back).
fn tuning_folds(fine: &FineLevel, training: &[usize]) -> Vec<Vec<usize>> {
    let poses = fine.poses;
    let key = |p: usize| poses.groups.as_ref().map_or(p as u64, |g| g[p] as u64);
    let trained = key(poses.template);
    let mut order: Vec<u64> = Vec::new();
    for &p in training {
        let k = key(p);
        if k != trained && !order.contains(&k) {
            order.push(k);
        }
    }
    let count = order.len().min(TUNING_FOLDS);
    if count < 2 {
        return Vec::new();
    }
    let mut folds = vec![Vec::new(); count];
    for &p in training {
        if let Some(i) = order.iter().position(|&o| o == key(p)) {
            folds[i % count].push(p);
        }
    }
    folds
}

/// Each training set's knobs: given, chosen over its folds (`folds[set]`, listed in the
/// groups after the training sets, set by set), or the fallback when it has none.
fn choose_knobs(rows: &Rows, sets: usize, folds: &[Vec<Vec<usize>>], config: &FittedConfig) -> Vec<Knobs> {
    let fallback = |settled| Knobs {
        neighbours: config.neighbours.or(FALLBACK_NEIGHBOURS),
        ridge: config.ridge.or(FALLBACK_RIDGE),
        settled,
    };
    if !config.chooses() {
        return (0..sets).map(|_| fallback(Settled::Given)).collect();
    }
    let ks = config.neighbours.values(&NEIGHBOUR_GRID);
    let ridges = config.ridge.values(&RIDGE_GRID);
    // The set index of each training set's first fold among the listed sets.
    let mut first = Vec::with_capacity(sets);
    let mut next = sets;
    for f in folds {
        first.push(next);
        next += f.len();
    }
    let tuned: Vec<usize> = (0..sets).filter(|&s| folds[s].len() >= 2).collect();
    let sampled = rows.sampled(TUNING_ROWS);
    let points = ks.len() * ridges.len();
    // Per sampled row, per tuned set, the held-out error of every (k, ridge), k-major.
    let per_row = |scratch: &mut Scratch, fine_idx: usize| -> Vec<Vec<Real>> {
        let widest = *ks.iter().max().expect("a grid");
        let problem = rows.problem(fine_idx, widest, scratch).expect("a sampled row is not coarse");
        tuned
            .iter()
            .map(|&set| {
                let (members, poses) = &rows.groups.members[set];
                let mut sums = vec![0.0; points];
                for fold in 0..folds[set].len() {
                    let (test, tested) = &rows.groups.members[first[set] + fold];
                    let train: Vec<usize> = members.iter().copied().filter(|g| !test.contains(g)).collect();
                    for (i, &k) in ks.iter().enumerate() {
                        // What depends on (fold, k) only, once for every ridge.
                        let positions = problem.positions(k);
                        let g = problem.gram(&train, &positions, (poses - tested) as Real);
                        let h = problem.gram(test, &positions, 1.0);
                        let b = problem.b(&positions);
                        for (j, &ridge) in ridges.iter().enumerate() {
                            let (w, _) = solve_dense(&g, &b, ridge);
                            sums[i * ridges.len() + j] += w.dot(&(&h * &w));
                        }
                    }
                }
                sums
            })
            .collect()
    };
    let sse: Vec<Vec<Real>> = sampled
        .par_iter()
        .map_init(|| Scratch::new(rows.fine.vertex_count()), |scratch, &fine_idx| per_row(scratch, fine_idx))
        .collect::<Vec<_>>()
        // Summed in row order, whatever the thread count: the choice is deterministic.
        .into_iter()
        .fold(vec![vec![0.0; points]; tuned.len()], |mut sum, row| {
            sum.iter_mut().flatten().zip(row.iter().flatten()).for_each(|(s, x)| *s += x);
            sum
        });
    (0..sets)
        .map(|set| match tuned.iter().position(|&s| s == set) {
            None => fallback(Settled::TooFewPoses),
            Some(t) => {
                let grid: Vec<GridPoint> = ks
                    .iter()
                    .flat_map(|&k| ridges.iter().map(move |&r| (k, r)))
                    .zip(&sse[t])
                    .map(|((neighbours, ridge), &sse)| GridPoint { neighbours, ridge, sse })
                    .collect();
                // The lowest error; ties to the earlier point (fewer neighbours, less ridge).
                let best = grid.iter().fold(grid[0], |b, p| if p.sse < b.sse { *p } else { b });
                Knobs {
                    neighbours: best.neighbours,
                    ridge: best.ridge,
                    settled: Settled::HeldOut { folds: folds[set].len(), rows: sampled.len(), grid },
                }
            }
        })
        .collect()
}

/// What every row's problem is built from: the fine poses' candidates and trajectories.
struct Rows<'a> {
    fine: &'a FineLevel<'a>,
    barycentric: &'a [Row],
    /// `u32::MAX` for a fine vertex that is not a coarse vertex.
    fine_to_coarse: Vec<u32>,
    search: Search,
    groups: &'a PoseGroups,
    trajectories: Trajectories,
}

impl<'a> Rows<'a> {
    fn new(
        fine: &'a FineLevel<'a>,
        coarse_to_fine: &[u32],
        barycentric: &'a [Row],
        groups: &'a PoseGroups,
        neighbourhood: Neighbourhood,
    ) -> Self {
        let template = fine.template;
        let coarse_template: Vec<Vec3> = coarse_to_fine.iter().map(|&f| template[f as usize]).collect();
        let search = match neighbourhood {
            Neighbourhood::Euclidean => Search::Grid(PointGrid::new(&coarse_template)),
            Neighbourhood::Geodesic => Search::Graph(EdgeGraph::new(template, fine.faces)),
        };
        let mut fine_to_coarse = vec![u32::MAX; fine.vertex_count()];
        for (coarse_idx, &fine_idx) in coarse_to_fine.iter().enumerate() {
            fine_to_coarse[fine_idx as usize] = coarse_idx as u32;
        }
        let trajectories = Trajectories::new(fine, coarse_to_fine, &groups.poses);
        Self { fine, barycentric, fine_to_coarse, search, groups, trajectories }
    }

    /// At most `count` fine vertices that are not coarse vertices, evenly strided.
    fn sampled(&self, count: usize) -> Vec<usize> {
        let free: Vec<usize> =
            (0..self.fine.vertex_count()).filter(|&i| self.fine_to_coarse[i] == u32::MAX).collect();
        let stride = free.len().div_ceil(count.max(1)).max(1);
        free.into_iter().step_by(stride).collect()
    }

    /// Fine vertex `fine_idx`'s problem with its `k` nearest coarse vertices and its
    /// barycentric corners, with `DᵀD` summed per group of poses; `None` for a coarse
    /// vertex (its row is exact).
    fn problem(&self, fine_idx: usize, k: usize, scratch: &mut Scratch) -> Option<Problem> {
        if self.fine_to_coarse[fine_idx] != u32::MAX {
            return None;
        }
        let template = self.fine.template;
        let nearest: Vec<u32> = match &self.search {
            Search::Grid(grid) => grid.nearest(&template[fine_idx], k).into_iter().map(|(j, _)| j).collect(),
            Search::Graph(graph) => nearest_marked(graph, &self.fine_to_coarse, fine_idx as u32, k, scratch),
        };
        let barycentric = &self.barycentric[fine_idx];
        let candidates = candidates(nearest.clone(), barycentric);
        let position = |j: &u32| candidates.binary_search(j).expect("a candidate");
        let nearest = nearest.iter().map(position).collect();
        let corners = barycentric.iter().map(|(j, _)| position(j)).collect();
        let b = candidates
            .iter()
            .map(|j| barycentric.iter().find(|(c, _)| c == j).map_or(0.0, |&(_, w)| w))
            .collect();

        // G = (1/|P|) DᵀD, with D the 3|P| × m offsets of the candidates from the vertex
        // over the training poses (column j: candidate j's trajectory minus the
        // vertex's), here over every group's poses, column by column: plain slices,
        // which the compiler vectorises (the matrix's column iterators cost ~20
        // instructions an entry), and no zero fill first.
        let own = self.trajectories.gather(self.fine, fine_idx);
        let mut d: Vec<Real> = Vec::with_capacity(own.len() * candidates.len());
        for &c in &candidates {
            let theirs = self.trajectories.of(c as usize);
            d.extend(theirs.iter().zip(&own).map(|(&t, o)| Real::from(t) - o));
        }
        let columns: Vec<&[Real]> = d.chunks_exact(own.len().max(1)).collect();
        let partial = self
            .groups
            .bounds
            .windows(2)
            .map(|poses| upper_gram(&columns, 3 * poses[0]..3 * poses[1]))
            .collect();
        Some(Problem { candidates, nearest, corners, b, partial })
    }
}

/// One fine vertex's least-squares problem over its widest candidate set.
struct Problem {
    /// Candidate coarse vertices, ascending `coarse_idx`.
    candidates: Vec<u32>,
    /// Positions in `candidates` of the nearest coarse vertices, nearest first.
    nearest: Vec<usize>,
    /// Positions in `candidates` of the barycentric corners.
    corners: Vec<usize>,
    /// The barycentric row over `candidates`.
    b: Vec<Real>,
    /// Per group of poses, the upper half of `DᵀD` over `candidates` (row-major `m × m`).
    partial: Vec<Vec<Real>>,
}

impl Problem {
    /// The positions, ascending, of the `k` nearest candidates and the corners.
    fn positions(&self, k: usize) -> Vec<usize> {
        let mut p: Vec<usize> = self.nearest.iter().take(k).chain(&self.corners).copied().collect();
        p.sort_unstable();
        p.dedup();
        p
    }

    fn b(&self, positions: &[usize]) -> DenseVec {
        DenseVec::from_iterator(positions.len(), positions.iter().map(|&p| self.b[p]))
    }

    /// `(Σ_{g ∈ members} DᵀD_g) / scale` over `positions`, mirrored: the groups summed in
    /// order, the first taken as it is (so one group is its own sum, bit for bit).
    fn gram(&self, members: &[usize], positions: &[usize], scale: Real) -> Dense {
        let m = self.candidates.len();
        let n = positions.len();
        let mut g = Dense::zeros(n, n);
        for (r, &pr) in positions.iter().enumerate() {
            for (c, &pc) in positions.iter().enumerate().skip(r) {
                let k = pr * m + pc;
                let mut sum = self.partial[members[0]][k];
                for &group in &members[1..] {
                    sum += self.partial[group][k];
                }
                let v = sum / scale;
                g[(r, c)] = v;
                g[(c, r)] = v;
            }
        }
        g
    }

    /// The row of weights `w` over `positions`, zeros left out.
    fn row(&self, positions: &[usize], w: &DenseVec) -> Row {
        positions
            .iter()
            .zip(w.iter())
            .filter(|&(_, &wj)| wj != 0.0)
            .map(|(&p, &wj)| (self.candidates[p], wj))
            .collect()
    }
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
/// ([`Trajectories::gather`]), so a copy of the whole pose set is never made. Held at
/// f32, the precision every pose set is read at (artifacts, PLY, the Python module), so
/// the values are the pose set's own and take half the memory.
struct Trajectories {
    poses: Vec<usize>,
    coords: Vec<f32>,
}

impl Trajectories {
    fn new(fine: &FineLevel, coarse_to_fine: &[u32], poses: &[usize]) -> Self {
        let width = 3 * poses.len();
        let mut coords = vec![0.0; coarse_to_fine.len() * width];
        coords.par_chunks_mut(width).zip(coarse_to_fine).for_each(|(block, &fine_idx)| {
            for (slot, &p) in block.chunks_exact_mut(3).zip(poses) {
                let q = fine.at(p, fine_idx as usize);
                slot.copy_from_slice(&[q.x as f32, q.y as f32, q.z as f32]);
            }
        });
        Self { poses: poses.to_vec(), coords }
    }

    /// Coarse vertex `coarse_idx`'s trajectory.
    fn of(&self, coarse_idx: usize) -> &[f32] {
        let width = 3 * self.poses.len();
        &self.coords[coarse_idx * width..(coarse_idx + 1) * width]
    }

    /// Fine vertex `fine_idx`'s trajectory over the same poses, laid out as [`Self::of`]'s
    /// (at the pose set's own precision).
    fn gather(&self, fine: &FineLevel, fine_idx: usize) -> Vec<Real> {
        let mut block = vec![0.0; 3 * self.poses.len()];
        for (slot, &p) in block.chunks_exact_mut(3).zip(&self.poses) {
            let q = fine.at(p, fine_idx);
            slot.copy_from_slice(&[q.x, q.y, q.z]);
        }
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

/// The constrained ridge problem (module docs) for `G` and the barycentric weights `b`:
/// by Cholesky when `λ > 0`, else (or when it fails) by pseudo-inverse.
fn solve_dense(g: &Dense, b: &DenseVec, ridge: Real) -> (DenseVec, Solve) {
    let m = b.len();
    if m == 1 {
        return (DenseVec::from_element(1, 1.0), Solve::Exact);
    }
    let lambda = ridge * g.trace() / m as Real;
    match solve_kkt(g, b, lambda) {
        Some(w) => (w, Solve::Cholesky),
        None => {
            let n = sum_free_basis(m);
            let reduced = n.transpose() * g * &n;
            let rhs = -(n.transpose() * (g * b));
            (b + n * pseudo_inverse_solve(reduced, rhs, lambda), Solve::PseudoInverse)
        }
    }
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

    fn level(set: &PoseSet) -> FineLevel<'_> {
        FineLevel { poses: set, orig: None, template: set.template_positions(), faces: &set.faces }
    }

    /// A fit's tuning folds hold out whole groups, never the template's, and only the
    /// fit's own training poses; without groups they go by pose; with fewer than two
    /// groups to hold out there are none (the knobs fall back).
    #[test]
    fn tuning_folds_hold_out_whole_groups_of_the_training_poses_only() {
        let names = (0..8).map(|i| i.to_string()).collect();
        let plain = PoseSet::try_new(names, vec![vec![Vec3::zeros(); 3]; 8], vec![[0, 1, 2]], 0).unwrap();
        let grouped = plain.clone().with_groups(Some(vec![0, 0, 1, 1, 2, 2, 3, 3])).unwrap();
        let all: Vec<usize> = (0..8).collect();
        assert_eq!(tuning_folds(&level(&grouped), &all), vec![vec![2, 3], vec![4, 5], vec![6, 7]]);
        assert_eq!(tuning_folds(&level(&grouped), &[0, 1, 2, 3, 6, 7]), vec![vec![2, 3], vec![6, 7]]);
        assert!(tuning_folds(&level(&grouped), &[0, 1, 4, 5]).is_empty());
        assert_eq!(
            tuning_folds(&level(&plain), &all),
            vec![vec![1, 6], vec![2, 7], vec![3], vec![4], vec![5]]
        );
        assert!(tuning_folds(&level(&plain), &[0, 3]).is_empty());
    }

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
