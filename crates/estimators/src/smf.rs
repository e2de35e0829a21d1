//! The improved set-membership filter of the paper, eqs (13)–(29), with certified containment.
//!
//! # One step
//!
//! Given `x_k ∈ 𝓔(x̂_k, P_k)`, `w_k ∈ 𝓔(0, Q)`, `v_{k+1} ∈ 𝓔(0, R)`:
//!
//! 1. `X₁ = A P_k Aᵀ`; an [`UpdateSolver`] solves (29) and returns `(L, τ)` (its `P` is not
//!    used). Unless the solver declares its `L` to be the closed-form gain for its `τ`
//!    ([`UpdateSolver::gain_is_closed_form`], true for the [`TwoMultiplierSolver`]), only `τ` is
//!    kept: `L` is replaced by the closed-form gain (G1) for the clamped `τ` (module
//!    [`two_multiplier`](crate::two_multiplier)), which for fixed `τ` minimises `Φ` below (in the
//!    Loewner order), so it is never worse than the solver's `L` and not sensitive to the
//!    `1/τᵢ` amplification of an inexact `L` when a multiplier is tiny;
//! 2. certification (below) recomputes `P_{k+1}` from `(L, τ)` and inflates it;
//! 3. the centre is (13) with the optimal free column zero:
//!    `x̂_{k+1} = (I − L C)(A x̂_k + B u_k) + L y_{k+1}`.
//!
//! # Certification
//!
//! Whatever solver produced `(L, τ)`, `τ` is first clamped onto the simplex by `clamp_tau`:
//! negative entries are set to 0, `τ` is rescaled to `Στ = 1` (scaling `τ` up by `c` divides `Φ`
//! by `c`, so this never hurts; the rescaling divides by the largest entry first, so it cannot
//! overflow), `τ₃ < ε·`[`TAU_FLOOR`] (below the rounding unit of the smallest allowed `τ₁`, `τ₂`) is
//! set to 0, then `τ₁, τ₂` are raised to [`TAU_FLOOR`] and the excess is taken off the largest
//! entry. The result satisfies, for any finite input that is not all zero or negative:
//! `τ₁ ≥ TAU_FLOOR`, `τ₂ ≥ TAU_FLOOR`, `τ₃ = 0` or `τ₃ ≥ ε·TAU_FLOOR`, and the floating-point sum
//! `τ₁ + τ₂ + τ₃ ≤ 1 − 2ε`, so the exact sum of the stored values is below 1. If `τ₃ = 0` the
//! measurement is not used and `L` is set to 0, the only gain (27) allows then. With
//! `K = I − L C`, (27) with the free column zero holds if and only if (Schur complement)
//!
//! ```text
//! P ⪰ Φ = K X₁ Kᵀ/τ₁ + K Q Kᵀ/τ₂ + L R Lᵀ/τ₃            (X₁ = A P_k Aᵀ exactly)
//! ```
//!
//! `Φ̂` is computed in floating point (unit roundoff `u = 2⁻⁵³`, `γ_k = k u/(1 − k u)`), with the
//! standard bounds `|fl(AB) − AB| ≤ γ_k |A||B|` and `‖|A||B|‖_F ≤ ‖A‖_F ‖B‖_F`:
//!
//! ```text
//! e_X = γ_{2n} ‖A‖²‖P_k‖                         (X̂₁ = fl(fl(A P_k) Aᵀ))
//! e_K = γ_{m+1} (√n + ‖L‖‖C‖),  κ = ‖K̂‖ + e_K     (K̂ = fl(I − L C))
//! E₁ = [γ_{2n+2}‖K̂‖²‖X̂₁‖ + (2‖K̂‖e_K + e_K²)‖X̂₁‖ + κ² e_X]/τ₁
//! E₂ = [γ_{2n+2}‖K̂‖²‖Q‖ + (2‖K̂‖e_K + e_K²)‖Q‖]/τ₂
//! E₃ = γ_{2m+2}‖L‖²‖R‖/τ₃
//! E  = E₁ + E₂ + E₃ + γ₄ (‖T̂₁‖ + ‖T̂₂‖ + ‖T̂₃‖)      (sums, divisions, symmetrisation)
//! ```
//!
//! (all norms Frobenius, which bound the spectral norm). `P_c = sym(Φ̂) + ε₂ I` with
//! `ε₂ = 2E + 4u‖Φ̂‖` (safety factor 2 for the rounding of the bound itself and second-order
//! terms) satisfies `P_c ⪰ Φ`. The centre has its own rounding error `δ`, bounded by
//!
//! ```text
//! e_z = γ_{n+p}(‖A‖‖x̂_k‖ + ‖B‖‖u‖),  ρ = 2[γ_{n+m+1}(‖K̂‖‖ẑ‖ + ‖L‖‖y‖) + e_K‖ẑ‖ + κ e_z]
//! ```
//!
//! and the error `e + δ` of the computed centre lies in the Minkowski sum
//! `𝓔(0, P_c) ⊕ 𝓔(0, ρ² I) ⊆ 𝓔(0, (1+s) P_c + (1+1/s) ρ² I)` for any `s > 0`; we take
//! `s = ρ √(n / tr P_c)` (the trace-optimal choice for the ball) and add `4u(1+s)‖P_c‖` to
//! the diagonal for the rounding of that last operation. So
//!
//! ```text
//! P_{k+1} = (1 + s) Φ̂ + ε I,   ε = (1+s) ε₂ + (1+1/s) ρ² + 4u(1+s)‖P_c‖
//! ```
//!
//! reported as [`Inflation`] `{ relative: s, absolute: ε }`; both are of order `10⁻¹⁵` relative
//! in ordinary cases. `x_{k+1} ∈ 𝓔(x̂_{k+1}, P_{k+1})` then holds exactly, whenever
//! `x_k ∈ 𝓔(x̂_k, P_k)`, for the stored `x̂_k`, `P_k`.
//!
//! # Fallback
//!
//! The solver's result is used when its status is [`SolveStatus::Solved`] or
//! [`SolveStatus::AlmostSolved`]. Accepting "almost solved" is safe: the published shape is
//! certified from `(L, τ)` whatever their quality (any point of the simplex is feasible), so an
//! inexact solve can only cost optimality, never containment.
//!
//! If the solver fails (another status, an error, or the optional per-step time budget
//! exceeded) or its `(L, τ)` is invalid (not finite; `τ` outside the simplex by more than
//! `10⁻⁶` — a negative entry or `Στ > 1 + 10⁻⁶` —, which a solver that reports success must not
//! return; the closed-form gain for its `τ` failing), the filter uses the previous step's `τ` (or `(⅓, ⅓, ⅓)` if it is not usable) with the closed-form optimal gain
//! for that `τ` (or, if even that fails, `τ = (½, ½, 0)`, `L = 0`: pure prediction). The same
//! happens if a finite `(L, τ)` that passed these checks gives a certified shape, centre or
//! inflation that is not finite (an overflow): the certification is redone with the fallback
//! `τ` and its gain ([`FallbackReason::InvalidSolution`]). Only if that fails too does the step
//! return [`EstimatorError::NumericalFailure`], with the filter unchanged. A solver whose gain is
//! closed-form but that returns `τ₃ = 0` (after clamping) with a non-zero `L` keeps its `τ` with
//! `L = 0`, the closed-form gain for `τ₃ = 0`, also reported as
//! [`FallbackReason::InvalidSolution`]. Every point of the simplex is feasible, so containment
//! still holds; [`StepReport::fallback`] says why.
//!
//! # Inputs
//!
//! With [`InputModel::BoundedDisturbance`] the guarantee covers only inputs in the declared box:
//! an input outside it is refused with [`EstimatorError::InputOutsideBounds`] before anything
//! changes.

