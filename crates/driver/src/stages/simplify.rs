//! Stage 3: its parameters and their validation, its cache key, and the one path into
//! `desal-simplify` that `desal run`, `desal simplify` and every `desal eval` method
//! share (the seams, the artifact conversion; which of the weights and labels the
//! engine reads is `SimplifyInput::with_inputs_read_by`'s rule, which desal-refit
//! shares).

use anyhow::{Result, bail};
use desal_io::artifact::{ArtifactKind, ContentHash, SimplifiedV1};
use desal_mesh::Progress;
use desal_mesh::{PartLabels, PoseSet, TriMesh, Vec3};
use desal_simplify::{
    Metric, PartBorders, Placement, Simplified, SimplifyConfig, SimplifyInput, SimplifyReport, StopReason,
    Target,
};
use serde::{Deserialize, Serialize};
use serde_json::json;

use crate::cache::{StageKey, canonical_json};
use crate::stages::runner::StageOutput;
use crate::stages::saliency::SaliencyParams;

/// The keys of `[simplify]` that name its target; at most one may be given.
pub const TARGET_KEYS: [&str; 3] = ["target_vertices", "target_faces", "ratio"];

/// Stage 3 parameters (`[simplify]` in pipeline files). Every default is the library's
/// ([`SimplifyConfig::default`]), so pipeline files, `desal-simplify` and the library
/// agree (README, "Defaults").
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
#[serde(from = "SimplifyKnobs")]
pub struct SimplifyParams {
    /// Target vertex count (the paper: 2500). At most one of the three targets is
    /// given; none means the library's default target (`ratio = 0.2`).
    pub target_vertices: Option<usize>,
    pub target_faces: Option<usize>,
    /// Target as a fraction of the input face count.
    pub ratio: Option<f64>,
    /// `optimal` (the paper) or `subset` (keep original vertices).
    #[serde(with = "crate::cache::by_name")]
    pub placement: Placement,
    /// Weight the cost by deformation saliency.
    pub saliency: bool,
    /// Multiply the cost by the edge length (the paper's balance term).
    pub balance: bool,
    /// Keep part borders (lock vertices on the border between two parts).
    pub keep_part_borders: bool,
    /// `quadric` (Garland–Heckbert, the paper's) or `lindstrom-turk` (memoryless,
    /// CGAL's default; lower surface error on one mesh, see BENCHMARKS.md).
    #[serde(with = "crate::cache::by_name")]
    pub metric: Metric,
    /// Weight of the boundary constraint quadrics ([`SimplifyConfig::boundary_weight`]);
    /// the library's default when absent.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub boundary_weight: Option<f64>,
    /// Rank collapses by the quadric error per unit area
    /// ([`SimplifyConfig::normalized_error`], meshoptimizer's error; `desal eval`'s
    /// `desal` method). Off (the paper's) when absent.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub normalized_error: bool,
    /// The fold guard ([`SimplifyConfig::max_corner_normal_deg`]): a collapse may not
    /// leave a face more than this many degrees from its corners' input normals (180
    /// switches it off); the library's default when absent.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_corner_normal_deg: Option<f64>,
    /// What stage 3 does with a dataset's attribute seams (a rig's UV and normal seams;
    /// pose-file datasets have none): `keep` them as polylines (the default when absent)
    /// or `ignore` them.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seams: Option<Seams>,
    /// One of desal's own methods (EVAL.md, "desal's method"), which set `placement`,
    /// `saliency`, `balance`, `normalized_error` and `metric` themselves: `desal` (one
    /// run, the error per unit area, subset placement) or `desal-refit` (`desal`, then
    /// again weighted by where its mesh deforms worse than the full one under the SCAPE
    /// pose model, both runs keeping the vertices that model places best, then edge
    /// flips; `crates/refit`). Absent: one run with the settings above (the paper's
    /// stage 3).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub method: Option<Method>,
    /// The use the dataset is simplified for (`hierarchy`, `pose-model`, `skinning`,
    /// `surface`): it sets `method` to [`Objective::method`] when no `method` is given.
    /// Not part of any key (the method it picks is).
    #[serde(skip)]
    pub objective: Option<Objective>,
    /// Which of the settings a `method` makes itself (`placement`, `saliency`, `balance`,
    /// `metric`, `normalized_error`) the file or the caller gave, by key: beside a method,
    /// a given one must have the method's value, even when it is the default. Not part
    /// of any key.
    #[serde(skip)]
    pub given: Vec<&'static str>,
}

