//! `faer-ipm`: a primal–dual interior-point SDP solver in pure Rust, written for problems with
//! a few small dense PSD blocks, some nonnegative scalars and up to a few hundred variables
//! (the set-membership filter's LMI: one block of order 16–29 and 30–100 variables).
//!
//! # Algorithm
//!
//! The problem is [`SdpProblem`] in SDPA form, `min cᵀx` s.t. `X = A(x) − F₀ ⪰ 0` with
//! `A(x) = Σ xᵢFᵢ`, and its dual `max tr(F₀Y)` s.t. `A*(Y) = c` (`A*(Y)ᵢ = tr(FᵢY)`), `Y ⪰ 0`.
//! The solver follows the *homogeneous self-dual embedding* in its simplified form (Xu, Hung
//! and Ye; as in ECOS, CVXOPT's `conelp` and Clarabel): with `τ, κ ≥ 0` it drives to zero the
//! residuals
//!
//! ```text
//! r_x = −A*(Y) + c τ,     r_z = A(x) − X − F₀ τ,     r_τ = −cᵀx + tr(F₀Y) − κ
//! ```
//!
//! together with the complementarity `⟨X, Y⟩ + τκ`. All residuals shrink at the rate of the
//! complementarity, so the iteration ends in one of three ways:
//!
//! * `τ` stays positive: `(x/τ, X/τ, Y/τ)` is optimal (residuals and gap below tolerance);
//! * `tr(F₀Y) > 0` and `‖A*(Y)‖ ≤ tol_infeas · tr(F₀Y)`: `Y / tr(F₀Y)` certifies that (P) is
//!   infeasible ([`SolveStatus::PrimalInfeasible`](crate::SolveStatus::PrimalInfeasible));
//! * `cᵀx < 0` and `‖A(x) − X‖ ≤ tol_infeas · |cᵀx|`: `x / |cᵀx|` is an improving ray, (D) is
//!   infeasible ([`SolveStatus::DualInfeasible`](crate::SolveStatus::DualInfeasible)).
//!
//! **Search direction.** Nesterov–Todd. Per dense block, with Cholesky factors `X = L₁L₁ᵀ`,
//! `Y = L₂L₂ᵀ` and the eigendecomposition `(L₂ᵀL₁)(L₂ᵀL₁)ᵀ = UΛ²Uᵀ`, the matrix `T = L₂UΛ^{-1/2}`
//! gives `Y = TΛTᵀ`, `X = T⁻ᵀΛT⁻¹`, and the NT scaling point `D = TTᵀ` (`DXD = Y`); `Λ` is the
//! scaled iterate `λ`. Nonnegative blocks use the diagonal analogue (`λ = √(xy)`, `D = √(y/x)`).
//! The linearised complementarity is `λ∘(Δx̃ + Δỹ) = r_s` in the scaled space
//! (`Δx̃ = TᵀΔXT`, `Δỹ = T⁻¹ΔYT⁻ᵀ`, `u∘v = (uv + vu)/2`); it is solved entrywise because `Λ` is
//! diagonal. Eliminating `ΔX`, `ΔY` and `Δκ` leaves the Schur complement system
//! `M Δx = h + (b − c)Δτ` with `Mᵢⱼ = tr(Fᵢ D Fⱼ D)`, `bᵢ = tr(Fᵢ D F₀ D)`, and a scalar equation
//! for `Δτ`; each solve costs two triangular solves with the Cholesky factor of `M` (one of them,
//! for `q = M⁻¹(b − c)`, is shared by predictor and corrector).
//!
//! **Schur matrix.** The sparsity of the `Fᵢ` is analysed once, in [`SdpBackend::setup`]: for
//! every block and every `j`, one of four ways to get `tr(Fᵢ D Fⱼ D)` for all `i ≥ j` is chosen
//! by a flop estimate: the pairwise formula `Σₖₗ vₖwₗ (D_bc D_ad + D_bd D_ac)` over the entries
//! `(a,b)` of `Fᵢ` and `(c,d)` of `Fⱼ` (very sparse `Fⱼ`, short tails); a *low-rank* form, in
//! which every `Fᵢ` is a sum over groups of entries sharing one index `c`, `e_c wᵀ + w e_cᵀ`
//! with a sparse `w`, and with `y = Dw` per group (computed once per iteration)
//! `tr(Fᵢ D Fⱼ D) = 2 Σ_g Σ_h (y_g[d_h] y_h[c_g] + (w_g·y_h) D_{c_g d_h})` (a variable that fills
//! part of one row, like the gain `L` of the filter LMI, is a single group); `G = DFⱼD` built by
//! rank-two updates with the columns of `D` (sparse `Fⱼ`; vectorises); or `G = DFⱼD` by two
//! matrix products (dense `Fⱼ`) — the last two followed by `⟨Fᵢ, G⟩` over the entries of `Fᵢ`.
//! When the estimate says so for the whole block, the low-rank form is evaluated for all pairs
//! of groups at once instead: `y_h` for every group, `Z = WᵀDW` row by row (contiguous, so it
//! vectorises), then one pass over the pairs. The low-rank forms are used for blocks of order 8
//! and more only (below, every strategy is cheap, and the nearly ill-posed SDPLIB `hinf` problems
//! are sensitive to the rounding of `M`). The filter LMI, built with its structural zeros kept,
//! has many entries whose value is zero (most of `F₀`, part of every `L` column): each solve
//! first lists the entries and groups with a nonzero value (into storage reserved at setup), and
//! `A(x)`, `A*(G)` and the grouped assembly run over those only.
//! `F₀` is treated as matrix `0`, so `b` and `tr(F₀DF₀D)` come out of the same assembly. The
//! Cholesky factorisation is retried with a diagonal shift of `10⁻¹³` and `10⁻¹⁰` times the
//! largest diagonal before giving up.
//!
//! **Accuracy near the end.** The Schur matrix becomes ill-conditioned as `μ → 0`. The corrector
//! direction is checked against the two equations it must satisfy (`−A*(ΔY) + cΔτ = d_x` and
//! the `τ` row); when they are off by more than a tiny fraction of their right-hand side, one step
//! of iterative refinement on the full Newton system follows. When the first equation is off by
//! more than `10⁻³` of its right-hand side, the solve switches for the rest of the run to a
//! *precision mode*: the factor of `M = RᵀR` is taken from a Householder QR (faer) of the scaled
//! constraint matrix `[svec(TᵀFᵢT)]ᵢ`, whose condition number is the square root of `M`'s, and the
//! step is recomputed. The `τ` equation's coefficient `tr(F₀DF₀D) − (b + c)ᵀM⁻¹(b − c)` is
//! evaluated as `‖Tᵀ(F₀ − A(q))T‖²` (no cancellation). The best iterate seen (by the largest of
//! the scaled residuals and gap) is kept, and used when the method stalls.
//!
//! **Predictor–corrector.** Mehrotra: an affine-scaling step (`σ = 0`) gives the step `αₐ`;
//! then `σ = (1 − αₐ)³` and the combined step with the second-order term `Δx̃ₐ∘Δỹₐ`. The step
//! is `α = min(1, 0.99 α_max)`, where `α_max` keeps `Λ + αΔx̃`, `Λ + αΔỹ`, `τ` and `κ`
//! nonnegative (the same step in all variables, as the embedding requires). For a dense block
//! this is the largest `α` with `I + αΛ^{-1/2}ΔΛ^{-1/2} ⪰ 0`: one Cholesky test of the full
//! step first (usually enough near the end); otherwise a Householder tridiagonalisation and a
//! bisection on Sturm counts for the smallest eigenvalue (relative accuracy `10⁻⁴`, rounded
//! towards the shorter step). The predictor's step only sets `σ`, so it uses two Cholesky-test
//! halvings instead (step known to within 1/4).
//!
//! **Starting point.** As in SDPT3: `x = 0`, `X = ξI`, `Y = ηI` with
//! `ξ = max(10, √ν, ‖F₀‖, maxᵢ‖Fᵢ‖)`, `η = max(10, √ν, ν maxᵢ (1 + |cᵢ|)/(1 + ‖Fᵢ‖))` and
//! `τ = κ = 1` (`ν` = the sum of the block orders).
//!
//! **Warm start** ([`SolverSettings::warm_start`], off by default; `docs/sdp.md` §3.7). For a
//! sequence of nearby problems of one structure, such as a filter's SDP at consecutive steps:
//! the previous solution `(x_w, X_w, Y_w)` (divided by its `τ`) blended with a multiple of the
//! identity, `X = λX_w + (1 − λ)(tr X_w/ν) I`, likewise `Y`, `x = λx_w`, `τ = 1`,
//! `κ = ⟨X, Y⟩/ν`, `λ = 0.99` (Skajaa, Andersen and Ye's warm start of the homogeneous
//! embedding). The identity part keeps the start away from the boundary of the cone, where a
//! near-optimal point of a neighbouring problem sits. A warm solve that ends neither `Solved` nor
//! with an infeasibility certificate is repeated from the default start with the rest of the
//! iteration budget and of the time limit (with nothing left, the warm outcome stands), so that
//! the outcome is either one the cold method's tests accept or the cold method's own. A solution
//! is stored when a solve ends `Solved` or `AlmostSolved`, and used only by a solve of the same
//! setup whose equilibration factors are those it was stored with.
//! On the carrier's filter steps the method takes about 4 iterations instead of 11–13.
//!
//! **Small dense kernels.** The whole iteration runs inside one `pulp` dispatch (faer's SIMD
//! layer; its kernels are inlined into it), so the hand-written loops are compiled for the best
//! instruction set of the machine (AVX2/FMA on x86-64) instead of the baseline target's SSE2.
//! Products use faer's `matmul` with `Par::Seq` (a hand-written loop was measured slower); Cholesky
//! factorisations use a plain left-looking loop up to order 48 (faster than a blocked
//! implementation at these sizes; above order 20 it subtracts four columns at a time) and
//! faer's `cholesky_in_place` above, with scratch from a
//! [`MemStack`] lent from one [`MemBuffer`]; the QR of precision mode is faer's `qr_in_place`.
//! The symmetric eigendecomposition of the scaling (one per dense block and iteration) is an
//! in-place Householder tridiagonalisation + implicit QL (`tred2`/`tql2`): faer's general
//! eigensolver costs about 15 µs at order 16, this one about 5 µs with vectors.
//!
//! On the filter LMI for `(n, m) = (4, 3)` as first stated (one block of order 16, 29 variables,
//! 12 iterations), the earlier method (faer's triangular solves for the Schur system, three
//! predictor halvings) took about 320 µs per solve on the development machine, roughly 27 µs per
//! iteration: the NT scaling (two Cholesky factorisations, the eigendecomposition, six products)
//! about a quarter, the step lengths about a quarter, the Schur matrix and its factorisation
//! about a fifth, the rest the right-hand sides and directions. Plain-loop Schur solves and two
//! halvings took a little off that; the main gain came from the whitened statement of the filter
//! LMI (fewer iterations). The measurements of both methods are in `docs/sdp.md` §3.5.
//!
//! **HKM direction** ([`FaerIpm::set_direction`], [`SearchDirection::Hkm`]; `docs/sdp.md` §3.6).
//! Instead of the NT scaling, the Helmberg–Kojima–Monteiro direction linearises `YX = σμI` and
//! symmetrises `ΔY = σμX⁻¹ − Y − sym(Y ΔX X⁻¹)`: the Schur matrix is `tr(Fᵢ Y Fⱼ X⁻¹)` and every
//! quantity comes from the Cholesky factors of `X` and `Y` (no eigendecomposition); step lengths
//! are Cholesky tests of `X + αΔX`, `Y + αΔY` by bisection. A breakdown (or the need for
//! precision mode) switches the rest of the solve to NT. NT stays the default.
//!
//! # Allocation
//!
//! [`SdpBackend::setup`] copies the problem (to check the structure of later problems), builds
//! per block the entry lists of every `Fᵢ` and the Schur strategy, and allocates every buffer:
//! per dense block about 30 matrices of its order, the `(m+1)²` Schur matrix, its factor, the
//! `(Σ n(n+1)/2) × m` matrix of precision mode, the vectors of length `m`, and the faer scratch
//! ([`StackReq`] → [`MemBuffer`], the largest of the Cholesky and QR requirements).
//! [`SdpBackend::solve`] allocates nothing (it writes into the caller's [`SdpSolution`]),
//! except when it returns an error, whose message is a `String`; the scaling of the problem
//! (see "Equilibration" in [`SolverSettings`]) is three factors computed per solve and applied
//! while the values are copied into the workspace, the answer mapped back in place.
//!
//! Before allocating anything, `setup` computes from the problem's sizes what all this (and the
//! caller's [`SdpSolution`]) will take (dominated by `8 (m+1)²` for the Schur matrix, `8 m²` for
//! its factor, `8 m Σ n(n+1)/2` for precision mode, about `200 n²` per dense block and
//! `40 (m + 2)` per block for the per-variable bookkeeping) and returns
//! [`LmiError::MemoryLimit`] if it exceeds [`SolverSettings::memory_limit_bytes`]; the buffers
//! of the low-rank Schur strategy, whose size depends on the analysis, are checked the same way
//! once the analysis has sized them.
//!
//! # Statuses
//!
//! * `Solved`: relative primal residual `‖A(x) − F₀ − X‖_F / max(1, ‖F₀‖_F + ‖x‖ + ‖X‖_F)` and
//!   relative dual residual `‖A*(Y) − c‖ / max(1, ‖c‖ + ‖x‖ + ‖Y‖_F)` (the normalisation of
//!   Clarabel) both `≤ tol_feas`, and the gap `|cᵀx − tr(F₀Y)|` is `≤ tol_gap_abs` or the
//!   relative gap [`SdpSolution::relative_gap`] `|cᵀx − tr(F₀Y)| / (1 + |cᵀx| + |tr(F₀Y)|)` is
//!   `≤ tol_gap_rel`. These are checked on the point that is returned
//!   (`x/τ`, `X/τ`, `Y/τ`) of the scaled problem (see "Equilibration" in [`SolverSettings`]),
//!   and reported in `primal_residual` / `dual_residual`; `x`, `Y` and the objectives are mapped
//!   back to the caller's problem.
//! * `PrimalInfeasible` / `DualInfeasible`: the certificate tests above with `tol_infeas`. The
//!   certificate is returned normalised (`tr(F₀Y) = 1` in `dual`, resp. `cᵀx = −1` in `x`); the
//!   other part of the solution is zero (every entry stays finite), both objectives are `+∞` (primal infeasible: the dual is
//!   unbounded) resp. `−∞`, and the residual field of the certificate holds its residual.
//!   The certificate is then checked independently on the caller's unscaled problem
//!   ([`crate::certificate`]); if it fails, the status is `NumericalTrouble`, the objectives
//!   NaN, and [`SdpSolution::rejected_certificate`] holds the claim and the reason.
//! * When the iteration limit, the time limit or a numerical breakdown (an iterate that is no
//!   longer numerically positive definite, a failed factorisation, a step below `10⁻¹⁰`, or no
//!   improvement of the best iterate for 5 iterations once it meets the relaxed tolerances, or
//!   for 20 iterations in any case) stops the method, the best iterate is restored and tested
//!   again with every tolerance multiplied by `reduced_tol_factor`: `AlmostSolved`,
//!   `AlmostPrimalInfeasible` or `AlmostDualInfeasible` if it passes, otherwise
//!   `IterationLimit`, `TimeLimit` or `NumericalTrouble`, with that iterate in the solution.

