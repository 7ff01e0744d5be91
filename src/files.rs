//! Files in and out, safely: inputs must be regular files, and outputs are replaced atomically.
//! A leaf: every floor that reads or writes a file may import it.
//!
//! - **Inputs** ([`read_regular`], [`check_regular`]): a device, FIFO or socket named as a
//!   script, mesh, material library, buffer, texture or tile is refused before it is opened
//!   (reading `/dev/zero` never ends; opening a FIFO blocks until someone writes to it).
//! - **Outputs** ([`write_replacing`]; [`write_bytes`] and [`write_replacing_io`] wrap it), for
//!   images, exported meshes (OBJ, glTF, GLB), Mitsuba scenes, photon maps and study tables
//!   alike: the data goes to a temporary file beside the target, which is renamed over it, so
//!   an interrupted write never leaves a truncated file where a good one was. The temporary
//!   file has an unpredictable name (64 random bits from the OS), is created exclusively
//!   (`O_CREAT | O_EXCL | O_NOFOLLOW`: a file or symlink planted at that name is never written
//!   through) and the writers write through the file so opened, never reopening it by name. A
//!   symlink at the *output* is followed (the file it names is replaced, the link kept); an
//!   existing file keeps its permissions (the temporary file is never more open than it); a
//!   special file (`/dev/null`, a FIFO) is refused, never replaced.
//! - **Checks before the work** ([`check_output`], [`check_not_input`]): an output whose folder
//!   does not exist or cannot be written to is refused before anything is rendered, and so is
//!   an output that is the same file as one of the command's inputs (device and inode, after
//!   symlinks: hard links and `./x` against `x` included).
//! - **Signals**: on SIGINT or SIGTERM the temporary files being written are removed before the
//!   process ends as the signal would end it (except a first SIGINT that [`crate::interrupt`]
//!   turns into a request to stop).

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

/// Opens the regular file `path` for reading: checked before it is opened ([`check_regular`]:
/// a FIFO is never opened) and again once open, so a file swapped for a special one in between
/// is refused too.
pub fn open_regular(path: &Path) -> io::Result<std::fs::File> {
    check_regular(path)?;
    let file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    if !meta.is_file() {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("{} ({REGULAR_ONLY})", kind(&meta)),
        ));
    }
    Ok(file)
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

/// Returns the folder `target` goes in (`.` for a bare file name).
fn folder_of(target: &Path) -> &Path {
    match target.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => dir,
        _ => Path::new("."),
    }
}

/// Returns an error unless the folder of `target` exists, is a folder and can be written to.
fn check_folder(target: &Path) -> Result<(), String> {
    let dir = folder_of(target);
    match std::fs::metadata(dir) {
        Ok(meta) if meta.is_dir() => {}
        Ok(_) => return Err(format!("{} is not a folder", dir.display())),
        Err(_) => return Err(format!("the folder {} does not exist", dir.display())),
    }
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::ffi::OsStrExt;
        let c = std::ffi::CString::new(dir.as_os_str().as_bytes()).map_err(|e| e.to_string())?;
        // SAFETY: c is a valid NUL-terminated path; access only reads it.
        if unsafe { libc::access(c.as_ptr(), libc::W_OK) } != 0 {
            return Err(format!("the folder {} cannot be written to", dir.display()));
        }
    }
    Ok(())
}

/// Returns the file a write to `path` replaces (its symlinks followed) and, when that file
/// exists, its permissions; an error when it is a special file (a device, FIFO or socket) or a
/// folder, or when its folder does not exist or cannot be written to. Callers check outputs
/// with it before spending a render on them.
pub fn check_output(path: &Path) -> Result<(PathBuf, Option<std::fs::Permissions>), String> {
    let target = write_target(path).map_err(|e| e.to_string())?;
    match std::fs::metadata(&target) {
        Ok(meta) if !meta.is_file() => Err(format!("{} ({REGULAR_ONLY})", kind(&meta))),
        Ok(meta) => check_folder(&target).map(|()| (target, Some(meta.permissions()))),
        Err(_) => check_folder(&target).map(|()| (target, None)),
    }
}