/// The stage-3 knobs as the front ends spell them, declared once: `[simplify]` in pipeline
/// files (and Python's `simplify=` table) and `desal simplify`'s flags. A setting left out
/// is `None`, so that [`SimplifyParams`] fills in the library's default and a method can
/// tell a given setting from a default one. The flags' help is these docs.
#[derive(Debug, Clone, Default, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
#[serde(deny_unknown_fields)]
pub struct SimplifyKnobs {
    /// Stop at this many vertices (the paper: 2500). One target at most; none: 20 % of
    /// the faces.
    #[cfg_attr(feature = "cli", arg(long))]
    pub target_vertices: Option<usize>,
    /// Stop at this many faces.
    #[cfg_attr(feature = "cli", arg(long))]
    pub target_faces: Option<usize>,
    /// Keep this fraction of the faces, in (0, 1].
    #[cfg_attr(feature = "cli", arg(long))]
    pub ratio: Option<f64>,
    /// Where a collapsed edge's vertex goes: `optimal` (the paper; the default) or
    /// `subset` (keep original vertices).
    #[serde(default, deserialize_with = "some_by_name")]
    #[cfg_attr(feature = "cli", arg(long))]
    pub placement: Option<Placement>,
    /// Weight the cost by deformation saliency (default on). `desal simplify` turns it on
    /// by reading weights (`--saliency FILE`).
    #[cfg_attr(feature = "cli", arg(skip))]
    pub saliency: Option<bool>,
    /// Multiply the cost by the edge length (the paper's balance term; with saliency, the
    /// paper's method). Off by default.
    #[cfg_attr(feature = "cli", arg(long, num_args = 0..=1, default_missing_value = "true"))]
    pub balance: Option<bool>,
    /// Lock vertices on the border between two parts (needs part labels). Off by default.
    #[cfg_attr(feature = "cli", arg(long, num_args = 0..=1, default_missing_value = "true"))]
    pub keep_part_borders: Option<bool>,
    /// The error the collapses minimise: `quadric` (Garland–Heckbert, the paper's Q; the
    /// default) or `lindstrom-turk` (memoryless, CGAL's default; lower surface error on
    /// one mesh, see BENCHMARKS.md).
    #[serde(default, deserialize_with = "some_by_name")]
    #[cfg_attr(feature = "cli", arg(long))]
    pub metric: Option<Metric>,
    /// Weight of the boundary constraint quadrics (× edge length²); default 10.
    #[cfg_attr(feature = "cli", arg(long))]
    pub boundary_weight: Option<f64>,
    /// Rank collapses by the quadric error per unit area (meshoptimizer's error; the
    /// `desal` method's). Off by default.
    #[cfg_attr(feature = "cli", arg(long, num_args = 0..=1, default_missing_value = "true"))]
    pub normalized_error: Option<bool>,
    /// The fold guard: no collapse leaves a face more than this many degrees from its
    /// corners' input normals (180 switches it off); default 70.
    #[cfg_attr(feature = "cli", arg(long))]
    pub max_corner_normal_deg: Option<f64>,
    /// A rig's attribute seams: `keep` (the default) or `ignore`. Rig datasets only.
    #[cfg_attr(feature = "cli", arg(skip))]
    pub seams: Option<Seams>,
    /// One of stage 3's methods, which set some of the settings above themselves:
    /// `desal`, `desal-refit`, `desal-upsample`, `multipose`, or a cost and a placement
    /// such as `qslim-optimal` (see [`SimplifyParams::method`]).
    #[cfg_attr(feature = "cli", arg(long, value_parser = parse_method))]
    pub method: Option<Method>,
    /// The use to simplify for, which picks the method: `hierarchy`, `pose-model`,
    /// `skinning` or `surface` (see [`SimplifyParams::objective`]); `method` overrides it.
    #[serde(default, deserialize_with = "some_by_name")]
    #[cfg_attr(feature = "cli", arg(long))]
    pub objective: Option<Objective>,
}

/// `--method`: a stage-3 method by its name in pipeline files.
#[cfg(feature = "cli")]
fn parse_method(name: &str) -> Result<Method, String> {
    name.parse()
}

fn some_by_name<'de, T, D>(deserializer: D) -> std::result::Result<Option<T>, D::Error>
where
    T: std::str::FromStr<Err = String>,
    D: serde::Deserializer<'de>,
{
    crate::cache::by_name::deserialize(deserializer).map(Some)
}

impl From<SimplifyKnobs> for SimplifyParams {
    fn from(file: SimplifyKnobs) -> Self {
        let default = SimplifyParams::default();
        let given = [
            ("placement", file.placement.is_some()),
            ("saliency", file.saliency.is_some()),
            ("balance", file.balance.is_some()),
            ("metric", file.metric.is_some()),
            ("normalized_error", file.normalized_error.is_some()),
        ];
        SimplifyParams {
            target_vertices: file.target_vertices,
            target_faces: file.target_faces,
            ratio: file.ratio,
            placement: file.placement.unwrap_or(default.placement),
            saliency: file.saliency.unwrap_or(default.saliency),
            balance: file.balance.unwrap_or(default.balance),
            keep_part_borders: file.keep_part_borders.unwrap_or(default.keep_part_borders),
            metric: file.metric.unwrap_or(default.metric),
            boundary_weight: file.boundary_weight,
            normalized_error: file.normalized_error.unwrap_or(default.normalized_error),
            max_corner_normal_deg: file.max_corner_normal_deg,
            seams: file.seams,
            method: file.method.or(file.objective.map(Objective::method)),
            objective: file.objective,
            given: given.into_iter().filter(|&(_, g)| g).map(|(key, _)| key).collect(),
        }
    }
}

/// `method = "desal" | "desal-refit" | "desal-upsample" | "multipose" | "<cost>-<placement>"`
/// (see [`SimplifyParams::method`]): every stage-3 method `desal eval` compares that
/// needs no peer tool.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(try_from = "String", into = "String")]
pub enum Method {
    /// One run with a cost and a placement, as `desal eval`'s `qslim-optimal`, …,
    /// `paper-subset` (the paper's stage 3 is `paper-optimal`).
    Quadric {
        cost: Cost,
        placement: Placement,
    },
    Desal,
    DesalRefit,
    /// The dataset's stage 3 (subset placement), then again weighted by where the fitted
    /// upsampler brings the poses back worst, held out (`desal_refit::upsampler`).
    DesalUpsample,
    /// Multi-pose QEM (Mohr & Gleicher 2003): the quadrics summed over the poses stage 2
    /// reads, subset placement, the cost's other factors as configured; no seams.
    Multipose,
}

impl Method {
    /// Every method, in the order documentation lists them.
    pub const ALL: [Method; 10] = [
        Method::Desal,
        Method::DesalRefit,
        Method::DesalUpsample,
        Method::Multipose,
        Method::Quadric { cost: Cost::Qslim, placement: Placement::Optimal },
        Method::Quadric { cost: Cost::Qslim, placement: Placement::Subset },
        Method::Quadric { cost: Cost::Saliency, placement: Placement::Optimal },
        Method::Quadric { cost: Cost::Saliency, placement: Placement::Subset },
        Method::Quadric { cost: Cost::Paper, placement: Placement::Optimal },
        Method::Quadric { cost: Cost::Paper, placement: Placement::Subset },
    ];

