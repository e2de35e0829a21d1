//! The typed errors of construction, evaluation and loading.

use std::fmt;

/// What is wrong with a fuzzy system's description or with an evaluation's inputs.
///
/// `context` fields name the offending item in words (for example ``input `N`, set `PS` ``); rule
/// indices are 0-based positions in the rule list as given.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum FuzzyError {
    /// A membership function has a NaN corner.
    #[error("{context}: a corner is NaN ({corners:?})")]
    NanCorner {
        /// The set.
        context: String,
        /// Its corners `[a, b, c, d]` (a triangle as `[a, b, b, c]`).
        corners: [f64; 4],
    },
    /// The corners of a triangle or trapezoid are not non-decreasing.
    #[error("{context}: corners must be non-decreasing (a <= b <= c <= d), got {corners:?}")]
    NonMonotoneCorners {
        /// The set.
        context: String,
        /// Its corners `[a, b, c, d]` (a triangle as `[a, b, b, c]`).
        corners: [f64; 4],
    },
    /// An infinite corner that is not a shoulder (`a = b = -inf` or `c = d = +inf` on an input set), or
    /// any infinite corner on an output set.
    #[error(
        "{context}: infinite corners are allowed only as input-set shoulders (a = b = -inf or c = d = inf), got {corners:?}"
    )]
    InfiniteCorner {
        /// The set.
        context: String,
        /// Its corners `[a, b, c, d]`.
        corners: [f64; 4],
    },
    /// An input range or the output universe is empty, reversed, NaN or not finite.
    #[error("{context}: the interval [{lo}, {hi}] must be finite with lo < hi")]
    EmptyRange {
        /// The variable.
        context: String,
        /// Lower end.
        lo: f64,
        /// Upper end.
        hi: f64,
    },
    /// An output set reaches outside the output universe.
    #[error("{context}: the set {corners:?} must lie within the output universe [{lo}, {hi}]")]
    OutputSetOutsideUniverse {
        /// The set.
        context: String,
        /// Its corners.
        corners: [f64; 4],
        /// Universe lower end.
        lo: f64,
        /// Universe upper end.
        hi: f64,
    },
    /// An output set has zero width, hence zero area: it could never move a centroid.
    #[error("{context}: an output set needs a positive width, got {corners:?}")]
    DegenerateOutputSet {
        /// The set.
        context: String,
        /// Its corners.
        corners: [f64; 4],
    },
    /// A variable has no fuzzy sets.
    #[error("{context} has no fuzzy sets")]
    NoSets {
        /// The variable.
        context: String,
    },
    /// Two variables, or two sets of one variable, share a name.
    #[error("{context}: duplicate name `{name}`")]
    DuplicateName {
        /// Where.
        context: String,
        /// The repeated name.
        name: String,
    },
    /// The system has no input variable.
    #[error("the system has no input variables")]
    NoInputs,
    /// The system has no rule.
    #[error("the system has no rules")]
    NoRules,
    /// A rule has no antecedent.
    #[error("rule {rule}: no antecedents")]
    EmptyRule {
        /// 0-based rule index.
        rule: usize,
    },
    /// A rule names an input variable that does not exist.
    #[error("rule {rule}: unknown input variable `{variable}`")]
    UnknownVariable {
        /// 0-based rule index.
        rule: usize,
        /// The name used.
        variable: String,
    },
    /// A rule names a set its variable (input or output) does not have.
    #[error("rule {rule}: variable `{variable}` has no set `{set}`")]
    UnknownSet {
        /// 0-based rule index.
        rule: usize,
        /// The variable.
        variable: String,
        /// The name used.
        set: String,
    },
    /// A rule tests one input twice.
    #[error("rule {rule}: input `{variable}` appears twice")]
    DuplicateAntecedent {
        /// 0-based rule index.
        rule: usize,
        /// The variable.
        variable: String,
    },
    /// The output used when no rule fires is NaN or infinite.
    #[error("the default output {value} must be finite")]
    InvalidDefault {
        /// The value given.
        value: f64,
    },
    /// The output used when no rule fires lies outside the outputs the system can give (the
    /// output universe, through the output scale: `[10^lo, 10^hi]` for a `log10` universe).
    #[error("the default output {value} lies outside the system's outputs [{lo}, {hi}] (the output universe{scale})")]
    DefaultOutsideUniverse {
        /// The value given.
        value: f64,
        /// Smallest output.
        lo: f64,
        /// Largest output.
        hi: f64,
        /// How the universe maps to outputs, in words (empty for a linear scale).
        scale: &'static str,
    },
    /// More rules than a system may have.
    #[error("{count} rules, the limit is {limit} (fuzzy_inference::MAX_RULES)")]
    TooManyRules {
        /// How many were given.
        count: usize,
        /// The limit.
        limit: usize,
    },
    /// An input whose name is none of the quantities the system is bound to.
    #[error("input `{name}` is not one of the quantities this system is fed: {expected}")]
    UnknownInput {
        /// The input's name.
        name: String,
        /// The quantities and their accepted names, in words.
        expected: String,
    },
    /// A quantity the system is fed has no input.
    #[error("no input for {meaning} (name it {names})")]
    MissingInput {
        /// The names accepted for it, in words.
        names: String,
        /// What the quantity is.
        meaning: &'static str,
    },
    /// Two inputs name the same quantity.
    #[error("inputs `{first}` and `{second}` both name {meaning}")]
    DuplicateInput {
        /// The first input's name.
        first: String,
        /// The second input's name.
        second: String,
        /// What the quantity is.
        meaning: &'static str,
    },
    /// The outputs the system can give do not suit its use (a noise scale must be positive and
    /// finite, say).
    #[error("the system's outputs [{lo}, {hi}] (from the output universe) must be {requirement}")]
    OutputRange {
        /// Smallest output.
        lo: f64,
        /// Largest output.
        hi: f64,
        /// What the use needs, in words.
        requirement: &'static str,
    },
    /// More sets than the allocation-free evaluation supports.
    #[error("{what}: {count} sets, the limit is {limit}")]
    TooManySets {
        /// Which sets (all inputs together, or the output).
        what: &'static str,
        /// How many were given.
        count: usize,
        /// The limit.
        limit: usize,
    },
    /// A defuzzifier's parameters are unusable (too few points, a grid too large).
    #[error("defuzzifier: {reason}")]
    InvalidDefuzzifier {
        /// Why.
        reason: String,
    },
    /// `evaluate` got the wrong number of inputs.
    #[error("expected {expected} inputs, got {got}")]
    InputCount {
        /// Number of input variables.
        expected: usize,
        /// Length of the slice given.
        got: usize,
    },
    /// An input is NaN.
    #[error("input {index} (`{name}`) is NaN")]
    NanInput {
        /// 0-based input index.
        index: usize,
        /// The input variable's name.
        name: String,
    },
}

