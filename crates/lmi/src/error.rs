//! Errors of the `lmi` crate: bad input or bad settings only. An infeasible or unsolved problem
//! is an outcome ([`crate::SolveStatus`]), not an error.

/// Everything that can be wrong with what a caller passes to this crate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LmiError {
    /// The problem data are inconsistent (index out of range, NaN, lower-triangle entry…).
    #[error("invalid problem: {0}")]
    InvalidProblem(String),
    /// A vector or matrix has the wrong size.
    #[error("dimension mismatch for {what}: expected {expected}, found {found}")]
    DimensionMismatch {
        /// What has the wrong size.
        what: &'static str,
        /// The size that was expected.
        expected: usize,
        /// The size that was given.
        found: usize,
    },
    /// A solver setting is out of range.
    #[error("invalid setting {name}: {reason}")]
    InvalidSetting {
        /// The setting's name.
        name: &'static str,
        /// Why the value is rejected.
        reason: String,
    },
    /// `solve` was called with a problem whose structure differs from the one given to `setup`,
    /// or before `setup`.
    #[error("structure mismatch: {0}")]
    StructureMismatch(String),
    /// A matrix argument that must be symmetric positive definite is not.
    #[error("{0} is not symmetric positive definite")]
    NotPositiveDefinite(&'static str),
    /// A variable handle does not belong to this builder or map.
    #[error("unknown variable: {0}")]
    UnknownVariable(String),
    /// An SDPA file could not be read.
    #[error("SDPA format error at line {line}: {message}")]
    Sdpa {
        /// 1-based line number where the problem was found (0 for I/O errors).
        line: usize,
        /// What was expected and what was found.
        message: String,
    },
    /// The backend itself failed to set up (for example, an internal solver rejected the data).
    #[error("backend {backend}: {message}")]
    Backend {
        /// The backend's name.
        backend: &'static str,
        /// The backend's message.
        message: String,
    },
}
