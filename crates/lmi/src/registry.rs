//! Backends by name, for command lines and for tests that run against every backend.

use crate::error::LmiError;
use crate::solver::{SdpBackend, SolverSettings};

/// Name of the default backend (pure Rust, always compiled).
pub const DEFAULT_BACKEND: &str = "faer-ipm";

/// Names of the backends compiled into this build, the default first.
pub fn backend_names() -> Vec<&'static str> {
    #[allow(unused_mut)]
    let mut names = vec![DEFAULT_BACKEND];
    #[cfg(feature = "clarabel")]
    names.push("clarabel");
    names
}

/// The backend called `name`, with the given settings.
pub fn backend_by_name(name: &str, settings: SolverSettings) -> Result<Box<dyn SdpBackend>, LmiError> {
    match name {
        DEFAULT_BACKEND => Ok(Box::new(crate::FaerIpm::new(settings)?)),
        #[cfg(feature = "clarabel")]
        "clarabel" => Ok(Box::new(crate::ClarabelBackend::new(settings)?)),
        _ => Err(LmiError::InvalidSetting {
            name: "backend",
            reason: format!("unknown backend {name:?}; available: {}", backend_names().join(", ")),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_backend_is_a_named_error() {
        let err = backend_by_name("nope", SolverSettings::default()).err().unwrap().to_string();
        assert!(err.contains("unknown backend \"nope\"") && err.contains(DEFAULT_BACKEND), "{err}");
        assert_eq!(backend_names()[0], DEFAULT_BACKEND);
    }
}
