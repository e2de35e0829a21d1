//! The set-membership filter itself: state, step, estimate and report.

use std::time::{Duration, Instant};

use intervals::Interval;
use nalgebra::{DMatrix, DVector};

use models::{Dims, LinearModel, StepModel};

use super::angles::AngleWork;
use super::certify::{CertInput, CertWork, Inflation, U, certify};
use super::consistency::{self, CheckInput, Consistency, ConsistencyWork, InconsistencyPolicy};
use super::fallback::{FallbackReason, GainCtx, clamp_tau, near_simplex};
use super::gain::GainWork;
use super::input::{InputModel, check_in_box, effective_noise};
use super::kernels::StepFns;
use super::partial::SubsetFilter;
use super::two_multiplier::TwoMultiplierSolver;
use super::update::{UpdateProblem, UpdateSolution, UpdateSolver, UpdateStatus};
use crate::angle_branch::Branch;
use crate::checks::DataChecks;
use crate::error::EstimatorError;
use crate::partial::Subsets;
use crate::traits::forward_estimator;
use crate::traits::{
    DataCheck, DetailField, Estimate, EstimateKind, Guarantee, Setup, SolveOutcome, StepDetails, StepStatus,
};
use crate::validate::{InitialData, check_initial, check_model, check_vec};

/// What one step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepReport {
    /// Initial, predicted, converged (the solver's `(L, τ)` used), or a fallback.
    pub outcome: SolveOutcome,
    /// The multipliers used (after clamping onto the simplex).
    pub tau: [f64; 3],
    /// The solver's status.
    pub status: UpdateStatus,
    /// The solver's iterations.
    pub iterations: u32,
    /// `Some(reason)` if the step did not use the solver's `(L, τ)` as returned but a feasible `τ`
    /// with its closed-form gain (the fallback of the module documentation, or `L = 0` for a
    /// solver's `τ₃ = 0`).
    pub fallback: Option<FallbackReason>,
    /// The certification inflation applied.
    pub inflation: Inflation,
    /// Wall-clock time of the solver call.
    pub solve_time: Duration,
    /// Whether the step's measurement was consistent with the predicted set and the noise bounds
    /// (module [`super::consistency`]).
    pub consistency: Consistency,
    /// Whether the published set is guaranteed: `false` from the first inconsistent step on
    /// (with [`InconsistencyPolicy::FlagAndContinue`]; the default policy refuses such a step).
    pub guaranteed: bool,
}

/// The numbers a set-membership step reports beyond its status (`port-est`'s columns, Python's
/// `details`): the multipliers of (29) and the solver's iterations.
pub const DETAILS: &[DetailField] = &[
    DetailField { name: "tau1", meaning: "multiplier of the predicted set in (29)" },
    DetailField { name: "tau2", meaning: "multiplier of the process noise in (29)" },
    DetailField { name: "tau3", meaning: "multiplier of the measurement's strip in (29)" },
    DetailField {
        name: "iterations",
        meaning: "iterations of the solve of (29): Newton steps of the two-multiplier method, or the SDP \
                  backend's interior-point iterations (0 for the initial set and predictions)",
    },
];

impl StepReport {
    /// The report as [`StepDetails`] ([`DETAILS`]).
    #[must_use]
    pub fn details(&self) -> StepDetails {
        let [t1, t2, t3] = self.tau;
        StepDetails::new(DETAILS, &[Some(t1), Some(t2), Some(t3), Some(f64::from(self.iterations))])
    }

    /// Whether a fallback was used.
    pub fn fallback_used(&self) -> bool {
        self.fallback.is_some()
    }
}

/// The set estimate `𝓔(center, shape)` after a step, its per-state bounds and the report.
#[derive(Debug, Clone, PartialEq)]
pub struct SetEstimate {
    /// `x̂_{k+1}`.
    pub center: DVector<f64>,
    /// `P_{k+1}` (symmetric positive definite, certified).
    pub shape: DMatrix<f64>,
    /// `x̂_i − √P_ii`, rounded down; for `smf-nl` cut by its declared bounds and its interval
    /// observer (docs/nonlinear-smf.md (N1'), (N7)–(N8)), which may leave `x̂_i` outside.
    pub lower: DVector<f64>,
    /// `x̂_i + √P_ii`, rounded up; cut likewise.
    pub upper: DVector<f64>,
    /// What the step did (for the initial set: `τ = (⅓, ⅓, ⅓)`, status unsolved).
    pub report: StepReport,
    /// Whether some state's interval is wider than [`DIVERGENCE_FACTOR`] times its initial width,
    /// or, for a state with finite declared bounds (`smf-nl`), spans their whole range: the status
    /// says `diverging`.
    pub diverging: bool,
    /// Per state, [`DIVERGENCE_FACTOR`] times the initial interval's width.
    width_limit: DVector<f64>,
}

