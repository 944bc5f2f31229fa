//! Poisson reconstruction of a mesh from per-triangle deformation gradients: SCAPE's
//! synthesis step.
//!
//! Anguelov et al. 2005, Eq. 9: given a linear map `T_k` per triangle (in SCAPE
//! `T_k = R_k Q_k`), find vertex positions `y` minimising
//! `Σ_k Σ_{j=2,3} ‖T_k ê_kj − (y_kj − y_k1)‖²`, where `ê_kj = x_kj − x_k1` are the
//! template's edges from the triangle's first corner. The normal equations
//! `L y = b` have the same matrix `L` (a graph Laplacian over those two edges per
//! triangle) for every pose, so `L` is factorised once per mesh (sparse Cholesky, faer)
//! and each pose costs one right-hand-side assembly and one triangular solve pair with
//! three columns (x, y, z).
//!
//! `L` is singular: each connected component can translate freely. One vertex per
//! component (its lowest index) is pinned at the origin and removed from the system,
//! which leaves `L` positive definite without perturbing the solution. Translation is
//! then fixed after the solve: the whole mesh is moved so that its vertex centroid (the
//! plain mean of its positions) is the target centroid; when there are several
//! components, each keeps the offset of its centroid from the whole-mesh centroid that
//! it has in the template (isolated vertices count as components of one vertex).
//!
//! **Anchored variant** ([`AnchoredPoissonSolver`]): instead of pinning a vertex and
//! placing the centroid, every vertex `v` is also pulled towards an anchor position
//! `a_v` with weight `w_v`, i.e. the energy gains `Σ_v w_v ‖y_v − a_v‖²`. The matrix
//! becomes `L + W` (positive definite as soon as every component has one positive
//! weight), so nothing is pinned and the anchors fix the translation. Because the
//! Laplacian's low-frequency modes have small eigenvalues, a small `W` acts as a
//! low-pass filter: error that varies slowly along the surface (drift integrated down a
//! kinematic chain) is taken from the anchors, detail from the gradients.
//!
//! The factorisation and solves run single-threaded (`Parallelism::None`): callers
//! parallelise over poses, and results stay bit-identical for any thread count.

use desal_mesh::{Face, Mat3, Real, Vec3};
use faer::dyn_stack::{GlobalPodBuffer, PodStack};
use faer::sparse::SparseColMat;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, LltRegularization, SymbolicCholesky, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::{Conj, Mat, Parallelism, Side};

use crate::error::EvalError;

/// Marks a pinned vertex in `free_index`.
const PINNED: u32 = u32::MAX;

/// A factorised Poisson system for one mesh (one template and triangle list).
#[derive(Debug)]
pub struct PoissonSolver {
    faces: Vec<Face>,
    /// Template edges `[x2 − x1, x3 − x1]` per face.
    template_edges: Vec<[Vec3; 2]>,
    /// Row of each vertex in the reduced system, or `PINNED`.
    free_index: Vec<u32>,
    /// Connected component of each vertex (ids in order of first vertex).
    component: Vec<u32>,
    /// Template centroid of each component minus the template's overall centroid.
    component_offsets: Vec<Vec3>,
    symbolic: SymbolicCholesky<usize>,
    factor_values: Vec<Real>,
}

impl PoissonSolver {
    /// Builds and factorises the system for a mesh with template positions `template`
    /// and triangles `faces` (indices into `template`).
    pub fn new(template: &[Vec3], faces: &[Face]) -> Result<Self, EvalError> {
        let component = label_components(template.len(), faces);
        let (free_index, free_count) = pin_one_vertex_per_component(&component);
        let component_offsets = component_centroid_offsets(template, &component);
        let (symbolic, factor_values) = factorise_laplacian(faces, &free_index, free_count, &[])?;
        Ok(Self {
            faces: faces.to_vec(),
            template_edges: template_edges(template, faces),
            free_index,
            component,
            component_offsets,
            symbolic,
            factor_values,
        })
    }

    pub fn vertex_count(&self) -> usize {
        self.free_index.len()
    }

    /// Number of nonzeros in the Cholesky factor (a measure of solve cost).
    pub fn factor_nonzeros(&self) -> usize {
        self.factor_values.len()
    }

    /// Positions whose edges best match `gradients[face] · ê` in the least-squares sense,
    /// moved so that their centroid is `target_centroid`. `gradients` is in face order.
    pub fn solve(&self, gradients: &[Mat3], target_centroid: &Vec3) -> Vec<Vec3> {
        debug_assert_eq!(gradients.len(), self.faces.len());
        let mut rhs = self.assemble_rhs(gradients);
        self.solve_in_place(&mut rhs);
        let positions = self.scatter_solution(&rhs);
        self.place_components(positions, target_centroid)
    }

