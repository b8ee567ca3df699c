//! Splits pbrt-v4 text into tokens: bare words (directives, numbers, `true`/`false`), quoted
//! strings, `[` and `]`. Comments run from `#` to the end of the line. A stack of sources
//! implements `Include`: when an included file ends, tokens continue from the includer, so a
//! parameter list may run on across the end of an included file.

use std::io::Read;
use std::path::Path;
use std::sync::Arc;

use crate::error::{Error, Result};
use crate::loc::FileLoc;

/// How deep `Include` may nest before we assume a file includes itself.
const MAX_INCLUDE_DEPTH: usize = 64;

/// What a token is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum TokenKind {
    /// A bare word: directive name, number, `true`, `false`, ...
    Word,
    /// A quoted string; `escaped` when it contains backslash escapes to decode.
    Str { escaped: bool },
    /// `[`
    Open,
    /// `]`
    Close,
}

/// A token: its kind and where its text lies. Strings exclude their quotes.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Token {
    pub kind: TokenKind,
    source: u32,
    start: usize,
    end: usize,
    line: u32,
    column: u32,
}

/// One file (or string) being read.
struct Source {
    name: Arc<str>,
    data: Vec<u8>,
}

/// Read position within one source.
struct Cursor {
    source: u32,
    pos: usize,
    line: u32,
    line_start: usize,
}

/// Tokens from a main source and the files it includes.
pub(crate) struct TokenStream {
    sources: Vec<Source>,
    stack: Vec<Cursor>,
    pending: Option<Token>,
    /// pbrt-v4's search directory: the directory of the scene named on the command line.
    search_dir: std::sync::Arc<Path>,
}

/// Reads a whole file, decompressing `.gz`; `-` is standard input.
pub(crate) fn read_source(path: &Path) -> std::io::Result<Vec<u8>> {
    let mut data = Vec::new();
    if path.as_os_str() == "-" {
        std::io::stdin().read_to_end(&mut data)?;
    } else if path.extension().is_some_and(|e| e == "gz") {
        let file = std::fs::File::open(path)?;
        flate2::read::MultiGzDecoder::new(std::io::BufReader::new(file)).read_to_end(&mut data)?;
    } else {
        data = std::fs::read(path)?;
    }
    Ok(data)
}

impl TokenStream {
    /// A stream over `data`, the scene file called `name`: relative paths in it and in every
    /// file it includes resolve against its directory.
    pub fn new(name: Arc<str>, data: Vec<u8>) -> Result<TokenStream> {
        let dir: Arc<Path> = Arc::from(FileLoc::directory_of(&name).as_path());
        Self::with_search_dir(name, data, dir)
    }

    /// A stream over `data` (the source called `name`) whose relative paths resolve against
    /// `search_dir`: for files that a scene imports.
    pub fn with_search_dir(name: Arc<str>, data: Vec<u8>, search_dir: Arc<Path>) -> Result<TokenStream> {
        let mut stream = TokenStream { sources: Vec::new(), stack: Vec::new(), pending: None, search_dir };
        stream.push(name, data)?;
        Ok(stream)
    }

    /// The directory relative paths resolve against.
    pub fn search_dir(&self) -> &Arc<Path> {
        &self.search_dir
    }

    /// Pushes an included source: its tokens come next, then the includer's resume.
    pub fn push(&mut self, name: Arc<str>, data: Vec<u8>) -> Result<()> {
        if self.stack.len() >= MAX_INCLUDE_DEPTH {
            return Err(Error::general(format!(
                "{name}: Include nested more than {MAX_INCLUDE_DEPTH} deep (does a file include itself?)"
            )));
        }
        let loc = FileLoc::new(name.clone(), 1, 1);
        if data.len() >= 2 && ((data[0] == 0xfe && data[1] == 0xff) || (data[0] == 0xff && data[1] == 0xfe)) {
            return Err(Error::new(&loc, "file is UTF-16 encoded; pbrt scene files must be UTF-8"));
        }
        // A UTF-8 byte order mark carries no meaning: drop it, so that it counts in no
        // column.
        let mut data = data;
        if data.starts_with(&[0xef, 0xbb, 0xbf]) {
            data.drain(..3);
        }
        let source = u32::try_from(self.sources.len()).map_err(|_| Error::new(&loc, "too many source files"))?;
        self.sources.push(Source { name, data });
        self.stack.push(Cursor { source, pos: 0, line: 1, line_start: 0 });
        Ok(())
    }

