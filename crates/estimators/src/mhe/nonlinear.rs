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

use std::time::{Duration, Instant};

use nalgebra::{DMatrix, DVector};

use dense_kernels as dense;
use models::{DifferentiableModel, Dims};

use crate::error::EstimatorError;
use crate::kalman::GaussianEstimate;
use crate::mhe::estimator::window_outcome;
use crate::mhe::solve::WindowStatus;
use crate::traits::{Estimate, EstimateKind, Estimator, Setup, SolveOutcome, StepDetails, StepStatus};
use crate::ukf::{UkfParams, UnscentedKalmanFilter};
use crate::validate::{InitialData, check_initial, check_vec};

/// How the arrival-cost weight `P_s` advances when the window slides.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum NonlinearArrival {
    /// One unscented-Kalman update with `y_s` and prediction with `u_s` about `(x̂_{s|T}, P_s)`
    /// (the paper's, with its `α, β, κ`).
    Ukf(UkfParams),
    /// The same with the model's Jacobians (extended Kalman).
    Ekf,
    /// `P_s = P_0` always.
    Fixed,
}

/// Settings of [`NonlinearMhe`] beyond its [`Setup`] (prior mean `x̄₀` and weight `P₀`, process
/// and measurement weights `Q`, `R`), as data.
#[derive(Debug, Clone, PartialEq)]
pub struct NonlinearMheSettings {
    /// Horizon `N` (the window holds `N + 1` states; the paper's 10).
    pub horizon: usize,
    /// Arrival-cost update.
    pub arrival: NonlinearArrival,
    /// At most this many Gauss–Newton iterations per update (default 20).
    pub max_iterations: usize,
    /// Stop when `‖Δx‖∞ ≤ tolerance · max(1, ‖x‖∞)` (default `1e−10`).
    pub tolerance: f64,
    /// The prior mean of a new window start (default: the paper's smoothed estimate).
    pub prior: NonlinearPrior,
    /// Optional box `[lo, hi]` on the disturbances `ω_j = x_{j+1} − f(x_j, u_j)` (length `n`;
    /// entries may be infinite). With a box (on `ω` or `ν`) each Gauss–Newton step is a QP with
    /// the linearised constraints, solved by Clarabel's pure-Rust QP path (allocates per update).
    pub w_box: Option<(DVector<f64>, DVector<f64>)>,
    /// Optional box on the measurement residuals `ν_j = y_j − h(x_j)` (length `m`).
    pub v_box: Option<(DVector<f64>, DVector<f64>)>,
}

/// Where the prior mean `x̄_{s+1}` of a new window start comes from, and about which point the
/// arrival update linearises or draws its sigma points (digest §6.8).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum NonlinearPrior {
    /// `x̄_{s+1} = x̂_{s+1|T}`, the update about `x̂_{s|T}` (the paper's, "the previous moment's
    /// estimate"). The window's measurements then enter twice (once through the smoothed prior),
    /// which makes the estimate follow the measurements more than the filters do.
    Smoothed,
    /// The arrival filter keeps its own mean: `x̄_{s+1}` is its prediction after the update with
    /// `y_s` (a UKF or EKF lagging `N` samples behind). No measurement enters twice; on a linear
    /// model with the EKF arrival the MHE is then the Kalman filter (tested).
    ArrivalFilter,
}

