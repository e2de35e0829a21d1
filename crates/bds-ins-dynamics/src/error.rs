//! The crate's error type.

use thiserror::Error;

/// Everything that can go wrong in this crate. Every variant names the offending parameter or
/// quantity, so that the message alone locates the problem.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum BdsInsError {
    /// A scalar parameter is NaN or infinite, not positive or negative (the message names it).
    #[error(transparent)]
    Parameter(#[from] models::validate::ParamError),
    /// A parameter lies outside the range the model is valid for.
    #[error("parameter {name} = {value} is outside [{lo}, {hi}]")]
    OutOfRange {
        /// Symbol and meaning of the parameter.
        name: &'static str,
        /// The rejected value.
        value: f64,
        /// Lower end of the valid range.
        lo: f64,
        /// Upper end of the valid range.
        hi: f64,
    },
    /// A zone of the BDS error simulator is invalid (the message names the zone and why).
    #[error("BDS zone {index} ({name}): {reason}")]
    InvalidZone {
        /// 0-based position of the zone.
        index: usize,
        /// The zone's name.
        name: String,
        /// What is wrong.
        reason: String,
    },
    /// A vector has the wrong length.
    #[error("{what}: expected length {expected}, got {found}")]
    DimensionMismatch {
        /// Which vector.
        what: &'static str,
        /// The expected length.
        expected: usize,
        /// The given length.
        found: usize,
    },
    /// A covariance used for sampling is not symmetric positive semidefinite.
    #[error("{what} is not symmetric positive semidefinite (smallest eigenvalue {min_eigenvalue:e})")]
    NotPositiveSemidefinite {
        /// Which matrix.
        what: &'static str,
        /// Its smallest eigenvalue.
        min_eigenvalue: f64,
    },
    /// A model tool of the `models` crate failed (matrix exponential, Van Loan).
    #[error(transparent)]
    Model(#[from] models::ModelError),
}

impl From<BdsInsError> for models::ModelError {
    /// Errors reach generic code (the simulator, estimators) as evaluation errors with this
    /// crate's message.
    fn from(e: BdsInsError) -> Self {
        match e {
            BdsInsError::Model(inner) => inner,
            other => models::ModelError::Evaluation(other.to_string()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use models::validate::ParamError;
    use models::validate::{non_negative, positive};

    #[test]
    fn errors_become_model_errors_with_their_message() {
        let e = BdsInsError::Parameter(ParamError::NotPositive { name: "g (gravity)", value: -1.0 });
        assert_eq!(
            models::ModelError::from(e),
            models::ModelError::Evaluation("parameter g (gravity) must be positive, got -1".to_owned())
        );
        let inner = models::ModelError::InvalidSamplingPeriod(0.0);
        assert_eq!(models::ModelError::from(BdsInsError::Model(inner.clone())), inner);
        assert!(positive("x", f64::NAN).is_err() && positive("x", 0.0).is_err() && positive("x", 1.0).is_ok());
        assert!(non_negative("x", -1e-300).is_err() && non_negative("x", 0.0).is_ok());
    }
}
