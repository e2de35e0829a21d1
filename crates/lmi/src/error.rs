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
    /// Setting the problem up would need more memory than
    /// [`SolverSettings::memory_limit_bytes`](crate::SolverSettings::memory_limit_bytes);
    /// nothing was allocated.
    #[error(
        "backend {backend}: the problem needs about {} of memory, more than the limit of {} \
         (SolverSettings::memory_limit_bytes)",
        human_bytes(*required_bytes),
        human_bytes(*limit_bytes)
    )]
    MemoryLimit {
        /// The backend's name.
        backend: &'static str,
        /// Bytes the setup and the solution would need (an estimate from the problem's sizes,
        /// saturating at `u64::MAX`).
        required_bytes: u64,
        /// The configured limit in bytes.
        limit_bytes: u64,
    },
    /// A third-party solver panicked inside the backend during `setup`; the panic was contained
    /// and the backend is not set up. (A panic during `solve` ends the solve with
    /// [`SolveStatus::NumericalTrouble`](crate::SolveStatus::NumericalTrouble) instead.)
    #[error("backend {backend} panicked: {message}")]
    BackendPanic {
        /// The backend's name.
        backend: &'static str,
        /// The panic message.
        message: String,
    },
}

/// `bytes` in binary units with three significant digits (`"320 GiB"`, `"1.50 MiB"`).
pub(crate) fn human_bytes(bytes: u64) -> String {
    const UNITS: [&str; 7] = ["bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    let mut v = bytes as f64;
    let mut unit = 0;
    while v >= 1024.0 && unit + 1 < UNITS.len() {
        v /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} bytes")
    } else if v >= 100.0 {
        format!("{v:.0} {}", UNITS[unit])
    } else if v >= 10.0 {
        format!("{v:.1} {}", UNITS[unit])
    } else {
        format!("{v:.2} {}", UNITS[unit])
    }
}

/// A byte count computed in `u128` (no overflow for any `usize` sizes), saturated to `u64`.
pub(crate) fn saturate_bytes(bytes: u128) -> u64 {
    u64::try_from(bytes).unwrap_or(u64::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn byte_counts_are_readable() {
        assert_eq!(human_bytes(512), "512 bytes");
        assert_eq!(human_bytes(1536), "1.50 KiB");
        assert_eq!(human_bytes(2 << 30), "2.00 GiB");
        assert_eq!(human_bytes(320_000_000_000), "298 GiB");
        assert_eq!(human_bytes(u64::MAX), "16.0 EiB");
        assert_eq!(saturate_bytes(u128::MAX), u64::MAX);
        let e = LmiError::MemoryLimit { backend: "faer-ipm", required_bytes: 3 << 30, limit_bytes: 2 << 30 };
        assert_eq!(
            e.to_string(),
            "backend faer-ipm: the problem needs about 3.00 GiB of memory, more than the limit of 2.00 GiB \
             (SolverSettings::memory_limit_bytes)"
        );
    }
}
