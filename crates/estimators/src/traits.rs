//! The estimator and estimate traits and the data every filter starts from: what every filter
//! offers, whatever its model and its kind of set, so that the command line, the reproduction,
//! the Python package and user code can drive any of them.
//!
//! Four concepts, as in filterpy: the sizes ([`Setup::inputs`], the lengths of `x0` and of the
//! measurement-noise matrix), the attributes ([`Setup`]: initial estimate and noise), and the two
//! verbs [`Estimator::predict`] and [`Estimator::update`]; [`Estimator::step`] is one of each.

use nalgebra::{DMatrix, DVector};

use models::Dims;

use crate::checks::DataChecks;
use crate::error::EstimatorError;
pub use crate::status::{DataCheck, DetailField, EstimateKind, Guarantee, SolveOutcome, StepDetails, StepStatus};

/// What every recursive estimator starts from. The meaning of the matrices depends on the
/// estimator's [`EstimateKind`]: covariances for the Gaussian filters, ellipsoid shape matrices
/// for the set-membership filters (`w ∈ {w : wᵀ Q⁻¹ w ≤ 1}`), weights for the moving-horizon
/// estimators. Fields are named, so `Q` and `R` cannot be swapped silently; each constructor
/// validates them (sizes, finiteness, symmetry, positive definiteness) and names the one at fault.
#[derive(Debug, Clone, PartialEq)]
pub struct Setup {
    /// Initial centre (mean) `x̂₀`, length `n`.
    pub x0: DVector<f64>,
    /// Initial covariance or shape `P₀` (`n × n`).
    pub p0: DMatrix<f64>,
    /// Process noise `Q` (`n × n`).
    pub process_noise: DMatrix<f64>,
    /// Measurement noise `R` (`m × m`).
    pub measurement_noise: DMatrix<f64>,
    /// Number of inputs `p`.
    pub inputs: usize,
}

impl Setup {
    /// `(n, p, m)` as the setup declares them.
    #[must_use]
    pub fn dims(&self) -> Dims {
        Dims::new(self.x0.len(), self.inputs, self.measurement_noise.nrows())
    }
}

/// An estimate: centre, shape, per-state bounds where they mean something, what kind of set it
/// is, the status of the step that produced it and the estimator's own details.
pub trait Estimate {
    /// Gaussian, guaranteed ellipsoid or point.
    fn kind(&self) -> EstimateKind;
    /// The centre `x̂` (the mean of a Gaussian estimate).
    fn center(&self) -> &DVector<f64>;
    /// The shape matrix; what it is depends on the kind ([`EstimateKind::shape_meaning`]).
    fn shape(&self) -> &DMatrix<f64>;
    /// Per-state bounds of state `i`: `x̂ᵢ ∓ √Pᵢᵢ` (one standard deviation of a Gaussian
    /// estimate, or a guaranteed set's projection); `None` for point estimates, whose shape is a
    /// weight, and when `i` is out of range.
    fn bounds(&self, i: usize) -> Option<(f64, f64)> {
        let c = self.center();
        (i < c.len() && self.kind() != EstimateKind::Point).then(|| {
            let r = self.shape()[(i, i)].max(0.0).sqrt();
            (c[i] - r, c[i] + r)
        })
    }
    /// How the step ended, what the data check found, whether the set is guaranteed.
    fn status(&self) -> StepStatus;
    /// The estimator's own account of the step (multipliers, iterations, noise scale…).
    fn details(&self) -> StepDetails;
    /// The guaranteed constrained zonotope itself, for estimates of that kind.
    fn constrained_zonotope(&self) -> Option<&constrained_zonotope::ConstrainedZonotope> {
        None
    }
}

