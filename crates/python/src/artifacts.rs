//! Artifacts and hierarchy arrays as Python values. An artifact body becomes a dict
//! through its serde form: every rectangular array of numbers becomes a NumPy array
//! (int64 when all its numbers are integers, `None` entries as -1; float64 otherwise),
//! everything else plain Python values. The file is read by desal's own hardened
//! reader, so a truncated, foreign or forged file is an `InputError` naming it.

use std::path::Path;

use desal_io::artifact::{
    ArtifactBody, ArtifactKind, FitV1, FloorV1, HierarchyLevelV1, LabelsV1, MapV1, PoseSetV2, SaliencyV1,
    SimplifiedV1, read_artifact, read_producer,
};
use desal_io::npz::{HierarchyArrays, NamedArray, NpyArray, NpyData};
use numpy::PyReadonlyArrayDyn;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use serde_json::Value;

use crate::convert;
use crate::errors::{self, InputError};

/// `desal.load`: the artifact at `path` as a dict.
pub fn load<'py>(py: Python<'py>, path: &Path) -> PyResult<Bound<'py, PyDict>> {
    let (header, _) = read_producer(path).map_err(|e| errors::input(e.into()))?;
    let (producer, body) = py.detach(|| match header.kind {
        ArtifactKind::PoseSet => body::<PoseSetV2>(path),
        ArtifactKind::Labels => body::<LabelsV1>(path),
        ArtifactKind::Fit => body::<FitV1>(path),
        ArtifactKind::Saliency => body::<SaliencyV1>(path),
        ArtifactKind::Simplified => body::<SimplifiedV1>(path),
        ArtifactKind::Map => body::<MapV1>(path),
        ArtifactKind::HierarchyLevel => body::<HierarchyLevelV1>(path),
        ArtifactKind::Floor => body::<FloorV1>(path),
    })?;
    let out = value(py, &body)?.cast_into::<PyDict>()?;
    out.set_item("kind", header.kind.name())?;
    out.set_item("version", header.version)?;
    out.set_item("producer", value(py, &producer)?)?;
    Ok(out)
}

fn body<T: ArtifactBody>(path: &Path) -> PyResult<(Value, Value)> {
    let (producer, body, _) = read_artifact::<T>(path).map_err(|e| errors::input(e.into()))?;
    let as_value = |v: serde_json::Result<Value>| v.map_err(|e| crate::errors::Error::new_err(e.to_string()));
    Ok((as_value(serde_json::to_value(&producer))?, as_value(serde_json::to_value(&body))?))
}

/// A JSON value as Python: numeric arrays as NumPy arrays.
fn value<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Number(n) => match (n.as_i64(), n.as_u64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (None, Some(u)) => u.into_pyobject(py)?.into_any(),
            _ => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Array(items) => match numeric(v) {
            Some(Numeric { shape, values, integer: true }) => {
                convert::array(py, values.iter().map(|x| x.map_or(-1, |x| x as i64)).collect(), shape)
                    .into_any()
            }
            Some(Numeric { shape, values, integer: false }) => {
                convert::array(py, values.iter().map(|x| x.unwrap_or(f64::NAN)).collect(), shape).into_any()
            }
            None => {
                let list = PyList::empty(py);
                for item in items {
                    list.append(value(py, item)?)?;
                }
                list.into_any()
            }
        },
        Value::Object(map) => {
            let dict = PyDict::new(py);
            for (k, item) in map {
                dict.set_item(k, value(py, item)?)?;
            }
            dict.into_any()
        }
    })
}

struct Numeric {
    shape: Vec<usize>,
    values: Vec<Option<f64>>,
    integer: bool,
}

/// A rectangular, non-empty array of numbers (and nulls) in row-major order.
fn numeric(v: &Value) -> Option<Numeric> {
    fn walk(v: &Value, depth: usize, shape: &mut Vec<usize>, out: &mut Numeric) -> bool {
        match v {
            Value::Array(items) => {
                if shape.len() == depth {
                    shape.push(items.len());
                } else if shape[depth] != items.len() {
                    return false;
                }
                !items.is_empty() && items.iter().all(|i| walk(i, depth + 1, shape, out))
            }
            _ if shape.len() != depth => false,
            Value::Number(n) => {
                out.integer &= n.is_i64() || n.is_u64();
                out.values.push(n.as_f64());
                true
            }
            Value::Null => {
                out.values.push(None);
                true
            }
            _ => false,
        }
    }
    let mut out = Numeric { shape: Vec::new(), values: Vec::new(), integer: true };
    let mut shape = Vec::new();
    if !walk(v, 0, &mut shape, &mut out) {
        return None;
    }
    // Nulls are -1 in an integer array; in a float array (NaN serialised) they are NaN.
    out.shape = shape;
    Some(out)
}

/// A hierarchy's npz arrays as a dict, in the file's key order.
pub fn hierarchy_dict<'py>(py: Python<'py>, h: &HierarchyArrays) -> PyResult<Bound<'py, PyDict>> {
    let arrays = h.to_arrays().map_err(InputError::new_err)?;
    let dict = PyDict::new(py);
    for (name, a) in arrays {
        let shape = a.shape.clone();
        match a.data {
            NpyData::I32(v) => dict.set_item(name, convert::array(py, v, shape))?,
            NpyData::I64(v) => dict.set_item(name, convert::array(py, v, shape))?,
            NpyData::F64(v) => dict.set_item(name, convert::array(py, v, shape))?,
        }
    }
    Ok(dict)
}

/// The inverse of [`hierarchy_dict`]: every array by its dtype (int32, int64 or float64),
/// the layout checked by the npz reader's own rules.
pub fn hierarchy_from_dict(dict: &Bound<'_, PyDict>) -> PyResult<HierarchyArrays> {
    let py = dict.py();
    let np = py.import("numpy")?;
    let mut arrays: Vec<NamedArray> = Vec::new();
    for (key, item) in dict.iter() {
        let name: String = key.extract()?;
        let a = np.call_method1("ascontiguousarray", (item,))?;
        let dtype = a.getattr("dtype")?.str()?.to_string();
        let data = match dtype.as_str() {
            "int32" => NpyData::I32(contiguous::<i32>(&a)?),
            "int64" => NpyData::I64(contiguous::<i64>(&a)?),
            "float64" => NpyData::F64(contiguous::<f64>(&a)?),
            other => {
                return Err(InputError::new_err(format!(
                    "{name}: dtype {other} is not int32, int64 or float64"
                )));
            }
        };
        let shape = a.getattr("shape")?.extract::<Vec<usize>>()?;
        arrays.push((name, NpyArray { shape, data }));
    }
    HierarchyArrays::from_arrays(&arrays).map_err(InputError::new_err)
}

fn contiguous<T: numpy::Element + Copy>(a: &Bound<'_, PyAny>) -> PyResult<Vec<T>> {
    let view: PyReadonlyArrayDyn<'_, T> = a.extract()?;
    Ok(view.as_array().iter().copied().collect())
}
