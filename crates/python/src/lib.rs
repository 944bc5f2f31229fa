//! `desal._desal`, the native half of the `desal` Python package: every stage and the
//! pipeline on NumPy arrays. The stages are desal-driver's own (`desal_driver::memory`, the
//! same calls `desal run` makes), so the same arrays give the same bytes as the CLI.
//! The GIL is released while a stage computes.
//!
//! Every entry point runs inside [`errors::guard`] (a Rust panic is `desal.Error`, never a
//! `PanicException`), takes its arguments through [`args`] (bad ones are `InputError`s
//! in the caller's words), reads user paths through `desal_io::file::read_regular_file`
//! and writes through `desal_io::write_atomic` (`_write_file` for the Python layer's own
//! writers), the one rule desal's readers and writers follow.

mod args;
mod artifacts;
mod convert;
mod errors;
mod progress;

use desal_driver::memory::{self, StageParams};
use desal_driver::stages::fit::FitParams;
use desal_driver::stages::hierarchy::HierarchyParams;
use desal_driver::stages::parts::PartsParams;
use desal_driver::stages::rig::RigParams;
use desal_driver::stages::saliency::SaliencyParams;
use desal_driver::stages::simplify::{self as simplify_stage, Cost, Method, SimplifyParams};
use desal_io::artifact::{FitV1, SaliencyV1, SimplifiedV1};
use desal_mesh::{PartLabels, PoseSet, TriMesh};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use crate::args::{table, table_as};
use crate::convert::bad;
use crate::errors::{Error, InputError, guard};
use crate::progress::PyProgress;

/// The most frames `simplify_rig` poses a rig at (per source: `poses="both"` gives twice
/// as many poses): the rig crate's one cap, which `rig.frames` in pipeline files has too.
/// Checked here before any work, since a count like 10**12 would otherwise abort the
/// interpreter in the allocator, where no error can be raised; the pose set's size is
/// capped again by `desal_rig::MAX_POSE_VERTICES` once the vertex count is known.
pub const MAX_RIG_FRAMES: usize = desal_rig::MAX_FRAMES;

/// The fit table's keys as `simplify_pose_set`, `simplify_rig` and `hierarchy` name them.
const FIT_METHOD: &[(&str, &str)] = &[("method", "fit_method")];

/// Runs `f` with the GIL released, reporting to `callback`.
fn detached<T: Send>(
    py: Python<'_>,
    callback: Option<Py<PyAny>>,
    f: impl FnOnce(&PyProgress) -> PyResult<T> + Send,
) -> PyResult<T> {
    let progress = PyProgress::new(args::progress(callback, py)?);
    let result = py.detach(|| f(&progress));
    progress.into_result()?;
    result
}

/// A registered pose set: P poses of one body, one triangle list, and part labels.
///
/// PoseSet(poses, faces, labels=None, template=0, names=None, part_names=None,
///         parts=None, progress=None)
///
/// - poses: (P, V, 3) float32/float64 array, or a sequence of (V, 3) arrays.
/// - faces: (F, 3) integer array, shared by every pose.
/// - labels: (V,) part id per vertex; None discovers the near-rigid parts from the
///   poses (`parts`: the JSON of a pipeline's `[dataset.parts]` table, e.g. '{"count": 16}').
/// - template: index of the template pose (the paper's rest pose).
/// - names, part_names: pose and part names (default pose000…, part0…).
///
/// The input is validated as `desal run` validates pose files, and positions are stored
/// at float32 as `desal run` stores them; bad input raises InputError naming the pose,
/// vertex, face or part. Degenerate and duplicate faces are removed (`removed_faces`).
#[pyclass(name = "PoseSet", module = "desal", frozen)]
#[derive(Debug)]
struct PyPoseSet {
    set: PoseSet,
    labels: PartLabels,
    /// [`content_digest`] of `set` and `labels`: a `Fit` records the one it was computed
    /// from, so it is never used with another pose set.
    digest: u64,
    /// The discovery's report when the labels were discovered.
    parts: Option<serde_json::Value>,
    removed_faces: (usize, usize),
}