impl NonlinearMheSettings {
    /// The paper's shape: `N = 10`, UKF arrival cost with `α, β, κ = 0.5, 2, −2`, 20 iterations,
    /// tolerance `1e−10`.
    #[must_use]
    pub fn paper() -> Self {
        Self {
            horizon: 10,
            arrival: NonlinearArrival::Ukf(UkfParams::paper()),
            max_iterations: 20,
            tolerance: 1e-10,
            prior: NonlinearPrior::Smoothed,
            w_box: None,
            v_box: None,
        }
    }
}

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
        StepDetails::NonlinearMovingHorizon(self.report)
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
    cap: usize,
    t: usize,
    q_inv: DMatrix<f64>,
    r_inv: DMatrix<f64>,
    // Rings by absolute sample k at k mod cap: u_k (transition k → k+1), y_k, its flag, the input
    // passed with it (for h).
    u_ring: Vec<DVector<f64>>,
    y_ring: Vec<DVector<f64>>,
    uh_ring: Vec<DVector<f64>>,
    has_y: Vec<bool>,
    // The committed window solution (states j = 0..len of the window starting at `start`).
    traj: Vec<DVector<f64>>,
    start: usize,
    len: usize,
    // Current arrival prior (x̄_s, P_s⁻¹ and P_s) for window start `start`.
    prior_mean: DVector<f64>,
    prior_cov: DMatrix<f64>,
    prior_inv: DMatrix<f64>,
    // Work.
    x: Vec<DVector<f64>>,
    x_trial: Vec<DVector<f64>>,
    a: Vec<DMatrix<f64>>,
    c: Vec<DMatrix<f64>>,
    fx: Vec<DVector<f64>>,
    hx: Vec<DVector<f64>>,
    d: Vec<DMatrix<f64>>,
    w: Vec<DMatrix<f64>>,
    g: Vec<DVector<f64>>,
    step: Vec<DVector<f64>>,
    tmp_n: DVector<f64>,
    tmp_n2: DVector<f64>,
    centre: DVector<f64>,
    tmp_m: DVector<f64>,
    tmp_m2: DVector<f64>,
    tmp_nm: DMatrix<f64>,
    tmp_nn: DMatrix<f64>,
    new_mean: DVector<f64>,
    new_cov: DMatrix<f64>,
    new_inv: DMatrix<f64>,
    ukf: Option<UnscentedKalmanFilter>,
    ekf_p: DMatrix<f64>,
    est: NonlinearMheEstimate,
    /// The setup's prior mean and weight and process weight.
    x0: DVector<f64>,
    p0: DMatrix<f64>,
    q: DMatrix<f64>,
}

