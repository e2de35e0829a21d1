//! Reading and writing the SDPA sparse format (`.dat-s`), the format of SDPLIB.
//!
//! # Format
//!
//! A file states an [`SdpProblem`] in SDPA standard form (see [`crate::problem`]):
//!
//! ```text
//! "optional comment lines, starting with " or *
//! 3 =mdim                  number m of variables (text after the first number is ignored)
//! 2 =nblocks               number of blocks (text after the first number is ignored)
//! {2, -3}                  the block sizes, on one line: k > 0 is a dense PSD block of order k,
//!                          -k a diagonal block of k nonnegative scalars
//! 48 -8 20                 the vector c: m numbers (they may continue on following lines)
//! 0 1 1 1 -11              one entry per line: matno blkno i j value
//! 1 2 3 3 1.0D+00          (1-based; matno 0 is F0; upper triangle i <= j)
//! ```
//!
//! * Comment lines (first non-blank character `"` or `*`) are allowed only before the header.
//!   Blank lines are skipped everywhere.
//! * The characters `, ( ) { }` are punctuation and read as whitespace, on every line.
//! * Integers (m, the number of blocks, the block sizes, `matno blkno i j`) must be integer
//!   literals (`2`, not `2.0`). Reals accept Rust's float syntax plus Fortran exponents
//!   (`1.0D+00`, `1d-3`); values must be finite.
//! * On the lines of m and of the number of blocks, everything after the first number is
//!   ignored (`21 =mdim`). After the last block size and after the last coefficient of `c`
//!   the rest of the line is ignored too, unless it starts with a number: a surplus number
//!   means that a count is wrong or a value is missing, and is an error.
//! * Each entry line holds exactly five fields. Entries must be in the upper triangle
//!   (`i <= j`); entries of a diagonal block must be on its diagonal; an entry may not be given
//!   twice (none of the SDPLIB problems repeats one). Explicit zero values are kept as entries.
//!
//! Entries become 0-based [`Entry`] values (`matno` stays as is: it is already `0` for `F₀` and
//! `i` for `Fᵢ`).
//!
//! # Limits
//!
//! A header is checked against these limits before anything is allocated from it, so a corrupt
//! or hostile file cannot make the reader allocate absurd amounts. Vectors sized by header counts
//! are preallocated to at most a small capacity and grow as numbers actually arrive; the memory
//! used is proportional to the length of the input.
//!
//! * m ≤ [`MAX_VARS`] (m = 0 is allowed: a pure feasibility problem);
//! * 1 ≤ number of blocks ≤ [`MAX_BLOCKS`];
//! * 1 ≤ order of each block ≤ [`MAX_BLOCK_SIZE`];
//! * the dense storage the block structure implies, `Σ n(n+1)/2` over PSD blocks plus `Σ n`
//!   over diagonal blocks, is at most [`MAX_TOTAL_ENTRIES`] (10⁷, i.e. 80 MB per dense copy; a
//!   solver holds several). A single PSD block is therefore of order at most 4 471.
//!
//! Everything else the reader allocates (the coefficients, the block list, the entries and the
//! table of positions seen) grows with the numbers actually present in the input. What a
//! *solver* needs for the problem read (for example the `m²` Schur matrix of an interior-point
//! method, 320 GB for a file of under a megabyte declaring m = 200 000) is not limited here:
//! each backend checks it in `setup` against
//! [`SolverSettings::memory_limit_bytes`](crate::SolverSettings::memory_limit_bytes).
//!
//! # Errors
//!
//! Malformed input gives [`LmiError::Sdpa`] with the 1-based line number where the problem was
//! found and a message saying what was expected and what was found. A file that ends too early
//! is reported at the line after its last line. The reader never panics.

use std::collections::HashMap;
use std::collections::hash_map::Entry as MapEntry;
use std::fmt::Write as _;
use std::path::Path;

use crate::error::LmiError;
use crate::problem::{Block, Entry, SdpProblem};