    /// The method's name in pipeline files, on the command line and in Python.
    pub fn name(self) -> &'static str {
        match self {
            Method::Quadric { cost, placement } => match (cost, placement) {
                (Cost::Qslim, Placement::Optimal) => "qslim-optimal",
                (Cost::Qslim, Placement::Subset) => "qslim-subset",
                (Cost::Saliency, Placement::Optimal) => "saliency-optimal",
                (Cost::Saliency, Placement::Subset) => "saliency-subset",
                (Cost::Paper, Placement::Optimal) => "paper-optimal",
                (Cost::Paper, Placement::Subset) => "paper-subset",
                (Cost::Balance, Placement::Optimal) => "balance-optimal",
                (Cost::Balance, Placement::Subset) => "balance-subset",
            },
            Method::Desal => "desal",
            Method::DesalRefit => "desal-refit",
            Method::DesalUpsample => "desal-upsample",
            Method::Multipose => "multipose",
        }
    }

    /// The keys of `[simplify]` the method sets itself.
    fn own_keys(self) -> &'static [&'static str] {
        match self {
            Method::Desal | Method::DesalRefit => {
                &["placement", "metric", "saliency", "balance", "normalized_error"]
            }
            Method::DesalUpsample => &["placement", "saliency", "balance"],
            Method::Multipose => &["placement"],
            Method::Quadric { .. } => &["placement", "saliency", "balance"],
        }
    }

    /// `config` with the settings the method makes itself.
    pub fn settings(self, config: SimplifyConfig) -> SimplifyConfig {
        match self {
            Method::Desal | Method::DesalRefit => desal_settings(config),
            Method::DesalUpsample => desal_refit::upsampler::settings(config),
            Method::Multipose => SimplifyConfig { placement: Placement::Subset, ..config },
            Method::Quadric { cost, placement } => {
                let (saliency, balance) = cost.switches();
                SimplifyConfig { placement, saliency, balance, ..config }
            }
        }
    }

    /// Whether the method reads the poses stage 2 read (its artifact records which).
    fn reads_poses(self) -> bool {
        matches!(self, Method::DesalRefit | Method::DesalUpsample | Method::Multipose)
    }
}

impl From<Method> for String {
    fn from(method: Method) -> String {
        method.name().into()
    }
}

impl TryFrom<String> for Method {
    type Error = String;

    fn try_from(name: String) -> Result<Self, String> {
        name.parse()
    }
}

/// `objective = "hierarchy" | "pose-model" | "skinning" | "surface"` (see
/// [`SimplifyParams::objective`]): the use a dataset is simplified for, which picks the
/// stage-3 method measured best for it (`Objective::method`).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Objective {
    /// Mesh networks' hierarchies: the lowest held-out upsampling MSE of the fitted U.
    Hierarchy,
    /// Trackers with a pose model: the lowest held-out pose-model v2f and v2v.
    PoseModel,
    /// Engines: the lowest held-out skinning v2f with the rig's weights.
    Skinning,
    /// The plain simplification: the lowest surface distance of the template itself.
    Surface,
}

impl Objective {
    pub const ALL: [Objective; 4] =
        [Objective::Hierarchy, Objective::PoseModel, Objective::Skinning, Objective::Surface];

    pub fn name(self) -> &'static str {
        match self {
            Objective::Hierarchy => "hierarchy",
            Objective::PoseModel => "pose-model",
            Objective::Skinning => "skinning",
            Objective::Surface => "surface",
        }
    }

    /// The method that serves the use best, as measured on SCAPE and the bundled samples
    /// (`desal eval`'s opening table; EVAL.md, "Which method for which use").
    pub fn method(self) -> Method {
        match self {
            Objective::Hierarchy => Method::DesalUpsample,
            Objective::PoseModel => Method::DesalRefit,
            Objective::Skinning => Method::Desal,
            Objective::Surface => Method::Quadric { cost: Cost::Qslim, placement: Placement::Optimal },
        }
    }
}

impl std::str::FromStr for Objective {
    type Err = String;

    fn from_str(name: &str) -> Result<Self, String> {
        Objective::ALL.into_iter().find(|o| o.name() == name).ok_or_else(|| {
            let names: Vec<&str> = Objective::ALL.iter().map(|o| o.name()).collect();
            format!("unknown objective '{name}': use one of {}", names.join(", "))
        })
    }
}

impl std::str::FromStr for Method {
    type Err = String;

    fn from_str(name: &str) -> Result<Self, String> {
        Method::ALL.into_iter().find(|m| m.name() == name).ok_or_else(|| {
            let names: Vec<&str> = Method::ALL.iter().map(|m| m.name()).collect();
            format!("unknown method '{name}': use one of {}", names.join(", "))
        })
    }
}

/// `seams = "keep" | "ignore"` (see [`SimplifyParams::seams`]).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, PartialEq, Eq, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Seams {
    /// Hand the seam edges to stage 3: a seam vertex collapses only along its seam, so
    /// every simplified face stays in one UV chart.
    #[default]
    Keep,
    /// Simplify as if the surface had no seams (what desal did before seams were kept).
    Ignore,
}

impl Default for SimplifyParams {
    fn default() -> Self {
        let library = SimplifyConfig::default();
        SimplifyParams {
            target_vertices: None,
            target_faces: None,
            ratio: None,
            placement: library.placement,
            saliency: library.saliency,
            balance: library.balance,
            keep_part_borders: library.part_borders == PartBorders::Lock,
            metric: library.metric,
            boundary_weight: None,
            normalized_error: library.normalized_error,
            max_corner_normal_deg: None,
            seams: None,
            method: None,
            objective: None,
            given: Vec::new(),
        }
    }
}

impl SimplifyParams {
    /// The target asked for: vertices, else faces, else the ratio, else the library's.
    pub fn target(&self) -> Target {
        match (self.target_vertices, self.target_faces, self.ratio) {
            (Some(v), _, _) => Target::Vertices(v),
            (None, Some(f), _) => Target::Faces(f),
            (None, None, Some(r)) => Target::Ratio(r),
            (None, None, None) => SimplifyConfig::default().target,
        }
    }

    /// The library configuration these parameters resolve to, validated.
    pub fn config(&self) -> Result<SimplifyConfig> {
        let given = [self.target_vertices.is_some(), self.target_faces.is_some(), self.ratio.is_some()];
        if given.iter().filter(|&&g| g).count() > 1 {
            bail!("simplify: give one of target_vertices, target_faces and ratio, not several");
        }
        match self.target() {
            Target::Vertices(n) | Target::Faces(n) if n < 4 => {
                bail!(
                    "simplify: a target of {n} is too small: the simplest closed surface has 4 vertices and 4 faces"
                )
            }
            _ => {}
        }
        let library = SimplifyConfig::default();
        let mut config = SimplifyConfig {
            target: self.target(),
            placement: self.placement,
            saliency: self.saliency,
            balance: self.balance,
            part_borders: if self.keep_part_borders { PartBorders::Lock } else { PartBorders::Ignore },
            metric: self.metric,
            boundary_weight: self.boundary_weight.unwrap_or(library.boundary_weight),
            normalized_error: self.normalized_error,
            max_corner_normal_deg: self.max_corner_normal_deg.unwrap_or(library.max_corner_normal_deg),
            ..library
        };
        if let Some(method) = self.method {
            self.check_method_settings(method)?;
            config = method.settings(config);
        }
        config.validate()?;
        Ok(config)
    }

