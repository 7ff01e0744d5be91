//! The pixel scope: which samples belong to one round of one pixel, on this thread.
//!
//! The camera pass traces a round of a pixel's samples in order on one thread
//! ([`super::aa::PixelSampler`]), and the time planner's pilot a set of a pixel's samples. Work
//! that those samples may share (the caustic estimate of
//! [`crate::integrator::photon_map::Prepass`], where two samples land within a fraction of its
//! radius) is kept only while a scope is open, and keyed by it: nothing is shared between
//! pixels, so the image does not depend on which pixel a thread rendered before (tiles stay
//! bit-identical to the full frame, the thread count changes nothing). Outside a scope (the
//! irradiance cache's probes, `--adaptive`'s corner rays) nothing is shared.
//!
//! The thread also notes whether a camera ray met a light before any surface
//! ([`light_seen`]): the pixels that see a light directly are left out of the error the
//! half-buffers estimate, as the planner's pilot and the error measures of `docs/` leave them
//! out (a light's edge is a step of a hundred times the image's brightness, and a few such
//! pixels would be most of the image's estimated error).

use std::cell::Cell;

thread_local! {
    /// The open scope's id (0: none), and the last id handed out on this thread.
    static OPEN: Cell<u64> = const { Cell::new(0) };
    static LAST: Cell<u64> = const { Cell::new(0) };
    /// Whether a camera ray met a light first since [`take_light_seen`] last ran.
    static LIGHT_SEEN: Cell<bool> = const { Cell::new(false) };
}

/// Notes that a camera ray met a light before any surface.
pub fn light_seen() {
    LIGHT_SEEN.set(true);
}

/// Returns whether a camera ray met a light first on this thread since the last call, and
/// clears the note.
pub fn take_light_seen() -> bool {
    LIGHT_SEEN.replace(false)
}

/// An open pixel scope; closing it (dropping it) ends what its samples share.
pub struct PixelScope(());

impl PixelScope {
    /// Opens a fresh scope on this thread (a scope open here is closed first).
    pub fn open() -> PixelScope {
        let id = LAST.get().wrapping_add(1).max(1);
        LAST.set(id);
        OPEN.set(id);
        PixelScope(())
    }
}

impl Drop for PixelScope {
    fn drop(&mut self) {
        OPEN.set(0);
    }
}

/// Returns the id of the scope open on this thread, unique on it among scopes, or `None`.
pub fn current() -> Option<u64> {
    Some(OPEN.get()).filter(|&id| id != 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scope is open only while its value lives, and each has an id of its own.
    #[test]
    fn scopes_are_fresh_and_close() {
        assert_eq!(current(), None);
        let a = {
            let _s = PixelScope::open();
            current().unwrap()
        };
        assert_eq!(current(), None);
        let _s = PixelScope::open();
        let b = current().unwrap();
        assert_ne!(a, b);
    }
}