use std::time::{Duration, Instant};

use nalgebra::{DMatrix, DVector};

use lmi::SolveStatus;

use crate::dense;
use crate::error::EstimatorError;
use crate::model::{InitialData, StepModel, check_initial, check_model, check_spd, check_vec};
use crate::two_multiplier::{GainWork, TAU_FLOOR, TwoMultiplierSolver};

/// The data of one update problem (29), borrowed from the filter.
#[derive(Debug, Clone, Copy)]
pub struct UpdateProblem<'a> {
    /// `A_k` (`n × n`).
    pub a: &'a DMatrix<f64>,
    /// `C_{k+1}` (`m × n`).
    pub c: &'a DMatrix<f64>,
    /// Process-noise shape (the effective one for the Yang–Li reconstruction), `n × n`.
    pub q: &'a DMatrix<f64>,
    /// Measurement-noise shape, `m × m`.
    pub r: &'a DMatrix<f64>,
    /// Current shape `P_k`.
    pub p: &'a DMatrix<f64>,
    /// Current centre `x̂_k`.
    pub x_hat: &'a DVector<f64>,
    /// `X₁ = A P_k Aᵀ` (computed once by the filter).
    pub x1: &'a DMatrix<f64>,
}

/// What a solver returns: the gain and the multipliers, plus how the solve went.
#[derive(Debug, Clone)]
pub struct UpdateSolution {
    /// The gain `L` (`n × m`).
    pub l: DMatrix<f64>,
    /// `(τ₁, τ₂, τ₃)`.
    pub tau: [f64; 3],
    /// How the solve ended.
    pub status: SolveStatus,
    /// Iterations (Newton or interior-point).
    pub iterations: u32,
}

impl UpdateSolution {
    /// A solution buffer for `n` states and `m` outputs.
    pub fn new(n: usize, m: usize) -> Self {
        Self { l: DMatrix::zeros(n, m), tau: [1.0 / 3.0; 3], status: SolveStatus::Unsolved, iterations: 0 }
    }
}

