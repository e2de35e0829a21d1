//! The fuzzy-adaptive Kalman filter of the BDS/INS paper (`docs/bds-ins-fuzzy-kf.md` §2): a
//! Kalman step whose measurement-noise covariance is scaled every epoch by `t_k`, chosen from
//! the receiver's working state and the innovation,
//!
//! ```text
//! (3), (4)  x⁻ = A x + B u,   P⁻ = A P Aᵀ + Q
//! (8)       r_k = y − C x⁻                         (innovation)
//!           d_k = √(r_x² + r_y²)                   (horizontal BDS-to-INS distance, A)
//!           t_k = scaling(N_k, RTK_k, d_k, r_k)    (the FIS, or any NoiseScaling)
//! (9)       K = P⁻ Cᵀ (C P⁻ Cᵀ + t_k R)⁻¹
//! (6), (7)  x = x⁻ + K r_k,   P = (I − K C) P⁻ (I − K C)ᵀ + K t_k R Kᵀ   (Joseph form)
//! ```
//!
//! The filter is a [`KalmanFilter`] whose step is split around the choice of `t_k` (the same
//! prediction and the same Joseph-form update, not a copy), so with `t_k ≡ 1` it is the plain
//! Kalman filter (tested). `t_k` comes from a [`NoiseScaling`]: the paper's Mamdani system through
//! [`FuzzyScaling`] (any [`FuzzySystem`] with inputs `[N, RTK, d]`, for example loaded from TOML),
//! a closure `|c: &ScalingContext| -> f64`, or [`ConstantScaling`]. Each step reports its `t_k` and
//! `d_k` ([`AdaptiveStep`]). Without a fix the filter only predicts ([`AdaptiveKalmanFilter::predict`]).
//!
//! As an [`Estimator`](crate::Estimator) (so that it runs wherever any filter runs), the receiver status travels
//! with its measurement: the measurement vector is the model's `m` outputs followed by the
//! satellite count and the RTK code, `y = [y₁ … y_m, N, RTK]` (length `m + 2`,
//! [`AdaptiveKalmanFilter::dims`]); an RTK code of 0 marks an epoch without a fix, whose step is a
//! prediction only.
//!
//! Bad input is a typed [`AdaptiveError`] and leaves the filter unchanged: NaN anywhere, a
//! negative satellite count, an RTK code outside 1–4 ([`ReceiverStatus::new`]), a scale that is not
//! positive and finite. After construction a step allocates nothing (tested with a counting
//! allocator, FIS included).

use nalgebra::{DMatrix, DVector};

use fuzzy_inference::{Evaluation, FuzzySystem};
use models::{Dims, LinearModel};

pub use crate::error::AdaptiveError;
use crate::error::EstimatorError;
use crate::kalman::{GaussianEstimate, KalmanFilter};
use crate::partial::Measured;
use crate::traits::forward_estimator;
use crate::traits::{DetailField, Setup, StepDetails};
use crate::validate::check_vec;

/// The RTK codes the paper uses (P): 1 single, 2 differential, 3 fixed, 4 float.
pub const RTK_CODES: std::ops::RangeInclusive<u8> = 1..=4;

/// The receiver's working state at one epoch, validated: satellites used `N ≥ 0` and the RTK
/// status code (1 single, 2 differential, 3 fixed, 4 float; NMEA GGA 1 → 1, 2 → 2, 4 → 3,
/// 5 → 4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReceiverStatus {
    satellites: f64,
    rtk: u8,
}

impl ReceiverStatus {
    /// The status of a measurement vector's two last entries `[N, RTK]`: `None` for RTK code 0 (no
    /// fix), else as [`ReceiverStatus::new`].
    ///
    /// # Errors
    /// As [`ReceiverStatus::new`].
    pub fn from_measurement(satellites: f64, rtk_code: f64) -> Result<Option<Self>, AdaptiveError> {
        if rtk_code == 0.0 { Ok(None) } else { Self::new(satellites, rtk_code).map(Some) }
    }

