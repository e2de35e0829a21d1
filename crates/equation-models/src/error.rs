//! The crate's errors: every complaint about a model file carries the `file:line:column` of the
//! key it is about.

use std::fmt;

use thiserror::Error;

/// A place in a model file: its name, 1-based line and column (in characters).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Location {
    /// The file's name as given by the caller.
    pub file: String,
    /// 1-based line.
    pub line: u64,
    /// 1-based column, in characters.
    pub column: u64,
}

impl Location {
    /// The location of byte `offset` of `text`, in the file named `file`.
    #[must_use]
    pub fn of_offset(file: &str, text: &str, offset: usize) -> Self {
        let mut end = offset.min(text.len());
        while !text.is_char_boundary(end) {
            end -= 1;
        }
        let before = &text[..end];
        let line = before.matches('\n').count() as u64 + 1;
        let column = before[before.rfind('\n').map_or(0, |i| i + 1)..].chars().count() as u64 + 1;
        Self { file: file.to_owned(), line, column }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file, self.line, self.column)
    }
}

/// Everything that can be wrong with a model file. Each variant says where (the key it is
/// about) and names the equation or name at fault.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum EquationError {
    /// The file is larger than [`crate::limits::MAX_FILE_BYTES`] (refused before parsing).
    #[error("{file}: the model file has {size} bytes, more than the limit of {limit}")]
    FileTooLarge {
        /// The file's name.
        file: String,
        /// Its size in bytes.
        size: usize,
        /// The limit.
        limit: usize,
    },
    /// The file could not be read (or is not UTF-8).
    #[error("{file}: cannot read the model file: {message}")]
    Io {
        /// The file's name.
        file: String,
        /// The system's message.
        message: String,
    },
    /// The file is not valid TOML.
    #[error("{location}: invalid TOML: {message}")]
    Toml {
        /// Where the TOML parser stopped.
        location: Location,
        /// The parser's message.
        message: String,
    },
    /// A key is missing, has the wrong type, or is not part of the format.
    #[error("{location}: {message}")]
    Format {
        /// The key (or table) at fault.
        location: Location,
        /// What is wrong.
        message: String,
    },
    /// A name is declared twice (states, inputs, outputs, parameters and definitions share
    /// one namespace).
    #[error("{location}: `{name}` is declared twice")]
    DuplicateName {
        /// The second declaration.
        location: Location,
        /// The name.
        name: String,
    },
    /// A name is not a valid identifier or clashes with a function or constant of the
    /// expression language.
    #[error("{location}: `{name}` cannot be used as a name: {reason}")]
    InvalidName {
        /// The declaration.
        location: Location,
        /// The name.
        name: String,
        /// Why (a function or constant of that name exists, not an identifier, ...).
        reason: String,
    },
    /// An expression uses a name that is neither a state, an input, a parameter nor an
    /// earlier definition.
    #[error("{location}: equation `{equation}` uses the unknown symbol `{symbol}`")]
    UnknownSymbol {
        /// The equation's key.
        location: Location,
        /// The equation (`f.x`, `h.y`, `definitions.alpha`, ...).
        equation: String,
        /// The unknown name.
        symbol: String,
    },
    /// An expression calls a function the expression language does not have.
    #[error("{location}: equation `{equation}` calls the unknown function `{function}`")]
    UnknownFunction {
        /// The equation's key.
        location: Location,
        /// The equation.
        equation: String,
        /// The function's name.
        function: String,
    },
    /// An expression could not be parsed (or differentiated).
    #[error("{location}: equation `{equation}`: {message}")]
    Parse {
        /// The equation's key.
        location: Location,
        /// The equation.
        equation: String,
        /// What went wrong.
        message: String,
    },
    /// A state (or output) has no equation.
    #[error("{location}: `{name}` has no equation in [{section}]")]
    MissingEquation {
        /// The table that should hold it (or the declaration when the table is absent).
        location: Location,
        /// `f`, `dxdt` or `h`.
        section: String,
        /// The state or output.
        name: String,
    },
    /// An equation is given for a name that is not a declared state (or output).
    #[error("{location}: [{section}] has an equation for `{name}`, which is not a declared {expected}")]
    UnknownTarget {
        /// The equation's key.
        location: Location,
        /// `f`, `dxdt` or `h`.
        section: String,
        /// The equation's name.
        name: String,
        /// `state` or `output`.
        expected: String,
    },
    /// `ts` is missing, not a number, not finite or not positive for a `[dxdt]` model.
    #[error("{location}: {message}")]
    SamplingPeriod {
        /// `ts` or the `[model]` table.
        location: Location,
        /// What is wrong.
        message: String,
    },
    /// An output depends on no state: the states are unobservable from it.
    #[error("{location}: output `{output}` depends on no state (the states are unobservable from it)")]
    Unobservable {
        /// The output's equation.
        location: Location,
        /// The output.
        output: String,
    },
    /// A size limit against hostile input was exceeded (refused before parsing).
    #[error("{location}: {what} is {size}, more than the limit of {limit}")]
    LimitExceeded {
        /// The key at fault.
        location: Location,
        /// What was counted (`the length of equation f.x after substitution`, ...).
        what: String,
        /// The count.
        size: usize,
        /// The limit.
        limit: usize,
    },
    /// Reading and compiling the model file took longer than
    /// [`crate::limits::MAX_COMPILE_SECONDS`] (a safeguard: compiling is linear in the size of
    /// the file, bounded by the [limits](crate::limits), far below the budget).
    #[error("{location}: compiling the model file took more than {seconds} s (simplify the equations)")]
    TooSlow {
        /// The start of the file.
        location: Location,
        /// The budget.
        seconds: u64,
    },
    /// `discretization = "zoh"` for `[dxdt]` equations that are not linear in the states and
    /// inputs.
    #[error("{location}: `discretization = \"zoh\"` needs linear [dxdt] equations: equation `{equation}` {reason}")]
    ZohNotLinear {
        /// The `discretization` key.
        location: Location,
        /// The first equation that is not linear (`dxdt.v`).
        equation: String,
        /// Why (a partial derivative that is not constant, a constant term, ...).
        reason: String,
    },
    /// The zero-order hold of linear `[dxdt]` equations failed (the matrix exponential
    /// overflowed).
    #[error("{location}: the zero-order hold failed: {message}")]
    ZohFailed {
        /// The `discretization` key.
        location: Location,
        /// The failure.
        message: String,
    },
    /// The compiler failed on an equation (a defect caught, not a crash; not produced by the
    /// current compiler, which has no such failure).
    #[error("{location}: equation `{equation}`: the expression library failed: {message}")]
    Internal {
        /// The equation's key.
        location: Location,
        /// The equation.
        equation: String,
        /// The panic's message.
        message: String,
    },
}