/// A solver of the update problem (29).
pub trait UpdateSolver {
    /// Short name for reports.
    fn name(&self) -> &str;
    /// Allocates what solves of dimension `(n, m)` need (called by the filter's constructor).
    fn prepare(&mut self, n: usize, m: usize) -> Result<(), EstimatorError>;
    /// Solves (29), writing `L`, `τ`, status and iterations into `out`. `warm` is the previous
    /// step's `τ`. An `Err` makes the filter fall back (see the module documentation).
    fn solve(
        &mut self,
        problem: &UpdateProblem<'_>,
        warm: [f64; 3],
        out: &mut UpdateSolution,
    ) -> Result<(), EstimatorError>;

    /// Whether the returned `L` is the closed-form optimal gain (G1) for the returned `τ`
    /// (module [`two_multiplier`](crate::two_multiplier)). If `false` (the default), the filter
    /// keeps only `τ` and replaces `L` by the closed-form gain for the clamped `τ`: optimal for
    /// that `τ`, so never worse than the solver's `L`, whose error would otherwise be amplified
    /// by `1/τᵢ` when a multiplier is tiny. If `true`, the solver's `L` is certified as it is.
    fn gain_is_closed_form(&self) -> bool {
        false
    }
}

/// Why a step did not use the solver's `(L, τ)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FallbackReason {
    /// The solver ended with this status.
    Status(SolveStatus),
    /// The solver returned an error.
    SolverError,
    /// `(L, τ)` was not usable: not finite, `τ` outside the simplex by more than `10⁻⁶`, a
    /// non-zero closed-form `L` with `τ₃ = 0`, no closed-form gain for `τ`, or a certified set
    /// that is not finite (see the module documentation).
    InvalidSolution,
    /// The per-step time budget was exceeded.
    TimeBudget,
}

/// The certification inflation: `P_{k+1} = (1 + relative) Φ̂ + absolute · I`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Inflation {
    /// `s`, the relative factor from the centre's rounding error.
    pub relative: f64,
    /// `ε`, added to the diagonal.
    pub absolute: f64,
}

/// What one step did.
#[derive(Debug, Clone, PartialEq)]
pub struct StepReport {
    /// The multipliers used (after clamping onto the simplex).
    pub tau: [f64; 3],
    /// The solver's status.
    pub status: SolveStatus,
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
}

impl StepReport {
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
    /// `x̂_i − √P_ii`.
    pub lower: DVector<f64>,
    /// `x̂_i + √P_ii`.
    pub upper: DVector<f64>,
    /// What the step did (for the initial set: `τ = (⅓, ⅓, ⅓)`, status unsolved).
    pub report: StepReport,
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

    fn set_bounds(&mut self) {
        for i in 0..self.center.len() {
            let r = self.shape[(i, i)].max(0.0).sqrt();
            self.lower[i] = self.center[i] - r;
            self.upper[i] = self.center[i] + r;
        }
    }
}

/// How the input enters the filter.
#[derive(Debug, Clone, PartialEq)]
pub enum InputModel {
    /// `B u_k` in the predictor, as in (13).
    Predictor,
    /// The input is not used: `B u` over the box `[lower, upper]` is a bounded disturbance
    /// with centre `B u_mid` and outer ellipsoid `B 𝓔(0, W) Bᵀ`, `W = p · diag(h²)` (`h` the
    /// half-widths), added to the process noise by a trace-optimal outer Minkowski sum
    /// (the Yang–Li reconstruction (a), see [`crate::yang_li`]).
    ///
    /// Each step checks that `u` lies in the box and refuses it otherwise
    /// ([`EstimatorError::InputOutsideBounds`]). The centre and `W` are computed from the box
    /// with their rounding covered (`W` is enlarged by `8u` relative).
    BoundedDisturbance {
        /// Lower corner of the box.
        lower: DVector<f64>,
        /// Upper corner of the box.
        upper: DVector<f64>,
        /// Box centre `u_mid`.
        mid: DVector<f64>,
        /// Diagonal of `W`.
        w_diag: DVector<f64>,
    },
}

#[derive(Debug, Clone)]
struct Workspace {
    ap: DMatrix<f64>,
    x1: DMatrix<f64>,
    q_eff: DMatrix<f64>,
    bw: DMatrix<f64>,
    cert: CertWork,
    gain: GainWork,
}

/// Buffers of the certification.
#[derive(Debug, Clone)]
struct CertWork {
    z: DVector<f64>,
    k: DMatrix<f64>,
    t: DMatrix<f64>,
    kx: DMatrix<f64>,
    lr: DMatrix<f64>,
    p_new: DMatrix<f64>,
    x_new: DVector<f64>,
}

/// The improved set-membership filter, generic over the solver of (29).
#[derive(Debug, Clone)]
pub struct SetMembershipFilter<S: UpdateSolver = TwoMultiplierSolver> {
    n: usize,
    p: usize,
    m: usize,
    q: DMatrix<f64>,
    r: DMatrix<f64>,
    input: InputModel,
    solver: S,
    time_budget: Option<Duration>,
    est: SetEstimate,
    sol: UpdateSolution,
    ws: Workspace,
}

const U: f64 = f64::EPSILON / 2.0;

fn gamma(k: usize) -> f64 {
    let ku = k as f64 * U;
    ku / (1.0 - ku)
}

