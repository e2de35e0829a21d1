//! Errors of the controller and the reference generator.

use thiserror::Error;

/// Everything the controller can reject. A failed call changes nothing.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum ControlError {
    /// A scalar parameter is out of range.
    #[error("parameter {name} = {value}: must be {requirement}")]
    InvalidParameter {
        /// Symbol and meaning of the parameter.
        name: &'static str,
        /// The rejected value.
        value: f64,
        /// What it must satisfy.
        requirement: &'static str,
    },
    /// A vector has the wrong length.
    #[error("dimension mismatch for {what}: expected {expected}, found {found}")]
    DimensionMismatch {
        /// What has the wrong size.
        what: &'static str,
        /// The expected length.
        expected: usize,
        /// The given length.
        found: usize,
    },
    /// A state, reference or result entry is NaN or infinite.
    #[error("{what} has a non-finite entry at index {index}")]
    NonFinite {
        /// Which vector.
        what: &'static str,
        /// Index of the first offending entry.
        index: usize,
    },
    /// The vessel's parameters are invalid.
    #[error("vessel: {0}")]
    Vessel(#[from] vessel_dynamics::VesselError),
    /// A model tool failed (the reference filter's discretisation).
    #[error("model: {0}")]
    Model(#[from] models::ModelError),
}

/// `Ok` if every entry is finite, else the error naming `what`.
pub(crate) fn check_finite(what: &'static str, v: &[f64]) -> Result<(), ControlError> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(index) => Err(ControlError::NonFinite { what, index }),
        None => Ok(()),
    }
}
