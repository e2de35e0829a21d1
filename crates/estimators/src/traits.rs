//! The estimator and estimate traits: what every filter offers, whatever its model and its kind
//! of set, so that the CLI, the reproduction and user code can drive any of them.

use nalgebra::{DMatrix, DVector};

use models::Dims;

use crate::error::EstimatorError;

/// What kind of set an [`Estimate`] describes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum EstimateKind {
    /// A Gaussian estimate: mean and covariance (bounds are ±1 standard deviation).
    Gaussian,
    /// A guaranteed ellipsoid `𝓔(c, P) = {x : (x − c)ᵀ P⁻¹ (x − c) ≤ 1}` that contains the true
    /// state whenever the noises respect their bounds (bounds are the set's projections).
    GuaranteedEllipsoid,
    /// A point estimate (moving-horizon estimators): the shape is a weight matrix of the method
    /// (documented by the estimator), neither a calibrated covariance nor a guaranteed set.
    Point,
}

impl EstimateKind {
    /// A short label for tables and file headers.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            EstimateKind::Gaussian => "gaussian",
            EstimateKind::GuaranteedEllipsoid => "guaranteed ellipsoid",
            EstimateKind::Point => "point",
        }
    }
}

/// An estimate after a step: centre, shape, per-state bounds and what kind of set it is.
pub trait Estimate {
    /// Gaussian covariance or guaranteed ellipsoid.
    fn kind(&self) -> EstimateKind;
    /// The centre (mean) `x̂`.
    fn center(&self) -> &DVector<f64>;
    /// The covariance (Gaussian) or the ellipsoid's shape matrix `P` (guaranteed).
    fn shape(&self) -> &DMatrix<f64>;
    /// Per-state bounds `x̂ᵢ ∓ √Pᵢᵢ` (one standard deviation, or the guaranteed interval);
    /// `None` if `i` is out of range.
    fn bounds(&self, i: usize) -> Option<(f64, f64)> {
        let c = self.center();
        (i < c.len()).then(|| {
            let r = self.shape()[(i, i)].max(0.0).sqrt();
            (c[i] - r, c[i] + r)
        })
    }
    /// The S-procedure multipliers `τ` of the step (set-membership filters of the carrier
    /// paper); `None` for other estimators.
    fn multipliers(&self) -> Option<[f64; 3]> {
        None
    }
    /// Whether the step fell back to a feasible solution because its solver failed.
    fn fallback_used(&self) -> bool {
        false
    }
    /// For guaranteed estimators: whether the step's data were consistent with the noise bounds
    /// (`None` for estimators that cannot tell).
    fn consistent(&self) -> Option<bool> {
        None
    }
    /// For guaranteed estimators: whether the published set is still guaranteed (`false` once
    /// inconsistent data were accepted); `None` for Gaussian estimates.
    fn guaranteed(&self) -> Option<bool> {
        None
    }
}

/// One recursive estimator over models of type `M` (a capability trait such as
/// [`models::LinearModel`] or [`models::DifferentiableModel`], possibly unsized).
///
/// A step consumes the input `u_k` and the measurement `y_{k+1}` taken after it, with the model
/// valid for that step, and returns the estimate of `x_{k+1}`. On error the estimator's state is
/// unchanged.
pub trait Estimator<M: ?Sized> {
    /// The estimate type.
    type Estimate: Estimate + 'static;
    /// One step.
    ///
    /// # Errors
    /// An [`EstimatorError`] naming what is wrong; the state is unchanged.
    fn step(&mut self, model: &M, u: &DVector<f64>, y: &DVector<f64>) -> Result<&Self::Estimate, EstimatorError>;
    /// A prediction-only step (no measurement arrived, for example a gap in a log): the
    /// estimate of `x_{k+1}` from `u_k` alone; for a guaranteed estimator the set grows to cover
    /// every state the model and the process-noise bound allow.
    ///
    /// # Errors
    /// As [`Estimator::step`]; the state is unchanged.
    fn predict(&mut self, model: &M, u: &DVector<f64>) -> Result<&Self::Estimate, EstimatorError>;
    /// The current estimate.
    fn estimate(&self) -> &Self::Estimate;
    /// States, inputs and outputs.
    fn dims(&self) -> Dims;
}

/// The object-safe face of [`Estimator`], for registries and user interfaces that choose an
/// estimator at run time (`Box<dyn DynEstimator<dyn LinearModel>>`). Implemented for every
/// estimator.
pub trait DynEstimator<M: ?Sized> {
    /// One step (see [`Estimator::step`]).
    ///
    /// # Errors
    /// As [`Estimator::step`].
    fn step_dyn(&mut self, model: &M, u: &DVector<f64>, y: &DVector<f64>) -> Result<&dyn Estimate, EstimatorError>;
    /// A prediction-only step (see [`Estimator::predict`]).
    ///
    /// # Errors
    /// As [`Estimator::predict`].
    fn predict_dyn(&mut self, model: &M, u: &DVector<f64>) -> Result<&dyn Estimate, EstimatorError>;
    /// The current estimate.
    fn estimate_dyn(&self) -> &dyn Estimate;
    /// States, inputs and outputs.
    fn dims_dyn(&self) -> Dims;
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
    fn estimate_dyn(&self) -> &dyn Estimate {
        self.estimate()
    }
    fn dims_dyn(&self) -> Dims {
        self.dims()
    }
}

/// The noise description of a filter: process noise `Q` (`n × n`) and measurement noise `R`
/// (`m × m`) — covariances for Gaussian filters, ellipsoid shape matrices
/// (`w ∈ {w : wᵀ Q⁻¹ w ≤ 1}`) for set-membership filters.
#[derive(Debug, Clone, PartialEq)]
pub struct NoiseSettings {
    /// Process noise `Q`.
    pub q: DMatrix<f64>,
    /// Measurement noise `R`.
    pub r: DMatrix<f64>,
}

impl NoiseSettings {
    /// `Q` and `R`.
    #[must_use]
    pub fn new(q: DMatrix<f64>, r: DMatrix<f64>) -> Self {
        Self { q, r }
    }
}
