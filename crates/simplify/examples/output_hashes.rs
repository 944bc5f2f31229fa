//! The byte-identity check for engine refactors: simplifies the bundled sample
//! (`data-samples/`) and, when `../shared/datasets` is present, SCAPE's template and pose
//! set, with every method and input kind the engine has (optimal and subset placement,
//! Lindstrom–Turk, the paper's weighted cost, normalised error, keep penalties, part
//! borders, seams, multi-pose) at several targets, and prints one FNV hash per case of
//! the output's positions (exact bits), faces (in order), `simp_to_orig` and report
//! (timing aside). A change that must not alter any output prints the same lines;
//! BENCHMARKS.md "Issue 40: the engine reads like meshoptimizer's" lists them.
//! Run: `cargo run --release -p desal-simplify --example output_hashes`.

use std::path::{Path, PathBuf};

use desal_mesh::{PoseSet, TriMesh};
use desal_simplify::{
    Metric, PartBorders, Placement, Simplified, SimplifyConfig, SimplifyInput, Target, simplify,
    simplify_multipose,
};
use desal_testdata::golden::Fnv;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let sample = root.join("data-samples");
    let labels = desal_io::labels::read_labels(&sample.join("labels.txt"))?.labels;
    let sample_poses: Vec<PathBuf> = sorted_plys(&sample.join("poses"));
    run_set("sample", &sample_poses, Some(&labels))?;
    if let Some(dir) = desal_testdata::scape_dir() {
        let files = desal_testdata::scape_files(&dir);
        run_set("scape", &files[..10], None)?;
    } else {
        println!("scape: skipped (no ../shared/datasets)");
    }
    Ok(())
}

fn sorted_plys(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("pose folder is readable")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "ply"))
        .collect();
    files.sort();
    files
}

