//! The crate's error type.

use thiserror::Error;

/// Everything that can go wrong in this crate. Every variant names the offending parameter or
/// quantity, so that the message alone locates the problem.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum CarError {
    /// A scalar parameter is NaN or infinite, not positive or negative (the message names it).
    #[error(transparent)]
    Parameter(#[from] models::validate::ParamError),
    /// A model tool of the `models` crate failed (discretisation, a non-finite matrix, a noise
    /// box).
    #[error(transparent)]
    Model(#[from] models::ModelError),
}

impl From<CarError> for models::ModelError {
    /// Car errors reach generic code (the simulator, estimators) as evaluation errors with the
    /// car's message.
    fn from(e: CarError) -> Self {
        match e {
            CarError::Model(inner) => inner,
            other => models::ModelError::Evaluation(other.to_string()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use models::validate::ParamError;

    #[test]
    fn car_errors_become_model_errors_with_their_message() {
        let e = CarError::Parameter(ParamError::NotPositive { name: "m (mass)", value: -1.0 });
        assert_eq!(
            models::ModelError::from(e),
            models::ModelError::Evaluation("parameter m (mass) must be positive, got -1".to_owned())
        );
        let inner = models::ModelError::InvalidSamplingPeriod(0.0);
        assert_eq!(models::ModelError::from(CarError::Model(inner.clone())), inner);
    }
}