    /// The raw bytes of a token (strings without quotes, escapes undecoded).
    pub fn bytes(&self, t: &Token) -> &[u8] {
        &self.sources[t.source as usize].data[t.start..t.end]
    }

    /// The location of a token.
    pub fn loc(&self, t: &Token) -> FileLoc {
        FileLoc {
            file: self.sources[t.source as usize].name.clone(),
            line: t.line,
            column: t.column,
            search_dir: Some(self.search_dir.clone()),
        }
    }

    /// The location where the stream stopped (for "premature end of file").
    pub fn end_loc(&self) -> FileLoc {
        match self.sources.first() {
            Some(s) => {
                let (line, column) = line_col_at(&s.data, s.data.len());
                FileLoc::new(s.name.clone(), line, column)
            }
            None => FileLoc::new(Arc::from("<input>"), 1, 1),
        }
    }

    /// A token's text as a string: decodes escapes of quoted strings and checks UTF-8.
    pub fn text(&self, t: &Token) -> Result<String> {
        let raw = self.bytes(t);
        let decoded = match t.kind {
            TokenKind::Str { escaped: true } => {
                let mut out = Vec::with_capacity(raw.len());
                let mut i = 0;
                while i < raw.len() {
                    if raw[i] == b'\\' {
                        i += 1;
                        out.push(match raw.get(i) {
                            Some(b'b') => 0x08,
                            Some(b'f') => 0x0c,
                            Some(b'n') => b'\n',
                            Some(b'r') => b'\r',
                            Some(b't') => b'\t',
                            Some(b'\\') => b'\\',
                            Some(b'\'') => b'\'',
                            Some(b'"') => b'"',
                            Some(&c) => {
                                return Err(Error::new(
                                    &self.loc(t),
                                    format!("unexpected escaped character '\\{}' in string", c.escape_ascii()),
                                ));
                            }
                            None => {
                                return Err(Error::new(&self.loc(t), "string ends with a lone '\\'"));
                            }
                        });
                    } else {
                        out.push(raw[i]);
                    }
                    i += 1;
                }
                out
            }
            _ => raw.to_vec(),
        };
        String::from_utf8(decoded).map_err(|_| Error::new(&self.loc(t), "text is not valid UTF-8"))
    }

    /// Puts one token back; the next call to [`TokenStream::next`] returns it.
    pub fn unget(&mut self, t: Token) {
        debug_assert!(self.pending.is_none());
        self.pending = Some(t);
    }

    /// The next token, continuing in the includer when an included file ends; `None` at the
    /// end of the main source.
    pub fn next(&mut self) -> Result<Option<Token>> {
        if let Some(t) = self.pending.take() {
            return Ok(Some(t));
        }
        while let Some(cursor) = self.stack.last_mut() {
            let source = &self.sources[cursor.source as usize];
            match scan(&source.data, cursor) {
                Ok(Some(t)) => return Ok(Some(t)),
                Ok(None) => {
                    self.stack.pop();
                }
                Err((message, line, column)) => {
                    return Err(Error::new(&FileLoc::new(source.name.clone(), line, column), message));
                }
            }
        }
        Ok(None)
    }

    /// The next token, which must exist; `what` names what was expected for the error.
    pub fn expect(&mut self, what: &str) -> Result<Token> {
        self.expect_with(|| what.to_string())
    }

    /// Like [`TokenStream::expect`], building the description only if it is needed (the
    /// value loops call this once per number).
    #[inline]
    pub fn expect_with(&mut self, what: impl FnOnce() -> String) -> Result<Token> {
        match self.next()? {
            Some(t) => Ok(t),
            None => Err(Error::new(&self.end_loc(), format!("premature end of file: expected {}", what()))),
        }
    }
}

fn line_col_at(data: &[u8], pos: usize) -> (u32, u32) {
    let before = &data[..pos.min(data.len())];
    let line = before.iter().filter(|&&c| c == b'\n').count() + 1;
    let line_start = before.iter().rposition(|&c| c == b'\n').map_or(0, |p| p + 1);
    (line as u32, (pos - line_start + 1) as u32)
}