#[pymethods]
impl PyPoseSet {
    #[new]
    #[pyo3(signature = (poses, faces, labels=None, template=None, names=None, part_names=None, parts=None, progress=None, groups=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        poses: &Bound<'_, PyAny>,
        faces: &Bound<'_, PyAny>,
        labels: Option<&Bound<'_, PyAny>>,
        template: Option<&Bound<'_, PyAny>>,
        names: Option<&Bound<'_, PyAny>>,
        part_names: Option<&Bound<'_, PyAny>>,
        parts: Option<&Bound<'_, PyAny>>,
        progress: Option<Py<PyAny>>,
        groups: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        guard("PoseSet", || {
            let positions = convert::poses(poses)?;
            let faces = convert::faces("faces", faces)?;
            let ids = labels.map(|l| convert::ids("labels", l)).transpose()?;
            let groups = groups.map(|g| convert::ids("groups", g)).transpose()?;
            let template = template.map(|t| args::index("template", t)).transpose()?.unwrap_or(0);
            let names = names.map(|n| args::strings("names", n)).transpose()?;
            let part_names = part_names.map(|n| args::strings("part_names", n)).transpose()?;
            let parts = parts.map(parts_json).transpose()?;
            let parts: PartsParams = table("parts", parts.as_deref())?;
            detached(py, progress, move |_| {
                let built =
                    memory::pose_set(names, positions, faces, template, groups).map_err(errors::input)?;
                let set = built.set;
                let (labels, parts) = match ids {
                    Some(ids) => (memory::labels(ids, part_names, &set).map_err(errors::input)?, None),
                    None => {
                        let (labels, summary) =
                            memory::discover_parts(&parts, &set).map_err(errors::classify)?;
                        (labels, Some(json(&summary)?))
                    }
                };
                let removed_faces = (built.cleanup.degenerate.len(), built.cleanup.duplicate.len());
                let digest = content_digest(&set, &labels);
                Ok(PyPoseSet { set, labels, digest, parts, removed_faces })
            })
        })
    }

    /// PoseSet.from_body_model(model, shapes=24, poses=6, seed=0, pose_sigma=None,
    ///     expressions=True, parts=16, progress=None)
    ///
    /// Samples a body-models model (SMPL, SMPL-H, SMPL-X, MANO, FLAME, ANNY, ...; its
    /// NumPy backend, no torch) into a pose set: the template (the mean shape in the zero
    /// pose) then `shapes` x `poses` samples, one group per shape (held-out figures hold
    /// out whole shapes), labels from the skin weights' dominant joints merged to about
    /// `parts` parts. The draw is documented in `desal._body_models`.
    #[classmethod]
    #[pyo3(signature = (model, shapes=24, poses=6, seed=0, pose_sigma=None, expressions=true, parts=16, progress=None))]
    #[allow(clippy::too_many_arguments)]
    fn from_body_model(
        _cls: &Bound<'_, pyo3::types::PyType>,
        py: Python<'_>,
        model: &Bound<'_, PyAny>,
        shapes: usize,
        poses: usize,
        seed: u64,
        pose_sigma: Option<f64>,
        expressions: bool,
        parts: usize,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Self> {
        guard("PoseSet.from_body_model", || {
            if parts == 0 {
                return Err(convert::bad("parts", "must be at least 1"));
            }
            let callback = args::progress(progress, py)?;
            let sampled = py.import("desal._body_models")?.call_method1(
                "sample",
                (
                    model,
                    shapes,
                    poses,
                    seed,
                    pose_sigma,
                    expressions,
                    callback.as_ref().map(|c| c.clone_ref(py)),
                ),
            )?;
            let item = |key: &str| sampled.get_item(key);
            let positions = convert::poses(&item("poses")?)?;
            let faces = convert::faces("faces", &item("faces")?)?;
            let names = args::strings("names", &item("names")?)?;
            let groups = convert::ids("groups", &item("groups")?)?;
            let rest: Vec<desal_mesh::Vec3> = convert::points_f64("rest", &item("rest")?)?
                .into_iter()
                .map(|[x, y, z]| desal_mesh::Vec3::new(x, y, z))
                .collect();
            let weights = item("weights")?;
            let shape: Vec<usize> = weights.getattr("shape")?.extract()?;
            let [vertices, joints] = shape[..] else {
                return Err(convert::bad(
                    "skin_weights",
                    format!("must have shape (vertices, joints), not {shape:?}"),
                ));
            };
            let dense = convert::values_f64("skin_weights", &weights.call_method0("ravel")?)?;
            let weights = desal_bodymodel::SparseRows::from_dense(&dense, vertices, joints);
            let parents: Vec<Option<usize>> = convert::indices("parents", &item("parents")?, true)?
                .into_iter()
                .map(|p| p.map(|p| p as usize))
                .collect();
            let joint_names = args::strings("joint_names", &item("joint_names")?)?;
            let skin = desal_bodymodel::Skin {
                rest: &rest,
                faces: &faces,
                weights: &weights,
                parents: &parents,
                names: &joint_names,
            };
            skin.check().map_err(|e| errors::input(anyhow::anyhow!("the model's skin: {e}")))?;
            let labels = desal_bodymodel::labels_from_skin(&skin, parts);
            detached(py, None, move |_| {
                let built = memory::pose_set(Some(names), positions, faces, 0, Some(groups))
                    .map_err(errors::input)?;
                let set = built.set;
                labels.check_vertex_count(set.vertex_count()).map_err(|e| errors::input(e.into()))?;
                let removed_faces = (built.cleanup.degenerate.len(), built.cleanup.duplicate.len());
                let digest = content_digest(&set, &labels);
                Ok(PyPoseSet { set, labels, digest, parts: None, removed_faces })
            })
        })
    }

    /// Positions, (poses, vertices, 3) float64 (stored at float32, as `desal run` stores them).
    #[getter]
    fn poses<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        pose_array(py, &self.set)
    }

    /// The triangle list, (faces, 3) int64, after removing degenerate and duplicate faces.
    #[getter]
    fn faces<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        convert::face_array(py, &self.set.faces).into_any()
    }

    /// Part id per vertex, (vertices,) int64.
    #[getter]
    fn labels<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        convert::index_array(py, self.labels.labels.iter().copied()).into_any()
    }

    #[getter]
    fn part_names(&self) -> Vec<String> {
        self.labels.names.clone()
    }

    #[getter]
    fn names(&self) -> Vec<String> {
        self.set.names.clone()
    }

    #[getter]
    fn template(&self) -> usize {
        self.set.template
    }

    /// Group id per pose, (poses,) int64, or None: held-out figures hold out whole groups.
    #[getter]
    fn groups<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyAny>> {
        let groups = self.set.groups.as_ref()?;
        Some(convert::index_array(py, groups.iter().copied()).into_any())
    }

    #[getter]
    fn vertex_count(&self) -> usize {
        self.set.vertex_count()
    }

    #[getter]
    fn pose_count(&self) -> usize {
        self.set.pose_count()
    }

    /// The part discovery's report (when `labels` was None), else None.
    #[getter]
    fn parts_report<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.parts.as_ref().map(|p| convert::to_python(py, p)).transpose()
    }

    /// (degenerate, duplicate) faces removed from the input's triangle list.
    #[getter]
    fn removed_faces(&self) -> (usize, usize) {
        self.removed_faces
    }

    fn __len__(&self) -> usize {
        self.set.pose_count()
    }

    fn __repr__(&self) -> String {
        format!(
            "PoseSet({} poses x {} vertices, {} faces, {} parts, template '{}')",
            self.set.pose_count(),
            self.set.vertex_count(),
            self.set.face_count(),
            self.labels.part_count(),
            self.set.names[self.set.template]
        )
    }
}

