//! Discovers the parts of a directory of registered PLY/OBJ poses (sorted by name, the
//! first one the template) and draws them on the template, one colour per part, as a
//! PNG — what the driver's `parts.png` will show. With a label file, also draws the
//! given parts beside them (each discovered part in the colour of the given part it
//! overlaps most) and prints the adjusted Rand index and stage 1's residual of both.
//!
//! `cargo run --release -p desal-parts --example parts_png -- POSE_DIR OUT.png [K] [LABELS]`
//!
//! SCAPE: `... -- ../shared/datasets/scape /tmp/scape-parts.png 16 ../shared/datasets/scape/vertex_part_labels_16.txt`
//! The sample: `... -- data-samples/poses /tmp/sample-parts.png 16 data-samples/labels.txt`

use std::path::{Path, PathBuf};
use std::time::Instant;

use desal_fit::{FitConfig, fit_pose_set};
use desal_mesh::{NoProgress, PartLabels, PoseSet};
use desal_parts::{PartsConfig, adjusted_rand_index, discover_parts};
use desal_viz::{RenderConfig, RgbaImage, Scalar, encode_png, render_heatmap};

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if !(2..=4).contains(&args.len()) {
        eprintln!("usage: parts_png POSE_DIR OUT.png [K] [LABELS]");
        std::process::exit(2);
    }
    let poses = read_poses(Path::new(&args[0]));
    let parts = args.get(2).map(|k| k.parse::<usize>().expect("K is a whole number"));
    let given = args.get(3).map(|p| desal_io::labels::read_labels(Path::new(p)).expect("label file"));

    let start = Instant::now();
    let cpu_start = cpu_seconds();
    let config = PartsConfig { parts, ..PartsConfig::default() };
    let (auto, report) = discover_parts(&poses, &config).expect("discovery");
    let cpu = cpu_seconds()
        .zip(cpu_start)
        .map_or("?".to_owned(), |(end, start)| format!("{:.0}", (end - start) * 1e3));
    println!(
        "{} poses x {} vertices: {} parts in {:.0} ms wall, {cpu} ms CPU over all threads ({} border sweeps), mean residual {:.3} mm",
        poses.pose_count(),
        poses.vertex_count(),
        auto.part_count(),
        start.elapsed().as_secs_f64() * 1e3,
        report.sweeps,
        report.mean_residual * 1e3
    );
    println!("parts: mean residual (mm) before the borders are relaxed");
    for point in &report.curve {
        let mark = if point.parts == report.parts { "  <- returned" } else { "" };
        println!("  {:>3}: {:8.3}{mark}", point.parts, point.mean_residual * 1e3);
    }
    println!("part sizes: {:?}", report.part_sizes);

    let mut panels = Vec::new();
    if let Some(given) = &given {
        // Each discovered part takes the colour of the given part it overlaps most, so
        // that the two drawings compare at a glance.
        let mut colour = vec![0u32; auto.part_count()];
        for (k, members) in auto.members().iter().enumerate() {
            let mut overlap = vec![0usize; given.part_count()];
            for &v in members {
                overlap[given.labels[v as usize] as usize] += 1;
            }
            colour[k] =
                (0..overlap.len()).max_by_key(|&g| (overlap[g], std::cmp::Reverse(g))).unwrap_or(0) as u32;
            println!(
                "  part {k:>2}: {:>5} vertices, {:>5.1} % in given part {} ('{}')",
                members.len(),
                100.0 * overlap[colour[k] as usize] as f64 / members.len() as f64,
                colour[k],
                given.names[colour[k] as usize]
            );
        }
        let matched = PartLabels::from_ids(auto.labels.iter().map(|&k| colour[k as usize]).collect());
        panels.push(draw(&poses, &matched, &format!("{} discovered parts", auto.part_count())));
        let residual = |labels: &PartLabels| {
            fit_pose_set(&poses, labels, &FitConfig::default(), &NoProgress)
                .expect("fit")
                .summary
                .mean_residual
                * 1e3
        };
        println!(
            "against the given labels: ARI {:.3}; mean residual {:.3} mm (given {:.3} mm)",
            adjusted_rand_index(&auto.labels, &given.labels),
            residual(&auto),
            residual(given)
        );
        panels.push(draw(&poses, given, &format!("{} given parts", given.part_count())));
    } else {
        panels.push(draw(&poses, &auto, &format!("{} discovered parts", auto.part_count())));
    }
    let out = &args[1];
    std::fs::write(out, encode_png(&RgbaImage::hstack(&panels, [255, 255, 255, 255])).expect("png"))
        .expect("write png");
    println!("wrote {out}");
}

/// CPU time of this process so far (user + system, every thread), from Linux's
/// `/proc/self/stat` in clock ticks of 1/100 s (`USER_HZ`); `None` elsewhere. The wall
/// time of a shared machine says little; this says what the run cost.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = &stat[stat.rfind(')')? + 2..];
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

fn read_poses(dir: &Path) -> PoseSet {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .expect("pose directory")
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.extension().is_some_and(|e| e == "ply" || e == "obj"))
        .collect();
    files.sort();
    let meshes: Vec<_> = files.iter().map(|f| desal_io::read_mesh(f).expect("pose file")).collect();
    let names = files.iter().map(|f| f.file_stem().unwrap().to_string_lossy().into_owned()).collect();
    let faces = meshes[0].faces.clone();
    PoseSet::try_new(names, meshes.into_iter().map(|m| m.positions).collect(), faces, 0)
        .expect("registered poses")
}

/// The parts on the template, one colour each (`desal_viz::part_face_values`, the rule
/// `parts.png` uses too).
fn draw(poses: &PoseSet, labels: &PartLabels, title: &str) -> RgbaImage {
    let values = desal_viz::part_face_values(&poses.faces, &labels.labels);
    let config = RenderConfig {
        title: title.into(),
        range: Some((0.0, 1.0)),
        colour_bar: false,
        ..RenderConfig::default()
    };
    render_heatmap(&poses.template_mesh(), Scalar::PerFace(&values), &config).expect("render")
}
