//! Shared helpers: a tiny two-part tube pose set written to a temp folder, and running
//! the `desal` binary on it.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use desal_io::ply::{PlyWriteOptions, write_ply};
use desal_mesh::{TriMesh, Vec3};

/// `../shared/datasets/<name>`, or `None` after printing why the test skips (a failure
/// instead under `.ci/run`); see `desal-testdata`.
pub fn shared_dataset(name: &str) -> Option<PathBuf> {
    desal_testdata::shared_dataset(name)
}

/// A closed tube along +y: `rings` rings of `segments` vertices plus two cap centres.
pub fn tube(rings: usize, segments: usize) -> TriMesh {
    desal_testdata::golden::tube_shaped(rings, segments, 0.0, 0.0)
}

/// Bends the upper half of `mesh` (y above the middle) about the z axis by `angle`.
pub fn bend(mesh: &TriMesh, angle: f64) -> TriMesh {
    let ymax = mesh.positions.iter().map(|p| p.y).fold(0.0, f64::max);
    let pivot = Vec3::new(0.0, ymax / 2.0, 0.0);
    let (s, c) = angle.sin_cos();
    let positions = mesh
        .positions
        .iter()
        .map(|p| {
            if p.y <= pivot.y {
                return *p;
            }
            let d = p - pivot;
            pivot + Vec3::new(c * d.x - s * d.y, s * d.x + c * d.y, d.z)
        })
        .collect();
    TriMesh { positions, faces: mesh.faces.clone() }
}

/// Writes a pose set of the tube (rest + bent poses), labels (lower/upper half) and a
/// pipeline file into `dir`; returns the pipeline path.
pub fn write_tube_dataset(dir: &Path, extra_toml: &str) -> PathBuf {
    let rest = tube(12, 10);
    std::fs::create_dir_all(dir.join("poses")).unwrap();
    for (k, angle) in [0.0, 0.3, 0.6, -0.4].into_iter().enumerate() {
        write_ply(&dir.join(format!("poses/p{k}.ply")), &bend(&rest, angle), &PlyWriteOptions::default())
            .unwrap();
    }
    let ymid = 11.0 * 0.05 / 2.0;
    let labels: Vec<String> =
        rest.positions.iter().map(|p| if p.y <= ymid { "0" } else { "1" }.to_owned()).collect();
    std::fs::write(dir.join("labels.txt"), format!("# ids: 0=lower, 1=upper\n{}\n", labels.join("\n")))
        .unwrap();
    let pipeline = dir.join("pipeline.toml");
    std::fs::write(
        &pipeline,
        format!(
            "schema = 1\nout = \"out\"\n\n[[dataset]]\nname = \"tube\"\nposes = \"poses/*.ply\"\nlabels = \"labels.txt\"\n{extra_toml}\n"
        ),
    )
    .unwrap();
    pipeline
}

/// Runs `desal` with `args`, writing the default viewer page whatever the caller's
/// `DESAL_THREE` says.
pub fn desal(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_desal"))
        .args(args)
        .env_remove(desal_rig::viewer::THREE_ENV)
        .output()
        .expect("desal runs")
}

pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Runs the pipeline quietly and returns the parsed report.json of dataset `name`.
pub fn run_ok(pipeline: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["run", pipeline.to_str().unwrap(), "--quiet"];
    args.extend_from_slice(extra);
    let out = desal(&args);
    assert!(out.status.success(), "desal failed: {}", stderr(&out));
    let report = pipeline.parent().unwrap().join("out/tube/report.json");
    serde_json::from_slice(&std::fs::read(report).unwrap()).unwrap()
}

/// The stages a run computed (not served by the cache), in run order, from its report.
pub fn ran(report: &serde_json::Value) -> Vec<String> {
    report["stages"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| !s["cached"].as_bool().unwrap())
        .map(|s| s["name"].as_str().unwrap().to_owned())
        .collect()
}
