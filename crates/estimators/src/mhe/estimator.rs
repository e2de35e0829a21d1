//! [`MovingHorizonEstimator`]: windowing (§2.2), the arrival cost (§2.3), blocking (§2.4) and the
//! window solvers (§2.6–2.7) of docs/robust-mhe.md behind the [`Estimator`] trait.

use std::time::{Duration, Instant};

use nalgebra::{DMatrix, DVector};

use models::{Dims, LinearModel};

use crate::checks::{DataChecks, InconsistencyPolicy};
use crate::error::EstimatorError;
use crate::mhe::consistency::{Sample, WindowCheck, WindowData, check_window, witnesses};
use crate::mhe::settings::{ArrivalRecursion, BlockWeighting, MheSettings, PriorMean, WindowSolver};
use crate::mhe::solve::{
    NoiseData, SolveCounters, SolverScratch, WindowStatus, coordinate_rotation, exact_saddle, saddle_value,
};
use crate::mhe::window::WindowProblem;
use crate::status::{DataCheck, Guarantee};
use crate::traits::{DetailField, Estimate, EstimateKind, Estimator, Setup, SolveOutcome, StepDetails, StepStatus};
use crate::validate::{check_model, check_vec};

/// Which form of the arrival-cost recursion (20) advanced the weight in this step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ArrivalStatus {
    /// The Kalman form with `R_eff`.
    Kalman,
    /// The H∞ form; its existence condition held.
    HInfinity,
    /// The H∞ form's existence condition `P⁻¹ − θ I + Cᵀ R⁻¹ C ≻ 0` failed: this step used the
    /// Kalman form instead.
    HInfinityConditionFailed,
}

/// The number a moving-horizon update reports beyond its status (`port-est`'s column, Python's
/// `details`; none before the first update).
pub const DETAILS: &[DetailField] = &[DetailField {
    name: "iterations",
    meaning: "min/max sweeps of the window's solve (the coordinate rotation), or Newton iterations of the \
              exact saddle",
}];

/// What one update did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MheReport {
    /// Window solver status and counters.
    pub solve: SolveCounters,
    /// Samples in the window (`T − s + 1`).
    pub window: usize,
    /// Vector unknowns `1 + S` (`x_s` and one per block).
    pub vector_unknowns: usize,
    /// Scalar unknowns `n (1 + S)`.
    pub unknowns: usize,
    /// The arrival-cost recursion of this step.
    pub arrival: ArrivalStatus,
    /// The window's saddle value `Φ(z*, v*)` (least squares: the MHE cost).
    pub objective: f64,
    /// Wall time of the update (recursion, window build and solve).
    pub elapsed: Duration,
    /// Whether the newest sample had a measurement (`false` after a prediction, or when the
    /// policy [`InconsistencyPolicy::Restart`] dropped it).
    pub measured: bool,
    /// What the window's data check found (docs/robust-mhe.md §2.8).
    pub data: DataCheck,
}

/// The estimate of a moving-horizon estimator: the last state of the window's optimal trajectory
/// and, as its shape, the arrival-cost recursion's matrix updated with the last measurement
/// (`(P_T⁻¹ + Cᵀ R_eff⁻¹ C)⁻¹`): a covariance of the equivalent Kalman filter, not a calibrated
/// covariance of the estimate nor a guaranteed set ([`EstimateKind::Point`]: no per-state bounds).
#[derive(Debug, Clone, PartialEq)]
pub struct MheEstimate {
    /// `x̂_{T|T}`.
    pub center: DVector<f64>,
    /// The weight matrix (see above).
    pub weight: DMatrix<f64>,
    /// What the last update did (`None` before the first).
    pub report: Option<MheReport>,
}

/// The shared status of a window solve: converged (a prediction when the newest sample had no
/// measurement), not converged (the sweep limit, or an inner QP failure: the last finite iterate
/// is published), relaxed (constraints that cannot all hold were dropped).
pub(crate) fn window_outcome(status: WindowStatus, measured: bool) -> SolveOutcome {
    match status {
        WindowStatus::Converged if measured => SolveOutcome::Converged,
        WindowStatus::Converged => SolveOutcome::Predicted,
        WindowStatus::NotConverged | WindowStatus::InnerFailure => SolveOutcome::NotConverged,
        WindowStatus::Infeasible => SolveOutcome::Relaxed,
        WindowStatus::RealTimeIteration => SolveOutcome::RealTimeIteration,
    }
}