/// `PoseSet(parts=...)`: the JSON of a `[dataset.parts]` table, or the table as a dict.
fn parts_json(parts: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(text) = parts.cast::<PyString>() {
        return Ok(text.to_string());
    }
    if parts.cast::<PyDict>().is_err() {
        return Err(bad("parts", format!("parts={} must be a dict or its JSON", args::repr(parts))));
    }
    let kwargs = PyDict::new(parts.py());
    kwargs.set_item("allow_nan", false)?;
    let text = parts.py().import("json")?.call_method("dumps", (parts,), Some(&kwargs));
    text.and_then(|t| t.extract()).map_err(|e| {
        let e = e.value(parts.py()).to_string();
        InputError::new_err(format!(
            "parts={} must hold only finite numbers, strings, bools and lists ({e})",
            args::repr(parts)
        ))
    })
}

/// A digest of a pose set's content: names, template, positions, faces and labels. Two
/// `PoseSet`s built from the same arrays have the same digest; a fit of one applies to
/// the other.
fn content_digest(set: &PoseSet, labels: &PartLabels) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::hash::DefaultHasher::new();
    (&set.names, set.template, &set.faces, &labels.labels, &labels.names).hash(&mut h);
    for p in set.poses.iter().flatten() {
        (p.x.to_bits(), p.y.to_bits(), p.z.to_bits()).hash(&mut h);
    }
    h.finish()
}

/// Stage 1's result: per pose and part a rigid (or affine) transform, per pose and
/// vertex the residual distance.
#[pyclass(name = "Fit", module = "desal", frozen)]
#[derive(Debug)]
struct PyFit {
    body: FitV1,
    summary: serde_json::Value,
    /// The [`content_digest`] of the pose set it was computed from.
    source: u64,
}

#[pymethods]
impl PyFit {
    /// (poses, parts, 3, 3) float64: the linear part (a rotation for the rigid fit).
    #[getter]
    fn rotations<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let (p, k) = (self.body.pose_names.len(), self.body.part_names.len());
        convert::array(py, self.body.linear.iter().flatten().copied().collect(), [p, k, 3, 3]).into_any()
    }

    /// (poses, parts, 3) float64.
    #[getter]
    fn translations<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let (p, k) = (self.body.pose_names.len(), self.body.part_names.len());
        convert::array(py, self.body.translation.iter().flatten().copied().collect(), [p, k, 3]).into_any()
    }

    /// (poses, vertices) float32: `|R v_T + t - v_X|` per pose and vertex.
    #[getter]
    fn residuals<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        let p = self.body.pose_names.len();
        convert::array(py, self.body.residuals.clone(), [p, self.body.vertex_count as usize]).into_any()
    }

    #[getter]
    fn model(&self) -> String {
        self.body.model.clone()
    }

    /// The stage's summary (`fit.json` of `desal run`).
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        convert::to_python(py, &self.summary)
    }

    fn __repr__(&self) -> String {
        format!(
            "Fit({} poses x {} parts, {})",
            self.body.pose_names.len(),
            self.body.part_names.len(),
            self.body.model
        )
    }
}

/// Stage 2's result: per-vertex saliency in [0, 1] and the weights stage 3 uses.
#[pyclass(name = "Saliency", module = "desal", frozen)]
#[derive(Debug)]
struct PySaliency {
    body: SaliencyV1,
    summary: serde_json::Value,
}

