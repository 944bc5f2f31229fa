//! The simplification methods `desal eval` compares, and how each turns the template
//! into a registered simplified pose set: stage 3 (or another tool's mesh), then stage 4.
//!
//! | name | stage 3 | stage 4 |
//! |---|---|---|
//! | `qslim-optimal`, `qslim-subset` | Garland–Heckbert cost, no saliency, no balance (the paper's baseline) | greedy / subset |
//! | `saliency-optimal`, `saliency-subset` | cost × saliency weight | greedy / subset |
//! | `paper-optimal`, `paper-subset` | cost × saliency × edge length (the paper, Eq. 5) | greedy / subset |
//! | `desal` | desal's own (issue 17): the template's quadrics, each collapse ranked by its error per unit area (`normalized_error`, meshoptimizer's normalisation), no saliency, no balance (EVAL.md, "desal") | subset |
//! | `desal-refit` | `desal`, then again with saliency weights from where `desal`'s mesh deforms worse than the full one under the eval's model, fitted in-sample (`refit.rs`); in both runs each collapse keeps the endpoint that the full-resolution model places best (keep penalties, `refit.rs`); then edges flipped to follow the full surface in every pose (`flip.rs`); needs a pose model (not `--model rig`); named explicitly, not in `all` | subset |
//! | `desal-upsample` | `multipose`, then again with saliency weights from where the fitted upsampler (default settings) brings the poses stage 2 saw back worst, held out over 5 folds (`desal_refit::upsampler`); named explicitly, not in `all` | subset |
//! | `multipose` | Mohr & Gleicher 2003: quadrics summed over all poses, no saliency | subset |
//! | `multipose-saliency`, `multipose-paper` | the same quadrics, the cost × saliency weight (and × edge length): issue 17's "saliency with multi-pose quadrics", measured worse than `multipose` (EVAL.md); named explicitly, not in `all` | subset |
//! | `multipose-normalized` | the same quadrics, each collapse ranked by its error per unit area as `desal`'s: measured worse than `desal` in v2v and than `multipose` in v2f (EVAL.md); named explicitly, not in `all` | subset |
//! | `meshopt`, `meshopt-regularize`, `meshopt-priority` | meshoptimizer in-process (feature `meshopt`, on by default): plain, `Regularize`, the most salient vertices flagged `Priority` (`meshopt.rs`) | subset |
//! | `meshlab`, `meshlab-saliency` | MeshLab's quadric edge collapse through pymeshlab (`$DESAL_PYTHON` or `python3`; feature `meshlab`, on by default): plain, and stage 2's weights as vertex quality (`qualityweight`; `meshlab.rs`); named explicitly, not in `all` | greedy |
//! | `gltfpack`, `gltfpack-sa` | rig datasets: gltfpack (`$DESAL_GLTFPACK` or `gltfpack`; feature `gltfpack`, on by default) on the rig file, `-si R -noq` (and `-sa`), its ratio bisected to the vertex target; its own skin is kept (`gltfpack.rs`); named explicitly, not in `all` | greedy (exact: it keeps input vertices) |
//! | `external:NAME=PATH` | a simplified template made by another tool | greedy |
//!
//! `optimal` placement moves vertices, so they are mapped back by the paper's greedy
//! rule; `subset` placement keeps original vertices, so the map is exact. Every other
//! stage-3 setting (boundary weight, part borders, safeguards) is the pipeline's.

use std::path::PathBuf;
use std::sync::OnceLock;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use desal_map::MapOutput;
use desal_measures::PoseModel;
use desal_mesh::{NoProgress, PartLabels, PoseSet, TriMesh};
use desal_simplify::{Placement, SimplifyConfig, StopReason, Target};

use crate::rig::{OwnSkin, RigModel};
pub use desal_driver::stages::simplify::Cost;
use desal_driver::stages::{map, simplify};

