//! `desal._desal`, the native half of the `desal` Python package: every stage and the
//! pipeline on NumPy arrays. The stages are the root package's own (`desal::memory`, the
//! same calls `desal run` makes), so the same arrays give the same bytes as the CLI.
//! The GIL is released while a stage computes.

mod artifacts;
mod convert;
mod errors;
mod progress;

use desal::memory::{self, Stage3, StageParams};
use desal::stages::fit::FitParams;
use desal::stages::hierarchy::HierarchyParams;
use desal::stages::parts::PartsParams;
use desal::stages::rig::RigParams;
use desal::stages::saliency::SaliencyParams;
use desal::stages::simplify::{self as simplify_stage, Cost, Method, SimplifyParams};
use desal_io::artifact::{FitV1, SaliencyV1, SimplifiedV1};
use desal_mesh::{PartLabels, PoseSet, TriMesh};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde::de::DeserializeOwned;

use crate::convert::bad;
use crate::errors::{Error, InputError};
use crate::progress::PyProgress;

/// Stage parameters from the JSON the Python layer builds from keyword arguments, with
/// the pipeline file's names and checks (`unknown field`, ranges).
fn params<T: DeserializeOwned>(what: &str, json: Option<&str>) -> PyResult<T> {
    serde_json::from_str(json.unwrap_or("{}")).map_err(|e| InputError::new_err(format!("{what}: {e}")))
}

/// Runs `f` with the GIL released, reporting to `callback`.
fn detached<T: Send>(
    py: Python<'_>,
    callback: Option<Py<PyAny>>,
    f: impl FnOnce(&PyProgress) -> PyResult<T> + Send,
) -> PyResult<T> {
    let progress = PyProgress::new(callback);
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
    /// The discovery's report when the labels were discovered.
    parts: Option<serde_json::Value>,
    removed_faces: (usize, usize),
}

