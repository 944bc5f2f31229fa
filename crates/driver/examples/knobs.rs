//! The paper's knobs, measured (issue 4): on SCAPE, 12500 → 2500 vertices with stage 2's
//! saliency, where do plain QSlim, the saliency cost and the paper's saliency + balance
//! cost put their vertices (per body part; joint regions against the rigid head, hands
//! and feet), how even are their edges (paper Fig. 3), how far is each result from the
//! original surface, and what does the saliency-weight floor change. Writes the tables
//! (`tables.md`) and the face-area and saliency heat maps to `docs/knobs/`; the
//! discussion is in `docs/KNOBS.md`.
//!
//! Run: `cargo run --release --example knobs [-- --out DIR --rings N --work DIR]`.
//! When `../shared/datasets/scape` is absent (a user's clone, which has no SCAPE) it
//! prints `skipped: ...` and exits 0.
//!
//! The story:
//! 1. run the SCAPE pipeline with the driver (in a temporary output folder unless
//!    `--work` names one, whose cache then makes reruns fast) and read the ingested
//!    template, the part labels and the saliency back from its artifacts;
//! 2. mark the joint regions: original vertices within `--rings` edge rings of a part
//!    border, where saliency peaks;
//! 3. simplify the template with each method in both placements, and with the paper's
//!    method at each weight floor;
//! 4. tabulate vertices and face areas per body part and per region, edge-length
//!    statistics, and the surface error against the template;
//! 5. render the face-area heat maps, one colour range for all methods, and the saliency.
//!
//! Every step is deterministic (the simplifier and the renderer are; the tables iterate
//! in index order), so rerunning rewrites byte-identical files.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result, ensure};
use clap::Parser;
use desal_driver::pipeline;
use desal_driver::progress::Lines;
use desal_driver::run::{RunOptions, run};
use desal_io::artifact::{LabelsV1, PoseSetV2, SaliencyV1, SimplifiedV1, read_artifact};
use desal_measures::{SurfaceIndex, VertexIndex, v2f};
use desal_mesh::{EdgeTopology, TriMesh, Vec3};
use desal_simplify::{Placement, Simplified, SimplifyConfig, SimplifyInput, StopReason, Target, simplify};
use desal_viz::{Direction, RenderConfig, Scalar};

const DATASET: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/datasets/scape");
const PIPELINE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/pipelines/scape.toml");
/// The bundled MakeHuman sample (same 16 part ids as SCAPE): skinned, so its rigid
/// vertices have a saliency of almost exactly 0, the case the floor exists for.
const SAMPLE_PIPELINE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/pipelines/sample.toml");
const DEFAULT_OUT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/knobs");

/// The paper's target: 12500 → 2500 vertices.
const TARGET_VERTICES: usize = 2500;
/// The weight floors swept for the paper's method (`w = floor + (1 − floor) · saliency`).
const FLOORS: [f64; 8] = [0.0, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0];
/// Stage 2's default floor: the sweep's reference, and what the driver's run used.
const DRIVER_FLOOR: f64 = 0.05;
/// Where [`DRIVER_FLOOR`] is in [`FLOORS`].
const DRIVER_FLOOR_INDEX: usize = 3;
const _: () = assert!(FLOORS[DRIVER_FLOOR_INDEX] == DRIVER_FLOOR);
/// Face areas are shown in cm² (SCAPE is in metres): ticks of 1.5 read better than 1.5e-4.
const CM2_PER_M2: f64 = 1e4;

/// SCAPE's part ids (`../shared/datasets/README.md`) grouped the way the paper's Figs.
/// 4–5 talk about them; left and right are pooled.
const PART_GROUPS: [(&str, &[u32]); 10] = [
    ("head", &[12]),
    ("hands", &[0, 3]),
    ("feet", &[6, 9]),
    ("upper arms", &[2, 5]),
    ("lower arms", &[1, 4]),
    ("upper legs", &[8, 11]),
    ("lower legs", &[7, 10]),
    ("chest", &[13]),
    ("stomach", &[14]),
    ("hip", &[15]),
];
/// The rigid extremities the paper says saliency takes vertices from.
const EXTREMITY_PARTS: [u32; 5] = [12, 0, 3, 6, 9];
/// Single parts whose kept vertex counts the floor sweep watches (a floor of 0 must not
/// let a rigid part collapse to nothing).
const WATCHED_PARTS: [(&str, u32); 5] =
    [("head", 12), ("left hand", 0), ("right hand", 3), ("left foot", 6), ("right foot", 9)];