/// One method of the comparison.
#[derive(Debug, Clone, PartialEq)]
pub enum Method {
    /// Single-pose quadric simplification of the template.
    Quadric { cost: Cost, placement: Placement },
    /// desal's own: area-normalised quadric error, subset placement.
    Desal,
    /// `Desal`, simplified again with weights from its own mesh's deformation residual
    /// (`refit.rs`), its edges then flipped to follow the full surface in every pose
    /// (`flip.rs`).
    DesalRefit,
    /// The dataset's stage 3 (subset placement), simplified again with weights from where
    /// the fitted upsampler brings the poses back worst, held out
    /// (`desal_refit::upsampler`).
    DesalUpsample,
    /// Multi-pose QEM (Mohr & Gleicher 2003), subset placement, its cost plain
    /// (`multipose`), weighted like stage 3's (`multipose-saliency`, `multipose-paper`),
    /// or per unit area like `desal`'s (`multipose-normalized`, with `Cost::Qslim`).
    Multipose { cost: Cost, normalized: bool },
    /// meshoptimizer, in-process.
    #[cfg(feature = "meshopt")]
    Meshopt(crate::meshopt::Variant),
    /// MeshLab through pymeshlab, in a Python subprocess.
    #[cfg(feature = "meshlab")]
    Meshlab(crate::meshlab::Variant),
    /// gltfpack on a rig dataset's file, in a subprocess.
    #[cfg(feature = "gltfpack")]
    Gltfpack(crate::gltfpack::Variant),
    /// Another tool's simplified template, read from `path`.
    External { name: String, path: PathBuf },
}

/// Built-in methods that `all` leaves out, because they need more than this binary
/// (MeshLab needs Python with pymeshlab, gltfpack needs gltfpack and a rig dataset).
pub const OPTIONAL: &[&str] = &[
    #[cfg(feature = "meshlab")]
    "meshlab",
    #[cfg(feature = "meshlab")]
    "meshlab-saliency",
    #[cfg(feature = "gltfpack")]
    "gltfpack",
    #[cfg(feature = "gltfpack")]
    "gltfpack-sa",
];

/// The methods run when none are named, in table order.
pub const ALL: &[&str] = &[
    "qslim-optimal",
    "saliency-optimal",
    "paper-optimal",
    "qslim-subset",
    "saliency-subset",
    "paper-subset",
    "desal",
    "multipose",
    #[cfg(feature = "meshopt")]
    "meshopt",
    #[cfg(feature = "meshopt")]
    "meshopt-regularize",
    #[cfg(feature = "meshopt")]
    "meshopt-priority",
];

/// The reference row of every relative change.
pub const BASELINE: &str = "qslim-optimal";

/// A peer that is a cargo feature of this crate: the feature, the names of its methods
/// and whether this build has it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Peer {
    pub feature: &'static str,
    pub methods: &'static [&'static str],
    pub built: bool,
}

/// Every peer behind a feature, so that a build without one still knows its methods'
/// names and refuses them saying which feature builds them. The names are those of the
/// peer module's `Variant::name` (a test checks it for the peers built).
pub const PEERS: &[Peer] = &[
    Peer {
        feature: "meshopt",
        methods: &["meshopt", "meshopt-regularize", "meshopt-priority"],
        built: cfg!(feature = "meshopt"),
    },
    Peer { feature: "meshlab", methods: &["meshlab", "meshlab-saliency"], built: cfg!(feature = "meshlab") },
    Peer { feature: "gltfpack", methods: &["gltfpack", "gltfpack-sa"], built: cfg!(feature = "gltfpack") },
];

/// The error for a method of a peer that `peers` says this build lacks; `None` for every
/// other name (a method this build runs, or one no peer has).
fn not_built(peers: &[Peer], text: &str) -> Option<String> {
    let peer = peers.iter().find(|p| !p.built && p.methods.contains(&text))?;
    let feature = peer.feature;
    Some(format!(
        "{text}: this desal was built without the `{feature}` feature; build with `--features {feature}`"
    ))
}

impl Method {
    /// The method's name in tables, file names and `eval.json`.
    pub fn name(&self) -> String {
        match self {
            Method::Quadric { cost, placement } => format!("{}-{}", cost.name(), placement.name()),
            Method::Desal => simplify::Method::Desal.name().into(),
            Method::DesalRefit => simplify::Method::DesalRefit.name().into(),
            Method::DesalUpsample => simplify::Method::DesalUpsample.name().into(),
            Method::Multipose { cost: Cost::Qslim, normalized: false } => "multipose".into(),
            Method::Multipose { normalized: true, .. } => "multipose-normalized".into(),
            Method::Multipose { cost, .. } => format!("multipose-{}", cost.name()),
            #[cfg(feature = "meshopt")]
            Method::Meshopt(variant) => variant.name().into(),
            #[cfg(feature = "meshlab")]
            Method::Meshlab(variant) => variant.name().into(),
            #[cfg(feature = "gltfpack")]
            Method::Gltfpack(variant) => variant.name().into(),
            Method::External { name, .. } => name.clone(),
        }
    }