impl SetMembershipFilter<TwoMultiplierSolver> {
    /// The filter with the exact two-multiplier solver.
    pub fn two_multiplier(
        x0: DVector<f64>,
        p0: DMatrix<f64>,
        q: DMatrix<f64>,
        r: DMatrix<f64>,
        inputs: usize,
    ) -> Result<Self, EstimatorError> {
        Self::new(x0, p0, q, r, inputs, TwoMultiplierSolver::new())
    }
}

impl<S: UpdateSolver> SetMembershipFilter<S> {
    /// A filter with initial set `𝓔(x0, p0)`, noise shapes `q` (`n × n`) and `r` (`m × m`),
    /// `inputs` input components and the given solver.
    pub fn new(
        x0: DVector<f64>,
        p0: DMatrix<f64>,
        q: DMatrix<f64>,
        r: DMatrix<f64>,
        inputs: usize,
        mut solver: S,
    ) -> Result<Self, EstimatorError> {
        let InitialData { n, m, p0, q, r } = check_initial(&x0, &p0, &q, &r)?;
        solver.prepare(n, m)?;
        let mut est = SetEstimate {
            center: x0,
            shape: p0,
            lower: DVector::zeros(n),
            upper: DVector::zeros(n),
            report: StepReport {
                tau: [1.0 / 3.0; 3],
                status: SolveStatus::Unsolved,
                iterations: 0,
                fallback: None,
                inflation: Inflation::default(),
                solve_time: Duration::ZERO,
            },
        };
        est.set_bounds();
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
            est,
            sol: UpdateSolution::new(n, m),
            ws: Workspace {
                ap: nn(),
                x1: nn(),
                q_eff: nn(),
                bw: DMatrix::zeros(n, inputs),
                cert: CertWork {
                    z: DVector::zeros(n),
                    k: nn(),
                    t: nn(),
                    kx: nn(),
                    lr: DMatrix::zeros(n, m),
                    p_new: nn(),
                    x_new: DVector::zeros(n),
                },
                gain: GainWork::new(n, m),
            },
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
        Ok(self)
    }

    /// Per-step wall-clock budget for the solver; a step exceeding it falls back.
    pub fn set_time_budget(&mut self, budget: Option<Duration>) {
        self.time_budget = budget;
    }

    /// Replaces the process-noise shape `Q` (symmetric positive definite).
    pub fn set_process_noise(&mut self, q: &DMatrix<f64>) -> Result<(), EstimatorError> {
        self.q = check_spd("Q", q, self.n)?;
        Ok(())
    }

    /// Replaces the measurement-noise shape `R` (symmetric positive definite).
    pub fn set_measurement_noise(&mut self, r: &DMatrix<f64>) -> Result<(), EstimatorError> {
        self.r = check_spd("R", r, self.m)?;
        Ok(())
    }

    /// Number of states, inputs, outputs `(n, p, m)`.
    pub fn dims(&self) -> (usize, usize, usize) {
        (self.n, self.p, self.m)
    }

    /// How the input enters.
    pub fn input_model(&self) -> &InputModel {
        &self.input
    }

    /// The current set estimate.
    pub fn estimate(&self) -> &SetEstimate {
        &self.est
    }

    /// The solver.
    pub fn solver(&self) -> &S {
        &self.solver
    }

    /// The solver, mutably (for example to change its settings).
    pub fn solver_mut(&mut self) -> &mut S {
        &mut self.solver
    }