#[pymethods]
impl PySaliency {
    /// (vertices,) float64 in [0, 1].
    #[getter]
    fn saliency<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        convert::vector(py, &self.body.saliency).into_any()
    }

    /// (vertices,) float64 in [floor, 1]: the weights `desal.simplify(weights=...)` takes.
    #[getter]
    fn weights<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        convert::vector(py, &self.body.weights).into_any()
    }

    /// (vertices,) float64: the raw per-vertex sums before normalisation.
    #[getter]
    fn raw<'py>(&self, py: Python<'py>) -> Bound<'py, PyAny> {
        convert::vector(py, &self.body.raw).into_any()
    }

    /// The stage's summary (`saliency.json` of `desal run`).
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        convert::to_python(py, &self.summary)
    }

    fn __repr__(&self) -> String {
        format!("Saliency({} vertices, normaliser {:.4})", self.body.saliency.len(), self.body.normaliser)
    }
}

fn json<T: serde::Serialize>(value: &T) -> PyResult<serde_json::Value> {
    serde_json::to_value(value).map_err(|e| Error::new_err(e.to_string()))
}

/// Stage 1 on a pose set: `fit(ps, method="rigid", progress=None)`.
#[pyfunction]
#[pyo3(signature = (ps, options=None, progress=None))]
fn fit(
    py: Python<'_>,
    ps: &Bound<'_, PyAny>,
    options: Option<&str>,
    progress: Option<Py<PyAny>>,
) -> PyResult<PyFit> {
    guard("fit", || {
        let ps = args::instance::<PyPoseSet>("ps", ps)?.get();
        let params: FitParams = table("fit", options)?;
        detached(py, progress, |p| {
            let out = memory::fit(&params, &ps.set, &ps.labels, p).map_err(errors::classify)?;
            Ok(PyFit { summary: json(&out.summary)?, body: out.body, source: ps.digest })
        })
    })
}

/// Stage 2 on a pose set and its fit.
#[pyfunction]
#[pyo3(signature = (ps, fit, options=None))]
fn saliency(
    py: Python<'_>,
    ps: &Bound<'_, PyAny>,
    fit: &Bound<'_, PyAny>,
    options: Option<&str>,
) -> PyResult<PySaliency> {
    guard("saliency", || {
        let ps = args::instance::<PyPoseSet>("ps", ps)?.get();
        let fit = args::instance::<PyFit>("fit", fit)?.get();
        if fit.source != ps.digest {
            return Err(bad(
                "fit",
                format!(
                    "was computed from another pose set ({} poses x {} vertices), not this one ({} poses x {} vertices); \
                     compute it with desal.fit(ps)",
                    fit.body.pose_names.len(),
                    fit.body.vertex_count,
                    ps.set.pose_count(),
                    ps.set.vertex_count()
                ),
            ));
        }
        let params: SaliencyParams = table("saliency", options)?;
        params.config().map_err(errors::input)?;
        detached(py, None, |_| {
            let out = memory::saliency(&params, &ps.set, &fit.body).map_err(errors::classify)?;
            Ok(PySaliency { summary: json(&out.summary)?, body: out.body })
        })
    })
}

/// The report of a simplification: the stage summary, its note and `simp_to_orig`.
fn simplified_report<'py>(
    py: Python<'py>,
    body: &SimplifiedV1,
    summary: &serde_json::Value,
    note: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let report = convert::to_python(py, summary)?.cast_into::<PyDict>()?;
    report.set_item("note", note)?;
    let kept: Vec<i64> = body.simp_to_orig.iter().map(|o| o.map_or(-1, i64::from)).collect();
    let n = kept.len();
    report.set_item("simp_to_orig", convert::array(py, kept, [n]))?;
    Ok(report)
}

/// Stage 3 on any mesh: returns (vertices, faces, report).
#[pyfunction]
#[pyo3(signature = (vertices, faces, options=None, weights=None, labels=None, progress=None))]
fn simplify<'py>(
    py: Python<'py>,
    vertices: &Bound<'py, PyAny>,
    faces: &Bound<'py, PyAny>,
    options: Option<&str>,
    weights: Option<&Bound<'py, PyAny>>,
    labels: Option<&Bound<'py, PyAny>>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>, Bound<'py, PyDict>)> {
    guard("simplify", || {
        let positions = convert::points_f64("vertices", vertices)?;
        let faces = convert::faces("faces", faces)?;
        let mut params: SimplifyParams = table("simplify", options)?;
        if let Some(method @ (Method::DesalRefit | Method::DesalUpsample)) = params.method {
            let name = method.name();
            return Err(bad(
                "options",
                format!(
                    "method = \"{name}\" measures the poses: use simplify_pose_set(..., method=\"{name}\")"
                ),
            ));
        }
        params.saliency = weights.is_some();
        let weights = weights.map(|w| convert::values_f64("weights", w)).transpose()?.unwrap_or_default();
        let labels = labels.map(|l| convert::ids("labels", l)).transpose()?;
        let config = params.config().map_err(errors::input)?;
        let out = detached(py, progress, move |p| {
            let mesh = TriMesh::try_new(positions.into_iter().map(Into::into).collect(), faces, "vertices")
                .map_err(|e| errors::input(e.into()))?;
            let n = mesh.vertex_count();
            if config.saliency && weights.len() != n {
                return Err(bad(
                    "weights",
                    format!("has {} entries but the mesh has {n} vertices", weights.len()),
                ));
            }
            let labels = match labels {
                Some(ids) if ids.len() != n => {
                    return Err(bad(
                        "labels",
                        format!("has {} entries but the mesh has {n} vertices", ids.len()),
                    ));
                }
                Some(ids) => PartLabels::from_ids(ids),
                None => PartLabels::from_ids(vec![0; n]),
            };
            simplify_stage::compute(&config, &mesh, &weights, &labels, p).map_err(errors::input)
        })?;
        let report = simplified_report(py, &out.body, &json(&out.summary)?, &out.note)?;
        Ok((
            convert::rows(py, &out.body.positions).into_any(),
            convert::face_array(py, &out.body.faces).into_any(),
            report,
        ))
    })
}