/// Largest number m of variables the reader accepts.
pub const MAX_VARS: usize = 10_000_000;
/// Largest number of blocks the reader accepts.
pub const MAX_BLOCKS: usize = 1_000_000;
/// Largest order of one block (PSD or diagonal) the reader accepts.
pub const MAX_BLOCK_SIZE: usize = 100_000;
/// Largest total number of independent entries of one block-diagonal matrix
/// (`Σ n(n+1)/2` over PSD blocks plus `Σ n` over diagonal blocks) the reader accepts.
pub const MAX_TOTAL_ENTRIES: u64 = 10_000_000;

/// Largest capacity preallocated from a header count; beyond it vectors grow as data arrive.
const PREALLOC_CAP: usize = 1024;

/// Parses a problem in SDPA sparse format (see the [module documentation](self)).
///
/// Errors are [`LmiError::Sdpa`] with the 1-based line number and what was expected.
pub fn read_sdpa(text: &str) -> Result<SdpProblem, LmiError> {
    let mut r = Reader { lines: text.lines(), line_no: 0 };

    // Number of variables m, after optional comment lines.
    let (ln, tok) = loop {
        let Some((n, line)) = r.next_line() else {
            return Err(r.eof("the number of variables m"));
        };
        let t = line.trim_start();
        if t.starts_with('"') || t.starts_with('*') {
            continue;
        }
        if let Some(tok) = tokens(line).next() {
            break (n, tok);
        }
    };
    let m = parse_count(tok, ln, "the number of variables m", 0, MAX_VARS)?;

    // Number of blocks.
    let Some((ln, line)) = r.next_nonblank() else {
        return Err(r.eof("the number of blocks"));
    };
    let tok = tokens(line).next().unwrap_or("");
    let nblocks = parse_count(tok, ln, "the number of blocks", 1, MAX_BLOCKS)?;

    // Block sizes, on one line.
    let Some((ln, line)) = r.next_nonblank() else {
        return Err(r.eof(&format!("the {nblocks} block sizes")));
    };
    let mut blocks = Vec::with_capacity(nblocks.min(PREALLOC_CAP));
    let mut total: u64 = 0;
    let mut it = tokens(line);
    for k in 1..=nblocks {
        let Some(tok) = it.next() else {
            return Err(err(ln, format!("expected {nblocks} block sizes on this line, found {}", k - 1)));
        };
        let Some(v) = parse_int(tok) else {
            return Err(err(ln, format!("expected block size {k} of {nblocks} (an integer), found `{tok}`")));
        };
        if v == 0 {
            return Err(err(ln, format!("block size {k} is zero")));
        }
        let n = v.unsigned_abs();
        if n > MAX_BLOCK_SIZE as u64 {
            return Err(err(ln, format!("block size {k} = {v} exceeds the limit {MAX_BLOCK_SIZE}")));
        }
        // n <= MAX_BLOCK_SIZE, so these conversions and products cannot overflow.
        let n = n as usize;
        let block = if v > 0 { Block::Psd(n) } else { Block::Nonneg(n) };
        total += block.num_entries() as u64;
        if total > MAX_TOTAL_ENTRIES {
            return Err(err(
                ln,
                format!(
                    "the block sizes up to block {k} imply {total} matrix entries, which exceeds \
                     the limit {MAX_TOTAL_ENTRIES}"
                ),
            ));
        }
        blocks.push(block);
    }
    if let Some(tok) = it.next().filter(|t| parse_real(t).is_some()) {
        return Err(err(ln, format!("more than {nblocks} block sizes on this line (found `{tok}`)")));
    }

    // The vector c: m numbers, possibly over several lines.
    let mut c = Vec::with_capacity(m.min(PREALLOC_CAP));
    while c.len() < m {
        let Some((ln, line)) = r.next_nonblank() else {
            return Err(r.eof(&format!("objective coefficient {} of m = {m}", c.len() + 1)));
        };
        let mut it = tokens(line);
        while c.len() < m {
            let Some(tok) = it.next() else { break };
            let k = c.len() + 1;
            let Some(v) = parse_real(tok) else {
                return Err(err(
                    ln,
                    format!("expected objective coefficient {k} of m = {m} (a number), found `{tok}`"),
                ));
            };
            if !v.is_finite() {
                return Err(err(ln, format!("objective coefficient {k} is not finite (`{tok}`)")));
            }
            c.push(v);
        }
        if c.len() == m {
            if let Some(tok) = it.next().filter(|t| parse_real(t).is_some()) {
                return Err(err(
                    ln,
                    format!(
                        "more numbers than the m = {m} objective coefficients (found `{tok}`): is m \
                         wrong or a coefficient missing?"
                    ),
                ));
            }
        }
    }

    // Entries, one per line.
    let mut entries = Vec::new();
    let mut seen: HashMap<(usize, usize, usize, usize), usize> = HashMap::new();
    while let Some((ln, line)) = r.next_nonblank() {
        let mut fields = [""; 5];
        let mut count = 0;
        for tok in tokens(line) {
            if let Some(f) = fields.get_mut(count) {
                *f = tok;
            }
            count += 1;
        }
        if count != 5 {
            return Err(err(ln, format!("expected an entry `matno blkno i j value` (5 fields), found {count} fields")));
        }
        let [f_mat, f_blk, f_i, f_j, f_val] = fields;
        let mat = parse_index(f_mat, ln, "matno")?;
        let blk = parse_index(f_blk, ln, "blkno")?;
        let i = parse_index(f_i, ln, "i")?;
        let j = parse_index(f_j, ln, "j")?;
        let Some(value) = parse_real(f_val) else {
            return Err(err(ln, format!("expected the entry value (a number), found `{f_val}`")));
        };
        if mat < 0 || mat > m as i64 {
            return Err(err(ln, format!("matno {mat} is out of range 0..={m}")));
        }
        if blk < 1 || blk > nblocks as i64 {
            return Err(err(ln, format!("blkno {blk} is out of range 1..={nblocks}")));
        }
        let block_index = (blk - 1) as usize;
        let block = blocks[block_index];
        let n = block.size();
        for (name, v) in [("i", i), ("j", j)] {
            if v < 1 || v > n as i64 {
                return Err(err(ln, format!("{name} = {v} is out of range 1..={n} for block {blk} of size {n}")));
            }
        }
        if i > j {
            return Err(err(
                ln,
                format!("lower-triangle entry i = {i} > j = {j} (SDPA files give the upper triangle, i <= j)"),
            ));
        }
        if matches!(block, Block::Nonneg(_)) && i != j {
            return Err(err(ln, format!("off-diagonal entry (i = {i}, j = {j}) in diagonal block {blk}")));
        }
        if !value.is_finite() {
            return Err(err(ln, format!("entry value is not finite (`{f_val}`)")));
        }
        let entry =
            Entry { mat: mat as usize, block: block_index, row: (i - 1) as usize, col: (j - 1) as usize, value };
        match seen.entry((entry.mat, entry.block, entry.row, entry.col)) {
            MapEntry::Occupied(first) => {
                return Err(err(
                    ln,
                    format!(
                        "duplicate entry matno {mat}, blkno {blk}, i {i}, j {j} (first given on line {})",
                        first.get()
                    ),
                ));
            }
            MapEntry::Vacant(slot) => {
                slot.insert(ln);
            }
        }
        entries.push(entry);
    }

    SdpProblem::new(blocks, c, entries)
}

