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
}

/// A [`Progress`] that shows nothing.
pub struct NoProgress;

impl Progress for NoProgress {
    fn start(&self, _: &str, _: u64) {}
    fn advance(&self, _: u64) {}
}
