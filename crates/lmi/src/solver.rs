//! The backend trait, solver settings and solve outcomes.

use std::time::Duration;

use nalgebra::DMatrix;

use crate::certificate::RejectedCertificate;
use crate::error::LmiError;
use crate::problem::{Block, SdpProblem};

/// How a solve ended. Infeasibility is an outcome, not an error.
///
/// "Primal" is the problem in `x`, "dual" the problem in `Y` (see [`crate::problem`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum SolveStatus {
    /// Not solved yet (a freshly allocated [`SdpSolution`]).
    Unsolved,
    /// Optimal within the requested tolerances.
    Solved,
    /// Optimal within the relaxed ("reduced") tolerances only.
    AlmostSolved,
    /// No `x` makes `Σ xᵢFᵢ − F₀ ⪰ 0`; `dual` holds a certificate `Y`.
    PrimalInfeasible,
    /// The dual equalities have no solution `Y ⪰ 0`; `x` holds a certificate (an improving ray).
    DualInfeasible,
    /// Primal infeasibility detected within relaxed tolerances only.
    AlmostPrimalInfeasible,
    /// Dual infeasibility detected within relaxed tolerances only.
    AlmostDualInfeasible,
    /// The iteration limit was reached before convergence.
    IterationLimit,
    /// The time limit was reached before convergence.
    TimeLimit,
    /// The method stalled or broke down numerically (for example a factorisation failed, or a
    /// third-party solver panicked and the backend contained the panic).
    NumericalTrouble,
}

impl SolveStatus {
    /// `Solved` or `AlmostSolved`.
    pub fn is_optimal(self) -> bool {
        matches!(self, SolveStatus::Solved | SolveStatus::AlmostSolved)
    }

    /// A short lower-case label for tables.
    pub fn label(self) -> &'static str {
        match self {
            SolveStatus::Unsolved => "unsolved",
            SolveStatus::Solved => "solved",
            SolveStatus::AlmostSolved => "almost solved",
            SolveStatus::PrimalInfeasible => "primal infeasible",
            SolveStatus::DualInfeasible => "dual infeasible",
            SolveStatus::AlmostPrimalInfeasible => "almost primal infeasible",
            SolveStatus::AlmostDualInfeasible => "almost dual infeasible",
            SolveStatus::IterationLimit => "iteration limit",
            SolveStatus::TimeLimit => "time limit",
            SolveStatus::NumericalTrouble => "numerical trouble",
        }
    }
}

impl std::fmt::Display for SolveStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.label())
    }
}

/// Where a solve started (see [`SolverSettings::warm_start`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum SolveStart {
    /// The backend's default starting point.
    #[default]
    Cold,
    /// The previous solve's solution, blended with the default starting point.
    Warm,
    /// A warm start that did not end `Solved` or with an infeasibility certificate, repeated
    /// from the default starting point with what was left of the iteration budget and the time
    /// limit; `iterations` counts both attempts (at most `max_iterations` in all).
    ColdAfterWarm,
}

/// The result of a solve. Allocated once per structure ([`SdpSolution::new`]) and overwritten by
/// every solve, so that repeated solves need not allocate.
#[derive(Debug, Clone)]
pub struct SdpSolution {
    /// How the solve ended.
    pub status: SolveStatus,
    /// Primal decision vector `x` (a certificate ray when `status` is dual infeasible).
    pub x: Vec<f64>,
    /// Dual matrix `Y`, one dense symmetric matrix per block; diagonal for nonnegative blocks
    /// (a certificate when `status` is primal infeasible).
    pub dual: Vec<DMatrix<f64>>,
    /// `cᵀx`.
    pub primal_objective: f64,
    /// `tr(F₀ Y)`.
    pub dual_objective: f64,
    /// Interior-point iterations performed (by both attempts after [`SolveStart::ColdAfterWarm`]).
    pub iterations: u32,
    /// Where the solve started.
    pub start: SolveStart,
    /// Relative primal residual reported by the backend (infeasibility of `x`).
    pub primal_residual: f64,
    /// Relative dual residual reported by the backend (`‖tr(Fᵢ Y) − cᵢ‖` scaled).
    pub dual_residual: f64,
    /// Wall-clock time of the numeric solve (not of the setup).
    pub solve_time: Duration,
    /// An infeasibility the backend claimed during this solve whose certificate failed the
    /// independent check on the caller's (unscaled) problem ([`crate::certificate`]); the status
    /// is then [`SolveStatus::NumericalTrouble`] (or the outcome of a later attempt within the
    /// same solve that is not optimal either). `None` after an optimal solve or an accepted
    /// certificate.
    pub rejected_certificate: Option<RejectedCertificate>,
}