/// Stage 4: maps a simplification of the pose set's template to original vertices and
/// applies the map to every pose. Returns (simp_to_orig, poses).
#[pyfunction]
#[pyo3(signature = (ps, simplified_vertices, simplified_faces, simp_to_orig=None))]
fn map<'py>(
    py: Python<'py>,
    ps: &Bound<'py, PyAny>,
    simplified_vertices: &Bound<'py, PyAny>,
    simplified_faces: &Bound<'py, PyAny>,
    simp_to_orig: Option<&Bound<'py, PyAny>>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    guard("map", || {
        let ps = args::instance::<PyPoseSet>("ps", ps)?.get();
        let positions = convert::points_f64("simplified_vertices", simplified_vertices)?;
        let faces = convert::faces("simplified_faces", simplified_faces)?;
        let kept = simp_to_orig.map(|k| convert::indices("simp_to_orig", k, true)).transpose()?;
        let (map, poses) = detached(py, None, move |_| {
            let mesh = TriMesh::try_new(
                positions.into_iter().map(Into::into).collect(),
                faces,
                "simplified_vertices",
            )
            .map_err(|e| errors::input(e.into()))?;
            let mut body = simplify_stage::external(&mesh);
            if let Some(kept) = kept {
                if kept.len() != mesh.vertex_count() {
                    return Err(bad(
                        "simp_to_orig",
                        format!(
                            "has {} entries but there are {} simplified vertices",
                            kept.len(),
                            mesh.vertex_count()
                        ),
                    ));
                }
                body.simp_to_orig = kept;
                body.placement = "given".into();
                body.input_vertices = ps.set.vertex_count() as u32;
                body.input_faces = ps.set.face_count() as u32;
            }
            let out =
                desal_driver::stages::map::compute(&body, &ps.set, &ps.labels).map_err(errors::input)?;
            let (poses, _) = memory::apply_map(&out.body, &ps.set, &ps.labels).map_err(errors::classify)?;
            Ok((out.body, poses))
        })?;
        Ok((convert::index_array(py, map.simp_to_orig.iter().copied()).into_any(), pose_array(py, &poses)))
    })
}

fn pose_array<'py>(py: Python<'py>, set: &PoseSet) -> Bound<'py, PyAny> {
    let flat: Vec<f64> = set.poses.iter().flatten().flat_map(|p| [p.x, p.y, p.z]).collect();
    convert::array(py, flat, [set.pose_count(), set.vertex_count(), 3]).into_any()
}

/// The stage parameters of `simplify_pose_set`, `simplify_rig` and `hierarchy`: the
/// pipeline file's `[dataset.fit]`, `[dataset.saliency]` and `[dataset.simplify]`, and a
/// method name: one of stage 3's methods (`[simplify] method`, which set their own
/// settings; `multipose` with the plain quadric cost, as `desal eval` names it), or a cost
/// that sets the cost's switches.
fn stage_params(
    method: &str,
    fit: Option<&str>,
    saliency: Option<&str>,
    simplify: Option<&str>,
) -> PyResult<StageParams> {
    let mut p = StageParams {
        fit: table_as("fit", fit, FIT_METHOD)?,
        saliency: table("saliency", saliency)?,
        simplify: table("simplify", simplify)?,
    };
    let cost = match method.parse::<Method>() {
        Ok(own) => {
            p.simplify.method = Some(own);
            (own == Method::Multipose).then_some(Cost::Qslim)
        }
        Err(_) => Some(method.parse::<Cost>().map_err(|e| {
            bad(
                "method",
                format!(
                    "{e}: use \"paper\", \"qslim\", \"saliency\", \"balance\", \"multipose\", \"desal\", \"desal-refit\", \"desal-upsample\" or a cost and a placement such as \"qslim-optimal\""
                ),
            )
        })?),
    };
    if let Some(cost) = cost {
        (p.simplify.saliency, p.simplify.balance) = cost.switches();
    }
    p.simplify.config().map_err(errors::input)?;
    p.saliency.config().map_err(errors::input)?;
    Ok(p)
}

