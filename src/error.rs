//! The library's error type: every message names the script line or file at fault.

use std::fmt;
use std::path::PathBuf;
use std::sync::Arc;

/// A place in a scene script: the script's path as given and a 1-based line number.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Loc {
    /// The script path as the user wrote it on the command line (or the chunk name).
    pub file: Arc<str>,
    /// The 1-based line, or 0 when unknown.
    pub line: u32,
}

impl Loc {
    /// Returns a location for code that did not come from a script (tests, Rust-built scenes).
    pub fn internal() -> Loc {
        Loc {
            file: Arc::from("<rust>"),
            line: 0,
        }
    }
}

impl fmt::Display for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(f, "{}:{}", self.file, self.line)
        } else {
            write!(f, "{}", self.file)
        }
    }
}

/// What kind of fault an [`Error::Script`] reports, for callers and tests that branch on it
/// rather than on the message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fault {
    /// A `gr` function got a bad argument: lauxlib's `bad argument #3 to 'nh_sphere' (…)`.
    BadArgument,
    /// The script used a `gr` function or node method that does not exist.
    UnknownFunction,
    /// A file the script names (mesh, texture, bump map) is in neither the working directory
    /// nor the script's folder.
    NotFound,
    /// A mesh file could not be read or parsed, is in a format caustic does not read, or holds
    /// data the scene cannot use (a non-finite vertex, mismatched per-triangle materials).
    MeshLoad,
    /// The script reached for what the sandbox does not give scenes (`docs/security.md`): a
    /// process, native code, a file outside its folders, a write, or more time than its budget.
    Sandbox,
    /// Any other fault at a script line: a cycle, a singular CSG operand, an unreadable texture…
    Other,
}

/// Everything that can go wrong between reading a script and writing its images.
#[derive(Clone, Debug, thiserror::Error)]
pub enum Error {
    /// A Lua error raised by the script itself (syntax error, `error()`, a bad call); the message
    /// already starts with `script:line:` as Lua formats it.
    #[error("{0}")]
    Lua(String),
    /// A fault found by caustic at a known script line (bad argument, missing file, bad scene).
    #[error("{loc}: {message}")]
    Script {
        loc: Loc,
        /// What went wrong, for matching; the message says it for people.
        fault: Fault,
        message: String,
    },
    /// A file that could not be read or written, outside any script line.
    #[error("{}: {message}", path.display())]
    File { path: PathBuf, message: String },
    /// A problem with the command line options.
    #[error("{0}")]
    Usage(String),
    /// The run was asked to stop (Ctrl-C, [`crate::interrupt`]); the message says what was
    /// written. The command line exits with status 130.
    #[error("interrupted: {0}")]
    Interrupted(String),
}

impl Error {
    /// Returns a [`Error::Script`] at `loc` of kind [`Fault::Other`].
    pub fn at(loc: &Loc, message: impl Into<String>) -> Error {
        Error::fault_at(Fault::Other, loc, message)
    }

    /// Returns a [`Error::Script`] at `loc` of kind `fault`.
    pub fn fault_at(fault: Fault, loc: &Loc, message: impl Into<String>) -> Error {
        Error::Script {
            loc: loc.clone(),
            fault,
            message: message.into(),
        }
    }

    /// Returns the kind of a [`Error::Script`], or `None` for the other variants.
    pub fn fault(&self) -> Option<Fault> {
        match self {
            Error::Script { fault, .. } => Some(*fault),
            Error::Lua(_) | Error::File { .. } | Error::Usage(_) | Error::Interrupted(_) => None,
        }
    }
}

/// The library's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