/// Returns an error naming both paths when the file a write to `output` would replace (its
/// symlinks followed) is one of `inputs`: the same device and inode, so hard links, symlinks
/// and `./x` against `x` are all caught. Inputs that do not exist are skipped, and so is an
/// output that does not exist yet (it cannot be any input).
pub fn check_not_input(output: &Path, inputs: &[&Path]) -> Result<(), String> {
    let Ok(out) = std::fs::metadata(output) else {
        return Ok(());
    };
    for input in inputs {
        if let Ok(meta) = std::fs::metadata(input)
            && same_file(&out, &meta)
        {
            return Err(format!(
                "is the same file as the input {}: caustic never overwrites its inputs",
                input.display()
            ));
        }
    }
    Ok(())
}

/// Returns whether two files' metadata describe the same file.
#[cfg(unix)]
fn same_file(a: &std::fs::Metadata, b: &std::fs::Metadata) -> bool {
    use std::os::unix::fs::MetadataExt;
    (a.dev(), a.ino()) == (b.dev(), b.ino())
}

/// Returns whether two files' metadata describe the same file (no inodes here: never).
#[cfg(not(unix))]
fn same_file(_: &std::fs::Metadata, _: &std::fs::Metadata) -> bool {
    false
}

/// Returns 64 bits from the operating system's random source, for temporary names.
fn random_u64() -> u64 {
    let mut b = [0u8; 8];
    #[cfg(target_os = "linux")]
    {
        // SAFETY: b is a valid 8-byte buffer.
        let n = unsafe { libc::getrandom(b.as_mut_ptr().cast(), b.len(), 0) };
        if n == 8 {
            return u64::from_le_bytes(b);
        }
    }
    use std::io::Read;
    if std::fs::File::open("/dev/urandom")
        .and_then(|mut f| f.read_exact(&mut b))
        .is_ok()
    {
        return u64::from_le_bytes(b);
    }
    // No OS source: std's per-process random hash keys, mixed with the time.
    use std::hash::{BuildHasher, Hasher};
    let mut h = std::collections::hash_map::RandomState::new().build_hasher();
    h.write_u128(
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_nanos()),
    );
    h.finish()
}

/// Creates the file `path` for writing with mode `mode` (less the umask), failing when
/// anything, a symlink included, is already there (`O_CREAT | O_EXCL`, and `O_NOFOLLOW`).
fn open_exclusive(path: &Path, mode: u32) -> io::Result<std::fs::File> {
    let mut options = std::fs::OpenOptions::new();
    options.write(true).create_new(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.mode(mode);
    }
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NOFOLLOW);
    }
    #[cfg(not(unix))]
    let _ = mode;
    options.open(path)
}

/// Creates a new temporary file beside `target` with an unpredictable name, exclusively
/// (`O_CREAT | O_EXCL`, and `O_NOFOLLOW`): a file or symlink planted at that name makes the
/// creation fail rather than be written through. Its mode is `mode` (less the umask), so it is
/// never more open than the file it replaces. Returns the file, its path and its signal guard.
fn create_temporary(
    target: &Path,
    mode: u32,
) -> Result<(std::fs::File, PathBuf, crate::interrupt::cleanup::Guard), String> {
    let name = target
        .file_name()
        .ok_or_else(|| "the output path names no file".to_string())?;
    let mut last = None;
    for _ in 0..8 {
        let tmp = target.with_file_name(format!(
            ".{}.{:016x}.tmp",
            name.to_string_lossy(),
            random_u64()
        ));
        let guard = crate::interrupt::cleanup::register(&tmp);
        match open_exclusive(&tmp, mode) {
            Ok(file) => return Ok((file, tmp, guard)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => last = Some(e),
            Err(e) => return Err(format!("cannot create a temporary file beside it: {e}")),
        }
    }
    Err(format!(
        "cannot create a temporary file beside it: {}",
        last.map_or_else(String::new, |e| e.to_string())
    ))
}

/// Writes a file at `path` through `write`, given the temporary file already open for
/// writing (never reopened by name), then renames it over the target: see the module doc for
/// symlinks, permissions and special files.
pub fn write_replacing(
    path: &Path,
    write: impl FnOnce(&mut std::fs::File) -> Result<(), String>,
) -> Result<(), String> {
    let (target, existing) = check_output(path)?;
    #[cfg(unix)]
    let mode = existing.as_ref().map_or(0o666, |p| {
        use std::os::unix::fs::PermissionsExt;
        p.mode() & 0o777
    });
    #[cfg(not(unix))]
    let mode = 0o666;
    let (mut file, tmp, guard) = create_temporary(&target, mode)?;
    let result = write(&mut file)
        .and_then(|()| match existing {
            // fchmod on the open file: the exact mode, whatever the umask took away.
            Some(perms) => file.set_permissions(perms).map_err(|e| e.to_string()),
            None => Ok(()),
        })
        .and_then(|()| {
            drop(file);
            std::fs::rename(&tmp, &target).map_err(|e| e.to_string())
        });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    drop(guard);
    result
}

/// Writes `bytes` as the file at `path` by [`write_replacing`].
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), String> {
    use std::io::Write;
    write_replacing(path, |file| {
        file.write_all(bytes).map_err(|e| e.to_string())
    })
}

