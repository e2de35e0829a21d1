//! The crate's error type.

use thiserror::Error;

/// Everything that can go wrong in this crate. Every variant names the offending parameter,
/// matrix or step, so that the message alone locates the problem.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum DynamicsError {
    /// A scalar parameter is NaN or infinite, not positive or negative (the message names it).
    #[error(transparent)]
    Parameter(#[from] models::validate::ParamError),
    /// The roll inertia about the CG, `I_x = I_xeq − m h²`, is not positive: no rigid body has
    /// such inertias (parallel-axis theorem). This is the literal reading of Table 1.
    #[error(
        "roll inertia about the CG I_x = I_xeq - m h^2 = {i_x} must be positive \
         (I_xeq = {i_xeq}, m h^2 = {m_h2}): non-physical parameters"
    )]
    NonPhysicalRollInertia {
        /// The given roll inertia about the roll axis `I_xeq`.
        i_xeq: f64,
        /// `m h²`.
        m_h2: f64,
        /// The resulting `I_x = I_xeq − m h²`.
        i_x: f64,
    },
    /// The load model covers 0, 1 or 2 containers only.
    #[error("unsupported load of {containers} containers: the load model covers 0, 1 or 2")]
    UnsupportedLoad {
        /// The requested number of containers.
        containers: usize,
    },
    /// A model tool of the `models` crate failed (discretisation, a non-finite matrix).
    #[error(transparent)]
    Model(#[from] models::ModelError),
}

impl From<DynamicsError> for models::ModelError {
    /// Carrier errors reach generic code (the simulator, estimators) as evaluation errors with
    /// the carrier's message.
    fn from(e: DynamicsError) -> Self {
        match e {
            DynamicsError::Model(inner) => inner,
            other => models::ModelError::Evaluation(other.to_string()),
        }
    }
}

pub(crate) use models::error::check_finite;
