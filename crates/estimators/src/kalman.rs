//! The Kalman filter with a Joseph-form update.
//!
//! ```text
//! predict:  x⁻ = A x + B u,            P⁻ = A P Aᵀ + Q
//! update:   S = C P⁻ Cᵀ + R = G Gᵀ,    K = P⁻ Cᵀ S⁻¹  (two triangular solves with G)
//!           x = x⁻ + K (y − C x⁻),     P = (I − K C) P⁻ (I − K C)ᵀ + K R Kᵀ   (Joseph form)
//! ```
//!
//! `Q` and `R` are covariances here (not ellipsoid shapes). All buffers are allocated in
//! [`KalmanFilter::new`]; [`KalmanFilter::step`] allocates nothing.

use nalgebra::{DMatrix, DVector};

use models::{Angles, Dims, LinearModel};

use crate::checks::map_worst_output;
use crate::checks::{DataChecks, InnovationGate};
use crate::error::EstimatorError;
pub use crate::gaussian_update::GaussianEstimate;
use crate::gaussian_update::{GaussianUpdate, commit_prediction};
use crate::partial::{GaussianSubset, Measured, Subsets, classify};
use crate::traits::forward_estimator;
use crate::traits::{Setup, StepDetails};
use crate::validate::{Covariances, InitialData, check_initial_as, check_model, check_vec};

/// A Kalman filter for `x_{k+1} = A_k x_k + B_k u_k + w_k`, `y = C x + v`, `w ~ (0, Q)`,
/// `v ~ (0, R)`.
#[derive(Debug, Clone)]
pub struct KalmanFilter {
    n: usize,
    p: usize,
    m: usize,
    q: DMatrix<f64>,
    r: DMatrix<f64>,
    est: GaussianEstimate,
    // workspace
    x_pred: DVector<f64>,
    p_pred: DMatrix<f64>,
    ap: DMatrix<f64>,
    innov: DVector<f64>,
    upd: GaussianUpdate,
    gate: InnovationGate,
    /// The updates of partial measurements, by measured count.
    subsets: Subsets<GaussianSubset>,
    /// Steps (predictions, with or without their update) so far.
    steps: u64,
}

impl KalmanFilter {
    /// A filter from its [`Setup`]: initial mean and covariance, process and measurement noise
    /// covariances, number of inputs.
    ///
    /// # Errors
    /// Dimension, finiteness, symmetry and positive-definiteness errors naming the matrix.
    pub fn new(setup: Setup) -> Result<Self, EstimatorError> {
        let InitialData { n, m, x0, p0, q, r, inputs } = check_initial_as(setup, Covariances::Semidefinite)?;
        Ok(Self {
            n,
            p: inputs,
            m,
            q,
            r,
            est: GaussianEstimate::initial(x0, p0, StepDetails::NONE),
            x_pred: DVector::zeros(n),
            p_pred: DMatrix::zeros(n, n),
            ap: DMatrix::zeros(n, n),
            innov: DVector::zeros(m),
            upd: GaussianUpdate::new(n, m),
            gate: InnovationGate::new(DataChecks::default(), m)?,
            subsets: Subsets::new(m),
            steps: 0,
        })
    }

    /// The innovation gate (module [`checks`](crate::checks)); by default a measurement outside
    /// it is an error naming the step.
    ///
    /// # Errors
    /// A gate probability outside `(0, 1)`; the filter is unchanged.
    pub fn set_data_checks(&mut self, checks: DataChecks) -> Result<(), EstimatorError> {
        self.gate = InnovationGate::new(checks, self.m)?;
        self.subsets.clear();
        Ok(())
    }

    /// The innovation gate.
    #[must_use]
    pub fn gate(&self) -> &InnovationGate {
        &self.gate
    }

    /// Number of states, inputs, outputs.
    #[must_use]
    pub fn dims(&self) -> Dims {
        Dims::new(self.n, self.p, self.m)
    }

    /// The current estimate.
    #[must_use]
    pub fn estimate(&self) -> &GaussianEstimate {
        &self.est
    }

    /// Replaces both noise matrices in place (each validated first; if either is rejected
    /// nothing changes; no allocation).
    pub fn set_noise(&mut self, q: &DMatrix<f64>, r: &DMatrix<f64>) -> Result<(), EstimatorError> {
        crate::validate::check_spd_no_alloc("R", r, self.m, &mut self.upd.buf.s)?;
        self.set_process_noise(q)?;
        self.set_measurement_noise(r)
    }

    /// Replaces the process-noise covariance `Q` in place (symmetric positive definite, `n × n`;
    /// no allocation; unchanged on error).
    pub fn set_process_noise(&mut self, q: &DMatrix<f64>) -> Result<(), EstimatorError> {
        crate::validate::replace_psd("Q", &mut self.q, q, &mut self.upd.buf.tmp)
    }

