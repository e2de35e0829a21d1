//! The unscented Kalman filter over any [`DiscreteModel`] (only `f` and `h` are needed), with
//! scaled sigma points (Wan & van der Merwe 2000; `docs/dp-vessel.md` (24)–(32) and steps 2–6 of
//! §2, reconstructed):
//!
//! ```text
//! λ = α²(n + κ) − n,   c = n + λ = α²(n + κ) > 0,   γ = √c
//! sigma points (24):   X₀ = m,  X_i = m + γ L_i,  X_{n+i} = m − γ L_i   (L = chol P, columns L_i)
//! weights (25)–(28):   Wm₀ = λ/c,  Wc₀ = λ/c + 1 − α² + β,  Wm_i = Wc_i = 1/(2c)
//! time update:         X'_i = f(X_i, u),  x⁻ = Σ Wm_i X'_i,  P⁻ = Σ Wc_i (X'_i − x⁻)(X'_i − x⁻)ᵀ + Q
//! measurement (29)–(32): redraw X from (x⁻, P⁻),  Z_i = h(X_i, u),  ẑ = Σ Wm_i Z_i,
//!                      Pzz = Σ Wc_i (Z_i − ẑ)(Z_i − ẑ)ᵀ + R,  Pxz = Σ Wc_i (X_i − x⁻)(Z_i − ẑ)ᵀ,
//!                      K = Pxz Pzz⁻¹,  x⁺ = x⁻ + K (y − ẑ),  P⁺ = P⁻ − K Pzz Kᵀ
//! ```
//!
//! The paper's `α = 0.5, β = 2, κ = −2` ([`UkfParams::paper`]) give, for `n = 6`, `c = 1`,
//! `Wm₀ = −5` and `Wc₀ = −2.25`: negative weights are allowed.
//!
//! **Positive-definiteness guard** (the digest's step 6, made precise; [`UkfReport`] counts its
//! uses). With `Wc₀ < 0` the sums above are not guaranteed positive semidefinite. Every
//! covariance is symmetrised and factorised with the workspace's relative pivot test
//! (`dense_kernels::PD_RELATIVE_TOLERANCE`); when that fails:
//!
//! * `P⁻` and `Pzz` (with `Pxz`) are recomputed about the propagated central point instead of
//!   the weighted mean, `Σ_{i≥1} Wc_i (X'_i − X'₀)(X'_i − X'₀)ᵀ + Q` (Julier's modified form):
//!   every weight in that sum is `1/(2c) > 0`, so the result is at least `Q` (resp. `R`) and
//!   positive definite;
//! * `P⁺` is recomputed in Joseph form with the statistically linearised output matrix
//!   `H = Pxzᵀ P⁻⁻¹`: `P⁺ = (I − K H) P⁻ (I − K H)ᵀ + K R Kᵀ`, positive semidefinite by
//!   construction and equal to `P⁻ − K Pzz Kᵀ` when `h` is linear.
//!
//! If a guarded covariance still fails the test the step is refused with
//! [`EstimatorError::NumericalFailure`]. So the published covariance is always positive definite.
//!
//! When is the guard needed? With `d_i = Y_i − Y₀` and `S = Σ_{i≥1} W_i d_i`, the identities
//! `Σ Wm = 1` and `Wc₀ − Wm₀ = 1 − α² + β` give
//! `Σ Wc_i (Y_i − ȳ)(Y_i − ȳ)ᵀ = Σ_{i≥1} W_i d_i d_iᵀ + (β − α²) S Sᵀ`, and Cauchy–Schwarz
//! (`Σ_{i≥1} W_i = n/c`) bounds the first sum below by `(c/n) S Sᵀ`. So the sample covariance is
//! positive semidefinite whenever `β ≥ −α² κ / n`, whatever the sign of `Wc₀` — in particular for
//! the paper's `α = 0.5, β = 2, κ = −2` (`Wc₀ = −2.25`), where the guard fires only on rounding.
//! It matters for `β < −α² κ / n` (tested with `β = −10`).
//!
//! On a linear model the central point is the mean, `Wc₀` multiplies a zero matrix, and the
//! filter is the Kalman filter (tested to 1e-9). All buffers are allocated in
//! [`UnscentedKalmanFilter::new`]; a step allocates nothing when the model's evaluations do not.
//! On error the filter is unchanged.

use nalgebra::{DMatrix, DVector};

use dense_kernels as dense;
use models::{Angles, Dims, DiscreteModel, wrap_angle};

use crate::checks::{DataChecks, GateVerdict, InnovationGate, map_worst_output, name_worst_output};
use crate::error::EstimatorError;
use crate::gaussian_update::{GaussianEstimate, data_check, nis};
use crate::partial::{self, Measured, Subsets, classify};
use crate::traits::forward_estimator;
use crate::traits::{Setup, SolveOutcome, StepDetails, StepStatus};
use crate::validate::{Covariances, InitialData, check_initial_as, check_vec, replace_psd, replace_spd};

/// The scaling parameters of the sigma points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UkfParams {
    /// Spread `α > 0`.
    pub alpha: f64,
    /// Prior-distribution weight `β` (2 is optimal for Gaussians).
    pub beta: f64,
    /// Secondary scaling `κ`; `α²(n + κ)` must be positive.
    pub kappa: f64,
}

