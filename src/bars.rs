//! The `desal` binary's progress: bars on a terminal (indicatif), the driver's plain log
//! lines otherwise (CI logs, pipes), nothing with `--quiet`.

use std::io::IsTerminal;
use std::sync::{Arc, Mutex};

use desal_driver::progress::{Console, Lines};
use desal_mesh::Progress;
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};

/// The console of a command: `quiet` → nothing but messages; a terminal → bars; else
/// log lines.
pub fn console(quiet: bool) -> Arc<dyn Console> {
    if quiet {
        Arc::new(Lines { quiet: true })
    } else if std::io::stderr().is_terminal() {
        Arc::new(Bars { multi: MultiProgress::with_draw_target(ProgressDrawTarget::stderr()) })
    } else {
        Arc::new(Lines { quiet: false })
    }
}

/// Bars on a terminal, one per running step.
#[derive(Debug)]
struct Bars {
    multi: MultiProgress,
}

impl Console for Bars {
    fn for_dataset(&self, prefix: &str) -> Box<dyn Progress + Send + '_> {
        Box::new(StepBar { multi: &self.multi, prefix: prefix.to_owned(), current: Mutex::new(None) })
    }

    fn println(&self, line: &str) {
        let _ = self.multi.println(line);
    }
}

/// One dataset's bar.
#[derive(Debug)]
struct StepBar<'a> {
    multi: &'a MultiProgress,
    prefix: String,
    current: Mutex<Option<ProgressBar>>,
}

impl Progress for StepBar<'_> {
    fn begin(&self, label: &str, total: u64) {
        let bar = self.multi.add(ProgressBar::new(total));
        bar.set_style(
            ProgressStyle::with_template("{prefix:>28} [{bar:30}] {pos}/{len} {elapsed}")
                .expect("valid template")
                .progress_chars("=> "),
        );
        bar.set_prefix(format!("{}: {label}", self.prefix));
        *self.current.lock().expect("progress lock") = Some(bar);
    }

    fn advance(&self, n: u64) {
        if let Some(bar) = &*self.current.lock().expect("progress lock") {
            bar.inc(n);
        }
    }

    fn finish(&self) {
        if let Some(bar) = self.current.lock().expect("progress lock").take() {
            bar.finish_and_clear();
            self.multi.remove(&bar);
        }
    }
}
