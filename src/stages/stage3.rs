//! Stage 3 as `desal run` runs it: the method `[simplify] method` names, else one run of
//! the template with the `[simplify]` settings. `run_stages`, every hierarchy level and
//! the library's `Stage3::Template` go through [`simplify_template`], and key it by
//! [`key`].

use anyhow::Result;
use desal_io::artifact::{ContentHash, SimplifiedV1};
use desal_mesh::{PartLabels, PoseSet, Progress};

use crate::cache::{StageKey, canonical_json};
use crate::stages::refit;
use crate::stages::runner::StageOutput;
use crate::stages::saliency::SaliencyParams;
use crate::stages::simplify::{self, Method, SimplifyParams, SimplifySummary};

/// Stage 3 as `desal run` runs it on `set`'s template: `simplify.method`'s method when
/// one is named (`desal-refit` fits the pose model on the poses `saliency` reads), else
/// one run with `simplify`'s settings; `weights` are stage 2's, `seams` the template's
/// attribute seams.
pub fn simplify_template(
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
        Some(Method::DesalRefit) => refit::compute(&config, set, labels, &saliency.seen_poses(set), seams),
        method => {
            let mut out = simplify::compute_with_seams(
                &config,
                &set.template_mesh(),
                weights,
                labels,
                seams,
                progress,
            )?;
            if let Some(method) = method {
                out.summary.method = method.name().into();
            }
            Ok(out)
        }
    }
}

/// The cache key of [`simplify_template`]: `simplify`'s key
/// ([`SimplifyParams::key_with_seams`]), and for `desal-refit` its own constants in the
/// resolved part ([`refit::resolved_json`]).
pub fn key(
    simplify: &SimplifyParams,
    poses: ContentHash,
    saliency: ContentHash,
    labels: ContentHash,
    seams: Option<ContentHash>,
) -> Result<StageKey> {
    let mut key = simplify.key_with_seams(poses, saliency, labels, seams)?;
    if simplify.method == Some(Method::DesalRefit) {
        let mut resolved: serde_json::Value = serde_json::from_str(&key.resolved)?;
        resolved["desal_refit"] = refit::resolved_json();
        key.resolved = canonical_json(&resolved);
    }
    Ok(key)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `desal-refit`'s constants are in its key; another method's key is simplify's.
    #[test]
    fn the_key_of_desal_refit_holds_its_constants() {
        let hash = ContentHash::of(b"poses");
        let desal = SimplifyParams { method: Some(Method::Desal), ..SimplifyParams::default() };
        let refit = SimplifyParams { method: Some(Method::DesalRefit), ..SimplifyParams::default() };
        assert_eq!(key(&desal, hash, hash, hash, None).unwrap(), desal.key(hash, hash, hash).unwrap());
        let with = key(&refit, hash, hash, hash, None).unwrap();
        let without = refit.key(hash, hash, hash).unwrap();
        assert_ne!(with.hash(), without.hash());
        assert_eq!((&with.parameters, &with.inputs), (&without.parameters, &without.inputs));
        for constant in ["desal_refit", "exponent", "keep_penalty", "\"model\":\"scape\""] {
            assert!(with.resolved.contains(constant), "{constant}: {}", with.resolved);
        }
    }
}
