//! Source locations: every token, parameter and entity remembers where it came from.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A position in a scene file: `file:line:column`, both 1-based.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct FileLoc {
    /// The file as it was named (after resolving it against the scene's directory), or
    /// `<stdin>` / `<string>` for input that has no file.
    pub file: Arc<str>,
    /// 1-based line number.
    pub line: u32,
    /// 1-based column, counted in bytes.
    pub column: u32,
    /// Where relative paths written here resolve: the directory of the scene file named on
    /// the command line, whichever file includes this one (pbrt-v4's search directory).
    /// `None` for locations made outside a scene (defaults), which use their own file's.
    pub search_dir: Option<Arc<Path>>,
}

impl FileLoc {
    /// A location in `file`.
    pub fn new(file: Arc<str>, line: u32, column: u32) -> FileLoc {
        FileLoc { file, line, column, search_dir: None }
    }

    /// The directory of the scene file `file` (the working directory for stdin or strings):
    /// pbrt-v4's search directory when `file` is the scene named on the command line.
    pub fn directory_of(file: &str) -> PathBuf {
        if file.starts_with('<') || file == "-" {
            return PathBuf::from(".");
        }
        match Path::new(file).parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        }
    }

    /// The directory that relative paths written at this location resolve against: the
    /// directory of the top-level scene file, as pbrt-v4 resolves them (not the directory of
    /// an included file).
    pub fn directory(&self) -> PathBuf {
        match &self.search_dir {
            Some(d) => d.to_path_buf(),
            None => Self::directory_of(&self.file),
        }
    }

    /// Resolves a path written in the file at this location: absolute paths stay, relative
    /// ones are taken relative to [`FileLoc::directory`].
    pub fn resolve(&self, path: &str) -> PathBuf {
        let p = Path::new(path);
        if p.is_absolute() { p.to_path_buf() } else { self.directory().join(p) }
    }
}

/// A path as error messages show the path that was tried: absolute, so it says where nimbus
/// looked whatever the working directory.
pub fn shown(path: &Path) -> String {
    std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf()).display().to_string()
}

impl fmt::Display for FileLoc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file, self.line, self.column)
    }
}
