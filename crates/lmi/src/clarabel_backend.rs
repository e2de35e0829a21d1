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
//!
//! **Scaling.** The values handed to Clarabel are those of the problem scaled as described under
//! "Equilibration" in [`SolverSettings`] (Clarabel's own equilibration then works on a problem of
//! moderate size); `x`, `Y` and the objectives are mapped back to the caller's problem.
//!
//! **Certificates.** An infeasibility Clarabel reports is kept only if its certificate passes
//! the independent check on the caller's unscaled problem ([`crate::certificate`]); otherwise
//! the solve continues as for any other non-optimal outcome (the unscaled problem is solved too)
//! and ends `NumericalTrouble` with [`SdpSolution::rejected_certificate`] set, unless that second
//! solve gives an optimum or an accepted certificate. An accepted certificate of the scaled solve
//! at the strict tolerances is the answer (no second solve).
//!
//! **Memory.** `setup` first estimates what Clarabel will need, dominated per PSD block of order
//! `n` by its dense `s × s` block (`s = n(n+1)/2`) in the scaling matrix, the KKT matrix and its
//! factor (about `24 s²` bytes), and returns [`LmiError::MemoryLimit`] beyond
//! [`SolverSettings::memory_limit_bytes`].
//!
//! **Panics.** Clarabel 0.11 panics on some inputs (`"Eigval error"`, `"SVD error"` from LAPACK
//! in its PSD cone when an iterate is no longer finite). Setup and solve run under
//! [`std::panic::catch_unwind`]: a panic in `setup` is [`LmiError::BackendPanic`]; a panic in
//! `solve` ends that solve with [`SolveStatus::NumericalTrouble`] (the message is kept, see
//! [`ClarabelBackend::last_panic`]) and the next solve rebuilds Clarabel's solver from the stored
//! structure, since the panicked one may be inconsistent. The default panic hook still prints the
//! message to standard error (silencing it would change process-wide state).

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::Instant;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, PSDTriangleConeT, SolverStatus,
    SupportedConeT,
};

use crate::certificate::{self, CertificateChecker, CertificateKind};
use crate::error::{LmiError, saturate_bytes};
use crate::problem::{Block, SdpProblem};
use crate::scaling::Equilibration;
use crate::solver::{SdpBackend, SdpSolution, SolveStart, SolveStatus, SolverSettings};
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

/// Clarabel as an [`SdpBackend`] (see the [module documentation](self)).
pub struct ClarabelBackend {
    settings: SolverSettings,
    state: Option<State>,
    /// Scratch of the independent check of infeasibility certificates.
    checker: Option<CertificateChecker>,
    last_panic: Option<String>,
}

impl std::fmt::Debug for ClarabelBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ClarabelBackend")
            .field("settings", &self.settings)
            .field("set_up", &self.state.is_some())
            .field("last_panic", &self.last_panic)
            .finish_non_exhaustive()
    }
}

struct State {
    structure: SdpProblem,
    slots: Vec<Slot>,
    a_values: Vec<f64>,
    b: Vec<f64>,
    q: Vec<f64>,
    row_offsets: Vec<usize>,
    colptr: Vec<usize>,
    rowval: Vec<usize>,
    cones: Vec<SupportedConeT<f64>>,
    /// `None` after a panic inside Clarabel: the next solve builds a new solver.
    solver: Option<DefaultSolver<f64>>,
}

/// Runs `f`, containing a panic: `Err` holds the panic message. The default hook has already
/// printed it to standard error.
pub(crate) fn contain<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    catch_unwind(AssertUnwindSafe(f)).map_err(|payload| {
        if let Some(s) = payload.downcast_ref::<&str>() {
            (*s).to_owned()
        } else if let Some(s) = payload.downcast_ref::<String>() {
            s.clone()
        } else {
            "panic with a non-string payload".to_owned()
        }
    })
}

/// Bytes Clarabel needs for `problem`, estimated from its sizes (and the solution's): per PSD
/// block with `s = n(n+1)/2`, the dense `s × s` block of the NT scaling (`8 s²`) and its upper
/// triangle in the KKT matrix and in the factor (values and row indices, `2 · 16 s²/2`); per
/// nonzero of `A` its copies in `A`, the KKT matrix and the factor; about twenty vectors of the
/// KKT dimension.
pub(crate) fn required_bytes(problem: &SdpProblem) -> u64 {
    let mut dense: u128 = 0;
    let mut rows: u128 = 0;
    for blk in problem.blocks() {
        let s = match *blk {
            Block::Psd(n) => svec_len(n) as u128,
            Block::Nonneg(n) => n as u128,
        };
        rows += s;
        if matches!(blk, Block::Psd(_)) {
            dense += 24 * s * s;
        }
    }
    let nnz = problem.entries().len() as u128;
    let vectors = 8 * 20 * (rows + problem.num_vars() as u128);
    saturate_bytes(
        dense
            + 3 * 16 * nnz
            + vectors
            + u128::from(SdpSolution::required_bytes(problem))
            + u128::from(CertificateChecker::required_bytes(problem)),
    )
}