/// Every case on the template `files[0]`, and multi-pose on all of `files`.
fn run_set(name: &str, files: &[PathBuf], labels: Option<&[u32]>) -> Result<(), Box<dyn std::error::Error>> {
    let mesh = desal_io::read_mesh(&files[0])?;
    let n = mesh.positions.len();
    // Smooth, deterministic stand-ins for saliency weights and keep penalties.
    let weights: Vec<f64> = mesh
        .positions
        .iter()
        .map(|p| 0.05 + 0.95 * (7.0 * p.x).sin().abs() * (3.0 * p.y).cos().abs())
        .collect();
    let penalty: Vec<f64> = (0..n).map(|i| ((i * 2_654_435_761) % 1000) as f64 * 1e-7).collect();
    // Seams: every edge between two different parts (the sample), or the edges crossing
    // a plane through the body (SCAPE: a seam loop per limb it cuts).
    let side: Vec<u32> = match labels {
        Some(l) => l.to_vec(),
        None => mesh.positions.iter().map(|p| u32::from(p.y > 0.0)).collect(),
    };
    let mut seams: Vec<[u32; 2]> = Vec::new();
    for f in &mesh.faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            if side[a as usize] != side[b as usize] && a < b {
                seams.push([a, b]);
            }
        }
    }
    let faces = mesh.faces.len();
    let targets = [
        Target::Faces(5000),
        Target::Faces(faces / 5),
        Target::Faces(1000),
        Target::Vertices(300),
        Target::Ratio(0.6),
    ];
    let plain = |target| SimplifyConfig::qslim(target);
    type Case<'a> = (&'static str, SimplifyConfig, SimplifyInput<'a>);
    let input = SimplifyInput::new(&mesh);
    for target in targets {
        let cases: Vec<Case> = vec![
            ("qslim-optimal", plain(target), input),
            ("qslim-subset", SimplifyConfig { placement: Placement::Subset, ..plain(target) }, input),
            ("lt-optimal", SimplifyConfig { metric: Metric::LindstromTurk, ..plain(target) }, input),
            (
                "lt-subset",
                SimplifyConfig {
                    metric: Metric::LindstromTurk,
                    placement: Placement::Subset,
                    ..plain(target)
                },
                input,
            ),
            ("paper-optimal", SimplifyConfig::paper(target), input.with_weights(&weights)),
            (
                "paper-subset",
                SimplifyConfig { placement: Placement::Subset, ..SimplifyConfig::paper(target) },
                input.with_weights(&weights),
            ),
            (
                "saliency-lt",
                SimplifyConfig { metric: Metric::LindstromTurk, ..SimplifyConfig::default() },
                input.with_weights(&weights),
            ),
            ("normalized", SimplifyConfig { normalized_error: true, ..plain(target) }, input),
            (
                "keep-penalty",
                SimplifyConfig { placement: Placement::Subset, ..plain(target) },
                input.with_keep_penalty(&penalty),
            ),
            ("seams-optimal", plain(target), input.with_seams(&seams)),
            (
                "seams-subset",
                SimplifyConfig { placement: Placement::Subset, ..plain(target) },
                input.with_seams(&seams),
            ),
            ("seams-paper", SimplifyConfig::paper(target), input.with_weights(&weights).with_seams(&seams)),
            ("guards-off", SimplifyConfig { max_corner_normal_deg: 180.0, ..plain(target) }, input),
        ];
        let mut cases = cases;
        if let Some(labels) = labels {
            cases.push((
                "parts-lock",
                SimplifyConfig { part_borders: PartBorders::Lock, ..plain(target) },
                input.with_part_labels(labels),
            ));
            cases.push((
                "parts-constrain",
                SimplifyConfig { part_borders: PartBorders::Constrain(5.0), ..SimplifyConfig::paper(target) },
                input.with_part_labels(labels).with_weights(&weights),
            ));
        }
        for (case, config, input) in cases {
            let config = SimplifyConfig { target, ..config };
            let out = simplify(&input, &config)?;
            print(name, case, target, &out);
        }
    }
    let poses: Vec<_> =
        files.iter().map(|f| desal_io::read_mesh(f).map(|m| m.positions)).collect::<Result<_, _>>()?;
    let names = files.iter().map(|f| f.display().to_string()).collect();
    let pose_set = PoseSet::try_new(names, poses, mesh.faces.clone(), 0)?;
    for target in [Target::Faces(faces / 5), Target::Vertices(300)] {
        let out = simplify_multipose(&pose_set, Some(&weights), labels, &SimplifyConfig::paper(target))?;
        print(name, "multipose-paper", target, &out);
        let out = simplify_multipose(&pose_set, None, None, &SimplifyConfig::qslim(target))?;
        print(name, "multipose-qslim", target, &out);
    }
    Ok(())
}

fn print(set: &str, case: &str, target: Target, out: &Simplified) {
    println!("{set} {case} {target:?}: {:016x} ({} faces)", hash(out), out.mesh.faces.len());
}

/// The output's exact bits: positions, faces, `simp_to_orig`, and the report's counts and
/// errors (its seconds aside).
fn hash(out: &Simplified) -> u64 {
    let TriMesh { positions, faces } = &out.mesh;
    let r = &out.report;
    let mut h = Fnv::default();
    h.points(positions).indices(faces.iter().flatten().copied());
    h.indices(out.simp_to_orig.iter().map(|o| o.unwrap_or(u32::MAX)));
    let refusals =
        [r.refusals.topology, r.refusals.flip, r.refusals.degenerate, r.refusals.fold, r.refusals.seam];
    let counts = [r.output_vertices, r.output_faces, r.collapses, r.locked_vertices, r.seam_vertices];
    h.indices(refusals.into_iter().chain(counts).map(|c| c as u32));
    h.f64s([r.max_error, r.mean_error, r.edge_length_mean, r.edge_length_variance]);
    h.word(u64::from(r.stop == desal_simplify::StopReason::TargetReached));
    h.finish()
}
