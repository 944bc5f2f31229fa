//! Where a run's progress goes. The driver reports through [`Console`]; the `desal`
//! binary implements it with terminal bars (`src/bars.rs`, indicatif), and [`Lines`] is
//! the plain one every other caller uses (the Python package, tests, benches): a log
//! line when a step begins and when it ends, or nothing when quiet.

use std::sync::Mutex;
use std::time::Instant;

use desal_mesh::Progress;

/// Where a run's progress and messages go, shared by all datasets of a run.
pub trait Console: Send + Sync + std::fmt::Debug {
    /// A progress sink for one dataset; its step labels are prefixed with `prefix`.
    fn for_dataset(&self, prefix: &str) -> Box<dyn Progress + Send + '_>;
    /// Prints a message line (a cache miss explained, say) without tearing any bars.
    fn println(&self, line: &str);
}

/// Plain log lines on standard error: `dataset: step ...` and `dataset: step done in
/// 0.123 s`; when `quiet`, only the messages of [`Console::println`].
#[derive(Debug, Clone, Copy, Default)]
pub struct Lines {
    pub quiet: bool,
}

impl Console for Lines {
    fn for_dataset(&self, prefix: &str) -> Box<dyn Progress + Send + '_> {
        Box::new(StepLines { quiet: self.quiet, prefix: prefix.to_owned(), current: Mutex::new(None) })
    }

    fn println(&self, line: &str) {
        eprintln!("{line}");
    }
}

/// [`Lines`]' progress sink for one dataset.
#[derive(Debug)]
struct StepLines {
    quiet: bool,
    prefix: String,
    current: Mutex<Option<(String, Instant)>>,
}

impl Progress for StepLines {
    fn begin(&self, label: &str, _total: u64) {
        let label = format!("{}: {label}", self.prefix);
        if !self.quiet {
            eprintln!("{label} ...");
        }
        *self.current.lock().expect("progress lock") = Some((label, Instant::now()));
    }

    fn advance(&self, _n: u64) {}

    fn finish(&self) {
        if let Some((label, start)) = self.current.lock().expect("progress lock").take()
            && !self.quiet
        {
            eprintln!("{label} done in {:.3} s", start.elapsed().as_secs_f64());
        }
    }
}
