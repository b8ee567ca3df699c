//! Source locations: every token, parameter and entity remembers where it came from.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A position in a scene file: `file:line:column`, both 1-based.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct FileLoc {
    /// The file as it was named (after resolving it against the including file), or `<stdin>`
    /// / `<string>` for input that has no file.
    pub file: Arc<str>,
    /// 1-based line number.
    pub line: u32,
    /// 1-based column, counted in bytes.
    pub column: u32,
}

impl FileLoc {
    /// A location in `file`.
    pub fn new(file: Arc<str>, line: u32, column: u32) -> FileLoc {
        FileLoc { file, line, column }
    }

    /// The directory that relative paths written at this location resolve against: the
    /// directory of the file that contains it (the working directory for stdin or strings).
    pub fn directory(&self) -> PathBuf {
        if self.file.starts_with('<') {
            return PathBuf::from(".");
        }
        match Path::new(&*self.file).parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        }
    }

    /// Resolves a path written in the file at this location: absolute paths stay, relative
    /// ones are taken relative to [`FileLoc::directory`].
    pub fn resolve(&self, path: &str) -> PathBuf {
        let p = Path::new(path);
        if p.is_absolute() { p.to_path_buf() } else { self.directory().join(p) }
    }
}

impl fmt::Display for FileLoc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file, self.line, self.column)
    }
}