impl SdpSolution {
    /// Allocates a solution sized for `problem`.
    pub fn new(problem: &SdpProblem) -> Self {
        Self {
            status: SolveStatus::Unsolved,
            x: vec![0.0; problem.num_vars()],
            dual: problem.blocks().iter().map(|b| DMatrix::zeros(b.size(), b.size())).collect(),
            primal_objective: f64::NAN,
            dual_objective: f64::NAN,
            iterations: 0,
            start: SolveStart::Cold,
            primal_residual: f64::NAN,
            dual_residual: f64::NAN,
            solve_time: Duration::ZERO,
            rejected_certificate: None,
        }
    }

    /// Bytes [`SdpSolution::new`] allocates for `problem` (`x` and a dense `n × n` matrix per
    /// block), saturating; backends count it against [`SolverSettings::memory_limit_bytes`].
    pub fn required_bytes(problem: &SdpProblem) -> u64 {
        let dual: u128 = problem.blocks().iter().map(|b| (b.size() as u128) * (b.size() as u128)).sum();
        crate::error::saturate_bytes(8 * (dual + problem.num_vars() as u128))
    }

    /// Whether this solution is sized for `problem`.
    pub fn fits(&self, problem: &SdpProblem) -> bool {
        self.x.len() == problem.num_vars()
            && self.dual.len() == problem.blocks().len()
            && self
                .dual
                .iter()
                .zip(problem.blocks())
                .all(|(y, b): (&DMatrix<f64>, &Block)| y.nrows() == b.size() && y.ncols() == b.size())
    }

    /// Relative duality gap `|cᵀx − tr(F₀Y)| / (1 + |cᵀx| + |tr(F₀Y)|)`.
    pub fn relative_gap(&self) -> f64 {
        (self.primal_objective - self.dual_objective).abs()
            / (1.0 + self.primal_objective.abs() + self.dual_objective.abs())
    }
}

/// Settings shared by all backends. Build with [`SolverSettings::builder`] (validated) or use
/// [`SolverSettings::default`] (tolerances `1e-8`, as Clarabel's defaults; relaxed by
/// `reduced_tol_factor` for the `Almost…` outcomes; equilibration on; memory limit
/// [`DEFAULT_MEMORY_LIMIT`]).
///
/// # Equilibration
///
/// With `equilibrate` (the default) every backend solves a scaled copy of the problem and maps
/// the answer back. Three factors, each a power of two (so the scaling is exact), are computed
/// from the values of each solve: `d` for every `Fᵢ` (`i ≥ 1`), `s₀` for `F₀` and `s_c` for the
/// objective, applied as `Fᵢ → d Fᵢ`, `F₀ → s₀ F₀`, `cᵢ → s_c d cᵢ`. Each brings the geometric
/// mean of the magnitudes of its nonzero data to about 1; a factor within `2^±8` of 1 is not
/// applied, so that moderately scaled problems (such as SDPLIB's and the filter's LMIs) are
/// solved exactly as given. The answer maps back as `x = d x'/s₀`, `Y = Y'/s_c` and objectives
/// divided by `s₀ s_c`; infeasibility certificates keep their normalisation (`Y = s₀ Y'`,
/// `x = s_c d x'`). The tolerances, and hence the status, apply to the scaled problem, so a
/// problem and a rescaling of its objective, of its constraint matrices or of all its data are
/// judged alike; the residuals a backend reports are those of the scaled problem. (One factor
/// per variable or per block is deliberately not used: the relative residuals are normalised by
/// `‖x‖` and `‖Y‖`, and such factors would loosen the accuracy of well-scaled problems in their
/// own units.)
#[derive(Debug, Clone, PartialEq)]
pub struct SolverSettings {
    /// Maximum number of interior-point iterations.
    pub max_iterations: u32,
    /// Relative duality-gap tolerance for `Solved`.
    pub tol_gap_rel: f64,
    /// Absolute duality-gap tolerance for `Solved`.
    pub tol_gap_abs: f64,
    /// Relative primal and dual feasibility tolerance for `Solved`.
    pub tol_feas: f64,
    /// Tolerance of infeasibility certificates.
    pub tol_infeas: f64,
    /// Factor by which the tolerances are relaxed for the `Almost…` outcomes.
    pub reduced_tol_factor: f64,
    /// Optional wall-clock limit for one solve.
    pub time_limit: Option<Duration>,
    /// Print iteration logs to standard error.
    pub verbose: bool,
    /// Scale the problem before solving (exact power-of-two factors for `c`, the `Fᵢ` and `F₀`;
    /// see [Equilibration](SolverSettings#equilibration)). On by default; turning it off judges
    /// the tolerances in the units of the data, so badly scaled problems can end with wrong
    /// statuses.
    pub equilibrate: bool,
    /// Largest amount of memory, in bytes, a backend may allocate for one problem (its setup
    /// workspace and the solution). `setup` computes the requirement first and returns
    /// [`LmiError::MemoryLimit`] instead of allocating beyond it.
    pub memory_limit_bytes: u64,
    /// Start each solve from the previous solve's solution (same structure, same setup) instead
    /// of the default point, for sequences of nearby problems such as a filter's SDP at
    /// consecutive steps. Off by default. `faer-ipm` blends the two as Skajaa, Andersen and Ye
    /// do for the homogeneous embedding (`docs/sdp.md` §3.7); a warm solve that ends neither
    /// `Solved` nor with an infeasibility certificate is repeated cold within the same
    /// `max_iterations` and `time_limit` (when nothing is left, the warm outcome stands), so the
    /// outcome is judged by the same tests either way. Backends that cannot warm start
    /// (Clarabel) solve cold; [`SdpSolution::start`] tells which start was used.
    pub warm_start: bool,
}