/// The cost variants of Eq. 5 (`E = d · (w1 + w2)/2 · v̄ᵀ(Q1 + Q2)v̄`).
#[derive(Debug, Clone, Copy)]
struct Method {
    /// File-name key, e.g. `paper`.
    key: &'static str,
    name: &'static str,
    saliency: bool,
    balance: bool,
}

const METHODS: [Method; 4] = [
    Method { key: "qslim", name: "QSlim", saliency: false, balance: false },
    Method { key: "saliency", name: "saliency", saliency: true, balance: false },
    Method { key: "balance", name: "balance only", saliency: false, balance: true },
    Method { key: "paper", name: "saliency + balance (paper)", saliency: true, balance: true },
];

/// Where an original vertex sits: near a part border, inside a rigid extremity, or
/// inside another part.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Region {
    Joint,
    Extremity,
    Other,
}

const REGIONS: [(Region, &str); 3] = [
    (Region::Joint, "joint regions"),
    (Region::Extremity, "head/hands/feet (rest)"),
    (Region::Other, "limbs/torso (rest)"),
];

#[derive(Debug, Parser)]
#[command(about = "Measure the paper's knobs (saliency, balance, weight floor) on SCAPE")]
struct Args {
    /// Folder for tables.md and the PNG heat maps.
    #[arg(long, default_value = DEFAULT_OUT)]
    out: PathBuf,
    /// Joint region: original vertices within this many edge rings of a part border.
    #[arg(long, default_value_t = 3)]
    rings: usize,
    /// Output folder for the driver's run (kept, so its cache makes reruns fast);
    /// default: a temporary folder, removed afterwards.
    #[arg(long)]
    work: Option<PathBuf>,
}

/// A pipeline's template, labels and saliency, in `orig_idx` space.
#[derive(Debug)]
struct Dataset {
    template: TriMesh,
    labels: Vec<u32>,
    regions: Vec<Region>,
    /// Stage 2's saliency in `[0, 1]`, before any floor.
    saliency: Vec<f64>,
    /// The driver's stage-3 result (the paper's method, optimal, floor 0.05).
    driver_simplified: SimplifiedV1,
}

impl Dataset {
    /// Stage-3 weights at `floor`: `w = floor + (1 − floor) · saliency`, as stage 2 does.
    fn weights(&self, floor: f64) -> Vec<f64> {
        self.saliency.iter().map(|&s| desal_saliency::weight(s, floor)).collect()
    }
}

/// One simplification and its measurements.
#[derive(Debug)]
struct Measured {
    result: Simplified,
    /// Per simplified vertex and per simplified face (centroid), the nearest original
    /// vertex: the label and region they are counted under.
    vertex_orig: Vec<u32>,
    face_orig: Vec<u32>,
    face_area: Vec<f64>,
    /// Per original vertex, the squared distance to the simplified surface, m².
    orig_error_sq: Vec<f64>,
    /// Symmetric v2f (paper Eq. 6) against the template, m².
    v2f: f64,
    /// Largest weight over the smallest: how much cheaper the least salient collapse is.
    weight_ratio: f64,
}

fn main() -> ExitCode {
    let args = Args::parse();
    if !Path::new(DATASET).is_dir() {
        eprintln!("skipped: SCAPE is not at {DATASET} (research-use data, not in the repository)");
        return ExitCode::SUCCESS;
    }
    match measure_knobs(&args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => desal_driver::report_error(&error),
    }
}