    /// One step: consumes `u_k` and the measurement `y_{k+1}`, returns the certified set
    /// estimate. On error the filter is unchanged. After the first step (which may set a
    /// solver up), this does not allocate with the two-multiplier solver or an SDP backend whose
    /// solve does not allocate.
    pub fn step(
        &mut self,
        model: &StepModel<'_>,
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) -> Result<&SetEstimate, EstimatorError> {
        check_model(model, self.n, self.p, self.m)?;
        check_vec("u", u, self.p)?;
        check_vec("y", y, self.m)?;
        if let InputModel::BoundedDisturbance { lower, upper, .. } = &self.input {
            check_in_box(u, lower, upper)?;
        }
        let Self { q, r, input, solver, time_budget, est, sol, ws, n, m, .. } = self;
        let (n, m) = (*n, *m);
        // X₁ = A P_k Aᵀ.
        dense::mul_nn(1.0, model.a, &est.shape, 0.0, &mut ws.ap);
        dense::mul_nt(1.0, &ws.ap, model.a, 0.0, &mut ws.x1);
        // Effective process noise and the input used by the predictor.
        let (q_used, u_used): (&DMatrix<f64>, &DVector<f64>) = match input {
            InputModel::Predictor => (q, u),
            InputModel::BoundedDisturbance { mid, w_diag, .. } => {
                effective_noise(q, model.b, w_diag, &mut ws.bw, &mut ws.q_eff);
                (&ws.q_eff, mid)
            }
        };
        let problem =
            UpdateProblem { a: model.a, c: model.c, q: q_used, r, p: &est.shape, x_hat: &est.center, x1: &ws.x1 };
        let warm = est.report.tau;
        let t0 = Instant::now();
        let result = solver.solve(&problem, warm, sol);
        let solve_time = t0.elapsed();
        let closed_form = solver.gain_is_closed_form();
        if sol.l.shape() != (n, m) {
            // A solver resized the gain buffer: restore it (allocates; never with our solvers).
            sol.l = DMatrix::zeros(n, m);
            sol.status = SolveStatus::NumericalTrouble;
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
        let mut inflation = certify(&mut ws.cert, model, &sol.l, tau, gain.x1, q_used, r, est, u_used, y);
        if inflation.is_none() && !fell_back {
            reason = Some(FallbackReason::InvalidSolution);
            tau = gain.fallback(warm, &mut sol.l);
            inflation = certify(&mut ws.cert, model, &sol.l, tau, gain.x1, q_used, r, est, u_used, y);
        }
        let Some(inflation) = inflation else {
            return Err(EstimatorError::NumericalFailure("the set estimate is not finite"));
        };
        std::mem::swap(&mut est.center, &mut ws.cert.x_new);
        std::mem::swap(&mut est.shape, &mut ws.cert.p_new);
        est.set_bounds();
        est.report =
            StepReport { tau, status: sol.status, iterations: sol.iterations, fallback: reason, inflation, solve_time };
        Ok(est)
    }
}

/// Refuses an input outside the declared box (allocation-free).
fn check_in_box(u: &DVector<f64>, lower: &DVector<f64>, upper: &DVector<f64>) -> Result<(), EstimatorError> {
    for i in 0..u.len() {
        let (value, lo, hi) = (u[i], lower[i], upper[i]);
        if !(lo <= value && value <= hi) {
            return Err(EstimatorError::InputOutsideBounds { index: i, value, lower: lo, upper: hi });
        }
    }
    Ok(())
}

/// The closed-form gain (G1) with its buffers and the data it needs, loaded on first use.
struct GainCtx<'a> {
    work: &'a mut GainWork,
    loaded: bool,
    x1: &'a DMatrix<f64>,
    q: &'a DMatrix<f64>,
    c: &'a DMatrix<f64>,
    r: &'a DMatrix<f64>,
}

impl GainCtx<'_> {
    /// Writes the closed-form gain for `tau` into `l`; `false` (and `l` untouched) if it fails.
    fn closed_form(&mut self, tau: [f64; 3], l: &mut DMatrix<f64>) -> bool {
        if !self.loaded {
            self.work.load(self.x1, self.q, self.c);
            self.loaded = true;
        }
        if self.work.gain(tau, self.c, self.r) && self.work.l.iter().all(|v| v.is_finite()) {
            l.copy_from(&self.work.l);
            true
        } else {
            false
        }
    }

    /// The fallback: the previous `τ` (or `(⅓, ⅓, ⅓)` if it is not usable) with its closed-form
    /// gain, or pure prediction `τ = (½, ½, 0)`, `L = 0` if that gain fails. Writes `L` into
    /// `l` and returns `τ` (clamped).
    fn fallback(&mut self, warm: [f64; 3], l: &mut DMatrix<f64>) -> [f64; 3] {
        let centre = clamp_tau([1.0; 3]).unwrap_or([0.25; 3]);
        let tau = clamp_tau(warm).filter(|t| t[2] > 0.0).unwrap_or(centre);
        if self.closed_form(tau, l) {
            tau
        } else {
            l.fill(0.0);
            clamp_tau([1.0, 1.0, 0.0]).unwrap_or([0.25, 0.25, 0.0])
        }
    }
}

