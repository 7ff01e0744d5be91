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

/// Everything that can go wrong between reading a script and writing its images.
#[derive(Clone, Debug, thiserror::Error)]
pub enum Error {
    /// A Lua error raised by the script itself (syntax error, `error()`, a bad call); the message
    /// already starts with `script:line:` as Lua formats it.
    #[error("{0}")]
    Lua(String),
    /// A fault found by caustic at a known script line (bad argument, missing file, bad scene).
    #[error("{loc}: {message}")]
    Script { loc: Loc, message: String },
    /// A file that could not be read or written, outside any script line.
    #[error("{}: {message}", path.display())]
    File { path: PathBuf, message: String },
    /// A problem with the command line options.
    #[error("{0}")]
    Usage(String),
}

impl Error {
    /// Returns a [`Error::Script`] at `loc`.
    pub fn at(loc: &Loc, message: impl Into<String>) -> Error {
        Error::Script {
            loc: loc.clone(),
            message: message.into(),
        }
    }
}

/// The library's result type.
pub type Result<T, E = Error> = std::result::Result<T, E>;
