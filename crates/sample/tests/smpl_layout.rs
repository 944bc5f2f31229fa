//! The SMPL-layout fixture's own properties: a regressor of non-negative rows summing to 1
//! that puts every joint at the rig's, weights summing to 1, and the same bytes each time.

use desal_sample::SourceAssets;
use desal_sample::smpl_layout::smpl_layout_model;

#[test]
fn regressor_weights_and_bytes() {
    let assets = SourceAssets::load(&desal_sample::source::repository_source_dir()).unwrap();
    let model = smpl_layout_model(&assets).unwrap();
    let v = model.v_template.len();
    for (j, joint) in model.joints.iter().enumerate() {
        let row = &model.j_regressor[j * v..(j + 1) * v];
        assert!(row.iter().all(|&w| w >= 0.0), "joint {j}");
        let sum: f64 = row.iter().map(|&w| f64::from(w)).sum();
        assert!((sum - 1.0).abs() < 1e-6, "joint {j}: weights sum to {sum}");
        for axis in 0..3 {
            let at: f64 =
                row.iter().zip(&model.v_template).map(|(&w, p)| f64::from(w) * f64::from(p[axis])).sum();
            assert!(
                (at - f64::from(joint[axis])).abs() < 1e-5,
                "joint {j} axis {axis}: {at} vs {}",
                joint[axis]
            );
        }
    }
    for (vertex, weights) in model.weights.chunks_exact(24).enumerate() {
        let sum: f32 = weights.iter().sum();
        assert!((sum - 1.0).abs() < 1e-5, "vertex {vertex}: {sum}");
    }
    assert_eq!(model.npz().unwrap(), smpl_layout_model(&assets).unwrap().npz().unwrap());
    assert_eq!(model.pkl(), smpl_layout_model(&assets).unwrap().pkl());
}