/// A state's interval wider than this many times its initial width marks the step diverging
/// ([`Guarantee::Diverging`]; the constrained-zonotope filters' default rule). A state with finite
/// declared bounds is held to them instead: diverging when its set spans their whole range (the
/// estimate then says nothing the bounds did not), whatever it is compared with the initial set.
pub const DIVERGENCE_FACTOR: f64 = 2.0;

impl StepReport {
    /// The report of the initial set.
    fn initial() -> Self {
        StepReport {
            outcome: SolveOutcome::Initial,
            tau: [1.0 / 3.0; 3],
            status: UpdateStatus::Unsolved,
            iterations: 0,
            fallback: None,
            inflation: Inflation::default(),
            solve_time: Duration::ZERO,
            consistency: Consistency::Consistent,
            guaranteed: true,
        }
    }
}

impl SetEstimate {
    /// `tr P`.
    pub fn trace(&self) -> f64 {
        self.shape.trace()
    }

    /// The estimate as an [`ellipsoid::Ellipsoid`] (allocates).
    pub fn to_ellipsoid(&self) -> Result<ellipsoid::Ellipsoid, ellipsoid::EllipsoidError> {
        ellipsoid::Ellipsoid::new(self.center.clone(), self.shape.clone())
    }

    /// `x̂_i ∓ √P_ii`, rounded outward (the square root and the sums each one ulp), so the
    /// published interval contains the certified ellipsoid's projection.
    fn set_bounds(&mut self) {
        self.diverging = false;
        for i in 0..self.center.len() {
            let r = intervals::up(self.shape[(i, i)].max(0.0).sqrt());
            self.lower[i] = intervals::down(self.center[i] - r);
            self.upper[i] = intervals::up(self.center[i] + r);
            self.diverging |= self.upper[i] - self.lower[i] > self.width_limit[i];
        }
    }

    /// Cuts the published interval by declared `bounds` the true state always respects and by a
    /// certified `observer` box, and decides divergence on the result (a state with finite bounds
    /// when it spans them, the others by [`DIVERGENCE_FACTOR`]); `false` (and that state left as
    /// the bounds cut it) where the observer's box misses the set's interval — both hold the true
    /// state, so the data contradict the assumptions.
    pub(crate) fn cut_by(&mut self, bounds: &[Interval], observer: &[Interval]) -> bool {
        let mut met = true;
        self.diverging = false;
        for (i, (b, o)) in bounds.iter().zip(observer).enumerate() {
            self.lower[i] = self.lower[i].max(b.lo());
            self.upper[i] = self.upper[i].min(b.hi());
            let (lo, hi) = (self.lower[i].max(o.lo()), self.upper[i].min(o.hi()));
            if lo <= hi {
                self.lower[i] = lo;
                self.upper[i] = hi;
            } else {
                met = false;
            }
            let bounded = b.lo().is_finite() && b.hi().is_finite();
            self.diverging |= if bounded {
                self.lower[i] <= b.lo() && self.upper[i] >= b.hi()
            } else {
                self.upper[i] - self.lower[i] > self.width_limit[i]
            };
        }
        met
    }
}

#[derive(Debug, Clone)]
struct Workspace {
    ap: DMatrix<f64>,
    x1: DMatrix<f64>,
    q_eff: DMatrix<f64>,
    bw: DMatrix<f64>,
    cert: CertWork,
    gain: GainWork,
    /// `m × m` scratch for validating a new `R` in place.
    gain_r: DMatrix<f64>,
    cons: ConsistencyWork,
    /// A zero measurement for the prediction-only step's certification (`L = 0`).
    y_zero: DVector<f64>,
    /// The step's parts compiled for this size, or the general ones (module `kernels`).
    fns: StepFns,
}

impl Workspace {
    /// Runs the step's parts with `fns` (the solver's own are set apart).
    fn set_fns(&mut self, fns: StepFns) {
        self.fns = fns;
        self.cert.fns = fns;
        self.gain.fns = fns;
        self.cons.fns = fns;
    }
}

/// What [`SetMembershipFilter::predict`] keeps for a following [`SetMembershipFilter::update`]:
/// the update (13)–(29) is joint with the prediction, from the set before it.
#[derive(Debug, Clone, Default)]
pub(super) struct PendingPrediction {
    /// Whether a prediction is waiting for its measurement.
    pub(super) armed: bool,
    /// `x̂_k`, `P_k` and the report of the set before the prediction.
    center: DVector<f64>,
    shape: DMatrix<f64>,
    report: Option<StepReport>,
    /// `A_k`, `B_k`, `u_k` of the prediction.
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    u: DVector<f64>,
}

