//! `eval.md`'s opening table (issue 43): every method under every measure, held out, each
//! against the baseline row with the poses won and the sign test — so that a method that
//! wins only under the measure it optimises shows where it loses — and the method each
//! use would pick from it ([`Objective`]).
//!
//! The measures, per evaluated pose (the eval's folds: over poses, or whole groups):
//! - the eval's deformation model (`--model`: SCAPE by default, the rig's own skinning on
//!   a rig dataset), held-out v2f and v2v against the full-resolution pose;
//! - each other model of [`OTHER_MODELS`] (LBS with the parts as bones, and SCAPE beside
//!   another `--model`), the same figures;
//! - model-free: the simplified *ground truth* upsampled back to full resolution, mean
//!   squared vertex error, by the fitted U and by COMA's barycentric U, each built on the
//!   fold's training poses;
//! - the plain simplification: v2f of the simplified template against the full one (one
//!   figure per method, so no poses won and no sign test);
//! - spikes (issue 42, item 7): faces of the held-out deformation more than 90° from the
//!   full surface's nearest normal, per pose.

pub use desal_driver::stages::simplify::Objective;

use std::fmt::Write as _;

use crate::report::{Cell, Column, EvalReport, MethodReport, p_value, percent, sci, sign_test};

/// The models measured beside `--model`, unless skipped (`--skip`) or `--model` itself.
pub const OTHER_MODELS: [&str; 2] = ["scape", "lbs"];

/// What `--skip` may name: the other models, `upsampling`, `surface`.
pub const SKIPPABLE: [&str; 6] = ["scape", "lbs", "upsampling", "surface", "spikes", "lods"];

/// Per-pose values of one measure for every method, or `None` where not measured.
type PerPose = Vec<Option<Vec<f64>>>;

/// A column from per-pose values (paired by pose with the baseline's).
fn column(key: String, title: String, values: PerPose, baseline: Option<usize>) -> Column {
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let base = baseline.and_then(|b| values[b].clone());
    let cells = values
        .iter()
        .enumerate()
        .map(|(k, v)| {
            let v = v.as_ref()?;
            let m = mean(v);
            let versus = base.as_ref().filter(|_| Some(k) != baseline && v.len() > 1);
            let (wins, p) = match versus {
                Some(b) => {
                    let wins = v.iter().zip(b).filter(|(o, b)| o < b).count();
                    let differing = v.iter().zip(b).filter(|(o, b)| o != b).count();
                    (Some(wins), Some(sign_test(wins, differing)))
                }
                None => (None, None),
            };
            let percent = base.as_ref().filter(|_| Some(k) != baseline).map(|b| 100.0 * (m / mean(b) - 1.0));
            Some(Cell { mean: m, percent, wins, poses: v.len(), p })
        })
        .collect();
    Column { key, title, cells }
}

/// The opening table's columns from the method reports; `model` is `--model`'s name.
pub fn columns(methods: &[MethodReport], model: &str, baseline: Option<usize>) -> Vec<Column> {
    let mut columns = Vec::new();
    let primary = |pick: fn(&crate::measure::Errors) -> f64| -> PerPose {
        methods.iter().map(|m| Some(m.poses.iter().map(|p| pick(&p.held_out.vs_full)).collect())).collect()
    };
    columns.push(column(format!("{model}.v2f"), format!("{model} v2f"), primary(|e| e.v2f), baseline));
    columns.push(column(format!("{model}.v2v"), format!("{model} v2v"), primary(|e| e.v2v), baseline));
    let others: Vec<String> =
        methods.iter().flat_map(|m| m.other_models.iter().map(|o| o.model.clone())).collect::<Vec<_>>();
    let mut seen = Vec::new();
    for other in others {
        if seen.contains(&other) {
            continue;
        }
        seen.push(other.clone());
        let of = |pick: fn(&crate::measure::Errors) -> f64| -> PerPose {
            methods
                .iter()
                .map(|m| {
                    let o = m.other_models.iter().find(|o| o.model == other)?;
                    o.error.is_none().then(|| o.poses.iter().map(pick).collect())
                })
                .collect()
        };
        columns.push(column(format!("{other}.v2f"), format!("{other} v2f"), of(|e| e.v2f), baseline));
        columns.push(column(format!("{other}.v2v"), format!("{other} v2v"), of(|e| e.v2v), baseline));
    }
    if methods.iter().any(|m| m.upsampling.is_some()) {
        let up = |fitted: bool| -> PerPose {
            methods
                .iter()
                .map(|m| {
                    m.upsampling.as_ref()?;
                    Some(
                        m.poses
                            .iter()
                            .map(|p| {
                                let u = p.upsampling.expect("measured with the method's upsampling");
                                if fitted {
                                    u.fitted.ground_truth.mse
                                } else {
                                    u.barycentric.ground_truth.mse
                                }
                            })
                            .collect(),
                    )
                })
                .collect()
        };
        columns.push(column(
            "upsampling.fitted".into(),
            "upsampling MSE, fitted U".into(),
            up(true),
            baseline,
        ));
        columns.push(column(
            "upsampling.barycentric".into(),
            "upsampling MSE, barycentric U".into(),
            up(false),
            baseline,
        ));
    }
    if methods.iter().any(|m| m.spikes_rest.is_some()) {
        let values = methods
            .iter()
            .map(|m| m.poses.iter().map(|p| p.spikes.map(|s| s as f64)).collect::<Option<Vec<f64>>>())
            .collect();
        columns.push(column("spikes".into(), "spikes per frame (faces > 90° off)".into(), values, baseline));
    }
    if methods.iter().any(|m| m.surface_v2f.is_some()) {
        let values = methods.iter().map(|m| m.surface_v2f.map(|v| vec![v])).collect();
        columns.push(column("surface".into(), "surface v2f (template)".into(), values, baseline));
    }
    columns
}