/// The whole pipeline on one pose set: stages 1–4 as `desal run` computes them.
#[pyfunction]
#[pyo3(signature = (ps, method="paper", fit=None, saliency=None, simplify=None, progress=None))]
fn simplify_pose_set<'py>(
    py: Python<'py>,
    ps: &Bound<'py, PyAny>,
    method: &str,
    fit: Option<&str>,
    saliency: Option<&str>,
    simplify: Option<&str>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    guard("simplify_pose_set", || {
        let ps = args::instance::<PyPoseSet>("ps", ps)?.get();
        let params = stage_params(method, fit, saliency, simplify)?;
        let (s, poses, labels) = detached(py, progress, |p| {
            let s = memory::simplify_pose_set(&params, &ps.set, &ps.labels, p).map_err(errors::classify)?;
            let (poses, labels) =
                memory::apply_map(&s.map.body, &ps.set, &ps.labels).map_err(errors::classify)?;
            Ok((s, poses, labels))
        })?;
        let out = PyDict::new(py);
        out.set_item("vertex_map", convert::index_array(py, s.map.body.simp_to_orig.iter().copied()))?;
        out.set_item("faces", convert::face_array(py, &s.map.body.faces))?;
        out.set_item("poses", pose_array(py, &poses))?;
        out.set_item("labels", convert::index_array(py, labels.labels.iter().copied()))?;
        out.set_item("saliency", convert::vector(py, &s.saliency.body.saliency))?;
        out.set_item("weights", convert::vector(py, &s.saliency.body.weights))?;
        out.set_item("simplified_vertices", convert::rows(py, &s.simplified.body.positions))?;
        let report = PyDict::new(py);
        report.set_item("method", method)?;
        report.set_item("fit", convert::to_python(py, &s.fit.summary)?)?;
        report.set_item("saliency", convert::to_python(py, &s.saliency.summary)?)?;
        report.set_item(
            "simplify",
            simplified_report(py, &s.simplified.body, &json(&s.simplified.summary)?, &s.simplified.note)?,
        )?;
        report.set_item("map", convert::to_python(py, &s.map.summary)?)?;
        out.set_item("report", report)?;
        Ok(out)
    })
}

/// A skinned glTF rig simplified as `desal run` simplifies a `[dataset.rig]`, written to
/// `out` as a `.glb` (the bytes `desal run` writes as `simplified.glb`), with `lods` each
/// level and the chain beside it ([`lod_path`]); returns the report. `rig` is the JSON of the `[dataset.rig]` table without `file`; `frames` is
/// at most [`MAX_RIG_FRAMES`].
#[pyfunction]
#[pyo3(signature = (file, out, rig=None, method="paper", fit=None, saliency=None, simplify=None, progress=None))]
#[allow(clippy::too_many_arguments)]
fn simplify_rig<'py>(
    py: Python<'py>,
    file: &Bound<'py, PyAny>,
    out: &Bound<'py, PyAny>,
    rig: Option<&str>,
    method: &str,
    fit: Option<&str>,
    saliency: Option<&str>,
    simplify: Option<&str>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    guard("simplify_rig", || {
        let (file, out) = (args::path("rig", file)?, args::path("out", out)?);
        let mut settings: serde_json::Value = table("rig", rig)?;
        let Some(object) = settings.as_object_mut() else {
            return Err(InputError::new_err("rig: the settings must be a table"));
        };
        if object.contains_key("file") {
            return Err(bad("rig", "give the rig's path as the first argument, not as `file`"));
        }
        object.insert("file".into(), file.display().to_string().into());
        let rig: RigParams = table("rig", Some(&settings.to_string()))?;
        if rig.frames > MAX_RIG_FRAMES {
            return Err(InputError::new_err(format!(
                "rig: frames={} is more than the {MAX_RIG_FRAMES} frames desal poses a rig at (desal.MAX_RIG_FRAMES)",
                rig.frames
            )));
        }
        rig.frame_config().map_err(errors::input)?;
        rig.parts_config().map_err(errors::input)?;
        rig.weight_options().map_err(errors::input)?;
        rig.lod_fractions().map_err(errors::input)?;
        rig.check_mesh_overrides().map_err(errors::input)?;
        let params = stage_params(method, fit, saliency, simplify)?;
        // Refused now, not after the simplification: an output that is a folder or a FIFO.
        desal_io::confine::write_target(&out).map_err(errors::io)?;
        let s = detached(py, progress, |p| {
            let s = memory::simplify_rig(&file, &rig, &params, p).map_err(errors::classify)?;
            // Every file is built before the first is written.
            let mut files = vec![(out.clone(), s.glb.clone())];
            if let Some(lods) = &s.lods {
                for (k, level) in lods.levels.iter().enumerate() {
                    files.push((lod_path(&out, &format!("lod{}", k + 1)), level.bytes.clone()));
                }
                files.push((lod_path(&out, "lods"), lods.combined.bytes.clone()));
            }
            for (path, _) in &files {
                desal_io::confine::write_target(path).map_err(errors::io)?;
            }
            for (path, bytes) in &files {
                desal_io::write_atomic(path, bytes).map_err(errors::io)?;
            }
            desal_driver::stages::rig::write_images_beside(&out, &s.images).map_err(errors::classify)?;
            Ok((s, files.into_iter().skip(1).map(|(path, _)| path).collect::<Vec<_>>()))
        })?;
        let (s, lod_files) = s;
        let report = PyDict::new(py);
        report.set_item("method", method)?;
        report.set_item("glb", out)?;
        report.set_item("rig", convert::to_python(py, &s.rig)?)?;
        report.set_item("ingest", convert::to_python(py, &s.ingest.summary)?)?;
        report.set_item("ingest_note", &s.ingest.note)?;
        report.set_item("labels", convert::to_python(py, &s.labels.summary)?)?;
        report.set_item("fit", convert::to_python(py, &s.stages.fit.summary)?)?;
        report.set_item("saliency", convert::to_python(py, &s.stages.saliency.summary)?)?;
        report.set_item(
            "simplify",
            simplified_report(
                py,
                &s.stages.simplified.body,
                &json(&s.stages.simplified.summary)?,
                &s.stages.simplified.note,
            )?,
        )?;
        report.set_item("map", convert::to_python(py, &s.stages.map.summary)?)?;
        report.set_item("lods", convert::to_python(py, &s.rig.lods)?)?;
        report.set_item("lod_files", lod_files)?;
        Ok(report)
    })
}

