//! Stopping a render early on Ctrl-C: the first SIGINT asks the render to stop and keep what it
//! has; a second one ends the process at once. A leaf: the command line turns it on, and its
//! progress display ([`crate::progress::Progress::should_stop`]) reports it to the passes, which
//! know nothing of signals.
//!
//! # What an interrupted render writes, and why
//! What the renderers we learn from do: in Mitsuba 3 (its `render` installs the handler), a
//! Ctrl-C cancels the integrator, whose block loop stops where it is while the film develops
//! the blocks it finished, and restores the previous handler, so a second Ctrl-C ends the
//! process; pbrt-v4 catches no signal but can write the image after every wave of samples
//! (`--write-partial-images`), recording the samples per pixel in the file's metadata; Blender,
//! interactively, keeps a cancelled render's finished tiles in its Render Result for the user to
//! save. caustic stops as Mitsuba 3 does, and marks what it writes as pbrt-v4 does:
//!
//! - the camera pass, photon tracing and irradiance precomputation check the request once per
//!   row, chunk of photons or point (never per ray) and skip what is left; a progressive render
//!   stops between passes, dropping the pass it was in;
//! - the command line writes what was rendered beside the output as `NAME.partial.EXT`, never
//!   at the output's own name: a render farm that takes an existing `tile7.png` as done must not
//!   mistake a half image for it. Inside the file a PNG has a `tEXt` chunk and an EXR a header
//!   attribute, both `caustic-partial`, saying what is in it (rows not rendered are black; a
//!   progressive image is the mean of the passes it finished); PFM and HDR have only the name.
//!   `caustic stitch` refuses a tile so marked;
//! - it says on stderr what it wrote (`interrupted: wrote 37% of rows (37 of 100) to
//!   out.partial.png`), or that nothing was rendered yet, and exits with status 130 (128 +
//!   SIGINT, as a shell reports a process Ctrl-C ended). A running script stops too (within a
//!   thousand Lua instructions): later `gr.render` calls do not run;
//! - a second SIGINT ends the process as the signal does, after removing any temporary file
//!   being written ([`crate::files`]), so no half-written file is ever left at any name;
//! - `--no-partial` keeps the old behaviour: the first SIGINT ends the process, nothing is
//!   written. SIGTERM always ends the process at once.
//!
//! Only Linux catches the signal (as [`crate::files`] does); elsewhere SIGINT ends the process.

use std::sync::atomic::{AtomicBool, Ordering};

/// Whether the first SIGINT is a request to stop rather than the end of the process.
static CATCHING: AtomicBool = AtomicBool::new(false);

/// Whether a stop has been requested.
static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Makes the first SIGINT a request to stop, read by [`requested`], rather than the end of the
/// process; a second SIGINT still ends it. Does nothing where signals are not caught.
pub fn catch_sigint() {
    CATCHING.store(true, Ordering::SeqCst);
    crate::files::install_signal_handlers();
}

/// Returns true once the first SIGINT has arrived (after [`catch_sigint`]).
pub fn requested() -> bool {
    REQUESTED.load(Ordering::Relaxed)
}

/// Returns true when the signal `sig` is the first SIGINT while catching it, recording the
/// request; the signal handler then returns instead of ending the process. Async-signal-safe
/// (atomics only).
#[cfg(target_os = "linux")]
pub(crate) fn absorb(sig: libc::c_int) -> bool {
    sig == libc::SIGINT
        && CATCHING.load(Ordering::SeqCst)
        && !REQUESTED.swap(true, Ordering::SeqCst)
}
