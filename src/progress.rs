//! How a long phase reports what it has done: the [`Progress`] trait the library's passes call
//! and the command line's bar implements. It imports only the film, a leaf.

/// How a long phase tells a progress display what it has done; calls may come from any thread.
pub trait Progress: Sync {
    /// A phase called `what` starts, with `total` units of work.
    fn start(&self, what: &str, total: u64);
    /// `n` more units of the current phase are done.
    fn advance(&self, n: u64);
    /// A progressive render has run `passes` passes, and `image` is their mean (every
    /// `--write-every` passes). Does nothing unless implemented.
    fn snapshot(&self, passes: u32, image: &crate::film::Film) {
        let _ = (passes, image);
    }
    /// Returns true when the phases should stop early and keep what they have (the command
    /// line's Ctrl-C, [`crate::interrupt`]); long loops ask once per row, chunk of photons or
    /// pass, never per ray. False unless implemented.
    fn should_stop(&self) -> bool {
        false
    }
}

/// A [`Progress`] that shows nothing but stops when `0` asks to: the inner phases of a
/// progressive pass, whose progress is counted in passes.
pub struct StopOnly<'a>(pub &'a dyn Progress);

impl Progress for StopOnly<'_> {
    fn start(&self, _: &str, _: u64) {}
    fn advance(&self, _: u64) {}
    fn should_stop(&self) -> bool {
        self.0.should_stop()
    }
}

/// A [`Progress`] that shows nothing.
pub struct NoProgress;

impl Progress for NoProgress {
    fn start(&self, _: &str, _: u64) {}
    fn advance(&self, _: u64) {}
}