impl Estimate for MheEstimate {
    fn kind(&self) -> EstimateKind {
        EstimateKind::Point
    }
    fn center(&self) -> &DVector<f64> {
        &self.center
    }
    fn shape(&self) -> &DMatrix<f64> {
        &self.weight
    }
    fn status(&self) -> StepStatus {
        match &self.report {
            None => StepStatus::unchecked(SolveOutcome::Initial),
            Some(r) => StepStatus {
                outcome: window_outcome(r.solve.status, r.measured),
                data: r.data,
                guarantee: Guarantee::NotApplicable,
            },
        }
    }
    fn details(&self) -> StepDetails {
        StepDetails::new(DETAILS, &[self.report.map(|r| r.solve.sweeps as f64)])
    }
}

/// A moving-horizon estimator for linear models with box-bounded noise: the robust min–max MHE
/// with disturbance blocking of the car paper (any blocks, either `λv`), or plain MHE
/// ([`MheCost::LeastSquares`](super::MheCost::LeastSquares)); configured entirely by [`MheSettings`].
///
/// A step consumes `u_k` and `y_{k+1}` (the workspace's convention) and returns `x̂_{k+1|k+1}`;
/// [`MovingHorizonEstimator::measure_initial`] adds a measurement of `x_0` before the first
/// step. After construction no update allocates with the active-set inner solver (tested).
#[derive(Debug, Clone)]
pub struct MovingHorizonEstimator {
    settings: MheSettings,
    n: usize,
    p: usize,
    m: usize,
    cap: usize,
    /// Current time `T` (steps done).
    t: usize,
    initial_measured: bool,
    // Rings indexed by absolute sample k at (k mod cap).
    a_ring: Vec<f64>,
    bu_ring: Vec<f64>,
    u_ring: Vec<f64>,
    c_ring: Vec<f64>,
    y_ring: Vec<f64>,
    has_y: Vec<bool>,
    /// Which outputs each sample measured (all but for a partial step's).
    outputs_ring: Vec<bool>,
    /// A partial step's measured outputs.
    partial_rows: Vec<usize>,
    p_ring: Vec<f64>,
    traj_ring: Vec<f64>,
    filt_ring: Vec<f64>,
    v_ring: Vec<f64>,
    // Constant data.
    q: Vec<f64>,
    q_inv: Vec<f64>,
    x0: Vec<f64>,
    p0: Vec<f64>,
    r_inv: Vec<f64>,
    v_lo: Vec<f64>,
    v_hi: Vec<f64>,
    w_lo: Vec<f64>,
    w_hi: Vec<f64>,
    // Work.
    window: WindowProblem,
    scratch: SolverScratch,
    z: Vec<f64>,
    v: Vec<f64>,
    z_start: Vec<f64>,
    v_start: Vec<f64>,
    traj_work: Vec<f64>,
    p_next: Vec<f64>,
    prior_mean: Vec<f64>,
    prior_inv: Vec<f64>,
    mat_a: Vec<f64>,
    mat_b: Vec<f64>,
    mat_c: Vec<f64>,
    mat_d: Vec<f64>,
    vec_a: Vec<f64>,
    buf_c: Vec<f64>,
    buf_y: Vec<f64>,
    checks: DataChecks,
    est: MheEstimate,
}