/// A position in a TOML source: `file:line:column` (1-based), or the file alone when the error
/// concerns the whole document.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Location {
    /// The file name (or the origin name given to [`crate::FuzzySystem::from_toml_str`]).
    pub file: String,
    /// 1-based line and column, when known.
    pub line_column: Option<(usize, usize)>,
}

impl Location {
    /// The location of byte `offset` of `text`.
    pub(crate) fn at(file: &str, text: &str, offset: usize) -> Self {
        let offset = offset.min(text.len());
        let before = text.get(..offset).unwrap_or(text);
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let column = before.get(line_start..).map_or(0, |s| s.chars().count()) + 1;
        Self { file: file.to_owned(), line_column: Some((line, column)) }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.line_column {
            Some((line, column)) => write!(f, "{}:{line}:{column}", self.file),
            None => write!(f, "{}", self.file),
        }
    }
}

/// Loading a system from TOML failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LoadError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The path.
        path: String,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// Not valid TOML, or not the expected layout (unknown key, wrong type, missing field).
    #[error("{location}: {message}")]
    Syntax {
        /// Where.
        location: Location,
        /// The TOML parser's message.
        message: String,
    },
    /// The file is larger than a system file may be (it is read whole).
    #[error("{path}: larger than {limit} bytes, the limit for a fuzzy-system file (fuzzy_inference::MAX_FILE_BYTES)")]
    TooLarge {
        /// The path.
        path: String,
        /// The limit in bytes.
        limit: u64,
    },
    /// Well-formed TOML describing an invalid system.
    #[error("{location}: {source}")]
    Invalid {
        /// Where (the offending input, output, set or rule).
        location: Location,
        /// What is wrong.
        #[source]
        source: FuzzyError,
    },
}
