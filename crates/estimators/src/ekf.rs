//! The extended Kalman filter over any [`DifferentiableModel`] (truck paper eqs (7)–(11),
//! `docs/truck-ekf.md`), with a Joseph-form covariance update:
//!
//! ```text
//! predict (7), (8):  x⁻ = f(x̂, u),            F = ∂f/∂x (x̂, u),   P⁻ = F P Fᵀ + Q
//! gain (9):          H = ∂h/∂x (x⁻, u),       S = H P⁻ Hᵀ + R = G Gᵀ,   K = P⁻ Hᵀ S⁻¹
//! update (10):       x̂⁺ = x⁻ + K (y − h(x⁻, u))
//! covariance (11):   P⁺ = (I − K H) P⁻ (I − K H)ᵀ + K R Kᵀ      (Joseph form of P = (I − KH) P⁻)
//! ```
//!
//! The measurement `y_{k+1}` is taken after the step and modelled as `h(x_{k+1}, u_k)` (the
//! `models` convention; the truck paper evaluates `h` with the input of the measurement instant,
//! which the caller passes as `u` when it differs). On a linear model the filter is the
//! [`KalmanFilter`](crate::KalmanFilter) (tested to 1e-12). All buffers are allocated in
//! [`ExtendedKalmanFilter::new`]; a step allocates nothing when the model's evaluations do not.

use nalgebra::{DMatrix, DVector};

use models::{DifferentiableModel, Dims};

use crate::checks::map_worst_output;
use crate::checks::{DataChecks, InnovationGate};
use crate::error::EstimatorError;
use crate::gaussian_update::GaussianUpdate;
use crate::gaussian_update::{GaussianEstimate, commit_prediction};
use crate::partial::{GaussianSubset, Measured, Subsets, classify};
use crate::traits::forward_estimator;
use crate::traits::{Setup, StepDetails};
use crate::validate::{Covariances, InitialData, all_finite, check_initial_as, check_vec, replace_psd, replace_spd};

/// An extended Kalman filter; `Q`, `R` are covariances.
#[derive(Debug, Clone)]
pub struct ExtendedKalmanFilter {
    n: usize,
    p: usize,
    m: usize,
    q: DMatrix<f64>,
    r: DMatrix<f64>,
    est: GaussianEstimate,
    x_pred: DVector<f64>,
    f: DMatrix<f64>,
    h: DMatrix<f64>,
    y_pred: DVector<f64>,
    p_pred: DMatrix<f64>,
    fp: DMatrix<f64>,
    innov: DVector<f64>,
    /// The input of the last prediction, for `h` in a following update.
    u_last: DVector<f64>,
    upd: GaussianUpdate,
    gate: InnovationGate,
    /// The updates of partial measurements, by measured count.
    subsets: Subsets<GaussianSubset>,
    /// Steps (predictions, with or without their update) so far.
    steps: u64,
}

impl ExtendedKalmanFilter {
    /// A filter from its [`Setup`] (covariances).
    ///
    /// # Errors
    /// Dimension, finiteness, symmetry and positive-definiteness errors naming the matrix.
    pub fn new(setup: Setup) -> Result<Self, EstimatorError> {
        let InitialData { n, m, x0, p0, q, r, inputs } = check_initial_as(setup, Covariances::Semidefinite)?;
        let nn = || DMatrix::zeros(n, n);
        Ok(Self {
            n,
            p: inputs,
            m,
            q,
            r,
            est: GaussianEstimate::initial(x0, p0, StepDetails::NONE),
            x_pred: DVector::zeros(n),
            f: nn(),
            h: DMatrix::zeros(m, n),
            y_pred: DVector::zeros(m),
            p_pred: nn(),
            fp: nn(),
            innov: DVector::zeros(m),
            u_last: DVector::zeros(inputs),
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

    /// Replaces the process covariance in place (no allocation; unchanged on error).
    ///
    /// # Errors
    /// As [`ExtendedKalmanFilter::new`] for `Q`.
    pub fn set_process_noise(&mut self, q: &DMatrix<f64>) -> Result<(), EstimatorError> {
        replace_psd("Q", &mut self.q, q, &mut self.upd.buf.tmp)
    }

    /// Replaces the measurement covariance in place (no allocation; unchanged on error).
    ///
    /// # Errors
    /// As [`ExtendedKalmanFilter::new`] for `R`.
    pub fn set_measurement_noise(&mut self, r: &DMatrix<f64>) -> Result<(), EstimatorError> {
        replace_spd("R", &mut self.r, r, &mut self.upd.buf.s)
    }

    /// The prediction (7), (8): `x⁻ = f(x̂, u)`, `P⁻ = F P Fᵀ + Q`, published. On error the state
    /// is unchanged.
    ///
    /// # Errors
    /// As [`ExtendedKalmanFilter::step`].
    pub fn predict<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        crate::validate::check_discrete(model, self.n, self.p, self.m)?;
        check_vec("u", u, self.p)?;
        self.predict_into_buffers(model, u)?;
        commit_prediction(&mut self.est, &mut self.x_pred, &mut self.p_pred)?;
        self.u_last.copy_from(u);
        self.steps += 1;
        Ok(&self.est)
    }

    /// The measurement update (9)–(11) of the current estimate with `y`, `h` evaluated with the
    /// input of the last prediction (zero before any). On error the state is unchanged.
    ///
    /// # Errors
    /// As [`ExtendedKalmanFilter::step`].
    pub fn update<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        y: &DVector<f64>,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        crate::validate::check_discrete(model, self.n, self.p, self.m)?;
        check_vec("y", y, self.m)?;
        self.x_pred.copy_from(&self.est.center);
        self.p_pred.copy_from(&self.est.covariance);
        self.measurement_update(model, None, y, self.steps.max(1))
    }

    /// (9)–(11) from the prediction buffers `x_pred`, `p_pred`, with `u` for `h` (`None`: the
    /// input of the last prediction), judged by the innovation gate at `step`; published on
    /// success.
    fn measurement_update<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        u: Option<&DVector<f64>>,
        y: &DVector<f64>,
        step: u64,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        let u = u.unwrap_or(&self.u_last);
        innovate(model, &self.x_pred, u, y, (&mut self.y_pred, &mut self.h, &mut self.innov))?;
        // Gain (9), update (10), covariance (11) in Joseph form.
        let nis = self.upd.compute(&self.x_pred, &self.p_pred, &self.h, &self.r, &self.innov, self.gate.is_on())?;
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

    /// (7), (8): `x⁻ = f(x̂, u)`, `F = ∂f/∂x`, `P⁻ = F P Fᵀ + Q` into the prediction buffers.
    fn predict_into_buffers<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
    ) -> Result<(), EstimatorError> {
        model.f_with_jacobian(&self.est.center, u, &mut self.x_pred, &mut self.f)?;
        if !all_finite(self.x_pred.as_slice()) || !all_finite(self.f.as_slice()) {
            return Err(EstimatorError::NumericalFailure("the model's prediction or its Jacobian is not finite"));
        }
        (self.upd.kernels.propagate)(&self.f, &self.est.covariance, &self.q, &mut self.fp, &mut self.p_pred);
        Ok(())
    }