    /// `b = Dᵀ g`: each edge target `g = T_k ê_kj` pulls its far corner by `+g` and the
    /// triangle's first corner by `−g`; pinned vertices (fixed at 0) drop out.
    fn assemble_rhs(&self, gradients: &[Mat3]) -> Mat<Real> {
        assemble_edge_rhs(
            &self.faces,
            &self.template_edges,
            &self.free_index,
            self.symbolic.nrows(),
            gradients,
        )
    }

    fn solve_in_place(&self, rhs: &mut Mat<Real>) {
        solve_llt_in_place(&self.symbolic, &self.factor_values, rhs);
    }

    fn scatter_solution(&self, solution: &Mat<Real>) -> Vec<Vec3> {
        self.free_index
            .iter()
            .map(|&row| match row {
                PINNED => Vec3::zeros(),
                r => row_of(solution, r as usize),
            })
            .collect()
    }

    /// Translates each component so that its centroid sits at `target_centroid` plus its
    /// template offset.
    fn place_components(&self, mut positions: Vec<Vec3>, target_centroid: &Vec3) -> Vec<Vec3> {
        let component_count = self.component_offsets.len();
        let mut sums = vec![Vec3::zeros(); component_count];
        let mut counts = vec![0usize; component_count];
        for (p, &c) in positions.iter().zip(&self.component) {
            sums[c as usize] += p;
            counts[c as usize] += 1;
        }
        let shifts: Vec<Vec3> = (0..component_count)
            .map(|c| target_centroid + self.component_offsets[c] - sums[c] / counts[c] as Real)
            .collect();
        for (p, &c) in positions.iter_mut().zip(&self.component) {
            *p += shifts[c as usize];
        }
        positions
    }
}

/// A factorised anchored Poisson system `(L + W) y = b + W a` for one mesh: the edge
/// terms of [`PoissonSolver`] plus a soft pull of each vertex towards an anchor (see the
/// module doc). Nothing is pinned; the anchors fix the translation.
#[derive(Debug)]
pub struct AnchoredPoissonSolver {
    faces: Vec<Face>,
    template_edges: Vec<[Vec3; 2]>,
    /// `w_v`, per vertex (dimensionless: it weighs squared distances against the
    /// squared edge residuals of the unit-weight edge terms).
    weights: Vec<Real>,
    symbolic: SymbolicCholesky<usize>,
    factor_values: Vec<Real>,
}

impl AnchoredPoissonSolver {
    /// Builds and factorises `L + W` for a mesh with template positions `template`,
    /// triangles `faces` and anchor weights `weights[v] > 0` (one per vertex).
    pub fn new(template: &[Vec3], faces: &[Face], weights: &[Real]) -> Result<Self, EvalError> {
        debug_assert_eq!(template.len(), weights.len());
        debug_assert!(weights.iter().all(|&w| w > 0.0 && w.is_finite()), "anchor weights must be positive");
        let free_index: Vec<u32> = (0..template.len() as u32).collect();
        let (symbolic, factor_values) = factorise_laplacian(faces, &free_index, template.len(), weights)?;
        Ok(Self {
            faces: faces.to_vec(),
            template_edges: template_edges(template, faces),
            weights: weights.to_vec(),
            symbolic,
            factor_values,
        })
    }

    pub fn vertex_count(&self) -> usize {
        self.weights.len()
    }

    /// Positions minimising the edge residuals of `gradients` (face order) plus
    /// `Σ_v w_v ‖y_v − anchors[v]‖²` (`anchors` in the mesh's vertex index space).
    pub fn solve(&self, gradients: &[Mat3], anchors: &[Vec3]) -> Vec<Vec3> {
        debug_assert_eq!(gradients.len(), self.faces.len());
        debug_assert_eq!(anchors.len(), self.weights.len());
        let free_index: Vec<u32> = (0..self.weights.len() as u32).collect();
        let mut rhs =
            assemble_edge_rhs(&self.faces, &self.template_edges, &free_index, self.weights.len(), gradients);
        for (v, (w, a)) in self.weights.iter().zip(anchors).enumerate() {
            for axis in 0..3 {
                rhs[(v, axis)] += w * a[axis];
            }
        }
        solve_llt_in_place(&self.symbolic, &self.factor_values, &mut rhs);
        (0..self.weights.len()).map(|v| row_of(&rhs, v)).collect()
    }
}

/// Template edges `[x2 − x1, x3 − x1]` per face.
fn template_edges(template: &[Vec3], faces: &[Face]) -> Vec<[Vec3; 2]> {
    faces
        .iter()
        .map(|&[a, b, c]| {
            let x1 = template[a as usize];
            [template[b as usize] - x1, template[c as usize] - x1]
        })
        .collect()
}

