//! Golden output of stage 3 on a small fixed input, for each placement and metric and
//! with the paper's weighted cost: fails when a simplification changes, naming the
//! `VERSION` to bump.

use desal_simplify::{Metric, Placement, SimplifyConfig, SimplifyInput, Target, simplify};
use desal_testdata::golden::{Fnv, assert_golden, tube};

#[test]
fn simplify_output_matches_its_golden_hash() {
    let mesh = tube(16, 12);
    let weights: Vec<f64> =
        mesh.positions.iter().map(|p| 0.05 + 0.95 * (-((p.y - 0.375) / 0.1).powi(2)).exp()).collect();
    let mut hash = Fnv::default();
    for (placement, metric, paper) in [
        (Placement::Optimal, Metric::Quadric, false),
        (Placement::Optimal, Metric::Quadric, true),
        (Placement::Subset, Metric::Quadric, true),
        (Placement::Optimal, Metric::LindstromTurk, false),
    ] {
        let config = SimplifyConfig {
            target: Target::Vertices(60),
            placement,
            metric,
            saliency: paper,
            balance: paper,
            ..SimplifyConfig::default()
        };
        let input = SimplifyInput::new(&mesh).with_weights(&weights);
        let out = simplify(&input, &config).unwrap();
        hash.points(&out.mesh.positions).indices(out.mesh.faces.iter().flatten().copied());
        hash.indices(out.simp_to_orig.iter().map(|o| o.unwrap_or(u32::MAX)));
    }
    assert_golden("stage 3 (simplify)", "desal_simplify::VERSION", hash.finish(), 0x185f914394339187);
}

/// The same tube with a seam down one column (every ring's vertex 0, end ring to end
/// ring) and one around its middle ring, in both placements: fails when the seam rules
/// change the output, naming the `VERSION` to bump.
#[test]
fn simplify_with_seams_matches_its_golden_hash() {
    let (rings, segments) = (16, 12);
    let mesh = tube(rings, segments);
    let at = |r: usize, s: usize| (r * segments + s % segments) as u32;
    let mut seams: Vec<[u32; 2]> = (0..rings - 1).map(|r| [at(r, 0), at(r + 1, 0)]).collect();
    seams.extend((0..segments).map(|s| [at(rings / 2, s), at(rings / 2, s + 1)]));
    let mut hash = Fnv::default();
    for placement in [Placement::Optimal, Placement::Subset] {
        let config = SimplifyConfig { target: Target::Vertices(60), placement, ..SimplifyConfig::default() };
        let out = simplify(&SimplifyInput::new(&mesh).with_seams(&seams), &config).unwrap();
        assert_eq!(out.report.seam_vertices, rings + segments - 1);
        hash.points(&out.mesh.positions).indices(out.mesh.faces.iter().flatten().copied());
        hash.indices(out.simp_to_orig.iter().map(|o| o.unwrap_or(u32::MAX)));
    }
    assert_golden(
        "stage 3 (simplify) with seams",
        "desal_simplify::VERSION",
        hash.finish(),
        0x1897dc9adb291d3f,
    );
}
