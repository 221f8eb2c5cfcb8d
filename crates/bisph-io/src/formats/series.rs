//! CSV time series, appended and flushed row by row, so a killed run keeps every completed
//! row.

use crate::formats::files::{at, OutputError};
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::PathBuf;

/// A CSV time series: header first, then one flushed row per call (a killed run keeps every
/// completed row). Its length in bytes is tracked so a resumed run can cut it back to a
/// checkpoint.
pub struct Series {
    path: PathBuf,
    out: BufWriter<File>,
    len: u64,
}

impl Series {
    /// Creates the file with its header.
    pub fn create(path: PathBuf, header: &[String]) -> Result<Self, OutputError> {
        let file = at(&path, File::create(&path))?;
        let mut s = Series {
            path,
            out: BufWriter::new(file),
            len: 0,
        };
        let line = header.join(",");
        s.line(&line)?;
        Ok(s)
    }

    /// Reopens an existing series cut back to its first `len` bytes (a checkpoint's length),
    /// appending after them.
    pub fn reopen(path: PathBuf, len: u64) -> Result<Self, OutputError> {
        let file = at(
            &path,
            std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .open(&path),
        )?;
        let found = at(&path, file.metadata())?.len();
        if found < len {
            return Err(OutputError {
                path,
                source: io::Error::new(
                    io::ErrorKind::UnexpectedEof,
                    format!("the file has {found} bytes, the checkpoint expects {len}"),
                ),
            });
        }
        at(&path, file.set_len(len))?;
        let mut file = file;
        at(&path, io::Seek::seek(&mut file, io::SeekFrom::End(0)))?;
        Ok(Series {
            path,
            out: BufWriter::new(file),
            len,
        })
    }

    /// Bytes written so far (header included).
    pub fn len(&self) -> u64 {
        self.len
    }

    /// `true` before the header is written (never, once created).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    fn line(&mut self, line: &str) -> Result<(), OutputError> {
        at(
            &self.path,
            writeln!(self.out, "{line}").and_then(|_| self.out.flush()),
        )?;
        self.len += line.len() as u64 + 1;
        Ok(())
    }

    /// Appends one row (full precision) and flushes it.
    pub fn row(&mut self, values: &[f64]) -> Result<(), OutputError> {
        let mut line = String::with_capacity(24 * values.len());
        for (k, v) in values.iter().enumerate() {
            if k > 0 {
                line.push(',');
            }
            line.push_str(&format!("{v:e}"));
        }
        self.line(&line)
    }

    /// Appends a row whose second column is a name.
    pub fn named_row(&mut self, t: f64, name: &str, values: &[f64]) -> Result<(), OutputError> {
        let mut line = format!("{t:e},{name}");
        for v in values {
            line.push_str(&format!(",{v:e}"));
        }
        self.line(&line)
    }
}