#[pymethods]
impl PyPoseSet {
    #[new]
    #[pyo3(signature = (poses, faces, labels=None, template=0, names=None, part_names=None, parts=None, progress=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        poses: &Bound<'_, PyAny>,
        faces: &Bound<'_, PyAny>,
        labels: Option<&Bound<'_, PyAny>>,
        template: usize,
        names: Option<Vec<String>>,
        part_names: Option<Vec<String>>,
        parts: Option<&str>,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Self> {
        let positions = convert::poses(poses)?;
        let faces = convert::faces("faces", faces)?;
        let ids = labels.map(|l| convert::ids("labels", l)).transpose()?;
        detached(py, progress, move |_| {
            let built = memory::pose_set(names, positions, faces, template).map_err(errors::input)?;
            let set = built.set;
            let (labels, parts) = match ids {
                Some(ids) => (memory::labels(ids, part_names, &set).map_err(errors::input)?, None),
                None => {
                    let params: PartsParams = params("parts", parts)?;
                    let (labels, summary) = memory::discover_parts(&params, &set).map_err(errors::failed)?;
                    (labels, Some(serde_json::to_value(summary).map_err(|e| Error::new_err(e.to_string()))?))
                }
            };
            let removed_faces = (built.cleanup.degenerate.len(), built.cleanup.duplicate.len());
            Ok(PyPoseSet { set, labels, parts, removed_faces })
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

/// Stage 1's result: per pose and part a rigid (or affine) transform, per pose and
/// vertex the residual distance.
#[pyclass(name = "Fit", module = "desal", frozen)]
#[derive(Debug)]
struct PyFit {
    body: FitV1,
    summary: serde_json::Value,
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
    ps: &Bound<'_, PyPoseSet>,
    options: Option<&str>,
    progress: Option<Py<PyAny>>,
) -> PyResult<PyFit> {
    let ps = ps.get();
    let params: FitParams = params("fit", options)?;
    detached(py, progress, |p| {
        let out = memory::fit(&params, &ps.set, &ps.labels, p).map_err(errors::failed)?;
        Ok(PyFit { summary: json(&out.summary)?, body: out.body })
    })
}

/// Stage 2 on a pose set and its fit.
#[pyfunction]
#[pyo3(signature = (ps, fit, options=None))]
fn saliency(
    py: Python<'_>,
    ps: &Bound<'_, PyPoseSet>,
    fit: &Bound<'_, PyFit>,
    options: Option<&str>,
) -> PyResult<PySaliency> {
    let (ps, fit) = (ps.get(), fit.get());
    let params: SaliencyParams = params("saliency", options)?;
    params.config().map_err(errors::input)?;
    detached(py, None, |_| {
        let out = memory::saliency(&params, &ps.set, &fit.body).map_err(errors::failed)?;
        Ok(PySaliency { summary: json(&out.summary)?, body: out.body })
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
    let positions = convert::points_f64("vertices", vertices)?;
    let faces = convert::faces("faces", faces)?;
    let mut params: SimplifyParams = params("simplify", options)?;
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
}

/// Stage 4: maps a simplification of the pose set's template to original vertices and
/// applies the map to every pose. Returns (simp_to_orig, poses).
#[pyfunction]
#[pyo3(signature = (ps, simplified_vertices, simplified_faces, simp_to_orig=None))]
fn map<'py>(
    py: Python<'py>,
    ps: &Bound<'py, PyPoseSet>,
    simplified_vertices: &Bound<'py, PyAny>,
    simplified_faces: &Bound<'py, PyAny>,
    simp_to_orig: Option<&Bound<'py, PyAny>>,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let ps = ps.get();
    let positions = convert::points_f64("simplified_vertices", simplified_vertices)?;
    let faces = convert::faces("simplified_faces", simplified_faces)?;
    let kept = simp_to_orig.map(|k| convert::indices("simp_to_orig", k, true)).transpose()?;
    let (map, poses) = detached(py, None, move |_| {
        let mesh =
            TriMesh::try_new(positions.into_iter().map(Into::into).collect(), faces, "simplified_vertices")
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
        let out = desal::stages::map::compute(&body, &ps.set, &ps.labels).map_err(errors::input)?;
        let (poses, _) = memory::apply_map(&out.body, &ps.set, &ps.labels).map_err(errors::failed)?;
        Ok((out.body, poses))
    })?;
    Ok((convert::index_array(py, map.simp_to_orig.iter().copied()).into_any(), pose_array(py, &poses)))
}

fn pose_array<'py>(py: Python<'py>, set: &PoseSet) -> Bound<'py, PyAny> {
    let flat: Vec<f64> = set.poses.iter().flatten().flat_map(|p| [p.x, p.y, p.z]).collect();
    convert::array(py, flat, [set.pose_count(), set.vertex_count(), 3]).into_any()
}

/// The stage parameters of `simplify_pose_set` and `hierarchy`: the pipeline file's
/// `[dataset.fit]`, `[dataset.saliency]` and `[dataset.simplify]`, and a method name
/// that sets the cost's switches.
fn stage_params(
    method: &str,
    fit: Option<&str>,
    saliency: Option<&str>,
    simplify: Option<&str>,
) -> PyResult<(StageParams, Stage3)> {
    let mut p = StageParams {
        fit: params("fit", fit)?,
        saliency: params("saliency", saliency)?,
        simplify: params("simplify", simplify)?,
    };
    let stage3 = if method == "multipose" { Stage3::Multipose } else { Stage3::Template };
    // desal's own methods (docs/eval/desal-method.md), as `[simplify] method` names
    // them: they set the cost's settings themselves.
    let own = match method {
        "desal" => Some(Method::Desal),
        "desal-refit" => Some(Method::DesalRefit),
        _ => None,
    };
    if own.is_some() {
        p.simplify.method = own;
    } else if stage3 == Stage3::Template {
        let cost: Cost = method.parse().map_err(|e| {
            bad(
                "method",
                format!(
                    "{e}: use \"paper\", \"qslim\", \"saliency\", \"balance\", \"multipose\", \"desal\" or \"desal-refit\""
                ),
            )
        })?;
        (p.simplify.saliency, p.simplify.balance) = cost.switches();
    }
    p.simplify.config().map_err(errors::input)?;
    p.saliency.config().map_err(errors::input)?;
    Ok((p, stage3))
}

/// The whole pipeline on one pose set: stages 1–4 as `desal run` computes them.
#[pyfunction]
#[pyo3(signature = (ps, method="paper", fit=None, saliency=None, simplify=None, progress=None))]
fn simplify_pose_set<'py>(
    py: Python<'py>,
    ps: &Bound<'py, PyPoseSet>,
    method: &str,
    fit: Option<&str>,
    saliency: Option<&str>,
    simplify: Option<&str>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let ps = ps.get();
    let (params, stage3) = stage_params(method, fit, saliency, simplify)?;
    let (s, poses, labels) = detached(py, progress, |p| {
        let s = memory::simplify_pose_set(&params, &ps.set, &ps.labels, stage3, p).map_err(errors::failed)?;
        let (poses, labels) = memory::apply_map(&s.map.body, &ps.set, &ps.labels).map_err(errors::failed)?;
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
}

/// A skinned glTF rig simplified as `desal run` simplifies a `[dataset.rig]`, written to
/// `out` as a `.glb` (the bytes `desal run` writes as `simplified.glb`); returns the
/// report. `rig` is the JSON of the `[dataset.rig]` table without `file`.
#[pyfunction]
#[pyo3(signature = (file, out, rig=None, method="paper", fit=None, saliency=None, simplify=None, progress=None))]
#[allow(clippy::too_many_arguments)]
fn simplify_rig<'py>(
    py: Python<'py>,
    file: std::path::PathBuf,
    out: std::path::PathBuf,
    rig: Option<&str>,
    method: &str,
    fit: Option<&str>,
    saliency: Option<&str>,
    simplify: Option<&str>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut table: serde_json::Value = params("rig", rig)?;
    let Some(object) = table.as_object_mut() else {
        return Err(InputError::new_err("rig: the settings must be a table"));
    };
    if object.contains_key("file") {
        return Err(bad("rig", "give the rig's path as the first argument, not as `file`"));
    }
    object.insert("file".into(), file.display().to_string().into());
    let rig: RigParams =
        serde_json::from_value(table).map_err(|e| InputError::new_err(format!("rig: {e}")))?;
    rig.frame_config().map_err(errors::input)?;
    rig.parts_config().map_err(errors::input)?;
    rig.weight_options().map_err(errors::input)?;
    let (params, stage3) = stage_params(method, fit, saliency, simplify)?;
    let s = detached(py, progress, |p| {
        let s = memory::simplify_rig(&file, &rig, &params, stage3, p).map_err(|e| {
            // A rig desal cannot read or pose is the caller's input, not a failure.
            if e.chain().any(|c| c.is::<desal_rig::RigError>()) {
                errors::input(e)
            } else {
                errors::failed(e)
            }
        })?;
        desal_io::write_atomic(&out, &s.glb).map_err(|e| errors::failed(e.into()))?;
        Ok(s)
    })?;
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
    Ok(report)
}

/// A hierarchy of coarse levels: the npz arrays (`levels`, `F{k}`, `A{k}_*`, `D{k}_*`,
/// `U{k}_*`, `map{k}`, `orig{k}`) and each level step's summary.
#[pyfunction]
#[pyo3(signature = (ps, hierarchy, method="paper", fit=None, saliency=None, simplify=None, progress=None))]
#[allow(clippy::too_many_arguments)]
fn hierarchy<'py>(
    py: Python<'py>,
    ps: &Bound<'py, PyPoseSet>,
    hierarchy: &str,
    method: &str,
    fit: Option<&str>,
    saliency: Option<&str>,
    simplify: Option<&str>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(Bound<'py, PyDict>, Bound<'py, PyAny>)> {
    let ps = ps.get();
    let (stage, stage3) = stage_params(method, fit, saliency, simplify)?;
    if stage3 != Stage3::Template {
        return Err(bad(
            "method",
            "a hierarchy's levels are simplified by a cost (paper, qslim, saliency, balance) or by desal or desal-refit",
        ));
    }
    let h: HierarchyParams = params("hierarchy", Some(hierarchy))?;
    h.config().map_err(errors::input)?;
    h.check_levels(Some(ps.set.vertex_count())).map_err(errors::input)?;
    let (arrays, summaries) = detached(py, progress, |p| {
        memory::hierarchy(&stage, &h, &ps.set, &ps.labels, p).map_err(errors::failed)
    })?;
    let dict = artifacts::hierarchy_dict(py, &arrays)?;
    Ok((dict, convert::to_python(py, &summaries)?))
}

/// Runs a pipeline file with the cache, as `desal run` does; returns one report per
/// dataset (`report.json`).
#[pyfunction]
#[pyo3(signature = (pipeline, out=None, force=false, from_stage=None, jobs=1, cache_dir=None, explain=false, progress=false))]
#[allow(clippy::too_many_arguments)]
fn run<'py>(
    py: Python<'py>,
    pipeline: std::path::PathBuf,
    out: Option<std::path::PathBuf>,
    force: bool,
    from_stage: Option<&str>,
    jobs: usize,
    cache_dir: Option<std::path::PathBuf>,
    explain: bool,
    progress: bool,
) -> PyResult<Bound<'py, PyAny>> {
    use clap::ValueEnum as _;
    let from = from_stage
        .map(|s| {
            desal::stages::runner::Stage::from_str(s, true).map_err(|_| {
                bad(
                    "from_stage",
                    format!(
                        "'{s}' is not a stage: use ingest, parts, fit, saliency, simplify, map or hierarchy"
                    ),
                )
            })
        })
        .transpose()?;
    let reports = py.detach(|| -> anyhow::Result<_> {
        let pipeline = desal::pipeline::load(&pipeline, out.as_deref())?;
        let options = desal::run::RunOptions {
            out,
            cache_dir,
            force,
            from,
            jobs: jobs.max(1),
            progress: if progress {
                desal::progress::ProgressMode::Auto
            } else {
                desal::progress::ProgressMode::Quiet
            },
            explain,
            ..Default::default()
        };
        desal::run::run(&pipeline, &options)
    });
    let reports = reports.map_err(errors::failed)?;
    convert::to_python(py, &reports)
}

/// Reads a desal artifact (`.dsa`) into a dict of NumPy arrays and values, with its
/// `kind`, `version` and `producer`.
#[pyfunction]
fn load<'py>(py: Python<'py>, path: std::path::PathBuf) -> PyResult<Bound<'py, PyDict>> {
    artifacts::load(py, &path)
}

