//! A Python callable as a stage `Progress`: `callback(step, done, total)` at the start of
//! each step, at every whole percent and at its end. Stages report from rayon workers with
//! the GIL released; each call takes the GIL for the callback only. An exception raised by
//! the callback is kept and raised once the call returns.

use std::sync::Mutex;

use desal_mesh::Progress;
use pyo3::prelude::*;

#[derive(Debug, Default)]
struct Step {
    label: String,
    total: u64,
    done: u64,
    reported: u64,
}

/// Calls `callback`; `None` reports nothing.
#[derive(Debug)]
pub struct PyProgress {
    callback: Option<Py<PyAny>>,
    step: Mutex<Step>,
    error: Mutex<Option<PyErr>>,
}

impl PyProgress {
    pub fn new(callback: Option<Py<PyAny>>) -> Self {
        PyProgress { callback, step: Mutex::default(), error: Mutex::default() }
    }

    fn call(&self, label: &str, done: u64, total: u64) {
        let Some(callback) = &self.callback else { return };
        let mut error = self.error.lock().expect("no panic holds it");
        if error.is_some() {
            return;
        }
        Python::attach(|py| {
            if let Err(e) = callback.call1(py, (label, done, total)) {
                *error = Some(e);
            }
        });
    }

    /// The callback's exception, if it raised one.
    pub fn into_result(self) -> PyResult<()> {
        match self.error.into_inner().expect("no panic holds it") {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

impl Progress for PyProgress {
    fn begin(&self, label: &str, total: u64) {
        if self.callback.is_none() {
            return;
        }
        *self.step.lock().expect("no panic holds it") =
            Step { label: label.to_owned(), total, done: 0, reported: 0 };
        self.call(label, 0, total);
    }

    fn advance(&self, n: u64) {
        if self.callback.is_none() {
            return;
        }
        let report = {
            let mut step = self.step.lock().expect("no panic holds it");
            step.done += n;
            let percent = |k: u64| k.saturating_mul(100) / step.total.max(1);
            if percent(step.done) > percent(step.reported) {
                step.reported = step.done;
                Some((step.label.clone(), step.done, step.total))
            } else {
                None
            }
        };
        if let Some((label, done, total)) = report {
            self.call(&label, done, total);
        }
    }

    fn finish(&self) {
        if self.callback.is_none() {
            return;
        }
        let (label, total) = {
            let step = self.step.lock().expect("no panic holds it");
            (step.label.clone(), step.total)
        };
        self.call(&label, total, total);
    }
}