impl MovingHorizonEstimator {
    /// An estimator from its [`Setup`] (prior mean and weight, process weight `Q`, diagonal
    /// measurement weight `R`, number of inputs) and its `settings`, both validated.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidConfiguration`] naming the first invalid setting.
    pub fn new(setup: Setup, settings: MheSettings) -> Result<Self, EstimatorError> {
        settings.validate(&setup)?;
        let Setup { x0, p0, process_noise: q, measurement_noise: r, inputs } = setup;
        let (n, m, p) = (x0.len(), r.nrows(), inputs);
        let horizon = settings.horizon;
        let cap = horizon + 2;
        let max_len = horizon + 1;
        let max_blocks = horizon.max(settings.blocks.len());
        let nz_cap = n * (1 + max_blocks);
        let to_vec = |a: &DMatrix<f64>| a.as_slice().to_vec();
        let mut q_inv = vec![0.0; n * n];
        let mut work = to_vec(&q);
        if dense_kernels::cholesky_slice(&mut work, n).is_err() {
            return Err(EstimatorError::InvalidConfiguration {
                estimator: "mhe",
                message: "Q is not positive definite".into(),
            });
        }
        dense_kernels::cholesky_inverse(&work, n, &mut q_inv);
        let r_inv: Vec<f64> = (0..m).map(|i| 1.0 / r[(i, i)]).collect();
        let mut p_ring = vec![0.0; cap * n * n];
        p_ring[..n * n].copy_from_slice(p0.as_slice());
        let mut traj_ring = vec![0.0; cap * n];
        traj_ring[..n].copy_from_slice(x0.as_slice());
        let mut filt_ring = vec![0.0; cap * n];
        filt_ring[..n].copy_from_slice(x0.as_slice());
        let est = MheEstimate { center: x0.clone(), weight: p0.clone(), report: None };
        Ok(Self {
            n,
            p,
            m,
            cap,
            t: 0,
            initial_measured: false,
            a_ring: vec![0.0; cap * n * n],
            bu_ring: vec![0.0; cap * n],
            u_ring: vec![0.0; cap * p],
            c_ring: vec![0.0; cap * m * n],
            y_ring: vec![0.0; cap * m],
            has_y: vec![false; cap],
            outputs_ring: vec![true; cap * m],
            partial_rows: Vec::with_capacity(m),
            p_ring,
            traj_ring,
            filt_ring,
            v_ring: vec![0.0; cap * m],
            q: to_vec(&q),
            q_inv,
            x0: x0.as_slice().to_vec(),
            p0: to_vec(&p0),
            r_inv,
            v_lo: settings.v_box.0.as_slice().to_vec(),
            v_hi: settings.v_box.1.as_slice().to_vec(),
            w_lo: settings.w_box.0.as_slice().to_vec(),
            w_hi: settings.w_box.1.as_slice().to_vec(),
            window: WindowProblem::new(n, m, max_len, max_blocks),
            scratch: SolverScratch::new(nz_cap, max_len * m),
            z: vec![0.0; nz_cap],
            v: vec![0.0; max_len * m],
            z_start: vec![0.0; nz_cap],
            v_start: vec![0.0; max_len * m],
            traj_work: vec![0.0; max_len * n],
            p_next: vec![0.0; n * n],
            prior_mean: vec![0.0; n],
            prior_inv: vec![0.0; n * n],
            mat_a: vec![0.0; n * n],
            mat_b: vec![0.0; n * n],
            mat_c: vec![0.0; n * n],
            mat_d: vec![0.0; n * n],
            vec_a: vec![0.0; n],
            buf_c: vec![0.0; m * n],
            buf_y: vec![0.0; m],
            checks: DataChecks::default(),
            est,
            settings,
        })
    }

    /// The settings.
    #[must_use]
    pub fn settings(&self) -> &MheSettings {
        &self.settings
    }

    /// Current time `T` (steps done).
    #[must_use]
    pub fn time(&self) -> usize {
        self.t
    }

    /// The current estimate (as [`Estimator::estimate`], without naming the model type).
    #[must_use]
    pub fn estimate(&self) -> &MheEstimate {
        &self.est
    }

    /// The window check of docs/robust-mhe.md §2.8 with `checks.policy` (the gate probability is
    /// not used: the check is a proof, not a statistical test). As
    /// [`Estimator::set_data_checks`], without naming the model type.
    ///
    /// # Errors
    /// None: every policy is supported.
    pub fn set_data_checks(&mut self, checks: DataChecks) -> Result<(), EstimatorError> {
        self.checks = checks;
        Ok(())
    }

    /// The report of the last update.
    #[must_use]
    pub fn report(&self) -> Option<&MheReport> {
        self.est.report.as_ref()
    }

