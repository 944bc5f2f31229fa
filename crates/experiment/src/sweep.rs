//! `desal eval --sweep`: the experiment at several vertex counts for the
//! `--sweep-methods` (by default desal's own, QSlim, the paper's method and multi-pose
//! QEM), for `sweep.json`, the error-vs-vertex-count plot and `eval.md`'s sweep table.
//!
//! Against the simplified ground truth each count is measured against a different
//! mesh, so only the full-resolution panels compare counts with each other; the
//! simplified panels compare methods at each count.

use std::fmt::Write as _;
use std::time::Instant;

use desal_simplify::Target;
use serde::Serialize;

use crate::figures::SweepPanel;
use crate::measure::{Run, measure};
use crate::methods::{Inputs, Method, simplify_and_map};
use crate::model::EvalModel;
use crate::report::{Figures, Summary, Versus, summarise, versus_split};

/// The methods a sweep compares unless `--sweep-methods` names others: issue 17's
/// list, but for MeshLab's, which needs Python with pymeshlab.
pub const SWEEP_METHODS: &str = "desal,qslim-optimal,paper-subset,multipose";

/// One method at one vertex count.
#[derive(Debug, Serialize)]
pub struct SweepPoint {
    pub method: String,
    pub target_vertices: usize,
    /// What the simplification reached (absent on error).
    pub vertices: Option<usize>,
    pub faces: Option<usize>,
    pub summary: Option<Summary>,
    /// Against the sweep's baseline at the same count, pose by pose (absent for the
    /// baseline itself, and when either has no figures).
    pub versus: Option<Versus>,
    /// Why this point has no figures (e.g. a part lost every vertex).
    pub error: Option<String>,
    /// Simplify, map, model fits and synthesis, seconds (measuring is shared per count).
    pub seconds: f64,
}

/// The row a sweep compares against: `preferred` (the run's `--baseline`) if the sweep
/// has it, else `qslim-optimal` if it has that, else its first method.
pub fn baseline(methods: &[Method], preferred: &str) -> String {
    [preferred, "qslim-optimal"]
        .into_iter()
        .find(|name| methods.iter().any(|m| m.name() == *name))
        .map(str::to_owned)
        .unwrap_or_else(|| methods.first().map(Method::name).unwrap_or_default())
}

/// Runs the sweep of `methods`, each at every count, and compares each with `baseline`
/// at the same count; a method failing at a count is recorded, not fatal.
#[allow(clippy::too_many_arguments)]
pub fn run_sweep(
    inputs: &Inputs,
    methods: &[Method],
    baseline: &str,
    counts: &[usize],
    folds: &[Vec<usize>],
    evaluated: &[usize],
    model: &EvalModel,
    log: &dyn Fn(&str),
) -> Vec<SweepPoint> {
    let mut points = Vec::new();
    for &count in counts {
        let mut ready = Vec::new();
        for method in methods {
            let started = Instant::now();
            let result = simplify_and_map(method, inputs, Target::Vertices(count)).and_then(|set| {
                let deformed = model.deform(inputs, &set, folds)?;
                Ok((set, deformed))
            });
            let seconds = started.elapsed().as_secs_f64();
            match result {
                Ok((set, deformed)) => ready.push((method.name(), set, deformed, seconds)),
                Err(e) => {
                    log(&format!("sweep {count}: {}: {e:#}", method.name()));
                    points.push(SweepPoint {
                        method: method.name(),
                        target_vertices: count,
                        vertices: None,
                        faces: None,
                        summary: None,
                        versus: None,
                        error: Some(format!("{e:#}")),
                        seconds,
                    });
                }
            }
        }
        let runs: Vec<Run> = ready
            .iter()
            .map(|(_, set, deformed, _)| Run { simplified: &set.mapped.poses, deformed })
            .collect();
        let measured = measure(&inputs.poses, evaluated, &runs);
        let base = ready.iter().zip(&measured).find(|((name, ..), _)| name == baseline).map(|(_, m)| m);
        for ((name, set, _, seconds), m) in ready.iter().zip(&measured) {
            let summary = summarise(&m.in_sample, &m.held_out);
            log(&format!(
                "sweep {count}: {name}: held-out v2v {:.3e} (simplified GT), {:.3e} (full GT)",
                summary.held_out.vs_simplified.v2v.mean, summary.held_out.vs_full.v2v.mean
            ));
            points.push(SweepPoint {
                method: name.clone(),
                target_vertices: count,
                vertices: Some(set.mapped.poses.vertex_count()),
                faces: Some(set.mapped.poses.face_count()),
                summary: Some(summary),
                versus: base.filter(|_| name != baseline).map(|b| Versus {
                    in_sample: versus_split(&m.in_sample, &b.in_sample),
                    held_out: versus_split(&m.held_out, &b.held_out),
                }),
                error: None,
                seconds: *seconds,
            });
        }
    }
    points
}

