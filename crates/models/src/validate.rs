//! Validation of scalar parameters, shared by the vehicle crates.
//!
//! Each check returns a [`ParamError`] naming the parameter; a vehicle crate's error wraps it in
//! one variant (`Parameter(#[from] ParamError)`, the same message), so `?` works in its validation
//! code:
//!
//! ```
//! use models::validate::{ParamError, positive};
//!
//! assert!(positive("m (mass)", 1500.0).is_ok());
//! let e = positive("m (mass)", 0.0).unwrap_err();
//! assert_eq!(e, ParamError::NotPositive { name: "m (mass)", value: 0.0 });
//! assert_eq!(e.to_string(), "parameter m (mass) must be positive, got 0");
//! ```

use thiserror::Error;

/// A scalar parameter that failed a check. Every variant names the parameter (symbol and
/// meaning) and carries the rejected value.
#[derive(Debug, Clone, Copy, PartialEq, Error)]
#[non_exhaustive]
pub enum ParamError {
    /// The parameter is NaN or infinite.
    #[error("parameter {name} must be finite, got {value}")]
    NonFinite {
        /// Symbol and meaning of the parameter.
        name: &'static str,
        /// The rejected value.
        value: f64,
    },
    /// A parameter that must be strictly positive is zero or negative.
    #[error("parameter {name} must be positive, got {value}")]
    NotPositive {
        /// Symbol and meaning of the parameter.
        name: &'static str,
        /// The rejected value.
        value: f64,
    },
    /// A parameter that must be non-negative is negative.
    #[error("parameter {name} must be non-negative, got {value}")]
    Negative {
        /// Symbol and meaning of the parameter.
        name: &'static str,
        /// The rejected value.
        value: f64,
    },
}

/// `Ok` if `value` is finite, else [`ParamError::NonFinite`] naming `name`.
pub fn finite(name: &'static str, value: f64) -> Result<(), ParamError> {
    if value.is_finite() { Ok(()) } else { Err(ParamError::NonFinite { name, value }) }
}

/// `Ok` if `value` is finite and strictly positive, else the error naming `name`.
pub fn positive(name: &'static str, value: f64) -> Result<(), ParamError> {
    finite(name, value)?;
    if value > 0.0 { Ok(()) } else { Err(ParamError::NotPositive { name, value }) }
}

/// `Ok` if `value` is finite and non-negative, else the error naming `name`.
pub fn non_negative(name: &'static str, value: f64) -> Result<(), ParamError> {
    finite(name, value)?;
    if value >= 0.0 { Ok(()) } else { Err(ParamError::Negative { name, value }) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checks_name_the_parameter_and_the_value() {
        assert_eq!(finite("g", 9.81), Ok(()));
        assert!(matches!(finite("g", f64::NAN), Err(ParamError::NonFinite { name: "g", .. })));
        assert_eq!(finite("g", f64::INFINITY), Err(ParamError::NonFinite { name: "g", value: f64::INFINITY }));

        assert_eq!(positive("m", 1e-300), Ok(()));
        assert_eq!(positive("m", 0.0), Err(ParamError::NotPositive { name: "m", value: 0.0 }));
        assert_eq!(positive("m", -1.0), Err(ParamError::NotPositive { name: "m", value: -1.0 }));
        assert_eq!(
            positive("m", f64::NEG_INFINITY),
            Err(ParamError::NonFinite { name: "m", value: f64::NEG_INFINITY })
        );
        assert!(matches!(positive("m", f64::NAN), Err(ParamError::NonFinite { .. })));

        assert_eq!(non_negative("h", 0.0), Ok(()));
        assert_eq!(non_negative("h", -1e-300), Err(ParamError::Negative { name: "h", value: -1e-300 }));
        assert!(matches!(non_negative("h", f64::NAN), Err(ParamError::NonFinite { .. })));

        assert_eq!(finite("v", f64::NAN).unwrap_err().to_string(), "parameter v must be finite, got NaN");
        assert_eq!(positive("v", -2.5).unwrap_err().to_string(), "parameter v must be positive, got -2.5");
        assert_eq!(non_negative("h", -1.0).unwrap_err().to_string(), "parameter h must be non-negative, got -1");
    }
}