impl NonlinearMhe {
    /// An estimator from its [`Setup`] (weights) and settings.
    ///
    /// # Errors
    /// Invalid settings ([`EstimatorError::InvalidConfiguration`] and the validation errors of
    /// `x0`, `P0`, `Q`, `R`); UKF parameters that give no weights.
    pub fn new(setup: Setup, settings: NonlinearMheSettings) -> Result<Self, EstimatorError> {
        let bad = |message: String| EstimatorError::InvalidConfiguration { estimator: "nonlinear-mhe", message };
        let InitialData { n, m, x0, p0, q, r, inputs } = check_initial(setup)?;
        let p = inputs;
        if settings.horizon == 0 {
            return Err(bad("the horizon N must be at least 1".into()));
        }
        if settings.max_iterations == 0 || settings.tolerance.is_nan() || settings.tolerance <= 0.0 {
            return Err(bad(format!(
                "max_iterations must be ≥ 1 and tolerance > 0, got {} and {}",
                settings.max_iterations, settings.tolerance
            )));
        }
        for (what, b, len) in [("w_box", &settings.w_box, n), ("v_box", &settings.v_box, m)] {
            if let Some((lo, hi)) = b {
                if lo.len() != len || hi.len() != len {
                    return Err(bad(format!("{what} must have {len} components, got {} and {}", lo.len(), hi.len())));
                }
                if let Some(i) = (0..len).find(|&i| lo[i].is_nan() || hi[i].is_nan() || lo[i] >= hi[i]) {
                    return Err(bad(format!("{what} is empty or NaN at component {i}: [{}, {}]", lo[i], hi[i])));
                }
            }
        }
        let cap = settings.horizon + 2;
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
        let ukf = match settings.arrival {
            NonlinearArrival::Ukf(params) => Some(UnscentedKalmanFilter::new(
                Setup {
                    x0: x0.clone(),
                    p0: p0.clone(),
                    process_noise: q.clone(),
                    measurement_noise: r.clone(),
                    inputs,
                },
                params,
            )?),
            _ => None,
        };
        let vn = |k: usize| vec![DVector::zeros(k); len_max];
        let mut traj = vn(n);
        traj[0].copy_from(&x0);
        let est = NonlinearMheEstimate { center: x0.clone(), covariance: p0.clone(), report: None };
        Ok(Self {
            n,
            p,
            m,
            cap,
            t: 0,
            q_inv,
            r_inv,
            u_ring: vec![DVector::zeros(p); cap],
            y_ring: vec![DVector::zeros(m); cap],
            uh_ring: vec![DVector::zeros(p); cap],
            has_y: vec![false; cap],
            traj,
            start: 0,
            len: 1,
            prior_mean: x0.clone(),
            prior_cov: p0.clone(),
            prior_inv,
            x: vn(n),
            x_trial: vn(n),
            a: vec![DMatrix::zeros(n, n); len_max],
            c: vec![DMatrix::zeros(m, n); len_max],
            fx: vn(n),
            hx: vn(m),
            d: vec![DMatrix::zeros(n, n); len_max],
            w: vec![DMatrix::zeros(n, n); len_max],
            g: vn(n),
            step: vn(n),
            tmp_n: DVector::zeros(n),
            tmp_n2: DVector::zeros(n),
            centre: DVector::zeros(n),
            tmp_m: DVector::zeros(m),
            tmp_m2: DVector::zeros(m),
            tmp_nm: DMatrix::zeros(n, m),
            tmp_nn: DMatrix::zeros(n, n),
            new_mean: DVector::zeros(n),
            new_cov: DMatrix::zeros(n, n),
            new_inv: DMatrix::zeros(n, n),
            ukf,
            ekf_p: DMatrix::zeros(n, n),
            est,
            settings,
            x0,
            p0,
            q,
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

    fn check_dims(&self, d: Dims) -> Result<(), EstimatorError> {
        crate::validate::check_dims(d, self.n, self.p, self.m)
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
        if self.t != 0 || self.has_y[0] {
            return Err(EstimatorError::InvalidConfiguration {
                estimator: "nonlinear-mhe",
                message: "the initial measurement can be given once, before the first step".into(),
            });
        }
        self.check_dims(model.dims())?;
        check_vec("u", u, self.p)?;
        check_vec("y", y0, self.m)?;
        let start = Instant::now();
        self.y_ring[0].copy_from(y0);
        self.uh_ring[0].copy_from(u);
        self.has_y[0] = true;
        self.x[0].copy_from(&self.x0);
        match self.solve(model, 0, 1, start) {
            Ok(()) => Ok(&self.est),
            Err(e) => {
                self.has_y[0] = false;
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
        self.check_dims(model.dims())?;
        check_vec("u", u, self.p)?;
        if let Some(y) = y {
            check_vec("y", y, self.m)?;
        }
        let started = Instant::now();
        let (t, cap) = (self.t, self.cap);
        let new_t = t + 1;
        let new_start = new_t.saturating_sub(self.settings.horizon);
        // Slot t gets the transition input; slot t+1 (outside the window) the new measurement.
        let (st, sn) = (t % cap, new_t % cap);
        self.u_ring[st].copy_from(u);
        let old_has = self.has_y[sn];
        match y {
            Some(y) => {
                self.y_ring[sn].copy_from(y);
                self.uh_ring[sn].copy_from(u);
                self.has_y[sn] = true;
            }
            None => self.has_y[sn] = false,
        }
        let result = self.prepare_and_solve(model, new_t, new_start, started);
        if result.is_err() {
            self.has_y[sn] = old_has;
        }
        result.map(|()| &self.est)
    }

    fn prepare_and_solve<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        new_t: usize,
        new_start: usize,
        started: Instant,
    ) -> Result<(), EstimatorError> {
        let len = new_t - new_start + 1;
        // Arrival prior of the new window (into new_mean, new_cov, new_inv).
        let slid = new_start > self.start;
        if slid {
            debug_assert_eq!(new_start, self.start + 1);
            self.advance_arrival(model)?;
        }
        // Warm start: the previous trajectory shifted, the new state predicted through f.
        let shift = new_start - self.start;
        for j in 0..len {
            let src = j + shift;
            if src < self.len {
                self.x[j].copy_from(&self.traj[src]);
            } else {
                let k = new_start + j - 1;
                let u = &self.u_ring[k % self.cap];
                model.f(&self.x[j - 1], u, &mut self.tmp_n)?;
                self.x[j].copy_from(&self.tmp_n);
            }
        }
        if self.x[..len].iter().any(|x| x.iter().any(|v| !v.is_finite())) {
            return Err(EstimatorError::NumericalFailure("the predicted state is not finite"));
        }
        if !slid {
            self.new_mean.copy_from(&self.prior_mean);
            self.new_cov.copy_from(&self.prior_cov);
            self.new_inv.copy_from(&self.prior_inv);
        }
        self.solve(model, new_start, len, started)?;
        self.t = new_t;
        Ok(())
    }

    /// `P_{s+1}`, `x̄_{s+1}` from the committed window (start `s`), into `new_*`.
    fn advance_arrival<M: DifferentiableModel + ?Sized>(&mut self, model: &M) -> Result<(), EstimatorError> {
        let s = self.start;
        let slot = s % self.cap;
        // The centre of the arrival update: x̂_{s|T} (the paper's) or the arrival filter's own mean.
        let own = self.settings.prior == NonlinearPrior::ArrivalFilter;
        if own {
            self.centre.copy_from(&self.prior_mean);
        } else {
            self.centre.copy_from(&self.traj[0]);
        }
        // x̄_{s+1} = x̂_{s+1|T} (the second state of the committed window), unless the arrival
        // filter's prediction replaces it below.
        self.new_mean.copy_from(&self.traj[1]);
        let (u, y, uh, has) = (&self.u_ring[slot], &self.y_ring[slot], &self.uh_ring[slot], self.has_y[slot]);
        match self.settings.arrival {
            NonlinearArrival::Fixed => self.new_cov.copy_from(&self.p0),
            NonlinearArrival::Ukf(_) => {
                // tidy: invariant — the UKF exists whenever the arrival is `Ukf` (built in `new`).
                let ukf = self.ukf.as_mut().expect("built with the settings");
                ukf.reset(&self.centre, &self.prior_cov)?;
                if has {
                    ukf.correct(model, uh, y)?;
                }
                let e = ukf.predict(model, u)?;
                self.new_cov.copy_from(&e.covariance);
                if own {
                    self.new_mean.copy_from(&e.center);
                }
            }
            NonlinearArrival::Ekf => {
                self.ekf_p.copy_from(&self.prior_cov);
                if has {
                    // P⁺ = (P⁻¹ + Hᵀ R⁻¹ H)⁻¹ at the centre; m⁺ = m + P⁺ Hᵀ R⁻¹ (y − h(m)).
                    model.h_with_jacobian(&self.centre, uh, &mut self.tmp_m, &mut self.c[0])?;
                    self.tmp_nn.copy_from(&self.prior_inv);
                    self.tmp_nm.gemm_tr(1.0, &self.c[0], &self.r_inv, 0.0);
                    dense::mul_nn(1.0, &self.tmp_nm, &self.c[0], 1.0, &mut self.tmp_nn);
                    let (work, out) = (&mut self.d[0], &mut self.ekf_p);
                    if dense::spd_inverse(&self.tmp_nn, work, out).is_err() {
                        return Err(EstimatorError::NumericalFailure(
                            "the arrival-cost update is not positive definite",
                        ));
                    }
                    if own {
                        self.tmp_m.neg_mut();
                        self.tmp_m += y;
                        self.tmp_n.gemv(1.0, &self.tmp_nm, &self.tmp_m, 0.0);
                        self.centre.gemv(1.0, &self.ekf_p, &self.tmp_n, 1.0);
                    }
                }
                model.f_with_jacobian(&self.centre, u, &mut self.tmp_n2, &mut self.a[0])?;
                if own {
                    self.new_mean.copy_from(&self.tmp_n2);
                }
                dense::mul_nn(1.0, &self.a[0], &self.ekf_p, 0.0, &mut self.tmp_nn);
                self.new_cov.copy_from(&self.q);
                dense::mul_nt(1.0, &self.tmp_nn, &self.a[0], 1.0, &mut self.new_cov);
                dense::symmetrize(&mut self.new_cov);
            }
        }
        let (work, out) = (&mut self.d[0], &mut self.new_inv);
        if dense::spd_inverse(&self.new_cov, work, out).is_err() {
            return Err(EstimatorError::NumericalFailure("the arrival-cost weight is not positive definite"));
        }
        Ok(())
    }

    /// The window cost at `xs` (states `0..len`), evaluating `f`, `h` into `fx`, `hx`.
    fn cost<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        start: usize,
        len: usize,
        trial: bool,
    ) -> Result<f64, EstimatorError> {
        let xs = if trial { &self.x_trial } else { &self.x };
        let mut total = 0.0;
        self.tmp_n.copy_from(&xs[0]);
        self.tmp_n -= &self.new_mean;
        total += quad(&self.new_inv, &self.tmp_n);
        for j in 0..len {
            let k = start + j;
            let sl = k % self.cap;
            if j + 1 < len {
                model.f(&xs[j], &self.u_ring[sl], &mut self.fx[j])?;
                self.tmp_n.copy_from(&xs[j + 1]);
                self.tmp_n -= &self.fx[j];
                total += quad(&self.q_inv, &self.tmp_n);
            }
            if self.has_y[sl] {
                model.h(&xs[j], &self.uh_ring[sl], &mut self.hx[j])?;
                self.tmp_m.copy_from(&self.y_ring[sl]);
                self.tmp_m -= &self.hx[j];
                total += quad(&self.r_inv, &self.tmp_m);
            }
        }
        Ok(total)
    }

    /// Gauss–Newton / Levenberg–Marquardt on the window `start..start+len` from `x` (warm start),
    /// with prior `new_*`; commits on success.
    fn solve<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        start: usize,
        len: usize,
        started: Instant,
    ) -> Result<(), EstimatorError> {
        let mut cost = self.cost(model, start, len, false)?;
        let mut mu = 0.0_f64;
        let mut status = WindowStatus::NotConverged;
        let mut iterations = 0;
        // Whether `d` holds the undamped factor at the current `x` (then the covariance below
        // needs no new factorisation).
        let mut factor_current = false;
        let mut constrained = self.settings.w_box.is_some() || self.settings.v_box.is_some();
        let mut infeasible = false;
        while iterations < self.settings.max_iterations {
            iterations += 1;
            self.linearise(model, start, len)?;
            if constrained {
                // Sequential QP: the Gauss–Newton step with the linearised boxes (full steps).
                match self.constrained_step(start, len) {
                    ConstrainedStep::Solved => {
                        let step = self.step[..len].iter().fold(0.0_f64, |a, s| a.max(s.amax()));
                        let scale = self.x[..len].iter().fold(1.0_f64, |a, x| a.max(x.amax()));
                        for j in 0..len {
                            self.x[j] += &self.step[j];
                        }
                        cost = self.cost(model, start, len, false)?;
                        if step <= self.settings.tolerance * scale {
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
                if !self.factor_and_solve(start, len, mu) {
                    mu = if mu == 0.0 { 1e-8 * self.max_diag(len) } else { mu * 10.0 };
                    continue;
                }
                let step = self.step[..len].iter().fold(0.0_f64, |a, s| a.max(s.amax()));
                let scale = self.x[..len].iter().fold(1.0_f64, |a, x| a.max(x.amax()));
                if step <= self.settings.tolerance * scale {
                    // The Gauss–Newton step vanishes: a stationary point to the tolerance.
                    status = WindowStatus::Converged;
                    factor_current = mu == 0.0;
                    break;
                }
                for j in 0..len {
                    self.x_trial[j].copy_from(&self.x[j]);
                    self.x_trial[j] += &self.step[j];
                }
                let trial = self.cost(model, start, len, true)?;
                if trial.is_finite() && trial <= cost + 1e-13 * cost.abs() {
                    for j in 0..len {
                        std::mem::swap(&mut self.x[j], &mut self.x_trial[j]);
                    }
                    cost = trial;
                    mu *= 0.1;
                    if mu < 1e-300 {
                        mu = 0.0;
                    }
                    accepted = true;
                    break;
                }
                mu = if mu == 0.0 { 1e-8 * self.max_diag(len) } else { mu * 10.0 };
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
        if infeasible {
            status = WindowStatus::Infeasible;
        }
        if self.x[..len].iter().any(|x| x.iter().any(|v| !v.is_finite())) || !cost.is_finite() {
            return Err(EstimatorError::NumericalFailure("the window's solution is not finite"));
        }
        // Covariance of the last state: the last diagonal block of the inverse Gauss–Newton
        // matrix = (L_last L_lastᵀ)⁻¹ of the (undamped) block Cholesky.
        let have_cov = factor_current || {
            self.linearise(model, start, len)?;
            self.factor_and_solve(start, len, 0.0)
        };
        // Commit.
        for j in 0..len {
            self.traj[j].copy_from(&self.x[j]);
        }
        if start != self.start {
            self.prior_mean.copy_from(&self.new_mean);
            self.prior_cov.copy_from(&self.new_cov);
            self.prior_inv.copy_from(&self.new_inv);
        }
        self.start = start;
        self.len = len;
        self.est.center.copy_from(&self.x[len - 1]);
        if have_cov {
            dense::cholesky_inverse(self.d[len - 1].as_slice(), self.n, self.est.covariance.as_mut_slice());
        }
        self.est.report = Some(NonlinearMheReport {
            status,
            iterations,
            window: len,
            unknowns: self.n * len,
            cost,
            elapsed: started.elapsed(),
            measured: self.has_y[(start + len - 1) % self.cap],
        });
        Ok(())
    }

    fn max_diag(&self, len: usize) -> f64 {
        self.d[..len].iter().fold(1e-12_f64, |a, d| (0..self.n).fold(a, |a, i| a.max(d[(i, i)].abs())))
    }

    /// Jacobians `A_j = ∂f/∂x`, `C_j = ∂h/∂x` at `x`, residuals, the gradient `g` and the
    /// diagonal blocks `D_j` (undamped) of the Gauss–Newton matrix (kept in `a`, `c`, `g` and
    /// recomputed into `d` by `factor_and_solve`).
    fn linearise<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        start: usize,
        len: usize,
    ) -> Result<(), EstimatorError> {
        for j in 0..len {
            let sl = (start + j) % self.cap;
            if j + 1 < len {
                model.f_with_jacobian(&self.x[j], &self.u_ring[sl], &mut self.fx[j], &mut self.a[j])?;
            }
            if self.has_y[sl] {
                model.h_with_jacobian(&self.x[j], &self.uh_ring[sl], &mut self.hx[j], &mut self.c[j])?;
            }
        }
        // g_j = ∂Φ/∂x_j / 2.
        for j in 0..len {
            self.g[j].fill(0.0);
        }
        self.tmp_n.copy_from(&self.x[0]);
        self.tmp_n -= &self.new_mean;
        dense::gemv(1.0, &self.new_inv, &self.tmp_n, 1.0, &mut self.g[0]);
        for j in 0..len {
            let sl = (start + j) % self.cap;
            if j + 1 < len {
                // d_j = x_{j+1} − f_j; g_{j+1} += Q⁻¹ d_j; g_j −= A_jᵀ Q⁻¹ d_j.
                self.tmp_n.copy_from(&self.x[j + 1]);
                self.tmp_n -= &self.fx[j];
                self.tmp_n2.gemv(1.0, &self.q_inv, &self.tmp_n, 0.0);
                self.g[j + 1] += &self.tmp_n2;
                self.g[j].gemv_tr(-1.0, &self.a[j], &self.tmp_n2, 1.0);
            }
            if self.has_y[sl] {
                self.tmp_m.copy_from(&self.y_ring[sl]);
                self.tmp_m -= &self.hx[j];
                self.tmp_m2.gemv(1.0, &self.r_inv, &self.tmp_m, 0.0);
                self.g[j].gemv_tr(-1.0, &self.c[j], &self.tmp_m2, 1.0);
            }
        }
        Ok(())
    }

    /// Builds `D_j + μ I`, the off-diagonal blocks `−Q⁻¹ A_j`, factorises by block Cholesky
    /// (`d` receives the factors `L_j`, `w` the blocks `W_j = O_{j−1} L_{j−1}⁻ᵀ`) and solves
    /// `H Δ = −g` into `step`. False if a pivot block is not positive definite.
    fn factor_and_solve(&mut self, start: usize, len: usize, mu: f64) -> bool {
        self.build_blocks(start, len, mu);
        self.factor_and_back_substitute(len)
    }

    /// The Gauss–Newton step as a QP with the boxes on `ω_j ≈ d_j + Δ_{j+1} − A_j Δ_j` and
    /// `ν_j ≈ e_j − C_j Δ_j` (linearised at the current `x`), solved by Clarabel; into `step`.
    fn constrained_step(&mut self, start: usize, len: usize) -> ConstrainedStep {
        use clarabel_qp::algebra::CscMatrix;
        use clarabel_qp::solver::{DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus};
        let (n, m) = (self.n, self.m);
        let nv = n * len;
        self.build_blocks(start, len, 0.0);
        // Upper triangle of H by columns: diagonal blocks D_j, and above them Oᵀ = −A_{j−1}ᵀ Q⁻¹
        // (block (j−1, j)).
        let mut cols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); nv];
        for j in 0..len {
            for c in 0..n {
                let col = &mut cols[j * n + c];
                if j > 0 {
                    // (row block j−1, col block j) = (−Q⁻¹ A_{j−1})ᵀ = −A_{j−1}ᵀ Q⁻¹.
                    for r in 0..n {
                        let mut v = 0.0;
                        for k in 0..n {
                            v -= self.a[j - 1][(k, r)] * self.q_inv[(k, c)];
                        }
                        if v != 0.0 {
                            col.push(((j - 1) * n + r, v));
                        }
                    }
                }
                for r in 0..=c {
                    let v = self.d[j][(r, c)];
                    if v != 0.0 {
                        col.push((j * n + r, v));
                    }
                }
            }
        }
        let q: Vec<f64> = self.g[..len].iter().flat_map(|g| g.iter().copied()).collect();
        // Constraint rows a·Δ ≤ b.
        let mut rows: Vec<(Vec<(usize, f64)>, f64)> = Vec::new();
        if let Some((lo, hi)) = &self.settings.w_box {
            for j in 0..len.saturating_sub(1) {
                for i in 0..n {
                    let dj = self.x[j + 1][i] - self.fx[j][i];
                    let mut row: Vec<(usize, f64)> = vec![((j + 1) * n + i, 1.0)];
                    for k in 0..n {
                        let a = self.a[j][(i, k)];
                        if a != 0.0 {
                            row.push((j * n + k, -a));
                        }
                    }
                    if hi[i].is_finite() {
                        rows.push((row.clone(), hi[i] - dj));
                    }
                    if lo[i].is_finite() {
                        rows.push((row.iter().map(|&(c, v)| (c, -v)).collect(), dj - lo[i]));
                    }
                }
            }
        }
        if let Some((lo, hi)) = &self.settings.v_box {
            for j in 0..len {
                if !self.has_y[(start + j) % self.cap] {
                    continue;
                }
                for i in 0..m {
                    let e = self.y_ring[(start + j) % self.cap][i] - self.hx[j][i];
                    // ν = e − C Δ ≤ hi  ⇔  −C Δ ≤ hi − e;   ν ≥ lo  ⇔  C Δ ≤ e − lo.
                    let row: Vec<(usize, f64)> =
                        (0..n).filter(|&k| self.c[j][(i, k)] != 0.0).map(|k| (j * n + k, self.c[j][(i, k)])).collect();
                    if hi[i].is_finite() {
                        rows.push((row.iter().map(|&(c, v)| (c, -v)).collect(), hi[i] - e));
                    }
                    if lo[i].is_finite() {
                        rows.push((row, e - lo[i]));
                    }
                }
            }
        }
        let to_csc = |nrows: usize, cols: &[Vec<(usize, f64)>]| {
            let mut colptr = vec![0];
            let mut rowval = Vec::new();
            let mut nzval = Vec::new();
            for col in cols {
                let mut sorted = col.clone();
                sorted.sort_by_key(|&(r, _)| r);
                for (r, v) in sorted {
                    rowval.push(r);
                    nzval.push(v);
                }
                colptr.push(rowval.len());
            }
            CscMatrix::new(nrows, cols.len(), colptr, rowval, nzval)
        };
        let mut a_cols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); nv];
        for (r, (row, _)) in rows.iter().enumerate() {
            for &(c, v) in row {
                a_cols[c].push((r, v));
            }
        }
        let b: Vec<f64> = rows.iter().map(|r| r.1).collect();
        let p = to_csc(nv, &cols);
        let a = to_csc(rows.len(), &a_cols);
        let cones = if rows.is_empty() { Vec::new() } else { vec![NonnegativeConeT(rows.len())] };
        let Ok(settings) = DefaultSettingsBuilder::default()
            .verbose(false)
            .tol_gap_abs(1e-12)
            .tol_gap_rel(1e-12)
            .tol_feas(1e-10)
            .build()
        else {
            return ConstrainedStep::Failed;
        };
        let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings).ok()?;
            solver.solve();
            Some((solver.solution.status, solver.solution.x.clone()))
        }));
        match outcome {
            Ok(Some((SolverStatus::Solved | SolverStatus::AlmostSolved, x))) if x.iter().all(|v| v.is_finite()) => {
                for j in 0..len {
                    for i in 0..n {
                        self.step[j][i] = x[j * n + i];
                    }
                }
                ConstrainedStep::Solved
            }
            Ok(Some((SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible, _))) => {
                ConstrainedStep::Infeasible
            }
            _ => ConstrainedStep::Failed,
        }
    }

    /// The diagonal blocks `D_j + μ I` of the Gauss–Newton matrix into `d` (the off-diagonal
    /// blocks are `O_j = −Q⁻¹ A_j`, below the diagonal).
    fn build_blocks(&mut self, start: usize, len: usize, mu: f64) {
        let n = self.n;
        for j in 0..len {
            let sl = (start + j) % self.cap;
            let dj = &mut self.d[j];
            dj.fill(0.0);
            if j == 0 {
                *dj += &self.new_inv;
            }
            if j > 0 {
                *dj += &self.q_inv;
            }
            if j + 1 < len {
                dense::mul_nn(1.0, &self.q_inv, &self.a[j], 0.0, &mut self.tmp_nn);
                dj.gemm_tr(1.0, &self.a[j], &self.tmp_nn, 1.0);
            }
            if self.has_y[sl] {
                self.tmp_nm.gemm_tr(1.0, &self.c[j], &self.r_inv, 0.0);
                dense::mul_nn(1.0, &self.tmp_nm, &self.c[j], 1.0, dj);
            }
            for i in 0..n {
                dj[(i, i)] += mu;
            }
        }
    }

    /// Block Cholesky of the matrix whose diagonal blocks `build_blocks` left in `d`, and the
    /// solve of `H Δ = −g` into `step`.
    fn factor_and_back_substitute(&mut self, len: usize) -> bool {
        // Block Cholesky: S_0 = D_0; S_j = D_j − W_j W_jᵀ, W_j = O_{j−1} L_{j−1}⁻ᵀ, O_{j−1} = −Q⁻¹ A_{j−1}.
        for j in 0..len {
            if j > 0 {
                dense::mul_nn(-1.0, &self.q_inv, &self.a[j - 1], 0.0, &mut self.w[j]);
                dense::solve_right_lower_t(&mut self.w[j], &self.d[j - 1]);
                let (wj, dj) = (&self.w[j], &mut self.d[j]);
                dense::mul_nt(-1.0, wj, wj, 1.0, dj);
            }
            dense::symmetrize(&mut self.d[j]);
            if dense::cholesky_in_place(&mut self.d[j]).is_err() {
                return false;
            }
        }
        // Forward: y_j = L_j⁻¹ (−g_j − W_j y_{j−1}); backward: Δ_j = L_j⁻ᵀ (y_j − W_{j+1}ᵀ Δ_{j+1}).
        for j in 0..len {
            self.step[j].copy_from(&self.g[j]);
            self.step[j].neg_mut();
            if j > 0 {
                let (prev, cur) = self.step.split_at_mut(j);
                cur[0].gemv(-1.0, &self.w[j], &prev[j - 1], 1.0);
            }
            dense::solve_lower(self.d[j].as_slice(), self.n, self.step[j].as_mut_slice());
        }
        for j in (0..len).rev() {
            if j + 1 < len {
                let (cur, next) = self.step.split_at_mut(j + 1);
                cur[j].gemv_tr(-1.0, &self.w[j + 1], &next[0], 1.0);
            }
            dense::solve_lower_t(self.d[j].as_slice(), self.n, self.step[j].as_mut_slice());
        }
        self.step[..len].iter().all(|s| s.iter().all(|v| v.is_finite()))
    }
}