/// Where `simplify_rig` writes a LOD file beside `out`: `<stem>-<what>.<extension>`
/// (`avatar-lod1.glb`, `avatar-lods.glb` for `avatar.glb`).
fn lod_path(out: &std::path::Path, what: &str) -> std::path::PathBuf {
    let stem = out.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let extension = out.extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_else(|| "glb".into());
    out.with_file_name(format!("{stem}-{what}.{extension}"))
}

/// A hierarchy of coarse levels: the npz arrays (`levels`, `F{k}`, `A{k}_*`, `D{k}_*`,
/// `U{k}_*`, `map{k}`, `orig{k}`) and each level step's summary.
#[pyfunction]
#[pyo3(signature = (ps, hierarchy, method="paper", fit=None, saliency=None, simplify=None, progress=None))]
#[allow(clippy::too_many_arguments)]
fn hierarchy<'py>(
    py: Python<'py>,
    ps: &Bound<'py, PyAny>,
    hierarchy: &str,
    method: &str,
    fit: Option<&str>,
    saliency: Option<&str>,
    simplify: Option<&str>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(Bound<'py, PyDict>, Bound<'py, PyAny>)> {
    guard("hierarchy", || {
        let ps = args::instance::<PyPoseSet>("ps", ps)?.get();
        let stage = stage_params(method, fit, saliency, simplify)?;
        let h: HierarchyParams = table("hierarchy", Some(hierarchy))?;
        h.config().map_err(errors::input)?;
        h.check_levels(Some(ps.set.vertex_count())).map_err(errors::input)?;
        let (arrays, summaries) = detached(py, progress, |p| {
            memory::hierarchy(&stage, &h, &ps.set, &ps.labels, p).map_err(errors::classify)
        })?;
        let dict = artifacts::hierarchy_dict(py, &arrays)?;
        Ok((dict, convert::to_python(py, &summaries)?))
    })
}

/// Runs a pipeline file with the cache, as `desal run` does; returns one report per
/// dataset (`report.json`).
#[pyfunction]
#[pyo3(signature = (pipeline, out=None, force=false, from_stage=None, jobs=None, cache_dir=None, explain=false, progress=false))]
#[allow(clippy::too_many_arguments)]
fn run<'py>(
    py: Python<'py>,
    pipeline: &Bound<'py, PyAny>,
    out: Option<&Bound<'py, PyAny>>,
    force: bool,
    from_stage: Option<&str>,
    jobs: Option<&Bound<'py, PyAny>>,
    cache_dir: Option<&Bound<'py, PyAny>>,
    explain: bool,
    progress: bool,
) -> PyResult<Bound<'py, PyAny>> {
    guard("run", || {
        let pipeline = args::path("pipeline", pipeline)?;
        let out = out.map(|o| args::path("out", o)).transpose()?;
        let cache_dir = cache_dir.map(|c| args::path("cache_dir", c)).transpose()?;
        let jobs = jobs.map(|j| args::index("jobs", j)).transpose()?.unwrap_or(1);
        let from = from_stage
            .map(|s| {
                s.parse::<desal_driver::stages::runner::Stage>().map_err(|_| {
                    bad(
                        "from_stage",
                        format!(
                            "'{s}' is not a stage: use ingest, parts, fit, saliency, simplify, map or hierarchy"
                        ),
                    )
                })
            })
            .transpose()?;
        let reports = py.detach(|| {
            // The pipeline file is the caller's input: anything wrong with it (a FIFO or
            // a device included, which the driver refuses) is an InputError.
            let pipeline = desal_driver::pipeline::load(&pipeline, out.as_deref()).map_err(errors::input)?;
            let options = desal_driver::run::RunOptions {
                out,
                cache_dir,
                force,
                from,
                jobs: jobs.max(1),
                console: std::sync::Arc::new(desal_driver::progress::Lines { quiet: !progress }),
                explain,
                ..Default::default()
            };
            desal_driver::run::run(&pipeline, &options).map_err(errors::classify)
        })?;
        convert::to_python(py, &reports)
    })
}