/// Computes the certified `P_{k+1}` into `cw.p_new` and the centre into `cw.x_new` from
/// `(L, τ)` (module documentation, "Certification"). `None` if the shape, the centre or the
/// inflation is not finite. `τ` must come from [`clamp_tau`] and `L` must be 0 if `τ₃ = 0`.
fn certify(
    cw: &mut CertWork,
    model: &StepModel<'_>,
    l: &DMatrix<f64>,
    tau: [f64; 3],
    x1: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
    est: &SetEstimate,
    u: &DVector<f64>,
    y: &DVector<f64>,
) -> Option<Inflation> {
    let (n, m) = l.shape();
    dense::i_minus_lc(l, model.c, &mut cw.k);
    let fro = |a: &DMatrix<f64>| dense::fro(a.as_slice());
    let (na, nb, nc, nl, nk) = (fro(model.a), fro(model.b), fro(model.c), fro(l), fro(&cw.k));
    let (nx1, nq, nr, np) = (fro(x1), fro(q), fro(r), fro(&est.shape));
    let e_x = gamma(2 * n) * na * na * np;
    let e_k = gamma(m + 1) * ((n as f64).sqrt() + nl * nc);
    let kappa = nk + e_k;
    let lin = 2.0 * nk * e_k + e_k * e_k;
    // T₁ = K X₁ Kᵀ/τ₁.
    dense::mul_nn(1.0, &cw.k, x1, 0.0, &mut cw.kx);
    dense::mul_nt(1.0 / tau[0], &cw.kx, &cw.k, 0.0, &mut cw.p_new);
    let nt1 = fro(&cw.p_new);
    let mut err = (gamma(2 * n + 2) * nk * nk * nx1 + lin * nx1 + kappa * kappa * e_x) / tau[0];
    // T₂ = K Q Kᵀ/τ₂.
    dense::mul_nn(1.0, &cw.k, q, 0.0, &mut cw.kx);
    dense::mul_nt(1.0 / tau[1], &cw.kx, &cw.k, 0.0, &mut cw.t);
    let nt2 = fro(&cw.t);
    err += (gamma(2 * n + 2) * nk * nk * nq + lin * nq) / tau[1];
    dense::add_scaled(cw.p_new.as_mut_slice(), 1.0, cw.t.as_slice());
    let mut nt3 = 0.0;
    if tau[2] > 0.0 {
        // T₃ = L R Lᵀ/τ₃.
        dense::mul_nn(1.0, l, r, 0.0, &mut cw.lr);
        dense::mul_nt(1.0 / tau[2], &cw.lr, l, 0.0, &mut cw.t);
        nt3 = fro(&cw.t);
        err += gamma(2 * m + 2) * nl * nl * nr / tau[2];
        dense::add_scaled(cw.p_new.as_mut_slice(), 1.0, cw.t.as_slice());
    }
    err += gamma(4) * (nt1 + nt2 + nt3);
    dense::symmetrize(&mut cw.p_new);
    let nphi = fro(&cw.p_new);
    let eps2 = 2.0 * err + 4.0 * U * nphi;
    // Centre: z = A x̂ + B ū, x̂⁺ = K̂ z + L y.
    dense::gemv(1.0, model.a, &est.center, 0.0, &mut cw.z);
    dense::gemv(1.0, model.b, u, 1.0, &mut cw.z);
    dense::gemv(1.0, &cw.k, &cw.z, 0.0, &mut cw.x_new);
    dense::gemv(1.0, l, y, 1.0, &mut cw.x_new);
    let nxh = dense::fro(est.center.as_slice());
    let nu = dense::fro(u.as_slice());
    let nz = dense::fro(cw.z.as_slice());
    let ny = dense::fro(y.as_slice());
    let e_z = gamma(n + u.len()) * (na * nxh + nb * nu);
    let rho = 2.0 * (gamma(n + m + 1) * (nk * nz + nl * ny) + e_k * nz + kappa * e_z);
    let trc = cw.p_new.trace() + n as f64 * eps2;
    let s = if rho > 0.0 && trc > 0.0 { rho * (n as f64 / trc).sqrt() } else { 0.0 };
    let nc_pub = nphi + (n as f64).sqrt() * eps2;
    let extra = if s > 0.0 { (1.0 + 1.0 / s) * rho * rho } else { 0.0 };
    let absolute = (1.0 + s) * eps2 + extra + 4.0 * U * (1.0 + s) * nc_pub;
    if s > 0.0 {
        cw.p_new.iter_mut().for_each(|v| *v *= 1.0 + s);
    }
    for i in 0..n {
        cw.p_new[(i, i)] += absolute;
    }
    let finite = cw.p_new.iter().chain(cw.x_new.iter()).all(|v| v.is_finite());
    (finite && absolute.is_finite() && s.is_finite()).then_some(Inflation { relative: s, absolute })
}

/// How far outside the simplex a solver's `τ` may be (rounding, interior-point feasibility
/// tolerances) before it is treated as invalid rather than clamped.
const SIMPLEX_TOLERANCE: f64 = 1e-6;

/// `τ₃` below this is treated as 0: it is below the rounding unit `ε·TAU_FLOOR` of the smallest
/// allowed `τ₁`, `τ₂`, so it does not register in `Στ`, and `1/τ₃` would risk overflow.
pub(crate) const TAU3_ZERO: f64 = f64::EPSILON * TAU_FLOOR;

/// Whether a solver's `τ` is on the simplex up to [`SIMPLEX_TOLERANCE`]: no entry below
/// `−10⁻⁶`, `Στ ≤ 1 + 10⁻⁶` (false for non-finite entries or an overflowing sum).
fn near_simplex(tau: [f64; 3]) -> bool {
    tau.iter().all(|v| *v >= -SIMPLEX_TOLERANCE) && tau[0] + tau[1] + tau[2] <= 1.0 + SIMPLEX_TOLERANCE
}