/// Reads `hierarchy.npz` (as `desal run` writes it) into its arrays, checking the layout.
#[pyfunction]
fn read_hierarchy_npz<'py>(py: Python<'py>, path: std::path::PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let arrays =
        py.detach(|| desal_io::npz::read_hierarchy_npz(&path)).map_err(|e| errors::input(e.into()))?;
    artifacts::hierarchy_dict(py, &arrays)
}

/// Writes a hierarchy's arrays (the dict `hierarchy` returns) as `hierarchy.npz`, the
/// bytes `desal run` writes.
#[pyfunction]
fn write_hierarchy_npz(path: std::path::PathBuf, arrays: &Bound<'_, PyDict>) -> PyResult<()> {
    let h = artifacts::hierarchy_from_dict(arrays)?;
    desal_io::npz::write_hierarchy_npz(&path, &h).map_err(|e| errors::failed(e.into()))
}

/// Reads a mesh file (PLY, OBJ, OFF) as desal's readers do: (vertices, faces).
#[pyfunction]
fn read_mesh<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyAny>)> {
    let mesh = py.detach(|| desal_io::read_mesh(&path)).map_err(|e| errors::input(e.into()))?;
    let rows: Vec<[f64; 3]> = mesh.positions.iter().map(|p| [p.x, p.y, p.z]).collect();
    Ok((convert::rows(py, &rows).into_any(), convert::face_array(py, &mesh.faces).into_any()))
}

/// Reads a labels file (`.txt` ids or `.json` with part names) as desal does:
/// (ids, names).
#[pyfunction]
fn read_labels<'py>(py: Python<'py>, path: std::path::PathBuf) -> PyResult<(Bound<'py, PyAny>, Vec<String>)> {
    let labels = desal_io::labels::read_labels(&path).map_err(|e| errors::input(e.into()))?;
    Ok((convert::index_array(py, labels.labels.iter().copied()).into_any(), labels.names))
}

#[pymodule]
fn _desal(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
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
        wrap_pyfunction!(read_mesh, m)?,
        wrap_pyfunction!(read_labels, m)?,
    ] {
        m.add_function(f)?;
    }
    Ok(())
}
