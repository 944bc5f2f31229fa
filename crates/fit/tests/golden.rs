//! Golden output of stage 1 on a small fixed input: fails when the fit's output changes,
//! naming the `VERSION` to bump.

use desal_fit::{FitConfig, fit_pose_set};
use desal_mesh::NoProgress;
use desal_testdata::golden::{Fnv, assert_golden, bent_tube_pose_set};

#[test]
fn fit_output_matches_its_golden_hash() {
    let (set, labels) = bent_tube_pose_set();
    let fit = fit_pose_set(&set, &labels, &FitConfig::default(), &NoProgress).unwrap();
    let mut hash = Fnv::default();
    hash.f64s(fit.residuals.iter().map(|&r| f64::from(r)));
    for part_fit in fit.part_fits.iter().flatten() {
        hash.f64s(part_fit.linear.iter().copied()).f64s([
            part_fit.translation.x,
            part_fit.translation.y,
            part_fit.translation.z,
        ]);
    }
    assert_golden("stage 1 (fit)", "desal_fit::VERSION", hash.finish(), 0x93937abc877dbe56);
}