/// The orchestrator: steps 1–5 of the module doc.
fn measure_knobs(args: &Args) -> Result<()> {
    let started = Instant::now();
    let temporary = match &args.work {
        Some(_) => None,
        None => Some(tempfile::tempdir().context("cannot create a temporary folder")?),
    };
    let work = args.work.as_deref().or(temporary.as_ref().map(|t| t.path())).expect("one of the two is set");
    let scape = load_dataset(Path::new(PIPELINE), work, args.rings)?;
    let sample = load_dataset(Path::new(SAMPLE_PIPELINE), work, args.rings)?;
    let target = Target::Vertices(TARGET_VERTICES);

    let mut report = String::new();
    writeln!(report, "# The paper's knobs on SCAPE: generated tables\n")?;
    writeln!(
        report,
        "Generated by `cargo run --release --example knobs` (`examples/knobs.rs`); do not edit by hand. \
         SCAPE template `mesh000`, {} → {TARGET_VERTICES} vertices; stage 2 saliency of the 71 poses \
         (plain distances, max normalisation). Joint regions: original vertices within {} edge rings of a \
         part border. Faces and vertices of a result are counted under the part and region of the \
         original vertex nearest to them (faces: to their centroid). Areas in cm², errors in m².\n",
        scape.template.vertex_count(),
        args.rings
    )?;
    write_region_summary(&mut report, &scape)?;

    let mut runs: Vec<(Method, Placement, Measured)> = Vec::new();
    for placement in [Placement::Optimal, Placement::Subset] {
        for method in METHODS {
            let config = SimplifyConfig {
                placement,
                saliency: method.saliency,
                balance: method.balance,
                ..SimplifyConfig::qslim(target)
            };
            runs.push((method, placement, simplify_and_measure(&scape, DRIVER_FLOOR, &config)?));
        }
    }
    check_against_driver(&scape, &runs[3].2)?;
    write_part_table(&mut report, &scape, &runs)?;
    write_region_table(&mut report, &scape, &runs)?;
    write_edge_table(&mut report, &runs)?;

    writeln!(report, "## Weight floor, paper's method, optimal placement\n")?;
    write_floor_table(&mut report, &scape, &sweep_floors(&scape, target)?)?;
    writeln!(
        report,
        "### The same sweep on the bundled MakeHuman sample ({} → {TARGET_VERTICES} vertices)\n\n\
         Linear-blend skinned, so vertices bound to one bone move rigidly: saliency ranges from \
         {:.1e} to 1, mean {:.3}.\n",
        sample.template.vertex_count(),
        min_max(&sample.saliency).0,
        mean(&sample.saliency)
    )?;
    let sample_sweep = sweep_floors(&sample, target)?;
    check_against_driver(&sample, &sample_sweep[DRIVER_FLOOR_INDEX].1)?;
    write_floor_table(&mut report, &sample, &sample_sweep)?;

    std::fs::create_dir_all(&args.out).with_context(|| format!("cannot create {}", args.out.display()))?;
    render_pictures(&args.out, &scape, &runs)?;
    let tables = args.out.join("tables.md");
    std::fs::write(&tables, &report).with_context(|| format!("cannot write {}", tables.display()))?;
    print!("{report}");
    eprintln!("wrote {} and the heat maps in {:.1} s", tables.display(), started.elapsed().as_secs_f64());
    Ok(())
}

/// Step 1: runs a pipeline file's (single) dataset with the driver, output under
/// `work`, and reads back its artifacts; step 2 on the template.
fn load_dataset(pipeline_file: &Path, work: &Path, rings: usize) -> Result<Dataset> {
    let pipeline = pipeline::load(pipeline_file, Some(work))?;
    let options = RunOptions { console: std::sync::Arc::new(Lines { quiet: true }), ..RunOptions::default() };
    let reports = run(&pipeline, &options)?;
    let dir = reports.first().context("the pipeline ran no dataset")?.out_dir.clone();
    let (_, poses, _) = read_artifact::<PoseSetV2>(&dir.join("poses.dsa"))?;
    let (_, labels, _) = read_artifact::<LabelsV1>(&dir.join("labels.dsa"))?;
    let (_, saliency, _) = read_artifact::<SaliencyV1>(&dir.join("saliency.dsa"))?;
    let (_, driver_simplified, _) = read_artifact::<SimplifiedV1>(&dir.join("simplified.dsa"))?;
    ensure!(
        saliency.weight_floor == DRIVER_FLOOR,
        "{}: the weight floor is {}, this report assumes {DRIVER_FLOOR}",
        pipeline_file.display(),
        saliency.weight_floor
    );
    let template = poses.to_pose_set()?.template_mesh();
    let n = template.vertex_count();
    ensure!(
        labels.labels.len() == n && saliency.saliency.len() == n,
        "labels or saliency do not fit the template"
    );
    ensure!(labels.labels.iter().all(|&l| l < 16), "expected SCAPE's 16 part ids");
    let regions = classify_regions(&template, &labels.labels, rings);
    Ok(Dataset { template, labels: labels.labels, regions, saliency: saliency.saliency, driver_simplified })
}

