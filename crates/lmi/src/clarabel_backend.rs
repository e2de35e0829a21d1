//! The Clarabel backend (cargo feature `clarabel`; links a system BLAS/LAPACK).
//!
//! Mapping: Clarabel solves `min qᵀx  s.t.  A x + s = b, s ∈ K`. With `s = svec(X)`,
//! `X = Σ xᵢFᵢ − F₀`, the columns of `A` are `−svec(Fᵢ)` and `b = −svec(F₀)`; PSD blocks become
//! `PSDTriangleConeT` (see [`crate::svec`]), nonnegative blocks `NonnegativeConeT`. Clarabel's
//! primal is therefore this crate's primal (P), and its dual variable `z = svec(Y)` gives the
//! dual matrix `Y` of (D): `Aᵀz + q = 0 ⇔ tr(FᵢY) = cᵢ`, and `−bᵀz = tr(F₀Y)`.
//!
//! [`SdpBackend::setup`] builds the sparse pattern of `A` once, with presolve, chordal
//! decomposition and zero-dropping off so that later solves only overwrite values
//! (`update_A`, `update_b`, `update_q`). Clarabel allocates inside its own solve.

use std::time::Instant;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, PSDTriangleConeT, SolverStatus,
    SupportedConeT,
};

use crate::error::LmiError;
use crate::problem::{Block, SdpProblem};
use crate::solver::{SdpBackend, SdpSolution, SolveStatus, SolverSettings};
use crate::svec::{smat_into, svec_index, svec_len, svec_scale};

const NAME: &str = "clarabel";

/// Where an entry of the problem lands in Clarabel's data.
#[derive(Debug, Clone, Copy)]
enum Slot {
    /// Index into `b` and the factor (−1 or −√2).
    B(usize, f64),
    /// Index into `A`'s nonzero values and the factor.
    A(usize, f64),
}

/// Clarabel as an [`SdpBackend`].
pub struct ClarabelBackend {
    settings: SolverSettings,
    state: Option<State>,
}

struct State {
    structure: SdpProblem,
    slots: Vec<Slot>,
    a_values: Vec<f64>,
    b: Vec<f64>,
    row_offsets: Vec<usize>,
    solver: DefaultSolver<f64>,
}

impl ClarabelBackend {
    /// A backend with validated settings.
    pub fn new(settings: SolverSettings) -> Result<Self, LmiError> {
        settings.validate()?;
        Ok(Self { settings, state: None })
    }

    fn clarabel_settings(&self) -> Result<DefaultSettings<f64>, LmiError> {
        let s = &self.settings;
        let f = s.reduced_tol_factor;
        DefaultSettingsBuilder::default()
            .max_iter(s.max_iterations)
            .verbose(s.verbose)
            .tol_gap_abs(s.tol_gap_abs)
            .tol_gap_rel(s.tol_gap_rel)
            .tol_feas(s.tol_feas)
            .tol_infeas_abs(s.tol_infeas)
            .tol_infeas_rel(s.tol_infeas)
            .reduced_tol_gap_abs(s.tol_gap_abs * f)
            .reduced_tol_gap_rel(s.tol_gap_rel * f)
            .reduced_tol_feas(s.tol_feas * f)
            .reduced_tol_infeas_abs(s.tol_infeas * f)
            .reduced_tol_infeas_rel(s.tol_infeas * f)
            .time_limit(s.time_limit.map_or(f64::INFINITY, |t| t.as_secs_f64()))
            .presolve_enable(false)
            .chordal_decomposition_enable(false)
            .input_sparse_dropzeros(false)
            .build()
            .map_err(|e| LmiError::Backend { backend: NAME, message: format!("settings: {e:?}") })
    }

    /// Writes the problem's values into `a_values`, `b`, `q`.
    fn fill(slots: &[Slot], problem: &SdpProblem, a_values: &mut [f64], b: &mut [f64]) {
        b.iter_mut().for_each(|v| *v = 0.0);
        for (slot, e) in slots.iter().zip(problem.entries()) {
            match *slot {
                Slot::B(i, f) => b[i] = f * e.value,
                Slot::A(k, f) => a_values[k] = f * e.value,
            }
        }
    }
}

fn map_status(s: SolverStatus) -> SolveStatus {
    match s {
        SolverStatus::Unsolved => SolveStatus::Unsolved,
        SolverStatus::Solved => SolveStatus::Solved,
        SolverStatus::AlmostSolved => SolveStatus::AlmostSolved,
        SolverStatus::PrimalInfeasible => SolveStatus::PrimalInfeasible,
        SolverStatus::DualInfeasible => SolveStatus::DualInfeasible,
        SolverStatus::AlmostPrimalInfeasible => SolveStatus::AlmostPrimalInfeasible,
        SolverStatus::AlmostDualInfeasible => SolveStatus::AlmostDualInfeasible,
        SolverStatus::MaxIterations => SolveStatus::IterationLimit,
        SolverStatus::MaxTime => SolveStatus::TimeLimit,
        SolverStatus::NumericalError | SolverStatus::InsufficientProgress | SolverStatus::CallbackTerminated => {
            SolveStatus::NumericalTrouble
        }
    }
}

