//! The one error type of the library and its mapping to the exit status of the CLI.
//!
//! `docs/user-guide.md`: exit status 0 success, 1 failure in the computation (no convergence, not yet
//! implemented), 2 bad input (unreadable file, unknown group, invalid case). Every message names the
//! file and, where it applies, the line/byte, group or key.

use std::path::{Path, PathBuf};

use crate::mesh::msh::MshError;

/// Any failure nlrom reports.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file concerned.
        path: PathBuf,
        /// The operating-system error.
        source: std::io::Error,
    },
    /// A malformed Gmsh MSH file.
    #[error(transparent)]
    Msh(#[from] MshError),
    /// Bad input other than MSH syntax: a malformed matrix or case file, an unknown group, an invalid
    /// parameter. The message names the file, line or key and says what to do.
    #[error("{0}")]
    Input(String),
    /// The computation failed (no convergence, singular system, ...).
    #[error("{0}")]
    Compute(String),
}

impl Error {
    /// Exit status per `docs/user-guide.md`: 2 for bad input, 1 for a failed computation.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Io { .. } | Error::Msh(_) | Error::Input(_) => 2,
            Error::Compute(_) => 1,
        }
    }

    /// An [`Error::Io`] for `path`.
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        Error::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    /// An [`Error::Input`] from anything printable.
    pub fn input(msg: impl Into<String>) -> Self {
        Error::Input(msg.into())
    }
}

/// Result with the library's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;