/// The improved set-membership filter, generic over the solver of (29).
#[derive(Debug, Clone)]
pub struct SetMembershipFilter<S: UpdateSolver = TwoMultiplierSolver> {
    pub(super) n: usize,
    pub(super) p: usize,
    pub(super) m: usize,
    pub(super) q: DMatrix<f64>,
    pub(super) r: DMatrix<f64>,
    pub(super) input: InputModel,
    pub(super) solver: S,
    pub(super) time_budget: Option<Duration>,
    pub(super) policy: InconsistencyPolicy,
    /// Steps taken so far.
    pub(super) steps: u64,
    /// Whether an inconsistent step was published (policy `FlagAndContinue`).
    pub(super) guarantee_lost: bool,
    pub(super) est: SetEstimate,
    sol: UpdateSolution,
    ws: Workspace,
    pub(super) pending: PendingPrediction,
    /// The filters of partial steps, by measured count (module `partial`).
    pub(super) partial: Subsets<SubsetFilter<S>>,
    /// The branches of angle outputs (module `angles`).
    pub(super) angles: AngleWork,
}

impl SetMembershipFilter<TwoMultiplierSolver> {
    /// The filter with the exact two-multiplier solver, from its [`Setup`]: the initial set
    /// `𝓔(x0, p0)` and the noise shapes `w ∈ 𝓔(0, Q)`, `v ∈ 𝓔(0, R)`.
    ///
    /// # Errors
    /// Dimension, finiteness, symmetry and positive-definiteness errors naming the matrix.
    pub fn new(setup: Setup) -> Result<Self, EstimatorError> {
        Self::with_solver(setup, TwoMultiplierSolver::new())
    }

    /// Runs every later step with the runtime-size kernels instead of those compiled for the
    /// filter's size (same numbers; for the tests and benches that compare the two).
    #[doc(hidden)]
    pub fn use_general_kernels(&mut self) {
        self.ws.set_fns(StepFns::general());
        self.solver.use_general_kernels();
        self.partial.clear();
    }

    /// Whether the step runs code compiled for the filter's size (module `kernels`).
    #[doc(hidden)]
    pub fn runs_compiled_step(&self) -> bool {
        self.ws.fns.fixed && self.solver.runs_compiled_kernels()
    }
}

impl<S: UpdateSolver> SetMembershipFilter<S> {
    /// A filter from its [`Setup`] (ellipsoid shapes) with the given solver of (29).
    ///
    /// # Errors
    /// As [`SetMembershipFilter::new`], and the solver's preparation error.
    pub fn with_solver(setup: Setup, mut solver: S) -> Result<Self, EstimatorError> {
        let InitialData { n, m, x0, p0, q, r, inputs } = check_initial(setup)?;
        solver.prepare(n, m)?;
        let mut est = SetEstimate {
            center: x0,
            shape: p0,
            lower: DVector::zeros(n),
            upper: DVector::zeros(n),
            report: StepReport::initial(),
            diverging: false,
            width_limit: DVector::from_element(n, f64::INFINITY),
        };
        est.set_bounds();
        est.width_limit = (&est.upper - &est.lower) * DIVERGENCE_FACTOR;
        let nn = || DMatrix::zeros(n, n);
        Ok(Self {
            n,
            p: inputs,
            m,
            q,
            r,
            input: InputModel::Predictor,
            solver,
            time_budget: None,
            policy: InconsistencyPolicy::default(),
            steps: 0,
            guarantee_lost: false,
            est,
            sol: UpdateSolution::new(n, m),
            ws: Workspace {
                ap: nn(),
                x1: nn(),
                q_eff: nn(),
                bw: DMatrix::zeros(n, inputs),
                cert: CertWork::new(n, m),
                gain: GainWork::new(n, m),
                gain_r: DMatrix::zeros(m, m),
                cons: ConsistencyWork::new(n, m),
                y_zero: DVector::zeros(m),
                fns: StepFns::for_sizes(n, m),
            },
            pending: PendingPrediction {
                armed: false,
                center: DVector::zeros(n),
                shape: DMatrix::zeros(n, n),
                report: None,
                a: DMatrix::zeros(n, n),
                b: DMatrix::zeros(n, inputs),
                u: DVector::zeros(inputs),
            },
            partial: Subsets::new(m),
            angles: AngleWork::new(n, m),
        })
    }

