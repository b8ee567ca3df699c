//! A read-only stream made of pieces: ranges of a file and bytes held in memory.
//!
//! vdb-rs reads a grid by seeking to the positions its grid descriptor records and reading on
//! from there. Appending pieces after the file's end and pointing the descriptor at them lets
//! nimbus show vdb-rs a grid as vdb-rs can read it — a transform it understands in place of
//! one it would panic on, the empty value arrays OpenVDB omits for half-float grids written
//! out as vdb-rs expects them — while the file itself is neither copied nor changed.

use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};

/// One piece of a spliced stream.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) enum Piece {
    /// `len` bytes of the file from `start`.
    File {
        /// First byte in the file.
        start: u64,
        /// Length.
        len: u64,
    },
    /// Bytes held in memory.
    Bytes(Vec<u8>),
}

impl Piece {
    fn len(&self) -> u64 {
        match self {
            Piece::File { len, .. } => *len,
            Piece::Bytes(b) => b.len() as u64,
        }
    }
}

/// The pieces laid end to end, readable and seekable as one stream.
pub(crate) struct SplicedStream {
    file: BufReader<File>,
    /// Where the underlying file is positioned, so sequential reads need no seek (a seek
    /// empties the `BufReader`).
    file_pos: Option<u64>,
    pieces: Vec<Piece>,
    /// Stream offset of each piece.
    starts: Vec<u64>,
    len: u64,
    pos: u64,
    /// Piece holding `pos`, as last found.
    current: usize,
}

impl SplicedStream {
    /// A stream of `pieces` read from `file`.
    pub(crate) fn new(file: File, pieces: Vec<Piece>) -> SplicedStream {
        let mut starts = Vec::with_capacity(pieces.len());
        let mut len = 0;
        for p in &pieces {
            starts.push(len);
            len += p.len();
        }
        SplicedStream {
            file: BufReader::with_capacity(1 << 16, file),
            file_pos: None,
            pieces,
            starts,
            len,
            pos: 0,
            current: 0,
        }
    }

    /// Stream offset where piece `i` starts.
    pub(crate) fn piece_start(&self, i: usize) -> u64 {
        self.starts[i]
    }

    /// The piece holding stream offset `pos` (the stream ends before `pieces.len()`).
    fn piece_at(&mut self, pos: u64) -> usize {
        let in_piece =
            |s: &Self, i: usize| i < s.pieces.len() && s.starts[i] <= pos && pos < s.starts[i] + s.pieces[i].len();
        if !in_piece(self, self.current) {
            // Last piece starting at or before pos; empty pieces are skipped by the loop.
            let mut i = self.starts.partition_point(|&s| s <= pos).saturating_sub(1);
            while i < self.pieces.len() && !in_piece(self, i) {
                i += 1;
            }
            self.current = i;
        }
        self.current
    }
}

impl Read for SplicedStream {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if self.pos >= self.len || buf.is_empty() {
            return Ok(0);
        }
        let i = self.piece_at(self.pos);
        let offset = self.pos - self.starts[i];
        let available = self.pieces[i].len() - offset;
        let n = (buf.len() as u64).min(available) as usize;
        match &self.pieces[i] {
            Piece::Bytes(bytes) => {
                let o = offset as usize;
                buf[..n].copy_from_slice(&bytes[o..o + n]);
            }
            Piece::File { start, .. } => {
                let at = start + offset;
                if self.file_pos != Some(at) {
                    self.file.seek(SeekFrom::Start(at))?;
                }
                self.file_pos = None;
                self.file.read_exact(&mut buf[..n])?;
                self.file_pos = Some(at + n as u64);
            }
        }
        self.pos += n as u64;
        Ok(n)
    }
}

impl Seek for SplicedStream {
    fn seek(&mut self, to: SeekFrom) -> std::io::Result<u64> {
        let target = match to {
            SeekFrom::Start(p) => Some(p),
            SeekFrom::End(d) => self.len.checked_add_signed(d),
            SeekFrom::Current(d) => self.pos.checked_add_signed(d),
        };
        match target {
            Some(p) => {
                self.pos = p;
                Ok(p)
            }
            None => Err(std::io::Error::new(std::io::ErrorKind::InvalidInput, "seek before the start of the stream")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    #[test]
    fn spliced_stream_reads_and_seeks_across_pieces() {
        let dir = std::env::temp_dir().join(format!("nimbus-spliced-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("data.bin");
        let data: Vec<u8> = (0..=255u8).collect();
        File::create(&path).unwrap().write_all(&data).unwrap();
        let pieces = vec![
            Piece::File { start: 0, len: 10 },
            Piece::Bytes(vec![200, 201]),
            Piece::File { start: 0, len: 0 },
            Piece::File { start: 100, len: 5 },
        ];
        let mut s = SplicedStream::new(File::open(&path).unwrap(), pieces);
        let mut all = Vec::new();
        s.read_to_end(&mut all).unwrap();
        let expected: Vec<u8> = (0..10).chain([200, 201]).chain(100..105).collect();
        assert_eq!(all, expected);
        assert_eq!(s.piece_start(3), 12);
        s.seek(SeekFrom::Start(9)).unwrap();
        let mut three = [0u8; 4];
        s.read_exact(&mut three).unwrap();
        assert_eq!(three, [9, 200, 201, 100]);
        s.seek(SeekFrom::End(-1)).unwrap();
        s.read_exact(&mut three[..1]).unwrap();
        assert_eq!(three[0], 104);
        assert!(s.seek(SeekFrom::Current(-100)).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