    /// Adds the measurement `y_0 = C x_0 + v_0` before the first step and publishes `x̂_{0|0}`.
    ///
    /// # Errors
    /// Wrong sizes or non-finite data, or a call after the first step or a second call
    /// ([`EstimatorError::InvalidConfiguration`]); the estimator is unchanged.
    pub fn measure_initial<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        y0: &DVector<f64>,
    ) -> Result<&MheEstimate, EstimatorError> {
        if self.t != 0 || self.initial_measured {
            return Err(EstimatorError::InvalidConfiguration {
                estimator: "mhe",
                message: "the initial measurement can be given once, before the first step".into(),
            });
        }
        self.check(model, None, Some(y0))?;
        let start = Instant::now();
        let (n, m) = (self.n, self.m);
        self.c_ring[..m * n].copy_from_slice(model.c().as_slice());
        self.y_ring[..m].copy_from_slice(y0.as_slice());
        self.has_y[0] = true;
        let solved = self.solve_window(0).and_then(|r| Ok((r, self.check_data(0, 0)?)));
        let ((counters, objective), data) = match solved {
            Ok(r) => r,
            Err(e) => {
                self.has_y[0] = false;
                return Err(e);
            }
        };
        self.initial_measured = true;
        self.commit(0, 0, (counters, objective, data), ArrivalStatus::Kalman, start);
        Ok(&self.est)
    }

    fn check<M: LinearModel + ?Sized>(
        &self,
        model: &M,
        u: Option<&DVector<f64>>,
        y: Option<&DVector<f64>>,
    ) -> Result<(), EstimatorError> {
        check_model(model, self.n, self.p, self.m)?;
        if let Some(u) = u {
            check_vec("u", u, self.p)?;
        }
        if let Some(y) = y {
            check_vec("y", y, self.m)?;
        }
        Ok(())
    }

    /// One update to time `t + 1` with input `u_t` and, if given, `y_{t+1}` (with `measured`,
    /// its measured outputs only; the data then checked by the caller).
    fn advance<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: Option<&DVector<f64>>,
        measured: Option<&[bool]>,
    ) -> Result<&MheEstimate, EstimatorError> {
        if measured.is_none() {
            self.check(model, Some(u), y)?;
        }
        let start = Instant::now();
        let (n, m, p, cap) = (self.n, self.m, self.p, self.cap);
        let t = self.t;
        let (st, sn) = (t % cap, (t + 1) % cap);
        // Transition t → t+1 (slot t) and measurement t+1 (slot t+1, outside the current window).
        self.a_ring[st * n * n..(st + 1) * n * n].copy_from_slice(model.a().as_slice());
        self.u_ring[st * p..(st + 1) * p].copy_from_slice(u.as_slice());
        let b = model.b();
        for r in 0..n {
            let mut s = 0.0;
            for k in 0..p {
                s += b[(r, k)] * u[k];
            }
            self.bu_ring[st * n + r] = s;
        }
        self.c_ring[sn * m * n..(sn + 1) * m * n].copy_from_slice(model.c().as_slice());
        let old_has = self.has_y[sn];
        match y {
            Some(y) => {
                self.y_ring[sn * m..(sn + 1) * m].copy_from_slice(y.as_slice());
                self.unwrap_angles(model, st, sn);
                self.has_y[sn] = true;
            }
            None => self.has_y[sn] = false,
        }
        // A partial measurement: its unmeasured outputs' rows of C and entries of y are zero, so
        // they weigh nothing in the window, the arrival recursion or the Riccati step (R is
        // diagonal: dropping a row is the update with the others), and the data check skips them.
        let outputs = &mut self.outputs_ring[sn * m..(sn + 1) * m];
        match measured {
            Some(mask) if y.is_some() => {
                outputs.copy_from_slice(mask);
                for (i, _) in mask.iter().enumerate().filter(|(_, m)| !**m) {
                    self.y_ring[sn * m + i] = 0.0;
                    for col in 0..n {
                        self.c_ring[sn * m * n + col * m + i] = 0.0;
                    }
                }
            }
            _ => outputs.fill(true),
        }
        // (20): P_{t+1} from P_t, the measurement at t and A_t.
        let arrival = self.riccati(st);
        let result = self.solve_checked(t + 1);
        match result {
            Ok(solved) => {
                self.p_ring[sn * n * n..(sn + 1) * n * n].copy_from_slice(&self.p_next);
                self.t = t + 1;
                self.commit(t + 1, self.window_start(t + 1), solved, arrival, start);
                Ok(&self.est)
            }
            Err(e) => {
                self.has_y[sn] = old_has;
                Err(e)
            }
        }
    }

    /// Angle outputs of the measurement in slot `sn` moved to the branch of their prediction
    /// `C (A x̂ + B u)` from the published estimate (slot `st` holds `A`, `B u`): the window's
    /// residuals `y − C x` of an angle are then those wrapped to `(−π, π]` near the prediction,
    /// and the quadratic programme stays convex. Allocation-free.
    fn unwrap_angles<M: LinearModel + ?Sized>(&mut self, model: &M, st: usize, sn: usize) {
        let (n, m) = (self.n, self.m);
        let a = &self.a_ring[st * n * n..(st + 1) * n * n];
        let c = model.c();
        for &k in LinearModel::angles(model).outputs {
            let mut reference = 0.0;
            for i in 0..n {
                let mut pred = self.bu_ring[st * n + i];
                for j in 0..n {
                    pred += a[j * n + i] * self.est.center[j];
                }
                reference += c[(k, i)] * pred;
            }
            let y = &mut self.y_ring[sn * m + k];
            let d = models::wrap_angle(*y - reference);
            if d != *y - reference {
                *y = reference + d;
            }
        }
    }

    /// Solves the window ending at `big_t` and checks its data with the policy: an inconsistent
    /// window is an error, flagged, or solved again without its newest measurement (`Restart`).
    fn solve_checked(&mut self, big_t: usize) -> Result<(SolveCounters, f64, DataCheck), EstimatorError> {
        let (counters, objective) = self.solve_window(big_t)?;
        let data = self.check_data(big_t, self.window_start(big_t))?;
        if data != DataCheck::Inconsistent || self.checks.policy != InconsistencyPolicy::Restart {
            return Ok((counters, objective, data));
        }
        let sn = big_t % self.cap;
        self.has_y[sn] = false;
        let (counters, objective) = self.solve_window(big_t)?;
        Ok((counters, objective, DataCheck::Inconsistent))
    }

    /// The data check of the window `s..=big_t` just solved (its trajectory in `traj_work`): the
    /// solution as a witness, then the linear programme (module `consistency`). `Err` with the
    /// policy `Error`; `Inconsistent` otherwise. A window whose newest sample has no measurement
    /// is not checked (a prediction).
    fn check_data(&self, big_t: usize, s: usize) -> Result<DataCheck, EstimatorError> {
        let (n, m, cap) = (self.n, self.m, self.cap);
        if self.checks.policy == InconsistencyPolicy::Off || !self.has_y[big_t % cap] {
            return Ok(DataCheck::NotChecked);
        }
        let len = big_t - s + 1;
        let sample = |j: usize| {
            let sl = (s + j) % cap;
            Sample {
                a: &self.a_ring[sl * n * n..(sl + 1) * n * n],
                bu: &self.bu_ring[sl * n..(sl + 1) * n],
                c: &self.c_ring[sl * m * n..(sl + 1) * m * n],
                y: &self.y_ring[sl * m..(sl + 1) * m],
                measured: self.has_y[sl],
                outputs: &self.outputs_ring[sl * m..(sl + 1) * m],
            }
        };
        let data = WindowData { n, m, len, sample, w: (&self.w_lo, &self.w_hi), v: (&self.v_lo, &self.v_hi) };
        if witnesses(&data, &self.traj_work[..len * n]) {
            return Ok(DataCheck::Consistent);
        }
        match check_window(&data) {
            WindowCheck::Consistent => Ok(DataCheck::Consistent),
            WindowCheck::Undecided => Ok(DataCheck::NotChecked),
            WindowCheck::Inconsistent { excess } if self.checks.policy == InconsistencyPolicy::Error => {
                let samples = (0..len).filter(|&j| self.has_y[(s + j) % cap]).count();
                Err(EstimatorError::InconsistentWindow { step: big_t as u64, samples, excess })
            }
            WindowCheck::Inconsistent { .. } => Ok(DataCheck::Inconsistent),
        }
    }

    fn window_start(&self, big_t: usize) -> usize {
        big_t.saturating_sub(self.settings.horizon)
    }

    /// Advances the arrival weight: `p_next = A (P⁻¹ + Cᵀ W C − θ I)⁻¹ Aᵀ + Q` with the slot's
    /// `P`, `C`, measurement flag and `A`.
    fn riccati(&mut self, slot: usize) -> ArrivalStatus {
        let n = self.n;
        let (r_eff, theta) = (self.settings.r_eff_factor(), self.settings.arrival);
        let status = match theta {
            ArrivalRecursion::HInfinity { theta } => {
                if self.information(slot, 1.0, theta) {
                    ArrivalStatus::HInfinity
                } else {
                    let ok = self.information(slot, r_eff, 0.0);
                    debug_assert!(ok);
                    ArrivalStatus::HInfinityConditionFailed
                }
            }
            ArrivalRecursion::Kalman => {
                self.information(slot, r_eff, 0.0);
                ArrivalStatus::Kalman
            }
        };
        // mat_b holds S⁻¹; p_next = A S⁻¹ Aᵀ + Q.
        let a = &self.a_ring[slot * n * n..(slot + 1) * n * n];
        dense_kernels::mul_slices(n, n, n, a, &self.mat_b, &mut self.mat_c);
        for c in 0..n {
            for r in 0..n {
                let mut s = self.q[c * n + r];
                for k in 0..n {
                    s += self.mat_c[k * n + r] * a[k * n + c];
                }
                self.p_next[c * n + r] = s;
            }
        }
        sym(&mut self.p_next, n);
        status
    }

    /// `mat_b ← (P⁻¹ + Cᵀ diag(1/(f R)) C − θ I)⁻¹` for the P, C and measurement flag of `slot`;
    /// false (and `mat_b` unspecified) if the bracket is not positive definite.
    fn information(&mut self, slot: usize, r_factor: f64, theta: f64) -> bool {
        let (n, m) = (self.n, self.m);
        self.mat_a.copy_from_slice(&self.p_ring[slot * n * n..(slot + 1) * n * n]);
        if dense_kernels::cholesky_slice(&mut self.mat_a, n).is_err() {
            return false;
        }
        dense_kernels::cholesky_inverse(&self.mat_a, n, &mut self.mat_d);
        if self.has_y[slot] {
            let c = &self.c_ring[slot * m * n..(slot + 1) * m * n];
            for i in 0..m {
                let w = self.r_inv[i] / r_factor;
                for col in 0..n {
                    for r in 0..n {
                        self.mat_d[col * n + r] += w * c[r * m + i] * c[col * m + i];
                    }
                }
            }
        }
        for i in 0..n {
            self.mat_d[i * n + i] -= theta;
        }
        if dense_kernels::cholesky_slice(&mut self.mat_d, n).is_err() {
            return false;
        }
        dense_kernels::cholesky_inverse(&self.mat_d, n, &mut self.mat_b);
        true
    }

    /// Builds and solves the window ending at `big_t` into `z`, `v`, `traj_work`.
    fn solve_window(&mut self, big_t: usize) -> Result<(SolveCounters, f64), EstimatorError> {
        let (n, m, cap) = (self.n, self.m, self.cap);
        let horizon = self.settings.horizon;
        let s = self.window_start(big_t);
        let len = big_t - s + 1;
        let blocked = big_t > horizon;
        let nblocks = if blocked { self.settings.blocks.len() } else { len - 1 };
        // Prior of x_s: (x̄_s, P_s).
        if s == 0 {
            self.prior_mean.copy_from_slice(&self.x0);
            self.mat_a.copy_from_slice(&self.p0);
        } else {
            match self.settings.prior_mean {
                PriorMean::Smoothed => {
                    let o = (s % cap) * n;
                    self.prior_mean.copy_from_slice(&self.traj_ring[o..o + n]);
                }
                PriorMean::Filtered => {
                    let sl = (s - 1) % cap;
                    let a = &self.a_ring[sl * n * n..(sl + 1) * n * n];
                    let x = &self.filt_ring[sl * n..(sl + 1) * n];
                    for r in 0..n {
                        let mut acc = self.bu_ring[sl * n + r];
                        for k in 0..n {
                            acc += a[k * n + r] * x[k];
                        }
                        self.prior_mean[r] = acc;
                    }
                }
            }
            // s = T − N ≤ T − 1 (N ≥ 1): P_s was committed to the ring at time s.
            let sl = s % cap;
            self.mat_a.copy_from_slice(&self.p_ring[sl * n * n..(sl + 1) * n * n]);
        }
        if dense_kernels::cholesky_slice(&mut self.mat_a, n).is_err() {
            return Err(EstimatorError::NumericalFailure("the arrival-cost weight lost positive definiteness"));
        }
        dense_kernels::cholesky_inverse(&self.mat_a, n, &mut self.prior_inv);
        // Blocks: lengths and weights.
        let blocks = &self.settings.blocks;
        let weighting = self.settings.block_weighting;
        let block_of = |j: usize| -> usize {
            if !blocked {
                return j;
            }
            let mut acc = 0;
            for (b, d) in blocks.iter().enumerate() {
                acc += d;
                if j < acc {
                    return b;
                }
            }
            blocks.len() - 1
        };
        let kappa = |b: usize| -> f64 {
            match (blocked, weighting) {
                (true, BlockWeighting::Length) => blocks[b] as f64,
                _ => 1.0,
            }
        };
        let (a_ring, bu_ring, c_ring, y_ring, has_y) =
            (&self.a_ring, &self.bu_ring, &self.c_ring, &self.y_ring, &self.has_y);
        self.window.build(
            len,
            nblocks,
            |j, a_out, bu_out| {
                let sl = (s + j) % cap;
                a_out.copy_from_slice(&a_ring[sl * n * n..(sl + 1) * n * n]);
                bu_out.copy_from_slice(&bu_ring[sl * n..(sl + 1) * n]);
            },
            |j, c_out, y_out| {
                let sl = (s + j) % cap;
                c_out.copy_from_slice(&c_ring[sl * m * n..(sl + 1) * m * n]);
                y_out.copy_from_slice(&y_ring[sl * m..(sl + 1) * m]);
                has_y[sl]
            },
            block_of,
            kappa,
            &self.prior_mean,
            &self.prior_inv,
            &self.q_inv,
            &self.w_lo,
            &self.w_hi,
            &mut self.mat_c,
            &mut self.vec_a,
            &mut self.buf_c,
            &mut self.buf_y,
        );
        // Warm start: x_s from the prior mean, ω = 0; v from the previous window, 0 for new samples.
        let nz = self.window.nz;
        self.z[..nz].fill(0.0);
        self.z[..n].copy_from_slice(&self.prior_mean);
        for j in 0..len {
            let k = s + j;
            let sl = k % cap;
            for i in 0..m {
                self.v[j * m + i] = if k < big_t && k <= self.t { self.v_ring[sl * m + i] } else { 0.0 };
            }
        }
        let mut noise = NoiseData {
            r_inv: &self.r_inv,
            v_lo: &self.v_lo,
            v_hi: &self.v_hi,
            cost: self.settings.cost,
            output_constraint: self.settings.output_constraint,
        };
        // Warm start kept for a second attempt without the output constraints.
        self.z_start[..nz].copy_from_slice(&self.z[..nz]);
        self.v_start[..len * m].copy_from_slice(&self.v[..len * m]);
        let mut counters =
            run_solver(self.settings.solver, &mut self.window, &noise, &mut self.scratch, &mut self.z, &mut self.v);
        if counters.status == WindowStatus::Infeasible {
            // The output constraints cannot all hold (data beyond V for every admissible
            // trajectory): solve without them and say so.
            noise.output_constraint = false;
            self.z[..nz].copy_from_slice(&self.z_start[..nz]);
            self.v[..len * m].copy_from_slice(&self.v_start[..len * m]);
            counters =
                run_solver(self.settings.solver, &mut self.window, &noise, &mut self.scratch, &mut self.z, &mut self.v);
            if counters.status == WindowStatus::Converged {
                counters.status = WindowStatus::Infeasible;
            }
        }
        let objective = saddle_value(&mut self.window, &noise, &self.z[..nz], &mut self.scratch.e[..len * m]);
        for j in 0..len {
            self.window.state(j, &self.z[..nz], &mut self.traj_work[j * n..(j + 1) * n]);
        }
        if !self.traj_work[..len * n].iter().all(|x| x.is_finite()) || !objective.is_finite() {
            return Err(EstimatorError::NumericalFailure("the window's solution is not finite"));
        }
        Ok((counters, objective))
    }

    /// Stores the solved window ending at `big_t` (start `s`) and publishes its last state.
    fn commit(
        &mut self,
        big_t: usize,
        s: usize,
        (solve, objective, data): (SolveCounters, f64, DataCheck),
        arrival: ArrivalStatus,
        start: Instant,
    ) {
        let (n, m, cap) = (self.n, self.m, self.cap);
        let len = big_t - s + 1;
        for j in 0..len {
            let sl = (s + j) % cap;
            self.traj_ring[sl * n..(sl + 1) * n].copy_from_slice(&self.traj_work[j * n..(j + 1) * n]);
            self.v_ring[sl * m..(sl + 1) * m].copy_from_slice(&self.v[j * m..(j + 1) * m]);
        }
        let sl = big_t % cap;
        let last = &self.traj_work[(len - 1) * n..len * n];
        self.filt_ring[sl * n..(sl + 1) * n].copy_from_slice(last);
        self.est.center.as_mut_slice().copy_from_slice(last);
        // Shape: (P_T⁻¹ + Cᵀ R_eff⁻¹ C)⁻¹ (the Kalman form's posterior).
        let r_eff = self.settings.r_eff_factor();
        if self.information(sl, r_eff, 0.0) {
            self.est.weight.as_mut_slice().copy_from_slice(&self.mat_b);
        }
        let blocks = if big_t > self.settings.horizon { self.settings.blocks.len() } else { len - 1 };
        self.est.report = Some(MheReport {
            solve,
            window: len,
            vector_unknowns: 1 + blocks,
            unknowns: n * (1 + blocks),
            arrival,
            objective,
            elapsed: start.elapsed(),
            measured: self.has_y[sl],
            data,
        });
    }
}

