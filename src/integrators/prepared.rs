//! What a method prepares before it renders (a radiance graph, a guide's trees), saved so that
//! later renders reuse it: one header for every method's file, and `--precomputed`'s rule in
//! one place ([`load_or_prepare`]: a file that exists is loaded and must match; a missing one
//! is prepared and saved).
//!
//! The header, little-endian: the method's 8-byte magic, its format version (u32), a hash of
//! what the preparation depends on in the scene (u64: each method hashes what it reads, such
//! as its media probed at 16³ points and its lights, so equal scenes hash equally whatever
//! files they come from) and one of the settings it depends on (u64). A file from another
//! scene or with other settings is refused by name ([`Error::Mismatch`]), never used.

use std::path::Path;

use crate::error::{Error, Result};

/// Bytes of the header.
pub const HEADER_BYTES: usize = 28;

/// One method's kind of prepared file.
#[derive(Clone, Copy, Debug)]
pub struct FileKind {
    /// The first 8 bytes of every such file.
    pub magic: &'static [u8; 8],
    /// The format this nimbus writes and reads.
    pub version: u32,
    /// What the file is called in messages ("graph", "guide cache").
    pub what: &'static str,
    /// How to make one anew, for messages ("rebuild it with `nimbus graph build`").
    pub remedy: &'static str,
    /// What the settings hash covers, for messages ("training parameters (maxdepth, ...)").
    pub settings: &'static str,
}

/// A prepared file's header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Header {
    /// The scene hash it was prepared for.
    pub scene_hash: u64,
    /// The settings hash it was prepared with.
    pub settings_hash: u64,
}

impl FileKind {
    /// Appends the header of a file prepared for `header`'s scene and settings.
    pub fn write_header(&self, header: Header, out: &mut Vec<u8>) {
        out.extend_from_slice(self.magic);
        out.extend_from_slice(&self.version.to_le_bytes());
        out.extend_from_slice(&header.scene_hash.to_le_bytes());
        out.extend_from_slice(&header.settings_hash.to_le_bytes());
    }

    /// Reads the header of `bytes` (the file `path`): refuses another format or version
    /// ([`Error::Malformed`]) and, where an expected hash is given, another scene or other
    /// settings ([`Error::Mismatch`]). Returns the header and the bytes after it.
    pub fn read_header<'b>(
        &self,
        bytes: &'b [u8],
        path: &Path,
        scene: Option<u64>,
        settings: Option<u64>,
    ) -> Result<(Header, &'b [u8])> {
        let what = self.what;
        if bytes.len() < 8 || &bytes[..8] != self.magic {
            return Err(Error::malformed(path, format!("not a nimbus {what} file (no {} signature)", magic(self))));
        }
        if bytes.len() < HEADER_BYTES {
            return Err(Error::malformed(path, format!("not a nimbus {what} file (truncated header)")));
        }
        let u32_at = |i: usize| u32::from_le_bytes(bytes[i..i + 4].try_into().expect("4 bytes"));
        let u64_at = |i: usize| u64::from_le_bytes(bytes[i..i + 8].try_into().expect("8 bytes"));
        let version = u32_at(8);
        if version != self.version {
            return Err(Error::malformed(
                path,
                format!("{what} format version {version}, this nimbus reads version {}: {}", self.version, self.remedy),
            ));
        }
        let header = Header { scene_hash: u64_at(12), settings_hash: u64_at(20) };
        if scene.is_some_and(|h| h != header.scene_hash) {
            return Err(Error::mismatch(
                path,
                format!(
                    "this {what} was built for another scene (its media, bounds or lights differ): {}",
                    self.remedy
                ),
            ));
        }
        if settings.is_some_and(|h| h != header.settings_hash) {
            return Err(Error::mismatch(
                path,
                format!("this {what} was built with other {}: {}", self.settings, self.remedy),
            ));
        }
        Ok((header, &bytes[HEADER_BYTES..]))
    }
}