/// Reads a desal artifact (`.dsa`) into a dict of NumPy arrays and values, with its
/// `kind`, `version` and `producer`.
#[pyfunction]
fn load<'py>(py: Python<'py>, path: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyDict>> {
    guard("load", || artifacts::load(py, &args::path("path", path)?))
}

/// Reads `hierarchy.npz` (as `desal run` writes it) into its arrays, checking the layout.
/// Only a regular file is read (a FIFO, device or folder is refused by name).
#[pyfunction]
fn read_hierarchy_npz<'py>(py: Python<'py>, path: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyDict>> {
    guard("load_hierarchy", || {
        let path = args::path("path", path)?;
        let arrays =
            py.detach(|| desal_io::npz::read_hierarchy_npz(&path)).map_err(|e| errors::input(e.into()))?;
        artifacts::hierarchy_dict(py, &arrays)
    })
}

/// Writes a hierarchy's arrays (the dict `hierarchy` returns) as `hierarchy.npz`, the
/// bytes `desal run` writes.
#[pyfunction]
fn write_hierarchy_npz(path: &Bound<'_, PyAny>, arrays: &Bound<'_, PyAny>) -> PyResult<()> {
    guard("Hierarchy.save", || {
        let path = args::path("path", path)?;
        let arrays = arrays.cast::<PyDict>().map_err(|_| bad("arrays", "must be a dict of arrays"))?;
        let h = artifacts::hierarchy_from_dict(arrays)?;
        desal_io::npz::write_hierarchy_npz(&path, &h).map_err(errors::io)
    })
}

/// Writes `data` to `path` by desal's one rule for what may be replaced
/// (`desal_io::write_atomic`): a temp file beside it, renamed over it (a symlink is
/// replaced, its target untouched); a character device such as `/dev/null` written
/// through; a folder, FIFO, socket or block device refused with `InputError`. On any
/// error nothing is left behind. The Python layer's own writers (`save_graphcmr`) go
/// through it.
#[pyfunction]
fn _write_file(py: Python<'_>, path: &Bound<'_, PyAny>, data: &[u8]) -> PyResult<()> {
    guard("write", || {
        let path = args::path("path", path)?;
        py.detach(|| desal_io::write_atomic(&path, data)).map_err(errors::io)
    })
}

/// Panics inside [`guard`], for the tests: proves a Rust panic reaches Python as
/// `desal.Error`, not as `PanicException`.
#[pyfunction]
fn _panic_for_tests(py: Python<'_>, message: &str) -> PyResult<()> {
    guard("_panic_for_tests", || py.detach(|| panic!("{message}")))
}

/// Reads a mesh file (PLY, OBJ, OFF) as desal's readers do: (vertices, faces).
#[pyfunction]
fn read_mesh<'py>(
    py: Python<'py>,
    path: &Bound<'py, PyAny>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    guard("read_mesh", || {
        let path = args::path("path", path)?;
        let mesh = py.detach(|| desal_io::read_mesh(&path)).map_err(|e| errors::input(e.into()))?;
        let rows: Vec<[f64; 3]> = mesh.positions.iter().map(|p| [p.x, p.y, p.z]).collect();
        Ok((convert::rows(py, &rows).into_any(), convert::face_array(py, &mesh.faces).into_any()))
    })
}

/// Reads a labels file (`.txt` ids or `.json` with part names) as desal does:
/// (ids, names).
#[pyfunction]
fn read_labels<'py>(py: Python<'py>, path: &Bound<'py, PyAny>) -> PyResult<(Bound<'py, PyAny>, Vec<String>)> {
    guard("read_labels", || {
        let path = args::path("path", path)?;
        let labels =
            py.detach(|| desal_io::labels::read_labels(&path)).map_err(|e| errors::input(e.into()))?;
        Ok((convert::index_array(py, labels.labels.iter().copied()).into_any(), labels.names))
    })
}

#[pymodule]
fn _desal(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("MAX_RIG_FRAMES", MAX_RIG_FRAMES)?;
    m.add("InputError", py.get_type::<InputError>())?;
    m.add("Error", py.get_type::<Error>())?;
    m.add_class::<PyPoseSet>()?;
    m.add_class::<PyFit>()?;
    m.add_class::<PySaliency>()?;
    for f in [
        wrap_pyfunction!(fit, m)?,
        wrap_pyfunction!(saliency, m)?,
        wrap_pyfunction!(simplify, m)?,
        wrap_pyfunction!(map, m)?,
        wrap_pyfunction!(simplify_pose_set, m)?,
        wrap_pyfunction!(simplify_rig, m)?,
        wrap_pyfunction!(hierarchy, m)?,
        wrap_pyfunction!(run, m)?,
        wrap_pyfunction!(load, m)?,
        wrap_pyfunction!(read_hierarchy_npz, m)?,
        wrap_pyfunction!(write_hierarchy_npz, m)?,
        wrap_pyfunction!(_write_file, m)?,
        wrap_pyfunction!(_panic_for_tests, m)?,
        wrap_pyfunction!(read_mesh, m)?,
        wrap_pyfunction!(read_labels, m)?,
    ] {
        m.add_function(f)?;
    }
    Ok(())
}