/// The column keys an objective ranks by, on a dataset evaluated with `model`: the
/// method with the lowest geometric mean of their ratios to the baseline's is its pick.
pub fn objective_keys(objective: Objective, model: &str) -> Vec<String> {
    match objective {
        Objective::Hierarchy => vec!["upsampling.fitted".into()],
        Objective::PoseModel => {
            let pose_model = if model == "rig" || model == "lbs" { "scape" } else { model };
            vec![format!("{pose_model}.v2f"), format!("{pose_model}.v2v")]
        }
        Objective::Skinning => vec![if model == "rig" { "rig.v2f".into() } else { "lbs.v2f".into() }],
        Objective::Surface => vec!["surface".into()],
    }
}

/// Per objective whose columns were all measured: the method (of `names`, the columns'
/// rows) it picks — the lowest geometric mean of the column means, each over the
/// column's lowest — and that score.
pub fn picks(columns: &[Column], model: &str, names: &[String]) -> Vec<(Objective, String, f64)> {
    Objective::ALL
        .into_iter()
        .filter_map(|objective| {
            let keys = objective_keys(objective, model);
            let cols: Vec<&Column> =
                keys.iter().map(|k| columns.iter().find(|c| &c.key == k)).collect::<Option<_>>()?;
            let score = |k: usize| -> Option<f64> {
                let mut log = 0.0;
                for c in &cols {
                    let best = c.cells[c.best()?]?.mean;
                    log += (c.cells[k]?.mean / best).ln();
                }
                Some((log / cols.len() as f64).exp())
            };
            let (k, s) = (0..names.len())
                .filter_map(|k| score(k).map(|s| (k, s)))
                .min_by(|a, b| a.1.total_cmp(&b.1))?;
            Some((objective, names[k].clone(), s))
        })
        .collect()
}

