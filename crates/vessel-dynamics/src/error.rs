//! The crate's error type.

use thiserror::Error;

/// Everything that can go wrong in this crate. Every variant names the offending parameter,
/// so that the message alone locates the problem.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum VesselError {
    /// A scalar parameter is NaN or infinite, not positive or negative (the message names it).
    #[error(transparent)]
    Parameter(#[from] models::validate::ParamError),
    /// The SI mass matrix `M` (rigid body plus added mass) is not invertible, or not positive
    /// definite: the model `M ν' = τ − D ν` cannot be solved for `ν'` or stores negative energy.
    #[error("mass matrix M is not positive definite (smallest leading minor {minor:e}); check m11, m22, m33, m23, m32")]
    MassNotPositiveDefinite {
        /// The smallest leading principal minor of the symmetric part of `M`.
        minor: f64,
    },
    /// A model tool of the `models` crate failed (dimensions, discretisation).
    #[error(transparent)]
    Model(#[from] models::ModelError),
}

impl From<VesselError> for models::ModelError {
    /// Vessel errors reach generic code (the simulator, estimators) as evaluation errors with
    /// the vessel's message.
    fn from(e: VesselError) -> Self {
        match e {
            VesselError::Model(inner) => inner,
            other => models::ModelError::Evaluation(other.to_string()),
        }
    }
}