/// Runs the configured window solver.
fn run_solver(
    solver: WindowSolver,
    window: &mut WindowProblem,
    noise: &NoiseData<'_>,
    scratch: &mut SolverScratch,
    z: &mut [f64],
    v: &mut [f64],
) -> SolveCounters {
    match solver {
        WindowSolver::CoordinateRotation { max_sweeps, tolerance, inner } => {
            coordinate_rotation(window, noise, scratch, z, v, max_sweeps, tolerance, inner)
        }
        WindowSolver::ExactSaddle { max_iterations, tolerance } => {
            exact_saddle(window, noise, scratch, z, v, max_iterations, tolerance)
        }
    }
}

fn sym(a: &mut [f64], n: usize) {
    for c in 0..n {
        for r in c + 1..n {
            let v = 0.5 * (a[c * n + r] + a[r * n + c]);
            a[c * n + r] = v;
            a[r * n + c] = v;
        }
    }
}

impl<M: LinearModel + ?Sized> Estimator<M> for MovingHorizonEstimator {
    type Estimate = MheEstimate;

    fn step(&mut self, model: &M, u: &DVector<f64>, y: &DVector<f64>) -> Result<&MheEstimate, EstimatorError> {
        self.advance(model, u, Some(y), None)
    }

    fn predict(&mut self, model: &M, u: &DVector<f64>) -> Result<&MheEstimate, EstimatorError> {
        self.advance(model, u, None, None)
    }