impl UkfParams {
    /// The paper's `α = 0.5, β = 2, κ = −2` **\[P\]** (valid for `n > 2`).
    #[must_use]
    pub fn paper() -> Self {
        Self { alpha: 0.5, beta: 2.0, kappa: -2.0 }
    }

    /// The weights for `n` states: `(c, Wm₀, Wc₀, W_i)`.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidSetting`] for a non-positive or non-finite `α`, a non-finite
    /// `β` or `κ`, or `c = α²(n + κ) ≤ 0`.
    pub fn weights(&self, n: usize) -> Result<(f64, f64, f64, f64), EstimatorError> {
        if !(self.alpha.is_finite() && self.alpha > 0.0) {
            return Err(EstimatorError::InvalidSetting { what: "UKF alpha", value: self.alpha, requirement: "> 0" });
        }
        if !self.beta.is_finite() {
            return Err(EstimatorError::InvalidSetting { what: "UKF beta", value: self.beta, requirement: "finite" });
        }
        if !self.kappa.is_finite() {
            return Err(EstimatorError::InvalidSetting { what: "UKF kappa", value: self.kappa, requirement: "finite" });
        }
        let c = self.alpha * self.alpha * (n as f64 + self.kappa);
        if !(c.is_finite() && c > 0.0) {
            return Err(EstimatorError::InvalidSetting {
                what: "UKF c = alpha^2 (n + kappa)",
                value: c,
                requirement: "> 0 (kappa > -n)",
            });
        }
        let lambda = c - n as f64;
        Ok((c, lambda / c, lambda / c + 1.0 - self.alpha * self.alpha + self.beta, 0.5 / c))
    }
}

impl Default for UkfParams {
    /// `α = 1, β = 2, κ = 0`: `c = n`, `Wm₀ = 0`, `Wc₀ = 2`, no negative weight, valid for every
    /// `n` (the registry's default).
    fn default() -> Self {
        Self { alpha: 1.0, beta: 2.0, kappa: 0.0 }
    }
}

/// What the last step did beyond the plain recursion.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct UkfReport {
    /// The predicted covariance `P⁻` needed the guard in the last step.
    pub guarded_prediction: bool,
    /// `Pzz` needed the guard in the last step.
    pub guarded_innovation: bool,
    /// `P⁺` needed the Joseph-form guard in the last step.
    pub guarded_update: bool,
    /// Guard uses since construction (all three kinds).
    pub guard_total: u64,
}

/// An unscented Kalman filter; `Q`, `R` are covariances.
#[derive(Debug, Clone)]
pub struct UnscentedKalmanFilter {
    n: usize,
    p: usize,
    m: usize,
    params: UkfParams,
    gamma: f64,
    wm0: f64,
    wc0: f64,
    wi: f64,
    q: DMatrix<f64>,
    est: GaussianEstimate,
    report: UkfReport,
    // Buffers (allocated once).
    /// The Cholesky factor of the published covariance when `chol_current`, else scratch.
    chol: DMatrix<f64>,
    /// Whether `chol` is the factor of `est.covariance` (kept from the update that published it,
    /// so the next prediction need not factorise it again).
    chol_current: bool,
    sig: DMatrix<f64>,
    prop: DMatrix<f64>,
    xcol: DVector<f64>,
    fcol: DVector<f64>,
    zcol: DVector<f64>,
    x_pred: DVector<f64>,
    p_pred: DMatrix<f64>,
    p_pred_chol: DMatrix<f64>,
    ikh: DMatrix<f64>,
    tmp_nn: DMatrix<f64>,
    x_new: DVector<f64>,
    p_new: DMatrix<f64>,
    p_new_chol: DMatrix<f64>,
    /// Deviations of the sigma points (or their images) from a centre, one per column, and the
    /// same columns times their weights `Wc_i`: the covariances are `dev_w devᵀ`.
    dev_x: DMatrix<f64>,
    dev_xw: DMatrix<f64>,
    /// The input of the last prediction, for `h` in a following update.
    u_last: DVector<f64>,
    /// The update's buffers sized by the outputs: all `m` of them (with `R` and the gate).
    meas: MeasurementBuffers,
    /// The same for partial measurements, by measured count (swapped with `meas`).
    subsets: Subsets<PartialWork>,
    /// Steps (predictions, with or without their update) so far.
    steps: u64,
}

/// The buffers of the update sized by its outputs (`k` of `m`), with `R` and the gate of that
/// size: the filter's own (`k = m`), or a partial measurement's, swapped in for its update
/// ([`UnscentedKalmanFilter::step_partial`]).
#[derive(Debug, Clone)]
struct MeasurementBuffers {
    zsig: DMatrix<f64>,
    z_pred: DVector<f64>,
    pzz: DMatrix<f64>,
    pzz_chol: DMatrix<f64>,
    pxz: DMatrix<f64>,
    k: DMatrix<f64>,
    h_stat: DMatrix<f64>,
    kr: DMatrix<f64>,
    dev_z: DMatrix<f64>,
    dev_zw: DMatrix<f64>,
    dz: DVector<f64>,
    innov: DVector<f64>,
    r: DMatrix<f64>,
    gate: InnovationGate,
}

/// A partial measurement's workspace: its buffers, the measured entries of `y` and the positions
/// of the angle outputs among them.
#[derive(Debug, Clone)]
struct PartialWork {
    buffers: MeasurementBuffers,
    y: DVector<f64>,
    angle_outputs: Vec<usize>,
}