/// Step 3, the floor: the paper's method at each of [`FLOORS`].
fn sweep_floors(data: &Dataset, target: Target) -> Result<Vec<(f64, Measured)>> {
    FLOORS
        .iter()
        .map(|&floor| Ok((floor, simplify_and_measure(data, floor, &SimplifyConfig::paper(target))?)))
        .collect()
}

/// Step 2: per original vertex, its region. Part-border vertices are those with a
/// neighbour of another part; a breadth-first search counts rings out from them.
fn classify_regions(template: &TriMesh, labels: &[u32], rings: usize) -> Vec<Region> {
    let n = template.vertex_count();
    let (offsets, neighbours) = EdgeTopology::new(&template.faces).vertex_neighbours(n);
    let around = |v: usize| &neighbours[offsets[v] as usize..offsets[v + 1] as usize];
    let mut ring = vec![usize::MAX; n];
    let mut frontier: Vec<usize> =
        (0..n).filter(|&v| around(v).iter().any(|&u| labels[u as usize] != labels[v])).collect();
    for &v in &frontier {
        ring[v] = 0;
    }
    for depth in 1..=rings {
        let mut next = Vec::new();
        for &v in &frontier {
            for &u in around(v) {
                if ring[u as usize] == usize::MAX {
                    ring[u as usize] = depth;
                    next.push(u as usize);
                }
            }
        }
        frontier = next;
    }
    (0..n)
        .map(|v| {
            if ring[v] <= rings {
                Region::Joint
            } else if EXTREMITY_PARTS.contains(&labels[v]) {
                Region::Extremity
            } else {
                Region::Other
            }
        })
        .collect()
}

/// Step 3: one simplification of the template, with what the tables need.
fn simplify_and_measure(data: &Dataset, floor: f64, config: &SimplifyConfig) -> Result<Measured> {
    let weights = data.weights(floor);
    let input = SimplifyInput::new(&data.template).with_weights(&weights);
    let result = simplify(&input, config)?;
    let mesh = &result.mesh;
    let originals = VertexIndex::new(&data.template.positions);
    let vertex_orig = mesh.positions.iter().map(|p| nearest_original(&originals, p)).collect();
    let face_orig = face_owners(mesh, &originals);
    let face_area = face_areas(mesh);
    let orig_error_sq = SurfaceIndex::new(mesh).distances_sq(&data.template.positions);
    let v2f = v2f(mesh, &data.template);
    let (lightest, heaviest) = min_max(&weights);
    let weight_ratio = heaviest / lightest;
    Ok(Measured { result, vertex_orig, face_orig, face_area, orig_error_sq, v2f, weight_ratio })
}

/// The example's paper/optimal run at the driver's floor must be the driver's stage 3,
/// bit for bit: the same template, weights and config.
fn check_against_driver(data: &Dataset, paper: &Measured) -> Result<()> {
    let ours: Vec<[f64; 3]> = paper.result.mesh.positions.iter().map(|p| [p.x, p.y, p.z]).collect();
    ensure!(
        ours == data.driver_simplified.positions && paper.result.mesh.faces == data.driver_simplified.faces,
        "the paper's method here differs from the driver's simplified.dsa: the pipeline's simplify \
         parameters are not what this report assumes"
    );
    Ok(())
}

