//! `DATA.csv`: header `k,u1,…,up,y1,…,ym`, then one row per step holding `k`, the input `u_k`
//! and the measurement `y_{k+1}` taken after it. Read with the `csv` crate one row at a time
//! (cells trimmed, blank lines skipped, quoted cells allowed, a UTF-8 byte-order mark ignored);
//! a bad cell is reported at its `file:line:column`.
//!
//! The `csv` crate gives the byte offset of each record; to name the column of a bad cell the
//! reader keeps the raw bytes of the current record (and of `csv`'s read-ahead) as they stream
//! past, and on an error finds the cell's first non-blank character in them. Positions are
//! exact with padding, quotes, CRLF line ends and a byte-order mark, and the input may be a
//! pipe: nothing is read twice.

use std::fs::File;
use std::io::{self, Cursor, Read};
use std::ops::Range;
use std::path::{Path, PathBuf};

use csv::StringRecord;
use nalgebra::DVector;

use crate::error::{Error, Location, echo};

const BOM: &[u8] = b"\xEF\xBB\xBF";

/// Forgotten bytes are dropped from the front of the kept buffer in chunks of at least this
/// size (amortised: no copy per row).
const FORGET_CHUNK: usize = 64 * 1024;

/// A stream that keeps the bytes read from it since a given offset, so that the raw text of the
/// current record can be looked at after `csv` has parsed it.
#[derive(Debug)]
struct Recording<R> {
    inner: R,
    kept: Vec<u8>,
    /// Stream offset of `kept[0]`.
    kept_from: u64,
}

/// The longest record (line) accepted: the kept bytes of one record beyond this are an error, so
/// that an endless line (`--input /dev/zero`) cannot grow memory without bound.
pub const MAX_RECORD_BYTES: usize = 1 << 20;

impl<R: Read> Read for Recording<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        if self.kept.len() > MAX_RECORD_BYTES + FORGET_CHUNK {
            return Err(io::Error::new(
                io::ErrorKind::InvalidData,
                format!("a line longer than {} MiB: not a data file of this format", MAX_RECORD_BYTES >> 20),
            ));
        }
        let n = self.inner.read(buf)?;
        self.kept.extend_from_slice(&buf[..n]);
        Ok(n)
    }
}

impl<R> Recording<R> {
    /// The bytes before stream offset `offset` are no longer needed.
    fn forget_before(&mut self, offset: u64) {
        let drop = usize::try_from(offset.saturating_sub(self.kept_from)).unwrap_or(usize::MAX).min(self.kept.len());
        if drop >= FORGET_CHUNK || drop == self.kept.len() {
            self.kept.drain(..drop);
            self.kept_from += drop as u64;
        }
    }

    /// The kept bytes of `range` (stream offsets), as far as they are kept.
    fn raw(&self, range: Range<u64>) -> &[u8] {
        let at = |x: u64| usize::try_from(x.saturating_sub(self.kept_from)).unwrap_or(usize::MAX).min(self.kept.len());
        &self.kept[at(range.start)..at(range.end.max(range.start))]
    }
}

/// One row of `DATA.csv`, reused from row to row.
#[derive(Debug, Clone, PartialEq)]
pub struct DataRow {
    /// The row's `k`.
    pub k: u64,
    /// `u_k` (p entries).
    pub u: DVector<f64>,
    /// `y_{k+1}` (m entries; 0 where not measured).
    pub y: DVector<f64>,
    /// Which outputs the row measured (an empty cell is not measured, where the reader allows it:
    /// [`DataReader::set_allow_empty_outputs`]).
    pub measured: Vec<bool>,
}

impl DataRow {
    /// A zero row for `p` inputs and `m` outputs, every output measured.
    #[must_use]
    pub fn zeros(p: usize, m: usize) -> Self {
        Self { k: 0, u: DVector::zeros(p), y: DVector::zeros(m), measured: vec![true; m] }
    }

    /// Whether every output was measured.
    #[must_use]
    pub fn complete(&self) -> bool {
        self.measured.iter().all(|&b| b)
    }
}

