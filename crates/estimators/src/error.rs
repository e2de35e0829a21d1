//! Errors of the estimators, by kind ([`EstimatorError::kind`]): input refused before any step
//! (named field, row or value), or how a step ended without an estimate to publish (an outlier,
//! data that contradict the noise bounds, a guarantee lost, a numerical failure). A failed call
//! leaves the filter's state unchanged.

use fuzzy_inference::FuzzyError;
use lmi::LmiError;
use models::{Capability, ModelError};

/// Everything a filter can reject.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum EstimatorError {
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
    /// An entry is NaN or infinite.
    #[error("{what} has a non-finite entry at index {index} (column-major)")]
    NonFinite {
        /// Which argument.
        what: &'static str,
        /// Index of the first offending entry (column-major for matrices).
        index: usize,
    },
    /// A matrix that must be symmetric is not (beyond `1e-10` relative).
    #[error("{what} is not symmetric")]
    NotSymmetric {
        /// Which matrix.
        what: &'static str,
    },
    /// A matrix that must be symmetric positive definite is not.
    #[error("{what} is not positive definite")]
    NotPositiveDefinite {
        /// Which matrix.
        what: &'static str,
    },
    /// A matrix that must be symmetric positive semidefinite (a Gaussian filter's `Q`, `P₀`) has
    /// a negative eigenvalue beyond rounding.
    #[error("{what} is not positive semidefinite")]
    NotPositiveSemidefinite {
        /// Which matrix.
        what: &'static str,
    },
    /// The input range of the Yang–Li filter is not a box (`lower ≤ upper`, finite).
    #[error("invalid input bounds at index {index}: lower {lower} > upper {upper} or not finite")]
    InvalidInputBounds {
        /// Input component.
        index: usize,
        /// Lower bound given.
        lower: f64,
        /// Upper bound given.
        upper: f64,
    },
    /// An input given to a filter that treats the input as a bounded disturbance
    /// ([`InputModel::BoundedDisturbance`](crate::smf::InputModel::BoundedDisturbance), the Yang–Li
    /// reconstruction (a)) lies outside the declared box: the guarantee covers only inputs in
    /// the box, so the step is refused.
    #[error("input u[{index}] = {value} is outside the declared input box [{lower}, {upper}]")]
    InputOutsideBounds {
        /// Input component.
        index: usize,
        /// The value given.
        value: f64,
        /// Lower bound of the box.
        lower: f64,
        /// Upper bound of the box.
        upper: f64,
    },
    /// The filter needs at least one state and one output.
    #[error("empty system: {0}")]
    EmptySystem(&'static str),
    /// The step produced a non-finite estimate (for example, an unstable model overflowed).
    #[error("numerical failure: {0}")]
    NumericalFailure(&'static str),
    /// No estimator of this name in the registry.
    #[error("unknown estimator {name:?} (known: {known})")]
    UnknownEstimator {
        /// The name asked for.
        name: String,
        /// The registered names, comma-separated.
        known: String,
    },
    /// No solver of (29) of this name in this build.
    #[error("unknown solver {name:?} (known: {known})")]
    UnknownSolver {
        /// The name asked for.
        name: String,
        /// The solvers of this build, comma-separated.
        known: String,
    },
    /// The estimator needs a setting that was not given (for example the input box of the
    /// Yang–Li reconstruction (a)).
    #[error("estimator {estimator} needs {what}")]
    MissingSetting {
        /// The estimator.
        estimator: &'static str,
        /// What is missing.
        what: &'static str,
    },
    /// The measurement of this step is provably incompatible with the predicted set and the noise
    /// bounds (module [`smf::consistency`](crate::smf::consistency)): a measurement outlier, a
    /// biased sensor, noise beyond its bound or a wrong model. The filter is unchanged.
    #[error(
        "data inconsistent with the noise bounds at step {step}: the measurement lies outside every set the \
         model and the bounds allow (beyond the set's reach by {excess:.3e} of it)"
    )]
    InconsistentData {
        /// The step (1 for the first step of the filter).
        step: u64,
        /// How far outside, relative to the set's extent in the separating direction.
        excess: f64,
    },
    /// A constrained-zonotope filter's measurement (with its noise set) misses the predicted set,
    /// or its certified hull misses the interval observer's box, or `smf-nl`'s interval observer
    /// meets a measurement whose strip misses its box: proved, not a tolerance. The filter is
    /// unchanged.
    #[error("data inconsistent with the noise bounds at step {step}: {reason}")]
    SetMissed {
        /// The step (0 for an update of the initial set).
        step: u64,
        /// What was proved.
        reason: &'static str,
    },
    /// A moving-horizon window whose measurements no disturbance sequence in the process-noise
    /// box fits into the measurement-noise box (docs/robust-mhe.md §2.8): the newest measurement,
    /// or one still in the window, contradicts the model and the boxes. The estimator is
    /// unchanged.
    #[error(
        "data inconsistent with the noise boxes at step {step}: no disturbance sequence within W fits the {samples} \
         measurements of the window into V (V would have to widen by {excess:.3e} of its widths)"
    )]
    InconsistentWindow {
        /// The step (1 for the first step of the estimator).
        step: u64,
        /// The measured samples in the window.
        samples: usize,
        /// How much `V` must widen, in widths, for the window to fit.
        excess: f64,
    },
    /// A Gaussian filter's measurement fails its innovation gate: the normalised innovation
    /// squared exceeds the χ² quantile at the gate's probability (a statistical test under the
    /// filter's own noise model, not a proof). The filter is unchanged.
    #[error(
        "measurement at step {step} is an outlier: normalised innovation squared {nis:.4e} above the gate {threshold:.4} \
         (passed with probability {probability} under the filter's noise model){worst}",
        worst = describe_worst(.worst.as_ref())
    )]
    Outlier {
        /// The step (1 for the first step of the filter).
        step: u64,
        /// `νᵀ S⁻¹ ν`.
        nis: f64,
        /// The χ² quantile.
        threshold: f64,
        /// The gate's probability.
        probability: f64,
        /// The output with the largest innovation in its own standard deviations.
        worst: Option<WorstOutput>,
    },
    /// The nonlinear set-membership filter cannot bound its linearisation remainder at this step
    /// (a function undefined somewhere on the set, an overflow, a remainder beyond its limit): it
    /// publishes no set it cannot certify, and the filter is unchanged.
    #[error("step {step}: no guaranteed set can be published: {reason}")]
    GuaranteeLost {
        /// The step (1 for the first).
        step: u64,
        /// Why, naming the function and the bound.
        reason: String,
    },
    /// The nonlinear set-membership filter's set lies wholly outside the state's declared bounds
    /// ([`NonlinearSetMembershipFilter::with_state_bounds`](crate::NonlinearSetMembershipFilter::with_state_bounds)):
    /// the data, the noise bounds or the state bounds contradict each other. The filter is
    /// unchanged.
    #[error(
        "step {step}: the set's interval [{set_lower:e}, {set_upper:e}] of state {state} lies outside its declared \
         bounds [{bound_lower:e}, {bound_upper:e}]: the data, the noise bounds or the state bounds are wrong"
    )]
    OutsideStateBounds {
        /// The step (1 for the first).
        step: u64,
        /// The state's index (0-based).
        state: usize,
        /// The set's interval of that state (its bounding box).
        set_lower: f64,
        /// Its upper end.
        set_upper: f64,
        /// The declared bounds.
        bound_lower: f64,
        /// Their upper end.
        bound_upper: f64,
    },
    /// A scalar setting of an estimator is out of range (for example the UKF's `α`).
    #[error("invalid setting {what} = {value}: must be {requirement}")]
    InvalidSetting {
        /// Which setting.
        what: &'static str,
        /// The value given (or derived from the settings).
        value: f64,
        /// What it must satisfy.
        requirement: &'static str,
    },
    /// A setting of an estimator is invalid (for example block lengths that do not sum to the
    /// horizon, an empty noise box, or `λv ≤ 1` for the min–max moving-horizon estimator).
    #[error("invalid configuration of {estimator}: {message}")]
    InvalidConfiguration {
        /// The estimator.
        estimator: &'static str,
        /// What is wrong, naming the setting.
        message: String,
    },
    /// [`Estimator::update`](crate::Estimator::update) of an estimator whose update is joint with
    /// its prediction, with no prediction pending.
    #[error(
        "{estimator} has no prediction to update: its update is joint with the prediction ((13)-(29)); call predict \
         before each update, or step"
    )]
    UpdateWithoutPrediction {
        /// The estimator.
        estimator: &'static str,
    },
    /// The estimator does not offer this operation.
    #[error("{estimator} does not offer {operation}: {reason}")]
    Unsupported {
        /// The estimator.
        estimator: &'static str,
        /// The operation asked for.
        operation: &'static str,
        /// Why, and what to use instead.
        reason: &'static str,
    },
    /// An estimator chosen at run time was given a model without the capability it needs.
    #[error("estimator {estimator} needs {} (a {} model); this model offers only {}", .needs.requirement(), .needs.label(), .offered.requirement())]
    ModelLacksCapability {
        /// The estimator.
        estimator: &'static str,
        /// What it needs.
        needs: Capability,
        /// What the model offers.
        offered: Capability,
    },
    /// An estimator was built with the settings of another.
    #[error("estimator {estimator} takes {expected}, not {given}")]
    WrongSettings {
        /// The estimator.
        estimator: &'static str,
        /// The settings it takes.
        expected: &'static str,
        /// The settings given.
        given: &'static str,
    },
    /// The adaptive filter rejected its receiver status or its noise scale.
    #[error("{}{source}", .index.map(|i| format!("y[{i}]: ")).unwrap_or_default())]
    Adaptive {
        /// The measurement component at fault (the satellite count or the RTK code), if any.
        index: Option<usize>,
        /// What is wrong.
        source: Box<AdaptiveError>,
    },
    /// The model could not be evaluated.
    #[error("model: {0}")]
    Model(#[from] ModelError),
    /// Setting up an SDP backend failed.
    #[error("SDP backend: {0}")]
    Lmi(#[from] LmiError),
}

/// What the adaptive filter ([`crate::adaptive`]) and its scalings can reject.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum AdaptiveError {
    /// A receiver-status value is NaN or infinite.
    #[error("{what} must be finite, got {value}")]
    NonFinite {
        /// Which value.
        what: &'static str,
        /// The value given.
        value: f64,
    },
    /// A negative number of satellites.
    #[error("the satellite count must be non-negative, got {0}")]
    NegativeSatellites(f64),
    /// An RTK status code outside 1–4 (or not an integer).
    #[error("RTK status code {0} is not one of 1 (single), 2 (differential), 3 (fixed), 4 (float)")]
    RtkOutOfRange(f64),
    /// The scaling returned a `t_k` that is not positive and finite.
    #[error("the noise scale t_k must be positive and finite, got {0}")]
    InvalidScale(f64),
    /// The innovation components that form `d_k` are not distinct outputs of the model.
    #[error("the horizontal components {components:?} must be two distinct indices below {outputs}")]
    HorizontalComponents {
        /// The indices given.
        components: [usize; 2],
        /// Number of outputs `m`.
        outputs: usize,
    },
    /// A fuzzy system given to [`FuzzyScaling`](crate::adaptive::FuzzyScaling) does not have the three inputs `[N, RTK, d]`.
    #[error("a noise-scaling fuzzy system needs 3 inputs [N, RTK, d], this one has {0}")]
    FuzzyInputCount(usize),
    /// The fuzzy system rejected its inputs.
    #[error("fuzzy inference: {0}")]
    Fuzzy(#[from] FuzzyError),
    /// The Kalman step rejected its data (dimensions, NaN, a numerical failure).
    #[error(transparent)]
    Filter(#[from] EstimatorError),
}

/// What kind of failure an [`EstimatorError`] is: the caller's input refused before anything was
/// computed, or how a step ended. The command line and Python map errors by this kind (Python:
/// `ValueError` for [`ErrorKind::RefusedInput`], `InconsistentDataError` for
/// [`ErrorKind::Outlier`] and [`ErrorKind::InconsistentData`], `NumericalError` for
/// [`ErrorKind::NumericalFailure`], `EstimationError` for the rest).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum ErrorKind {
    /// The input was refused before any step: sizes, NaN, matrices that are not symmetric or
    /// definite, unknown names, settings, a model without the capability the estimator needs, a
    /// receiver status or an input outside its declared box. Fix the input and call again.
    RefusedInput,
    /// The estimator cannot do what was asked: an operation it does not offer, an update without
    /// the prediction it is joint with, an SDP backend that cannot be set up.
    Unsupported,
    /// The step's measurement failed the innovation gate.
    Outlier,
    /// The step's data provably contradict the noise bounds or the declared state bounds.
    InconsistentData,
    /// No guaranteed set can be published at this step.
    GuaranteeLost,
    /// The step failed numerically: a non-finite prediction, a covariance or shape that lost
    /// definiteness, a model evaluation that overflowed.
    NumericalFailure,
}

impl ErrorKind {
    /// A short label: `refused-input`, `unsupported`, `outlier`, `inconsistent-data`,
    /// `guarantee-lost`, `numerical-failure`.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            ErrorKind::RefusedInput => "refused-input",
            ErrorKind::Unsupported => "unsupported",
            ErrorKind::Outlier => "outlier",
            ErrorKind::InconsistentData => "inconsistent-data",
            ErrorKind::GuaranteeLost => "guarantee-lost",
            ErrorKind::NumericalFailure => "numerical-failure",
        }
    }
}

