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
        let mut error = lock(&self.error);
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
        match self.error.into_inner().unwrap_or_else(|poisoned| poisoned.into_inner()) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

/// The lock's value even when a panic poisoned it: the entry point's guard turns that
/// panic into `desal.Error`, and the progress state it leaves is still usable.
fn lock<T>(mutex: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    mutex.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

impl Progress for PyProgress {
    fn begin(&self, label: &str, total: u64) {
        if self.callback.is_none() {
            return;
        }
        *lock(&self.step) = Step { label: label.to_owned(), total, done: 0, reported: 0 };
        self.call(label, 0, total);
    }

    fn advance(&self, n: u64) {
        if self.callback.is_none() {
            return;
        }
        let report = {
            let mut step = lock(&self.step);
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
            let step = lock(&self.step);
            (step.label.clone(), step.total)
        };
        self.call(&label, total, total);
    }
}