    /// Parses one method name (see the module table).
    pub fn parse(text: &str) -> Result<Method> {
        if let Some(spec) = text.strip_prefix("external:") {
            let (name, path) = spec
                .split_once('=')
                .with_context(|| format!("'{text}': an external method is written external:NAME=PATH"))?;
            // A peer's names stay reserved in a build without it, so that a name in
            // eval.json means the same method whatever the build.
            let valid = !name.is_empty()
                && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
                && !ALL.contains(&name)
                && !OPTIONAL.contains(&name)
                && !PEERS.iter().any(|p| p.methods.contains(&name));
            if !valid {
                bail!("'{text}': NAME must be letters, digits, '-' or '_', and not a built-in method name");
            }
            return Ok(Method::External { name: name.into(), path: PathBuf::from(path) });
        }
        if let Some(refusal) = not_built(PEERS, text) {
            bail!(refusal);
        }
        // desal's own methods, by the names `[simplify] method` gives them.
        if let Ok(own) = text.parse::<simplify::Method>() {
            return Ok(match own {
                simplify::Method::Desal => Method::Desal,
                simplify::Method::DesalRefit => Method::DesalRefit,
                simplify::Method::DesalUpsample => Method::DesalUpsample,
                simplify::Method::Quadric { cost, placement } => Method::Quadric { cost, placement },
                simplify::Method::Multipose => Method::Multipose { cost: Cost::Qslim, normalized: false },
            });
        }
        if text == "multipose-normalized" {
            return Ok(Method::Multipose { cost: Cost::Qslim, normalized: true });
        }
        if let Some(cost) = text.strip_prefix("multipose-") {
            let cost: Cost = cost.parse().map_err(|_| anyhow::anyhow!(unknown(text)))?;
            if matches!(cost, Cost::Saliency | Cost::Paper) {
                return Ok(Method::Multipose { cost, normalized: false });
            }
        }
        #[cfg(feature = "meshlab")]
        if let Some(variant) = crate::meshlab::Variant::ALL.into_iter().find(|v| v.name() == text) {
            return Ok(Method::Meshlab(variant));
        }
        #[cfg(feature = "gltfpack")]
        if let Some(variant) = crate::gltfpack::Variant::ALL.into_iter().find(|v| v.name() == text) {
            return Ok(Method::Gltfpack(variant));
        }
        #[cfg(feature = "meshopt")]
        if let Some(variant) = crate::meshopt::Variant::ALL.into_iter().find(|v| v.name() == text) {
            return Ok(Method::Meshopt(variant));
        }
        let (cost, placement) = text.split_once('-').with_context(|| unknown(text))?;
        let cost: Cost = cost.parse().map_err(|_| anyhow::anyhow!(unknown(text)))?;
        let placement: Placement = placement.parse().map_err(|_| anyhow::anyhow!(unknown(text)))?;
        Ok(Method::Quadric { cost, placement })
    }

    /// Parses a `--methods` list: `all`, bare cost names (`paper` = `paper-optimal` and
    /// `paper-subset`), full names, `external:NAME=PATH`. A method named twice is an error.
    pub fn parse_list(items: &[String]) -> Result<Vec<Method>> {
        let mut names: Vec<String> = Vec::new();
        for item in items.iter().map(|s| s.trim()).filter(|s| !s.is_empty()) {
            match item {
                "all" => names.extend(ALL.iter().map(|s| s.to_string())),
                "qslim" | "saliency" | "paper" => {
                    names.extend(["optimal", "subset"].map(|p| format!("{item}-{p}")));
                }
                other => names.push(other.to_owned()),
            }
        }
        if names.is_empty() {
            bail!("no method given: use --methods with e.g. qslim,paper,multipose (or all)");
        }
        let methods: Vec<Method> = names.iter().map(|n| Method::parse(n)).collect::<Result<_>>()?;
        for (k, m) in methods.iter().enumerate() {
            if methods[..k].iter().any(|earlier| earlier.name() == m.name()) {
                bail!("method '{}' is named twice in --methods", m.name());
            }
        }
        Ok(methods)
    }