impl EstimatorError {
    /// The keyword of the setting an [`EstimatorError::InvalidSetting`] is about, as the
    /// registry's keywords spell it (`UKF alpha` → `alpha`, `x_lower/x_upper` → `x_lower`);
    /// `None` for other errors.
    #[must_use]
    pub fn setting_keyword(&self) -> Option<&'static str> {
        let EstimatorError::InvalidSetting { what, .. } = self else {
            return None;
        };
        let last = what.rsplit(' ').next().unwrap_or(what);
        last.split('/').next()
    }

    /// Which kind of failure this is ([`ErrorKind`]).
    #[must_use]
    pub fn kind(&self) -> ErrorKind {
        match self {
            EstimatorError::DimensionMismatch { .. }
            | EstimatorError::NonFinite { .. }
            | EstimatorError::NotSymmetric { .. }
            | EstimatorError::NotPositiveDefinite { .. }
            | EstimatorError::NotPositiveSemidefinite { .. }
            | EstimatorError::InvalidInputBounds { .. }
            | EstimatorError::InputOutsideBounds { .. }
            | EstimatorError::EmptySystem(_)
            | EstimatorError::UnknownEstimator { .. }
            | EstimatorError::UnknownSolver { .. }
            | EstimatorError::MissingSetting { .. }
            | EstimatorError::InvalidSetting { .. }
            | EstimatorError::InvalidConfiguration { .. }
            | EstimatorError::ModelLacksCapability { .. }
            | EstimatorError::WrongSettings { .. } => ErrorKind::RefusedInput,
            EstimatorError::Adaptive { source, .. } => match &**source {
                AdaptiveError::Filter(e) => e.kind(),
                _ => ErrorKind::RefusedInput,
            },
            EstimatorError::Model(m) if m.is_numerical() => ErrorKind::NumericalFailure,
            EstimatorError::Model(_) => ErrorKind::RefusedInput,
            EstimatorError::NumericalFailure(_) => ErrorKind::NumericalFailure,
            EstimatorError::Outlier { .. } => ErrorKind::Outlier,
            EstimatorError::InconsistentData { .. }
            | EstimatorError::SetMissed { .. }
            | EstimatorError::InconsistentWindow { .. }
            | EstimatorError::OutsideStateBounds { .. } => ErrorKind::InconsistentData,
            EstimatorError::GuaranteeLost { .. } => ErrorKind::GuaranteeLost,
            EstimatorError::UpdateWithoutPrediction { .. }
            | EstimatorError::Unsupported { .. }
            | EstimatorError::Lmi(_) => ErrorKind::Unsupported,
        }
    }
}

