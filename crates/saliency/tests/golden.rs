//! Golden output of stage 2 on a small fixed residual table: fails when the saliency
//! changes, naming the `VERSION` to bump.

use desal_saliency::{ResidualTable, SaliencyConfig, compute_saliency};
use desal_testdata::golden::{Fnv, assert_golden};

#[test]
fn saliency_output_matches_its_golden_hash() {
    let (poses, vertices) = (5, 40);
    // Deterministic residuals: a smooth bump that moves with the pose, plus a ripple.
    let values: Vec<f32> = (0..poses * vertices)
        .map(|k| {
            let (pose, v) = (k / vertices, k % vertices);
            let bump = (-((v as f32 - 8.0 * pose as f32) / 6.0).powi(2)).exp();
            if pose == 0 { 0.0 } else { 0.01 * bump + 0.001 * ((v * 7 + pose * 3) % 11) as f32 }
        })
        .collect();
    let names: Vec<String> = (0..poses).map(|p| format!("p{p}")).collect();
    let table = ResidualTable {
        values: &values,
        vertex_count: vertices,
        pose_names: &names,
        template: Some(0),
        length_scale: 1.0,
    };
    let s = compute_saliency(&table, &SaliencyConfig::default()).unwrap();
    let mut hash = Fnv::default();
    hash.f64s(s.saliency.iter().copied()).f64s(s.weights.iter().copied()).f64s([s.normaliser]);
    assert_golden("stage 2 (saliency)", "desal_saliency::VERSION", hash.finish(), 0xab35648c28976aeb);
}