impl ClarabelBackend {
    /// A backend with validated settings.
    pub fn new(settings: SolverSettings) -> Result<Self, LmiError> {
        settings.validate()?;
        Ok(Self { settings, state: None, checker: None, last_panic: None })
    }

    /// The message of the last panic contained in `setup` or `solve`, if any.
    pub fn last_panic(&self) -> Option<&str> {
        self.last_panic.as_deref()
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

    /// Writes the problem's values, scaled by `scale`, into `a_values`, `b`, `q`.
    fn fill(
        slots: &[Slot],
        problem: &SdpProblem,
        scale: &Equilibration,
        a_values: &mut [f64],
        b: &mut [f64],
        q: &mut [f64],
    ) {
        b.iter_mut().for_each(|v| *v = 0.0);
        for (slot, e) in slots.iter().zip(problem.entries()) {
            match *slot {
                Slot::B(i, f) => b[i] = f * scale.entry(e),
                Slot::A(k, f) => a_values[k] = f * scale.entry(e),
            }
        }
        for (q, &c) in q.iter_mut().zip(problem.c()) {
            *q = scale.cost(c);
        }
    }

    /// A Clarabel solver for the state's pattern and current values; a panic is contained.
    fn build(&self, st: &State) -> Result<DefaultSolver<f64>, LmiError> {
        let nvars = st.q.len();
        let a = CscMatrix::new(st.b.len(), nvars, st.colptr.clone(), st.rowval.clone(), st.a_values.clone());
        let p = CscMatrix::<f64>::zeros((nvars, nvars));
        let settings = self.clarabel_settings()?;
        contain(|| DefaultSolver::new(&p, &st.q, &a, &st.b, &st.cones, settings))
            .map_err(|message| LmiError::BackendPanic { backend: NAME, message })?
            .map_err(|e| LmiError::Backend { backend: NAME, message: format!("setup: {e:?}") })
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
        self.state = None;
        self.checker = None;
        let required = required_bytes(problem);
        if required > self.settings.memory_limit_bytes {
            return Err(LmiError::MemoryLimit {
                backend: NAME,
                required_bytes: required,
                limit_bytes: self.settings.memory_limit_bytes,
            });
        }
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
        let mut st = State {
            structure: problem.clone(),
            a_values: vec![0.0; rowval.len()],
            b: vec![0.0; rows],
            q: vec![0.0; nvars],
            slots,
            row_offsets,
            colptr,
            rowval,
            cones,
            solver: None,
        };
        let scale = Equilibration::compute(problem, self.settings.equilibrate);
        Self::fill(&st.slots, problem, &scale, &mut st.a_values, &mut st.b, &mut st.q);
        let solver = self.build(&st).inspect_err(|e| {
            if let LmiError::BackendPanic { message, .. } = e {
                self.last_panic = Some(message.clone());
            }
        })?;
        st.solver = Some(solver);
        self.state = Some(st);
        self.checker = Some(CertificateChecker::new(problem));
        Ok(())
    }

    fn solve(&mut self, problem: &SdpProblem, solution: &mut SdpSolution) -> Result<(), LmiError> {
        let Some(mut st) = self.state.take() else {
            return Err(LmiError::StructureMismatch("solve called before setup".into()));
        };
        let result = self.solve_with(&mut st, problem, solution);
        self.state = Some(st);
        result
    }
}

impl ClarabelBackend {
    /// Solves the equilibrated problem; if that ends neither optimal nor with an infeasibility
    /// (strict tolerances) whose certificate passes the independent check
    /// ([`crate::certificate`]) and the scaling was not the identity, solves the problem as given too (whose outcome is then reported, its
    /// certificate checked the same way).
    /// Clarabel equilibrates internally as well, and on some moderately scaled problems (the
    /// carrier's LMI (28) with a small `P_k`) the two scalings together end in numerical trouble
    /// where the unscaled problem is solved.
    fn solve_with(&mut self, st: &mut State, problem: &SdpProblem, solution: &mut SdpSolution) -> Result<(), LmiError> {
        if !st.structure.same_structure(problem) {
            return Err(LmiError::StructureMismatch("problem differs from the one given to setup".into()));
        }
        if !solution.fits(problem) {
            return Err(LmiError::StructureMismatch("solution is not sized for this problem".into()));
        }
        let scale = Equilibration::compute(problem, self.settings.equilibrate);
        let start = Instant::now();
        solution.rejected_certificate = None;
        self.solve_scaled(st, problem, solution, scale)?;
        self.vet(problem, solution);
        // An accepted certificate at the strict tolerances is an answer: solving the unscaled
        // problem could only replace it by an outcome judged on worse-scaled data. (A relaxed
        // "almost infeasible" still gets the second solve, as before.)
        let answered = solution.status.is_optimal()
            || matches!(solution.status, SolveStatus::PrimalInfeasible | SolveStatus::DualInfeasible);
        if !answered && !scale.is_identity() {
            self.solve_scaled(st, problem, solution, Equilibration::IDENTITY)?;
            self.vet(problem, solution);
            solution.solve_time = start.elapsed();
        }
        if solution.status.is_optimal() || CertificateKind::of(solution.status).is_some() {
            // Optimal or an accepted certificate: an earlier rejection is not the outcome.
            solution.rejected_certificate = None;
        }
        Ok(())
    }