impl MeasurementBuffers {
    fn new(n: usize, k: usize, checks: DataChecks) -> Result<Self, EstimatorError> {
        let s = 2 * n + 1;
        Ok(Self {
            zsig: DMatrix::zeros(k, s),
            z_pred: DVector::zeros(k),
            pzz: DMatrix::zeros(k, k),
            pzz_chol: DMatrix::zeros(k, k),
            pxz: DMatrix::zeros(n, k),
            k: DMatrix::zeros(n, k),
            h_stat: DMatrix::zeros(k, n),
            kr: DMatrix::zeros(n, k),
            dev_z: DMatrix::zeros(k, s),
            dev_zw: DMatrix::zeros(k, s),
            dz: DVector::zeros(k),
            innov: DVector::zeros(k),
            r: DMatrix::zeros(k, k),
            gate: InnovationGate::new(checks, k)?,
        })
    }
}

/// Copies the symmetric `src` into `dst` and factorises it there; `true` if it is positive
/// definite to working precision (the pivot rule of `dense_kernels`).
fn factor_pd(src: &DMatrix<f64>, dst: &mut DMatrix<f64>) -> bool {
    dst.copy_from(src);
    dense::cholesky_in_place(dst).is_ok()
}

/// `dev = points − centre` column by column and `dev_w` = its columns times `Wc₀` (the first)
/// and `Wc_i` (the others); `centre` is a vector (`Some`) or the first point (`None`, whose own
/// deviation is then exactly 0, as the guard's sum leaves it out). Deviations of the
/// `angle_rows` are wrapped to `(−π, π]`.
fn deviations(
    points: &DMatrix<f64>,
    centre: Option<&DVector<f64>>,
    (w0, wi): (f64, f64),
    dev: &mut DMatrix<f64>,
    dev_w: &mut DMatrix<f64>,
    angle_rows: &[usize],
) {
    let rows = points.nrows();
    let src = points.as_slice();
    let (first, _) = src.split_at(rows);
    let c = centre.map_or(first, |c| c.as_slice());
    for (j, ((col, d), dw)) in src
        .chunks_exact(rows)
        .zip(dev.as_mut_slice().chunks_exact_mut(rows))
        .zip(dev_w.as_mut_slice().chunks_exact_mut(rows))
        .enumerate()
    {
        let w = if j == 0 { w0 } else { wi };
        for (((d, dw), p), c) in d.iter_mut().zip(dw.iter_mut()).zip(col).zip(c) {
            *d = p - c;
            *dw = w * *d;
        }
        for &r in angle_rows {
            d[r] = wrap_angle(d[r]);
            dw[r] = w * d[r];
        }
    }
}

/// `out = Σ_j w_j points_j` (the weighted mean, `Wm₀` for the first point, `Wm_i` for the others).
///
/// The `angle_rows` take the circular mean about the first (central) point,
/// `p₀ + Σ_j w_j wrap(p_j − p₀)` (the weights sum to one): the linear mean whenever no point
/// lies more than π from the central one (then it is left as computed, bit for bit), and the
/// mean on the circle, continuous with the central point, when the points straddle ±π. Unlike
/// `atan2(Σ w sin, Σ w cos)` it does not shrink the mean of a wide spread, and it keeps the
/// branch of the central point, so a heading is never wrapped by the filter.
fn weighted_mean(points: &DMatrix<f64>, (w0, wi): (f64, f64), out: &mut DVector<f64>, angle_rows: &[usize]) {
    let rows = points.nrows();
    let out = out.as_mut_slice();
    out.fill(0.0);
    for (j, col) in points.as_slice().chunks_exact(rows).enumerate() {
        let w = if j == 0 { w0 } else { wi };
        for (o, p) in out.iter_mut().zip(col) {
            *o += w * p;
        }
    }
    let src = points.as_slice();
    for &r in angle_rows {
        let centre = src[r];
        let straddles = src.chunks_exact(rows).any(|col| wrap_angle(col[r] - centre) != col[r] - centre);
        if straddles {
            let sum: f64 = src
                .chunks_exact(rows)
                .enumerate()
                .map(|(j, col)| if j == 0 { 0.0 } else { wi * wrap_angle(col[r] - centre) })
                .sum();
            out[r] = centre + sum;
        }
    }
}

impl UnscentedKalmanFilter {
    /// A filter from its [`Setup`] (covariances) and sigma-point parameters `params`.
    ///
    /// # Errors
    /// Dimension, finiteness, symmetry and positive-definiteness errors naming the matrix;
    /// [`EstimatorError::InvalidSetting`] for `params` (see [`UkfParams::weights`]).
    pub fn new(setup: Setup, params: UkfParams) -> Result<Self, EstimatorError> {
        let InitialData { n, m, x0, p0, q, r, inputs } = check_initial_as(setup, Covariances::DefinitePrior)?;
        let (c, wm0, wc0, wi) = params.weights(n)?;
        let s = 2 * n + 1;
        let nn = || DMatrix::zeros(n, n);
        Ok(Self {
            n,
            p: inputs,
            m,
            params,
            gamma: c.sqrt(),
            wm0,
            wc0,
            wi,
            q,
            est: GaussianEstimate::initial(x0, p0, StepDetails::NONE),
            report: UkfReport::default(),
            chol: nn(),
            chol_current: false,
            sig: DMatrix::zeros(n, s),
            prop: DMatrix::zeros(n, s),
            xcol: DVector::zeros(n),
            fcol: DVector::zeros(n),
            zcol: DVector::zeros(m),
            x_pred: DVector::zeros(n),
            p_pred: nn(),
            p_pred_chol: nn(),
            ikh: nn(),
            tmp_nn: nn(),
            x_new: DVector::zeros(n),
            p_new: nn(),
            p_new_chol: nn(),
            dev_x: DMatrix::zeros(n, s),
            dev_xw: DMatrix::zeros(n, s),
            u_last: DVector::zeros(inputs),
            meas: MeasurementBuffers::new(n, m, DataChecks::default()).map(|mut b| {
                b.r = r;
                b
            })?,
            subsets: Subsets::new(m),
            steps: 0,
        })
    }

