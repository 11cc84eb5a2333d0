//! Progress reporting for long operations, without tying the library to a terminal.

/// Receives the fraction of work done, in `[0, 1]`. Calls are cheap to ignore; the library
/// calls it at most a few hundred times per operation.
pub trait Progress: Sync {
    /// Reports that `fraction` of the work is done.
    fn update(&self, fraction: f64);
}

impl<F: Fn(f64) + Sync> Progress for F {
    fn update(&self, fraction: f64) {
        self(fraction)
    }
}

/// A [`Progress`] that ignores every update.
pub struct NoProgress;

impl Progress for NoProgress {
    fn update(&self, _fraction: f64) {}
}