type ScanError = (&'static str, u32, u32);

/// Scans the next token of `data` from `c`; `None` at the end of the data.
#[inline]
fn scan(data: &[u8], c: &mut Cursor) -> std::result::Result<Option<Token>, ScanError> {
    let len = data.len();
    let mut pos = c.pos;
    loop {
        if pos >= len {
            c.pos = pos;
            return Ok(None);
        }
        match data[pos] {
            b'\n' => {
                pos += 1;
                c.line += 1;
                c.line_start = pos;
            }
            b' ' | b'\t' | b'\r' => pos += 1,
            b'#' => {
                while pos < len && data[pos] != b'\n' && data[pos] != b'\r' {
                    pos += 1;
                }
            }
            _ => break,
        }
    }
    let line = c.line;
    let column = (pos - c.line_start + 1) as u32;
    let make = |kind, start, end| Token { kind, source: c.source, start, end, line, column };
    let token = match data[pos] {
        b'[' => {
            pos += 1;
            make(TokenKind::Open, pos - 1, pos)
        }
        b']' => {
            pos += 1;
            make(TokenKind::Close, pos - 1, pos)
        }
        b'"' => {
            let start = pos + 1;
            let mut p = start;
            let mut escaped = false;
            loop {
                if p >= len {
                    return Err(("premature end of file inside a quoted string", line, column));
                }
                match data[p] {
                    b'"' => break,
                    b'\n' => {
                        return Err(("unterminated string: newline before the closing '\"'", line, column));
                    }
                    b'\\' => {
                        escaped = true;
                        p += 1;
                        if p >= len {
                            return Err(("premature end of file inside a quoted string", line, column));
                        }
                        if data[p] == b'\n' {
                            return Err(("unterminated string: newline before the closing '\"'", line, column));
                        }
                        p += 1;
                    }
                    _ => p += 1,
                }
            }
            pos = p + 1;
            make(TokenKind::Str { escaped }, start, p)
        }
        _ => {
            let start = pos;
            while pos < len && !matches!(data[pos], b' ' | b'\n' | b'\t' | b'\r' | b'"' | b'[' | b']') {
                pos += 1;
            }
            make(TokenKind::Word, start, pos)
        }
    };
    c.pos = pos;
    Ok(Some(token))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tokens(text: &str) -> Result<Vec<(TokenKind, String, u32, u32)>> {
        let mut s = TokenStream::new(Arc::from("t.pbrt"), text.as_bytes().to_vec())?;
        let mut out = Vec::new();
        while let Some(t) = s.next()? {
            out.push((t.kind, s.text(&t)?, t.line, t.column));
        }
        Ok(out)
    }

    #[test]
    fn splits_words_strings_brackets_and_skips_comments() {
        let t = tokens("Shape \"sphere\" # comment\n  \"float radius\"[2.5]").unwrap();
        let texts: Vec<_> = t.iter().map(|x| x.1.as_str()).collect();
        assert_eq!(texts, ["Shape", "sphere", "float radius", "[", "2.5", "]"]);
        assert_eq!((t[2].2, t[2].3), (2, 3));
        assert_eq!(t[3].0, TokenKind::Open);
    }

    #[test]
    fn decodes_escapes() {
        let t = tokens(r#""a\"b\\c\n\t""#).unwrap();
        assert_eq!(t[0].1, "a\"b\\c\n\t");
        let err = tokens(r#""a\qb""#).unwrap_err();
        assert!(err.to_string().contains("unexpected escaped character"), "{err}");
    }

    #[test]
    fn unterminated_string_is_reported_where_it_starts() {
        let err = tokens("Shape\n  \"sphere\n").unwrap_err();
        assert_eq!(err.loc.as_ref().unwrap().line, 2);
        assert_eq!(err.loc.as_ref().unwrap().column, 3);
        assert!(err.message.contains("unterminated string"));
        let err = tokens("Shape \"sph").unwrap_err();
        assert!(err.message.contains("premature end of file"));
    }

    #[test]
    fn include_stack_continues_in_the_includer() {
        let mut s = TokenStream::new(Arc::from("a"), b"A B".to_vec()).unwrap();
        let first = s.next().unwrap().unwrap();
        assert_eq!(s.bytes(&first), b"A");
        s.push(Arc::from("b"), b"X".to_vec()).unwrap();
        let x = s.next().unwrap().unwrap();
        assert_eq!(s.bytes(&x), b"X");
        assert_eq!(&*s.loc(&x).file, "b");
        let b = s.next().unwrap().unwrap();
        assert_eq!(s.bytes(&b), b"B");
        assert!(s.next().unwrap().is_none());
    }

    #[test]
    fn rejects_utf16() {
        assert!(TokenStream::new(Arc::from("a"), vec![0xff, 0xfe, 0, 0]).is_err());
    }
}