    /// The innovation gate (module [`checks`](crate::checks)) on `Pzz`; by default a measurement
    /// outside it is an error naming the step.
    ///
    /// # Errors
    /// A gate probability outside `(0, 1)`; the filter is unchanged.
    pub fn set_data_checks(&mut self, checks: DataChecks) -> Result<(), EstimatorError> {
        self.meas.gate = InnovationGate::new(checks, self.m)?;
        self.subsets.clear();
        Ok(())
    }

    /// The current estimate.
    #[must_use]
    pub fn estimate(&self) -> &GaussianEstimate {
        &self.est
    }

    /// Number of states, inputs, outputs.
    #[must_use]
    pub fn dims(&self) -> Dims {
        Dims::new(self.n, self.p, self.m)
    }

    /// The sigma-point parameters.
    pub fn params(&self) -> UkfParams {
        self.params
    }

    /// The weights `(Wm₀, Wc₀, W_i)` in use.
    pub fn weights(&self) -> (f64, f64, f64) {
        (self.wm0, self.wc0, self.wi)
    }

    /// What the last step did (guard uses).
    pub fn report(&self) -> UkfReport {
        self.report
    }

    /// Replaces the process covariance in place (no allocation; unchanged on error).
    ///
    /// # Errors
    /// As [`UnscentedKalmanFilter::new`] for `Q`.
    pub fn set_process_noise(&mut self, q: &DMatrix<f64>) -> Result<(), EstimatorError> {
        replace_psd("Q", &mut self.q, q, &mut self.tmp_nn)
    }

    /// Replaces the measurement covariance in place (no allocation; unchanged on error).
    ///
    /// # Errors
    /// As [`UnscentedKalmanFilter::new`] for `R`.
    pub fn set_measurement_noise(&mut self, r: &DMatrix<f64>) -> Result<(), EstimatorError> {
        replace_spd("R", &mut self.meas.r, r, &mut self.meas.pzz_chol)
    }

    /// Sigma points (24) of `mean` with the lower factor `l` into `sig`.
    fn draw(sig: &mut DMatrix<f64>, mean: &DVector<f64>, l: &DMatrix<f64>, gamma: f64) {
        let n = mean.len();
        let (centre, rest) = sig.as_mut_slice().split_at_mut(n);
        centre.copy_from_slice(mean.as_slice());
        let (plus, minus) = rest.split_at_mut(n * n);
        let mean = mean.as_slice();
        for ((p, m), l) in plus.chunks_exact_mut(n).zip(minus.chunks_exact_mut(n)).zip(l.as_slice().chunks_exact(n)) {
            for (((p, m), l), c) in p.iter_mut().zip(m.iter_mut()).zip(l).zip(mean) {
                let d = gamma * l;
                *p = c + d;
                *m = c - d;
            }
        }
    }

