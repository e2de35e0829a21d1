//! Nonlinear moving-horizon estimation (the supply-vessel paper's (21)–(23), docs/dp-vessel.md
//! §3.1–3.2) for any [`DifferentiableModel`]:
//!
//! ```text
//! min over x_s..x_T   ‖x_s − x̄_s‖²_{P_s⁻¹} + Σ_{j=s}^{T−1} ‖x_{j+1} − f(x_j, u_j)‖²_{Q⁻¹} + Σ_{j=s}^{T} ‖y_j − h(x_j)‖²_{R⁻¹}
//! ```
//!
//! (the disturbances `ω_j = x_{j+1} − f(x_j, u_j)` eliminated), full information while `T ≤ N`.
//! Solved by Gauss–Newton with Levenberg–Marquardt damping on the states of the window: the
//! Gauss–Newton matrix is **block tridiagonal** (`n × n` blocks), factorised by a block Cholesky
//! recursion in `O(N n³)`, warm-started from the previous window's trajectory shifted by one
//! sample (the new state predicted through `f`).
//!
//! The arrival cost (§3.2): `x̄_{s+1} = x̂_{s+1|T}` (the previous window's estimate of the new
//! start state) and `P_{s+1}` from one unscented-Kalman step about `(x̂_{s|T}, P_s)`: the
//! measurement update with `y_s`, then the time update with `u_s` ([`NonlinearArrival::Ukf`], the
//! paper's), or the same with an extended-Kalman linearisation ([`NonlinearArrival::Ekf`]), or
//! `P_0` kept ([`NonlinearArrival::Fixed`]). While the window grows, `(x̄_0, P_0)` are kept.
//!
//! All buffers are allocated at construction; an update allocates nothing when the model's
//! evaluations do not (tested). On error the estimator is unchanged.
//!
//! * `settings`: [`NonlinearMheSettings`] and their validation;
//! * `arrival`: the arrival-cost update;
//! * `window`: the samples, cost, linearisation and the block-tridiagonal factor and solve;
//! * `qp`: the Gauss–Newton step with boxes on the residuals (Clarabel);
//! * here: the estimator, its Gauss–Newton / Levenberg–Marquardt iteration and its estimate.

mod arrival;
mod qp;
mod settings;
mod window;

use std::time::{Duration, Instant};

use nalgebra::{DMatrix, DVector};

use dense_kernels as dense;
use models::{DifferentiableModel, Dims};

use self::arrival::{Arrival, Prior, StartSample};
use self::qp::{ConstrainedStep, constrained_step};
use self::window::{Rings, Span, Weights, Window};
use crate::error::EstimatorError;
use crate::kalman::GaussianEstimate;
use crate::mhe::estimator::window_outcome;
use crate::mhe::solve::WindowStatus;
use crate::partial::{Measured, Subsets, classify};
use crate::traits::{DetailField, Estimate, EstimateKind, Estimator, Setup, SolveOutcome, StepDetails, StepStatus};
use crate::validate::{InitialData, check_initial, check_vec};

pub use settings::{NonlinearArrival, NonlinearMheSettings, NonlinearPrior};

/// The number a nonlinear moving-horizon update reports beyond its status (`port-est`'s column,
/// Python's `details`; none before the first update).
pub const DETAILS: &[DetailField] =
    &[DetailField { name: "iterations", meaning: "Gauss-Newton iterations of the window's solve" }];

/// What one update did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NonlinearMheReport {
    /// Converged, or stopped at the iteration limit (the last iterate is published).
    pub status: WindowStatus,
    /// Gauss–Newton iterations (accepted or not).
    pub iterations: usize,
    /// Samples in the window.
    pub window: usize,
    /// Scalar unknowns (`n` per state of the window).
    pub unknowns: usize,
    /// The window's cost at the solution.
    pub cost: f64,
    /// Whether the newest sample had a measurement (`false` after a prediction).
    pub measured: bool,
    /// Wall time of the update (arrival update, build and solve).
    pub elapsed: Duration,
}