/// Reads a file in SDPA sparse format with [`read_sdpa`].
///
/// An I/O error (missing file, not UTF-8…) is an [`LmiError::Sdpa`] at line 0 naming the path;
/// format errors name the path in their message.
pub fn read_sdpa_file(path: &Path) -> Result<SdpProblem, LmiError> {
    let text = std::fs::read_to_string(path).map_err(|e| err(0, format!("cannot read {}: {e}", path.display())))?;
    read_sdpa(&text).map_err(|e| match e {
        LmiError::Sdpa { line, message } => {
            LmiError::Sdpa { line, message: format!("{message} (in {})", path.display()) }
        }
        other => other,
    })
}

/// Writes a problem in SDPA sparse format; [`read_sdpa`] reads it back to an equal problem.
///
/// Diagonal blocks get negative sizes; values are printed with `{:e}`, the shortest form that
/// reads back to the same `f64`. Indices are 1-based, entries in the problem's order.
pub fn write_sdpa(problem: &SdpProblem) -> String {
    let mut s = String::new();
    // Writing to a `String` cannot fail, so the `fmt::Result`s below are always `Ok`.
    let _ = writeln!(s, "{}", problem.num_vars());
    let _ = writeln!(s, "{}", problem.blocks().len());
    for (k, b) in problem.blocks().iter().enumerate() {
        let sep = if k == 0 { "" } else { " " };
        let _ = match *b {
            Block::Psd(n) => write!(s, "{sep}{n}"),
            Block::Nonneg(n) => write!(s, "{sep}-{n}"),
        };
    }
    s.push('\n');
    for (k, v) in problem.c().iter().enumerate() {
        let sep = if k == 0 { "" } else { " " };
        let _ = write!(s, "{sep}{v:e}");
    }
    s.push('\n');
    for e in problem.entries() {
        let _ = writeln!(s, "{} {} {} {} {:e}", e.mat, e.block + 1, e.row + 1, e.col + 1, e.value);
    }
    s
}