    /// Validates a status as logged (numbers, as read from a file).
    ///
    /// # Errors
    /// [`AdaptiveError::NonFinite`] for a NaN/∞ value, [`AdaptiveError::NegativeSatellites`],
    /// [`AdaptiveError::RtkOutOfRange`] for a code that is not an integer in 1–4.
    pub fn new(satellites: f64, rtk_code: f64) -> Result<Self, AdaptiveError> {
        if !satellites.is_finite() {
            return Err(AdaptiveError::NonFinite { what: "the satellite count", value: satellites });
        }
        if satellites < 0.0 {
            return Err(AdaptiveError::NegativeSatellites(satellites));
        }
        if !rtk_code.is_finite() {
            return Err(AdaptiveError::NonFinite { what: "the RTK status code", value: rtk_code });
        }
        let code = rtk_code as u8;
        if rtk_code.fract() != 0.0 || !(f64::from(*RTK_CODES.start())..=f64::from(*RTK_CODES.end())).contains(&rtk_code)
        {
            return Err(AdaptiveError::RtkOutOfRange(rtk_code));
        }
        Ok(Self { satellites, rtk: code })
    }

    /// Satellites used `N`.
    #[must_use]
    pub fn satellites(&self) -> f64 {
        self.satellites
    }

    /// The RTK status code (1–4).
    #[must_use]
    pub fn rtk_code(&self) -> u8 {
        self.rtk
    }
}

/// What a [`NoiseScaling`] may look at to choose `t_k`.
#[derive(Debug, Clone, Copy)]
pub struct ScalingContext<'a> {
    /// The receiver's working state.
    pub status: ReceiverStatus,
    /// `d_k`: the norm of the two horizontal innovation components (BDS fix to INS prediction).
    pub distance: f64,
    /// The whole innovation `r_k = y − C x⁻` (8); in a partial step its unmeasured entries are
    /// not defined (NaN when the measurement's were).
    pub innovation: &'a DVector<f64>,
    /// The step (1 for the first update of the filter).
    pub step: u64,
}

/// Chooses the measurement-noise scale `t_k` of (9) at every update. Implemented by
/// [`FuzzyScaling`] (the paper's FIS), [`ConstantScaling`], and every closure
/// `FnMut(&ScalingContext) -> f64`.
pub trait NoiseScaling {
    /// `t_k` for this epoch (must be positive and finite; the filter checks).
    ///
    /// # Errors
    /// Whatever the scaling rejects (the filter is left unchanged).
    fn scale(&mut self, context: &ScalingContext<'_>) -> Result<f64, AdaptiveError>;
}

impl<F: FnMut(&ScalingContext<'_>) -> f64> NoiseScaling for F {
    fn scale(&mut self, context: &ScalingContext<'_>) -> Result<f64, AdaptiveError> {
        Ok(self(context))
    }
}

/// A constant `t_k` (`ConstantScaling(1.0)` is the plain Kalman filter).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConstantScaling(pub f64);

impl NoiseScaling for ConstantScaling {
    fn scale(&mut self, _context: &ScalingContext<'_>) -> Result<f64, AdaptiveError> {
        Ok(self.0)
    }
}

/// A Mamdani [`FuzzySystem`] as the noise scaling: `t_k = FIS(N_k, RTK_k, d_k)`, the paper's
/// fuzzy Kalman filter. The system's inputs are, in order, satellites, RTK code and `d` \[m\].
#[derive(Debug, Clone)]
pub struct FuzzyScaling {
    system: FuzzySystem,
    last: Option<Evaluation>,
}

impl FuzzyScaling {
    /// Wraps `system`.
    ///
    /// # Errors
    /// [`AdaptiveError::FuzzyInputCount`] unless the system has exactly three inputs.
    pub fn new(system: FuzzySystem) -> Result<Self, AdaptiveError> {
        match system.inputs().len() {
            3 => Ok(Self { system, last: None }),
            n => Err(AdaptiveError::FuzzyInputCount(n)),
        }
    }

    /// The digest's 45-rule system with `σ0 = 0.2 m` ([`FuzzySystem::bds_ins_default`]).
    #[must_use]
    pub fn bds_ins_default() -> Self {
        Self { system: FuzzySystem::bds_ins_default(), last: None }
    }

    /// The fuzzy system.
    #[must_use]
    pub fn system(&self) -> &FuzzySystem {
        &self.system
    }