/// Where the rows of a run come from: a CSV log ([`DataReader`]) or a ROS 2 bag
/// ([`crate::bag::BagRows`]). Columns are `k`, the inputs, the outputs (and any extra the
/// estimator reads); a position names a row and a column of that table.
pub trait RowSource {
    /// Reads the next row into `row`; `false` at the end.
    ///
    /// # Errors
    /// A malformed row, at its position.
    fn read_row(&mut self, row: &mut DataRow) -> Result<bool, Error>;
    /// The position of `column` (0-based; `None` for the row itself) of the last row read.
    fn locate(&self, column: Option<usize>) -> Location;
    /// The columns' names: `k`, inputs, outputs.
    fn columns(&self) -> &[String];
    /// The number of inputs `p`.
    fn inputs(&self) -> usize;
    /// The time (ns) of the estimate of the last row read (`x_{k+1}`), where the source has a
    /// clock (a bag read at a fixed step); `None` for a CSV log.
    fn estimate_time_ns(&self) -> Option<i64> {
        None
    }
}

impl<R: Read> RowSource for DataReader<R> {
    fn read_row(&mut self, row: &mut DataRow) -> Result<bool, Error> {
        DataReader::read_row(self, row)
    }
    fn locate(&self, column: Option<usize>) -> Location {
        DataReader::locate(self, column)
    }
    fn columns(&self) -> &[String] {
        DataReader::columns(self)
    }
    fn inputs(&self) -> usize {
        DataReader::inputs(self)
    }
}

/// Reads `DATA.csv` row by row for a model with `p` inputs and `m` outputs, from any stream
/// (a file, a pipe, memory).
#[derive(Debug)]
pub struct DataReader<R: Read> {
    csv: csv::Reader<Recording<io::Chain<Cursor<Vec<u8>>, R>>>,
    path: PathBuf,
    /// `k`, `u1`…, `y1`…, or the model's names where the header uses them.
    names: Vec<String>,
    /// The model's name of each column, where it has one.
    aliases: Vec<Option<String>>,
    p: usize,
    record: StringRecord,
    /// Start (as `csv` gives it: possibly before skipped blank lines) and end of the last record.
    start: csv::Position,
    end: u64,
    header_line: u64,
    rows: u64,
    /// `k` of the previous data row.
    last_k: Option<u64>,
    /// Whether `k` may skip values (the caller bridges the gap).
    allow_gaps: bool,
    /// The most missing steps accepted at one gap.
    max_gap: u64,
    /// Whether an output cell may be empty (a partial measurement).
    allow_empty_outputs: bool,
    /// The file's column of each name (`k`, inputs, outputs), and the number of columns.
    column_of: Vec<usize>,
    width: usize,
    /// Header cells that name nothing the model reads (ignored), with their file columns.
    ignored: Vec<(usize, String)>,
}

impl DataReader<File> {
    /// Opens `path` and checks its header against the model's `p` inputs and `m` outputs.
    ///
    /// # Errors
    /// [`Error::Io`] if the file cannot be read; [`Error::At`] for an empty file or a header
    /// that is not `k,u1,…,up,y1,…,ym`.
    pub fn open(path: &Path, p: usize, m: usize) -> Result<Self, Error> {
        Self::open_named(path, p, m, None)
    }

    /// As [`DataReader::open`], and the header may name the first inputs and outputs after
    /// `names` (the model's input and output names, in order) instead of `u1…`, `y1…`; columns
    /// beyond them (the fuzzy-adaptive filter's receiver status) keep their positional names.
    ///
    /// # Errors
    /// As [`DataReader::open`].
    pub fn open_named(path: &Path, p: usize, m: usize, names: Option<(&[String], &[String])>) -> Result<Self, Error> {
        let file = File::open(path).map_err(|e| Error::io(path, e))?;
        Self::from_reader_named(path, file, p, m, names)
    }
}

impl<'a> DataReader<&'a [u8]> {
    /// Reads data from memory (`path` names it in errors); see [`DataReader::open`].
    ///
    /// # Errors
    /// As [`DataReader::open`].
    pub fn from_text(path: &Path, text: &'a str, p: usize, m: usize) -> Result<Self, Error> {
        Self::from_reader(path, text.as_bytes(), p, m)
    }

