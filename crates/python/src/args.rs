//! Arguments as the user gave them. Every bad argument is an `InputError` in the user's
//! own words: the argument or option as the caller spells it and the value as Python
//! writes it (`ratio='x' must be a number`), never a PyO3 `OverflowError`/`TypeError`
//! or serde_json's position in JSON the user never wrote.
//!
//! Stage options reach Rust as the JSON of a pipeline file's table (the Python layer
//! builds it from keyword arguments and `*_options` dicts, refusing NaN, infinities and
//! integers past 64 bits by name), and are parsed into the stage's own `Params`, so the
//! names, defaults and range checks are the pipeline file's.

use pyo3::prelude::*;
use pyo3::types::{PyBool, PyString};
use serde::de::DeserializeOwned;
use serde_json::Value;

use crate::convert::bad;
use crate::errors::InputError;

/// The stage table `what` (e.g. `"simplify"`) from its JSON (`None`: all defaults).
pub fn table<T: DeserializeOwned>(what: &str, json: Option<&str>) -> PyResult<T> {
    table_as(what, json, &[])
}

/// [`table`], where the caller spells some keys differently: `(key, caller's name)`
/// pairs, e.g. the fit table's `method` is `simplify_pose_set`'s `fit_method`.
pub fn table_as<T: DeserializeOwned>(what: &str, json: Option<&str>, names: &[(&str, &str)]) -> PyResult<T> {
    // The text is JSON the Python layer wrote, or (`PoseSet(parts=...)`) the caller's
    // own; only then does a position in it mean something to them.
    let value: Value = serde_json::from_str(json.unwrap_or("{}"))
        .map_err(|e| bad(what, format!("the options are not valid JSON: {e}")))?;
    serde_json::from_value::<T>(value.clone()).map_err(|e| {
        let reason = e.to_string();
        let name = |key: &str| names.iter().find(|(k, _)| *k == key).map_or(key, |(_, n)| *n).to_owned();
        match culprit::<T>(&value, &reason) {
            Some((key, v)) => bad(what, option_error(&name(key), v, &reason)),
            None => bad(what, reason),
        }
    })
}

/// The key of `table` that `reason` (its deserialisation error) is about: the first one
/// whose removal changes the error. serde reports no path, and the error's position is
/// in JSON the user did not write. A missing required key has no culprit.
fn culprit<'a, T: DeserializeOwned>(table: &'a Value, reason: &str) -> Option<(&'a str, &'a Value)> {
    let object = table.as_object()?;
    if reason.starts_with("missing field") {
        return None;
    }
    object.iter().map(|(k, v)| (k.as_str(), v)).find(|(key, _)| {
        let mut without = object.clone();
        without.remove(*key);
        serde_json::from_value::<T>(Value::Object(without)).err().is_none_or(|e| e.to_string() != reason)
    })
}

/// serde's message about option `name` = `value`, in Python's words: `ratio='x' must be
/// a number`, `fit_method='x': fit method 'x' is unknown: use "rigid" or "affine"`.
fn option_error(name: &str, value: &Value, reason: &str) -> String {
    let shown = format!("{name}={}", python_literal(value));
    if let Some(rest) = reason.strip_prefix("unknown field ") {
        let known = rest.split_once(", expected ").map_or("", |(_, k)| k);
        return format!("unknown option {shown}; expected {known}");
    }
    let expected = ["invalid type: ", "invalid value: "]
        .iter()
        .find_map(|p| reason.strip_prefix(p))
        .and_then(|rest| rest.rsplit_once(", expected "))
        .map(|(_, expected)| expected);
    match expected {
        Some(expected) => format!("{shown} must be {}", expected_words(expected)),
        None => format!("{shown}: {reason}"),
    }
}

/// serde's name for the type it wanted, as a Python caller would say it.
fn expected_words(expected: &str) -> String {
    match expected {
        "usize" | "u64" => "a non-negative integer".into(),
        "u32" => "a non-negative integer below 2**32".into(),
        "u16" => "a non-negative integer below 65536".into(),
        "u8" => "a non-negative integer below 256".into(),
        "i64" | "i32" | "isize" => "an integer".into(),
        "f64" | "f32" => "a number".into(),
        "a boolean" => "True or False".into(),
        "a sequence" => "a list".into(),
        "a map" => "a dict".into(),
        other => other.into(),
    }
}

