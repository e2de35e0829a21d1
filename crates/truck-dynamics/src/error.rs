//! The crate's error type.

use thiserror::Error;

/// Everything that can go wrong in this crate. Every variant names the offending parameter,
/// state, input or tyre quantity, so that the message alone locates the problem.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum TruckError {
    /// A scalar parameter is NaN or infinite, not positive or negative (the message names it).
    #[error(transparent)]
    Parameter(#[from] models::validate::ParamError),
    /// Parameters that are valid one by one but not together (e.g. axle 3 ahead of axle 2).
    #[error("parameter {name}: {reason}")]
    Inconsistent {
        /// Symbol and meaning of the parameter.
        name: &'static str,
        /// What is wrong, with the values involved.
        reason: String,
    },
    /// A state or input handed to a model is NaN or infinite.
    #[error("{name} must be finite, got {value}")]
    NonFiniteInput {
        /// Symbol and meaning of the state or input (e.g. `δ (road-wheel angle)`).
        name: &'static str,
        /// The rejected value.
        value: f64,
    },
    /// A speed the model divides by (or whose sign the slip conventions assume) is zero or
    /// negative.
    #[error("{name} must be positive (the model divides by it / assumes forward motion), got {value}")]
    NonPositiveSpeed {
        /// Symbol and meaning of the speed.
        name: &'static str,
        /// The rejected value.
        value: f64,
    },
    /// The Pac89 coefficient laws give an unusable curve at this load (peak `D ≤ 0`,
    /// stiffness `BCD ≤ 0`, curvature `E > 1`, …): the load is outside the tyre data's range.
    #[error("{curve} Pac89 curve at F_z = {fz_kn} kN per tyre: {quantity} = {value} ({requirement})")]
    TyreOutOfRange {
        /// `"lateral"` or `"longitudinal"`.
        curve: &'static str,
        /// Load per tyre at which the coefficients were evaluated \[kN\].
        fz_kn: f64,
        /// Which Magic Formula factor failed (e.g. `D (peak factor)`).
        quantity: &'static str,
        /// Its value.
        value: f64,
        /// What it must satisfy.
        requirement: &'static str,
    },
    /// No slip within the tyre's monotone range produces the requested force (initial
    /// equilibrium of the truth model).
    #[error("no longitudinal slip of wheel {wheel} within ±{max_slip} gives F_x = {force} N")]
    SlipNotFound {
        /// Wheel name (`L1` … `R3`).
        wheel: &'static str,
        /// Requested force \[N\].
        force: f64,
        /// Searched slip range (unit slip).
        max_slip: f64,
    },
    /// A model tool of the `models` crate failed (dimensions, discretisation).
    #[error(transparent)]
    Model(#[from] models::ModelError),
}

impl From<TruckError> for models::ModelError {
    /// Truck errors reach generic code (the simulator, estimators) as evaluation errors with
    /// the truck's message.
    fn from(e: TruckError) -> Self {
        match e {
            TruckError::Model(inner) => inner,
            other => models::ModelError::Evaluation(other.to_string()),
        }
    }
}

/// `Ok` if the state or input `value` is finite, else the error naming `name`.
pub(crate) fn finite_input(name: &'static str, value: f64) -> Result<(), TruckError> {
    if value.is_finite() { Ok(()) } else { Err(TruckError::NonFiniteInput { name, value }) }
}