/// Clamps `τ` onto the feasible simplex (see the module documentation): negatives to 0,
/// rescaled to `Στ = 1` (largest entry first, so nothing overflows), `τ₃ <` [`TAU3_ZERO`] to 0,
/// then `τ₁, τ₂ ≥` [`TAU_FLOOR`] with the excess taken off the largest entry. Guarantees
/// `τ₁, τ₂ ≥ TAU_FLOOR`, `τ₃ = 0` or `τ₃ ≥ TAU3_ZERO`, and `fl(fl(τ₁ + τ₂) + τ₃) ≤ 1 − 2ε`, which
/// puts the exact sum of the three stored numbers below 1 (its rounding error is at most
/// `γ₂ ≈ 2.2·10⁻¹⁶`). `None` if an entry is not finite or none is positive.
pub(crate) fn clamp_tau(tau: [f64; 3]) -> Option<[f64; 3]> {
    const LIMIT: f64 = 1.0 - 2.0 * f64::EPSILON;
    if tau.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let mut t = tau.map(|v| v.max(0.0));
    let top = t[0].max(t[1]).max(t[2]);
    if top <= 0.0 {
        return None;
    }
    // Renormalise: divide by the largest entry (now all in [0, 1], the largest exactly 1), then
    // by the sum (in [1, 3]).
    t = t.map(|v| v / top);
    let sum = t[0] + t[1] + t[2];
    t = t.map(|v| v / sum);
    if t[2] < TAU3_ZERO {
        t[2] = 0.0;
    }
    t[0] = t[0].max(TAU_FLOOR);
    t[1] = t[1].max(TAU_FLOOR);
    // The largest entry is at least ⅓ − 2·TAU_FLOOR: taking the excess (at most 2·TAU_FLOOR plus
    // rounding) off it keeps it far above every floor.
    let big = if t[0] >= t[1] && t[0] >= t[2] {
        0
    } else if t[1] >= t[2] {
        1
    } else {
        2
    };
    for _ in 0..8 {
        let s = t[0] + t[1] + t[2];
        if s <= LIMIT {
            return Some(t);
        }
        t[big] -= (s - LIMIT).max(t[big] * f64::EPSILON);
    }
    None
}