impl SdpBackend for ClarabelBackend {
    fn name(&self) -> &'static str {
        NAME
    }

    fn setup(&mut self, problem: &SdpProblem) -> Result<(), LmiError> {
        let mut row_offsets = Vec::with_capacity(problem.blocks().len() + 1);
        let mut rows = 0;
        let mut cones: Vec<SupportedConeT<f64>> = Vec::with_capacity(problem.blocks().len());
        for blk in problem.blocks() {
            row_offsets.push(rows);
            match *blk {
                Block::Psd(n) => {
                    rows += svec_len(n);
                    cones.push(PSDTriangleConeT(n));
                }
                Block::Nonneg(n) => {
                    rows += n;
                    cones.push(NonnegativeConeT(n));
                }
            }
        }
        row_offsets.push(rows);
        let nvars = problem.num_vars();
        // Entries are sorted by (mat, block, col, row), so within one matrix the svec rows
        // increase: the CSC pattern can be laid out in one pass.
        let mut colptr = vec![0usize; nvars + 1];
        let mut rowval = Vec::new();
        let mut slots = Vec::with_capacity(problem.entries().len());
        for e in problem.entries() {
            let (row, factor) = match problem.blocks()[e.block] {
                Block::Psd(_) => (row_offsets[e.block] + svec_index(e.row, e.col), -svec_scale(e.row, e.col)),
                Block::Nonneg(_) => (row_offsets[e.block] + e.row, -1.0),
            };
            if e.mat == 0 {
                slots.push(Slot::B(row, factor));
            } else {
                slots.push(Slot::A(rowval.len(), factor));
                rowval.push(row);
                colptr[e.mat] += 1;
            }
        }
        for j in 0..nvars {
            colptr[j + 1] += colptr[j];
        }
        let mut a_values = vec![0.0; rowval.len()];
        let mut b = vec![0.0; rows];
        Self::fill(&slots, problem, &mut a_values, &mut b);
        let a = CscMatrix::new(rows, nvars, colptr, rowval, a_values.clone());
        let p = CscMatrix::<f64>::zeros((nvars, nvars));
        let solver = DefaultSolver::new(&p, problem.c(), &a, &b, &cones, self.clarabel_settings()?)
            .map_err(|e| LmiError::Backend { backend: NAME, message: format!("setup: {e:?}") })?;
        self.state = Some(State { structure: problem.clone(), slots, a_values, b, row_offsets, solver });
        Ok(())
    }

    fn solve(&mut self, problem: &SdpProblem, solution: &mut SdpSolution) -> Result<(), LmiError> {
        let Some(st) = self.state.as_mut() else {
            return Err(LmiError::StructureMismatch("solve called before setup".into()));
        };
        if !st.structure.same_structure(problem) {
            return Err(LmiError::StructureMismatch("problem differs from the one given to setup".into()));
        }
        if !solution.fits(problem) {
            return Err(LmiError::StructureMismatch("solution is not sized for this problem".into()));
        }
        let start = Instant::now();
        Self::fill(&st.slots, problem, &mut st.a_values, &mut st.b);
        let upd = |e| LmiError::Backend { backend: NAME, message: format!("data update: {e:?}") };
        st.solver.update_A(&st.a_values).map_err(upd)?;
        st.solver.update_b(&st.b).map_err(upd)?;
        st.solver.update_q(&problem.c().to_vec()).map_err(upd)?;
        st.solver.solve();
        let sol = &st.solver.solution;
        solution.status = map_status(sol.status);
        solution.x.copy_from_slice(&sol.x);
        for (b, blk) in problem.blocks().iter().enumerate() {
            let z = &sol.z[st.row_offsets[b]..st.row_offsets[b + 1]];
            let y = &mut solution.dual[b];
            match blk {
                Block::Psd(_) => smat_into(z, y)?,
                Block::Nonneg(n) => {
                    y.fill(0.0);
                    for i in 0..*n {
                        y[(i, i)] = z[i];
                    }
                }
            }
        }
        solution.primal_objective = problem.c().iter().zip(&sol.x).map(|(c, x)| c * x).sum();
        solution.dual_objective = -st.b.iter().zip(&sol.z).map(|(b, z)| b * z).sum::<f64>();
        solution.iterations = sol.iterations;
        solution.primal_residual = sol.r_prim;
        solution.dual_residual = sol.r_dual;
        solution.solve_time = start.elapsed();
        Ok(())
    }
}