/// Outcome of a constrained Gauss–Newton step.
enum ConstrainedStep {
    Solved,
    Infeasible,
    Failed,
}

fn quad(a: &DMatrix<f64>, x: &DVector<f64>) -> f64 {
    let n = x.len();
    let mut s = 0.0;
    for c in 0..n {
        for r in 0..n {
            s += x[r] * a[(r, c)] * x[c];
        }
    }
    s
}

impl<M: DifferentiableModel + ?Sized> Estimator<M> for NonlinearMhe {
    type Estimate = NonlinearMheEstimate;

    fn step(&mut self, model: &M, u: &DVector<f64>, y: &DVector<f64>) -> Result<&NonlinearMheEstimate, EstimatorError> {
        self.advance(model, u, Some(y))
    }

    fn predict(&mut self, model: &M, u: &DVector<f64>) -> Result<&NonlinearMheEstimate, EstimatorError> {
        self.advance(model, u, None)
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
}

/// The Gaussian view of the estimate (mean and approximate covariance).
impl From<&NonlinearMheEstimate> for GaussianEstimate {
    fn from(e: &NonlinearMheEstimate) -> Self {
        GaussianEstimate {
            center: e.center.clone(),
            covariance: e.covariance.clone(),
            std_dev: e.covariance.diagonal().map(|v| v.max(0.0).sqrt()),
            status: e.status(),
            details: StepDetails::None,
        }
    }
}