    /// The evaluation of the last call of [`NoiseScaling::scale`] (rules fired, firing strength,
    /// clamping), `None` before the first.
    #[must_use]
    pub fn last_evaluation(&self) -> Option<&Evaluation> {
        self.last.as_ref()
    }
}

impl NoiseScaling for FuzzyScaling {
    fn scale(&mut self, c: &ScalingContext<'_>) -> Result<f64, AdaptiveError> {
        let e = self.system.evaluate(&[c.status.satellites(), f64::from(c.status.rtk_code()), c.distance])?;
        self.last = Some(e);
        Ok(e.output)
    }
}

/// What one update chose: the scale `t_k` and the distance `d_k` it was chosen from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdaptiveStep {
    /// `t_k` of (9).
    pub scale: f64,
    /// `d_k` \[units of the horizontal outputs\].
    pub distance: f64,
}

/// The numbers an adaptive step reports beyond its status (`port-est`'s columns, Python's
/// `details`; `None` before the first update and after a prediction without a fix).
pub const DETAILS: &[DetailField] = &[
    DetailField { name: "scale", meaning: "the measurement-noise scale t_k of the epoch" },
    DetailField { name: "distance", meaning: "the horizontal innovation distance d_k that chose it" },
];

/// The Kalman filter with the measurement noise scaled by a [`NoiseScaling`] (module
/// documentation); [`FuzzyKalmanFilter`] is the paper's.
#[derive(Debug, Clone)]
pub struct AdaptiveKalmanFilter<S> {
    kf: KalmanFilter,
    scaling: S,
    r_scaled: DMatrix<f64>,
    horizontal: [usize; 2],
    updates: u64,
    /// `t_k`, `d_k` of the last step (`None` before the first update and after a prediction).
    last_step: Option<AdaptiveStep>,
    /// The model outputs `y₁ … y_m` of a measurement vector `[y, N, RTK]`.
    outputs: DVector<f64>,
}

/// The paper's fuzzy Kalman filter (FKF): the adaptive filter with a [`FuzzyScaling`].
pub type FuzzyKalmanFilter = AdaptiveKalmanFilter<FuzzyScaling>;

impl<S: NoiseScaling> AdaptiveKalmanFilter<S> {
    /// A filter from its [`Setup`] (covariances; the measurement noise is the nominal `R`,
    /// `t_k = 1`) and the scaling. `d_k` is formed from innovation components 0 and 1 (see
    /// [`AdaptiveKalmanFilter::with_horizontal`]).
    ///
    /// # Errors
    /// As [`KalmanFilter::new`] (wrapped in [`AdaptiveError::Filter`]), and
    /// [`AdaptiveError::HorizontalComponents`] for fewer than two outputs.
    pub fn new(setup: Setup, scaling: S) -> Result<Self, AdaptiveError> {
        let kf = KalmanFilter::new(setup)?;
        let r_scaled = kf.measurement_noise().clone();
        let outputs = DVector::zeros(r_scaled.nrows());
        let mut f = Self { kf, scaling, r_scaled, horizontal: [0, 1], updates: 0, last_step: None, outputs };
        f.publish_step(None);
        f.with_horizontal([0, 1])
    }

    /// Chooses which two innovation components form `d_k = √(r_i² + r_j²)`.
    ///
    /// # Errors
    /// [`AdaptiveError::HorizontalComponents`] unless they are distinct and below `m`.
    pub fn with_horizontal(mut self, components: [usize; 2]) -> Result<Self, AdaptiveError> {
        let m = self.kf.dims().outputs;
        if components[0] == components[1] || components.iter().any(|&i| i >= m) {
            return Err(AdaptiveError::HorizontalComponents { components, outputs: m });
        }
        self.horizontal = components;
        Ok(self)
    }