    /// A setting `method` makes itself may be left out or given the method's value; any
    /// other value is an error (it would be silently replaced), the default included when
    /// it was given ([`Self::given`]).
    fn check_method_settings(&self, method: Method) -> Result<()> {
        let default = SimplifyParams::default();
        let own = method.settings(SimplifyConfig::default());
        // Each setting as a pipeline file spells it: given, default, the method's.
        let quoted = |name: &str| format!("\"{name}\"");
        let settings = [
            (
                "placement",
                quoted(self.placement.name()),
                quoted(default.placement.name()),
                quoted(own.placement.name()),
            ),
            ("metric", quoted(self.metric.name()), quoted(default.metric.name()), quoted(own.metric.name())),
            ("saliency", self.saliency.to_string(), default.saliency.to_string(), own.saliency.to_string()),
            ("balance", self.balance.to_string(), default.balance.to_string(), own.balance.to_string()),
            (
                "normalized_error",
                self.normalized_error.to_string(),
                default.normalized_error.to_string(),
                own.normalized_error.to_string(),
            ),
        ];
        for (key, value, default, wanted) in settings {
            if method.own_keys().contains(&key)
                && value != wanted
                && (value != default || self.given.contains(&key))
            {
                let by = match self.objective {
                    Some(o) if o.method() == method => {
                        format!("objective = \"{}\" picks method = \"{}\", which", o.name(), method.name())
                    }
                    _ => format!("method = \"{}\"", method.name()),
                };
                bail!("simplify: {by} sets {key} = {wanted} itself; remove {key} = {value}");
            }
        }
        Ok(())
    }

    /// Whether a dataset's seams go to stage 3 (`seams` absent or `keep`, and a method
    /// that takes seams: `multipose` takes none).
    pub fn keeps_seams(&self) -> bool {
        self.seams.unwrap_or_default() == Seams::Keep
            && !matches!(self.method, Some(Method::Multipose | Method::DesalUpsample))
    }

    /// The cache key of a simplification of `poses`' template without seams. The
    /// resolved part holds every field of the library configuration; the inputs only
    /// what the cost uses (the saliency when weighted, the labels when part borders are
    /// kept).
    pub fn key(&self, poses: ContentHash, saliency: ContentHash, labels: ContentHash) -> Result<StageKey> {
        self.key_with_seams(poses, saliency, labels, None)
    }

    /// [`Self::key`] for a simplification that is handed seam edges (`seams`: their
    /// content hash, an input of the key), or none.
    pub fn key_with_seams(
        &self,
        poses: ContentHash,
        saliency: ContentHash,
        labels: ContentHash,
        seams: Option<ContentHash>,
    ) -> Result<StageKey> {
        let config = self.config()?;
        let refit = self.method == Some(Method::DesalRefit);
        let mut inputs = vec![("poses".to_owned(), poses)];
        // `desal-refit` and `multipose` read the poses stage 2 saw (recorded in its
        // artifact); `desal-refit` fits the pose model on the labels.
        if config.saliency || self.method.is_some_and(Method::reads_poses) {
            inputs.push(("saliency".into(), saliency));
        }
        if config.part_borders != PartBorders::Ignore || refit {
            inputs.push(("labels".into(), labels));
        }
        if let Some(seams) = seams {
            inputs.push(("seams".into(), seams));
        }
        let mut parameters = json!({
            "target": target_json(config.target),
            "placement": self.placement.name(),
            "saliency": self.saliency,
            "balance": self.balance,
            "keep_part_borders": self.keep_part_borders,
            "metric": self.metric.name(),
        });
        if let Some(w) = self.boundary_weight {
            parameters["boundary_weight"] = json!(w);
        }
        if self.normalized_error {
            parameters["normalized_error"] = json!(true);
        }
        if let Some(deg) = self.max_corner_normal_deg {
            parameters["max_corner_normal_deg"] = json!(deg);
        }
        if let Some(mode) = self.seams {
            parameters["seams"] = json!(mode);
        }
        // Only with a method, so that every key made before it still matches.
        if let Some(method) = self.method {
            parameters["method"] = json!(method.name());
        }
        let mut resolved = resolved_json(&config);
        // desal-refit's own constants: a change to any of them makes another result.
        if refit {
            resolved["desal_refit"] = serde_json::to_value(desal_refit::SETTINGS)?;
        }
        if self.method == Some(Method::DesalUpsample) {
            resolved["desal_upsample"] = serde_json::to_value(desal_refit::upsampler::SETTINGS)?;
        }
        Ok(StageKey {
            stage: "simplify".into(),
            stage_version: desal_simplify::VERSION,
            format_version: ArtifactKind::Simplified.current_version(),
            parameters: canonical_json(&parameters),
            resolved: canonical_json(&resolved),
            inputs,
        })
    }
}

fn target_json(target: Target) -> serde_json::Value {
    match target {
        Target::Vertices(v) => json!({ "vertices": v }),
        Target::Faces(f) => json!({ "faces": f }),
        Target::Ratio(r) => json!({ "ratio": r }),
    }
}

/// `config` with the settings desal's own methods make (`desal`, and both runs of
/// `desal-refit`): the error per unit area, subset placement, the quadric metric, no
/// saliency, no balance. The target, part borders and guards stay `config`'s.
pub fn desal_settings(config: SimplifyConfig) -> SimplifyConfig {
    SimplifyConfig {
        placement: Placement::Subset,
        saliency: false,
        balance: false,
        metric: Metric::Quadric,
        normalized_error: true,
        ..config
    }
}

/// Every field of the configuration, destructured exhaustively: a field added to
/// [`SimplifyConfig`] and left out here does not compile, so it cannot miss the key.
fn resolved_json(config: &SimplifyConfig) -> serde_json::Value {
    let SimplifyConfig {
        target,
        placement,
        saliency,
        balance,
        boundary_weight,
        part_borders,
        max_normal_rotation_deg,
        max_corner_normal_deg,
        max_placement_distance,
        metric,
        normalized_error,
    } = config;
    let part_borders = match part_borders {
        PartBorders::Ignore => json!("ignore"),
        PartBorders::Lock => json!("lock"),
        PartBorders::Constrain(w) => json!({ "constrain": w }),
    };
    let mut resolved = json!({
        "target": target_json(*target),
        "placement": placement.name(),
        "saliency": saliency,
        "balance": balance,
        "boundary_weight": boundary_weight,
        "part_borders": part_borders,
        "max_normal_rotation_deg": max_normal_rotation_deg,
        "max_corner_normal_deg": max_corner_normal_deg,
        "max_placement_distance": max_placement_distance,
        "metric": metric.name(),
    });
    // Only when on, so that every key made before the option existed still matches.
    if *normalized_error {
        resolved["normalized_error"] = json!(true);
    }
    resolved
}