/// The estimate: `x̂_{T|T}` and, as its shape, the Gauss–Newton matrix's inverse block of the
/// last state (the Laplace approximation of its covariance; a point estimate: no per-state bounds
/// are published from it).
#[derive(Debug, Clone, PartialEq)]
pub struct NonlinearMheEstimate {
    /// `x̂_{T|T}`.
    pub center: DVector<f64>,
    /// Approximate covariance of `x̂_{T|T}`.
    pub covariance: DMatrix<f64>,
    /// The last update's report (`None` before the first).
    pub report: Option<NonlinearMheReport>,
}

impl Estimate for NonlinearMheEstimate {
    fn kind(&self) -> EstimateKind {
        EstimateKind::Point
    }
    fn center(&self) -> &DVector<f64> {
        &self.center
    }
    fn shape(&self) -> &DMatrix<f64> {
        &self.covariance
    }
    fn status(&self) -> StepStatus {
        StepStatus::unchecked(match &self.report {
            None => SolveOutcome::Initial,
            Some(r) => window_outcome(r.status, r.measured),
        })
    }
    fn details(&self) -> StepDetails {
        StepDetails::new(DETAILS, &[self.report.map(|r| r.iterations as f64)])
    }
}

/// Moving-horizon estimator for differentiable nonlinear models (Gauss–Newton / Levenberg–
/// Marquardt on the block-tridiagonal window problem, UKF or EKF arrival cost).
#[derive(Debug, Clone)]
pub struct NonlinearMhe {
    settings: NonlinearMheSettings,
    n: usize,
    p: usize,
    m: usize,
    t: usize,
    q_inv: DMatrix<f64>,
    r_inv: DMatrix<f64>,
    rings: Rings,
    /// `R`, and the weight and mask of the partial step being taken.
    r: DMatrix<f64>,
    partial: PartialWeight,
    // The committed window solution (states j = 0..len of the window starting at `start`).
    traj: Vec<DVector<f64>>,
    start: usize,
    len: usize,
    // The arrival prior of the committed window, and that of the window being solved.
    prior: Prior,
    next: Prior,
    window: Window,
    arrival: Arrival,
    est: NonlinearMheEstimate,
    /// The setup's prior mean.
    x0: DVector<f64>,
}

impl NonlinearMhe {
    /// An estimator from its [`Setup`] (weights) and settings.
    ///
    /// # Errors
    /// Invalid settings ([`EstimatorError::InvalidConfiguration`] and the validation errors of
    /// `x0`, `P0`, `Q`, `R`); UKF parameters that give no weights.
    pub fn new(setup: Setup, settings: NonlinearMheSettings) -> Result<Self, EstimatorError> {
        let InitialData { n, m, x0, p0, q, r, inputs } = check_initial(setup)?;
        settings.validate(n, m)?;
        let len_max = settings.horizon + 1;
        let mut q_inv = DMatrix::zeros(n, n);
        let mut r_inv = DMatrix::zeros(m, m);
        let mut work = DMatrix::zeros(n, n);
        let mut work_m = DMatrix::zeros(m, m);
        if dense::spd_inverse(&q, &mut work, &mut q_inv).is_err() {
            return Err(EstimatorError::NotPositiveDefinite { what: "Q" });
        }
        if dense::spd_inverse(&r, &mut work_m, &mut r_inv).is_err() {
            return Err(EstimatorError::NotPositiveDefinite { what: "R" });
        }
        let mut prior_inv = DMatrix::zeros(n, n);
        if dense::spd_inverse(&p0, &mut work, &mut prior_inv).is_err() {
            return Err(EstimatorError::NotPositiveDefinite { what: "P0" });
        }
        let setup_r = r.clone();
        let setup = Setup { x0: x0.clone(), p0: p0.clone(), process_noise: q, measurement_noise: r, inputs };
        let arrival = Arrival::new(settings.arrival, settings.prior, &setup, &r_inv)?;
        let mut traj = vec![DVector::zeros(n); len_max];
        traj[0].copy_from(&x0);
        let est = NonlinearMheEstimate { center: x0.clone(), covariance: p0.clone(), report: None };
        Ok(Self {
            n,
            p: inputs,
            m,
            t: 0,
            q_inv,
            r_inv,
            rings: Rings::new(settings.horizon + 2, inputs, m),
            r: setup_r,
            partial: PartialWeight::new(m),
            traj,
            start: 0,
            len: 1,
            prior: Prior { mean: x0.clone(), cov: p0, inv: prior_inv },
            next: Prior::zeros(n),
            window: Window::new(n, m, len_max),
            arrival,
            est,
            settings,
            x0,
        })
    }