/// The opening table (issue 43): every method under every measure, held out.
pub fn markdown(report: &EvalReport) -> String {
    let mut md = String::new();
    let md = &mut md;
    let _ = writeln!(md, "## Every method under every measure (held out)\n");
    let base = report.baseline.as_deref().unwrap_or("(baseline not run)");
    let _ = writeln!(
        md,
        "Each column is one use's measure, held out over the {} folds (a pose is measured by models and \
         upsamplers that did not see it): the deformation model of this eval and every other one, v2f and v2v \
         against the full-resolution pose; the simplified ground truth upsampled back to full resolution (mean \
         squared vertex error; fitted U and COMA's barycentric U, built on the training poses); and the \
         simplified template's own v2f against the full one; and the spikes: simplified faces of the held-out \
         deformation whose normal turns more than 90° from the full surface's nearest one (mean count per \
         pose; the rest pose's count is in `eval.json`). The `{base}` row gives the figure (m²); every other \
         row its change against it, then the poses on which it is lower and the two-sided sign test's p. \
         **Bold**: the lowest of the column. A method that wins only the measure it optimises loses elsewhere: \
         read the whole row.\n",
        report.folds.len()
    );
    let mut header = String::from("| method |");
    for c in &report.measures {
        let _ = write!(header, " {} |", c.title);
    }
    let _ = writeln!(md, "{header}\n|---|{}", "---|".repeat(report.measures.len()));
    let best: Vec<Option<usize>> = report.measures.iter().map(|c| c.best()).collect();
    for (k, m) in report.methods.iter().enumerate() {
        let mut row = format!("| {} |", m.name);
        for (c, best) in report.measures.iter().zip(&best) {
            let text = match c.cells[k] {
                None => "—".to_owned(),
                Some(cell) => match cell.percent {
                    None if c.key == "spikes" => format!("{:.1}", cell.mean),
                    None => sci(cell.mean),
                    Some(pct) => match (cell.wins, cell.p) {
                        (Some(w), Some(p)) => {
                            format!("{} ({w}/{}, p {})", percent(pct), cell.poses, p_value(p))
                        }
                        _ => percent(pct),
                    },
                },
            };
            if *best == Some(k) {
                let _ = write!(row, " **{text}** |");
            } else {
                let _ = write!(row, " {text} |");
            }
        }
        let _ = writeln!(md, "{row}");
    }
    let _ = writeln!(md);
    for m in &report.methods {
        for o in m.other_models.iter().filter(|o| o.error.is_some()) {
            let _ = writeln!(
                md,
                "- `{}` under `{}`: not measured ({}).",
                m.name,
                o.model,
                o.error.as_deref().unwrap_or_default()
            );
        }
    }
    if !report.skipped.is_empty() {
        let _ = writeln!(md, "- Skipped by `--skip`: {}.", report.skipped.join(", "));
    }
    if !report.picks.is_empty() {
        let _ = writeln!(
            md,
            "\n**Which method for which use**, from this table (`[simplify] objective`; the score is the \
             geometric mean of the use's columns over each column's lowest, 1 = the best in all of them):\n"
        );
        let _ = writeln!(md, "| objective | measure | pick | score |\n|---|---|---|---|");
        for p in &report.picks {
            let objective: Objective = p.objective.parse().expect("an objective's own name");
            let _ = writeln!(
                md,
                "| `{}` | {} | `{}` | {:.3} |",
                p.objective,
                objective_keys(objective, &report.model).join(" and "),
                p.method,
                p.score
            );
        }
    }
    let _ = writeln!(md);
    md.clone()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three methods, two poses: the baseline's row is the figure, the others' their
    /// change, wins and sign test; a method not measured is `None` and never the best.
    #[test]
    fn a_column_pairs_every_method_with_the_baseline_pose_by_pose() {
        let values = vec![Some(vec![2.0, 4.0]), Some(vec![1.0, 5.0]), None, Some(vec![1.0, 2.0])];
        let c = column("k".into(), "t".into(), values, Some(0));
        let base = c.cells[0].unwrap();
        assert_eq!((base.mean, base.percent, base.wins, base.p), (3.0, None, None, None));
        let one = c.cells[1].unwrap();
        assert_eq!(one.mean, 3.0);
        assert_eq!((one.percent, one.wins, one.poses), (Some(0.0), Some(1), 2));
        assert_eq!(one.p, Some(sign_test(1, 2)));
        assert!(c.cells[2].is_none());
        let three = c.cells[3].unwrap();
        assert_eq!((three.percent, three.wins), (Some(-50.0), Some(2)));
        assert_eq!(c.best(), Some(3));
        // Without the baseline, no changes.
        let c = column("k".into(), "t".into(), vec![Some(vec![1.0]), Some(vec![2.0])], None);
        assert!(c.cells.iter().all(|c| c.unwrap().percent.is_none()));
    }

    /// Each objective picks by its own columns; the pose model's is the geometric mean of
    /// v2f and v2v; an objective whose column is missing picks nothing.
    #[test]
    fn each_objective_picks_by_its_own_measure() {
        let col = |key: &str, means: [f64; 3]| {
            column(key.into(), key.into(), means.iter().map(|&m| Some(vec![m])).collect(), Some(0))
        };
        let columns = vec![
            col("scape.v2f", [1.0, 0.8, 1.2]),
            col("scape.v2v", [1.0, 1.3, 0.9]),
            col("lbs.v2f", [1.0, 0.9, 1.1]),
            col("upsampling.fitted", [1.0, 2.0, 0.5]),
        ];
        let names: Vec<String> = ["a", "b", "c"].map(String::from).to_vec();
        let picks = picks(&columns, "scape", &names);
        let of = |o: Objective| picks.iter().find(|p| p.0 == o).map(|p| (p.1.as_str(), p.2));
        assert_eq!(of(Objective::Hierarchy), Some(("c", 1.0)));
        assert_eq!(of(Objective::Skinning), Some(("b", 1.0)));
        // a: sqrt(1/0.8 · 1/0.9) = 1.178; b: sqrt(1 · 1.3/0.9) = 1.202; c: sqrt(1.5 · 1).
        let (pick, score) = of(Objective::PoseModel).unwrap();
        assert_eq!(pick, "a");
        assert!((score - (1.0f64 / 0.72).sqrt()).abs() < 1e-12);
        assert_eq!(of(Objective::Surface), None);
    }
}