    /// As [`DataReader::from_text`], with the model's column names (see
    /// [`DataReader::open_named`]).
    ///
    /// # Errors
    /// As [`DataReader::open`].
    pub fn from_text_named(
        path: &Path,
        text: &'a str,
        p: usize,
        m: usize,
        names: Option<(&[String], &[String])>,
    ) -> Result<Self, Error> {
        Self::from_reader_named(path, text.as_bytes(), p, m, names)
    }
}

impl<R: Read> DataReader<R> {
    /// Reads data from `reader` (`path` names it in errors); see [`DataReader::open`].
    ///
    /// # Errors
    /// As [`DataReader::open`].
    pub fn from_reader(path: &Path, reader: R, p: usize, m: usize) -> Result<Self, Error> {
        Self::from_reader_named(path, reader, p, m, None)
    }

    /// As [`DataReader::from_reader`], with the model's column names (see
    /// [`DataReader::open_named`]).
    ///
    /// # Errors
    /// As [`DataReader::open`].
    pub fn from_reader_named(
        path: &Path,
        mut reader: R,
        p: usize,
        m: usize,
        model_names: Option<(&[String], &[String])>,
    ) -> Result<Self, Error> {
        // A byte-order mark is dropped before `csv` sees the stream (offsets start after it).
        let mut head = vec![0u8; BOM.len()];
        let mut got = 0;
        while got < head.len() {
            match reader.read(&mut head[got..]) {
                Ok(0) => break,
                Ok(k) => got += k,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) => return Err(Error::io(path, e)),
            }
        }
        head.truncate(got);
        if head == BOM {
            head.clear();
        }
        let source = Recording { inner: Cursor::new(head).chain(reader), kept: Vec::new(), kept_from: 0 };
        let csv = csv::ReaderBuilder::new()
            .has_headers(false) // checked here, to say which cell is wrong
            .flexible(true) // the field count is checked here too
            .trim(csv::Trim::All)
            .from_reader(source);
        let names: Vec<String> = std::iter::once("k".to_owned())
            .chain((1..=p).map(|i| format!("u{i}")))
            .chain((1..=m).map(|i| format!("y{i}")))
            .collect();
        let mut aliases: Vec<Option<String>> = vec![None; names.len()];
        if let Some((inputs, outputs)) = model_names {
            for (j, name) in inputs.iter().take(p).enumerate() {
                aliases[1 + j] = Some(name.clone());
            }
            for (i, name) in outputs.iter().take(m).enumerate() {
                aliases[1 + p + i] = Some(name.clone());
            }
        }
        let mut r = Self {
            csv,
            path: path.to_owned(),
            names,
            aliases,
            p,
            record: StringRecord::new(),
            start: csv::Position::new(),
            end: 0,
            header_line: 1,
            rows: 0,
            last_k: None,
            allow_gaps: false,
            max_gap: crate::limits::DEFAULT_MAX_GAP,
            allow_empty_outputs: false,
            column_of: Vec::new(),
            width: 0,
            ignored: Vec::new(),
        };
        r.read_header()?;
        Ok(r)
    }

    /// Accept rows whose `k` skips values (still strictly increasing): the caller bridges the
    /// missing steps (`port-est filter --gaps bridge`).
    pub fn set_allow_gaps(&mut self, allow: bool) {
        self.allow_gaps = allow;
    }

    /// Whether an output cell may be empty: the output was not measured at that row (a partial
    /// measurement, [`DataRow::measured`]). Off by default: an empty cell is an error at its place.
    pub fn set_allow_empty_outputs(&mut self, allow: bool) {
        self.allow_empty_outputs = allow;
    }

    /// The most missing steps accepted at one gap when gaps are allowed (default
    /// [`crate::limits::DEFAULT_MAX_GAP`]; `--max-gap`): a larger gap is an error at its row,
    /// so that one bad `k` cannot make the caller bridge billions of steps.
    pub fn set_max_gap(&mut self, max_gap: u64) {
        self.max_gap = max_gap;
    }

    /// The number of inputs `p` (the outputs' columns follow them).
    #[must_use]
    pub fn inputs(&self) -> usize {
        self.p
    }

    /// The file's name, as given.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The column names: `k`, `u1`…, `y1`… (or the model's names, where the header uses them).
    #[must_use]
    pub fn columns(&self) -> &[String] {
        &self.names
    }

    /// Number of data rows read so far.
    #[must_use]
    pub fn rows_read(&self) -> u64 {
        self.rows
    }

    /// Reads the next non-blank record; `false` at the end of the file.
    fn next_record(&mut self) -> Result<bool, Error> {
        loop {
            self.csv.get_mut().forget_before(self.end);
            match self.csv.read_record(&mut self.record) {
                Ok(false) => return Ok(false),
                Ok(true) => {
                    self.start = self.record.position().cloned().unwrap_or_else(|| self.csv.position().clone());
                    self.end = self.csv.position().byte();
                    let blank = self.record.len() == 1 && self.record[0].is_empty();
                    if !blank {
                        return Ok(true);
                    }
                }
                Err(e) => return Err(self.csv_error(e)),
            }
        }
    }

    fn csv_error(&mut self, e: csv::Error) -> Error {
        if let csv::ErrorKind::Utf8 { pos, err } = e.kind() {
            let field = err.field();
            self.start = pos.clone().unwrap_or_else(|| self.csv.position().clone());
            self.end = self.csv.position().byte();
            let slot = self.column_of.iter().position(|&c| c == field);
            let name = slot.and_then(|s| self.names.get(s)).map_or("the cell", |s| s.as_str()).to_owned();
            return Error::at(self.locate_file(Some(field)), format!("{name} is not valid UTF-8"));
        }
        let message = e.to_string();
        match e.into_kind() {
            csv::ErrorKind::Io(e) => Error::io(&self.path, e),
            _ => Error::File { path: self.path.clone(), message },
        }
    }

    fn read_header(&mut self) -> Result<(), Error> {
        let expected = self.names.join(",");
        let named: Vec<&str> =
            self.names.iter().zip(&self.aliases).map(|(n, a)| a.as_deref().unwrap_or(n.as_str())).collect();
        let expected = if self.aliases.iter().any(Option::is_some) {
            format!("{expected}` or `{}", named.join(","))
        } else {
            expected
        };
        if !self.next_record()? {
            let at = Location::new(&self.path, 1, 1);
            return Err(Error::at(at, format!("empty file, expected the header `{expected}`")));
        }
        self.header_line = self.locate_file(None).line;
        let (p, m) = (self.p, self.names.len() - 1 - self.p);
        // Columns are matched by name, in any order; other columns are ignored (and listed).
        let mut column_of: Vec<Option<usize>> = vec![None; self.names.len()];
        for (j, got) in self.record.iter().enumerate() {
            let slot = (0..self.names.len()).find(|&s| self.names[s] == got || self.aliases[s].as_deref() == Some(got));
            match slot {
                Some(s) => {
                    if let Some(first) = column_of[s] {
                        let message =
                            format!("column {} appears twice (columns {} and {})", echo(got), first + 1, j + 1);
                        return Err(Error::at(self.locate_file(Some(j)), message));
                    }
                    column_of[s] = Some(j);
                }
                None => self.ignored.push((j, got.to_owned())),
            }
        }
        if let Some(s) = column_of.iter().position(Option::is_none) {
            let want = match &self.aliases[s] {
                Some(alias) => format!("{:?} or {alias:?}", self.names[s]),
                None => format!("{:?}", self.names[s]),
            };
            let mut message = format!(
                "the header has no column {want} (model has p = {p} inputs, m = {m} outputs; expected `{expected}`, in \
                 any order)"
            );
            let unread: Vec<String> =
                self.ignored.iter().map(|(j, g)| format!("{} (column {})", echo(g), j + 1)).collect();
            if !unread.is_empty() {
                message.push_str(&format!("; columns the model does not read: {}", unread.join(", ")));
            }
            // At the first column the model does not read (a misspelt name, most likely).
            let at = self.locate_file(self.ignored.first().map(|(j, _)| *j));
            return Err(Error::at(at, message));
        }
        self.column_of = column_of.into_iter().flatten().collect();
        for (s, &j) in self.column_of.iter().enumerate() {
            if let Some(alias) = &self.aliases[s] {
                if &self.record[j] == alias.as_str() {
                    self.names[s] = alias.clone();
                }
            }
        }
        self.width = self.record.len();
        Ok(())
    }

    /// The header's columns that name nothing the model reads: they are ignored, each with its
    /// column number (1-based) and name.
    #[must_use]
    pub fn ignored_columns(&self) -> Vec<(usize, &str)> {
        self.ignored.iter().map(|(j, name)| (j + 1, name.as_str())).collect()
    }

    /// Refuses a header with a column the model does not read (`--exact-columns`); call before
    /// the first row.
    ///
    /// # Errors
    /// [`Error::At`] at the first such column.
    pub fn require_exact_columns(&self) -> Result<(), Error> {
        match self.ignored.first() {
            Some((j, name)) => {
                let message = format!(
                    "unexpected column {} (expected `{}`; without --exact-columns it would be ignored)",
                    echo(name),
                    self.names.join(",")
                );
                Err(Error::at(self.locate_file(Some(*j)), message))
            }
            None => Ok(()),
        }
    }

    /// Reads the next data row into `row`; `Ok(false)` at the end of the file.
    ///
    /// # Errors
    /// [`Error::At`] for a row with the wrong number of cells, a `k` that is not a nonnegative
    /// integer or does not follow the previous row's `k` by one (a gap, a repeated or a decreasing
    /// `k`), a value that is not a finite number, or a file without data rows;
    /// [`Error::Io`] if reading fails.
    pub fn read_row(&mut self, row: &mut DataRow) -> Result<bool, Error> {
        if !self.next_record()? {
            if self.rows == 0 {
                let at = Location::new(&self.path, self.header_line + 1, 1);
                return Err(Error::at(at, "no data rows after the header"));
            }
            return Ok(false);
        }
        let n = self.names.len();
        if self.record.len() != self.width {
            let message = format!("{} fields, expected {} (as the header)", self.record.len(), self.width);
            return Err(Error::at(self.locate(None), message));
        }
        let ks = &self.record[self.column_of[0]];
        let Ok(k) = ks.parse::<u64>() else {
            let message = format!("k = {} is not a nonnegative integer", echo(ks));
            return Err(Error::at(self.locate(Some(0)), message));
        };
        // One step per row: `k` increases by exactly one. A repeated, decreasing or skipping `k`
        // (duplicated blocks, shuffled rows, concatenated logs, dropped rows) would otherwise be
        // taken as one step each, and a guaranteed set would silently stop being one.
        if let Some(prev) = self.last_k {
            if k <= prev {
                let message = format!(
                    "k = {k} after k = {prev}: k must increase by one from row to row (a repeated or out-of-order row)"
                );
                return Err(Error::at(self.locate(Some(0)), message));
            }
            let missing = k - prev - 1;
            if missing > self.max_gap && self.allow_gaps {
                let message = format!(
                    "k jumps from {prev} to {k}: a gap of {missing} missing steps, more than --max-gap {} (each \
                     missing step is bridged by a predicted output row); raise --max-gap to bridge it",
                    self.max_gap
                );
                return Err(Error::at(self.locate(Some(0)), message));
            }
            if missing > 0 && !self.allow_gaps {
                let message = format!(
                    "k jumps from {prev} to {k}: the rows k = {}..={} are missing (dropped rows or concatenated logs); \
                     k must increase by one from row to row",
                    prev + 1,
                    k - 1
                );
                return Err(Error::at(self.locate(Some(0)), message));
            }
        }
        self.last_k = Some(k);
        if row.u.len() != self.p || row.y.len() != n - 1 - self.p {
            *row = DataRow::zeros(self.p, n - 1 - self.p);
        }
        row.k = k;
        for j in 1..n {
            let s = &self.record[self.column_of[j]];
            if s.trim().is_empty() {
                if j <= self.p {
                    let message = format!("{} is empty: an input must be given at every row", self.names[j]);
                    return Err(Error::at(self.locate(Some(j)), message));
                }
                if !self.allow_empty_outputs {
                    let message = format!(
                        "{} is empty: this command needs every output at every row (`port-est filter` takes \
                         partial measurements)",
                        self.names[j]
                    );
                    return Err(Error::at(self.locate(Some(j)), message));
                }
                row.y[j - 1 - self.p] = 0.0;
                row.measured[j - 1 - self.p] = false;
                continue;
            }
            let v = match s.parse::<f64>() {
                Ok(v) if v.is_finite() => v,
                Ok(_) => {
                    let message = format!("{} = {} is not finite", self.names[j], echo(s));
                    return Err(Error::at(self.locate(Some(j)), message));
                }
                Err(_) => {
                    let message = format!("{} = {} is not a number", self.names[j], echo(s));
                    return Err(Error::at(self.locate(Some(j)), message));
                }
            };
            if j <= self.p {
                row.u[j - 1] = v;
            } else {
                row.y[j - 1 - self.p] = v;
                row.measured[j - 1 - self.p] = true;
            }
        }
        self.rows += 1;
        Ok(true)
    }

    /// Where the last record read starts (`column = None`: its line, column 1) or where its
    /// cell `column` (0 = `k`, then `u1`…, `y1`…) starts, at the cell's first non-blank
    /// character. A missing cell is placed where it would start after one more comma.
    #[must_use]
    pub fn locate(&self, column: Option<usize>) -> Location {
        self.locate_file(column.map(|c| self.column_of.get(c).copied().unwrap_or(c)))
    }

    /// As [`DataReader::locate`], with `column` the file's column.
    fn locate_file(&self, column: Option<usize>) -> Location {
        let raw = self.csv.get_ref().raw(self.start.byte()..self.end);
        let (line, col) = locate_in(&String::from_utf8_lossy(raw), self.start.line(), column);
        Location::new(&self.path, line, col)
    }
}