    /// The settings.
    #[must_use]
    pub fn settings(&self) -> &NonlinearMheSettings {
        &self.settings
    }

    /// The current estimate.
    #[must_use]
    pub fn estimate(&self) -> &NonlinearMheEstimate {
        &self.est
    }

    /// Current time `T`.
    #[must_use]
    pub fn time(&self) -> usize {
        self.t
    }

    /// The window's optimal trajectory `x̂_{s|T} … x̂_{T|T}` of the last update.
    #[must_use]
    pub fn trajectory(&self) -> &[DVector<f64>] {
        &self.traj[..self.len]
    }

    /// Adds a measurement of `x_0` (with input `u` for `h`, usually zeros) before the first step.
    ///
    /// # Errors
    /// As a step; after the first step or twice ([`EstimatorError::InvalidConfiguration`]).
    pub fn measure_initial<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y0: &DVector<f64>,
    ) -> Result<&NonlinearMheEstimate, EstimatorError> {
        if self.t != 0 || self.rings.has_y[0] {
            return Err(EstimatorError::InvalidConfiguration {
                estimator: "nonlinear-mhe",
                message: "the initial measurement can be given once, before the first step".into(),
            });
        }
        crate::validate::check_discrete(model, self.n, self.p, self.m)?;
        check_vec("u", u, self.p)?;
        check_vec("y", y0, self.m)?;
        let start = Instant::now();
        self.rings.y[0].copy_from(y0);
        self.rings.uh[0].copy_from(u);
        self.rings.has_y[0] = true;
        self.window.x[0].copy_from(&self.x0);
        // The first window's prior is the setup's (x̄₀, P₀).
        self.next.copy_from(&self.prior);
        match self.solve(model, 0, 1, start) {
            Ok(()) => Ok(&self.est),
            Err(e) => {
                self.rings.has_y[0] = false;
                Err(e)
            }
        }
    }

    fn advance<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: Option<&DVector<f64>>,
    ) -> Result<&NonlinearMheEstimate, EstimatorError> {
        crate::validate::check_discrete(model, self.n, self.p, self.m)?;
        check_vec("u", u, self.p)?;
        if let Some(y) = y {
            check_vec("y", y, self.m)?;
        }
        self.advance_checked(model, u, y, false)
    }

    /// [`Self::advance`] after the data were checked; `partial`: `y` is a partial measurement
    /// whose mask and weight are in `self.partial` (module `partial`).
    fn advance_checked<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: Option<&DVector<f64>>,
        partial: bool,
    ) -> Result<&NonlinearMheEstimate, EstimatorError> {
        let started = Instant::now();
        let t = self.t;
        let new_t = t + 1;
        let new_start = new_t.saturating_sub(self.settings.horizon);
        // Slot t gets the transition input; slot t+1 (outside the window) the new measurement.
        let (st, sn) = (self.rings.slot(t), self.rings.slot(new_t));
        self.rings.u[st].copy_from(u);
        let (old_has, old_partial) = (self.rings.has_y[sn], self.rings.partial[sn]);
        match y {
            Some(y) => {
                self.rings.y[sn].copy_from(y);
                self.rings.uh[sn].copy_from(u);
                self.rings.has_y[sn] = true;
            }
            None => self.rings.has_y[sn] = false,
        }
        self.rings.partial[sn] = partial;
        if partial {
            let m = self.m;
            self.rings.mask[sn * m..(sn + 1) * m].copy_from_slice(&self.partial.mask);
            self.rings.w[sn].copy_from(&self.partial.weight);
            for i in 0..m {
                if !self.partial.mask[i] {
                    self.rings.y[sn][i] = 0.0;
                }
            }
        }
        let result = self.prepare_and_solve(model, new_t, new_start, started);
        if result.is_err() {
            self.rings.has_y[sn] = old_has;
            self.rings.partial[sn] = old_partial;
        }
        result.map(|()| &self.est)
    }

    /// One step with the outputs where `measured` is true (the others' entries of `y` are not
    /// read and may be NaN): that sample's term of the window cost is `ν_Sᵀ (R_SS)⁻¹ ν_S`, with
    /// the measured rows only (and its box, if any, on them), and the arrival cost's update with
    /// it when the window leaves it behind is the EKF's or the UKF's partial update. Every
    /// output measured: a step; none: a prediction. On error the estimator is unchanged.
    /// Allocation-free after the first step with that many outputs measured.
    ///
    /// # Errors
    /// As a step; a mask or `y` of another length than `m`.
    pub fn step_partial<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        measured: &[bool],
    ) -> Result<&NonlinearMheEstimate, EstimatorError> {
        crate::validate::check_discrete(model, self.n, self.p, self.m)?;
        let k = match classify(measured, u, y, (self.m, self.p), &mut self.partial.subsets.rows)? {
            Measured::All => return self.advance(model, u, Some(y)),
            Measured::Nothing => return self.advance(model, u, None),
            Measured::Some(k) => k,
        };
        self.partial.weigh(&self.r, k, measured)?;
        self.advance_checked(model, u, Some(y), true)
    }

    fn prepare_and_solve<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        new_t: usize,
        new_start: usize,
        started: Instant,
    ) -> Result<(), EstimatorError> {
        let len = new_t - new_start + 1;
        // Arrival prior of the new window (into `next`).
        let slid = new_start > self.start;
        if slid {
            debug_assert_eq!(new_start, self.start + 1);
            let slot = self.rings.slot(self.start);
            let r = &self.rings;
            let sample = StartSample {
                u: &r.u[slot],
                measured: r.has_y[slot].then_some((&r.uh[slot], &r.y[slot])),
                partial: r.measured(slot).map(|mask| (mask, &r.w[slot])),
            };
            self.arrival.advance(model, &self.prior, &self.traj[0], &self.traj[1], sample, &mut self.next)?;
        }
        // Warm start: the previous trajectory shifted, the new state predicted through f.
        let shift = new_start - self.start;
        let x = &mut self.window.x;
        for j in 0..len {
            let src = j + shift;
            if src < self.len {
                x[j].copy_from(&self.traj[src]);
            } else {
                let u = &self.rings.u[self.rings.slot(new_start + j - 1)];
                let (done, rest) = x.split_at_mut(j);
                model.f(&done[j - 1], u, &mut rest[0])?;
            }
        }
        if !self.window.is_finite(len) {
            return Err(EstimatorError::NumericalFailure("the predicted state is not finite"));
        }
        if !slid {
            self.next.copy_from(&self.prior);
        }
        self.solve(model, new_start, len, started)?;
        self.t = new_t;
        Ok(())
    }

    /// Gauss–Newton / Levenberg–Marquardt on the window `start..start+len` from the window's
    /// iterate (warm start), with the prior `next`; commits on success.
    fn solve<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        start: usize,
        len: usize,
        started: Instant,
    ) -> Result<(), EstimatorError> {
        let (rings, win) = (&self.rings, &mut self.window);
        let wts =
            Weights { q_inv: &self.q_inv, r_inv: &self.r_inv, prior_mean: &self.next.mean, prior_inv: &self.next.inv };
        let span = Span { rings, wts, start, len };
        let tolerance = self.settings.tolerance;
        let (w_box, v_box) = (self.settings.w_box.as_ref(), self.settings.v_box.as_ref());
        let mut cost = win.cost(model, &span, false)?;
        let mut mu = 0.0_f64;
        let mut status = WindowStatus::NotConverged;
        let mut iterations = 0;
        // Whether `d` holds the undamped factor at the current iterate (then the covariance below
        // needs no new factorisation).
        let mut factor_current = false;
        let mut constrained = w_box.is_some() || v_box.is_some();
        let mut infeasible = false;
        // The relative size of the last accepted step (the contraction estimate).
        let mut last_ratio: Option<f64> = None;
        // Real-time iterations: the budget, and whether `d` holds the undamped factor at the
        // last linearisation point (then the covariance below takes it).
        let budget = self.settings.real_time_iterations.unwrap_or(self.settings.max_iterations);
        let mut factor_at_last_point = false;
        while iterations < budget {
            iterations += 1;
            win.linearise(model, &span)?;
            if constrained {
                // Sequential QP: the Gauss–Newton step with the linearised boxes (full steps).
                match constrained_step(win, &span, w_box, v_box) {
                    ConstrainedStep::Solved => {
                        let negligible = win.step_is_negligible(len, tolerance);
                        win.apply_step(len);
                        cost = win.cost(model, &span, false)?;
                        if negligible {
                            status = WindowStatus::Converged;
                            break;
                        }
                    }
                    ConstrainedStep::Infeasible => {
                        // The boxes cannot all hold: publish the unconstrained estimate, say so.
                        infeasible = true;
                        constrained = false;
                    }
                    ConstrainedStep::Failed => {
                        status = WindowStatus::InnerFailure;
                        break;
                    }
                }
                continue;
            }
            // Damped solve; raise μ until the cost does not increase (beyond rounding).
            let mut accepted = false;
            for _ in 0..30 {
                if !win.factor_and_solve(&span, mu) {
                    mu = if mu == 0.0 { 1e-8 * win.max_diag(len) } else { mu * 10.0 };
                    continue;
                }
                if win.step_is_negligible(len, tolerance) {
                    // The Gauss–Newton step vanishes: a stationary point to the tolerance.
                    status = WindowStatus::Converged;
                    factor_current = mu == 0.0;
                    break;
                }
                let ratio = win.step_ratio(len);
                win.set_trial(len);
                let trial = win.cost(model, &span, true)?;
                if trial.is_finite() && trial <= cost + 1e-13 * cost.abs() {
                    win.accept_trial(len);
                    cost = trial;
                    factor_at_last_point = mu == 0.0;
                    // Linear convergence at the observed rate c: the iterate is within
                    // ‖Δ‖ c/(1 − c) of the limit.
                    if let (Some(limit), Some(last)) = (self.settings.estimate_tolerance, last_ratio) {
                        let c = ratio / last;
                        if c < 0.5 && ratio * c / (1.0 - c) <= limit {
                            status = WindowStatus::Converged;
                        }
                    }
                    last_ratio = Some(ratio);
                    mu *= 0.1;
                    if mu < 1e-300 {
                        mu = 0.0;
                    }
                    accepted = true;
                    break;
                }
                mu = if mu == 0.0 { 1e-8 * win.max_diag(len) } else { mu * 10.0 };
            }
            if status == WindowStatus::Converged {
                break;
            }
            if !accepted {
                // No decrease along any damped step: a minimum to working precision.
                status = WindowStatus::Converged;
                break;
            }
        }
        let real_time = self.settings.real_time_iterations.is_some();
        if real_time && status == WindowStatus::NotConverged {
            status = WindowStatus::RealTimeIteration;
        }
        if infeasible {
            status = WindowStatus::Infeasible;
        }
        if !win.is_finite(len) || !cost.is_finite() {
            return Err(EstimatorError::NumericalFailure("the window's solution is not finite"));
        }
        // Covariance of the last state: the last diagonal block of the inverse Gauss–Newton
        // matrix = (L_last L_lastᵀ)⁻¹ of the (undamped) block Cholesky.
        let have_cov =
            factor_current || (real_time && status == WindowStatus::RealTimeIteration && factor_at_last_point) || {
                win.linearise(model, &span)?;
                win.factor_and_solve(&span, 0.0)
            };
        // Commit.
        for j in 0..len {
            self.traj[j].copy_from(&win.x[j]);
        }
        if start != self.start {
            self.prior.copy_from(&self.next);
        }
        self.start = start;
        self.len = len;
        self.est.center.copy_from(&win.x[len - 1]);
        if have_cov {
            win.last_covariance(len, &mut self.est.covariance);
        }
        self.est.report = Some(NonlinearMheReport {
            status,
            iterations,
            window: len,
            unknowns: self.n * len,
            cost,
            elapsed: started.elapsed(),
            measured: rings.has_y[rings.slot(start + len - 1)],
        });
        Ok(())
    }
}

