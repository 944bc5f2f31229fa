//! Progress bars for the binaries: an `indicatif` implementation of the libraries'
//! `Progress` trait, or plain log lines when stderr is not a terminal (CI logs, pipes).

use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::Instant;

use desal_mesh::Progress;
use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};

/// How progress is shown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ProgressMode {
    /// Bars on a terminal, log lines otherwise.
    Auto,
    /// Nothing.
    Quiet,
}

/// Shared by all datasets of a run: one bar per running step.
#[derive(Debug, Clone)]
pub struct Bars {
    multi: Option<MultiProgress>,
    plain: bool,
}

impl Bars {
    pub fn new(mode: ProgressMode) -> Self {
        match mode {
            ProgressMode::Quiet => Bars { multi: None, plain: false },
            ProgressMode::Auto if std::io::stderr().is_terminal() => Bars {
                multi: Some(MultiProgress::with_draw_target(ProgressDrawTarget::stderr())),
                plain: false,
            },
            ProgressMode::Auto => Bars { multi: None, plain: true },
        }
    }

    /// A progress sink for one dataset; labels are prefixed with `prefix`.
    pub fn for_dataset(&self, prefix: &str) -> StepProgress {
        StepProgress { bars: self.clone(), prefix: prefix.to_owned(), current: Mutex::new(None) }
    }

    /// Prints a line without tearing the bars.
    pub fn println(&self, line: &str) {
        match &self.multi {
            Some(m) => {
                let _ = m.println(line);
            }
            None => eprintln!("{line}"),
        }
    }
}

/// `Progress` for one dataset.
#[derive(Debug)]
pub struct StepProgress {
    bars: Bars,
    prefix: String,
    current: Mutex<Option<(ProgressBar, String, Instant)>>,
}

impl Progress for StepProgress {
    fn begin(&self, label: &str, total: u64) {
        let label = format!("{}: {label}", self.prefix);
        let bar = match &self.bars.multi {
            Some(m) => {
                let bar = m.add(ProgressBar::new(total));
                bar.set_style(
                    ProgressStyle::with_template("{prefix:>28} [{bar:30}] {pos}/{len} {elapsed}")
                        .expect("valid template")
                        .progress_chars("=> "),
                );
                bar.set_prefix(label.clone());
                bar
            }
            None => ProgressBar::hidden(),
        };
        if self.bars.plain {
            eprintln!("{label} ...");
        }
        *self.current.lock().expect("progress lock") = Some((bar, label, Instant::now()));
    }

    fn advance(&self, n: u64) {
        if let Some((bar, _, _)) = &*self.current.lock().expect("progress lock") {
            bar.inc(n);
        }
    }

    fn finish(&self) {
        if let Some((bar, label, start)) = self.current.lock().expect("progress lock").take() {
            bar.finish_and_clear();
            if let Some(m) = &self.bars.multi {
                m.remove(&bar);
            }
            if self.bars.plain {
                eprintln!("{label} done in {:.3} s", start.elapsed().as_secs_f64());
            }
        }
    }
}