/// `b = Dᵀ g`: each edge target `g = T_k ê_kj` pulls its far corner by `+g` and the
/// triangle's first corner by `−g`; pinned vertices (fixed at 0) drop out.
fn assemble_edge_rhs(
    faces: &[Face],
    template_edges: &[[Vec3; 2]],
    free_index: &[u32],
    free_count: usize,
    gradients: &[Mat3],
) -> Mat<Real> {
    let mut rhs = Mat::<Real>::zeros(free_count, 3);
    let mut add = |vertex: u32, g: &Vec3| {
        let row = free_index[vertex as usize];
        if row != PINNED {
            for axis in 0..3 {
                rhs[(row as usize, axis)] += g[axis];
            }
        }
    };
    for ((&[v1, v2, v3], edges), gradient) in faces.iter().zip(template_edges).zip(gradients) {
        for (far, edge) in [(v2, &edges[0]), (v3, &edges[1])] {
            let g = gradient * edge;
            add(far, &g);
            add(v1, &-g);
        }
    }
    rhs
}

fn solve_llt_in_place(symbolic: &SymbolicCholesky<usize>, factor_values: &[Real], rhs: &mut Mat<Real>) {
    let req = symbolic.solve_in_place_req::<Real>(3).expect("workspace size of a 3-column solve");
    let mut buffer = GlobalPodBuffer::new(req);
    LltRef::<usize, Real>::new(symbolic, factor_values).solve_in_place_with_conj(
        Conj::No,
        rhs.as_mut(),
        Parallelism::None,
        PodStack::new(&mut buffer),
    );
}

fn row_of(solution: &Mat<Real>, r: usize) -> Vec3 {
    Vec3::new(solution[(r, 0)], solution[(r, 1)], solution[(r, 2)])
}

/// Connected components of the vertex graph of `faces` (union–find), numbered in order
/// of their lowest vertex.
fn label_components(vertex_count: usize, faces: &[Face]) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..vertex_count as u32).collect();
    fn root(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            parent[v as usize] = parent[parent[v as usize] as usize];
            v = parent[v as usize];
        }
        v
    }
    for &[a, b, c] in faces {
        for (x, y) in [(a, b), (a, c)] {
            let (rx, ry) = (root(&mut parent, x), root(&mut parent, y));
            // Keep the lower vertex as the root so a component's root is its lowest vertex.
            if rx < ry {
                parent[ry as usize] = rx;
            } else if ry < rx {
                parent[rx as usize] = ry;
            }
        }
    }
    let mut component = vec![0u32; vertex_count];
    let mut id_of_root = vec![PINNED; vertex_count];
    let mut next = 0u32;
    for v in 0..vertex_count as u32 {
        let r = root(&mut parent, v) as usize;
        if id_of_root[r] == PINNED {
            id_of_root[r] = next;
            next += 1;
        }
        component[v as usize] = id_of_root[r];
    }
    component
}

/// Pins the lowest vertex of every component; numbers the others `0..free_count`.
fn pin_one_vertex_per_component(component: &[u32]) -> (Vec<u32>, usize) {
    let mut pinned_component = vec![false; component.iter().map(|&c| c as usize + 1).max().unwrap_or(0)];
    let mut free_count = 0u32;
    let free_index = component
        .iter()
        .map(|&c| {
            if !pinned_component[c as usize] {
                pinned_component[c as usize] = true;
                PINNED
            } else {
                free_count += 1;
                free_count - 1
            }
        })
        .collect();
    (free_index, free_count as usize)
}

fn component_centroid_offsets(template: &[Vec3], component: &[u32]) -> Vec<Vec3> {
    let count = component.iter().map(|&c| c as usize + 1).max().unwrap_or(0);
    let mut sums = vec![Vec3::zeros(); count];
    let mut sizes = vec![0usize; count];
    for (p, &c) in template.iter().zip(component) {
        sums[c as usize] += p;
        sizes[c as usize] += 1;
    }
    let overall = template.iter().sum::<Vec3>() / template.len().max(1) as Real;
    sums.iter().zip(&sizes).map(|(s, &n)| s / n as Real - overall).collect()
}