/// The weight `(R_SS)⁻¹` of a partial measurement, embedded in `m × m`, and its mask; the `k × k`
/// buffers of its inverse by measured count (made on first use).
#[derive(Debug, Clone)]
struct PartialWeight {
    mask: Vec<bool>,
    weight: DMatrix<f64>,
    subsets: Subsets<(DMatrix<f64>, DMatrix<f64>, DMatrix<f64>)>,
}

impl PartialWeight {
    fn new(m: usize) -> Self {
        Self { mask: vec![true; m], weight: DMatrix::zeros(m, m), subsets: Subsets::new(m) }
    }

    /// `weight` and `mask` for the `k` measured outputs `subsets.rows` of `measured`.
    fn weigh(&mut self, r: &DMatrix<f64>, k: usize, measured: &[bool]) -> Result<(), EstimatorError> {
        let ((r_ss, work, inv), rows) =
            self.subsets.get(k, || Ok((DMatrix::zeros(k, k), DMatrix::zeros(k, k), DMatrix::zeros(k, k))))?;
        crate::partial::gather_block(r, rows, r_ss);
        if dense::spd_inverse(r_ss, work, inv).is_err() {
            return Err(EstimatorError::NotPositiveDefinite { what: "R" });
        }
        self.weight.fill(0.0);
        for (b, &j) in rows.iter().enumerate() {
            for (a, &i) in rows.iter().enumerate() {
                self.weight[(i, j)] = inv[(a, b)];
            }
        }
        self.mask.copy_from_slice(measured);
        Ok(())
    }
}