    /// Replaces the measurement-noise covariance `R` in place (symmetric positive definite, `m × m`;
    /// no allocation; unchanged on error).
    pub fn set_measurement_noise(&mut self, r: &DMatrix<f64>) -> Result<(), EstimatorError> {
        crate::validate::replace_spd("R", &mut self.r, r, &mut self.upd.buf.s)
    }

    /// The prediction `x⁻ = A x + B u`, `P⁻ = A P Aᵀ + Q`, published. On error the state is
    /// unchanged. Allocation-free.
    ///
    /// # Errors
    /// As [`KalmanFilter::step`].
    pub fn predict<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        check_model(model, self.n, self.p, self.m)?;
        check_vec("u", u, self.p)?;
        self.predict_into_buffers(model.a(), model.b(), u);
        commit_prediction(&mut self.est, &mut self.x_pred, &mut self.p_pred)?;
        self.steps += 1;
        Ok(&self.est)
    }

    /// The measurement update of the current estimate with `y` and the model's `C`, Joseph form.
    /// On error the state is unchanged. Allocation-free.
    ///
    /// # Errors
    /// As [`KalmanFilter::step`].
    pub fn update<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        y: &DVector<f64>,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        check_model(model, self.n, self.p, self.m)?;
        check_vec("y", y, self.m)?;
        self.x_pred.copy_from(&self.est.center);
        self.p_pred.copy_from(&self.est.covariance);
        self.innovate(model.c(), y, model.angles());
        self.gated_update(model.c(), None, self.steps.max(1))
    }

    /// The update of the buffered prediction and innovation with `C` and `r` (`None`: the filter's
    /// `R`), judged by the gate at `step` and published. On error nothing changes.
    fn gated_update(
        &mut self,
        c: &DMatrix<f64>,
        r: Option<&DMatrix<f64>>,
        step: u64,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        let r = r.unwrap_or(&self.r);
        let nis = self.upd.compute(&self.x_pred, &self.p_pred, c, r, &self.innov, self.gate.is_on())?;
        self.upd.commit_gated(
            &self.gate,
            (nis, &self.innov),
            step,
            &mut self.est,
            &mut self.x_pred,
            &mut self.p_pred,
        )?;
        Ok(&self.est)
    }

    /// `ν = y − C x⁻` with angle outputs wrapped to `(−π, π]`, into the innovation buffer.
    fn innovate(&mut self, c: &DMatrix<f64>, y: &DVector<f64>, angles: Angles<'_>) {
        self.innov.copy_from(y);
        (self.upd.kernels.gemv_m)(-1.0, c, &self.x_pred, 1.0, &mut self.innov);
        angles.wrap_outputs(self.innov.as_mut_slice());
    }

    /// `x⁻ = A x + B u`, `P⁻ = A P Aᵀ + Q` into the prediction buffers (allocation-free).
    fn predict_into_buffers(&mut self, a: &DMatrix<f64>, b: &DMatrix<f64>, u: &DVector<f64>) {
        let (x, p) = (&self.est.center, &self.est.covariance);
        (self.upd.kernels.linear_predict)(a, b, x, p, u, &self.q, &mut self.ap, &mut self.x_pred, &mut self.p_pred);
    }

    /// The first half of a step for filters that choose their measurement noise from the
    /// innovation (`adaptive`): validates the data, predicts into the buffers and forms the
    /// innovation `ν = y − C x⁻`; nothing is published. Allocation-free.
    pub(crate) fn predict_and_innovate<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) -> Result<(), EstimatorError> {
        check_model(model, self.n, self.p, self.m)?;
        check_vec("u", u, self.p)?;
        check_vec("y", y, self.m)?;
        self.predict_into_buffers(model.a(), model.b(), u);
        self.innovate(model.c(), y, model.angles());
        Ok(())
    }

    /// The second half: the Joseph-form update of the buffered prediction and innovation with
    /// `C` and the measurement covariance `r` (`m × m`, for example a scaled `R`), published on
    /// success; on error nothing changes. Allocation-free.
    pub(crate) fn update_buffered(
        &mut self,
        c: &DMatrix<f64>,
        r: &DMatrix<f64>,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        self.gated_update(c, Some(r), self.steps + 1)?;
        self.steps += 1;
        Ok(&self.est)
    }

    /// The innovation formed by the last [`KalmanFilter::predict_and_innovate`] or
    /// [`KalmanFilter::innovate_estimate`].
    pub(crate) fn innovation(&self) -> &DVector<f64> {
        &self.innov
    }

    /// Loads the current estimate as the prediction and forms the innovation `ν = y − C x̂`
    /// (an update without a prediction). Allocation-free; nothing is published.
    pub(crate) fn innovate_estimate<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        y: &DVector<f64>,
    ) -> Result<(), EstimatorError> {
        check_model(model, self.n, self.p, self.m)?;
        check_vec("y", y, self.m)?;
        self.x_pred.copy_from(&self.est.center);
        self.p_pred.copy_from(&self.est.covariance);
        self.innovate(model.c(), y, model.angles());
        Ok(())
    }

    /// Sets the details published with the estimate (the adaptive filter's scale).
    pub(crate) fn set_details(&mut self, details: StepDetails) {
        self.est.details = details;
    }

    /// The measurement-noise covariance `R`.
    pub(crate) fn measurement_noise(&self) -> &DMatrix<f64> {
        &self.r
    }

    /// One step, [`KalmanFilter::predict`] then [`KalmanFilter::update`]: consumes `u_k` and the
    /// measurement `y_{k+1}`. On error the state is unchanged. Allocation-free.
    ///
    /// # Errors
    /// Wrong dimensions of the model, `u` or `y`; NaN/∞ in them; an innovation covariance that is
    /// not positive definite or a non-finite estimate ([`EstimatorError::NumericalFailure`]).
    pub fn step<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        check_model(model, self.n, self.p, self.m)?;
        let (a, b, c) = (model.a(), model.b(), model.c());
        check_vec("u", u, self.p)?;
        check_vec("y", y, self.m)?;
        self.predict_into_buffers(a, b, u);
        // Gain, mean and Joseph-form covariance, judged by the innovation gate.
        self.innovate(c, y, model.angles());
        self.gated_update(c, None, self.steps + 1)?;
        self.steps += 1;
        Ok(&self.est)
    }
}