    /// `optimal`, `subset` or `external`, for reports.
    pub fn placement(&self) -> &'static str {
        match self {
            Method::Quadric { placement, .. } => placement.name(),
            Method::Desal | Method::DesalRefit | Method::DesalUpsample | Method::Multipose { .. } => "subset",
            #[cfg(feature = "meshopt")]
            Method::Meshopt(_) => "subset",
            #[cfg(feature = "meshlab")]
            Method::Meshlab(_) => "optimal",
            #[cfg(feature = "gltfpack")]
            Method::Gltfpack(_) => "subset",
            Method::External { .. } => "external",
        }
    }
}

fn unknown(text: &str) -> String {
    format!(
        "unknown method '{text}': use {}, {}, desal-refit, desal-upsample, multipose-saliency, multipose-paper, multipose-normalized, a bare qslim/saliency/paper (both placements), all, or external:NAME=PATH",
        ALL.join(", "),
        OPTIONAL.join(", ")
    )
}

/// What every method reads: the registered pose set, its labels, stage 2's weights and
/// the pipeline's stage-3 settings.
#[derive(Debug)]
pub struct Inputs {
    pub poses: PoseSet,
    pub labels: PartLabels,
    /// Stage-3 weights per original vertex (saliency with its floor applied).
    pub weights: Vec<f64>,
    /// The poses whose shapes may guide a pose-aware simplification: those stage 2's
    /// saliency summed (every pose but the ones `[saliency] exclude` names). `multipose`
    /// sums its quadrics over these too, so excluding a pose hides it from both.
    pub simplification_poses: Vec<usize>,
    /// The pipeline's stage-3 configuration; each method overrides the target, the
    /// placement and the cost switches.
    pub base_config: SimplifyConfig,
    /// A rig dataset's rig, posed at the pose set's frames.
    pub rig: Option<RigModel>,
    /// The deformation model starts from a rigid fit of every part (every model but the
    /// rig's own skinning), so each part must keep three non-collinear vertices.
    pub part_fits: bool,
    /// A rig dataset's attribute seams, when the pipeline keeps them (`desal run`'s
    /// stage 3 does): the template-quadric methods keep them too, so that each method's
    /// mesh is the one `desal run` would write (`multipose` and other tools take none).
    pub seams: Option<Vec<[u32; 2]>>,
    /// The eval's deformation model when it is a pose model (`desal-refit` refits it;
    /// the rig's own skinning is none).
    pub refit_model: Option<PoseModel>,
    /// `desal-refit`'s measures of the full-resolution model, computed once (`refit.rs`).
    pub full_model: OnceLock<desal_refit::FullModel>,
}

/// A method's registered simplified pose set.
#[derive(Debug)]
pub struct SimplifiedSet {
    /// The simplified template as stage 3 (or the other tool) left it, `simp_idx` space.
    pub raw: TriMesh,
    /// Stage 4's output: the map, every pose simplified, the labels carried along.
    pub mapped: MapOutput,
    /// `None` for an external mesh.
    pub stop: Option<StopReason>,
    /// One line about the simplification (stage 3's report, or the external file).
    pub note: String,
    pub simplify_seconds: f64,
    /// The skin of a method that brings its own (gltfpack), for the rig model.
    pub skin: Option<OwnSkin>,
}