/// Line and column of cell `field` (or of the record's start) in the raw text of a record that
/// starts on line `line` (the text may begin with the line ends of skipped blank lines). Follows
/// the `csv` crate's defaults: `,` separates, `"` quotes at the start of a cell, `""` escapes.
fn locate_in(raw: &str, mut line: u64, field: Option<usize>) -> (u64, u64) {
    let mut col = 1;
    let mut chars = raw.chars().peekable();
    while let Some(&c) = chars.peek() {
        match c {
            '\n' => (line, col) = (line + 1, 1),
            '\r' => {}
            _ => break,
        }
        chars.next();
    }
    let Some(want) = field else {
        return (line, col);
    };
    let (mut index, mut at_start, mut quoted) = (0, true, false);
    while let Some(c) = chars.next() {
        if index == want && !quoted {
            if at_start && c.is_whitespace() && c != '\n' && c != '\r' {
                col += 1;
                continue;
            }
            return (line, col);
        }
        if quoted {
            if c == '"' {
                if chars.peek() == Some(&'"') {
                    chars.next();
                    col += 1;
                } else {
                    quoted = false;
                }
            }
        } else {
            match c {
                '"' if at_start => quoted = true,
                ',' => {
                    index += 1;
                    at_start = true;
                    col += 1;
                    continue;
                }
                '\n' | '\r' => return (line, col + (want - index) as u64),
                _ => {}
            }
        }
        at_start = false;
        if c == '\n' {
            (line, col) = (line + 1, 1);
        } else {
            col += 1;
        }
    }
    (line, col + want.saturating_sub(index) as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        let p = Path::new("d.csv");
        let result = DataReader::from_text(p, text, 1, 1).and_then(|mut r| {
            let mut row = DataRow::zeros(1, 1);
            while r.read_row(&mut row)? {}
            Ok(())
        });
        result.unwrap_err().to_string()
    }

    #[test]
    fn empty_output_cells_are_unmeasured_only_where_allowed() {
        let text = "k,u1,y1,y2\n0,1, ,2\n1,1,3,\n";
        let p = Path::new("d.csv");
        let mut r = DataReader::from_text(p, text, 1, 2).unwrap();
        let mut row = DataRow::zeros(1, 2);
        let e = r.read_row(&mut row).unwrap_err().to_string();
        assert!(e.starts_with("d.csv:2:") && e.contains("y1 is empty: this command needs every output"), "{e}");
        let mut r = DataReader::from_text(p, text, 1, 2).unwrap();
        r.set_allow_empty_outputs(true);
        assert!(r.read_row(&mut row).unwrap());
        assert_eq!((row.measured.clone(), row.y[1]), (vec![false, true], 2.0));
        assert!(r.read_row(&mut row).unwrap());
        assert_eq!((row.measured.clone(), row.y[0]), (vec![true, false], 3.0));
        assert!(!row.complete());
    }

    fn rows(text: &str) -> Vec<(u64, f64, f64)> {
        let mut r = DataReader::from_text(Path::new("d.csv"), text, 1, 1).unwrap();
        let mut row = DataRow::zeros(1, 1);
        let mut out = Vec::new();
        while r.read_row(&mut row).unwrap() {
            out.push((row.k, row.u[0], row.y[0]));
        }
        out
    }

    #[test]
    fn data_errors_name_line_and_column() {
        assert_eq!(rows("k,u1,y1\n0,1.0,0.5\n1,1.0,0.6\n"), vec![(0, 1.0, 0.5), (1, 1.0, 0.6)]);
        let e = err("k,u1,z1\n");
        assert!(e.starts_with("d.csv:1:6: the header has no column \"y1\""), "{e}");
        assert!(e.contains("does not read: \"z1\" (column 3)"), "{e}");
        let e = err("k,u1,y1\n0,1.0,abc\n");
        assert!(e.starts_with("d.csv:2:7: y1 = \"abc\" is not a number"), "{e}");
        let e = err("k,u1,y1\n0,1.0\n");
        assert!(e.starts_with("d.csv:2:1: 2 fields, expected 3"), "{e}");
        let e = err("k,u1,y1\n-1,1.0,2\n");
        assert!(e.starts_with("d.csv:2:1: k = \"-1\" is not a nonnegative integer"), "{e}");
        let e = err("k,u1,y1\n0,NaN,2\n");
        assert!(e.starts_with("d.csv:2:3: u1 = \"NaN\" is not finite"), "{e}");
        let e = err("");
        assert!(e.starts_with("d.csv:1:1: empty file, expected the header `k,u1,y1`"), "{e}");
        let e = err("k,u1,y1\n");
        assert!(e.starts_with("d.csv:2:1: no data rows"), "{e}");
        let e = err("k,u1\n");
        assert!(e.starts_with("d.csv:1:1: the header has no column \"y1\""), "{e}");
        let e = err("k,y1,u1,y1\n");
        assert!(e.starts_with("d.csv:1:9: column \"y1\" appears twice (columns 2 and 4)"), "{e}");
    }

    #[test]
    fn columns_are_matched_by_name_in_any_order_and_extras_are_ignored_or_refused() {
        assert_eq!(rows("y1,k,u1\n0.5,0,1.0\n0.6,1,2.0\n"), vec![(0, 1.0, 0.5), (1, 2.0, 0.6)]);
        assert_eq!(rows("k,speed,u1,y1,note\n0,9,1.0,0.5,x\n"), vec![(0, 1.0, 0.5)]);
        let r = DataReader::from_text(Path::new("d.csv"), "k,u1,y1,z\n0,1,2,3\n", 1, 1).unwrap();
        assert_eq!(r.ignored_columns(), vec![(4, "z")]);
        let e = r.require_exact_columns().unwrap_err().to_string();
        assert!(e.starts_with("d.csv:1:9: unexpected column \"z\""), "{e}");
        // A value error names the file's column, wherever the name is.
        let e = err("y1,k,u1\n0.5,0,x\n");
        assert!(e.starts_with("d.csv:2:7: u1 = \"x\" is not a number"), "{e}");
        let e = err("y1,k,u1\n0.5,0\n");
        assert!(e.starts_with("d.csv:2:1: 2 fields, expected 3"), "{e}");
    }

    #[test]
    fn padding_blank_lines_crlf_quotes_and_bom_do_not_shift_positions() {
        let e = err(" k , u1 , z1 \n");
        assert!(e.starts_with("d.csv:1:11: the header has no column \"y1\""), "{e}");
        assert_eq!(rows("\u{feff}k,u1,y1\n0,1,2\n"), vec![(0, 1.0, 2.0)]);
        let e = err("\u{feff}k,u1,z1\n");
        assert!(e.starts_with("d.csv:1:6: "), "{e}");
        let e = err("\n  \nk,u1,y1\r\n0,1,2\r\n\r\n \r\n1,1,  x\r\n");
        assert!(e.starts_with("d.csv:7:7: y1 = \"x\""), "{e}");
        let e = err("k,u1,y1\n\"0\",\"a,\"\"b\",1\n2,\"multi\nline\", z\n");
        assert!(e.starts_with("d.csv:2:5: u1 = \"a,\\\"b\" is not a number"), "{e}");
        assert_eq!(rows("k,u1,y1\n\"0\",\" 1.5 \",2\n"), vec![(0, 1.5, 2.0)]);
        let e = err("k,u1,y1\n0,\"multi\nline\", z\n");
        assert!(e.starts_with("d.csv:2:3: "), "{e}");
        let e = err("k,u1,y1\n0,\"1\",\n  \n");
        assert!(e.starts_with("d.csv:2:7: y1 is empty"), "{e}");
    }

    #[test]
    fn an_overlong_cell_is_echoed_truncated() {
        let e = err(&format!("k,u1,y1\n0,1,{}\n", "x".repeat(10_000)));
        assert!(e.starts_with("d.csv:2:5: y1 = \"xxx") && e.len() < 150, "{e}");
    }

    #[test]
    fn positions_stay_exact_deep_into_a_long_file() {
        let mut text = String::from("k,u1,y1\n");
        for k in 0..20_000 {
            text.push_str(&format!("{k},  0.125,\"{}\"\r\n", k % 7));
        }
        assert_eq!(rows(&text).len(), 20_000);
        text.push_str("20000,1,\"two\nlines\"\n20001,  x,1\n");
        let e = err(&text);
        assert!(e.starts_with("d.csv:20002:9: y1 = \"two\\nlines\" is not a number"), "{e}");
        let e = err(&text.replace("\"two\nlines\"", "2"));
        assert!(e.starts_with("d.csv:20003:9: u1 = \"x\" is not a number"), "{e}");
    }

    #[test]
    fn invalid_utf8_is_located() {
        let p = Path::new("d.csv");
        let mut r = DataReader::from_reader(p, &b"k,u1,y1\n0,1,\xff\n"[..], 1, 1).unwrap();
        let e = r.read_row(&mut DataRow::zeros(1, 1)).unwrap_err().to_string();
        assert!(e.starts_with("d.csv:2:5: y1 is not valid UTF-8"), "{e}");
    }

    #[test]
    fn k_must_increase_by_one() {
        let read_all = |text: &str| -> Result<u64, Error> {
            let mut r = DataReader::from_text(Path::new("d.csv"), text, 1, 1)?;
            let mut row = DataRow::zeros(1, 1);
            let mut n = 0;
            while r.read_row(&mut row)? {
                n += 1;
            }
            Ok(n)
        };
        assert_eq!(read_all("k,u1,y1\n7,0,0\n8,0,0\n9,0,0\n").unwrap(), 3);
        let e = read_all("k,u1,y1\n0,0,0\n1,0,0\n4,0,0\n").unwrap_err().to_string();
        assert!(e.starts_with("d.csv:4:1: k jumps from 1 to 4: the rows k = 2..=3 are missing"), "{e}");
        let e = read_all("k,u1,y1\n0,0,0\n1,0,0\n1,0,0\n").unwrap_err().to_string();
        assert!(e.starts_with("d.csv:4:1: k = 1 after k = 1: k must increase by one"), "{e}");
        let e = read_all("k,u1,y1\n5,0,0\n6,0,0\n0,0,0\n1,0,0\n").unwrap_err().to_string();
        assert!(e.starts_with("d.csv:4:1: k = 0 after k = 6"), "{e}");
    }

    #[test]
    fn an_endless_line_is_refused_with_bounded_memory() {
        let endless = std::io::repeat(b'0').take(64 << 20);
        let e = DataReader::from_reader(Path::new("/dev/zero"), endless, 1, 1).unwrap_err().to_string();
        assert!(e.contains("a line longer than 1 MiB"), "{e}");
    }
}