impl<M: DifferentiableModel + ?Sized> Estimator<M> for NonlinearMhe {
    type Estimate = NonlinearMheEstimate;

    fn step(&mut self, model: &M, u: &DVector<f64>, y: &DVector<f64>) -> Result<&NonlinearMheEstimate, EstimatorError> {
        self.advance(model, u, Some(y))
    }

    fn predict(&mut self, model: &M, u: &DVector<f64>) -> Result<&NonlinearMheEstimate, EstimatorError> {
        self.advance(model, u, None)
    }

    fn step_partial(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        measured: &[bool],
    ) -> Result<&NonlinearMheEstimate, EstimatorError> {
        NonlinearMhe::step_partial(self, model, u, y, measured)
    }

    fn update(&mut self, _model: &M, _y: &DVector<f64>) -> Result<&NonlinearMheEstimate, EstimatorError> {
        Err(EstimatorError::Unsupported {
            estimator: "the nonlinear moving-horizon estimator",
            operation: "update",
            reason: "a window sample is an input and the measurement after it; use step (or predict when no \
                     measurement arrived)",
        })
    }

    fn estimate(&self) -> &NonlinearMheEstimate {
        &self.est
    }

    fn dims(&self) -> Dims {
        Dims::new(self.n, self.p, self.m)
    }