    /// A step with the outputs where `measured` is true (the others' entries of `y` are not
    /// read): `R` is diagonal, so the window, the arrival recursion and the Riccati step drop the
    /// unmeasured rows (kept as zero rows of `C` and entries of `y` in the sample's slot) and
    /// the data check skips them. Every output: a step; none: a prediction. Refused with the
    /// output constraint (its constraints are built for whole samples). On error the estimator
    /// is unchanged.
    fn step_partial(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        measured: &[bool],
    ) -> Result<&MheEstimate, EstimatorError> {
        check_model(model, self.n, self.p, self.m)?;
        match crate::partial::classify(measured, u, y, (self.m, self.p), &mut self.partial_rows)? {
            crate::partial::Measured::All => self.advance(model, u, Some(y), None),
            crate::partial::Measured::Nothing => self.advance(model, u, None, None),
            crate::partial::Measured::Some(_) if self.settings.output_constraint => Err(EstimatorError::Unsupported {
                estimator: "the moving-horizon estimator with the output constraint",
                operation: "a partial measurement",
                reason: "its output constraints are built for whole samples",
            }),
            crate::partial::Measured::Some(_) => self.advance(model, u, Some(y), Some(measured)),
        }
    }

    fn update(&mut self, _model: &M, _y: &DVector<f64>) -> Result<&MheEstimate, EstimatorError> {
        Err(EstimatorError::Unsupported {
            estimator: "the moving-horizon estimator",
            operation: "update",
            reason: "a window sample is an input and the measurement after it; use step (or predict when no \
                     measurement arrived)",
        })
    }

    fn estimate(&self) -> &MheEstimate {
        &self.est
    }

    fn dims(&self) -> Dims {
        Dims::new(self.n, self.p, self.m)
    }

    fn set_data_checks(&mut self, checks: DataChecks) -> Result<(), EstimatorError> {
        MovingHorizonEstimator::set_data_checks(self, checks)
    }
}