/// The output of an outlying measurement whose innovation is the largest in its own standard
/// deviations, `|ν_i| / √S_ii`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorstOutput {
    /// The output's index in `y` (0-based).
    pub index: usize,
    /// Its innovation `ν_i = y_i − ŷ_i` (wrapped for an angle).
    pub residual: f64,
    /// `|ν_i| / √S_ii`.
    pub sigmas: f64,
}

fn describe_worst(worst: Option<&WorstOutput>) -> String {
    worst.map_or_else(String::new, |w| {
        format!(
            "; the largest innovation is y[{}]: residual {:.4e}, {:.1} standard deviations",
            w.index, w.residual, w.sigmas
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_are_classified_by_kind() {
        let input = EstimatorError::DimensionMismatch { what: "y", expected: 3, found: 2 };
        assert_eq!(input.kind(), ErrorKind::RefusedInput);
        let outlier = EstimatorError::Outlier { step: 4, nis: 30.0, threshold: 11.3, probability: 0.99, worst: None };
        assert_eq!(outlier.kind(), ErrorKind::Outlier);
        assert_eq!(EstimatorError::SetMissed { step: 2, reason: "r" }.kind(), ErrorKind::InconsistentData);
        assert_eq!(EstimatorError::GuaranteeLost { step: 2, reason: "r".into() }.kind(), ErrorKind::GuaranteeLost);
        let numerical = EstimatorError::NumericalFailure("the prediction is not finite");
        assert_eq!(numerical.kind(), ErrorKind::NumericalFailure);
        // A model's numerical failure is not the caller's input; its refusal of a value is.
        assert_eq!(EstimatorError::Model(ModelError::Diverged { step: 3 }).kind(), ErrorKind::NumericalFailure);
        assert_eq!(EstimatorError::Model(ModelError::Evaluation("v = 0".into())).kind(), ErrorKind::RefusedInput);
        // The adaptive filter's own refusals are input; its Kalman step's failures keep their kind.
        let wrapped = EstimatorError::Adaptive { index: None, source: Box::new(AdaptiveError::Filter(numerical)) };
        assert_eq!(wrapped.kind(), ErrorKind::NumericalFailure);
        let rtk = EstimatorError::Adaptive { index: Some(4), source: Box::new(AdaptiveError::RtkOutOfRange(9.0)) };
        assert_eq!(rtk.kind(), ErrorKind::RefusedInput);
        assert_eq!(EstimatorError::UpdateWithoutPrediction { estimator: "smf" }.kind().label(), "unsupported");
    }
}