    /// Time update into `x_pred`, `P⁻` (`p_pred`) and its factor `p_pred_chol`.
    fn predict_into_buffers<M: DiscreteModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
    ) -> Result<bool, EstimatorError> {
        let (n, s) = (self.n, 2 * self.n + 1);
        if !self.chol_current {
            if !factor_pd(&self.est.covariance, &mut self.chol) {
                return Err(EstimatorError::NumericalFailure("the covariance is not positive definite"));
            }
            self.chol_current = true;
        }
        Self::draw(&mut self.sig, &self.est.center, &self.chol, self.gamma);
        for j in 0..s {
            self.xcol.as_mut_slice().copy_from_slice(&self.sig.as_slice()[j * n..(j + 1) * n]);
            model.f(&self.xcol, u, &mut self.fcol)?;
            self.prop.as_mut_slice()[j * n..(j + 1) * n].copy_from_slice(self.fcol.as_slice());
        }
        if self.prop.as_slice().iter().any(|v| !v.is_finite()) {
            return Err(EstimatorError::NumericalFailure("the model's prediction of a sigma point is not finite"));
        }
        weighted_mean(&self.prop, (self.wm0, self.wi), &mut self.x_pred, model.angles().states);
        // P⁻ about the mean; the guard recomputes it about the central point.
        let mut guarded = false;
        for attempt in 0..2 {
            let centre = (attempt == 0).then_some(&self.x_pred);
            deviations(
                &self.prop,
                centre,
                (self.wc0, self.wi),
                &mut self.dev_x,
                &mut self.dev_xw,
                model.angles().states,
            );
            self.p_pred.copy_from(&self.q);
            dense::mul_nt(1.0, &self.dev_xw, &self.dev_x, 1.0, &mut self.p_pred);
            dense::symmetrize(&mut self.p_pred);
            if factor_pd(&self.p_pred, &mut self.p_pred_chol) {
                return Ok(guarded);
            }
            guarded = true;
        }
        Err(EstimatorError::NumericalFailure("the predicted covariance is not positive definite"))
    }

    /// A prediction-only step: the time update, published. On error the state is unchanged.
    ///
    /// # Errors
    /// As [`UnscentedKalmanFilter::step`].
    pub fn predict<M: DiscreteModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        crate::validate::check_discrete(model, self.n, self.p, self.m)?;
        check_vec("u", u, self.p)?;
        let guarded = self.predict_into_buffers(model, u)?;
        std::mem::swap(&mut self.est.center, &mut self.x_pred);
        std::mem::swap(&mut self.est.covariance, &mut self.p_pred);
        self.chol_current = false;
        self.est.refresh_std_dev();
        self.report.guarded_prediction = guarded;
        self.report.guarded_innovation = false;
        self.report.guarded_update = false;
        self.report.guard_total += u64::from(guarded);
        self.u_last.copy_from(u);
        self.steps += 1;
        self.publish_report(SolveOutcome::Predicted);
        Ok(&self.est)
    }

    /// Writes the status from the report (a fallback when a guard was needed in this step); the
    /// report itself is [`UnscentedKalmanFilter::report`].
    fn publish_report(&mut self, outcome: SolveOutcome) {
        let r = self.report;
        let guarded = r.guarded_prediction || r.guarded_innovation || r.guarded_update;
        self.est.status = StepStatus::unchecked(if guarded { SolveOutcome::FallbackUsed } else { outcome });
    }

    /// The measurement update (29)–(32) of the current estimate with `y`, `h` evaluated with the
    /// input of the last prediction (zero before any). On error the state is unchanged.
    ///
    /// # Errors
    /// As [`UnscentedKalmanFilter::step`].
    pub fn update<M: DiscreteModel + ?Sized>(
        &mut self,
        model: &M,
        y: &DVector<f64>,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        crate::validate::check_discrete(model, self.n, self.p, self.m)?;
        check_vec("y", y, self.m)?;
        self.load_prediction_from_estimate()?;
        self.update_from_prediction(model, None, y, false, self.steps.max(1))
    }

    /// Copies the current estimate into the prediction buffers and factorises it.
    fn load_prediction_from_estimate(&mut self) -> Result<(), EstimatorError> {
        self.x_pred.copy_from(&self.est.center);
        self.p_pred.copy_from(&self.est.covariance);
        if !factor_pd(&self.p_pred, &mut self.p_pred_chol) {
            return Err(EstimatorError::NumericalFailure("the covariance is not positive definite"));
        }
        Ok(())
    }

    /// One step: time update with `u_k`, measurement update with `y_{k+1}`. On error the state
    /// is unchanged.
    ///
    /// # Errors
    /// Wrong dimensions of the model or of `u`, `y`; NaN/∞ in `u`, `y`; a model that cannot be
    /// evaluated ([`EstimatorError::Model`]); a non-finite sigma-point image, or a covariance the
    /// guard cannot make positive definite ([`EstimatorError::NumericalFailure`]).
    pub fn step<M: DiscreteModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        crate::validate::check_discrete(model, self.n, self.p, self.m)?;
        check_vec("u", u, self.p)?;
        check_vec("y", y, self.m)?;
        let guarded_prediction = self.predict_into_buffers(model, u)?;
        self.update_from_prediction(model, Some(u), y, guarded_prediction, self.steps + 1)?;
        self.u_last.copy_from(u);
        self.steps += 1;
        Ok(&self.est)
    }

    /// One step with the outputs `measured[i]` only (module `partial`): the sigma points mapped
    /// through the whole `h`, then the update (30)–(32) with their measured rows, `R_SS` and the
    /// gate with `|S|` degrees of freedom; none measured is [`UnscentedKalmanFilter::predict`],
    /// all is [`UnscentedKalmanFilter::step`]. Unmeasured entries of `y` are ignored.
    /// Allocation-free after the first step with that many outputs measured.
    ///
    /// # Errors
    /// As [`UnscentedKalmanFilter::step`]; a mask of another length.
    pub fn step_partial<M: DiscreteModel + ?Sized>(
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
        let (guarded_prediction, saved_chol) = (self.predict_into_buffers(model, u)?, self.chol_current);
        self.sigma_outputs(model, Some(u))?;
        let step = self.steps + 1;
        self.update_rows(model, y, k, guarded_prediction, step).inspect_err(|_| self.chol_current = saved_chol)?;
        self.u_last.copy_from(u);
        self.steps += 1;
        Ok(&self.est)
    }

    /// Replaces the state by `(mean, covariance)` (for an arrival-cost update that starts from
    /// another estimator's estimate). Allocation-free; on error the filter is unchanged.
    ///
    /// # Errors
    /// Wrong sizes, non-finite entries, a covariance that is not symmetric positive definite.
    pub fn reset(&mut self, mean: &DVector<f64>, covariance: &DMatrix<f64>) -> Result<(), EstimatorError> {
        check_vec("mean", mean, self.n)?;
        if covariance.shape() != (self.n, self.n) {
            return Err(EstimatorError::DimensionMismatch {
                what: "covariance",
                expected: self.n,
                found: covariance.nrows(),
            });
        }
        if let Some(index) = covariance.iter().position(|v| !v.is_finite()) {
            return Err(EstimatorError::NonFinite { what: "covariance", index });
        }
        if dense::max_asymmetry(covariance, dense::SYMMETRY_TOLERANCE).is_some() {
            return Err(EstimatorError::NotSymmetric { what: "covariance" });
        }
        // `chol` is scratch here: it no longer holds the published covariance's factor.
        self.chol_current = false;
        if !factor_pd(covariance, &mut self.chol) {
            return Err(EstimatorError::NotPositiveDefinite { what: "covariance" });
        }
        self.est.center.copy_from(mean);
        self.est.covariance.copy_from(covariance);
        dense::symmetrize(&mut self.est.covariance);
        self.est.refresh_std_dev();
        Ok(())
    }

    /// A measurement update only, (29)–(32), of the current state with `y` (`u` is passed to
    /// `h`): the first half of the arrival-cost update of the vessel paper's §3.2 (update with
    /// `y_s`, then [`UnscentedKalmanFilter::predict`] with `u_s`). On error the state is unchanged.
    ///
    /// # Errors
    /// As [`UnscentedKalmanFilter::step`].
    pub fn correct<M: DiscreteModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        crate::validate::check_discrete(model, self.n, self.p, self.m)?;
        check_vec("u", u, self.p)?;
        check_vec("y", y, self.m)?;
        self.load_prediction_from_estimate()?;
        self.update_from_prediction(model, Some(u), y, false, self.steps.max(1))
    }

    /// [`UnscentedKalmanFilter::correct`] with the outputs `measured[i]` only (the update of
    /// [`UnscentedKalmanFilter::step_partial`]); with none measured the state is unchanged.
    /// On error the state is unchanged.
    ///
    /// # Errors
    /// As [`UnscentedKalmanFilter::step_partial`].
    pub fn correct_partial<M: DiscreteModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        measured: &[bool],
    ) -> Result<&GaussianEstimate, EstimatorError> {
        crate::validate::check_discrete(model, self.n, self.p, self.m)?;
        let k = match classify(measured, u, y, (self.m, self.p), &mut self.subsets.rows)? {
            Measured::All => return self.correct(model, u, y),
            Measured::Nothing => return Ok(&self.est),
            Measured::Some(k) => k,
        };
        self.load_prediction_from_estimate()?;
        let saved_chol = self.chol_current;
        self.sigma_outputs(model, Some(u))?;
        self.update_rows(model, y, k, false, self.steps.max(1)).inspect_err(|_| self.chol_current = saved_chol)?;
        Ok(&self.est)
    }

    /// The update (30)–(32) with the measured rows `subsets.rows` (`k` of them) of the sigma
    /// points' images in `zsig`, of `R` and of `y`, in the buffers for `k` outputs.
    fn update_rows<M: DiscreteModel + ?Sized>(
        &mut self,
        model: &M,
        y: &DVector<f64>,
        k: usize,
        guarded_prediction: bool,
        step: u64,
    ) -> Result<(), EstimatorError> {
        let (n, m, checks) = (self.n, self.m, self.meas.gate.checks());
        self.subsets.get(k, || {
            let buffers = MeasurementBuffers::new(n, k, checks)?;
            Ok(PartialWork { buffers, y: DVector::zeros(k), angle_outputs: Vec::with_capacity(m) })
        })?;
        let Some(mut work) = self.subsets.take(k) else {
            return Err(EstimatorError::NumericalFailure("the partial update's buffers are missing"));
        };
        let rows = &self.subsets.rows;
        partial::gather_rows(&self.meas.zsig, rows, &mut work.buffers.zsig);
        partial::gather_block(&self.meas.r, rows, &mut work.buffers.r);
        for (a, &i) in rows.iter().enumerate() {
            work.y[a] = y[i];
        }
        partial::angle_positions(rows, model.angles().outputs, &mut work.angle_outputs);
        std::mem::swap(&mut self.meas, &mut work.buffers);
        let angles = Angles::new(model.angles().states, &work.angle_outputs);
        let result = self.update_core(&work.y, angles, guarded_prediction, step).map(|_| ());
        std::mem::swap(&mut self.meas, &mut work.buffers);
        self.subsets.put(k, work);
        result.map_err(|e| map_worst_output(e, &self.subsets.rows))
    }

    /// The measurement update (29)–(32) from `x_pred`, `p_pred` (factor in `p_pred_chol`).
    /// `u` is the input for `h` (`None`: the input of the last prediction).
    fn update_from_prediction<M: DiscreteModel + ?Sized>(
        &mut self,
        model: &M,
        u: Option<&DVector<f64>>,
        y: &DVector<f64>,
        guarded_prediction: bool,
        step: u64,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        self.sigma_outputs(model, u)?;
        let angles = model.angles();
        self.update_core(y, angles, guarded_prediction, step)
    }

    /// Redraws the sigma points from `(x⁻, P⁻)` and maps them through `h` (29) into `zsig`
    /// (`u`: the input for `h`, `None` for the last prediction's).
    fn sigma_outputs<M: DiscreteModel + ?Sized>(
        &mut self,
        model: &M,
        u: Option<&DVector<f64>>,
    ) -> Result<(), EstimatorError> {
        let (n, m, s) = (self.n, self.zcol.len(), 2 * self.n + 1);
        let u = u.unwrap_or(&self.u_last);
        Self::draw(&mut self.sig, &self.x_pred, &self.p_pred_chol, self.gamma);
        for j in 0..s {
            self.xcol.as_mut_slice().copy_from_slice(&self.sig.as_slice()[j * n..(j + 1) * n]);
            model.h(&self.xcol, u, &mut self.zcol)?;
            self.meas.zsig.as_mut_slice()[j * m..(j + 1) * m].copy_from_slice(self.zcol.as_slice());
        }
        if self.meas.zsig.as_slice().iter().any(|v| !v.is_finite()) {
            return Err(EstimatorError::NumericalFailure("the model's output at a sigma point is not finite"));
        }
        Ok(())
    }

    /// The update (30)–(32) from the sigma points' images in `zsig` and the measurement `y`
    /// (the rows the measurement buffers hold; `angles.outputs` indexes them).
    fn update_core(
        &mut self,
        y: &DVector<f64>,
        angles: Angles<'_>,
        guarded_prediction: bool,
        step: u64,
    ) -> Result<&GaussianEstimate, EstimatorError> {
        weighted_mean(&self.meas.zsig, (self.wm0, self.wi), &mut self.meas.z_pred, angles.outputs);
        // Pzz, Pxz (30)–(31); guard: about the central point. X₀ = x⁻: the sigma points'
        // centre is the same in both forms, and the first column of `dev_x` is exactly 0.
        deviations(
            &self.sig,
            Some(&self.x_pred),
            (self.wc0, self.wi),
            &mut self.dev_x,
            &mut self.dev_xw,
            angles.states,
        );
        let mut guarded_innovation = false;
        let mut ok = false;
        for attempt in 0..2 {
            let centre = (attempt == 0).then_some(&self.meas.z_pred);
            deviations(
                &self.meas.zsig,
                centre,
                (self.wc0, self.wi),
                &mut self.meas.dev_z,
                &mut self.meas.dev_zw,
                angles.outputs,
            );
            self.meas.pzz.copy_from(&self.meas.r);
            dense::mul_nt(1.0, &self.meas.dev_zw, &self.meas.dev_z, 1.0, &mut self.meas.pzz);
            dense::mul_nt(1.0, &self.dev_x, &self.meas.dev_zw, 0.0, &mut self.meas.pxz);
            dense::symmetrize(&mut self.meas.pzz);
            if factor_pd(&self.meas.pzz, &mut self.meas.pzz_chol) {
                ok = true;
                break;
            }
            guarded_innovation = true;
        }
        if !ok {
            return Err(EstimatorError::NumericalFailure("the innovation covariance is not positive definite"));
        }
        self.meas.innov.copy_from(y);
        self.meas.innov -= &self.meas.z_pred;
        angles.wrap_outputs(self.meas.innov.as_mut_slice());
        // The innovation gate on Pzz, before anything changes; an overflowing innovation is a
        // failure of this step whatever the gate (as in the Kalman filters' update).
        let nis = nis(&self.meas.pzz_chol, &self.meas.innov, &mut self.meas.dz);
        if !nis.is_finite() {
            return Err(EstimatorError::NumericalFailure(crate::gaussian_update::INNOVATION_OVERFLOW));
        }
        let nis = if self.meas.gate.is_on() { nis } else { f64::NAN };
        let verdict =
            self.meas.gate.judge(nis, step).map_err(|e| name_worst_output(e, &self.meas.innov, &self.meas.pzz_chol))?;
        if verdict == GateVerdict::Drop {
            // The measurement is dropped: publish the prediction.
            std::mem::swap(&mut self.est.center, &mut self.x_pred);
            std::mem::swap(&mut self.est.covariance, &mut self.p_pred);
            self.chol_current = false;
            self.est.refresh_std_dev();
            self.report.guarded_prediction = guarded_prediction;
            self.report.guarded_innovation = guarded_innovation;
            self.report.guarded_update = false;
            self.report.guard_total += u64::from(guarded_prediction) + u64::from(guarded_innovation);
            self.publish_report(SolveOutcome::Predicted);
            self.est.status.data = data_check(verdict);
            return Ok(&self.est);
        }
        // K = Pxz Pzz⁻¹ (32), by two triangular solves with the factor of Pzz.
        self.meas.k.copy_from(&self.meas.pxz);
        dense::solve_right_lower_t(&mut self.meas.k, &self.meas.pzz_chol);
        dense::solve_right_lower(&mut self.meas.k, &self.meas.pzz_chol);
        self.x_new.copy_from(&self.x_pred);
        dense::gemv(1.0, &self.meas.k, &self.meas.innov, 1.0, &mut self.x_new);
        // P⁺ = P⁻ − K Pzz Kᵀ = P⁻ − K Pxzᵀ.
        self.p_new.copy_from(&self.p_pred);
        dense::mul_nt(-1.0, &self.meas.k, &self.meas.pxz, 1.0, &mut self.p_new);
        dense::symmetrize(&mut self.p_new);
        let mut guarded_update = false;
        if !factor_pd(&self.p_new, &mut self.p_new_chol) {
            // Joseph form with H = Pxzᵀ P⁻⁻¹ (statistical linearisation).
            guarded_update = true;
            self.meas.h_stat.tr_copy_from(&self.meas.pxz);
            dense::solve_right_lower_t(&mut self.meas.h_stat, &self.p_pred_chol);
            dense::solve_right_lower(&mut self.meas.h_stat, &self.p_pred_chol);
            dense::i_minus_lc(&self.meas.k, &self.meas.h_stat, &mut self.ikh);
            dense::mul_nn(1.0, &self.ikh, &self.p_pred, 0.0, &mut self.tmp_nn);
            dense::mul_nt(1.0, &self.tmp_nn, &self.ikh, 0.0, &mut self.p_new);
            dense::mul_nn(1.0, &self.meas.k, &self.meas.r, 0.0, &mut self.meas.kr);
            dense::mul_nt(1.0, &self.meas.kr, &self.meas.k, 1.0, &mut self.p_new);
            dense::symmetrize(&mut self.p_new);
            if !factor_pd(&self.p_new, &mut self.p_new_chol) {
                return Err(EstimatorError::NumericalFailure("the updated covariance is not positive definite"));
            }
        }
        if self.x_new.iter().any(|v| !v.is_finite()) {
            return Err(EstimatorError::NumericalFailure("the estimate is not finite"));
        }
        std::mem::swap(&mut self.est.center, &mut self.x_new);
        std::mem::swap(&mut self.est.covariance, &mut self.p_new);
        // `p_new_chol` is the factor of the covariance just published.
        std::mem::swap(&mut self.chol, &mut self.p_new_chol);
        self.chol_current = true;
        self.est.refresh_std_dev();
        self.report.guarded_prediction = guarded_prediction;
        self.report.guarded_innovation = guarded_innovation;
        self.report.guarded_update = guarded_update;
        self.report.guard_total +=
            u64::from(guarded_prediction) + u64::from(guarded_innovation) + u64::from(guarded_update);
        self.publish_report(SolveOutcome::Converged);
        self.est.status.data = data_check(verdict);
        Ok(&self.est)
    }
}