/// Writes the file at `path` by [`write_replacing`] through `write`, an `io` writer given the
/// open temporary file; the error keeps its message.
pub fn write_replacing_io(
    path: &Path,
    write: impl FnOnce(&mut std::fs::File) -> io::Result<()>,
) -> io::Result<()> {
    write_replacing(path, |file| write(file).map_err(|e| e.to_string())).map_err(io::Error::other)
}

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    /// A symlink (to a file, or dangling) or a file planted at a temporary name makes the
    /// exclusive creation fail: nothing is written through it, and the file it names is
    /// neither changed nor created.
    #[test]
    fn a_name_already_taken_is_never_written_through() {
        let dir = std::env::temp_dir().join(format!("caustic-files-excl-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let victim = dir.join("victim");
        std::fs::write(&victim, b"precious").unwrap();
        let cases = [
            ("link", Some(victim.clone())),
            ("dangling", Some(dir.join("nothing-yet"))),
            ("file", None),
        ];
        for (name, link_to) in cases {
            let tmp = dir.join(name);
            match &link_to {
                Some(to) => std::os::unix::fs::symlink(to, &tmp).unwrap(),
                None => std::fs::write(&tmp, b"planted").unwrap(),
            }
            let e = open_exclusive(&tmp, 0o666).unwrap_err();
            assert_eq!(e.kind(), io::ErrorKind::AlreadyExists, "{name}: {e}");
        }
        assert_eq!(std::fs::read(&victim).unwrap(), b"precious");
        assert!(!dir.join("nothing-yet").exists());
        let _ = std::fs::remove_dir_all(&dir);
    }
}

/// The folders an untrusted scene's files may name other files in (a mesh's material
/// libraries, glTF buffers and images; `docs/security.md`): canonical trees, or any file.
#[derive(Clone, Debug, Default)]
pub struct ReadScope {
    /// The readable trees; `None` for any file (scenes built in Rust, trusted tools).
    roots: Option<std::sync::Arc<[PathBuf]>>,
}

impl ReadScope {
    /// Returns the scope that lets any file be read.
    pub fn any() -> ReadScope {
        ReadScope { roots: None }
    }

    /// Returns the scope of the canonical folder trees `roots`.
    pub fn within(roots: Vec<PathBuf>) -> ReadScope {
        ReadScope {
            roots: Some(roots.into()),
        }
    }

    /// Returns an error unless the existing file `path`, its symlinks and `..` resolved, lies in
    /// the scope; a file that does not exist is left to the reader to report.
    pub fn check(&self, path: &Path) -> io::Result<()> {
        let Some(roots) = &self.roots else {
            return Ok(());
        };
        let Ok(real) = std::fs::canonicalize(path) else {
            return Ok(());
        };
        if roots.iter().any(|r| real.starts_with(r)) {
            return Ok(());
        }
        let shown: Vec<String> = roots.iter().map(|r| r.display().to_string()).collect();
        Err(io::Error::new(
            io::ErrorKind::PermissionDenied,
            format!(
                "{} is outside the folders a scene may read ({}); a scene reads only files in its \
                 own folder and below it (docs/security.md): copy the file there, or name its \
                 folder with --allow-read DIR",
                real.display(),
                shown.join(", ")
            ),
        ))
    }
}