/// Default of [`SolverSettings::memory_limit_bytes`]: 2 GiB.
pub const DEFAULT_MEMORY_LIMIT: u64 = 2 << 30;

impl Default for SolverSettings {
    fn default() -> Self {
        Self {
            max_iterations: 100,
            tol_gap_rel: 1e-8,
            tol_gap_abs: 1e-8,
            tol_feas: 1e-8,
            tol_infeas: 1e-8,
            reduced_tol_factor: 1e3,
            time_limit: None,
            verbose: false,
            equilibrate: true,
            memory_limit_bytes: DEFAULT_MEMORY_LIMIT,
            warm_start: false,
        }
    }
}

impl SolverSettings {
    /// A builder starting from the defaults.
    pub fn builder() -> SolverSettingsBuilder {
        SolverSettingsBuilder { settings: Self::default() }
    }

    /// Checks every field; called by each backend's constructor.
    pub fn validate(&self) -> Result<(), LmiError> {
        let positive = |name: &'static str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(LmiError::InvalidSetting { name, reason: format!("must be finite and positive, got {v}") })
            }
        };
        if self.max_iterations == 0 {
            return Err(LmiError::InvalidSetting { name: "max_iterations", reason: "must be at least 1".into() });
        }
        positive("tol_gap_rel", self.tol_gap_rel)?;
        positive("tol_gap_abs", self.tol_gap_abs)?;
        positive("tol_feas", self.tol_feas)?;
        positive("tol_infeas", self.tol_infeas)?;
        if !(self.reduced_tol_factor.is_finite() && self.reduced_tol_factor >= 1.0) {
            return Err(LmiError::InvalidSetting {
                name: "reduced_tol_factor",
                reason: format!("must be finite and at least 1, got {}", self.reduced_tol_factor),
            });
        }
        if let Some(t) = self.time_limit {
            if t.is_zero() {
                return Err(LmiError::InvalidSetting { name: "time_limit", reason: "must be positive".into() });
            }
        }
        if self.memory_limit_bytes == 0 {
            return Err(LmiError::InvalidSetting { name: "memory_limit_bytes", reason: "must be positive".into() });
        }
        Ok(())
    }
}

/// Validated construction of [`SolverSettings`].
#[derive(Debug, Clone)]
pub struct SolverSettingsBuilder {
    settings: SolverSettings,
}