    /// Switches to the "input as bounded disturbance" model with the input box
    /// `[lower, upper]` (see [`InputModel::BoundedDisturbance`]).
    pub fn with_input_bounds(mut self, lower: &DVector<f64>, upper: &DVector<f64>) -> Result<Self, EstimatorError> {
        check_vec("input lower bounds", lower, self.p)?;
        check_vec("input upper bounds", upper, self.p)?;
        let mut mid = DVector::zeros(self.p);
        let mut w_diag = DVector::zeros(self.p);
        for i in 0..self.p {
            let (lo, hi) = (lower[i], upper[i]);
            // Halves first: lo + hi and hi − lo cannot overflow.
            let c = 0.5 * lo + 0.5 * hi;
            // |u − c| ≤ h_exact for u in the box; fl(h) ≥ h_exact (1 − u).
            let h = (hi - c).max(c - lo);
            // The box lies in c ⊕ 𝓔(0, p·diag(h²)): Σ dᵢ²/(p hᵢ²) ≤ Σ 1/p = 1. The factor 1 + 8u
            // covers h_exact ≤ h/(1 − u) and the three roundings of the product: (1 + 8u)(1 − u)⁵ > 1.
            let w = self.p as f64 * h * h * (1.0 + 8.0 * U);
            if lo > hi || !w.is_finite() {
                return Err(EstimatorError::InvalidInputBounds { index: i, lower: lo, upper: hi });
            }
            mid[i] = c;
            w_diag[i] = w;
        }
        self.input = InputModel::BoundedDisturbance { lower: lower.clone(), upper: upper.clone(), mid, w_diag };
        self.partial.clear();
        Ok(self)
    }

    /// Replaces both noise matrices in place (each validated first; if either is rejected
    /// nothing changes; no allocation).
    pub fn set_noise(&mut self, q: &DMatrix<f64>, r: &DMatrix<f64>) -> Result<(), EstimatorError> {
        crate::validate::check_spd_no_alloc("R", r, self.m, &mut self.ws.gain_r)?;
        self.set_process_noise(q)?;
        self.set_measurement_noise(r)
    }

    /// Replaces the process-noise shape `Q` in place (symmetric positive definite, `n × n`;
    /// no allocation; unchanged on error).
    pub fn set_process_noise(&mut self, q: &DMatrix<f64>) -> Result<(), EstimatorError> {
        crate::validate::replace_spd("Q", &mut self.q, q, &mut self.ws.cert.t)
    }

    /// Replaces the measurement-noise shape `R` in place (symmetric positive definite, `m × m`;
    /// no allocation; unchanged on error).
    pub fn set_measurement_noise(&mut self, r: &DMatrix<f64>) -> Result<(), EstimatorError> {
        crate::validate::replace_spd("R", &mut self.r, r, &mut self.ws.gain_r)
    }

    /// What a step does when its data are provably inconsistent with the noise bounds (default:
    /// [`InconsistencyPolicy::Error`]; [`InconsistencyPolicy::Off`] skips the check).
    pub fn set_inconsistency_policy(&mut self, policy: InconsistencyPolicy) {
        self.policy = policy;
    }

    /// The data checks ([`DataChecks::policy`]; the set-membership filter's check is a proof, so
    /// the gate probability is not used).
    pub fn set_data_checks(&mut self, checks: DataChecks) -> Result<(), EstimatorError> {
        self.set_inconsistency_policy(checks.policy);
        Ok(())
    }

    /// Steps taken so far (the next step is number `steps() + 1`).
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Per-step wall-clock budget for the solver; a step exceeding it falls back.
    pub fn set_time_budget(&mut self, budget: Option<Duration>) {
        self.time_budget = budget;
    }

    /// Number of states, inputs, outputs.
    #[must_use]
    pub fn dims(&self) -> Dims {
        Dims::new(self.n, self.p, self.m)
    }

    /// How the input enters.
    pub fn input_model(&self) -> &InputModel {
        &self.input
    }

    /// The current set estimate.
    pub fn estimate(&self) -> &SetEstimate {
        &self.est
    }

    /// The current set estimate, for a wrapper that refines its published interval.
    pub(crate) fn estimate_mut(&mut self) -> &mut SetEstimate {
        &mut self.est
    }

    /// Marks the current estimate inconsistent, its data contradicted by a proof found outside
    /// the update (`smf-nl`'s interval observer) under a policy that publishes such steps: no set
    /// from now on is guaranteed, as after [`InconsistencyPolicy::FlagAndContinue`].
    pub(crate) fn mark_inconsistent(&mut self) {
        self.guarantee_lost = true;
        self.est.report.guaranteed = false;
        if self.policy != InconsistencyPolicy::Off {
            // How far outside is not measured by the observer's proof.
            self.est.report.consistency = Consistency::Inconsistent { excess: f64::NAN };
        }
    }

    /// The policy for inconsistent data.
    pub(crate) fn inconsistency_policy(&self) -> InconsistencyPolicy {
        self.policy
    }

    /// The solver.
    pub fn solver(&self) -> &S {
        &self.solver
    }

    /// The solver, mutably (for example to change its settings).
    pub fn solver_mut(&mut self) -> &mut S {
        &mut self.solver
    }