forward_estimator!(impl<> for UnscentedKalmanFilter, DiscreteModel, GaussianEstimate, partial);

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn angle_rows_take_the_circular_mean_and_wrapped_deviations() {
        // Row 0 an ordinary value, row 1 an angle whose points straddle ±π about the central one.
        let pts = DMatrix::from_column_slice(2, 5, &[1.0, 3.1, 2.0, -3.1, 0.0, 3.05, 1.5, PI, 0.5, -3.05]);
        let (w0, wi) = (0.2, 0.2);
        let mut mean = DVector::zeros(2);
        weighted_mean(&pts, (w0, wi), &mut mean, &[]);
        assert!((mean[1] - (3.1 - 3.1 + 3.05 + PI - 3.05) / 5.0).abs() < 1e-15, "linear mean {}", mean[1]);
        weighted_mean(&pts, (w0, wi), &mut mean, &[1]);
        // The deviations from 3.1 are 0, 2π − 6.2, −0.05, π − 3.1, 2π − 6.15: the mean on the
        // circle, on the central point's branch (not wrapped to −π).
        let expected = 3.1 + 0.2 * ((2.0 * PI - 6.2) - 0.05 + (PI - 3.1) + (2.0 * PI - 6.15));
        assert!((mean[1] - expected).abs() < 1e-14, "{} vs {expected}", mean[1]);
        assert!((mean[0] - 1.0).abs() < 1e-15);
        let (mut dev, mut dev_w) = (DMatrix::zeros(2, 5), DMatrix::zeros(2, 5));
        deviations(&pts, Some(&mean), (w0, wi), &mut dev, &mut dev_w, &[1]);
        assert!(dev.row(1).iter().all(|d| d.abs() < 0.1), "{dev}");
        assert!((dev[(1, 1)] - wrap_angle(-3.1 - expected)).abs() < 1e-15);
        assert!((dev_w[(1, 3)] - 0.2 * dev[(1, 3)]).abs() < 1e-17);
        // Points that do not straddle are averaged exactly as an ordinary row.
        let calm = DMatrix::from_column_slice(1, 3, &[0.3, 0.31, 0.29]);
        let (mut a, mut b) = (DVector::zeros(1), DVector::zeros(1));
        weighted_mean(&calm, (0.5, 0.25), &mut a, &[]);
        weighted_mean(&calm, (0.5, 0.25), &mut b, &[0]);
        assert_eq!(a[0].to_bits(), b[0].to_bits());
    }

    #[test]
    fn paper_weights() {
        let (c, wm0, wc0, wi) = UkfParams::paper().weights(6).unwrap();
        assert_eq!((c, wm0, wc0, wi), (1.0, -5.0, -2.25, 0.5));
        // The weights of the mean sum to one; Wc₀ − Wm₀ = 1 − α² + β.
        assert!((wm0 + 12.0 * wi - 1.0).abs() < 1e-15);
        assert!(UkfParams::paper().weights(2).is_err());
        assert!(UkfParams { alpha: 0.0, ..UkfParams::paper() }.weights(6).is_err());
        assert!(UkfParams { beta: f64::NAN, ..UkfParams::paper() }.weights(6).is_err());
        let (c, wm0, wc0, _) = UkfParams::default().weights(3).unwrap();
        assert_eq!((c, wm0, wc0), (3.0, 0.0, 2.0));
    }
}