    /// One predict–update step with the receiver's working state given apart from the
    /// measurement: consumes `u_k`, the model outputs `y_{k+1}` (length `m`) and the status of that
    /// epoch; returns the `t_k` and `d_k` used (the estimate is
    /// [`AdaptiveKalmanFilter::estimate`]). On error the filter is unchanged. Allocation-free (if
    /// the scaling is).
    ///
    /// # Errors
    /// [`AdaptiveError::Filter`] for a model, input or measurement the Kalman step rejects
    /// (dimensions, NaN/∞, a numerical failure), the scaling's error, or
    /// [`AdaptiveError::InvalidScale`].
    pub fn step_with_status<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        status: &ReceiverStatus,
    ) -> Result<AdaptiveStep, AdaptiveError> {
        self.kf.predict_and_innovate(model, u, y)?;
        self.scaled_update(model, status)
    }

    /// The update of the buffered prediction and innovation with `t_k` from the scaling.
    fn scaled_update<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        status: &ReceiverStatus,
    ) -> Result<AdaptiveStep, AdaptiveError> {
        let scale = self.scale(status)?;
        self.kf.update_buffered(model.c(), &self.r_scaled)?;
        Ok(self.commit_scale(scale))
    }

    /// `t_k` and `d_k` from the buffered innovation, with `t_k R` in `r_scaled`.
    fn scale(&mut self, status: &ReceiverStatus) -> Result<AdaptiveStep, AdaptiveError> {
        let innovation = self.kf.innovation();
        let [i, j] = self.horizontal;
        let distance = innovation[i].hypot(innovation[j]);
        let context = ScalingContext { status: *status, distance, innovation, step: self.updates + 1 };
        let scale = self.scaling.scale(&context)?;
        if !(scale.is_finite() && scale > 0.0) {
            return Err(AdaptiveError::InvalidScale(scale));
        }
        self.r_scaled.copy_from(self.kf.measurement_noise());
        self.r_scaled.iter_mut().for_each(|v| *v *= scale);
        Ok(AdaptiveStep { scale, distance })
    }

    /// Counts a published update and reports its scale.
    fn commit_scale(&mut self, report: AdaptiveStep) -> AdaptiveStep {
        self.updates += 1;
        self.publish_step(Some(report));
        report
    }

    /// Records `t_k`, `d_k` of the step (`None`: no update) and writes them into the estimate's
    /// details: the one place both are set.
    fn publish_step(&mut self, step: Option<AdaptiveStep>) {
        self.last_step = step;
        self.kf.set_details(StepDetails::new(DETAILS, &[step.map(|s| s.scale), step.map(|s| s.distance)]));
    }

    /// The prediction (no fix this epoch, or the first half of a step): `x⁻ = A x + B u`,
    /// `P⁻ = A P Aᵀ + Q`. On error the filter is unchanged. Allocation-free.
    ///
    /// # Errors
    /// As [`KalmanFilter::predict`].
    pub fn predict<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        self.kf.predict(model, u)?;
        self.publish_step(None);
        Ok(self.kf.estimate())
    }

    /// Splits a measurement vector `[y₁ … y_m, N, RTK]` into the outputs (kept in `self.outputs`)
    /// and the receiver status (`None`: no fix).
    fn split_measurement(&mut self, y: &DVector<f64>) -> Result<Option<ReceiverStatus>, EstimatorError> {
        let m = self.outputs.len();
        check_vec("y", y, m + 2)?;
        let status = ReceiverStatus::from_measurement(y[m], y[m + 1]).map_err(|e| adaptive_error(e, m))?;
        self.outputs.copy_from(&y.rows(0, m));
        Ok(status)
    }

    /// One step on a measurement vector `[y₁ … y_m, N, RTK]` (module documentation): the adaptive
    /// predict–update with the status of the epoch, or a prediction only when the RTK code is 0.
    /// On error the filter is unchanged. Allocation-free (if the scaling is).
    ///
    /// # Errors
    /// As [`AdaptiveKalmanFilter::step_with_status`], the receiver status and noise-scale errors as
    /// [`EstimatorError::Adaptive`] naming the measurement component.
    pub fn step<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        let m = self.outputs.len();
        match self.split_measurement(y)? {
            None => self.predict(model, u),
            Some(status) => {
                let outputs = std::mem::take(&mut self.outputs);
                let result = self.step_with_status(model, u, &outputs, &status);
                self.outputs = outputs;
                result.map_err(|e| adaptive_error(e, m))?;
                Ok(self.kf.estimate())
            }
        }
    }

    /// One step with the entries `measured[i]` of `[y₁ … y_m, N, RTK]` only
    /// (docs/partial-measurements.md (P7)): no output measured is a prediction, as is a fix
    /// whose RTK code is 0; a proper subset of the outputs updates with their rows `C_S` and the
    /// sub-block of `t_k R`, where `t_k` comes from the fix as in a whole step — which needs the
    /// receiver status and both horizontal outputs (`d_k`): without them the scale is not defined
    /// and the step is refused. Unmeasured entries are ignored (they may be NaN). On error the
    /// filter is unchanged. Allocation-free after the first step with that many outputs measured
    /// (if the scaling is).
    ///
    /// # Errors
    /// As [`AdaptiveKalmanFilter::step`]; a mask of another length; [`EstimatorError::Unsupported`]
    /// for a proper subset without the receiver status or a horizontal output.
    pub fn step_partial<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        measured: &[bool],
    ) -> Result<&GaussianEstimate, EstimatorError> {
        let m = self.outputs.len();
        if measured.len() != m + 2 {
            return Err(EstimatorError::DimensionMismatch { what: "measured", expected: m + 2, found: measured.len() });
        }
        if y.len() != m + 2 {
            return Err(EstimatorError::DimensionMismatch { what: "y", expected: m + 2, found: y.len() });
        }
        if let Some(index) = (0..m + 2).find(|&i| measured[i] && !y[i].is_finite()) {
            return Err(EstimatorError::NonFinite { what: "y", index });
        }
        let outputs = &measured[..m];
        if measured.iter().all(|&b| b) {
            return self.step(model, u, y);
        }
        if !outputs.iter().any(|&b| b) {
            return self.predict(model, u);
        }
        let [i, j] = self.horizontal;
        if !(measured[m] && measured[m + 1] && outputs[i] && outputs[j]) {
            return Err(EstimatorError::Unsupported {
                estimator: "fkf",
                operation: "a partial measurement without the receiver status or a horizontal output",
                reason: "its noise scale t_k is a function of the receiver status (N, RTK) and of the horizontal \
                         innovation d_k, so both horizontal outputs and the status must be measured; leave every \
                         output unmeasured for a prediction",
            });
        }
        let Some(status) = ReceiverStatus::from_measurement(y[m], y[m + 1]).map_err(|e| adaptive_error(e, m))? else {
            return self.predict(model, u);
        };
        self.outputs.copy_from(&y.rows(0, m));
        let outputs_y = std::mem::take(&mut self.outputs);
        let result = self.partial_update(model, u, &outputs_y, outputs, &status);
        self.outputs = outputs_y;
        result.map_err(|e| adaptive_error(e, m))?;
        Ok(self.kf.estimate())
    }

    /// The partial step's prediction, innovation and update with `t_k` (`outputs` measured).
    fn partial_update<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        outputs: &[bool],
        status: &ReceiverStatus,
    ) -> Result<AdaptiveStep, AdaptiveError> {
        let k = match self.kf.predict_and_innovate_partial(model, u, y, outputs)? {
            Measured::Some(k) => k,
            // The caller sends a proper, non-empty subset only.
            Measured::All | Measured::Nothing => {
                return Err(AdaptiveError::Filter(EstimatorError::NumericalFailure(
                    "the partial step's mask is not a proper subset",
                )));
            }
        };
        let scale = self.scale(status)?;
        self.kf.update_buffered_partial(model.c(), Some(&self.r_scaled), k)?;
        Ok(self.commit_scale(scale))
    }

    /// The measurement update of the current estimate with `[y₁ … y_m, N, RTK]` (nothing changes
    /// without a fix). On error the filter is unchanged.
    ///
    /// # Errors
    /// As [`AdaptiveKalmanFilter::step`].
    pub fn update<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        y: &DVector<f64>,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        let m = self.outputs.len();
        let Some(status) = self.split_measurement(y)? else {
            return Ok(self.kf.estimate());
        };
        self.kf.innovate_estimate(model, &self.outputs)?;
        self.scaled_update(model, &status).map_err(|e| adaptive_error(e, m))?;
        Ok(self.kf.estimate())
    }

    /// The current estimate.
    #[must_use]
    pub fn estimate(&self) -> &GaussianEstimate {
        self.kf.estimate()
    }

    /// `t_k` and `d_k` of the last step (`None` before the first update and after a prediction).
    #[must_use]
    pub fn last_step(&self) -> Option<AdaptiveStep> {
        self.last_step
    }

    /// Number of updates so far (prediction-only steps are not counted).
    #[must_use]
    pub fn updates(&self) -> u64 {
        self.updates
    }

    /// The nominal measurement covariance `R` (`t_k = 1`).
    #[must_use]
    pub fn nominal_measurement_noise(&self) -> &DMatrix<f64> {
        self.kf.measurement_noise()
    }

    /// The scaling.
    #[must_use]
    pub fn scaling(&self) -> &S {
        &self.scaling
    }

    /// The scaling, mutably (for example to change a closure's settings between steps).
    pub fn scaling_mut(&mut self) -> &mut S {
        &mut self.scaling
    }

    /// States, inputs, and the length of the measurement vector `[y₁ … y_m, N, RTK]` (`m + 2`).
    #[must_use]
    pub fn dims(&self) -> Dims {
        let d = self.kf.dims();
        Dims::new(d.states, d.inputs, d.outputs + 2)
    }

    /// The innovation gate of the underlying Kalman step, judged with the scaled `t_k R` (module
    /// [`checks`](crate::checks)); by default a measurement outside it is an error naming the step.
    ///
    /// # Errors
    /// A gate probability outside `(0, 1)`; the filter is unchanged.
    pub fn set_data_checks(&mut self, checks: crate::checks::DataChecks) -> Result<(), EstimatorError> {
        self.kf.set_data_checks(checks)
    }

    /// Replaces the process-noise covariance in place (a model rebuilt per step, e.g. a turning
    /// route with body-frame biases); validated, no allocation, unchanged on error.
    ///
    /// # Errors
    /// As [`KalmanFilter::set_process_noise`].
    pub fn set_process_noise(&mut self, q: &DMatrix<f64>) -> Result<(), AdaptiveError> {
        Ok(self.kf.set_process_noise(q)?)
    }
}