    /// One step (7)–(11): consumes `u_k` and `y_{k+1}`. On error the state is unchanged.
    ///
    /// # Errors
    /// Wrong dimensions of the model or of `u`, `y`; NaN/∞ in `u`, `y`; a model that cannot
    /// be evaluated ([`EstimatorError::Model`]); a non-finite Jacobian; an innovation covariance
    /// that is not positive definite or a non-finite estimate
    /// ([`EstimatorError::NumericalFailure`]).
    pub fn step<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        crate::validate::check_discrete(model, self.n, self.p, self.m)?;
        check_vec("u", u, self.p)?;
        check_vec("y", y, self.m)?;
        self.predict_into_buffers(model, u)?;
        self.measurement_update(model, Some(u), y, self.steps + 1)?;
        self.u_last.copy_from(u);
        self.steps += 1;
        Ok(&self.est)
    }

    /// One step with the outputs `measured[i]` only (module `partial`): the rows of `h` and `H`,
    /// the sub-block `R_SS`, the gate with `|S|` degrees of freedom; none measured is
    /// [`ExtendedKalmanFilter::predict`], all is [`ExtendedKalmanFilter::step`]. Unmeasured
    /// entries of `y` are ignored. Allocation-free after the first step with that many measured.
    ///
    /// # Errors
    /// As [`ExtendedKalmanFilter::step`]; a mask of another length.
    pub fn step_partial<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        measured: &[bool],
    ) -> Result<&GaussianEstimate, EstimatorError> {
        crate::validate::check_discrete(model, self.n, self.p, self.m)?;
        let k = match classify(measured, u, y, (self.m, self.p), &mut self.subsets.rows)? {
            Measured::All => return self.step(model, u, y),
            Measured::Nothing => return self.predict(model, u),
            Measured::Some(k) => k,
        };
        self.predict_into_buffers(model, u)?;
        innovate(model, &self.x_pred, u, y, (&mut self.y_pred, &mut self.h, &mut self.innov))?;
        let (n, checks, step) = (self.n, self.gate.checks(), self.steps + 1);
        let (sub, rows) = self.subsets.get(k, || GaussianSubset::new(n, k, checks))?;
        sub.gather(rows, &self.h, &self.r, &self.innov);
        let nis = sub.upd.compute(&self.x_pred, &self.p_pred, &sub.h, &sub.r, &sub.innov, sub.gate.is_on())?;
        sub.upd
            .commit_gated(&sub.gate, (nis, &sub.innov), step, &mut self.est, &mut self.x_pred, &mut self.p_pred)
            .map_err(|e| map_worst_output(e, rows))?;
        self.u_last.copy_from(u);
        self.steps += 1;
        Ok(&self.est)
    }
}

/// `ŷ = h(x⁻, u)`, `H = ∂h/∂x` and the innovation `ν = y − ŷ` (angle outputs wrapped) into
/// `(y_pred, h, innov)`.
fn innovate<M: DifferentiableModel + ?Sized>(
    model: &M,
    x_pred: &DVector<f64>,
    u: &DVector<f64>,
    y: &DVector<f64>,
    (y_pred, h, innov): (&mut DVector<f64>, &mut DMatrix<f64>, &mut DVector<f64>),
) -> Result<(), EstimatorError> {
    model.h_with_jacobian(x_pred, u, y_pred, h)?;
    if !all_finite(y_pred.as_slice()) || !all_finite(h.as_slice()) {
        return Err(EstimatorError::NumericalFailure("the model's output or its Jacobian is not finite"));
    }
    innov.copy_from(y);
    *innov -= &*y_pred;
    model.angles().wrap_outputs(innov.as_mut_slice());
    Ok(())
}

forward_estimator!(impl<> for ExtendedKalmanFilter, DifferentiableModel, GaussianEstimate, partial);