/// Simplifies the template with `method` to `target`, maps it to original vertices and
/// applies the map to every pose.
///
/// Errors: the simplifier's and mapper's errors, an unreadable external mesh, and — as
/// the deformation model needs a rigid fit of every part — a part that no simplified
/// vertex carries, or one whose vertices are collinear: both say which parts, and that
/// a larger target fixes it.
pub fn simplify_and_map(method: &Method, inputs: &Inputs, target: Target) -> Result<SimplifiedSet> {
    let name = method.name();
    let started = Instant::now();
    let template = inputs.poses.template_mesh();
    // Only a tool that brings its own skin sets it: gltfpack.
    #[cfg_attr(not(feature = "gltfpack"), expect(unused_mut))]
    let mut skin = None;
    let (body, stop, note) = match method {
        Method::Quadric { cost, placement } => {
            let (saliency, balance) = cost.switches();
            let config = SimplifyConfig {
                target,
                placement: *placement,
                saliency,
                balance,
                ..inputs.base_config.clone()
            };
            template_quadrics(inputs, &template, &config).with_context(|| format!("{name}: stage 3"))?
        }
        Method::Desal => template_quadrics(inputs, &template, &desal_config(inputs, target))
            .with_context(|| format!("{name}: stage 3"))?,
        Method::DesalRefit => {
            let Some(model) = &inputs.refit_model else {
                bail!(
                    "{name} refits the deformation model (scape, scape-cv, scape-centroid or lbs); --model rig has none"
                );
            };
            let seen = &inputs.simplification_poses;
            let full =
                desal_refit::full_model(&inputs.full_model, &inputs.poses, seen, &inputs.labels, model)
                    .with_context(|| format!("{name}: the full-resolution model"))?;
            let refit = desal_refit::Refit {
                poses: &inputs.poses,
                labels: &inputs.labels,
                seen,
                seams: inputs.seams.as_deref(),
                model,
                full,
            };
            let refitted = refit.simplify(&desal_config(inputs, target)).with_context(|| name.clone())?;
            let out = simplify::refitted(&refitted);
            (out.body, Some(out.summary.stop), out.note)
        }
        Method::DesalUpsample => {
            let config = SimplifyConfig { target, ..inputs.base_config.clone() };
            let seen = &inputs.simplification_poses;
            let out = simplify::desal_upsample(&config, &inputs.poses, &inputs.labels, seen)
                .with_context(|| name.clone())?;
            (out.body, Some(out.summary.stop), out.note)
        }
        Method::Multipose { cost, normalized } => {
            let (saliency, balance) = cost.switches();
            let config = SimplifyConfig {
                target,
                saliency,
                balance,
                normalized_error: *normalized,
                ..inputs.base_config.clone()
            };
            let quadric_poses = inputs.poses.subset(&inputs.simplification_poses);
            let out = simplify::compute_multipose(&config, &quadric_poses, &inputs.weights, &inputs.labels)
                .with_context(|| format!("{name}: multi-pose simplification"))?;
            (out.body, Some(out.summary.stop), out.note)
        }
        #[cfg(feature = "meshopt")]
        Method::Meshopt(variant) => {
            let Target::Vertices(n) = target else {
                bail!("{name}: meshoptimizer is compared at a vertex count; give --target-vertices");
            };
            let (body, runs) = crate::meshopt::simplify(&template, &inputs.weights, *variant, n);
            let note = format!(
                "meshoptimizer {}: {} vertices, {} faces (target {n}; {runs} runs bisecting its index target)",
                variant.name(),
                body.positions.len(),
                body.faces.len()
            );
            let stop = if body.positions.len() == n {
                StopReason::TargetReached
            } else {
                StopReason::NoValidCollapse
            };
            (body, Some(stop), note)
        }
        #[cfg(feature = "meshlab")]
        Method::Meshlab(variant) => {
            let Target::Vertices(n) = target else {
                bail!("{name}: MeshLab is compared at a vertex count; give --target-vertices");
            };
            let (mesh, seconds) = crate::meshlab::simplify(&template, &inputs.weights, *variant, n)?;
            let mesh = compact(&mesh);
            let note = format!(
                "MeshLab quadric edge collapse ({}): {} vertices, {} faces (target {n} vertices = {} faces), {seconds:.3} s in MeshLab",
                if *variant == crate::meshlab::Variant::Saliency {
                    "saliency as vertex quality"
                } else {
                    "plain"
                },
                mesh.vertex_count(),
                mesh.face_count(),
                crate::meshlab::face_target(&template, n),
            );
            let stop = if mesh.vertex_count() <= n {
                StopReason::TargetReached
            } else {
                StopReason::NoValidCollapse
            };
            (simplify::external(&mesh), Some(stop), note)
        }
        #[cfg(feature = "gltfpack")]
        Method::Gltfpack(variant) => {
            let Target::Vertices(n) = target else {
                bail!("{name}: gltfpack is compared at a vertex count; give --target-vertices");
            };
            let Some(rig) = &inputs.rig else {
                bail!("{name}: gltfpack simplifies a glTF rig, so it runs on [dataset.rig] datasets only");
            };
            let out = crate::gltfpack::simplify(rig, *variant, n).with_context(|| name.clone())?;
            let stop = if out.reached { StopReason::TargetReached } else { StopReason::NoValidCollapse };
            skin = Some(out.skin);
            (simplify::external(&out.mesh), Some(stop), out.note)
        }
        Method::External { path, .. } => {
            let mesh =
                desal_io::read_mesh(path).with_context(|| format!("{name}: reading {}", path.display()))?;
            let mesh = compact(&mesh);
            let note =
                format!("{} ({} vertices, {} faces)", path.display(), mesh.vertex_count(), mesh.face_count());
            (simplify::external(&mesh), None, note)
        }
    };
    let simplify_seconds = started.elapsed().as_secs_f64();
    let raw = simplify::mesh(&body);
    let mapped = map::map(&body, &inputs.poses, &inputs.labels)
        .with_context(|| format!("{name}: stage 4 (mapping to original vertices)"))?;
    if inputs.part_fits {
        check_parts(&name, &mapped)?;
    }
    Ok(SimplifiedSet { raw, mapped, stop, note, simplify_seconds, skin })
}