fn err(line: usize, message: impl Into<String>) -> LmiError {
    LmiError::Sdpa { line, message: message.into() }
}

/// Splits a line into tokens at whitespace and the punctuation `, ( ) { }`.
fn tokens(line: &str) -> impl Iterator<Item = &str> {
    line.split(|ch: char| ch.is_whitespace() || matches!(ch, ',' | '(' | ')' | '{' | '}')).filter(|t| !t.is_empty())
}

/// An integer literal (optional sign, decimal digits); out-of-range literals saturate to
/// `i64::MIN`/`i64::MAX` so that they are reported as exceeding a limit.
fn parse_int(tok: &str) -> Option<i64> {
    let digits = tok.strip_prefix(['+', '-']).unwrap_or(tok);
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    Some(tok.parse().unwrap_or(if tok.starts_with('-') { i64::MIN } else { i64::MAX }))
}

/// A real number; `D`/`d` is accepted as the exponent marker (Fortran style).
fn parse_real(tok: &str) -> Option<f64> {
    if tok.contains(['d', 'D']) { tok.replace(['d', 'D'], "e").parse().ok() } else { tok.parse().ok() }
}

/// A header count in `min..=max`.
fn parse_count(tok: &str, line: usize, what: &str, min: usize, max: usize) -> Result<usize, LmiError> {
    let Some(v) = parse_int(tok) else {
        return Err(err(line, format!("expected {what} (an integer), found `{tok}`")));
    };
    if v < min as i64 {
        return Err(err(line, format!("{what} must be at least {min}, found {v}")));
    }
    if v > max as i64 {
        return Err(err(line, format!("{what} = {v} exceeds the limit {max}")));
    }
    Ok(v as usize)
}

/// An integer field of an entry line (range checked by the caller).
fn parse_index(tok: &str, line: usize, what: &str) -> Result<i64, LmiError> {
    parse_int(tok).ok_or_else(|| err(line, format!("expected {what} (an integer), found `{tok}`")))
}

/// Line cursor that counts 1-based line numbers.
struct Reader<'a> {
    lines: std::str::Lines<'a>,
    /// Number of lines consumed so far (the number of the last line returned).
    line_no: usize,
}

impl<'a> Reader<'a> {
    fn next_line(&mut self) -> Option<(usize, &'a str)> {
        let line = self.lines.next()?;
        self.line_no += 1;
        Some((self.line_no, line))
    }

    /// The next line holding at least one token.
    fn next_nonblank(&mut self) -> Option<(usize, &'a str)> {
        loop {
            let (n, line) = self.next_line()?;
            if tokens(line).next().is_some() {
                return Some((n, line));
            }
        }
    }

