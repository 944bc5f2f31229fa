//! Stages 1–4 written once: fit → saliency → simplify → map of one pose set, over a
//! [`Store`]. `desal run` chains them over the cache (`run_stages`), the Python package
//! and the single-stage commands over memory (`memory.rs`), and every hierarchy or LOD
//! level over scratch memory inside its own cached stage (`hierarchy::compute_level`,
//! `lods.rs`).
//!
//! Stages 1 and 2 always run, also where stage 3 reads no weights (desal's own methods,
//! `multipose`, a cost without saliency): `fit.dsa` and `saliency.png` are outputs of a
//! run, and a level's are cheap next to its upsampler.

use anyhow::{Result, anyhow};
use desal_io::artifact::{ContentHash, FitV1, MapV1, SaliencyV1, SimplifiedV1};
use desal_mesh::{PartLabels, PoseSet, Progress};

use super::fit::{self, FitParams, FitSummary};
use super::map::{self, MapSummary};
use super::meshes::{self, MeshPlan};
use super::runner::{Stage, Staged, Store};
use super::saliency::{self, SaliencyParams, SaliencySummary};
use super::seams::SeamEdges;
use super::simplify::{self, SimplifyParams, SimplifySummary};

/// The settings of stages 1–3: a dataset's `[fit]`, `[saliency]` and `[simplify]`.
#[derive(Debug, Clone, Copy)]
pub struct ChainSettings<'a> {
    pub fit: &'a FitParams,
    pub saliency: &'a SaliencyParams,
    pub simplify: &'a SimplifyParams,
}

/// What the chain reads: the pose set and its labels — through functions, so that a
/// warm cached run decodes neither —, their content hashes when the store keys its
/// stages, and the template's attribute seams when stage 3 keeps them.
pub struct ChainInput<'a> {
    pub set: &'a dyn Fn() -> Result<&'a PoseSet>,
    pub labels: &'a dyn Fn() -> Result<&'a PartLabels>,
    /// The pose set's and the labels' content hashes (the cache's key inputs); `None`
    /// for [`super::runner::Memory`], which builds no key.
    pub hashes: Option<(ContentHash, ContentHash)>,
    /// Handed to stage 3 as given: the caller asks [`SimplifyParams::keeps_seams`].
    pub seams: Option<&'a SeamEdges>,
    /// A rig's meshes under one budget (`stages::meshes`): stage 3 runs per rule and the
    /// plan enters its key; `None`: one run.
    pub meshes: Option<&'a MeshPlan>,
}

impl std::fmt::Debug for ChainInput<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ChainInput")
            .field("hashes", &self.hashes)
            .field("seams", &self.seams)
            .field("meshes", &self.meshes)
            .finish_non_exhaustive()
    }
}

impl ChainInput<'_> {
    /// [`Self::hashes`], which a store that keys its stages needs.
    pub fn hashes(&self) -> Result<(ContentHash, ContentHash)> {
        self.hashes.ok_or_else(|| anyhow!("the pose set has no content hash to key a stage with"))
    }
}

/// Stages 1–4 of one pose set.
#[derive(Debug)]
pub struct Chain {
    pub fit: Staged<FitV1, FitSummary>,
    pub saliency: Staged<SaliencyV1, SaliencySummary>,
    pub simplified: Staged<SimplifiedV1, SimplifySummary>,
    pub map: Staged<MapV1, MapSummary>,
}

/// Runs stages 1–4 over `store`, in the paper's order.
pub fn chain(
    store: &mut impl Store,
    settings: ChainSettings,
    input: &ChainInput,
    progress: &dyn Progress,
) -> Result<Chain> {
    let (set, labels) = (input.set, input.labels);

    // Stage 1: per-part rigid fit of the template onto every pose.
    let mut fitted = store.stage(
        Stage::Fit,
        || {
            let (poses, labels) = input.hashes()?;
            Ok(settings.fit.key(poses, labels))
        },
        &[],
        || fit::compute(settings.fit, set()?, labels()?, progress),
    )?;

    // Stage 2: deformation saliency from the residuals.
    let salient = store.stage(
        Stage::Saliency,
        || settings.saliency.key(input.hashes()?.0, fitted.hash()?),
        &[],
        || saliency::compute(settings.saliency, fitted.body()?, set()?.template_mesh().diagonal()),
    )?;
    // The residuals (one per pose and vertex) are read by stage 2 only: a computed fit's
    // go back now when its cache entry holds them, or when the store's caller does not
    // read them (`Scratch`).
    store.release(&mut fitted);

    // Stage 3: the template simplified by the configured method, keeping the seams it
    // is handed as polylines (keyed by their content); a rig's meshes by their plan.
    let simplified = store.stage(
        Stage::Simplify,
        || {
            let (poses, labels) = input.hashes()?;
            let seams = input.seams.map(|s| s.hash);
            let mut key = settings.simplify.key_with_seams(poses, salient.hash()?, labels, seams)?;
            if let Some(plan) = input.meshes {
                key.inputs.push(("meshes".into(), plan.hash()));
            }
            Ok(key)
        },
        &[],
        || {
            let seams = input.seams.map(|s| s.edges.as_slice());
            let weights = &salient.body()?.weights;
            match input.meshes {
                Some(plan) => meshes::run(
                    plan,
                    settings.simplify,
                    settings.saliency,
                    set()?,
                    labels()?,
                    weights,
                    seams,
                    progress,
                ),
                None => simplify::run(
                    settings.simplify,
                    settings.saliency,
                    set()?,
                    labels()?,
                    weights,
                    seams,
                    progress,
                ),
            }
        },
    )?;

    // Stage 4: the simplified vertices mapped to original ones.
    let mapped = store.stage(
        Stage::Map,
        || Ok(map::key(input.hashes()?.0, simplified.hash()?)),
        &[],
        || map::compute(simplified.body()?, set()?, labels()?),
    )?;
    Ok(Chain { fit: fitted, saliency: salient, simplified, map: mapped })
}