    /// The prediction (no measurement yet, or none arrived): the certified outer bound of
    /// `A 𝓔(x̂_k, P_k) ⊕ 𝓔(0, Q)` (plus `B u_k`), the update (13)–(29) with `τ₃ = 0` and `L = 0`:
    /// `P = X₁/τ₁ + Q/τ₂` with the trace-optimal weights of [`ellipsoid::minkowski`], certified
    /// as every published set. The set grows honestly; it stays guaranteed. The set before it is
    /// kept, so that a following [`SetMembershipFilter::update`] makes the joint step (13)–(29)
    /// from it. On error the filter is unchanged. Allocation-free.
    ///
    /// # Errors
    /// As [`SetMembershipFilter::step`], except the data checks of `y`.
    pub fn predict<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
    ) -> Result<&SetEstimate, EstimatorError> {
        check_model(model, self.n, self.p, self.m)?;
        let model = &StepModel::new(model.a(), model.b(), model.c());
        check_vec("u", u, self.p)?;
        if let InputModel::BoundedDisturbance { lower, upper, .. } = &self.input {
            check_in_box(u, lower, upper)?;
        }
        let Self { q, r, input, est, sol, ws, steps, guarantee_lost, pending, .. } = self;
        let (bounded, u_used) = predictor(model, &est.shape, q, input, u, ws);
        let q_used: &DMatrix<f64> = if bounded { &ws.q_eff } else { q };
        let (t1, t2) = ellipsoid::minkowski::min_trace_weights(ws.x1.trace(), q_used.trace());
        let Some(tau) = clamp_tau([t1, t2, 0.0]) else {
            return Err(EstimatorError::NumericalFailure("the prediction's multipliers are not finite"));
        };
        sol.l.fill(0.0);
        let input = CertInput { model, l: &sol.l, tau, x1: &ws.x1, q: q_used, r, est, u: u_used, y: &ws.y_zero };
        let Some(inflation) = certify(&mut ws.cert, &input) else {
            return Err(EstimatorError::NumericalFailure("the predicted set is not finite"));
        };
        pending.center.copy_from(&est.center);
        pending.shape.copy_from(&est.shape);
        pending.report = Some(est.report);
        pending.a.copy_from(model.a);
        pending.b.copy_from(model.b);
        pending.u.copy_from(u);
        pending.armed = true;
        std::mem::swap(&mut est.center, &mut ws.cert.x_new);
        std::mem::swap(&mut est.shape, &mut ws.cert.p_new);
        est.set_bounds();
        *steps += 1;
        est.report = StepReport {
            outcome: SolveOutcome::Predicted,
            tau,
            status: UpdateStatus::Unsolved,
            iterations: 0,
            fallback: None,
            inflation,
            solve_time: Duration::ZERO,
            consistency: Consistency::Consistent,
            guaranteed: !*guarantee_lost,
        };
        Ok(est)
    }

    /// The measurement update with `y_{k+1}` of the last [`SetMembershipFilter::predict`]: the
    /// joint step (13)–(29) from the set before that prediction with its `A_k`, `B_k`, `u_k`, and
    /// this model's `C_{k+1}` — the same numbers as [`SetMembershipFilter::step`]. On error the
    /// filter is unchanged (the prediction stays published and pending). Allocation-free.
    ///
    /// # Errors
    /// [`EstimatorError::UpdateWithoutPrediction`] when no prediction is pending (the update is
    /// joint with a prediction; a second update of the same step has none); otherwise as
    /// [`SetMembershipFilter::step`].
    pub fn update<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        y: &DVector<f64>,
    ) -> Result<&SetEstimate, EstimatorError> {
        check_model(model, self.n, self.p, self.m)?;
        check_vec("y", y, self.m)?;
        if !self.pending.armed {
            return Err(EstimatorError::UpdateWithoutPrediction { estimator: "the set-membership filter" });
        }
        let mut pending = std::mem::take(&mut self.pending);
        let Some(mut prior_report) = pending.report else {
            return Err(EstimatorError::UpdateWithoutPrediction { estimator: "the set-membership filter" });
        };
        let swap = |est: &mut SetEstimate, pending: &mut PendingPrediction, report: &mut StepReport| {
            std::mem::swap(&mut est.center, &mut pending.center);
            std::mem::swap(&mut est.shape, &mut pending.shape);
            std::mem::swap(&mut est.report, report);
        };
        swap(&mut self.est, &mut pending, &mut prior_report);
        self.steps -= 1;
        let angles = LinearModel::angles(model).outputs;
        let result =
            self.step_model(&StepModel::new(&pending.a, &pending.b, model.c()), angles, &pending.u, y).map(|_| ());
        match result {
            Ok(()) => {
                pending.armed = false;
                pending.report = None;
                self.pending = pending;
                Ok(&self.est)
            }
            Err(e) => {
                swap(&mut self.est, &mut pending, &mut prior_report);
                pending.report = Some(prior_report);
                self.steps += 1;
                self.pending = pending;
                Err(e)
            }
        }
    }

    /// One step, [`SetMembershipFilter::predict`] and [`SetMembershipFilter::update`] at once:
    /// consumes `u_k` and the measurement `y_{k+1}`, returns the certified set estimate. On error
    /// the filter is unchanged. After the first step (which may set a solver up), this does not
    /// allocate with the two-multiplier solver or an SDP backend whose solve does not allocate.
    ///
    /// # Errors
    /// Wrong dimensions of the model, `u` or `y`; NaN/∞ in them; an input outside its declared
    /// box ([`EstimatorError::InputOutsideBounds`]); a measurement that contradicts the predicted
    /// set and the noise bounds ([`EstimatorError::InconsistentData`], with the default policy); a
    /// set that is not finite ([`EstimatorError::NumericalFailure`]).
    pub fn step<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) -> Result<&SetEstimate, EstimatorError> {
        check_model(model, self.n, self.p, self.m)?;
        let angles = LinearModel::angles(model).outputs;
        self.step_model(&StepModel::new(model.a(), model.b(), model.c()), angles, u, y)
    }

    /// [`Self::step`] for the matrices of `model` whose outputs `angle_outputs` are angles
    /// (module `angles`: their branch chosen over the predicted set, `R` inflated by its rounding).
    pub(super) fn step_model(
        &mut self,
        model: &StepModel<'_>,
        angle_outputs: &[usize],
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) -> Result<&SetEstimate, EstimatorError> {
        check_vec("u", u, self.p)?;
        check_vec("y", y, self.m)?;
        if let InputModel::BoundedDisturbance { lower, upper, .. } = &self.input {
            check_in_box(u, lower, upper)?;
        }
        let Self {
            q,
            r,
            input,
            solver,
            time_budget,
            est,
            sol,
            ws,
            n,
            m,
            policy,
            steps,
            guarantee_lost,
            pending,
            angles,
            ..
        } = self;
        let (n, m) = (*n, *m);
        let (bounded, u_used) = predictor(model, &est.shape, q, input, u, ws);
        let (y, r, off_branch) = if angle_outputs.is_empty() {
            (y, &*r, false)
        } else {
            let q_pred = if bounded { &ws.q_eff } else { &*q };
            let shape = (&est.center, &est.shape);
            let found = angles.choose(model, angle_outputs, shape, q_pred, u_used, r, y, *steps + 1)?;
            if found == Branch::Contradicted && *policy == InconsistencyPolicy::Error {
                return Err(EstimatorError::SetMissed { step: *steps + 1, reason: ANGLE_MISSED });
            }
            (&angles.y, &angles.r, found == Branch::Contradicted)
        };
        let warm = est.report.tau;
        // Consistency of y with the predicted set and the noise bounds, before anything changes.
        let consistency = if *policy == InconsistencyPolicy::Off {
            Consistency::NotChecked
        } else {
            consistency_of(ws, model, (&est.center, warm), (u_used, q, bounded), r, y)
        };
        let mut restarted = false;
        if let Consistency::Inconsistent { excess } = consistency {
            match *policy {
                InconsistencyPolicy::FlagAndContinue => {}
                InconsistencyPolicy::Restart => {
                    // Inflate the prediction (A P_k Aᵀ, Q and P_k alike) by powers of four, starting
                    // from (1 + excess)², until the measurement is compatible with it.
                    if !bounded {
                        ws.q_eff.copy_from(q);
                    }
                    ws.ap.copy_from(&est.shape);
                    let mut factor = (1.0 + excess) * (1.0 + excess);
                    for _ in 0..64 {
                        for m in [&mut ws.x1, &mut ws.q_eff, &mut ws.ap] {
                            m.iter_mut().for_each(|v| *v *= factor);
                        }
                        let ok = ws.x1.iter().chain(ws.q_eff.iter()).all(|v| v.is_finite());
                        if ok
                            && consistency::check(
                                &mut ws.cons,
                                &CheckInput { c: model.c, x1: &ws.x1, q: &ws.q_eff, r, y, tau: warm },
                            )
                            .is_consistent()
                        {
                            restarted = true;
                            break;
                        }
                        if !ok {
                            break;
                        }
                        factor = 4.0;
                    }
                    if !restarted {
                        return Err(EstimatorError::InconsistentData { step: *steps + 1, excess });
                    }
                }
                _ => return Err(EstimatorError::InconsistentData { step: *steps + 1, excess }),
            }
        }
        let q_used: &DMatrix<f64> = if bounded || restarted { &ws.q_eff } else { q };
        let p_used: &DMatrix<f64> = if restarted { &ws.ap } else { &est.shape };
        let problem = UpdateProblem { a: model.a, c: model.c, q: q_used, r, p: p_used, x_hat: &est.center, x1: &ws.x1 };
        let t0 = Instant::now();
        let result = solver.solve(&problem, warm, sol);
        let solve_time = t0.elapsed();
        let closed_form = solver.gain_is_closed_form();
        if sol.l.shape() != (n, m) {
            // A solver resized the gain buffer: restore it (allocates; never with our solvers).
            sol.l = DMatrix::zeros(n, m);
            sol.status = UpdateStatus::NumericalTrouble;
        }
        // Decide whether the solver's (L, τ) is usable.
        let mut reason = match result {
            Err(_) => Some(FallbackReason::SolverError),
            Ok(()) if !sol.status.is_optimal() => Some(FallbackReason::Status(sol.status)),
            Ok(()) => None,
        };
        if reason.is_none() && time_budget.is_some_and(|b| solve_time >= b) {
            reason = Some(FallbackReason::TimeBudget);
        }
        let mut gain = GainCtx { work: &mut ws.gain, loaded: false, x1: &ws.x1, q: q_used, c: model.c, r };
        let mut tau = [0.0; 3];
        // Whether (τ, L) is already the fallback one.
        let mut fell_back = reason.is_some();
        if !fell_back {
            match clamp_tau(sol.tau).filter(|_| near_simplex(sol.tau)) {
                None => fell_back = true,
                Some(t) if t[2] == 0.0 => {
                    // τ₃ = 0: the measurement is not used, which (27) allows only with L = 0 (also
                    // the closed-form gain for τ₃ = 0). A closed-form solver's non-zero L is
                    // inconsistent with its τ: reported, but (τ, 0) is still a valid choice.
                    tau = t;
                    if closed_form && sol.l.iter().any(|v| *v != 0.0) {
                        reason = Some(FallbackReason::InvalidSolution);
                    }
                    sol.l.fill(0.0);
                }
                Some(t) if !closed_form => {
                    tau = t;
                    fell_back = !gain.closed_form(t, &mut sol.l);
                }
                Some(t) => {
                    tau = t;
                    fell_back = !sol.l.iter().all(|v| v.is_finite());
                }
            }
            if fell_back {
                reason = Some(FallbackReason::InvalidSolution);
            }
        }
        if fell_back {
            tau = gain.fallback(warm, &mut sol.l);
        }
        // Certified P_{k+1} and centre; redone with the fallback if they overflowed.
        let mut inflation =
            certify(&mut ws.cert, &CertInput { model, l: &sol.l, tau, x1: gain.x1, q: q_used, r, est, u: u_used, y });
        if inflation.is_none() && !fell_back {
            reason = Some(FallbackReason::InvalidSolution);
            tau = gain.fallback(warm, &mut sol.l);
            inflation = certify(
                &mut ws.cert,
                &CertInput { model, l: &sol.l, tau, x1: gain.x1, q: q_used, r, est, u: u_used, y },
            );
        }
        let Some(inflation) = inflation else {
            return Err(EstimatorError::NumericalFailure("the set estimate is not finite"));
        };
        std::mem::swap(&mut est.center, &mut ws.cert.x_new);
        std::mem::swap(&mut est.shape, &mut ws.cert.p_new);
        est.set_bounds();
        // An angle output off every branch of its enclosure contradicts the set (a policy other
        // than the default let the step through): published marked, no later set guaranteed.
        let consistency = match consistency {
            _ if off_branch && *policy != InconsistencyPolicy::Off => Consistency::Inconsistent { excess: f64::NAN },
            c => c,
        };
        let guaranteed = !*guarantee_lost && consistency.is_consistent() && !off_branch;
        *guarantee_lost = !guaranteed;
        *steps += 1;
        pending.armed = false;
        est.report = StepReport {
            outcome: if reason.is_some() { SolveOutcome::FallbackUsed } else { SolveOutcome::Converged },
            tau,
            status: sol.status,
            iterations: sol.iterations,
            fallback: reason,
            inflation,
            solve_time,
            consistency,
            guaranteed,
        };
        Ok(est)
    }
}