/// Which factors of the paper's cost (Eq. 5) are on: the names of tables and reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cost {
    /// Plain quadric error (Garland & Heckbert 1997).
    Qslim,
    /// Quadric error × mean saliency weight of the edge.
    Saliency,
    /// Quadric error × edge length.
    Balance,
    /// Quadric error × mean saliency weight × edge length (the paper).
    Paper,
}

impl Cost {
    pub const ALL: [Cost; 4] = [Cost::Qslim, Cost::Saliency, Cost::Balance, Cost::Paper];

    pub fn name(self) -> &'static str {
        match self {
            Cost::Qslim => "qslim",
            Cost::Saliency => "saliency",
            Cost::Balance => "balance",
            Cost::Paper => "paper",
        }
    }

    /// `(saliency, balance)` switches of [`SimplifyConfig`].
    pub fn switches(self) -> (bool, bool) {
        match self {
            Cost::Qslim => (false, false),
            Cost::Saliency => (true, false),
            Cost::Balance => (false, true),
            Cost::Paper => (true, true),
        }
    }

    /// The cost a configuration's switches select.
    pub fn of(config: &SimplifyConfig) -> Cost {
        let switches = (config.saliency, config.balance);
        Cost::ALL.into_iter().find(|c| c.switches() == switches).expect("every switch pair has a name")
    }
}

impl std::str::FromStr for Cost {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        Cost::ALL.into_iter().find(|c| c.name() == s).ok_or_else(|| format!("cost '{s}' is unknown"))
    }
}

/// `simplified.json`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SimplifySummary {
    pub method: String,
    #[serde(with = "crate::cache::by_name")]
    pub placement: Placement,
    #[serde(with = "crate::cache::by_name")]
    pub metric: Metric,
    pub input_vertices: usize,
    pub input_faces: usize,
    pub output_vertices: usize,
    pub output_faces: usize,
    pub collapses: usize,
    #[serde(with = "crate::cache::by_name")]
    pub stop: StopReason,
    pub refused_topology: usize,
    pub refused_flip: usize,
    /// Refused by the fold guard (`max_corner_normal_deg`), counted apart from flips.
    pub refused_fold: usize,
    pub refused_degenerate: usize,
    /// Refused by the seam rule; present when the input had seams.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refused_seam: Option<usize>,
    pub locked_vertices: usize,
    /// Input vertices on a seam; present when the input had seams.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seam_vertices: Option<usize>,
    pub max_error: f64,
    pub mean_error: f64,
    pub edge_length_mean: f64,
    pub edge_length_variance: f64,
    pub seconds: f64,
}

/// Runs stage 3 on the template: `weights` (stage 2's, per original vertex) are used when
/// `config.saliency` is on, `labels` when part borders are kept.
pub fn compute(
    config: &SimplifyConfig,
    template: &TriMesh,
    weights: &[f64],
    labels: &PartLabels,
    progress: &dyn desal_mesh::Progress,
) -> Result<StageOutput<SimplifiedV1, SimplifySummary>> {
    compute_with_seams(config, template, weights, labels, None, progress)
}

/// [`compute`] with the template's attribute seams (`[lo, hi]` vertex pairs of the
/// template, `stages::seams`), which stage 3 keeps as polylines, or none.
pub fn compute_with_seams(
    config: &SimplifyConfig,
    template: &TriMesh,
    weights: &[f64],
    labels: &PartLabels,
    seams: Option<&[[u32; 2]]>,
    progress: &dyn desal_mesh::Progress,
) -> Result<StageOutput<SimplifiedV1, SimplifySummary>> {
    let mut input = SimplifyInput::new(template).with_inputs_read_by(config, weights, &labels.labels);
    if let Some(seams) = seams {
        input = input.with_seams(seams);
    }
    let result = desal_simplify::simplify_with_progress(&input, config, progress)?;
    Ok(output(config, Cost::of(config).name(), &result))
}

/// Multi-pose QEM (Mohr & Gleicher 2003) over `poses`, subset placement, as a stage-3
/// output (`method = "multipose"`, and `desal eval`'s `multipose` and its variants): with
/// `config.saliency`, the cost is also weighted by stage 2's `weights`, as in
/// [`compute`].
pub fn compute_multipose(
    config: &SimplifyConfig,
    poses: &PoseSet,
    weights: &[f64],
    labels: &PartLabels,
) -> Result<StageOutput<SimplifiedV1, SimplifySummary>> {
    let labels = (config.part_borders != PartBorders::Ignore).then_some(labels.labels.as_slice());
    let weights = config.saliency.then_some(weights);
    let result = desal_simplify::simplify_multipose(poses, weights, labels, config)?;
    let config = SimplifyConfig { placement: Placement::Subset, ..config.clone() };
    let method = if config.saliency {
        format!("multipose-{}", Cost::of(&config).name())
    } else {
        "multipose".to_owned()
    };
    Ok(output(&config, &method, &result))
}

/// Stage 3 as `desal run`, every hierarchy level and the Python package run it on
/// `set`'s template, keyed by [`SimplifyParams::key_with_seams`]: `simplify.method`'s
/// method when one is named (`desal-refit` fits the pose model, and `multipose` sums its
/// quadrics, over the poses `saliency` reads), else one run with `simplify`'s settings;
/// `weights` are stage 2's, `seams` the template's attribute seams.
pub fn run(
    simplify: &SimplifyParams,
    saliency: &SaliencyParams,
    set: &PoseSet,
    labels: &PartLabels,
    weights: &[f64],
    seams: Option<&[[u32; 2]]>,
    progress: &dyn Progress,
) -> Result<StageOutput<SimplifiedV1, SimplifySummary>> {
    let config = simplify.config()?;
    match simplify.method {
        Some(Method::DesalRefit) => {
            let started = std::time::Instant::now();
            let result = desal_refit::refit(&config, set, labels, &saliency.seen_poses(set), seams)?;
            let mut out = refitted(&result);
            out.summary.seconds = started.elapsed().as_secs_f64();
            Ok(out)
        }
        Some(Method::DesalUpsample) => desal_upsample(&config, set, labels, &saliency.seen_poses(set)),
        Some(Method::Multipose) => {
            let poses = set.subset(&saliency.seen_poses(set));
            compute_multipose(&config, &poses, weights, labels)
        }
        method => {
            let mut out =
                compute_with_seams(&config, &set.template_mesh(), weights, labels, seams, progress)?;
            if let Some(method) = method {
                out.summary.method = method.name().into();
            }
            Ok(out)
        }
    }
}

