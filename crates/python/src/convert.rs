//! NumPy arrays in and out. Inputs are read through strided views (any layout, float32
//! or float64, any integer type), each copied once into the Rust types the stages take;
//! other dtypes go through `numpy.asarray` first. Outputs are new arrays owned by Python.

use numpy::ndarray::{Array, ArrayView2, ArrayView3, Dimension, IntoDimension, Ix2, Ix3};
use numpy::{IntoPyArray, PyArrayDyn, PyReadonlyArray, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::{PyList, PyTuple};

use crate::errors::InputError;

/// An `InputError` naming the argument.
pub fn bad(argument: &str, message: impl std::fmt::Display) -> PyErr {
    InputError::new_err(format!("{argument}: {message}"))
}

/// `obj` as an array of `dims` dimensions of f64 or f32 (converted with `numpy.asarray`
/// when it is neither), handed to `f` as an f64 view.
fn with_float_view<R, D: Dimension>(
    argument: &str,
    obj: &Bound<'_, PyAny>,
    shape_text: &str,
    f: impl Fn(FloatView<'_, D>) -> PyResult<R>,
) -> PyResult<R> {
    if let Ok(a) = obj.extract::<PyReadonlyArray<'_, f64, D>>() {
        return f(FloatView::F64(a.as_array()));
    }
    if let Ok(a) = obj.extract::<PyReadonlyArray<'_, f32, D>>() {
        return f(FloatView::F32(a.as_array()));
    }
    let py = obj.py();
    let array = py
        .import("numpy")?
        .call_method1("asarray", (obj,))
        .map_err(|e| bad(argument, format!("is not a float array: {e}")))?;
    // Only real numbers are positions: numpy would turn complex into its real part
    // (with a warning), bools into 0 and 1, and strings into the numbers they spell.
    let kind: String = array.getattr("dtype")?.getattr("kind")?.extract()?;
    if !matches!(kind.as_str(), "f" | "i" | "u") {
        return Err(bad(argument, format!("must be a float array, not {}", dtype_name(&array)?)));
    }
    let converted = array.call_method1("astype", ("float64",))?;
    match converted.extract::<PyReadonlyArray<'_, f64, D>>() {
        Ok(a) => f(FloatView::F64(a.as_array())),
        Err(_) => {
            let ndim = converted.getattr("ndim")?.extract::<usize>()?;
            Err(bad(argument, format!("must have shape {shape_text}, but it has {ndim} dimensions")))
        }
    }
}