impl<S: UpdateSolver> SetMembershipFilter<S> {
    /// Runs the runtime-size kernels when `parent` does (a partial step's filter).
    pub(super) fn follow_kernels_of(&mut self, parent: &Self) {
        if !parent.ws.fns.fixed {
            self.ws.set_fns(StepFns::general());
        }
    }

    /// The filter's own proof ([`consistency`]) that `y` contradicts the set predicted with
    /// `model` and `u` and the noise bounds: `Some(excess)` when it finds one. Only workspaces
    /// change; allocation-free.
    pub(crate) fn proves_inconsistent(
        &mut self,
        model: &StepModel<'_>,
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) -> Option<f64> {
        let Self { q, r, input, est, ws, .. } = self;
        let (bounded, u_used) = predictor(model, &est.shape, q, input, u, ws);
        match consistency_of(ws, model, (&est.center, est.report.tau), (u_used, q, bounded), r, y) {
            Consistency::Inconsistent { excess } => Some(excess),
            _ => None,
        }
    }

    /// For a partial step: the measured angle outputs (those of `angle_outputs` in `rows`) of
    /// `y` on their branch over the set predicted with `model` and `u`, and `R` inflated by the
    /// shifts' rounding, into `self.angles` (module `angles`). Whether one was off every branch
    /// (with the default policy that is an error).
    ///
    /// # Errors
    /// An input outside its box; [`EstimatorError::GuaranteeLost`] for an enclosure 2π wide;
    /// [`EstimatorError::SetMissed`] for a reading off every branch with the default policy.
    pub(super) fn branch_partial(
        &mut self,
        model: &StepModel<'_>,
        angle_outputs: &[usize],
        rows: &[usize],
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) -> Result<bool, EstimatorError> {
        if let InputModel::BoundedDisturbance { lower, upper, .. } = &self.input {
            check_in_box(u, lower, upper)?;
        }
        let Self { q, r, input, est, ws, angles, steps, policy, .. } = self;
        let (bounded, u_used) = predictor(model, &est.shape, q, input, u, ws);
        let q_pred = if bounded { &ws.q_eff } else { &*q };
        let mut measured = std::mem::take(&mut angles.measured);
        measured.clear();
        measured.extend(angle_outputs.iter().copied().filter(|i| rows.binary_search(i).is_ok()));
        let found = angles.choose(model, &measured, (&est.center, &est.shape), q_pred, u_used, r, y, *steps + 1);
        angles.measured = measured;
        if found? == Branch::Contradicted {
            if *policy == InconsistencyPolicy::Error {
                return Err(EstimatorError::SetMissed { step: *steps + 1, reason: ANGLE_MISSED });
            }
            return Ok(true);
        }
        Ok(false)
    }
}