/// `desal-upsample` (`desal_refit::upsampler`) as stage 3's output: multi-pose quadrics
/// over the poses `seen` of `set`, weighted by the held-out error of the default fitted
/// upsampler, with `config`'s target, part borders and guards.
pub fn desal_upsample(
    config: &SimplifyConfig,
    set: &PoseSet,
    labels: &PartLabels,
    seen: &[usize],
) -> Result<StageOutput<SimplifiedV1, SimplifySummary>> {
    let started = std::time::Instant::now();
    let upsampler = desal_hierarchy::Upsampler::default();
    let weighted = desal_refit::upsampler::ForUpsampler { poses: set, labels, seen, upsampler: &upsampler }
        .simplify(config)?;
    let mut out = output(&weighted.config, Method::DesalUpsample.name(), &weighted.simplified);
    out.summary.seconds = started.elapsed().as_secs_f64();
    let kept = match weighted.kept {
        desal_refit::upsampler::Run::First => "the first run kept",
        desal_refit::upsampler::Run::Weighted => "the weighted run kept",
    };
    out.note = format!(
        "{} (multi-pose quadrics, then weighted by the first run's held-out upsampling error; held-out MSE {:.3e} first, {:.3e} weighted: {kept})",
        out.note, weighted.first_mse, weighted.weighted_mse
    );
    Ok(out)
}

/// `desal-refit`'s result as stage 3's output: the weighted run's, named `desal-refit`,
/// with a note that counts the flips.
pub fn refitted(refitted: &desal_refit::Refitted) -> StageOutput<SimplifiedV1, SimplifySummary> {
    let config = &refitted.config;
    let mut out = output(config, Cost::of(config).name(), &refitted.simplified);
    out.summary.method = Method::DesalRefit.name().into();
    out.note = format!(
        "{} (weighted by the first run's residual; both runs keep the vertices the full model places best), edge flips: {}",
        out.note, refitted.flips
    );
    out
}

fn output(
    config: &SimplifyConfig,
    method: &str,
    result: &Simplified,
) -> StageOutput<SimplifiedV1, SimplifySummary> {
    let r: &SimplifyReport = &result.report;
    let summary = SimplifySummary {
        method: method.into(),
        placement: config.placement,
        metric: config.metric,
        input_vertices: r.input_vertices,
        input_faces: r.input_faces,
        output_vertices: r.output_vertices,
        output_faces: r.output_faces,
        collapses: r.collapses,
        stop: r.stop,
        refused_topology: r.refusals.topology,
        refused_flip: r.refusals.flip,
        refused_fold: r.refusals.fold,
        refused_degenerate: r.refusals.degenerate,
        refused_seam: (r.seam_vertices > 0).then_some(r.refusals.seam),
        locked_vertices: r.locked_vertices,
        seam_vertices: (r.seam_vertices > 0).then_some(r.seam_vertices),
        max_error: r.max_error,
        mean_error: r.mean_error,
        edge_length_mean: r.edge_length_mean,
        edge_length_variance: r.edge_length_variance,
        seconds: r.seconds,
    };
    let body = SimplifiedV1 {
        positions: result.mesh.positions.iter().map(|p| [p.x, p.y, p.z]).collect(),
        faces: result.mesh.faces.clone(),
        simp_to_orig: result.simp_to_orig.clone(),
        placement: config.placement.name().into(),
        input_vertices: r.input_vertices as u32,
        input_faces: r.input_faces as u32,
        collapses: r.collapses as u32,
        stop: r.stop.name().into(),
        max_error: r.max_error,
        mean_error: r.mean_error,
        edge_length_mean: r.edge_length_mean,
        edge_length_variance: r.edge_length_variance,
    };
    StageOutput { body, summary, note: r.to_string() }
}

/// A simplified template made by another tool, as a stage-3 body: no vertex is known to
/// be an original one, so stage 4 maps all of them by the greedy rule.
pub fn external(mesh: &TriMesh) -> SimplifiedV1 {
    SimplifiedV1 {
        positions: mesh.positions.iter().map(|p| [p.x, p.y, p.z]).collect(),
        faces: mesh.faces.clone(),
        simp_to_orig: vec![None; mesh.vertex_count()],
        placement: "external".into(),
        input_vertices: 0,
        input_faces: 0,
        collapses: 0,
        stop: "external".into(),
        max_error: f64::NAN,
        mean_error: f64::NAN,
        edge_length_mean: f64::NAN,
        edge_length_variance: f64::NAN,
    }
}

/// The simplified template as a mesh.
pub fn mesh(body: &SimplifiedV1) -> TriMesh {
    TriMesh { positions: body.positions.iter().map(|&p| Vec3::from(p)).collect(), faces: body.faces.clone() }
}

