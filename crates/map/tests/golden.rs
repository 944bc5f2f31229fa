//! Golden output of stage 4 on a small fixed input: the greedy map of moved positions
//! onto a template. Fails when the map changes, naming the `VERSION` to bump.

use desal_map::greedy_map;
use desal_mesh::Vec3;
use desal_testdata::golden::{Fnv, assert_golden, tube};

#[test]
fn map_output_matches_its_golden_hash() {
    let original = tube(16, 12).positions;
    // Every third vertex, nudged off its place as an optimal placement would move it.
    let simplified: Vec<Vec3> = original
        .iter()
        .enumerate()
        .filter(|(k, _)| k % 3 == 0)
        .map(|(k, p)| p + Vec3::new(0.004 * ((k % 5) as f64 - 2.0), 0.003, -0.002 * ((k % 7) as f64 - 3.0)))
        .collect();
    let map = greedy_map(&simplified, &original).unwrap();
    let mut hash = Fnv::default();
    hash.indices(map.simp_to_orig.iter().copied());
    assert_golden("stage 4 (map)", "desal_map::VERSION", hash.finish(), 0xce1297dfaaeb9b45);
}