    fn set_data_checks(&mut self, checks: crate::checks::DataChecks) -> Result<(), EstimatorError> {
        if checks.policy == crate::checks::InconsistencyPolicy::Off {
            return Ok(());
        }
        Err(EstimatorError::Unsupported {
            estimator: "the nonlinear moving-horizon estimator",
            operation: "data checks",
            reason: "its windows are not yet checked against the noise boxes: its steps say `NotChecked`; only the \
                     policy `Off` is accepted",
        })
    }
}

/// The Gaussian view of the estimate (mean and approximate covariance).
impl From<&NonlinearMheEstimate> for GaussianEstimate {
    fn from(e: &NonlinearMheEstimate) -> Self {
        GaussianEstimate {
            center: e.center.clone(),
            covariance: e.covariance.clone(),
            std_dev: e.covariance.diagonal().map(|v| v.max(0.0).sqrt()),
            status: e.status(),
            details: StepDetails::NONE,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use models::ConstantModel;

    fn model() -> ConstantModel {
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 0.1, -0.1, 0.9]);
        ConstantModel::new(a, DMatrix::from_column_slice(2, 1, &[0.0, 0.1]), DMatrix::from_row_slice(1, 2, &[1.0, 0.0]))
            .unwrap()
    }

    fn estimator(horizon: usize) -> NonlinearMhe {
        let setup = Setup {
            x0: DVector::zeros(2),
            p0: DMatrix::identity(2, 2),
            process_noise: DMatrix::identity(2, 2) * 0.01,
            measurement_noise: DMatrix::from_element(1, 1, 0.1),
            inputs: 1,
        };
        NonlinearMhe::new(
            setup,
            NonlinearMheSettings { horizon, arrival: NonlinearArrival::Ekf, ..NonlinearMheSettings::paper() },
        )
        .unwrap()
    }

