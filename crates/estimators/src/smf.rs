//! The improved set-membership filter of the paper, eqs (13)–(29), with certified containment.
//!
//! # One step
//!
//! Given `x_k ∈ 𝓔(x̂_k, P_k)`, `w_k ∈ 𝓔(0, Q)`, `v_{k+1} ∈ 𝓔(0, R)`:
//!
//! 1. `X₁ = A P_k Aᵀ`; an [`UpdateSolver`] solves (29) and returns `(L, τ)` (its `P` is not
//!    used);
//! 2. certification (below) recomputes `P_{k+1}` from `(L, τ)` and inflates it;
//! 3. the centre is (13) with the optimal free column zero:
//!    `x̂_{k+1} = (I − L C)(A x̂_k + B u_k) + L y_{k+1}`.
//!
//! # Certification
//!
//! Whatever solver produced `(L, τ)`, `τ` is clamped onto the simplex (`τ₁, τ₂ ≥` [`TAU_FLOOR`],
//! `τ₃ ≥ 0`, divided by `Στ` if `Στ > 1`; if `τ₃` ends at 0 the measurement is not used and `L`
//! is set to 0, the only gain (27) allows then) and, with
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
//! If the solver fails (status other than solved / almost solved, an error, a non-finite or
//! invalid `(L, τ)`, or the optional per-step time budget exceeded), the filter uses the
//! previous step's `τ` (or `(⅓, ⅓, ⅓)` if it is not usable) with the closed-form optimal gain
//! for that `τ` (or, if even that fails, `τ = (½, ½, 0)`, `L = 0`: pure prediction). Every point
//! of the simplex is feasible, so containment still holds; [`StepReport::fallback`] says why.

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
}