/// Per original vertex: which of `PART_GROUPS` it belongs to.
fn group_of(label: u32) -> usize {
    PART_GROUPS.iter().position(|(_, ids)| ids.contains(&label)).expect("SCAPE labels are 0..=15")
}

fn write_region_summary(report: &mut String, data: &Dataset) -> Result<()> {
    writeln!(report, "## Regions of the original template\n")?;
    let mut rows = Vec::new();
    for (region, name) in REGIONS {
        let members = data.regions.iter().filter(|&&r| r == region).count();
        let saliency = mean_over_region(&data.saliency, &data.regions, region);
        rows.push(vec![name.to_owned(), members.to_string(), format!("{saliency:.3}")]);
    }
    let (lo, hi) = min_max(&data.saliency);
    rows.push(vec!["all".into(), data.regions.len().to_string(), format!("{:.3}", mean(&data.saliency))]);
    write_table(report, &["region", "original vertices", "mean saliency"], &rows)?;
    writeln!(report, "Saliency over all vertices ranges from {lo:.4} to {hi:.4}.\n")?;
    Ok(())
}

/// Table 1: per body-part group, vertices kept and mean face area, per method.
fn write_part_table(
    report: &mut String,
    data: &Dataset,
    runs: &[(Method, Placement, Measured)],
) -> Result<()> {
    for placement in [Placement::Optimal, Placement::Subset] {
        writeln!(report, "## Per body part, {} placement\n", placement_name(placement))?;
        writeln!(
            report,
            "Simplified vertices (and mean face area, cm²) per group; `orig` is the template (12500 vertices, \
             mean face area {:.3} cm²).\n",
            mean(&face_areas(&data.template)) * CM2_PER_M2
        )?;
        let chosen: Vec<&(Method, Placement, Measured)> = runs.iter().filter(|r| r.1 == placement).collect();
        let mut header = vec!["part".to_owned(), "orig V".to_owned()];
        header.extend(chosen.iter().map(|r| r.0.name.to_owned()));
        let template_owner = face_owners(&data.template, &VertexIndex::new(&data.template.positions));
        let template_area = face_areas(&data.template);
        let mut rows = Vec::new();
        for (g, (name, _)) in PART_GROUPS.iter().enumerate() {
            let orig_v = data.labels.iter().filter(|&&l| group_of(l) == g).count();
            let in_group = |v: u32| group_of(data.labels[v as usize]) == g;
            let orig_area = mean_where(&template_area, &template_owner, in_group);
            let mut row = vec![(*name).to_owned(), format!("{orig_v} ({:.2})", orig_area * CM2_PER_M2)];
            for (_, _, m) in &chosen {
                let kept = m.vertex_orig.iter().filter(|&&v| in_group(v)).count();
                let area = mean_where(&m.face_area, &m.face_orig, in_group);
                row.push(format!("{kept} ({:.2})", area * CM2_PER_M2));
            }
            rows.push(row);
        }
        let header: Vec<&str> = header.iter().map(String::as_str).collect();
        write_table(report, &header, &rows)?;
    }
    Ok(())
}

/// Table 2: the same split by region, with each region's surface error.
fn write_region_table(
    report: &mut String,
    data: &Dataset,
    runs: &[(Method, Placement, Measured)],
) -> Result<()> {
    writeln!(report, "## Joint regions against the rest\n")?;
    writeln!(
        report,
        "Per region: simplified vertices / mean face area (cm²) / mean squared distance of the region's \
         original vertices to the simplified surface (m², the template's half of v2f).\n"
    )?;
    let mut rows = Vec::new();
    for (method, placement, m) in runs {
        let mut row = vec![format!("{} ({})", method.name, placement_name(*placement))];
        for (region, _) in REGIONS {
            let in_region = |v: u32| data.regions[v as usize] == region;
            let kept = m.vertex_orig.iter().filter(|&&v| in_region(v)).count();
            let area = mean_where(&m.face_area, &m.face_orig, in_region);
            let error = mean_over_region(&m.orig_error_sq, &data.regions, region);
            row.push(format!("{kept} / {:.2} / {error:.2e}", area * CM2_PER_M2));
        }
        rows.push(row);
    }
    let mut header = vec!["method (placement)"];
    header.extend(REGIONS.iter().map(|(_, name)| *name));
    write_table(report, &header, &rows)?;
    Ok(())
}

