//! Progress reporting from library code without a terminal dependency: stages call a
//! `Progress`; binaries implement it with progress bars, tests with `NoProgress`.

/// Receives progress of one long step. Implementations must be cheap and thread-safe:
/// stages call `advance` from rayon workers.
pub trait Progress: Sync {
    /// A step named `label` with `total` units of work begins.
    fn begin(&self, label: &str, total: u64);
    /// `n` more units are done.
    fn advance(&self, n: u64);
    /// The step is over.
    fn finish(&self);
}

/// Ignores all progress.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn begin(&self, _label: &str, _total: u64) {}
    fn advance(&self, _n: u64) {}
    fn finish(&self) {}
}