/// An [`AdaptiveError`] as an [`EstimatorError`]: the Kalman step's own errors as they are, the
/// rest wrapped, naming measurement component `m` (satellites) or `m + 1` (RTK code) where the
/// error is about one of them.
fn adaptive_error(e: AdaptiveError, m: usize) -> EstimatorError {
    match e {
        AdaptiveError::Filter(e) => e,
        AdaptiveError::NegativeSatellites(_) | AdaptiveError::NonFinite { what: "the satellite count", .. } => {
            EstimatorError::Adaptive { index: Some(m), source: Box::new(e) }
        }
        AdaptiveError::RtkOutOfRange(_) | AdaptiveError::NonFinite { .. } => {
            EstimatorError::Adaptive { index: Some(m + 1), source: Box::new(e) }
        }
        e => EstimatorError::Adaptive { index: None, source: Box::new(e) },
    }
}

forward_estimator!(impl<S: NoiseScaling> for AdaptiveKalmanFilter<S>, LinearModel, GaussianEstimate, partial);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn receiver_status_is_validated() {
        let s = ReceiverStatus::new(20.0, 3.0).unwrap();
        assert_eq!((s.satellites(), s.rtk_code()), (20.0, 3));
        assert_eq!(ReceiverStatus::new(-1.0, 3.0), Err(AdaptiveError::NegativeSatellites(-1.0)));
        assert!(matches!(ReceiverStatus::new(f64::NAN, 3.0), Err(AdaptiveError::NonFinite { .. })));
        assert!(matches!(ReceiverStatus::new(5.0, f64::INFINITY), Err(AdaptiveError::NonFinite { .. })));
        for bad in [0.0, 5.0, 2.5, -1.0, 300.0] {
            assert_eq!(ReceiverStatus::new(5.0, bad), Err(AdaptiveError::RtkOutOfRange(bad)));
        }
        for code in 1..=4 {
            assert_eq!(ReceiverStatus::new(0.0, f64::from(code)).unwrap().rtk_code(), code);
        }
        assert_eq!(
            AdaptiveError::RtkOutOfRange(5.0).to_string(),
            "RTK status code 5 is not one of 1 (single), 2 (differential), 3 (fixed), 4 (float)"
        );
    }

    #[test]
    fn fuzzy_scaling_needs_three_inputs() {
        let f = FuzzyScaling::bds_ins_default();
        assert_eq!(f.system().inputs().len(), 3);
        assert!(f.last_evaluation().is_none());
        assert!(FuzzyScaling::new(FuzzySystem::bds_ins_default()).is_ok());
    }
}
