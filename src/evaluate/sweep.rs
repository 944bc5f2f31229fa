//! `desal eval --sweep`: the experiment at several vertex counts for QSlim, the paper's
//! method and multi-pose QEM, for `sweep.json` and the error-vs-vertex-count plot.
//!
//! Against the simplified ground truth each count is measured against a different
//! mesh, so only the full-resolution panels compare counts with each other; the
//! simplified panels compare methods at each count.

use std::time::Instant;

use desal_simplify::Target;
use serde::Serialize;

use super::figures::SweepPanel;
use super::measure::{Run, measure};
use super::methods::{Inputs, Method, simplify_and_map};
use super::model::EvalModel;
use super::report::{Figures, Summary, summarise};

/// The methods a sweep compares.
pub const SWEEP_METHODS: [&str; 3] = ["qslim-optimal", "paper-optimal", "multipose"];

/// One method at one vertex count.
#[derive(Debug, Serialize)]
pub struct SweepPoint {
    pub method: String,
    pub target_vertices: usize,
    /// What the simplification reached (absent on error).
    pub vertices: Option<usize>,
    pub faces: Option<usize>,
    pub summary: Option<Summary>,
    /// Why this point has no figures (e.g. a part lost every vertex).
    pub error: Option<String>,
    /// Simplify, map, model fits and synthesis, seconds (measuring is shared per count).
    pub seconds: f64,
}

/// Runs the sweep; a method failing at a count is recorded, not fatal.
pub fn run_sweep(
    inputs: &Inputs,
    counts: &[usize],
    folds: &[Vec<usize>],
    evaluated: &[usize],
    model: &EvalModel,
    log: &dyn Fn(&str),
) -> Vec<SweepPoint> {
    let methods: Vec<Method> =
        SWEEP_METHODS.iter().map(|name| Method::parse(name).expect("built-in method names parse")).collect();
    let mut points = Vec::new();
    for &count in counts {
        let mut ready = Vec::new();
        for method in &methods {
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
        for ((name, set, _, seconds), m) in ready.iter().zip(measured) {
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
                error: None,
                seconds: *seconds,
            });
        }
    }
    points
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
            series: SWEEP_METHODS
                .iter()
                .map(|&name| desal_viz::Series {
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
