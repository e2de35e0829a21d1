//! The update problem (29) as a solver sees it, the solver trait, and the solver's status.

use nalgebra::{DMatrix, DVector};

use crate::error::EstimatorError;

/// How a solve of (29) ended: the estimators' own status, mapped from an SDP backend's status
/// where one is used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum UpdateStatus {
    /// Not solved yet (the initial set, or a fresh buffer).
    Unsolved,
    /// Optimal within the solver's tolerances.
    Solved,
    /// Optimal within relaxed tolerances only.
    AlmostSolved,
    /// The solver declared (29) infeasible (impossible for (29), whose simplex is always
    /// feasible: a sign of numerical trouble in the solver).
    Infeasible,
    /// The iteration limit was reached.
    IterationLimit,
    /// The solver's time limit was reached.
    TimeLimit,
    /// The solver broke down numerically.
    NumericalTrouble,
}

impl UpdateStatus {
    /// `Solved` or `AlmostSolved`.
    #[must_use]
    pub fn is_optimal(self) -> bool {
        matches!(self, UpdateStatus::Solved | UpdateStatus::AlmostSolved)
    }

    /// A short lower-case label for tables.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            UpdateStatus::Unsolved => "unsolved",
            UpdateStatus::Solved => "solved",
            UpdateStatus::AlmostSolved => "almost solved",
            UpdateStatus::Infeasible => "infeasible",
            UpdateStatus::IterationLimit => "iteration limit",
            UpdateStatus::TimeLimit => "time limit",
            UpdateStatus::NumericalTrouble => "numerical trouble",
        }
    }
}

impl From<lmi::SolveStatus> for UpdateStatus {
    fn from(s: lmi::SolveStatus) -> Self {
        use lmi::SolveStatus as S;
        match s {
            S::Unsolved => UpdateStatus::Unsolved,
            S::Solved => UpdateStatus::Solved,
            S::AlmostSolved => UpdateStatus::AlmostSolved,
            S::PrimalInfeasible | S::DualInfeasible | S::AlmostPrimalInfeasible | S::AlmostDualInfeasible => {
                UpdateStatus::Infeasible
            }
            S::IterationLimit => UpdateStatus::IterationLimit,
            S::TimeLimit => UpdateStatus::TimeLimit,
            _ => UpdateStatus::NumericalTrouble,
        }
    }
}

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
    pub status: UpdateStatus,
    /// Iterations (Newton or interior-point).
    pub iterations: u32,
}

impl UpdateSolution {
    /// A solution buffer for `n` states and `m` outputs.
    pub fn new(n: usize, m: usize) -> Self {
        Self { l: DMatrix::zeros(n, m), tau: [1.0 / 3.0; 3], status: UpdateStatus::Unsolved, iterations: 0 }
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
    /// (module [`two_multiplier`](super::two_multiplier)). If `false` (the default), the filter
    /// keeps only `τ` and replaces `L` by the closed-form gain for the clamped `τ`: optimal for
    /// that `τ`, so never worse than the solver's `L`, whose error would otherwise be amplified
    /// by `1/τᵢ` when a multiplier is tiny. If `true`, the solver's `L` is certified as it is.
    fn gain_is_closed_form(&self) -> bool {
        false
    }

    /// A new solver of the same kind, to be prepared for fewer outputs (a filter's partial
    /// steps); `None` (the default) when this solver cannot make one, and the filter then refuses
    /// partial steps.
    fn for_fewer_outputs(&self) -> Option<Self>
    where
        Self: Sized,
    {
        None
    }
}