/// A JSON value as Python writes it (`None`, `True`, `'text'`, `[1, 2]`).
pub fn python_literal(value: &Value) -> String {
    match value {
        Value::Null => "None".into(),
        Value::Bool(true) => "True".into(),
        Value::Bool(false) => "False".into(),
        Value::Number(n) => n.to_string(),
        Value::String(s) => python_str(s),
        Value::Array(items) => {
            format!("[{}]", items.iter().map(python_literal).collect::<Vec<_>>().join(", "))
        }
        Value::Object(map) => {
            let items: Vec<String> =
                map.iter().map(|(k, v)| format!("{}: {}", python_str(k), python_literal(v))).collect();
            format!("{{{}}}", items.join(", "))
        }
    }
}

fn python_str(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('\'');
    for c in s.chars() {
        match c {
            '\\' => out.push_str("\\\\"),
            '\'' => out.push_str("\\'"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => out.push_str(&format!("\\x{:02x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('\'');
    out
}

/// `repr(obj)`, for messages (a value whose `repr` fails is `<unprintable>`).
pub fn repr(obj: &Bound<'_, PyAny>) -> String {
    obj.repr().map_or_else(|_| "<unprintable>".into(), |r| r.to_string())
}

/// A non-negative integer argument (a count or an index): any Python or NumPy integer
/// except `bool`; negative, too large and non-integer values are refused by name.
pub fn index(argument: &str, obj: &Bound<'_, PyAny>) -> PyResult<usize> {
    let refuse = |what: &str| InputError::new_err(format!("{argument}={} {what}", repr(obj)));
    if obj.is_instance_of::<PyBool>() {
        return Err(refuse("must be a non-negative integer, not a bool"));
    }
    let as_int = obj
        .py()
        .import("operator")?
        .call_method1("index", (obj,))
        .map_err(|_| refuse("must be a non-negative integer"))?;
    if as_int.lt(0)? {
        return Err(refuse("must be a non-negative integer"));
    }
    as_int.extract::<usize>().map_err(|_| refuse("is too large"))
}

/// A list of strings (`names=`, `part_names=`): a sequence of `str`, not one `str`.
pub fn strings(argument: &str, obj: &Bound<'_, PyAny>) -> PyResult<Vec<String>> {
    if obj.is_instance_of::<PyString>() {
        return Err(bad(argument, format!("must be a list of str, not the str {}", repr(obj))));
    }
    let items =
        obj.try_iter().map_err(|_| bad(argument, format!("must be a list of str, not {}", repr(obj))))?;
    items
        .enumerate()
        .map(|(k, item)| {
            let item = item?;
            item.extract::<String>()
                .map_err(|_| InputError::new_err(format!("{argument}[{k}]={} must be a str", repr(&item))))
        })
        .collect()
}

/// A path argument: `str` or `os.PathLike`.
pub fn path(argument: &str, obj: &Bound<'_, PyAny>) -> PyResult<std::path::PathBuf> {
    obj.extract().map_err(|_| {
        InputError::new_err(format!("{argument}={} must be a path (str or os.PathLike)", repr(obj)))
    })
}

/// `obj` as the pyclass `T` (a `PoseSet`, a `Fit`), else an `InputError` naming the
/// argument and what it got.
pub fn instance<'a, 'py, T: pyo3::PyTypeInfo>(
    argument: &str,
    obj: &'a Bound<'py, PyAny>,
) -> PyResult<&'a Bound<'py, T>> {
    obj.cast::<T>().map_err(|_| {
        let name =
            |t: Bound<'_, pyo3::types::PyType>| t.name().map_or_else(|_| "?".into(), |n| n.to_string());
        let wanted = name(T::type_object(obj.py()));
        bad(argument, format!("must be a desal.{wanted}, not {}", name(obj.get_type())))
    })
}

/// A progress callback: `None` or a callable.
pub fn progress(obj: Option<Py<PyAny>>, py: Python<'_>) -> PyResult<Option<Py<PyAny>>> {
    match obj {
        Some(cb) if cb.is_none(py) => Ok(None),
        Some(cb) if !cb.bind(py).is_callable() => Err(InputError::new_err(format!(
            "progress={} must be callable as progress(step, done, total)",
            repr(cb.bind(py))
        ))),
        other => Ok(other),
    }
}
