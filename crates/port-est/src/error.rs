//! The errors of `port-est`: every one names the file it is about and, where the file is at
//! fault, the `file:line:column` of the offending text.

use std::fmt;
use std::path::{Path, PathBuf};

use estimators::EstimatorError;

/// A position in a file: 1-based line and column (columns count characters, not bytes; a
/// UTF-8 byte-order mark is not counted).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    /// The file, as the user named it.
    pub path: PathBuf,
    /// 1-based line.
    pub line: u64,
    /// 1-based column, in characters.
    pub column: u64,
}

impl Location {
    /// `path:line:column`.
    #[must_use]
    pub fn new(path: &Path, line: u64, column: u64) -> Self {
        Self { path: path.to_owned(), line, column }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.path.display(), self.line, self.column)
    }
}

/// Everything `port-est` can reject. Displayed as one line (the binary prefixes `error: `).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file (or directory) concerned.
        path: PathBuf,
        /// What the operating system said.
        #[source]
        source: std::io::Error,
    },
    /// Malformed content at a known place of a file (model or data).
    #[error("{at}: {message}")]
    At {
        /// Where.
        at: Location,
        /// What is wrong and what was expected.
        message: String,
    },
    /// Malformed content of a file without a more precise place.
    #[error("{}: {message}", path.display())]
    File {
        /// The file.
        path: PathBuf,
        /// What is wrong and what was expected.
        message: String,
    },
    /// The estimator rejected a step (an input outside the declared box, a numerical failure…).
    #[error("{at}: step k = {k}: {source}")]
    Step {
        /// The data row (its `k` cell, or the cell at fault).
        at: Location,
        /// The row's `k`.
        k: u64,
        /// The estimator's complaint.
        #[source]
        source: EstimatorError,
    },
    /// The estimator could not be built for a reason that is not the model file's (for example
    /// an SDP backend that failed to start).
    #[error("{0}")]
    Estimator(#[source] EstimatorError),
    /// `--output` names the input or the model file.
    #[error("refusing to overwrite the {role} file: --output {} is --{role} {}", output.display(), other.display())]
    SameFile {
        /// `"input"` or `"model"`.
        role: &'static str,
        /// The output path as given.
        output: PathBuf,
        /// The other path as given.
        other: PathBuf,
    },
    /// `--output` cannot be written (a directory, a read-only file, a missing directory…).
    #[error("--output {}: {message}", path.display())]
    Output {
        /// The output path as given.
        path: PathBuf,
        /// Why it cannot be written.
        message: String,
    },
    /// A choice of options that does not make sense (an unknown estimator or solver, `--solver`
    /// for an estimator without one).
    #[error("{0}")]
    Usage(String),
    /// A model written as equations is malformed (at its `file:line:column`), or cannot be
    /// compiled within its limits.
    #[error("{0}")]
    Equations(#[from] equation_models::EquationError),
    /// A file read whole is larger than the limit (`--max-file-size`).
    #[error(
        "{}: larger than {}, the limit for a {what} (raise it with --max-file-size)",
        path.display(),
        estimators::registry::show_bytes(u128::from(*limit))
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Its role (`model file`, `settings file`, `rule file`).
        what: &'static str,
        /// The limit in bytes.
        limit: u64,
    },
    /// The rule file (`--fis`) made a step fail (a noise scale the filter cannot use).
    #[error("{}: {message} (at {at}, step k = {k}: the rule file's output, not the row, is the cause)", path.display())]
    RuleFile {
        /// The rule file, or `<built-in system>`.
        path: PathBuf,
        /// What went wrong.
        message: String,
        /// The data row where it happened.
        at: Location,
        /// The row's `k`.
        k: u64,
    },
    /// A run stopped at an error; what was done with the steps before it
    /// (`--on-error keep-partial`).
    #[error("{source} ({kept})")]
    Stopped {
        /// Why the run stopped.
        #[source]
        source: Box<Error>,
        /// What became of the steps before it.
        kept: Kept,
    },
}

/// What became of the steps written before a run stopped (`--on-error keep-partial`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Kept {
    /// They are in this file (named `OUT.partial.csv`).
    Partial {
        /// The partial file.
        path: PathBuf,
        /// Steps (rows) it holds.
        steps: u64,
    },
    /// They were streamed to a device or pipe as they were computed.
    Streamed {
        /// The output.
        path: PathBuf,
        /// Steps written.
        steps: u64,
    },
    /// Nothing was kept: no step had succeeded, or the partial file could not be written.
    Nothing {
        /// Why.
        reason: String,
    },
}

impl fmt::Display for Kept {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Kept::Partial { path, steps } => {
                write!(f, "the {steps} steps before it are kept in {}; the output was not written", path.display())
            }
            Kept::Streamed { path, steps } => {
                write!(f, "the {steps} steps before it were written to {}", path.display())
            }
            Kept::Nothing { reason } => write!(f, "nothing kept: {reason}"),
        }
    }
}

impl Error {
    /// The `file:line:column` of the error, if it has one.
    #[must_use]
    pub fn location(&self) -> Option<&Location> {
        match self {
            Error::At { at, .. } | Error::Step { at, .. } | Error::RuleFile { at, .. } => Some(at),
            Error::Stopped { source, .. } => source.location(),
            _ => None,
        }
    }

    pub(crate) fn at(at: Location, message: impl Into<String>) -> Self {
        Error::At { at, message: message.into() }
    }

    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        Error::Io { path: path.to_owned(), source }
    }
}

/// A cell or key as echoed in an error: quoted, at most [`ECHO_CHARS`] characters (longer text is
/// cut with `…`), so that a runaway cell cannot flood the terminal.
pub(crate) fn echo(s: &str) -> String {
    match s.char_indices().nth(ECHO_CHARS) {
        None => format!("{s:?}"),
        Some((cut, _)) => format!("{:?}…", &s[..cut]),
    }
}

/// How many characters of a cell an error message shows.
pub const ECHO_CHARS: usize = 40;

/// 1-based line and column (in characters) of a byte offset of `text`.
pub(crate) fn line_col(text: &str, offset: usize) -> (u64, u64) {
    let mut end = offset.min(text.len());
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    let before = &text[..end];
    let line = before.matches('\n').count() + 1;
    let col = before[before.rfind('\n').map_or(0, |i| i + 1)..].chars().count() + 1;
    (line as u64, col as u64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn echo_quotes_and_truncates() {
        assert_eq!(echo("abc"), "\"abc\"");
        let long = "é".repeat(100);
        let e = echo(&long);
        assert_eq!(e, format!("{:?}…", "é".repeat(ECHO_CHARS)));
    }

    #[test]
    fn location_displays_as_file_line_column() {
        let e = Error::at(Location::new(Path::new("d.csv"), 3, 7), "bad");
        assert_eq!(e.to_string(), "d.csv:3:7: bad");
        assert_eq!(e.location().map(|l| (l.line, l.column)), Some((3, 7)));
    }
}
