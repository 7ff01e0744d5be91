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
//! Only Linux catches the signal; elsewhere SIGINT ends the process. The handler (`cleanup`)
//! also removes the temporary files [`crate::files`] registers with it.

use std::sync::atomic::{AtomicBool, Ordering};

/// Whether the first SIGINT is a request to stop rather than the end of the process.
static CATCHING: AtomicBool = AtomicBool::new(false);

/// Whether a stop has been requested.
static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Makes the first SIGINT a request to stop, read by [`requested`], rather than the end of the
/// process; a second SIGINT still ends it. Does nothing where signals are not caught.
pub fn catch_sigint() {
    CATCHING.store(true, Ordering::SeqCst);
    cleanup::install_once();
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

/// The one SIGINT and SIGTERM handler: it records a first SIGINT as [`absorb`] asks, or else
/// removes the temporary files [`crate::files`] is writing and re-raises; all of it
/// async-signal-safe, with libc's `sigaction` (already a dependency on Linux). It lives here,
/// below `files`, so that the two leaves do not import each other.
#[cfg(target_os = "linux")]
pub(crate) mod cleanup {
    use std::ffi::CString;
    use std::os::unix::ffi::OsStrExt;
    use std::path::Path;
    use std::sync::Once;
    use std::sync::atomic::{AtomicPtr, Ordering};

    /// Temporary files being written at once (more are written, just not cleaned up).
    const SLOTS: usize = 16;
    /// The paths of the temporary files being written, as C strings; null when free. A path
    /// is never freed once published, so the handler can read it at any moment.
    static PENDING: [AtomicPtr<libc::c_char>; SLOTS] =
        [const { AtomicPtr::new(std::ptr::null_mut()) }; SLOTS];

    /// Unregisters its temporary file when dropped.
    pub struct Guard(Option<usize>);

    impl Drop for Guard {
        fn drop(&mut self) {
            if let Some(slot) = self.0 {
                PENDING[slot].store(std::ptr::null_mut(), Ordering::SeqCst);
            }
        }
    }

    /// Installs the signal handlers, once.
    pub fn install_once() {
        static INSTALL: Once = Once::new();
        INSTALL.call_once(install);
    }

    /// Registers `tmp` for removal on SIGINT and SIGTERM until the guard is dropped.
    pub fn register(tmp: &Path) -> Guard {
        install_once();
        let Ok(c) = CString::new(tmp.as_os_str().as_bytes()) else {
            return Guard(None);
        };
        // Leaked on purpose (a few bytes per image written): see PENDING.
        let ptr = c.into_raw();
        for (k, slot) in PENDING.iter().enumerate() {
            let free = std::ptr::null_mut();
            if slot
                .compare_exchange(free, ptr, Ordering::SeqCst, Ordering::SeqCst)
                .is_ok()
            {
                return Guard(Some(k));
            }
        }
        Guard(None)
    }

    extern "C" fn on_signal(sig: libc::c_int) {
        if super::absorb(sig) {
            return;
        }
        for slot in &PENDING {
            let p = slot.load(Ordering::SeqCst);
            if !p.is_null() {
                // SAFETY: p is a NUL-terminated path that is never freed; unlink is
                // async-signal-safe.
                unsafe { libc::unlink(p) };
            }
        }
        // SAFETY: restoring the default action and re-raising are async-signal-safe; the
        // process then ends as the signal would have ended it.
        unsafe {
            libc::signal(sig, libc::SIG_DFL);
            libc::raise(sig);
        }
    }

    fn install() {
        for sig in [libc::SIGINT, libc::SIGTERM] {
            // SAFETY: a zeroed sigaction with a handler and an empty mask is valid; the
            // handler only does async-signal-safe work. SA_RESTART: a SIGINT the handler
            // absorbs must not fail a read or write in progress with EINTR.
            unsafe {
                let mut action: libc::sigaction = std::mem::zeroed();
                action.sa_sigaction = on_signal as extern "C" fn(libc::c_int) as usize;
                action.sa_flags = libc::SA_RESTART;
                libc::sigemptyset(&mut action.sa_mask);
                libc::sigaction(sig, &action, std::ptr::null_mut());
            }
        }
    }
}

/// Elsewhere no signal handler is installed; temporary files are still removed on errors.
#[cfg(not(target_os = "linux"))]
pub(crate) mod cleanup {
    use std::path::Path;

    /// Stands for the Linux guard.
    pub struct Guard;

    /// Does nothing: no signal cleanup on this platform.
    pub fn register(_tmp: &Path) -> Guard {
        Guard
    }

    /// Does nothing: no signal handlers on this platform.
    pub fn install_once() {}
}
