//! The public types of stage 3's entry points: [`SimplifyInput`] in, [`Simplified`] out.

use desal_mesh::TriMesh;

use crate::config::{PartBorders, SimplifyConfig};

use crate::report::SimplifyReport;

/// The data one simplification reads.
#[derive(Debug, Clone, Copy)]
pub struct SimplifyInput<'a> {
    /// The mesh to simplify (the template).
    pub mesh: &'a TriMesh,
    /// One weight per input vertex (stage 2's saliency, floor already applied), used by
    /// the cost when [`crate::SimplifyConfig::saliency`] is on. `None`: all weights 1.
    pub weights: Option<&'a [f64]>,
    /// One part id per input vertex, used by [`crate::SimplifyConfig::part_borders`].
    pub part_labels: Option<&'a [u32]>,
    /// Attribute seams: input edges `[a, b]` (input vertex indices, either order, repeats
    /// allowed) along which the caller's attributes are split (UV charts, hard normals).
    /// Each seam survives as a polyline: a seam vertex collapses only along its seam onto
    /// a seam vertex, and seam ends and junctions are never removed. `None`: no seams.
    pub seams: Option<&'a [[u32; 2]]>,
    /// One keep penalty per input vertex, in squared mesh units (finite, >= 0), read by
    /// [`crate::Placement::Subset`] only: an edge collapse keeps the endpoint with the
    /// smaller `merged error per unit area + penalty`, so that among two endpoints the
    /// cheaper-to-keep one survives; the collapse is still ranked by the better
    /// endpoint's error alone, so the penalties choose *which* vertex of a region stays,
    /// not how many. `desal eval`'s `desal-refit` passes each vertex's squared position
    /// error under the pose model. `None`: the smaller merged error decides.
    pub keep_penalty: Option<&'a [f64]>,
}

impl<'a> SimplifyInput<'a> {
    /// A mesh with no weights and no labels.
    pub fn new(mesh: &'a TriMesh) -> Self {
        Self { mesh, weights: None, part_labels: None, seams: None, keep_penalty: None }
    }

    /// Adds per-vertex saliency weights.
    pub fn with_weights(self, weights: &'a [f64]) -> Self {
        Self { weights: Some(weights), ..self }
    }

    /// Adds per-vertex part labels.
    pub fn with_part_labels(self, labels: &'a [u32]) -> Self {
        Self { part_labels: Some(labels), ..self }
    }

    /// Adds per-vertex keep penalties (see [`SimplifyInput::keep_penalty`]).
    pub fn with_keep_penalty(self, penalty: &'a [f64]) -> Self {
        Self { keep_penalty: Some(penalty), ..self }
    }

    /// Adds attribute seams (see [`SimplifyInput::seams`]).
    pub fn with_seams(self, seams: &'a [[u32; 2]]) -> Self {
        Self { seams: Some(seams), ..self }
    }

    /// Adds the per-vertex inputs `config` reads, and only those: the saliency weights
    /// when its saliency factor is on, the part labels when it does not ignore part
    /// borders. The one rule for callers that hold both (`desal run`'s stage 3, both
    /// runs of desal-refit).
    pub fn with_inputs_read_by(self, config: &SimplifyConfig, weights: &'a [f64], labels: &'a [u32]) -> Self {
        let input = if config.saliency { self.with_weights(weights) } else { self };
        if config.part_borders != PartBorders::Ignore { input.with_part_labels(labels) } else { input }
    }
}

/// The result of a simplification.
#[derive(Debug, Clone, PartialEq)]
pub struct Simplified {
    /// The simplified mesh; its vertex indices are `simp_idx`. Vertices appear in
    /// increasing order of the input vertex that holds their slot; faces keep the input's
    /// relative order; orientation is preserved.
    pub mesh: TriMesh,
    /// For every `simp_idx`, the `orig_idx` whose exact input position the vertex has,
    /// or `None` when optimal placement moved it. Always `Some` with
    /// [`crate::Placement::Subset`] and for [`crate::simplify_multipose`].
    pub simp_to_orig: Vec<Option<u32>>,
    pub report: SimplifyReport,
}

impl Simplified {
    /// `simp_to_orig` without the options, when every output vertex is an input vertex
    /// (subset placement); `None` otherwise.
    pub fn subset_indices(&self) -> Option<Vec<u32>> {
        self.simp_to_orig.iter().copied().collect()
    }
}