/// `desal`'s stage-3 settings (`stages::simplify::desal_settings`, which `desal run`'s
/// `method = "desal"` and `"desal-refit"` use too) with `target`.
fn desal_config(inputs: &Inputs, target: Target) -> SimplifyConfig {
    desal_driver::stages::simplify::desal_settings(SimplifyConfig { target, ..inputs.base_config.clone() })
}

/// Stage 3 on the template with `config`, the dataset's seams kept: the body, its stop
/// and its note.
fn template_quadrics(
    inputs: &Inputs,
    template: &TriMesh,
    config: &SimplifyConfig,
) -> Result<(desal_io::artifact::SimplifiedV1, Option<StopReason>, String)> {
    let seams = inputs.seams.as_deref();
    let out =
        simplify::compute_with_seams(config, template, &inputs.weights, &inputs.labels, seams, &NoProgress)?;
    Ok((out.body, Some(out.summary.stop), out.note))
}

/// The per-part rigid fit the model starts from needs every part to keep at least three
/// non-collinear vertices. Merging a vanished part into a neighbour would change the
/// model being compared, so this is an error that names the parts.
fn check_parts(name: &str, mapped: &MapOutput) -> Result<()> {
    let labels = &mapped.labels;
    if !mapped.report.empty_parts.is_empty() {
        let parts: Vec<&str> =
            mapped.report.empty_parts.iter().map(|&p| labels.names[p as usize].as_str()).collect();
        bail!(
            "{name}: no simplified vertex carries part(s) {}; the deformation model needs a rigid fit of every \
             part. Use a larger --target-vertices",
            parts.join(", ")
        );
    }
    labels.check_parts_fittable(mapped.poses.template_positions()).with_context(|| {
        format!("{name}: a part keeps too few vertices for a rigid fit; use a larger --target-vertices")
    })?;
    Ok(())
}