    /// The error for input that ends where `expected` should come, at the line after the last.
    fn eof(&self, expected: &str) -> LmiError {
        err(self.line_no + 1, format!("unexpected end of input: expected {expected}"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    /// The SDPA manual's example, with a diagonal block added.
    const EXAMPLE: &str = "\"Example 1: mDim = 3, nBLOCK = 2, {2, -2}\"\n\
        * another comment\n\
        \n\
        3 =mDIM\n\
        2 =nBLOCK\n\
        {2, -2} = bLOCKsTRUCT\n\
        {48, -8, 20}\n\
        0 1 1 1 -11\n\
        0 1 2 2 23\n\
        \n\
        1 1 1 1 10\n\
        1 1 1 2 4\n\
        2 1 2 2 -8\n\
        3 1 1 2 -1\n\
        3 1 2 2 -3\n\
        3 2 2 2 1.5D+00\n";

    fn read_err(text: &str) -> (usize, String) {
        match read_sdpa(text) {
            Err(LmiError::Sdpa { line, message }) => (line, message),
            other => panic!("expected an SDPA error for {text:?}, got {other:?}"),
        }
    }

    /// Asserts that `text` fails at `line` with a message containing `keyword`.
    fn assert_err(text: &str, line: usize, keyword: &str) {
        let (l, msg) = read_err(text);
        assert_eq!(l, line, "line for {text:?}: {msg}");
        assert!(msg.contains(keyword), "message for {text:?} lacks `{keyword}`: {msg}");
    }

    /// A valid header for m = 2 and blocks {2, -2}, followed by `rest`.
    fn with_header(rest: &str) -> String {
        format!("2\n2\n2 -2\n1.0 2.0\n{rest}")
    }

    #[test]
    fn reads_the_manual_example_with_comments_punctuation_and_fortran_exponents() {
        let p = read_sdpa(EXAMPLE).unwrap();
        assert_eq!(p.num_vars(), 3);
        assert_eq!(p.blocks(), &[Block::Psd(2), Block::Nonneg(2)]);
        assert_eq!(p.c(), &[48.0, -8.0, 20.0]);
        assert_eq!(p.entries().len(), 8);
        let last = p.entries().last().unwrap();
        assert_eq!((last.mat, last.block, last.row, last.col, last.value), (3, 1, 1, 1, 1.5));
        let e = p.entries().iter().find(|e| e.mat == 1 && e.row == 0 && e.col == 1).unwrap();
        assert_eq!((e.block, e.value), (0, 4.0));
        // CRLF line ends and c spread over several lines.
        let p2 = read_sdpa(&EXAMPLE.replace("{48, -8, 20}", "48\n-8 (20)").replace('\n', "\r\n")).unwrap();
        assert_eq!(p2, p);
    }

    #[test]
    fn writes_one_based_negative_diagonal_sizes_and_round_trips() {
        let p = read_sdpa(EXAMPLE).unwrap();
        let text = write_sdpa(&p);
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("3"));
        assert_eq!(lines.next(), Some("2"));
        assert_eq!(lines.next(), Some("2 -2"));
        assert_eq!(lines.next(), Some("4.8e1 -8e0 2e1"));
        assert_eq!(lines.next(), Some("0 1 1 1 -1.1e1"));
        assert_eq!(read_sdpa(&text).unwrap(), p);

        // Awkward values survive bit for bit; m = 0 and no entries round trip too.
        let vals = [0.1, 1.0 / 3.0, -1e-300, 5e-324, f64::MAX, -f64::MIN_POSITIVE, 123456789.0123];
        let entries =
            vals.iter().enumerate().map(|(k, &v)| Entry { mat: k % 3, block: 0, row: 0, col: k, value: v }).collect();
        let p = SdpProblem::new(vec![Block::Psd(7), Block::Nonneg(1)], vec![0.1, -2.5e-17], entries).unwrap();
        let q = read_sdpa(&write_sdpa(&p)).unwrap();
        assert_eq!(q, p);
        for (a, b) in p.entries().iter().zip(q.entries()) {
            assert_eq!(a.value.to_bits(), b.value.to_bits());
        }
        let empty = SdpProblem::new(vec![Block::Nonneg(3)], vec![], vec![]).unwrap();
        assert_eq!(read_sdpa(&write_sdpa(&empty)).unwrap(), empty);
    }

    #[test]
    fn truncated_and_garbled_headers_name_the_line() {
        assert_err("", 1, "end of input");
        assert_err("\"only a comment\n* and another\n", 3, "number of variables");
        assert_err("2\n", 2, "number of blocks");
        assert_err("2\n1\n", 3, "block sizes");
        assert_err("2\n2\n3\n1 2\n", 3, "expected 2 block sizes on this line, found 1");
        assert_err("2\n1\n3\n", 4, "objective coefficient 1 of m = 2");
        assert_err("2\n1\n3\n1.0\n", 5, "end of input");
        // A missing coefficient makes the first entry line supply it: the surplus is reported.
        assert_err("2\n1\n3\n1.0\n0 1 1 1 1.0\n", 5, "more numbers than the m = 2");
        assert_err("2\n1\n3\n1.0 2.0 3.0\n", 4, "more numbers");
        assert_err("2\n1\n3 4\n1.0 2.0\n", 3, "more than 1 block sizes");
        assert_err("two\n", 1, "expected the number of variables m (an integer), found `two`");
        assert_err("2.5\n", 1, "integer");
        assert_err("2\nx\n", 2, "number of blocks (an integer)");
        assert_err("2\n1\nabc\n", 3, "block size 1 of 1");
        assert_err("2\n1\n2.0\n", 3, "block size 1 of 1 (an integer), found `2.0`");
        assert_err("2\n1\n3\n1.0 x\n", 4, "objective coefficient 2 of m = 2 (a number), found `x`");
        assert_err("2\n1\n3\n1.0 nan\n", 4, "not finite");
        assert_err("2\n1\n3\n1.0\ninf\n", 5, "not finite");
        // Comments are only allowed before the header.
        assert_err("2\n\"c\n", 2, "number of blocks");
        // Trailing text on header lines is ignored.
        let p = read_sdpa("2 =mdim 7\n1 =nblocks\n3 =sizes\n1.0 2.0 =c\n").unwrap();
        assert_eq!((p.num_vars(), p.blocks(), p.entries().len()), (2, &[Block::Psd(3)][..], 0));
    }

    #[test]
    fn absurd_or_invalid_sizes_are_rejected_before_allocating() {
        assert_err("1000000000000000\n1\n1\n", 1, "exceeds the limit 10000000");
        assert_err("99999999999999999999999999\n", 1, "exceeds the limit");
        assert_err("-3\n1\n1\n", 1, "must be at least 0, found -3");
        assert_err("-99999999999999999999999\n", 1, "must be at least 0");
        assert_err("2\n1000000000000000\n", 2, "number of blocks = 1000000000000000 exceeds the limit");
        assert_err("2\n0\n", 2, "number of blocks must be at least 1, found 0");
        assert_err("2\n-1\n", 2, "must be at least 1");
        assert_err("2\n2\n1 1000000000000\n", 3, "block size 2 = 1000000000000 exceeds the limit 100000");
        assert_err("2\n1\n-1000000000000\n", 3, "exceeds the limit");
        assert_err("2\n2\n4 0\n", 3, "block size 2 is zero");
        // 5 000 is a legal order but a dense block of that order is too much storage.
        assert_err("2\n1\n5000\n", 3, "exceeds the limit 10000000");
        // The largest PSD block within the limit is accepted (here: a problem with no entries).
        assert!(!matches!(read_sdpa("1\n1\n4471\n1\n"), Err(e) if e.to_string().contains("exceeds the limit")));
        let many = vec!["-100000"; 101].join(" ");
        assert_err(&format!("2\n101\n{many}\n"), 3, "up to block 101");
        // m at the limit is accepted as a header; the missing c is reported at end of input.
        assert_err("10000000\n1\n1\n", 4, "objective coefficient 1 of m = 10000000");
    }

    #[test]
    fn malformed_entries_name_the_line() {
        assert_err(&with_header("0 1 1 1\n"), 5, "5 fields), found 4 fields");
        assert_err(&with_header("0 1 1 1 1.0\n0 1 1 2 1.0 7\n"), 6, "found 6 fields");
        assert_err(&with_header("0 1 1 1 abc\n"), 5, "entry value (a number), found `abc`");
        assert_err(&with_header("x 1 1 1 1.0\n"), 5, "matno (an integer), found `x`");
        assert_err(&with_header("1.0 1 1 1 1.0\n"), 5, "matno (an integer)");
        assert_err(&with_header("0 one 1 1 1.0\n"), 5, "blkno (an integer)");
        assert_err(&with_header("0 1 1.5 1 1.0\n"), 5, "i (an integer)");
        assert_err(&with_header("0 1 1 2e0 1.0\n"), 5, "j (an integer)");
        assert_err(&with_header("3 1 1 1 1.0\n"), 5, "matno 3 is out of range 0..=2");
        assert_err(&with_header("-1 1 1 1 1.0\n"), 5, "matno -1 is out of range");
        assert_err(&with_header("0 3 1 1 1.0\n"), 5, "blkno 3 is out of range 1..=2");
        assert_err(&with_header("0 0 1 1 1.0\n"), 5, "blkno 0 is out of range");
        assert_err(&with_header("0 1 0 1 1.0\n"), 5, "i = 0 is out of range 1..=2");
        assert_err(&with_header("0 1 1 0 1.0\n"), 5, "j = 0 is out of range");
        assert_err(&with_header("0 1 1 3 1.0\n"), 5, "j = 3 is out of range 1..=2 for block 1");
        assert_err(&with_header("0 2 3 3 1.0\n"), 5, "i = 3 is out of range");
        assert_err(&with_header("0 1 99999999999999999999 1 1.0\n"), 5, "out of range");
        assert_err(&with_header("0 1 2 1 1.0\n"), 5, "lower-triangle entry i = 2 > j = 1");
        assert_err(&with_header("0 2 1 2 1.0\n"), 5, "off-diagonal entry (i = 1, j = 2) in diagonal block 2");
        assert_err(&with_header("0 1 1 1 NaN\n"), 5, "not finite");
        assert_err(&with_header("0 1 1 1 -inf\n"), 5, "not finite");
        assert_err(&with_header("0 1 1 1 1e400\n"), 5, "not finite");
        assert_err(&with_header("\"late comment\n"), 5, "5 fields");
        assert_err(&with_header("0 1 1 2 1.0\n\n1 1 1 1 1.0\n0 1 1 2 2.0\n"), 8, "first given on line 5");
        let (_, msg) = read_err(&with_header("1 2 2 2 1.0\n1 2 2 2 1.0\n"));
        assert!(msg.contains("duplicate entry matno 1, blkno 2, i 2, j 2"), "{msg}");
        // The first error in file order is the one reported.
        assert_err(&with_header("0 1 1 1 1.0\n0 1 1 1 1.0\n9 1 1 1 1.0\n"), 6, "duplicate");
    }

    #[test]
    fn never_panics_on_truncated_or_mutated_input() {
        let base = write_sdpa(&read_sdpa(EXAMPLE).unwrap());
        for cut in 0..=base.len() {
            let _ = read_sdpa(&base[..cut]);
        }
        let junk = [b'0', b'9', b'-', b' ', b'\n', b'e', b'D', b'.', b'{', b'"', b'x', b'+'];
        let mut state: u64 = 0x2545_f491_4f6c_dd1d;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for _ in 0..2000 {
            let mut bytes = base.clone().into_bytes();
            for _ in 0..1 + next() % 3 {
                let pos = (next() % bytes.len() as u64) as usize;
                bytes[pos] = junk[(next() % junk.len() as u64) as usize];
            }
            let text = String::from_utf8(bytes).unwrap();
            if let Err(e) = read_sdpa(&text) {
                assert!(matches!(e, LmiError::Sdpa { .. }), "{e}");
            }
        }
    }

    #[test]
    fn file_errors_name_the_path() {
        let missing = Path::new("/nonexistent/dir/problem.dat-s");
        match read_sdpa_file(missing) {
            Err(LmiError::Sdpa { line, message }) => {
                assert_eq!(line, 0);
                assert!(message.contains("cannot read /nonexistent/dir/problem.dat-s"), "{message}");
            }
            other => panic!("expected an I/O error, got {other:?}"),
        }
        let dir = std::env::temp_dir().join(format!("lmi-sdpa-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("bad.dat-s");
        std::fs::write(&path, "2\n1\n0\n").unwrap();
        let res = read_sdpa_file(&path);
        std::fs::write(&path, EXAMPLE).unwrap();
        let ok = read_sdpa_file(&path);
        std::fs::remove_dir_all(&dir).unwrap();
        match res {
            Err(LmiError::Sdpa { line, message }) => {
                assert_eq!(line, 3);
                assert!(message.contains("zero") && message.contains("bad.dat-s"), "{message}");
            }
            other => panic!("expected a format error, got {other:?}"),
        }
        assert_eq!(ok.unwrap(), read_sdpa(EXAMPLE).unwrap());
    }

    fn sdplib_dir() -> PathBuf {
        match std::env::var_os("SDPLIB_DIR") {
            Some(d) => PathBuf::from(d),
            None => Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/sdplib"),
        }
    }

    #[test]
    fn sdplib_files_parse_with_the_documented_sizes_and_round_trip() {
        let dir = sdplib_dir();
        if !dir.is_dir() {
            eprintln!("skipping SDPLIB test: {} not found (set SDPLIB_DIR)", dir.display());
            return;
        }
        let (p5, h5) = (Block::Psd(5), Block::Psd(6));
        let expected: &[(&str, usize, &[Block])] = &[
            ("control1", 21, &[Block::Psd(10), p5]),
            ("hinf1", 13, &[Block::Psd(4), Block::Psd(4), h5]),
            ("hinf2", 13, &[p5, p5, h5]),
            ("hinf3", 13, &[p5, p5, h5]),
            ("hinf4", 13, &[p5, p5, h5]),
            ("hinf5", 13, &[p5, p5, h5]),
            ("truss1", 6, &[Block::Psd(2); 6]),
            ("truss3", 27, &[p5; 6]),
            ("theta1", 104, &[Block::Psd(50)]),
            ("infp1", 10, &[Block::Psd(30)]),
            ("infd1", 10, &[Block::Psd(30)]),
        ];
        for &(name, m, blocks) in expected {
            let path = dir.join(format!("{name}.dat-s"));
            let p = read_sdpa_file(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(p.num_vars(), m, "{name}");
            let got = p.blocks();
            if name.starts_with("truss") {
                // The truss problems end with a 1×1 block.
                assert_eq!(&got[..6], blocks, "{name}");
                assert_eq!(&got[6..], &[Block::Psd(1)], "{name}");
            } else {
                assert_eq!(got, blocks, "{name}");
            }
        }
        let mut files: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "dat-s"))
            .collect();
        files.sort();
        assert!(files.len() >= expected.len(), "{files:?}");
        for path in &files {
            let text = std::fs::read_to_string(path).unwrap();
            let p = read_sdpa(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            // Every nonblank line after the four header lines is one entry.
            let entry_lines = text.lines().skip(4).filter(|l| !l.trim().is_empty()).count();
            assert_eq!(p.entries().len(), entry_lines, "{}", path.display());
            assert_eq!(read_sdpa(&write_sdpa(&p)).unwrap(), p, "{}", path.display());
        }
    }
}