/// The consistency check ([`consistency`]) of `y` with the set `(centre, P_k)` predicted by
/// [`predictor`] (its `X₁` in `ws.x1`; `Q_eff` in `ws.q_eff` when `bounded`) with `u_used`, from the
/// multipliers `warm`. Allocation-free.
fn consistency_of(
    ws: &mut Workspace,
    model: &StepModel<'_>,
    (center, warm): (&DVector<f64>, [f64; 3]),
    (u_used, q, bounded): (&DVector<f64>, &DMatrix<f64>, bool),
    r: &DMatrix<f64>,
    y: &DVector<f64>,
) -> Consistency {
    (ws.fns.centre)(model.a, model.b, center, u_used, &mut ws.cons.z);
    let q_used = if bounded { &ws.q_eff } else { q };
    consistency::check(&mut ws.cons, &CheckInput { c: model.c, x1: &ws.x1, q: q_used, r, y, tau: warm })
}

/// The prediction shared by a step and a prediction-only step: `X₁ = A P_k Aᵀ` into `ws.x1`, and
/// the input the predictor uses with the effective process noise: `(false, u)` with `Q`, or for
/// an input treated as a bounded disturbance `(true, u_mid)` with `Q_eff` written into
/// `ws.q_eff`. Allocation-free.
fn predictor<'a>(
    model: &StepModel<'_>,
    shape: &DMatrix<f64>,
    q: &DMatrix<f64>,
    input: &'a InputModel,
    u: &'a DVector<f64>,
    ws: &mut Workspace,
) -> (bool, &'a DVector<f64>) {
    (ws.fns.x1)(model.a, shape, &mut ws.ap, &mut ws.x1);
    match input {
        InputModel::Predictor => (false, u),
        InputModel::BoundedDisturbance { mid, w_diag, .. } => {
            effective_noise(q, model.b, w_diag, &mut ws.bw, &mut ws.q_eff);
            (true, mid)
        }
    }
}