/// Why a step did not use the solver's `(L, τ)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FallbackReason {
    /// The solver ended with this status.
    Status(SolveStatus),
    /// The solver returned an error.
    SolverError,
    /// `L` or `τ` was not finite.
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
    /// `Some(reason)` if the step fell back to a feasible `τ` with its closed-form gain.
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
    BoundedDisturbance {
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
    z: DVector<f64>,
    k: DMatrix<f64>,
    t: DMatrix<f64>,
    kx: DMatrix<f64>,
    lr: DMatrix<f64>,
    p_new: DMatrix<f64>,
    x_new: DVector<f64>,
    gain: GainWork,
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
                z: DVector::zeros(n),
                k: nn(),
                t: nn(),
                kx: nn(),
                lr: DMatrix::zeros(n, m),
                p_new: nn(),
                x_new: DVector::zeros(n),
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
            let h = 0.5 * (hi - lo);
            if lo > hi || !h.is_finite() {
                return Err(EstimatorError::InvalidInputBounds { index: i, lower: lo, upper: hi });
            }
            mid[i] = 0.5 * (lo + hi);
            // The box lies in 𝓔(0, p·diag(h²)): Σ dᵢ²/(p hᵢ²) ≤ Σ 1/p = 1.
            w_diag[i] = self.p as f64 * h * h;
        }
        self.input = InputModel::BoundedDisturbance { mid, w_diag };
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
    /// estimate. On error the filter is unchanged. With the two-multiplier solver this does
    /// not allocate.
    pub fn step(
        &mut self,
        model: &StepModel<'_>,
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) -> Result<&SetEstimate, EstimatorError> {
        check_model(model, self.n, self.p, self.m)?;
        check_vec("u", u, self.p)?;
        check_vec("y", y, self.m)?;
        let Self { q, r, input, solver, time_budget, est, sol, ws, n, m, .. } = self;
        let (n, m) = (*n, *m);
        // X₁ = A P_k Aᵀ.
        dense::mul_nn(1.0, model.a, &est.shape, 0.0, &mut ws.ap);
        dense::mul_nt(1.0, &ws.ap, model.a, 0.0, &mut ws.x1);
        // Effective process noise and the input used by the predictor.
        let (q_used, u_used): (&DMatrix<f64>, &DVector<f64>) = match input {
            InputModel::Predictor => (q, u),
            InputModel::BoundedDisturbance { mid, w_diag } => {
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
        if sol.l.shape() != (n, m) {
            // A solver resized the gain buffer: restore it (allocates; never with our solvers).
            sol.l = DMatrix::zeros(n, m);
            sol.status = SolveStatus::NumericalTrouble;
        }
        // Decide whether the solver's (L, τ) is usable.
        let mut fallback = match result {
            Err(_) => Some(FallbackReason::SolverError),
            Ok(()) if !sol.status.is_optimal() => Some(FallbackReason::Status(sol.status)),
            Ok(()) => None,
        };
        if fallback.is_none() && time_budget.is_some_and(|b| solve_time >= b) {
            fallback = Some(FallbackReason::TimeBudget);
        }
        let mut tau = [0.0; 3];
        if fallback.is_none() {
            match clamp_tau(sol.tau) {
                Some(t) if sol.l.iter().all(|v| v.is_finite()) => {
                    tau = t;
                    if t[2] == 0.0 {
                        // τ₃ = 0: the measurement is not used, which (27) allows only with L = 0.
                        sol.l.fill(0.0);
                    }
                }
                _ => fallback = Some(FallbackReason::InvalidSolution),
            }
        }
        if fallback.is_some() {
            // A feasible τ with its closed-form gain.
            tau = clamp_tau(warm).filter(|t| t[2] > 0.0).unwrap_or([1.0 / 3.0; 3]);
            ws.gain.load(&ws.x1, q_used, model.c);
            if ws.gain.gain(tau, model.c, r) {
                sol.l.copy_from(&ws.gain.l);
            } else {
                tau = [0.5, 0.5, 0.0];
                sol.l.fill(0.0);
            }
        }
        // Certified P_{k+1} and centre.
        let l = &sol.l;
        dense::i_minus_lc(l, model.c, &mut ws.k);
        let fro = |a: &DMatrix<f64>| dense::fro(a.as_slice());
        let (na, nb, nc, nl, nk) = (fro(model.a), fro(model.b), fro(model.c), fro(l), fro(&ws.k));
        let (nx1, nq, nr, np) = (fro(&ws.x1), fro(q_used), fro(r), fro(&est.shape));
        let e_x = gamma(2 * n) * na * na * np;
        let e_k = gamma(m + 1) * ((n as f64).sqrt() + nl * nc);
        let kappa = nk + e_k;
        let lin = 2.0 * nk * e_k + e_k * e_k;
        // T₁ = K X₁ Kᵀ/τ₁.
        dense::mul_nn(1.0, &ws.k, &ws.x1, 0.0, &mut ws.kx);
        dense::mul_nt(1.0 / tau[0], &ws.kx, &ws.k, 0.0, &mut ws.p_new);
        let nt1 = fro(&ws.p_new);
        let mut err = (gamma(2 * n + 2) * nk * nk * nx1 + lin * nx1 + kappa * kappa * e_x) / tau[0];
        // T₂ = K Q Kᵀ/τ₂.
        dense::mul_nn(1.0, &ws.k, q_used, 0.0, &mut ws.kx);
        dense::mul_nt(1.0 / tau[1], &ws.kx, &ws.k, 0.0, &mut ws.t);
        let nt2 = fro(&ws.t);
        err += (gamma(2 * n + 2) * nk * nk * nq + lin * nq) / tau[1];
        dense::add_scaled(ws.p_new.as_mut_slice(), 1.0, ws.t.as_slice());
        let mut nt3 = 0.0;
        if tau[2] > 0.0 {
            // T₃ = L R Lᵀ/τ₃.
            dense::mul_nn(1.0, l, r, 0.0, &mut ws.lr);
            dense::mul_nt(1.0 / tau[2], &ws.lr, l, 0.0, &mut ws.t);
            nt3 = fro(&ws.t);
            err += gamma(2 * m + 2) * nl * nl * nr / tau[2];
            dense::add_scaled(ws.p_new.as_mut_slice(), 1.0, ws.t.as_slice());
        }
        err += gamma(4) * (nt1 + nt2 + nt3);
        dense::symmetrize(&mut ws.p_new);
        let nphi = fro(&ws.p_new);
        let eps2 = 2.0 * err + 4.0 * U * nphi;
        // Centre: z = A x̂ + B ū, x̂⁺ = K̂ z + L y.
        dense::gemv(1.0, model.a, &est.center, 0.0, &mut ws.z);
        dense::gemv(1.0, model.b, u_used, 1.0, &mut ws.z);
        dense::gemv(1.0, &ws.k, &ws.z, 0.0, &mut ws.x_new);
        dense::gemv(1.0, l, y, 1.0, &mut ws.x_new);
        let nxh = dense::fro(est.center.as_slice());
        let nu = dense::fro(u_used.as_slice());
        let nz = dense::fro(ws.z.as_slice());
        let ny = dense::fro(y.as_slice());
        let e_z = gamma(n + u_used.len()) * (na * nxh + nb * nu);
        let rho = 2.0 * (gamma(n + m + 1) * (nk * nz + nl * ny) + e_k * nz + kappa * e_z);
        let trc = ws.p_new.trace() + n as f64 * eps2;
        let s = if rho > 0.0 && trc > 0.0 { rho * (n as f64 / trc).sqrt() } else { 0.0 };
        let nc_pub = nphi + (n as f64).sqrt() * eps2;
        let extra = if s > 0.0 { (1.0 + 1.0 / s) * rho * rho } else { 0.0 };
        let absolute = (1.0 + s) * eps2 + extra + 4.0 * U * (1.0 + s) * nc_pub;
        if s > 0.0 {
            ws.p_new.iter_mut().for_each(|v| *v *= 1.0 + s);
        }
        for i in 0..n {
            ws.p_new[(i, i)] += absolute;
        }
        if ws.p_new.iter().chain(ws.x_new.iter()).any(|v| !v.is_finite()) || !absolute.is_finite() {
            return Err(EstimatorError::NumericalFailure("the set estimate is not finite"));
        }
        std::mem::swap(&mut est.center, &mut ws.x_new);
        std::mem::swap(&mut est.shape, &mut ws.p_new);
        est.set_bounds();
        est.report = StepReport {
            tau,
            status: sol.status,
            iterations: sol.iterations,
            fallback,
            inflation: Inflation { relative: s, absolute },
            solve_time,
        };
        Ok(est)
    }
}

/// Clamps `τ` onto the feasible simplex: `τ₁, τ₂ ≥ f`, `τ₃ ≥ 0`, `Στ ≤ 1`. `None` if not finite.
pub(crate) fn clamp_tau(tau: [f64; 3]) -> Option<[f64; 3]> {
    if tau.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let mut t = [tau[0].max(TAU_FLOOR), tau[1].max(TAU_FLOOR), tau[2].max(0.0)];
    let s = t[0] + t[1] + t[2];
    if s > 1.0 {
        for v in &mut t {
            *v /= s;
        }
        // Make sure the rounded sum does not exceed one.
        while t[0] + t[1] + t[2] > 1.0 {
            for v in &mut t {
                *v *= 1.0 - 2.0 * f64::EPSILON;
            }
        }
    }
    Some(t)
}

/// `Q_eff = (1 + 1/s) Q + (1 + s) B W Bᵀ`, `s = √(tr Q / tr BWBᵀ)` (trace-optimal outer bound of
/// `𝓔(0, Q) ⊕ B 𝓔(0, W)`, valid even when `B W Bᵀ` is singular since `Q` is positive
/// definite), inflated on the diagonal by twice a bound on its rounding error.
fn effective_noise(
    q: &DMatrix<f64>,
    b: &DMatrix<f64>,
    w_diag: &DVector<f64>,
    bw: &mut DMatrix<f64>,
    out: &mut DMatrix<f64>,
) {
    let (n, p) = b.shape();
    for j in 0..p {
        for i in 0..n {
            bw[(i, j)] = b[(i, j)] * w_diag[j];
        }
    }
    dense::mul_nt(1.0, bw, b, 0.0, out);
    let tq = q.trace();
    let tb = out.trace();
    if tb.is_nan() || tb <= 0.0 {
        out.copy_from(q);
        return;
    }
    let s = (tq / tb).sqrt();
    let nbwb = dense::fro(out.as_slice());
    out.iter_mut().for_each(|v| *v *= 1.0 + s);
    dense::add_scaled(out.as_mut_slice(), 1.0 + 1.0 / s, q.as_slice());
    let err = gamma(p + 4) * ((1.0 + s) * nbwb + (1.0 + 1.0 / s) * dense::fro(q.as_slice()));
    dense::symmetrize(out);
    for i in 0..n {
        out[(i, i)] += 2.0 * err;
    }
}