/// The methods of `points`, in their first appearance's order.
fn method_names(points: &[SweepPoint]) -> Vec<&str> {
    let mut names: Vec<&str> = Vec::new();
    for p in points {
        if !names.contains(&p.method.as_str()) {
            names.push(&p.method);
        }
    }
    names
}

/// The four panels of `sweep.png`: v2f and v2v, held-out, against the simplified and
/// the full ground truth; one series per method, x = reached vertex count.
pub fn panels(points: &[SweepPoint]) -> Vec<SweepPanel> {
    /// Panel title, which ground truth, and whether the figure is v2v (else v2f).
    type Pick = (&'static str, fn(&Summary) -> Figures, bool);
    let picks: [Pick; 4] = [
        ("held-out v2f vs simplified GT", |s| s.held_out.vs_simplified, false),
        ("held-out v2v vs simplified GT", |s| s.held_out.vs_simplified, true),
        ("held-out v2f vs full GT", |s| s.held_out.vs_full, false),
        ("held-out v2v vs full GT", |s| s.held_out.vs_full, true),
    ];
    picks
        .iter()
        .map(|&(title, pick, v2v)| SweepPanel {
            title: title.into(),
            y_label: "mean squared distance (m^2)".into(),
            series: method_names(points)
                .into_iter()
                .map(|name| desal_viz::Series {
                    name: name.into(),
                    points: points
                        .iter()
                        .filter(|p| p.method == name)
                        .filter_map(|p| {
                            let figures = pick(p.summary.as_ref()?);
                            let value = if v2v { figures.v2v.mean } else { figures.v2f.mean };
                            Some((p.vertices? as f64, value))
                        })
                        .collect(),
                })
                .collect(),
        })
        .collect()
}

/// `eval.md`'s sweep section: per count and method, the held-out errors against the
/// full-resolution pose, each with its change against `baseline` at that count and the
/// poses won; the lowest of each count in bold.
pub fn markdown(points: &[SweepPoint], baseline: &str) -> String {
    let names = method_names(points);
    let mut md = String::new();
    let _ = writeln!(md, "## Error vs vertex count (`--sweep`)\n");
    let _ = writeln!(
        md,
        "Held-out, vs the full-resolution pose, v2f / v2v (m²) at each target; in brackets the change against \
         `{baseline}` at the same count and the poses (of the evaluated ones) on which the method is lower. The \
         lowest figure of each count is in bold. `sweep.json` has every split, the sign tests and the timings.\n"
    );
    let _ = writeln!(md, "| target | {} |", names.join(" | "));
    let _ = writeln!(md, "|---|{}", "---|".repeat(names.len()));
    let mut counts: Vec<usize> = points.iter().map(|p| p.target_vertices).collect();
    counts.dedup();
    for count in counts {
        let at: Vec<Option<&SweepPoint>> = names
            .iter()
            .map(|n| points.iter().find(|p| p.target_vertices == count && p.method == *n))
            .collect();
        let figure = |p: &SweepPoint, v2v: bool| {
            p.summary.as_ref().map(|s| {
                let f = s.held_out.vs_full;
                if v2v { f.v2v.mean } else { f.v2f.mean }
            })
        };
        let lowest =
            |v2v: bool| at.iter().flatten().filter_map(|p| figure(p, v2v)).fold(f64::INFINITY, f64::min);
        let (low_f, low_v) = (lowest(false), lowest(true));
        let cell = |p: &Option<&SweepPoint>| -> String {
            let Some(p) = p else { return "—".into() };
            let (Some(f), Some(v)) = (figure(p, false), figure(p, true)) else {
                return format!("failed: {}", p.error.as_deref().unwrap_or("no figures"));
            };
            let bold = |x: f64, low: f64| if x == low { format!("**{x:.3e}**") } else { format!("{x:.3e}") };
            let change = p.versus.map(|c| c.held_out.vs_full).map_or(String::new(), |c| {
                format!(
                    " ({:+.1} %, {} / {:+.1} %, {})",
                    c.v2f_percent, c.v2f_wins, c.v2v_percent, c.v2v_wins
                )
            });
            format!("{} / {}{change}", bold(f, low_f), bold(v, low_v))
        };
        let cells: Vec<String> = at.iter().map(cell).collect();
        let _ = writeln!(md, "| {count} | {} |", cells.join(" | "));
    }
    md
}
