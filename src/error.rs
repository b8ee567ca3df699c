//! The library's errors, by kind: a caller can tell a missing file from a corrupt one, or a
//! prepared file made for another scene from one it may prepare anew, without reading
//! messages. Every message names the file (and what in it) so that it can be shown as it is.
//! Errors about a scene's text carry its location ([`nimbus_parser::Error`]); the scene
//! builder wraps the others with the location of the entity that read the file. (Volume grid
//! files have their own, finer kinds: `media::grid::GridError`.)

use std::path::{Path, PathBuf};

/// What went wrong.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be opened, read or written.
    #[error("{}: cannot {action}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What was being done ("read", "write", "read the guide cache", ...).
        action: &'static str,
        /// The cause.
        source: std::io::Error,
    },
    /// A file's contents are not what its format says (truncated, corrupt, another format or
    /// another version of it).
    #[error("{}: {message}", path.display())]
    Malformed {
        /// The file.
        path: PathBuf,
        /// What is wrong, and where in the file.
        message: String,
    },
    /// A file a method prepared (a radiance graph, a guide cache) that belongs to another
    /// scene or other settings: refused rather than rendered wrong.
    #[error("{}: {message}", path.display())]
    Mismatch {
        /// The file.
        path: PathBuf,
        /// What differs.
        message: String,
    },
    /// A feature or format nimbus does not have, by name.
    #[error("{0}")]
    Unsupported(String),
    /// A value or combination nimbus cannot use (out of range, inconsistent sizes, a lens
    /// that cannot focus, a command-line override the method has no parameter for).
    #[error("{0}")]
    Invalid(String),
    /// An error in the scene's text, with its location.
    #[error(transparent)]
    Scene(#[from] nimbus_parser::Error),
}

impl Error {
    /// [`Error::Io`] for `path`.
    pub fn io(path: &Path, action: &'static str, source: std::io::Error) -> Error {
        Error::Io { path: path.to_path_buf(), action, source }
    }

    /// [`Error::Malformed`] for `path`.
    pub fn malformed(path: &Path, message: impl Into<String>) -> Error {
        Error::Malformed { path: path.to_path_buf(), message: message.into() }
    }

    /// [`Error::Mismatch`] for `path`.
    pub fn mismatch(path: &Path, message: impl Into<String>) -> Error {
        Error::Mismatch { path: path.to_path_buf(), message: message.into() }
    }

    /// [`Error::Invalid`].
    pub fn invalid(message: impl Into<String>) -> Error {
        Error::Invalid(message.into())
    }

    /// Whether the error is a file that does not exist (which a caller may create).
    pub fn is_not_found(&self) -> bool {
        matches!(self, Error::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound)
    }
}

/// The message, for code that reports errors as text (the scene builder's located errors,
/// the command line).
impl From<Error> for String {
    fn from(e: Error) -> String {
        e.to_string()
    }
}

/// A result with the library's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