mod dense;
pub(crate) mod eig;
mod engine;
mod workspace;

use std::time::Instant;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};

use crate::certificate::{self, CertificateChecker};
use crate::error::{LmiError, saturate_bytes};
use crate::problem::SdpProblem;
use crate::scaling::Equilibration;
use crate::solver::{SdpBackend, SdpSolution, SolverSettings};

use workspace::Workspace;

/// [`Workspace::run`] as a pulp operation, so that it is compiled for each instruction set.
struct Run<'a> {
    ws: &'a mut Workspace,
    settings: &'a SolverSettings,
    start: Instant,
    solution: &'a mut SdpSolution,
    stack: &'a mut MemStack,
}

impl faer::traits::pulp::WithSimd for Run<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: faer::traits::pulp::Simd>(self, _simd: S) {
        self.ws.run(self.settings, self.start, self.solution, self.stack);
    }
}

/// Search direction of [`FaerIpm`] on the dense (semidefinite) blocks; nonnegative blocks are
/// the same under both.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum SearchDirection {
    /// Nesterov–Todd (`docs/sdp.md` §3.2): symmetric scaling from an eigendecomposition per
    /// block. The default.
    #[default]
    NesterovTodd,
    /// Helmberg–Kojima–Monteiro (XZ) direction (`docs/sdp.md` §3.6): Schur matrix
    /// `tr(Fᵢ Y Fⱼ X⁻¹)` and step lengths from Cholesky factors only, no eigendecomposition.
    /// Falls back to NT for the rest of a solve if it breaks down or needs precision mode.
    Hkm,
}