impl Estimate for SetEstimate {
    fn kind(&self) -> EstimateKind {
        EstimateKind::GuaranteedEllipsoid
    }
    fn center(&self) -> &DVector<f64> {
        &self.center
    }
    fn shape(&self) -> &DMatrix<f64> {
        &self.shape
    }
    fn bounds(&self, i: usize) -> Option<(f64, f64)> {
        (i < self.lower.len()).then(|| (self.lower[i], self.upper[i]))
    }
    fn status(&self) -> StepStatus {
        let r = &self.report;
        let data = match (r.outcome, r.consistency) {
            (SolveOutcome::Initial | SolveOutcome::Predicted, _) | (_, Consistency::NotChecked) => {
                DataCheck::NotChecked
            }
            (_, Consistency::Consistent) => DataCheck::Consistent,
            _ => DataCheck::Inconsistent,
        };
        StepStatus {
            outcome: r.outcome,
            data,
            guarantee: match (r.guaranteed, self.diverging) {
                (false, _) => Guarantee::Lost,
                (true, true) => Guarantee::Diverging,
                (true, false) => Guarantee::Holds,
            },
        }
    }
    fn details(&self) -> StepDetails {
        self.report.details()
    }
}

forward_estimator!(impl<S: UpdateSolver> for SetMembershipFilter<S>, LinearModel, SetEstimate, partial);

/// Why a step whose angle output has no branch in its enclosure was refused.
const ANGLE_MISSED: &str =
    "an angle output has no representative within the enclosure of C x over the predicted set widened by V";