    #[test]
    fn the_window_grows_to_n_plus_one_states_then_slides() {
        let (model, mut mhe) = (model(), estimator(3));
        let u = DVector::from_element(1, 0.5);
        for k in 1..=6 {
            let y = DVector::from_element(1, 0.1 * k as f64);
            let e = if k == 5 { mhe.predict(&model, &u) } else { mhe.step(&model, &u, &y) }.unwrap().clone();
            assert_eq!(mhe.time(), k);
            let len = (k + 1).min(4);
            assert_eq!(mhe.trajectory().len(), len);
            assert_eq!(mhe.trajectory()[len - 1], e.center);
            let report = e.report.unwrap();
            assert_eq!((report.window, report.unknowns, report.measured), (len, 2 * len, k != 5));
            assert_eq!(report.status, WindowStatus::Converged);
            assert!(e.covariance.iter().all(|v| v.is_finite()) && e.covariance[(0, 0)] > 0.0);
        }
    }

    #[test]
    fn refused_operations_leave_the_estimator_unchanged() {
        let (model, mut mhe) = (model(), estimator(2));
        mhe.step(&model, &DVector::from_element(1, 0.5), &DVector::from_element(1, 0.2)).unwrap();
        let before = mhe.estimate().clone();
        assert!(matches!(
            Estimator::update(&mut mhe, &model, &DVector::from_element(1, 0.2)),
            Err(EstimatorError::Unsupported { operation: "update", .. })
        ));
        assert!(mhe.step(&model, &DVector::from_element(1, f64::NAN), &DVector::from_element(1, 0.2)).is_err());
        assert!(mhe.measure_initial(&model, &DVector::zeros(1), &DVector::zeros(1)).is_err());
        assert_eq!((mhe.estimate(), mhe.time()), (&before, 1));
    }
}