/// The pure-Rust interior-point backend (`"faer-ipm"`); see the [module documentation](self).
pub struct FaerIpm {
    settings: SolverSettings,
    ws: Option<Workspace>,
    buf: Option<MemBuffer>,
    direction: SearchDirection,
    /// The scaling of the solve whose solution is stored for a warm start.
    warm_scale: Option<Equilibration>,
    /// Scratch of the independent check of infeasibility certificates.
    checker: Option<CertificateChecker>,
}

impl std::fmt::Debug for FaerIpm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FaerIpm")
            .field("settings", &self.settings)
            .field("set_up", &self.ws.is_some())
            .finish_non_exhaustive()
    }
}

impl FaerIpm {
    /// A backend with validated `settings`; call [`SdpBackend::setup`] before solving.
    pub fn new(settings: SolverSettings) -> Result<Self, LmiError> {
        settings.validate()?;
        Ok(Self {
            settings,
            ws: None,
            buf: None,
            direction: SearchDirection::NesterovTodd,
            warm_scale: None,
            checker: None,
        })
    }

    /// The settings in use.
    pub fn settings(&self) -> &SolverSettings {
        &self.settings
    }

    /// Replaces the settings (validated; on error, unchanged). The setup and a solution stored
    /// for a warm start are kept, so that tolerances or limits can change between solves.
    pub fn set_settings(&mut self, settings: SolverSettings) -> Result<(), LmiError> {
        settings.validate()?;
        self.settings = settings;
        Ok(())
    }

