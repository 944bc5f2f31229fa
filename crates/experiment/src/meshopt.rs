//! meshoptimizer (zeux/meshoptimizer through the `meshopt` crate, built from source by
//! cargo), in-process, as the baselines a user would try in five minutes: plain,
//! `Regularize`, and the most salient vertices flagged `Priority`.
//!
//! meshoptimizer collapses onto existing vertices, so its result is a vertex subset and
//! stage 4 maps it exactly. It targets an index count, not a vertex count, and is run
//! with an unbounded error so that the count alone stops it; the index target is
//! bisected to the largest that keeps at most the target's vertices, so every method of
//! a comparison has the same budget (or, where meshoptimizer cannot get there, the
//! reached count is reported).

use desal_io::artifact::SimplifiedV1;
use desal_mesh::TriMesh;
use meshopt::{SimplifyOptions, SimplifyVertex};

/// The share of vertices, most salient first, that `meshopt-priority` flags `Priority`.
pub const PRIORITY_FRACTION: f64 = 0.2;

/// Which meshoptimizer run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Variant {
    Plain,
    Regularize,
    Priority,
}

impl Variant {
    pub const ALL: [Variant; 3] = [Variant::Plain, Variant::Regularize, Variant::Priority];

    pub fn name(self) -> &'static str {
        match self {
            Variant::Plain => "meshopt",
            Variant::Regularize => "meshopt-regularize",
            Variant::Priority => "meshopt-priority",
        }
    }
}

/// Simplifies `template` to at most `target_vertices` vertices; `weights` (stage 2's, per
/// vertex) choose the `Priority` vertices. Returns the stage-3 body (a subset, with its
/// `simp_to_orig`) and how many bisection runs it took.
pub fn simplify(
    template: &TriMesh,
    weights: &[f64],
    variant: Variant,
    target_vertices: usize,
) -> (SimplifiedV1, usize) {
    let runner = Runner::new(template, weights, variant);
    // Bisect the face target: the largest whose result keeps <= target_vertices.
    let (mut lo, mut hi) = (1usize, template.face_count());
    let mut best = runner.run(lo);
    let mut runs = 1;
    while lo < hi {
        let mid = lo + (hi - lo).div_ceil(2);
        let result = runner.run(mid);
        runs += 1;
        if runner.vertices_of(&result) <= target_vertices {
            lo = mid;
            best = result;
        } else {
            hi = mid - 1;
        }
    }
    (subset_body(template, &best), runs)
}

/// Simplifies `template` to at most `faces` faces in one run (a LOD level's budget).
pub fn simplify_to_faces(
    template: &TriMesh,
    weights: &[f64],
    variant: Variant,
    faces: usize,
) -> SimplifiedV1 {
    subset_body(template, &Runner::new(template, weights, variant).run(faces))
}

/// One variant's meshoptimizer input: positions, indices, `Priority` flags, options.
struct Runner {
    positions: Vec<[f32; 3]>,
    indices: Vec<u32>,
    locks: Vec<SimplifyVertex>,
    options: SimplifyOptions,
}

impl Runner {
    fn new(template: &TriMesh, weights: &[f64], variant: Variant) -> Self {
        let positions: Vec<[f32; 3]> =
            template.positions.iter().map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect();
        let indices: Vec<u32> = template.faces.iter().flatten().copied().collect();
        let mut locks = vec![SimplifyVertex::None; positions.len()];
        if variant == Variant::Priority {
            let mut order: Vec<usize> = (0..weights.len()).collect();
            order.sort_by(|&a, &b| weights[b].total_cmp(&weights[a]).then(a.cmp(&b)));
            let flagged = (PRIORITY_FRACTION * positions.len() as f64).round() as usize;
            for &v in order.iter().take(flagged) {
                locks[v] = SimplifyVertex::Priority;
            }
        }
        let options = match variant {
            Variant::Regularize => SimplifyOptions::Regularize,
            _ => SimplifyOptions::None,
        };
        Self { positions, indices, locks, options }
    }

    /// At most `faces` faces, the error unbounded so that the count alone stops it.
    fn run(&self, faces: usize) -> Vec<u32> {
        meshopt::simplify_with_locks_decoder(
            &self.indices,
            &self.positions,
            &self.locks,
            faces * 3,
            f32::MAX,
            self.options,
            None,
        )
    }

    fn vertices_of(&self, result: &[u32]) -> usize {
        let mut used = vec![false; self.positions.len()];
        result.iter().for_each(|&v| used[v as usize] = true);
        used.iter().filter(|&&u| u).count()
    }
}

/// The kept vertices in original index order, and the faces renumbered onto them.
fn subset_body(template: &TriMesh, result: &[u32]) -> SimplifiedV1 {
    let faces: Vec<[u32; 3]> = result.chunks_exact(3).map(|f| [f[0], f[1], f[2]]).collect();
    let (kept, faces) = desal_mesh::used_vertices(template.vertex_count(), &faces);
    let mut body = desal_driver::stages::simplify::external(&TriMesh {
        positions: kept.iter().map(|&v| template.positions[v as usize]).collect(),
        faces,
    });
    body.simp_to_orig = kept.iter().map(|&v| Some(v)).collect();
    body.placement = "subset".into();
    body.input_vertices = template.vertex_count() as u32;
    body.input_faces = template.face_count() as u32;
    body.stop = "target".into();
    body
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a closed tube every variant reaches the vertex budget from below, keeps original
    /// vertices only, and `Priority` keeps more of the flagged vertices than plain does.
    #[test]
    fn every_variant_keeps_a_subset_within_the_budget() {
        let template = &desal_testdata::golden::tube(20, 16);
        let n = template.vertex_count();
        let weights: Vec<f64> =
            template.positions.iter().map(|p| if p.y > 0.5 { 1.0 } else { 0.05 }).collect();
        let target = n / 4;
        let mut kept_salient = Vec::new();
        for variant in Variant::ALL {
            let (body, runs) = simplify(template, &weights, variant, target);
            let vertices = body.positions.len();
            assert!(
                vertices <= target && vertices + 8 >= target,
                "{}: {vertices} of {target}",
                variant.name()
            );
            assert!(runs > 1);
            for (p, o) in body.positions.iter().zip(&body.simp_to_orig) {
                let q = template.positions[o.unwrap() as usize];
                assert_eq!(*p, [q.x, q.y, q.z]);
            }
            let salient = body.simp_to_orig.iter().filter(|o| weights[o.unwrap() as usize] == 1.0).count();
            kept_salient.push(salient);
        }
        assert!(kept_salient[2] > kept_salient[0], "{kept_salient:?}");
    }
}
