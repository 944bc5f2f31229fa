//! The bundled sample (`data-samples/`, 11 poses of the CC0 MakeHuman body, 13 380
//! vertices): a [2500, 625] hierarchy of the paper's method builds, and the fitted U,
//! fitted on the even poses, beats the barycentric U on the odd ones at both levels.
//! Prints the figures with `--nocapture`.

mod common;

use std::path::{Path, PathBuf};

use common::{Method, SaliencyPerLevel, build_geometry, build_levels, composed};
use desal_hierarchy::{Upsampler, upsampling_error};
use desal_mesh::PoseSet;

fn sample() -> (PoseSet, desal_mesh::PartLabels) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data-samples");
    let mut files: Vec<PathBuf> = std::fs::read_dir(root.join("poses"))
        .expect("data-samples/poses")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "ply"))
        .collect();
    files.sort();
    let meshes: Vec<_> = files.iter().map(|f| desal_io::read_mesh(f).expect("sample pose")).collect();
    let names = files.iter().map(|f| f.file_stem().unwrap().to_string_lossy().into_owned()).collect();
    let faces = meshes[0].faces.clone();
    let set =
        PoseSet::try_new(names, meshes.into_iter().map(|m| m.positions).collect(), faces, 0).expect("poses");
    let labels = desal_io::labels::read_labels(&root.join("labels.txt")).expect("labels");
    (set, labels)
}

#[test]
fn fitted_beats_barycentric_on_the_sample() {
    let (full, labels) = sample();
    let even: Vec<usize> = (0..full.pose_count()).filter(|p| p % 2 == 0).collect();
    let odd: Vec<usize> = (0..full.pose_count()).filter(|p| p % 2 == 1).collect();
    let geometry = build_geometry(&full, &labels, &[2500, 625], Method::Paper, SaliencyPerLevel::Recompute);
    let mut mse = Vec::new();
    for up in [Upsampler::Barycentric, Upsampler::default()] {
        let levels = build_levels(&full, &geometry, &even, &up);
        let at =
            |k: usize| upsampling_error(&full, &composed(&levels, k), &geometry[k].orig, &odd).unwrap().mse;
        mse.push((at(0), at(1)));
    }
    let (bary, fitted) = (mse[0], mse[1]);
    println!(
        "sample, held out (MSE, 1e-6 m^2): barycentric {:.3} | {:.3}, fitted {:.3} | {:.3}; ratio {:.3} | {:.3}",
        bary.0 * 1e6,
        bary.1 * 1e6,
        fitted.0 * 1e6,
        fitted.1 * 1e6,
        fitted.0 / bary.0,
        fitted.1 / bary.1
    );
    assert!(fitted.0 < bary.0 && fitted.1 < bary.1);
}