    /// Selects the search direction (NT by default).
    pub fn set_direction(&mut self, direction: SearchDirection) {
        self.direction = direction;
    }

    /// The selected search direction ([`FaerIpm::set_direction`]).
    pub fn direction(&self) -> SearchDirection {
        self.direction
    }
}

impl SdpBackend for FaerIpm {
    fn name(&self) -> &'static str {
        "faer-ipm"
    }

    fn setup(&mut self, problem: &SdpProblem) -> Result<(), LmiError> {
        // Release the previous structure's buffers first: a failed setup leaves the backend not
        // set up, and the limit is not shared with buffers about to be dropped.
        self.ws = None;
        self.buf = None;
        self.warm_scale = None;
        self.checker = None;
        let limit = self.settings.memory_limit_bytes;
        let too_large = |required: u128| LmiError::MemoryLimit {
            backend: "faer-ipm",
            required_bytes: saturate_bytes(required),
            limit_bytes: limit,
        };
        // Sizes first (nothing allocated), then faer's scratch (only computed for moderate sizes),
        // then the grouping-dependent buffers inside `Workspace::new`.
        let mut required = workspace::base_bytes(problem)
            + u128::from(SdpSolution::required_bytes(problem))
            + u128::from(CertificateChecker::required_bytes(problem));
        if required > u128::from(limit) {
            return Err(too_large(required));
        }
        required += workspace::workspace_tail_bytes(problem);
        if required > u128::from(limit) {
            return Err(too_large(required));
        }
        let ws = Workspace::new(problem, u128::from(limit) - required).map_err(|extra| too_large(required + extra))?;
        let req: StackReq = workspace::scratch(problem);
        self.buf = Some(MemBuffer::new(req));
        self.ws = Some(ws);
        self.checker = Some(CertificateChecker::new(problem));
        Ok(())
    }

    fn solve(&mut self, problem: &SdpProblem, solution: &mut SdpSolution) -> Result<(), LmiError> {
        let start = Instant::now();
        let (Some(ws), Some(buf), Some(checker)) = (self.ws.as_mut(), self.buf.as_mut(), self.checker.as_mut()) else {
            return Err(LmiError::StructureMismatch("faer-ipm: solve called before setup".into()));
        };
        if !ws.structure.same_structure(problem) {
            return Err(LmiError::StructureMismatch(
                "faer-ipm: the problem's sizes, blocks or entry positions differ from those given to setup".into(),
            ));
        }
        if !solution.fits(problem) {
            return Err(LmiError::DimensionMismatch {
                what: "solution (not sized by SdpSolution::new for this problem)",
                expected: problem.num_vars(),
                found: solution.x.len(),
            });
        }
        let settings = &self.settings;
        let scale = Equilibration::compute(problem, settings.equilibrate);
        ws.load_values(problem, &scale);
        ws.hkm = self.direction == SearchDirection::Hkm;
        // The stored solution is in the previous solve's scaled units: usable only if this solve
        // is scaled alike (the factors are powers of two and usually all 1).
        ws.warm_wanted = settings.warm_start && self.warm_scale == Some(scale);
        // The whole iteration is compiled for the best instruction set available (AVX2/FMA or
        // AVX-512 on x86-64), so that the hand-written kernels vectorise as well as faer's.
        faer::traits::pulp::Arch::new().dispatch(Run { ws, settings, start, solution, stack: MemStack::new(buf) });
        self.warm_scale = ws.has_warm.then_some(scale);
        // Back to the caller's problem (statuses were judged on the equilibrated one).
        scale.unscale(solution);
        let f = scale.objective_factor();
        solution.primal_objective *= f;
        solution.dual_objective *= f;
        // An infeasibility is reported only with a certificate that holds for the caller's data.
        solution.rejected_certificate = None;
        certificate::vet(checker, problem, settings, solution);
        solution.solve_time = start.elapsed();
        Ok(())
    }
}
