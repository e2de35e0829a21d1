//! Backends by name, for command lines and for tests that run against every backend.

use crate::error::LmiError;
use crate::solver::{SdpBackend, SolverSettings};

/// Names of the backends compiled into this build, the default first.
pub fn backend_names() -> Vec<&'static str> {
    let mut names = Vec::new();
    #[cfg(feature = "clarabel")]
    names.push("clarabel");
    names
}

/// The backend called `name`, with the given settings.
pub fn backend_by_name(name: &str, settings: SolverSettings) -> Result<Box<dyn SdpBackend>, LmiError> {
    match name {
        #[cfg(feature = "clarabel")]
        "clarabel" => Ok(Box::new(crate::ClarabelBackend::new(settings)?)),
        _ => {
            let _ = settings;
            Err(LmiError::InvalidSetting {
                name: "backend",
                reason: format!("unknown backend {name:?}; available: {}", backend_names().join(", ")),
            })
        }
    }
}