/// Drops faces that repeat a vertex or an earlier face, and vertices no face uses
/// (another tool's file may carry either; the model needs neither), keeping order.
fn compact(mesh: &TriMesh) -> TriMesh {
    let (faces, _) = desal_mesh::clean_faces(&mesh.faces);
    let (kept, faces) = desal_mesh::used_vertices(mesh.vertex_count(), &faces);
    TriMesh { positions: kept.iter().map(|&v| mesh.positions[v as usize]).collect(), faces }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bare_names_expand_to_both_placements_and_duplicates_are_refused() {
        let names = |items: &[&str]| -> Vec<String> {
            let items: Vec<String> = items.iter().map(|s| s.to_string()).collect();
            Method::parse_list(&items).unwrap().iter().map(Method::name).collect()
        };
        assert_eq!(names(&["paper", "multipose"]), ["paper-optimal", "paper-subset", "multipose"]);
        assert_eq!(names(&["all"]).len(), ALL.len());
        assert_eq!(names(&["external:cgal=/x/y.ply"]), ["cgal"]);
        let twice = Method::parse_list(&["paper".into(), "paper-subset".into()]).unwrap_err();
        assert!(twice.to_string().contains("named twice"), "{twice}");
        assert!(Method::parse("paper-best").is_err());
        assert_eq!(
            names(&["multipose-saliency", "multipose-paper"]),
            ["multipose-saliency", "multipose-paper"]
        );
        assert!(Method::parse("multipose-qslim").is_err(), "that is `multipose`");
        assert!(Method::parse("multipose-balance").is_err());
        assert!(Method::parse("external:paper-optimal=x.ply").is_err(), "shadows a built-in");
        assert!(Method::parse("external:a b=x.ply").is_err());
        #[cfg(feature = "meshopt")]
        {
            let all = names(&["all"]);
            assert!(
                ["meshopt", "meshopt-regularize", "meshopt-priority"]
                    .iter()
                    .all(|m| all.contains(&m.to_string()))
            );
            assert!(Method::parse("external:meshopt=x.ply").is_err(), "shadows a built-in");
            assert_eq!(Method::parse("meshopt-priority").unwrap().placement(), "subset");
        }
    }

    /// In every build, each peer's method parses when its feature is built and is
    /// otherwise refused with a message naming the method and the feature; either way
    /// its name cannot be taken by an external mesh.
    #[test]
    fn a_peer_not_built_is_refused_by_name_with_its_feature() {
        for peer in PEERS {
            for &name in peer.methods {
                match Method::parse(name) {
                    Ok(method) => {
                        assert!(peer.built, "{name} parsed without the `{}` feature", peer.feature);
                        assert_eq!(method.name(), name);
                    }
                    Err(error) => {
                        assert!(!peer.built, "{name}: {error}");
                        let message = error.to_string();
                        assert!(message.starts_with(&format!("{name}: ")), "{message}");
                        assert!(message.contains(&format!("--features {}", peer.feature)), "{message}");
                        assert!(!message.contains("unknown method"), "{message}");
                    }
                }
                assert!(Method::parse(&format!("external:{name}=x.ply")).is_err(), "{name} is reserved");
            }
        }
        // The rule itself, on a table where meshopt is missing, whatever this build has.
        let without = [Peer { built: false, ..PEERS[0] }];
        let refusal = not_built(&without, "meshopt-priority").unwrap();
        assert_eq!(
            refusal,
            "meshopt-priority: this desal was built without the `meshopt` feature; build with `--features meshopt`"
        );
        assert_eq!(not_built(&without, "qslim-optimal"), None);
        assert_eq!(not_built(&[Peer { built: true, ..PEERS[0] }], "meshopt"), None);
    }

    /// The peers this build has are those `PEERS` marks built, and each one's `Variant`
    /// names are its row, in order.
    #[test]
    fn peers_list_the_names_their_modules_give() {
        let modules: &[(&str, Vec<&str>)] = &[
            #[cfg(feature = "meshopt")]
            ("meshopt", crate::meshopt::Variant::ALL.map(|v| v.name()).to_vec()),
            #[cfg(feature = "meshlab")]
            ("meshlab", crate::meshlab::Variant::ALL.map(|v| v.name()).to_vec()),
            #[cfg(feature = "gltfpack")]
            ("gltfpack", crate::gltfpack::Variant::ALL.map(|v| v.name()).to_vec()),
        ];
        let built: Vec<(&str, Vec<&str>)> =
            PEERS.iter().filter(|p| p.built).map(|p| (p.feature, p.methods.to_vec())).collect();
        assert_eq!(modules, built);
    }

    /// Vertex 1 is unused and face 2 repeats face 0: both go, the rest is renumbered in
    /// order.
    #[test]
    fn compact_drops_unused_vertices_and_repeated_faces() {
        let v = |x: f64| desal_mesh::Vec3::new(x, 0.0, 0.0);
        let mesh = TriMesh {
            positions: vec![v(0.0), v(1.0), v(2.0), v(3.0)],
            faces: vec![[0, 2, 3], [3, 2, 0], [0, 0, 2]],
        };
        let out = compact(&mesh);
        assert_eq!(out.positions, vec![v(0.0), v(2.0), v(3.0)]);
        assert_eq!(out.faces, vec![[0, 1, 2]]);
    }
}