fn magic(kind: &FileKind) -> String {
    String::from_utf8_lossy(kind.magic).into_owned()
}

/// How a method's preparation was had.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Source {
    /// Loaded from this file.
    Loaded(std::path::PathBuf),
    /// Prepared now and saved to this file.
    Saved(std::path::PathBuf),
    /// Prepared now (no file was named).
    Prepared,
}

/// `--precomputed FILE`, the same for every method: a file that exists is loaded (and must
/// match the scene and settings: `load` refuses it otherwise); a missing one is prepared and
/// saved there; without a file the method prepares and keeps nothing.
pub fn load_or_prepare<T>(
    path: Option<&Path>,
    load: impl FnOnce(&Path) -> Result<T>,
    prepare: impl FnOnce() -> Result<T>,
    save: impl FnOnce(&Path, &T) -> Result<()>,
) -> Result<(T, Source)> {
    let Some(path) = path else { return Ok((prepare()?, Source::Prepared)) };
    match load(path) {
        Ok(t) => Ok((t, Source::Loaded(path.to_path_buf()))),
        Err(e) if e.is_not_found() => {
            let t = prepare()?;
            save(path, &t)?;
            Ok((t, Source::Saved(path.to_path_buf())))
        }
        Err(e) => Err(e),
    }
}

/// Reads a prepared file whole.
pub fn read_file(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|e| Error::io(path, "read", e))
}

/// Writes a prepared file whole, through a temporary file so that a render interrupted while
/// saving leaves no half-written file for the next one to refuse.
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    std::fs::write(&tmp, bytes).map_err(|e| Error::io(path, "write", e))?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::io(path, "write", e)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const KIND: FileKind =
        FileKind { magic: b"NIMBUSXX", version: 3, what: "test", remedy: "make it anew", settings: "settings (a, b)" };

    #[test]
    fn headers_round_trip_and_refuse_by_name() {
        let h = Header { scene_hash: 11, settings_hash: 22 };
        let mut bytes = Vec::new();
        KIND.write_header(h, &mut bytes);
        bytes.extend_from_slice(b"rest");
        let p = Path::new("x.test");
        let (back, rest) = KIND.read_header(&bytes, p, Some(11), Some(22)).unwrap();
        assert_eq!((back, rest), (h, &b"rest"[..]));
        let scene = KIND.read_header(&bytes, p, Some(12), None).unwrap_err();
        assert!(
            matches!(scene, Error::Mismatch { .. })
                && scene.to_string().contains("x.test: this test was built for another scene")
        );
        let settings = KIND.read_header(&bytes, p, None, Some(23)).unwrap_err();
        assert!(settings.to_string().contains("other settings (a, b)"), "{settings}");
        let mut old = bytes.clone();
        old[8] = 2;
        let version = KIND.read_header(&old, p, None, None).unwrap_err();
        assert!(version.to_string().contains("test format version 2, this nimbus reads version 3"), "{version}");
        assert!(matches!(KIND.read_header(&bytes[..20], p, None, None), Err(Error::Malformed { .. })));
        assert!(matches!(KIND.read_header(b"NIMBUSYY", p, None, None), Err(Error::Malformed { .. })));
    }

    #[test]
    fn a_missing_file_is_prepared_and_saved_a_present_one_loaded() {
        let dir = std::env::temp_dir().join(format!("nimbus-prepared-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("p.test");
        let load = |p: &Path| read_file(p).map(|b| b.len());
        let save = |p: &Path, n: &usize| write_file(p, &vec![0; *n]);
        let first = load_or_prepare(Some(&path), load, || Ok(5), save).unwrap();
        let second = load_or_prepare(Some(&path), load, || panic!("prepared twice"), save).unwrap();
        let none = load_or_prepare(None, load, || Ok(7), save).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(first, (5, Source::Saved(path.clone())));
        assert_eq!(second, (5, Source::Loaded(path)));
        assert_eq!(none, (7, Source::Prepared));
    }
}