enum FloatView<'a, D: Dimension> {
    F64(numpy::ndarray::ArrayView<'a, f64, D>),
    F32(numpy::ndarray::ArrayView<'a, f32, D>),
}

/// Rows of a (n, 3) view as f32 (the pose-set artifact's precision).
fn rows_f32(view: &FloatView<'_, Ix2>) -> Vec<[f32; 3]> {
    match view {
        FloatView::F64(a) => a.outer_iter().map(|r| [r[0] as f32, r[1] as f32, r[2] as f32]).collect(),
        FloatView::F32(a) => a.outer_iter().map(|r| [r[0], r[1], r[2]]).collect(),
    }
}

fn shape_of<D: Dimension>(view: &FloatView<'_, D>) -> Vec<usize> {
    match view {
        FloatView::F64(a) => a.shape().to_vec(),
        FloatView::F32(a) => a.shape().to_vec(),
    }
}

/// Poses: one (poses, vertices, 3) array, or a sequence of (vertices, 3) arrays (which may
/// differ in vertex count; the pose set then refuses them, naming the pose).
pub fn poses(obj: &Bound<'_, PyAny>) -> PyResult<Vec<Vec<[f32; 3]>>> {
    let is_sequence = obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>();
    if is_sequence {
        let mut out = Vec::new();
        for (k, item) in obj.try_iter()?.enumerate() {
            out.push(points_f32(&format!("poses[{k}]"), &item?)?);
        }
        return Ok(out);
    }
    with_float_view::<_, Ix3>("poses", obj, "(poses, vertices, 3)", |view| {
        let shape = shape_of(&view);
        if shape[2] != 3 {
            return Err(bad("poses", format!("must have shape (poses, vertices, 3), not {shape:?}")));
        }
        Ok(match view {
            FloatView::F64(a) => pose_rows(a),
            FloatView::F32(a) => pose_rows(a),
        })
    })
}

fn f32_of<T: Into<f64>>(x: T) -> f32 {
    x.into() as f32
}

fn pose_rows<T: Copy + Into<f64>>(a: ArrayView3<'_, T>) -> Vec<Vec<[f32; 3]>> {
    a.outer_iter()
        .map(|pose| pose.outer_iter().map(|r| [f32_of(r[0]), f32_of(r[1]), f32_of(r[2])]).collect())
        .collect()
}

/// A (n, 3) point array, at f32.
pub fn points_f32(argument: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<[f32; 3]>> {
    with_float_view::<_, Ix2>(argument, obj, "(vertices, 3)", |view| {
        check_columns(argument, &shape_of(&view), "(vertices, 3)")?;
        Ok(rows_f32(&view))
    })
}

/// A (n, 3) point array, at f64.
pub fn points_f64(argument: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<[f64; 3]>> {
    with_float_view::<_, Ix2>(argument, obj, "(vertices, 3)", |view| {
        check_columns(argument, &shape_of(&view), "(vertices, 3)")?;
        Ok(match view {
            FloatView::F64(a) => a.outer_iter().map(|r| [r[0], r[1], r[2]]).collect(),
            FloatView::F32(a) => a.outer_iter().map(|r| [r[0].into(), r[1].into(), r[2].into()]).collect(),
        })
    })
}

/// A 1-D float array (per-vertex weights), at f64.
pub fn values_f64(argument: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    with_float_view::<_, numpy::ndarray::Ix1>(argument, obj, "(vertices,)", |view| {
        Ok(match view {
            FloatView::F64(a) => a.to_vec(),
            FloatView::F32(a) => a.iter().map(|&x| x.into()).collect(),
        })
    })
}

fn check_columns(argument: &str, shape: &[usize], shape_text: &str) -> PyResult<()> {
    if shape[1] != 3 {
        return Err(bad(argument, format!("must have shape {shape_text}, not {shape:?}")));
    }
    Ok(())
}

/// The dtype's name (`complex128`, `<U3`, `bool`).
fn dtype_name(array: &Bound<'_, PyAny>) -> PyResult<String> {
    Ok(array.getattr("dtype")?.str()?.to_string())
}

/// `obj` as an int64 array (any integer dtype converts exactly, int64 without a copy;
/// floats and the rest are refused).
fn int64_array<'py>(argument: &str, obj: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyAny>> {
    let py = obj.py();
    let np = py.import("numpy")?;
    let array = np.call_method1("asarray", (obj,)).map_err(|e| bad(argument, e))?;
    let kind: String = array.getattr("dtype")?.getattr("kind")?.extract()?;
    if kind != "i" && kind != "u" {
        return Err(bad(argument, format!("must be an integer array, not {}", dtype_name(&array)?)));
    }
    // uint64 values past int64 would wrap to negative indices in the cast below.
    if kind == "u" && array.getattr("size")?.extract::<usize>()? > 0 {
        let max = array.call_method0("max")?;
        if max.gt(i64::MAX)? {
            return Err(bad(argument, format!("has the value {max}, too large for an index")));
        }
    }
    let kwargs = pyo3::types::PyDict::new(py);
    kwargs.set_item("copy", false)?;
    array.call_method("astype", ("int64",), Some(&kwargs))
}

/// Faces: a (faces, 3) integer array; every index non-negative and below `u32::MAX`.
pub fn faces(argument: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<[u32; 3]>> {
    let array = int64_array(argument, obj)?;
    let a: PyReadonlyArray<'_, i64, Ix2> =
        array.extract().map_err(|_| bad(argument, "must have shape (faces, 3)"))?;
    let view: ArrayView2<'_, i64> = a.as_array();
    if view.shape()[1] != 3 {
        return Err(bad(argument, format!("must have shape (faces, 3), not {:?}", view.shape())));
    }
    view.outer_iter()
        .enumerate()
        .map(|(face, r)| {
            let mut f = [0u32; 3];
            for (slot, &v) in f.iter_mut().zip(r.iter()) {
                *slot = u32::try_from(v)
                    .map_err(|_| bad(argument, format!("face {face} has vertex index {v}")))?;
            }
            Ok(f)
        })
        .collect()
}

/// A 1-D array of non-negative integers (part ids, vertex indices); `allow_minus_one`
/// maps -1 to `None` (a simplified vertex that is no original one).
pub fn indices(argument: &str, obj: &Bound<'_, PyAny>, allow_minus_one: bool) -> PyResult<Vec<Option<u32>>> {
    let array = int64_array(argument, obj)?;
    let a: PyReadonlyArray1<'_, i64> =
        array.extract().map_err(|_| bad(argument, "must be one-dimensional"))?;
    a.as_array()
        .iter()
        .enumerate()
        .map(|(i, &v)| match u32::try_from(v) {
            Ok(v) => Ok(Some(v)),
            Err(_) if v == -1 && allow_minus_one => Ok(None),
            Err(_) => Err(bad(argument, format!("entry {i} is {v}, not an index"))),
        })
        .collect()
}

/// A 1-D array of non-negative integers.
pub fn ids(argument: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<u32>> {
    Ok(indices(argument, obj, false)?.into_iter().map(|v| v.expect("no -1 allowed")).collect())
}

/// A flat vector as an array of `shape`.
pub fn array<'py, T: numpy::Element, D: IntoDimension>(
    py: Python<'py>,
    flat: Vec<T>,
    shape: D,
) -> Bound<'py, PyArrayDyn<T>> {
    let shape = shape.into_dimension();
    Array::from_shape_vec(shape.into_dyn(), flat).expect("the shape matches the data").into_pyarray(py)
}

/// Rows of three as a (n, 3) array.
pub fn rows<'py, T: numpy::Element + Copy>(py: Python<'py>, rows: &[[T; 3]]) -> Bound<'py, PyArrayDyn<T>> {
    array(py, rows.iter().flatten().copied().collect(), [rows.len(), 3])
}

/// Faces as a (faces, 3) int64 array.
pub fn face_array<'py>(py: Python<'py>, faces: &[[u32; 3]]) -> Bound<'py, PyArrayDyn<i64>> {
    array(py, faces.iter().flatten().map(|&i| i64::from(i)).collect(), [faces.len(), 3])
}

/// Indices as a 1-D int64 array.
pub fn index_array<'py>(
    py: Python<'py>,
    values: impl IntoIterator<Item = u32>,
) -> Bound<'py, PyArrayDyn<i64>> {
    let v: Vec<i64> = values.into_iter().map(i64::from).collect();
    let n = v.len();
    array(py, v, [n])
}

/// A slice as a 1-D array.
pub fn vector<'py, T: numpy::Element + Copy>(py: Python<'py>, values: &[T]) -> Bound<'py, PyArrayDyn<T>> {
    array(py, values.to_vec(), [values.len()])
}

/// A serialisable value as Python objects (through JSON: dicts, lists, numbers).
pub fn to_python<'py, T: serde::Serialize>(py: Python<'py>, value: &T) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(|e| crate::errors::Error::new_err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}