/// Table 3: the paper's Fig. 3 figure and the surface error.
fn write_edge_table(report: &mut String, runs: &[(Method, Placement, Measured)]) -> Result<()> {
    writeln!(report, "## Edge lengths and surface error\n")?;
    writeln!(
        report,
        "Edge-length mean (m) and population variance (m², `report.edge_length_variance`, the paper's \
         Fig. 3 figure), the squared coefficient of variation var/mean² (unit-free), and v2f against the \
         template (m², paper Eq. 6).\n"
    )?;
    let mut rows = Vec::new();
    for (method, placement, m) in runs {
        let r = &m.result.report;
        rows.push(vec![
            format!("{} ({})", method.name, placement_name(*placement)),
            format!("{} / {}", r.output_vertices, r.output_faces),
            format!("{:.4}", r.edge_length_mean),
            format!("{:.3e}", r.edge_length_variance),
            format!("{:.4}", r.edge_length_variance / (r.edge_length_mean * r.edge_length_mean)),
            format!("{:.3e}", m.v2f),
            stop_name(r.stop).to_owned(),
        ]);
    }
    write_table(
        report,
        &["method (placement)", "V / F", "edge mean", "edge variance", "var/mean²", "v2f", "stop"],
        &rows,
    )?;
    Ok(())
}

/// Table 4: a weight-floor sweep of the paper's method (optimal placement).
fn write_floor_table(report: &mut String, data: &Dataset, sweep: &[(f64, Measured)]) -> Result<()> {
    writeln!(
        report,
        "`w = floor + (1 − floor) · saliency`; `w max/min`: the largest weight over the smallest (how many \
         times cheaper the least salient collapse is). Simplified vertices per region and per watched \
         part; v2f against the template (m²); `err`: mean squared distance of the region's original \
         vertices to the result (m²). Floor 1 is balance only (all weights 1).\n"
    )?;
    let mut rows = Vec::new();
    for (floor, m) in sweep {
        let ratio = m.weight_ratio;
        let ratio = if ratio < 1e3 { format!("{ratio:.1}") } else { format!("{ratio:.1e}") };
        let mut row = vec![format!("{floor}"), ratio];
        for (region, _) in REGIONS {
            row.push(
                m.vertex_orig.iter().filter(|&&v| data.regions[v as usize] == region).count().to_string(),
            );
        }
        for (_, part) in WATCHED_PARTS {
            row.push(m.vertex_orig.iter().filter(|&&v| data.labels[v as usize] == part).count().to_string());
        }
        row.push(format!("{:.3e}", m.v2f));
        for region in [Region::Extremity, Region::Joint] {
            row.push(format!("{:.2e}", mean_over_region(&m.orig_error_sq, &data.regions, region)));
        }
        row.push(format!("{:.3e}", m.result.report.edge_length_variance));
        rows.push(row);
    }
    let mut header = vec!["floor", "w max/min", "V joint", "V extremity", "V other"];
    header.extend(WATCHED_PARTS.iter().map(|(name, _)| *name));
    header.extend(["v2f", "err extremity", "err joint", "edge var"]);
    write_table(report, &header, &rows)?;
    Ok(())
}