/// `desal inspect` lines for a simplified artifact.
pub fn describe(s: &SimplifiedV1, out: &mut String) {
    use std::fmt::Write as _;
    let kept = s.simp_to_orig.iter().filter(|o| o.is_some()).count();
    let _ = writeln!(
        out,
        "    {} placement: {} -> {} vertices, {} -> {} faces ({} collapses, stopped: {})",
        s.placement,
        s.input_vertices,
        s.positions.len(),
        s.input_faces,
        s.faces.len(),
        s.collapses,
        s.stop
    );
    let _ = writeln!(
        out,
        "    collapse error (RMS distance, mesh units) max {:.3e} mean {:.3e}; edge length mean {:.4e}, variance {:.3e}; {} of {} vertices are original vertices",
        s.max_error,
        s.mean_error,
        s.edge_length_mean,
        s.edge_length_variance,
        kept,
        s.positions.len()
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parameters_are_checked_and_the_metric_enters_the_cache_key() {
        let hash = ContentHash::of(b"poses");
        let quadric = SimplifyParams::default();
        assert_eq!(quadric.config().unwrap().metric, Metric::Quadric);
        let lt = SimplifyParams { metric: Metric::LindstromTurk, ..SimplifyParams::default() };
        assert_eq!(lt.config().unwrap().metric, Metric::LindstromTurk);
        assert_ne!(quadric.key(hash, hash, hash).unwrap().hash(), lt.key(hash, hash, hash).unwrap().hash());
        let two =
            SimplifyParams { target_vertices: Some(100), ratio: Some(0.5), ..SimplifyParams::default() };
        assert!(two.config().unwrap_err().to_string().contains("not several"));
        let zero = SimplifyParams { target_vertices: Some(0), ..SimplifyParams::default() };
        assert!(zero.config().unwrap_err().to_string().contains("too small"));
    }

    /// The demonstration knob: `boundary_weight` changes the key (through the resolved
    /// config) and the producer's parameters only when set.
    #[test]
    fn boundary_weight_enters_the_key_and_the_producer_only_when_set() {
        let hash = ContentHash::of(b"poses");
        let default = SimplifyParams::default().key(hash, hash, hash).unwrap();
        let same = SimplifyParams { boundary_weight: Some(10.0), ..SimplifyParams::default() };
        let same = same.key(hash, hash, hash).unwrap();
        assert_eq!(default.resolved, same.resolved, "10 is the library default");
        assert!(!default.parameters.contains("boundary_weight"));
        let other = SimplifyParams { boundary_weight: Some(2.0), ..SimplifyParams::default() };
        let other = other.key(hash, hash, hash).unwrap();
        assert_ne!(default.hash(), other.hash());
        assert!(other.parameters.contains("\"boundary_weight\":2.0"), "{}", other.parameters);
    }

    /// The seams enter the key as an input when they are handed to stage 3, and the
    /// setting enters the producer's parameters only when set; a key without seams is
    /// the key stage 3 always had.
    #[test]
    fn seams_and_their_setting_enter_the_key() {
        let hash = ContentHash::of(b"poses");
        let (one, other) = (ContentHash::of(b"seams 1"), ContentHash::of(b"seams 2"));
        let default = SimplifyParams::default();
        let plain = default.key(hash, hash, hash).unwrap();
        assert_eq!(plain, default.key_with_seams(hash, hash, hash, None).unwrap());
        assert!(!plain.parameters.contains("seams") && plain.inputs.iter().all(|(role, _)| role != "seams"));
        let kept = default.key_with_seams(hash, hash, hash, Some(one)).unwrap();
        assert_ne!(kept.hash(), plain.hash());
        assert_ne!(kept.hash(), default.key_with_seams(hash, hash, hash, Some(other)).unwrap().hash());
        let ignore = SimplifyParams { seams: Some(Seams::Ignore), ..SimplifyParams::default() };
        assert!(!ignore.keeps_seams() && default.keeps_seams());
        let ignored = ignore.key(hash, hash, hash).unwrap();
        assert!(ignored.parameters.contains("\"seams\":\"ignore\""), "{}", ignored.parameters);
        assert_ne!(ignored.hash(), plain.hash());
        let parsed: SimplifyParams = toml::from_str("seams = \"ignore\"").unwrap();
        assert_eq!(parsed.seams, Some(Seams::Ignore));
        assert!(toml::from_str::<SimplifyParams>("seams = \"weld\"").is_err());
    }

    /// `method` resolves to desal's settings (whatever the defaults say), refuses a
    /// setting it would replace, and enters the key: `desal-refit` with the saliency
    /// artifact (the poses stage 2 saw) and the labels as inputs (its constants:
    /// `desal_refit::SETTINGS`); a key without a method is the key stage 3 always had.
    /// `objective` picks its method; `method` overrides it; a setting the picked method
    /// makes itself is refused naming the objective; every method's name parses back to
    /// it, the eval's cost-and-placement names included.
    #[test]
    fn an_objective_picks_the_method_measured_best_for_its_use() {
        for objective in Objective::ALL {
            let text = format!("target_vertices = 100\nobjective = \"{}\"", objective.name());
            let parsed: SimplifyParams = toml::from_str(&text).unwrap();
            assert_eq!((parsed.objective, parsed.method), (Some(objective), Some(objective.method())));
            parsed.config().unwrap();
        }
        let surface: SimplifyParams = toml::from_str("objective = \"surface\"").unwrap();
        let config = surface.config().unwrap();
        assert_eq!((config.placement, config.saliency, config.balance), (Placement::Optimal, false, false));
        let both: SimplifyParams = toml::from_str("objective = \"hierarchy\"\nmethod = \"desal\"").unwrap();
        assert_eq!(both.method, Some(Method::Desal), "method overrides the objective");
        let err = toml::from_str::<SimplifyParams>("objective = \"pose-model\"\nbalance = true")
            .unwrap()
            .config()
            .unwrap_err()
            .to_string();
        assert!(err.contains("objective = \"pose-model\" picks method = \"desal-refit\""), "{err}");
        let err = toml::from_str::<SimplifyParams>("objective = \"speed\"").unwrap_err().to_string();
        assert!(err.contains("unknown objective 'speed'"), "{err}");
        for method in Method::ALL {
            assert_eq!(method.name().parse::<Method>(), Ok(method));
            let text = format!("method = \"{}\"", method.name());
            assert_eq!(toml::from_str::<SimplifyParams>(&text).unwrap().method, Some(method));
        }
        let paper: SimplifyParams = toml::from_str("method = \"paper-subset\"").unwrap();
        let config = paper.config().unwrap();
        assert_eq!((config.placement, config.saliency, config.balance), (Placement::Subset, true, true));
    }

    #[test]
    fn a_method_sets_its_own_settings_and_enters_the_key() {
        let (poses, saliency, labels) =
            (ContentHash::of(b"poses"), ContentHash::of(b"s"), ContentHash::of(b"l"));
        let parsed: SimplifyParams =
            toml::from_str("target_vertices = 100\nmethod = \"desal-refit\"").unwrap();
        assert_eq!(parsed.method, Some(Method::DesalRefit));
        let config = parsed.config().unwrap();
        assert_eq!(
            config,
            desal_settings(SimplifyConfig { target: Target::Vertices(100), ..SimplifyConfig::default() })
        );
        assert_eq!(
            (config.placement, config.saliency, config.normalized_error),
            (Placement::Subset, false, true)
        );
        assert!(toml::from_str::<SimplifyParams>("method = \"qslim\"").is_err());

        let plain = SimplifyParams { target_vertices: Some(100), ..SimplifyParams::default() };
        let desal = SimplifyParams { method: Some(Method::Desal), ..plain.clone() };
        let keys = [&plain, &desal, &parsed].map(|p| p.key(poses, saliency, labels).unwrap());
        assert!(!keys[0].parameters.contains("method"));
        assert!(keys[1].parameters.contains("\"method\":\"desal\""), "{}", keys[1].parameters);
        assert_ne!(keys[0].hash(), keys[1].hash());
        assert_ne!(keys[1].hash(), keys[2].hash());
        let roles = |k: &StageKey| k.inputs.iter().map(|(role, _)| role.clone()).collect::<Vec<_>>();
        assert_eq!(roles(&keys[1]), ["poses"], "desal reads the template alone");
        assert_eq!(roles(&keys[2]), ["poses", "saliency", "labels"]);
        let other_labels = parsed.key(poses, saliency, ContentHash::of(b"other")).unwrap();
        assert_ne!(other_labels.hash(), keys[2].hash());

        // The method's own value, or the default, may stand beside it; another may not.
        let same = SimplifyParams { placement: Placement::Subset, normalized_error: true, ..parsed.clone() };
        assert_eq!(same.config().unwrap(), config);
        let err = SimplifyParams { balance: true, ..parsed.clone() }.config().unwrap_err().to_string();
        assert!(err.contains("sets balance = false itself; remove balance = true"), "{err}");
        let lt = SimplifyParams { metric: Metric::LindstromTurk, ..parsed };
        let err = lt.config().unwrap_err().to_string();
        assert!(err.contains("sets metric = \"quadric\" itself"), "{err}");
    }

    /// D13: beside a method, a setting the method makes itself is refused when given
    /// with another value than the method's, even when that value is the default (which
    /// the method would silently replace); left out, or given the method's value, it is
    /// accepted; and the keys of every accepted file are those of today.
    /// `multipose` sets the placement only, reads the poses stage 2 read (the saliency
    /// artifact is an input of its key, weighted or not) and takes no seams.
    #[test]
    fn multipose_sets_the_placement_reads_stage_2s_poses_and_takes_no_seams() {
        let (poses, saliency, labels) =
            (ContentHash::of(b"poses"), ContentHash::of(b"s"), ContentHash::of(b"l"));
        let parsed: SimplifyParams =
            toml::from_str("target_vertices = 100\nmethod = \"multipose\"\nsaliency = false").unwrap();
        assert_eq!(parsed.method, Some(Method::Multipose));
        let config = parsed.config().unwrap();
        assert_eq!((config.placement, config.saliency, config.balance), (Placement::Subset, false, false));
        assert!(!parsed.keeps_seams(), "multipose takes no seams");
        let key = parsed.key(poses, saliency, labels).unwrap();
        let roles: Vec<&str> = key.inputs.iter().map(|(role, _)| role.as_str()).collect();
        assert_eq!(roles, ["poses", "saliency"]);
        assert!(key.parameters.contains("\"method\":\"multipose\""), "{}", key.parameters);
        let other_poses = parsed.key(poses, ContentHash::of(b"other"), labels).unwrap();
        assert_ne!(other_poses.hash(), key.hash(), "other poses seen by stage 2");
        // The cost's factors are the settings'; only the placement is the method's.
        let weighted = SimplifyParams { saliency: true, balance: true, ..parsed.clone() };
        let c = weighted.config().unwrap();
        assert_eq!((c.saliency, c.balance), (true, true));
        let err = SimplifyParams { placement: Placement::Optimal, given: vec!["placement"], ..parsed }
            .config()
            .unwrap_err()
            .to_string();
        assert!(err.contains("method = \"multipose\" sets placement = \"subset\" itself"), "{err}");
    }

    #[test]
    fn d13_a_given_default_beside_a_method_is_refused() {
        let parse = |text: &str| toml::from_str::<SimplifyParams>(text).unwrap();
        for (key, value) in [
            ("placement", "\"optimal\""),
            ("saliency", "true"),
            ("normalized_error", "false"),
            ("balance", "true"),
        ] {
            let params = parse(&format!("method = \"desal-refit\"\n{key} = {value}"));
            let err = params.config().unwrap_err().to_string();
            assert!(err.contains(&format!("remove {key} = {value}")), "{key}: {err}");
        }
        for text in [
            "method = \"desal-refit\"\nplacement = \"subset\"\nsaliency = false",
            "method = \"desal\"\nnormalized_error = true\nmetric = \"quadric\"",
        ] {
            assert!(parse(text).config().is_ok(), "{text}");
        }
        // Without a method a given default is the default: the same key as before.
        let hash = ContentHash::of(b"x");
        let given = parse("placement = \"optimal\"\nsaliency = true\nbalance = false");
        let plain = SimplifyParams::default();
        assert_eq!(given.key(hash, hash, hash).unwrap(), plain.key(hash, hash, hash).unwrap());
    }

    /// The pipeline's defaults are the library's, field by field.
    #[test]
    fn pipeline_defaults_are_the_library_defaults() {
        let config = SimplifyParams::default().config().unwrap();
        assert_eq!(config, SimplifyConfig::default());
    }

    #[test]
    fn every_cost_name_reads_back() {
        for cost in Cost::ALL {
            assert_eq!(cost.name().parse::<Cost>(), Ok(cost));
            let (saliency, balance) = cost.switches();
            assert_eq!(Cost::of(&SimplifyConfig { saliency, balance, ..SimplifyConfig::default() }), cost);
        }
    }
    /// `desal-refit`'s constants are in its key's resolved part; no other key holds them.
    #[test]
    fn the_key_of_desal_refit_holds_its_constants() {
        let hash = ContentHash::of(b"poses");
        let desal = SimplifyParams { method: Some(Method::Desal), ..SimplifyParams::default() };
        let refit = SimplifyParams { method: Some(Method::DesalRefit), ..SimplifyParams::default() };
        let with = refit.key(hash, hash, hash).unwrap();
        assert!(!desal.key(hash, hash, hash).unwrap().resolved.contains("desal_refit"));
        for constant in ["desal_refit", "exponent", "keep_penalty", "\"model\":\"scape\""] {
            assert!(with.resolved.contains(constant), "{constant}: {}", with.resolved);
        }
    }
}