/// `Q_eff = (1 + 1/s) Q + (1 + s) B W Bᵀ`, `s = √(tr Q / tr BWBᵀ)` (trace-optimal outer bound of
/// `𝓔(0, Q) ⊕ B 𝓔(0, W)`, valid even when `B W Bᵀ` is singular since `Q` is positive
/// definite), with a bound on its rounding error added to the diagonal so that the stored
/// `Q_eff` dominates the exact one (for the computed `s`; any `s > 0` gives a valid bound).
///
/// Rounding (`u = 2⁻⁵³`): entrywise, `|fl(Q_eff) − Q_eff| ≤ γ_{p+6} (1+s) |B|W|B|ᵀ +
/// γ₆ (1+1/s) |Q|` (for `BWBᵀ`: `B·W` one rounding, the `p`-term products `γ_{p+1}`, the
/// coefficient `1 + s` and its product two, the sum and the symmetrisation two; for `Q`: the
/// coefficient `1 + 1/s` two, its product, the sum and the symmetrisation three, plus one of
/// slack). Its spectral norm is at most `γ_{p+6}(1+s) ‖|B|W|B|ᵀ‖₂ + γ₆(1+1/s) ‖Q‖_F`, and
/// `‖|B|W|B|ᵀ‖₂ ≤ tr(|B|W|B|ᵀ) = Σⱼ wⱼ‖bⱼ‖² = tr(BWBᵀ)` (positive semidefinite), computed
/// directly from the columns of `B` and enlarged by `1 + γ_{n+p+1}` for its own rounding
/// (`‖Q‖_F` by `1 + γ_{n²+2}`). Adding `ε` to a diagonal entry `d` rounds too; `ε` is enlarged
/// by `16u` relative and by `4u max|dᵢ|`, which covers it.
fn effective_noise(
    q: &DMatrix<f64>,
    b: &DMatrix<f64>,
    w_diag: &DVector<f64>,
    bw: &mut DMatrix<f64>,
    out: &mut DMatrix<f64>,
) {
    let (n, p) = b.shape();
    let mut tb = 0.0;
    for j in 0..p {
        let col = &b.as_slice()[j * n..(j + 1) * n];
        tb += w_diag[j] * dense::dot(col, col);
        for i in 0..n {
            bw[(i, j)] = b[(i, j)] * w_diag[j];
        }
    }
    if tb.is_nan() || tb <= 0.0 {
        // B W Bᵀ = 0 (exactly: every term of the trace is a square times wⱼ ≥ 0).
        out.copy_from(q);
        return;
    }
    dense::mul_nt(1.0, bw, b, 0.0, out);
    let s = (q.trace() / tb).sqrt();
    out.iter_mut().for_each(|v| *v *= 1.0 + s);
    dense::add_scaled(out.as_mut_slice(), 1.0 + 1.0 / s, q.as_slice());
    dense::symmetrize(out);
    let tb_up = tb * (1.0 + gamma(n + p + 1));
    let nq_up = dense::fro(q.as_slice()) * (1.0 + gamma(n * n + 2));
    let err = gamma(p + 6) * (1.0 + s) * tb_up + gamma(6) * (1.0 + 1.0 / s) * nq_up;
    let max_d = (0..n).map(|i| out[(i, i)].abs()).fold(0.0, f64::max);
    let eps = err * (1.0 + 16.0 * U) + 4.0 * U * max_d;
    for i in 0..n {
        out[(i, i)] += eps;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamp_tau_lands_on_the_simplex_with_the_floors() {
        let f = TAU_FLOOR;
        let sub = 1e-320;
        let inputs = [
            [1e308, 1e308, 1e308],
            [0.5, 0.5, sub],
            [0.0, 0.0, 1e300],
            [1.0 / 3.0; 3],
            [0.5, 0.5, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [f, f, 1.0 - 2.0 * f],
            [1e-13, 1e-13, 1.0],
            [-1.0, 0.3, 0.7],
            [0.2, 0.3, 0.5],
            [2e-7, 3e-7, 5e-7],
            [sub, sub, sub],
            [sub, 0.0, 0.0],
            [0.6, 0.6, 1e-29],
            [0.6, 0.6, 1e-27],
            [f64::MAX, f64::MAX, 0.0],
            [0.999_999_999_999, 1e-15, 1e-15],
        ];
        for tau in inputs {
            let t = clamp_tau(tau).unwrap_or_else(|| panic!("{tau:?}"));
            assert!(t[0] >= f && t[1] >= f, "{tau:?} → {t:?}");
            assert!(t[2] == 0.0 || t[2] >= TAU3_ZERO, "{tau:?} → {t:?}");
            // fl sum ≤ 1 − 2ε: the exact sum is below 1 (its rounding error is ≤ γ₂).
            assert!(t[0] + t[1] + t[2] <= 1.0 - 2.0 * f64::EPSILON, "{tau:?} → {t:?}");
            // The renormalised point, up to the floors.
            assert!(t[0] + t[1] + t[2] >= 1.0 - 4.0 * f, "{tau:?} → {t:?}");
        }
        // Proportions are kept when no floor binds.
        let t = clamp_tau([2e-7, 3e-7, 5e-7]).unwrap();
        for (got, want) in t.iter().zip([0.2, 0.3, 0.5]) {
            assert!((got - want).abs() < 1e-15, "{t:?}");
        }
        // τ₃ below ε·TAU_FLOOR is zero; just above it is kept.
        assert_eq!(clamp_tau([0.5, 0.5, sub]).unwrap()[2], 0.0);
        assert_eq!(clamp_tau([0.6, 0.6, 1e-29]).unwrap()[2], 0.0);
        assert!(clamp_tau([0.6, 0.6, 1e-27]).unwrap()[2] > 0.0);
        // Nothing usable.
        for tau in [[0.0; 3], [-1.0, -2.0, 0.0], [f64::NAN, 0.5, 0.5], [f64::INFINITY, 0.0, 0.0]] {
            assert_eq!(clamp_tau(tau), None, "{tau:?}");
        }
    }

    #[test]
    fn near_simplex_flags_results_far_outside() {
        assert!(near_simplex([0.3, 0.3, 0.4]));
        assert!(near_simplex([0.3, 0.3, 0.4 + 1e-7]));
        assert!(near_simplex([1e-5; 3]));
        assert!(!near_simplex([1e308; 3]));
        assert!(!near_simplex([0.0, 0.0, 1e300]));
        assert!(!near_simplex([0.5, 0.6, 0.0]));
        assert!(!near_simplex([-1e-3, 0.5, 0.5]));
        assert!(!near_simplex([f64::NAN, 0.5, 0.5]));
    }

    /// A deterministic pseudo-random number in [−1, 1).
    fn lcg(state: &mut u64) -> f64 {
        *state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (*state >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }

    #[test]
    fn effective_noise_dominates_the_exact_sum() {
        // Q_eff − [(1 + 1/s) Q + (1 + s) B W Bᵀ] ⪰ 0 against nalgebra's evaluation, and the
        // inflation stays at the rounding level.
        let mut state = 42;
        for (n, p) in [(1, 1), (2, 3), (4, 8), (8, 8), (8, 2), (3, 1)] {
            for scale in [1e-6, 1.0, 1e6] {
                let g = DMatrix::from_fn(n, n, |_, _| lcg(&mut state));
                let q = &g * g.transpose() + DMatrix::identity(n, n) * 0.1;
                let b = DMatrix::from_fn(n, p, |_, _| lcg(&mut state) * scale);
                let w = DVector::from_fn(p, |_, _| 1.0 + lcg(&mut state));
                let mut bw = DMatrix::zeros(n, p);
                let mut out = DMatrix::zeros(n, n);
                effective_noise(&q, &b, &w, &mut bw, &mut out);
                let bwb = &b * DMatrix::from_diagonal(&w) * b.transpose();
                let s = (q.trace() / bwb.trace()).sqrt();
                let exact = &q * (1.0 + 1.0 / s) + &bwb * (1.0 + s);
                let diff = &out - &exact;
                let lmin = diff.clone().symmetric_eigenvalues().min();
                let scale_ref = exact.trace();
                assert!(lmin >= 0.0, "n = {n}, p = {p}: λmin = {lmin:e} (trace {scale_ref:e})");
                assert!(diff.norm() <= 1e-12 * scale_ref, "n = {n}, p = {p}: {:e}", diff.norm() / scale_ref);
            }
        }
    }
}