/// One recursive estimator over models of type `M` (a capability trait such as
/// [`models::LinearModel`] or [`models::DifferentiableModel`], possibly unsized, or
/// `dyn` [`models::AnyModel`] for estimators chosen at run time).
///
/// [`Estimator::predict`] consumes the input `u_k` and publishes the prediction of `x_{k+1}`;
/// [`Estimator::update`] consumes the measurement `y_{k+1}` taken after it; [`Estimator::step`]
/// does both at once (the same numbers as `predict` then `update`, in one call that either
/// succeeds or leaves the estimator unchanged). The model passed is the one valid for that
/// step. On error the estimator's state is unchanged.
pub trait Estimator<M: ?Sized> {
    /// The estimate type.
    type Estimate: Estimate + 'static;
    /// One step: predict with `u_k`, update with `y_{k+1}`.
    ///
    /// # Errors
    /// An [`EstimatorError`] naming what is wrong; the state is unchanged.
    fn step(&mut self, model: &M, u: &DVector<f64>, y: &DVector<f64>) -> Result<&Self::Estimate, EstimatorError>;
    /// The prediction with `u_k` alone (no measurement arrived, or the first half of a step): for
    /// a guaranteed estimator the set grows to cover every state the model and the process-noise
    /// bound allow.
    ///
    /// # Errors
    /// As [`Estimator::step`]; the state is unchanged.
    fn predict(&mut self, model: &M, u: &DVector<f64>) -> Result<&Self::Estimate, EstimatorError>;
    /// The measurement update with `y_{k+1}` (the measurement function sees the input of the last
    /// prediction, zero before any). A set-membership filter's update is joint with its
    /// prediction ((13)–(29)) and needs one; a moving-horizon estimator's window sample is an
    /// input and the measurement after it, so it offers [`Estimator::step`] and
    /// [`Estimator::predict`] only ([`EstimatorError::Unsupported`]).
    ///
    /// # Errors
    /// As [`Estimator::step`]; the state is unchanged.
    fn update(&mut self, model: &M, y: &DVector<f64>) -> Result<&Self::Estimate, EstimatorError>;
    /// One step in which only the outputs with `measured[i]` were taken (sensors at their own
    /// rates, dropouts): the update uses those rows of `h` and the sub-block of `R` (for a
    /// set-valued noise its projection onto them); unmeasured entries of `y` are ignored and may
    /// be NaN. Every output measured is [`Estimator::step`], none is [`Estimator::predict`].
    ///
    /// The default does those two and refuses a proper subset
    /// ([`EstimatorError::Unsupported`]); every estimator but the fuzzy-adaptive filter
    /// overrides it and updates with any subset (docs/partial-measurements.md).
    ///
    /// # Errors
    /// As [`Estimator::step`]; a mask of another length than `y`.
    fn step_partial(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        measured: &[bool],
    ) -> Result<&Self::Estimate, EstimatorError> {
        if measured.len() != y.len() {
            return Err(EstimatorError::DimensionMismatch {
                what: "measured",
                expected: y.len(),
                found: measured.len(),
            });
        }
        if measured.iter().all(|&b| b) {
            self.step(model, u, y)
        } else if measured.iter().all(|&b| !b) {
            self.predict(model, u)
        } else {
            Err(EstimatorError::Unsupported {
                estimator: "this estimator",
                operation: "a partial measurement",
                reason: "it updates with every output at once; give every output, or none for a prediction",
            })
        }
    }
    /// The current estimate.
    fn estimate(&self) -> &Self::Estimate;
    /// The lengths of the state, of the input `u` and of the measurement `y` the estimator
    /// consumes.
    fn dims(&self) -> Dims;
    /// How the estimator checks its data against its noise description and what a step whose
    /// data fail does ([`DataChecks`]; module [`checks`](crate::checks)). Every estimator starts
    /// with [`DataChecks::default`]: an error naming the step.
    ///
    /// # Errors
    /// An invalid setting (a gate probability outside `(0, 1)`), or
    /// [`EstimatorError::Unsupported`] for a check the estimator cannot make; unchanged on error.
    fn set_data_checks(&mut self, checks: DataChecks) -> Result<(), EstimatorError>;
}

/// The object-safe face of [`Estimator`], for registries and user interfaces that choose an
/// estimator at run time (`Box<dyn DynEstimator<dyn AnyModel>>`). Implemented for every
/// estimator.
pub trait DynEstimator<M: ?Sized> {
    /// One step (see [`Estimator::step`]).
    ///
    /// # Errors
    /// As [`Estimator::step`].
    fn step_dyn(&mut self, model: &M, u: &DVector<f64>, y: &DVector<f64>) -> Result<&dyn Estimate, EstimatorError>;
    /// A prediction (see [`Estimator::predict`]).
    ///
    /// # Errors
    /// As [`Estimator::predict`].
    fn predict_dyn(&mut self, model: &M, u: &DVector<f64>) -> Result<&dyn Estimate, EstimatorError>;
    /// A measurement update (see [`Estimator::update`]).
    ///
    /// # Errors
    /// As [`Estimator::update`].
    fn update_dyn(&mut self, model: &M, y: &DVector<f64>) -> Result<&dyn Estimate, EstimatorError>;
    /// A step with a partial measurement (see [`Estimator::step_partial`]).
    ///
    /// # Errors
    /// As [`Estimator::step_partial`].
    fn step_partial_dyn(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        measured: &[bool],
    ) -> Result<&dyn Estimate, EstimatorError>;
    /// The current estimate.
    fn estimate_dyn(&self) -> &dyn Estimate;
    /// The lengths of the state, the input and the measurement.
    fn dims_dyn(&self) -> Dims;
    /// The data checks (see [`Estimator::set_data_checks`]).
    ///
    /// # Errors
    /// As [`Estimator::set_data_checks`].
    fn set_data_checks_dyn(&mut self, checks: DataChecks) -> Result<(), EstimatorError>;
}