    /// An infeasibility is reported only with a certificate that holds for the caller's data
    /// (checked on `problem`, unscaled).
    fn vet(&mut self, problem: &SdpProblem, solution: &mut SdpSolution) {
        if let Some(checker) = self.checker.as_mut() {
            certificate::vet(checker, problem, &self.settings, solution);
        }
    }

    fn solve_scaled(
        &mut self,
        st: &mut State,
        problem: &SdpProblem,
        solution: &mut SdpSolution,
        scale: Equilibration,
    ) -> Result<(), LmiError> {
        let start = Instant::now();
        Self::fill(&st.slots, problem, &scale, &mut st.a_values, &mut st.b, &mut st.q);
        let solver = match st.solver.take() {
            Some(mut solver) => {
                let upd = |e| LmiError::Backend { backend: NAME, message: format!("data update: {e:?}") };
                solver.update_A(&st.a_values).map_err(upd)?;
                solver.update_b(&st.b).map_err(upd)?;
                solver.update_q(&st.q).map_err(upd)?;
                Ok(solver)
            }
            // The previous solve panicked: start from a fresh solver with the current values.
            None => self.build(st),
        };
        let mut solver = match solver {
            Ok(solver) => solver,
            Err(LmiError::BackendPanic { message, .. }) => {
                self.panicked(message, start, solution);
                return Ok(());
            }
            Err(e) => return Err(e),
        };
        if let Err(message) = contain(|| solver.solve()) {
            // The solver may be inconsistent: dropped, rebuilt by the next solve.
            self.panicked(message, start, solution);
            return Ok(());
        }
        let sol = &solver.solution;
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
        solution.iterations = sol.iterations;
        // Clarabel's Rust API has no warm start: every solve starts cold.
        solution.start = SolveStart::Cold;
        solution.primal_residual = sol.r_prim;
        solution.dual_residual = sol.r_dual;
        st.solver = Some(solver);
        // Back to the caller's problem; objectives from its data.
        scale.unscale(solution);
        solution.primal_objective = problem.c().iter().zip(&solution.x).map(|(c, x)| c * x).sum();
        solution.dual_objective = f0_trace(problem, &solution.dual);
        solution.solve_time = start.elapsed();
        Ok(())
    }

    /// Records a contained panic of Clarabel's solve as the outcome of this solve.
    fn panicked(&mut self, message: String, start: Instant, solution: &mut SdpSolution) {
        if self.settings.verbose {
            eprintln!("clarabel: panic contained: {message}");
        }
        self.last_panic = Some(message);
        solution.status = SolveStatus::NumericalTrouble;
        solution.x.fill(0.0);
        solution.dual.iter_mut().for_each(|y| y.fill(0.0));
        solution.primal_objective = f64::NAN;
        solution.dual_objective = f64::NAN;
        solution.iterations = 0;
        solution.start = SolveStart::Cold;
        solution.primal_residual = f64::NAN;
        solution.dual_residual = f64::NAN;
        solution.solve_time = start.elapsed();
    }
}

/// `tr(F₀ Y)` over the entries of `F₀` (the first entries: they are sorted by matrix).
fn f0_trace(problem: &SdpProblem, y: &[nalgebra::DMatrix<f64>]) -> f64 {
    problem
        .entries()
        .iter()
        .take_while(|e| e.mat == 0)
        .map(|e| {
            let yb = &y[e.block];
            if e.row == e.col {
                e.value * yb[(e.row, e.row)]
            } else {
                e.value * (yb[(e.row, e.col)] + yb[(e.col, e.row)])
            }
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The containment wrapper turns a panic (with a `&str` or a `String` payload) into its
    /// message and lets values through.
    #[test]
    fn contain_turns_panics_into_messages() {
        assert_eq!(contain(|| 7), Ok(7));
        assert_eq!(contain(|| -> u8 { panic!("Eigval error") }), Err("Eigval error".to_owned()));
        let code = -4;
        assert_eq!(contain(|| -> u8 { panic!("SVD error: SVD({code})") }), Err("SVD error: SVD(-4)".to_owned()));
        assert!(contain(|| std::panic::panic_any(3u8)).unwrap_err().contains("non-string"));
    }
}
