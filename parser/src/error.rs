//! Errors and warnings, each naming the `file:line:col` it is about.

use std::fmt;

use crate::loc::FileLoc;

/// A fatal problem with the scene description. Its `Display` form is
/// `file:line:col: message`, the form editors and terminals recognise.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub struct Error {
    /// Where the problem is; `None` only for problems with no place in a file (for example
    /// a scene that ends before `WorldBegin`).
    pub loc: Option<FileLoc>,
    /// What is wrong, quoting the offending text.
    pub message: String,
}

impl Error {
    /// An error at `loc`.
    pub fn new(loc: &FileLoc, message: impl Into<String>) -> Error {
        Error { loc: Some(loc.clone()), message: message.into() }
    }

    /// An error that belongs to no particular place.
    pub fn general(message: impl Into<String>) -> Error {
        Error { loc: None, message: message.into() }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.loc {
            Some(loc) => write!(f, "{loc}: {}", self.message),
            None => f.write_str(&self.message),
        }
    }
}

/// Shorthand for results whose error is a scene [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

/// Something suspicious that does not stop the scene from loading (a deprecated directive, a
/// parameter nothing reads, ...). Displayed like an [`Error`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Warning {
    /// Where the suspicious text is.
    pub loc: Option<FileLoc>,
    /// What is suspicious about it.
    pub message: String,
}

impl Warning {
    /// A warning at `loc`.
    pub fn new(loc: &FileLoc, message: impl Into<String>) -> Warning {
        Warning { loc: Some(loc.clone()), message: message.into() }
    }
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.loc {
            Some(loc) => write!(f, "{loc}: {}", self.message),
            None => f.write_str(&self.message),
        }
    }
}

impl From<Warning> for Error {
    fn from(w: Warning) -> Error {
        Error { loc: w.loc, message: w.message }
    }
}