impl<M: ?Sized, E: Estimator<M>> DynEstimator<M> for E {
    fn step_dyn(&mut self, model: &M, u: &DVector<f64>, y: &DVector<f64>) -> Result<&dyn Estimate, EstimatorError> {
        match self.step(model, u, y) {
            Ok(e) => Ok(e),
            Err(e) => Err(e),
        }
    }
    fn predict_dyn(&mut self, model: &M, u: &DVector<f64>) -> Result<&dyn Estimate, EstimatorError> {
        match self.predict(model, u) {
            Ok(e) => Ok(e),
            Err(e) => Err(e),
        }
    }
    fn update_dyn(&mut self, model: &M, y: &DVector<f64>) -> Result<&dyn Estimate, EstimatorError> {
        match self.update(model, y) {
            Ok(e) => Ok(e),
            Err(e) => Err(e),
        }
    }
    fn step_partial_dyn(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        measured: &[bool],
    ) -> Result<&dyn Estimate, EstimatorError> {
        match self.step_partial(model, u, y, measured) {
            Ok(e) => Ok(e),
            Err(e) => Err(e),
        }
    }
    fn estimate_dyn(&self) -> &dyn Estimate {
        self.estimate()
    }
    fn dims_dyn(&self) -> Dims {
        self.dims()
    }
    fn set_data_checks_dyn(&mut self, checks: DataChecks) -> Result<(), EstimatorError> {
        self.set_data_checks(checks)
    }
}

/// Implements [`Estimator`] for a filter whose inherent `step`, `predict`, `update`, `estimate`
/// and `dims` have the trait's signatures, for every model of the capability `$bound`:
/// `forward_estimator!(impl<S: UpdateSolver> for Filter<S>, LinearModel, Estimate)`.
macro_rules! forward_estimator {
    (impl<$($g:ident: $gb:path),*> for $ty:ty, $bound:path, $est:ty) => {
        $crate::traits::forward_estimator!(@impl [$($g: $gb),*] $ty, $bound, $est, {});
    };
    (impl<$($g:ident: $gb:path),*> for $ty:ty, $bound:path, $est:ty, partial) => {
        $crate::traits::forward_estimator!(@impl [$($g: $gb),*] $ty, $bound, $est, {
            fn step_partial(
                &mut self,
                model: &M,
                u: &nalgebra::DVector<f64>,
                y: &nalgebra::DVector<f64>,
                measured: &[bool],
            ) -> Result<&$est, $crate::error::EstimatorError> {
                <$ty>::step_partial(self, model, u, y, measured)
            }
        });
    };
    (@impl [$($g:ident: $gb:path),*] $ty:ty, $bound:path, $est:ty, { $($extra:tt)* }) => {
        impl<$($g: $gb,)* M: $bound + ?Sized> $crate::traits::Estimator<M> for $ty {
            type Estimate = $est;
            fn step(
                &mut self,
                model: &M,
                u: &nalgebra::DVector<f64>,
                y: &nalgebra::DVector<f64>,
            ) -> Result<&$est, $crate::error::EstimatorError> {
                <$ty>::step(self, model, u, y)
            }
            fn predict(&mut self, model: &M, u: &nalgebra::DVector<f64>) -> Result<&$est, $crate::error::EstimatorError> {
                <$ty>::predict(self, model, u)
            }
            fn update(&mut self, model: &M, y: &nalgebra::DVector<f64>) -> Result<&$est, $crate::error::EstimatorError> {
                <$ty>::update(self, model, y)
            }
            fn estimate(&self) -> &$est {
                <$ty>::estimate(self)
            }
            fn dims(&self) -> models::Dims {
                <$ty>::dims(self)
            }
            fn set_data_checks(&mut self, checks: $crate::checks::DataChecks) -> Result<(), $crate::error::EstimatorError> {
                <$ty>::set_data_checks(self, checks)
            }
            $($extra)*
        }
    };
}
pub(crate) use forward_estimator;
