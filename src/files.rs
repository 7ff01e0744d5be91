//! Files in and out, safely: inputs must be regular files, and outputs are replaced atomically.
//! A leaf: every floor that reads or writes a file may import it.
//!
//! - **Inputs** ([`read_regular`], [`check_regular`]): a device, FIFO or socket named as a
//!   script, mesh, material library, buffer, texture or tile is refused before it is opened
//!   (reading `/dev/zero` never ends; opening a FIFO blocks until someone writes to it).
//! - **Outputs** ([`write_replacing`]; [`write_bytes`] and [`write_replacing_io`] wrap it), for
//!   images, exported meshes (OBJ, glTF, GLB) and Mitsuba scenes alike: the data goes to a temporary file beside the target,
//!   which is renamed over it, so an interrupted write never leaves a truncated file where a good
//!   one was. A symlink is followed (the file it names is replaced, the link kept); an existing
//!   file keeps its permissions; a special file (`/dev/null`, a FIFO) is refused, never replaced.
//!   On SIGINT or SIGTERM the temporary files being written are removed before the process
//!   ends as the signal would end it (except a first SIGINT that [`crate::interrupt`] turns
//!   into a request to stop).

use std::io;
use std::path::{Path, PathBuf};

/// What messages about a special file add.
const REGULAR_ONLY: &str = "caustic reads and writes regular files only";

/// Returns an error unless `path` names a regular file (following symlinks).
pub fn check_regular(path: &Path) -> io::Result<()> {
    let meta = std::fs::metadata(path)?;
    if meta.is_file() {
        return Ok(());
    }
    Err(io::Error::new(
        io::ErrorKind::InvalidInput,
        format!("{} ({REGULAR_ONLY})", kind(&meta)),
    ))
}

/// Returns the bytes of the regular file `path` ([`check_regular`]).
pub fn read_regular(path: &Path) -> io::Result<Vec<u8>> {
    check_regular(path)?;
    std::fs::read(path)
}

/// Returns what kind of non-regular file `meta` describes, for messages.
fn kind(meta: &std::fs::Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_char_device() || t.is_block_device() {
            return "is a device";
        }
        if t.is_fifo() {
            return "is a FIFO";
        }
        if t.is_socket() {
            return "is a socket";
        }
    }
    if meta.is_dir() {
        "is a folder"
    } else {
        "is not a regular file"
    }
}

/// Returns the file a write to `path` must replace: `path` itself, or the file its chain of
/// symlinks ends at (which need not exist yet).
fn write_target(path: &Path) -> io::Result<PathBuf> {
    let mut target = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&target) {
            Ok(m) if m.file_type().is_symlink() => {
                let link = std::fs::read_link(&target)?;
                target = match target.parent() {
                    Some(dir) => dir.join(link),
                    None => link,
                };
            }
            _ => return Ok(target),
        }
    }
    Err(io::Error::other("too many levels of symbolic links"))
}

/// Returns the file a write to `path` replaces (its symlinks followed) and, when that file
/// exists, its permissions; an error when it is a special file (a device, FIFO or socket) or a
/// folder. Callers check outputs with it before spending a render on them.
pub fn check_output(path: &Path) -> Result<(PathBuf, Option<std::fs::Permissions>), String> {
    let target = write_target(path).map_err(|e| e.to_string())?;
    match std::fs::metadata(&target) {
        Ok(meta) if !meta.is_file() => Err(format!("{} ({REGULAR_ONLY})", kind(&meta))),
        Ok(meta) => Ok((target, Some(meta.permissions()))),
        Err(_) => Ok((target, None)),
    }
}

/// Writes a file at `path` through `write` (given the temporary path to create), then renames
/// it over the target: see the module doc for symlinks, permissions and special files.
pub fn write_replacing(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), String> {
    let (target, existing) = check_output(path)?;
    let name = target
        .file_name()
        .ok_or_else(|| "the output path names no file".to_string())?;
    let tmp = target.with_file_name(format!(
        ".{}.tmp{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    let guard = cleanup::register(&tmp);
    let result = write(&tmp)
        .and_then(|()| match existing {
            Some(perms) => std::fs::set_permissions(&tmp, perms).map_err(|e| e.to_string()),
            None => Ok(()),
        })
        .and_then(|()| std::fs::rename(&tmp, &target).map_err(|e| e.to_string()));
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    drop(guard);
    result
}

/// Writes `bytes` as the file at `path` by [`write_replacing`].
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), String> {
    write_replacing(path, |tmp| {
        std::fs::write(tmp, bytes).map_err(|e| e.to_string())
    })
}

/// Writes the file at `path` by [`write_replacing`] through `write`, an `io` writer given the
/// temporary path; the error keeps its message.
pub fn write_replacing_io(
    path: &Path,
    write: impl FnOnce(&Path) -> io::Result<()>,
) -> io::Result<()> {
    write_replacing(path, |tmp| write(tmp).map_err(|e| e.to_string())).map_err(io::Error::other)
}

/// Installs the SIGINT and SIGTERM handlers now rather than at the first file written (for
/// [`crate::interrupt::catch_sigint`]); installing them twice does nothing.
pub fn install_signal_handlers() {
    cleanup::install_once();
}

/// Removing temporary files when SIGINT or SIGTERM arrives, with libc's `sigaction` (already a
/// dependency on Linux; the handler only unlinks and re-raises, or records a first SIGINT as
/// [`crate::interrupt`] asks, all async-signal-safe).
#[cfg(target_os = "linux")]
mod cleanup {
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
        if crate::interrupt::absorb(sig) {
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
mod cleanup {
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