impl KalmanFilter {
    /// One step with the outputs `measured[i]` only (module `partial`): the rows `C_S`, the
    /// sub-block `R_SS`, the innovation gate with `|S|` degrees of freedom; none measured is
    /// [`KalmanFilter::predict`], all is [`KalmanFilter::step`]. Unmeasured entries of `y` are
    /// ignored. Allocation-free after the first step with that many outputs measured.
    ///
    /// # Errors
    /// As [`KalmanFilter::step`]; a mask of another length.
    pub fn step_partial<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        measured: &[bool],
    ) -> Result<&GaussianEstimate, EstimatorError> {
        match self.predict_and_innovate_partial(model, u, y, measured)? {
            Measured::All => self.step(model, u, y),
            Measured::Nothing => self.predict(model, u),
            Measured::Some(k) => self.update_buffered_partial(model.c(), None, k),
        }
    }

    /// The first half of [`KalmanFilter::step_partial`] for filters that choose their measurement
    /// noise from the innovation (`adaptive`): validates and classifies the mask and, for a
    /// proper subset, predicts into the buffers and forms the innovation (its unmeasured entries
    /// are not read); nothing is published. Allocation-free.
    pub(crate) fn predict_and_innovate_partial<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        measured: &[bool],
    ) -> Result<Measured, EstimatorError> {
        check_model(model, self.n, self.p, self.m)?;
        let k = classify(measured, u, y, (self.m, self.p), &mut self.subsets.rows)?;
        if let Measured::Some(_) = k {
            self.predict_into_buffers(model.a(), model.b(), u);
            self.innovate(model.c(), y, model.angles());
        }
        Ok(k)
    }

    /// The second half: the update of the buffered prediction with the `k` rows the last
    /// classification measured, `C_S`, the sub-block of `r` (`m × m`; `None`: `R`) and the gate
    /// with `k` degrees of freedom; published on success, nothing changes on error.
    /// Allocation-free after the first step with `k` outputs measured.
    pub(crate) fn update_buffered_partial(
        &mut self,
        c: &DMatrix<f64>,
        r: Option<&DMatrix<f64>>,
        k: usize,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        let (n, checks, step) = (self.n, self.gate.checks(), self.steps + 1);
        let r = r.unwrap_or(&self.r);
        let (sub, rows) = self.subsets.get(k, || GaussianSubset::new(n, k, checks))?;
        sub.gather(rows, c, r, &self.innov);
        let nis = sub.upd.compute(&self.x_pred, &self.p_pred, &sub.h, &sub.r, &sub.innov, sub.gate.is_on())?;
        sub.upd
            .commit_gated(&sub.gate, (nis, &sub.innov), step, &mut self.est, &mut self.x_pred, &mut self.p_pred)
            .map_err(|e| map_worst_output(e, rows))?;
        self.steps += 1;
        Ok(&self.est)
    }
}

forward_estimator!(impl<> for KalmanFilter, LinearModel, GaussianEstimate, partial);