/// Step 5: face-area heat maps of every method (optimal placement) on one colour range,
/// and the saliency heat map on the template.
fn render_pictures(out: &Path, data: &Dataset, runs: &[(Method, Placement, Measured)]) -> Result<()> {
    let optimal: Vec<&(Method, Placement, Measured)> =
        runs.iter().filter(|r| r.1 == Placement::Optimal).collect();
    let mut all_areas: Vec<f64> =
        optimal.iter().flat_map(|r| r.2.face_area.iter().map(|a| a * CM2_PER_M2)).collect();
    all_areas.sort_by(f64::total_cmp);
    // The 99th percentile, not the maximum: a few long slivers would wash out the rest.
    let top = all_areas[(all_areas.len() * 99) / 100];
    for (method, _, m) in optimal {
        let areas: Vec<f64> = m.face_area.iter().map(|a| a * CM2_PER_M2).collect();
        let title = format!("face area: {}", method.name);
        let path = out.join(format!("face-area-{}.png", method.key));
        write_heatmap(&path, &m.result.mesh, Scalar::PerFace(&areas), &title, "cm^2", (0.0, top))?;
    }
    let path = out.join("saliency.png");
    write_heatmap(
        &path,
        &data.template,
        Scalar::PerVertex(&data.saliency),
        "deformation saliency",
        "0-1",
        (0.0, 1.0),
    )
}

fn write_heatmap(
    path: &Path,
    mesh: &TriMesh,
    scalar: Scalar,
    title: &str,
    units: &str,
    range: (f64, f64),
) -> Result<()> {
    let config = RenderConfig {
        up: Some(Direction::PosX),
        title: title.into(),
        units: units.into(),
        range: Some(range),
        ..RenderConfig::default()
    };
    let png = desal_viz::encode_png(&desal_viz::render_heatmap(mesh, scalar, &config)?)?;
    std::fs::write(path, png).with_context(|| format!("cannot write {}", path.display()))
}

/// The original vertex nearest to `p` (`orig_idx`; the lowest index among equals).
fn nearest_original(originals: &VertexIndex, p: &Vec3) -> u32 {
    originals.nearest(p).map(|(v, _)| v).expect("the template has vertices")
}

/// Per face of `mesh`, the original vertex nearest to its centroid.
fn face_owners(mesh: &TriMesh, originals: &VertexIndex) -> Vec<u32> {
    (0..mesh.face_count())
        .map(|f| {
            let [a, b, c] = mesh.corners(f);
            nearest_original(originals, &((a + b + c) / 3.0))
        })
        .collect()
}

/// Per face, its area in squared mesh units (m² for SCAPE).
fn face_areas(mesh: &TriMesh) -> Vec<f64> {
    (0..mesh.face_count()).map(|f| mesh.face_area(f)).collect()
}

/// The mean of `values[i]` over the `i` whose `owner[i]` passes `keep` (0 when none do).
fn mean_where(values: &[f64], owner: &[u32], keep: impl Fn(u32) -> bool) -> f64 {
    let (sum, count) = values
        .iter()
        .zip(owner)
        .filter(|(_, o)| keep(**o))
        .fold((0.0, 0usize), |(s, n), (v, _)| (s + v, n + 1));
    if count == 0 { 0.0 } else { sum / count as f64 }
}

/// The mean of a per-original-vertex quantity over the vertices of `region`.
fn mean_over_region(per_orig: &[f64], regions: &[Region], region: Region) -> f64 {
    let (sum, count) = per_orig
        .iter()
        .zip(regions)
        .filter(|(_, r)| **r == region)
        .fold((0.0, 0usize), |(s, n), (v, _)| (s + v, n + 1));
    if count == 0 { 0.0 } else { sum / count as f64 }
}

fn mean(values: &[f64]) -> f64 {
    values.iter().sum::<f64>() / values.len().max(1) as f64
}

fn min_max(values: &[f64]) -> (f64, f64) {
    values.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)))
}

fn placement_name(placement: Placement) -> &'static str {
    match placement {
        Placement::Optimal => "optimal",
        Placement::Subset => "subset",
    }
}

fn stop_name(stop: StopReason) -> &'static str {
    match stop {
        StopReason::TargetReached => "target",
        StopReason::NoValidCollapse => "no valid collapse",
    }
}

/// A GitHub-flavoured markdown table followed by a blank line.
fn write_table(report: &mut String, header: &[&str], rows: &[Vec<String>]) -> Result<()> {
    writeln!(report, "| {} |", header.join(" | "))?;
    writeln!(report, "|{}", "---|".repeat(header.len()))?;
    for row in rows {
        writeln!(report, "| {} |", row.join(" | "))?;
    }
    writeln!(report)?;
    Ok(())
}