/// Assembles the lower triangle of the reduced Laplacian (two edges per face, unit
/// weights) plus `diagonal[row]` on its diagonal (none when `diagonal` is empty) and
/// factorises it: symbolic analysis with an AMD ordering, then a numeric LLT.
fn factorise_laplacian(
    faces: &[Face],
    free_index: &[u32],
    free_count: usize,
    diagonal: &[Real],
) -> Result<(SymbolicCholesky<usize>, Vec<Real>), EvalError> {
    let mut triplets: Vec<(usize, usize, Real)> = Vec::with_capacity(faces.len() * 6 + diagonal.len());
    triplets.extend(diagonal.iter().enumerate().map(|(row, &w)| (row, row, w)));
    for &[v1, v2, v3] in faces {
        for far in [v2, v3] {
            let (a, b) = (free_index[v1 as usize], free_index[far as usize]);
            if a != PINNED {
                triplets.push((a as usize, a as usize, 1.0));
            }
            if b != PINNED {
                triplets.push((b as usize, b as usize, 1.0));
            }
            if a != PINNED && b != PINNED && a != b {
                let (hi, lo) = (a.max(b) as usize, a.min(b) as usize);
                triplets.push((hi, lo, -1.0));
            }
        }
    }
    let factorisation = |e: &dyn std::fmt::Debug| EvalError::Factorisation(format!("{e:?}"));
    let matrix = SparseColMat::<usize, Real>::try_new_from_triplets(free_count, free_count, &triplets)
        .map_err(|e| factorisation(&e))?;
    let symbolic = factorize_symbolic_cholesky(
        matrix.symbolic(),
        Side::Lower,
        SymmetricOrdering::Amd,
        CholeskySymbolicParams::default(),
    )
    .map_err(|e| factorisation(&e))?;
    let mut values = vec![0.0; symbolic.len_values()];
    let req = symbolic.factorize_numeric_llt_req::<Real>(Parallelism::None).map_err(|e| factorisation(&e))?;
    symbolic
        .factorize_numeric_llt::<Real>(
            &mut values,
            matrix.as_ref(),
            Side::Lower,
            LltRegularization::default(),
            Parallelism::None,
            PodStack::new(&mut GlobalPodBuffer::new(req)),
        )
        .map_err(|e| factorisation(&e))?;
    Ok((symbolic, values))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gradient::{deformation_gradient, inverse_template_frame};

    /// A closed octahedron.
    fn octahedron() -> (Vec<Vec3>, Vec<Face>) {
        let p = vec![
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(-1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(0.0, -1.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.0, 0.0, -1.0),
        ];
        let f = vec![[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]];
        (p, f)
    }

    fn gradients(template: &[Vec3], posed: &[Vec3], faces: &[Face]) -> Vec<Mat3> {
        faces
            .iter()
            .map(|&[a, b, c]| {
                let inv = inverse_template_frame(
                    &template[a as usize],
                    &template[b as usize],
                    &template[c as usize],
                )
                .unwrap();
                deformation_gradient(&inv, [posed[a as usize], posed[b as usize], posed[c as usize]])
            })
            .collect()
    }

    /// Exact gradients of an arbitrary (non-rigid) deformation reproduce it, at the
    /// requested centroid.
    #[test]
    fn exact_gradients_reproduce_the_pose() {
        let (template, faces) = octahedron();
        let posed: Vec<Vec3> = template
            .iter()
            .enumerate()
            .map(|(i, p)| Vec3::new(2.0 * p.x + 0.1 * i as f64, p.y - 0.3 * p.z, 0.5 * p.z + p.x * p.y))
            .collect();
        let centroid = posed.iter().sum::<Vec3>() / posed.len() as f64;
        let solver = PoissonSolver::new(&template, &faces).unwrap();
        let got = solver.solve(&gradients(&template, &posed, &faces), &centroid);
        for (g, p) in got.iter().zip(&posed) {
            assert!((g - p).norm() < 1e-12, "{g} vs {p}");
        }
    }

    /// Two disjoint copies of the octahedron plus an isolated vertex: identity gradients
    /// give back the template, each component at its template offset.
    #[test]
    fn components_keep_their_template_offsets() {
        let (one, faces_one) = octahedron();
        let mut template = one.clone();
        template.extend(one.iter().map(|p| p + Vec3::new(5.0, 0.0, 0.0)));
        template.push(Vec3::new(0.0, 9.0, 0.0));
        let mut faces = faces_one.clone();
        faces.extend(faces_one.iter().map(|f| f.map(|v| v + 6)));
        let solver = PoissonSolver::new(&template, &faces).unwrap();
        let shift = Vec3::new(0.5, -1.0, 2.0);
        let centroid = template.iter().sum::<Vec3>() / template.len() as f64 + shift;
        let got = solver.solve(&vec![Mat3::identity(); faces.len()], &centroid);
        for (g, p) in got.iter().zip(&template) {
            assert!((g - (p + shift)).norm() < 1e-12, "{g} vs {p}");
        }
    }
}