impl SolverSettingsBuilder {
    /// Maximum number of iterations (at least 1).
    pub fn max_iterations(mut self, n: u32) -> Self {
        self.settings.max_iterations = n;
        self
    }
    /// Sets the gap (relative and absolute) and feasibility tolerances at once.
    pub fn tolerance(mut self, tol: f64) -> Self {
        self.settings.tol_gap_rel = tol;
        self.settings.tol_gap_abs = tol;
        self.settings.tol_feas = tol;
        self
    }
    /// Infeasibility-certificate tolerance.
    pub fn tol_infeas(mut self, tol: f64) -> Self {
        self.settings.tol_infeas = tol;
        self
    }
    /// Wall-clock limit of one solve.
    pub fn time_limit(mut self, limit: Duration) -> Self {
        self.settings.time_limit = Some(limit);
        self
    }
    /// Iteration logs on standard error.
    pub fn verbose(mut self, verbose: bool) -> Self {
        self.settings.verbose = verbose;
        self
    }
    /// Whether to equilibrate the problem before solving (default `true`).
    pub fn equilibrate(mut self, equilibrate: bool) -> Self {
        self.settings.equilibrate = equilibrate;
        self
    }
    /// Largest memory, in bytes, a backend may allocate for one problem (default
    /// [`DEFAULT_MEMORY_LIMIT`]; must be positive).
    pub fn memory_limit_bytes(mut self, bytes: u64) -> Self {
        self.settings.memory_limit_bytes = bytes;
        self
    }
    /// Whether to warm-start each solve from the previous one (default `false`; see
    /// [`SolverSettings::warm_start`]).
    pub fn warm_start(mut self, warm_start: bool) -> Self {
        self.settings.warm_start = warm_start;
        self
    }
    /// Validates and returns the settings.
    pub fn build(self) -> Result<SolverSettings, LmiError> {
        self.settings.validate()?;
        Ok(self.settings)
    }
}

/// An SDP solver: set up once for a structure, then solve many problems of that structure.
///
/// Implementations hold their settings and every buffer a solve needs. `setup` analyses the
/// structure (sizes, which entries of which `Fᵢ` are nonzero); `solve` reads only values. A
/// problem that is infeasible, or a solve that stalls, ends with an [`SolveStatus`]; `Err` is
/// only for bad input (a structure that differs from the one set up, NaN data), for a problem
/// whose setup would need more memory than [`SolverSettings::memory_limit_bytes`]
/// ([`LmiError::MemoryLimit`], checked before allocating), and for a failure of the backend's
/// own setup. Backends scale the problem before solving (see "Equilibration" in
/// [`SolverSettings`]) and never let a panic of a third-party solver unwind into the caller.
/// Backends are `Send`, so that an estimator holding one can move to another thread (a worker, a
/// Python call that releases the GIL).
pub trait SdpBackend: Send {
    /// Short name used in tables and on the command line.
    fn name(&self) -> &'static str;

    /// Analyses `problem`'s structure and allocates what solves need.
    fn setup(&mut self, problem: &SdpProblem) -> Result<(), LmiError>;

    /// Solves `problem`, which must have the structure given to [`SdpBackend::setup`], writing
    /// into `solution` (sized by [`SdpSolution::new`]).
    fn solve(&mut self, problem: &SdpProblem, solution: &mut SdpSolution) -> Result<(), LmiError>;

    /// Convenience: `setup`, then `solve` into a fresh solution.
    fn setup_and_solve(&mut self, problem: &SdpProblem) -> Result<SdpSolution, LmiError> {
        self.setup(problem)?;
        let mut solution = SdpSolution::new(problem);
        self.solve(problem, &mut solution)?;
        Ok(solution)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settings_are_validated_with_named_errors() {
        assert!(SolverSettings::builder().build().is_ok());
        let err = SolverSettings::builder().max_iterations(0).build().unwrap_err().to_string();
        assert!(err.contains("max_iterations"), "{err}");
        let err = SolverSettings::builder().tolerance(f64::NAN).build().unwrap_err().to_string();
        assert!(err.contains("tol_gap_rel") && err.contains("NaN"), "{err}");
        let err = SolverSettings::builder().tol_infeas(-1.0).build().unwrap_err().to_string();
        assert!(err.contains("tol_infeas"), "{err}");
        let err = SolverSettings::builder().time_limit(Duration::ZERO).build().unwrap_err().to_string();
        assert!(err.contains("time_limit"), "{err}");
        let s = SolverSettings { reduced_tol_factor: 0.5, ..SolverSettings::default() };
        assert!(s.validate().unwrap_err().to_string().contains("reduced_tol_factor"));
        let err = SolverSettings::builder().memory_limit_bytes(0).build().unwrap_err().to_string();
        assert!(err.contains("memory_limit_bytes"), "{err}");
    }
}
