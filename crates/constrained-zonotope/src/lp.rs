//! The linear programs over a constrained zonotope's factors,
//! `min qᵀ ξ  s.t.  A ξ = b, −1 ≤ ξ ≤ 1`, solved by Clarabel's pure-Rust interior-point method.
//! Their answers are proposals only: the multipliers `λ` they return are verified by the caller
//! in interval arithmetic (Z7), so no solver tolerance can shrink a published bound.

use clarabel_lp::algebra::CscMatrix;
use clarabel_lp::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, SupportedConeT, ZeroConeT,
};
use nalgebra::{DMatrix, DVector};

/// What the solver proposes.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum LpProposal {
    /// Multipliers `λ` of `A ξ = b` at an (approximate) optimum, and the primal point.
    Optimal { lambda: Vec<f64>, xi: Vec<f64> },
    /// A proposed Farkas certificate `λ` (`λᵀ b > ‖Aᵀ λ‖₁`): no `ξ` in the box meets `A ξ = b`.
    Infeasible { lambda: Vec<f64> },
    /// No usable answer (iteration limit, numerical trouble, a panic inside the solver).
    Failed,
}

/// One set of constraints `A ξ = b, ‖ξ‖∞ ≤ 1`, set up once and solved for many objectives.
pub(crate) struct FactorLp {
    solver: Option<DefaultSolver<f64>>,
    nc: usize,
}

fn settings() -> Option<clarabel_lp::solver::DefaultSettings<f64>> {
    DefaultSettingsBuilder::default()
        .verbose(false)
        .presolve_enable(false)
        .input_sparse_dropzeros(false)
        .tol_gap_abs(1e-10)
        .tol_gap_rel(1e-10)
        .tol_feas(1e-10)
        .max_iter(100)
        .build()
        .ok()
}

impl FactorLp {
    /// The constraints of `⟨·, ·, A, b⟩`; `q0` the first objective (it sets Clarabel's scaling).
    pub(crate) fn new(a: &DMatrix<f64>, b: &DVector<f64>, q0: &[f64]) -> Self {
        let (nc, ng) = (a.nrows(), a.ncols());
        // Rows: nc equalities, then ξ ≤ 1 and −ξ ≤ 1 per factor. Column j: A's column, +1, −1.
        let mut colptr = Vec::with_capacity(ng + 1);
        let mut rowval = Vec::with_capacity(ng * (nc + 2));
        let mut nzval = Vec::with_capacity(ng * (nc + 2));
        colptr.push(0);
        for j in 0..ng {
            for i in 0..nc {
                // Structural zeros kept: the matrix is what the multipliers are verified against.
                rowval.push(i);
                nzval.push(a[(i, j)]);
            }
            rowval.push(nc + 2 * j);
            nzval.push(1.0);
            rowval.push(nc + 2 * j + 1);
            nzval.push(-1.0);
            colptr.push(rowval.len());
        }
        let rows = nc + 2 * ng;
        let amat = CscMatrix::new(rows, ng, colptr, rowval, nzval);
        let p = CscMatrix::zeros((ng, ng));
        let mut bb = Vec::with_capacity(rows);
        bb.extend_from_slice(b.as_slice());
        bb.resize(rows, 1.0);
        let mut cones: Vec<SupportedConeT<f64>> = Vec::with_capacity(2);
        if nc > 0 {
            cones.push(ZeroConeT(nc));
        }
        if ng > 0 {
            cones.push(NonnegativeConeT(2 * ng));
        }
        let solver = settings().and_then(|s| {
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                DefaultSolver::new(&p, q0, &amat, &bb, &cones, s).ok()
            }))
            .ok()
            .flatten()
        });
        Self { solver, nc }
    }

    /// Solves for the objective `q` (the first call may pass the `q0` of [`FactorLp::new`]).
    pub(crate) fn solve(&mut self, q: &[f64], first: bool) -> LpProposal {
        let Some(solver) = self.solver.as_mut() else { return LpProposal::Failed };
        let nc = self.nc;
        let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            if !first && solver.update_q(&q.to_vec()).is_err() {
                return None;
            }
            solver.solve();
            let s = &solver.solution;
            Some((s.status, s.x.clone(), s.z[..nc].to_vec()))
        }));
        match result {
            Ok(Some((SolverStatus::Solved | SolverStatus::AlmostSolved, xi, z))) => {
                LpProposal::Optimal { lambda: z.iter().map(|v| -v).collect(), xi }
            }
            Ok(Some((SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible, _, z))) => {
                LpProposal::Infeasible { lambda: z.iter().map(|v| -v).collect() }
            }
            _ => LpProposal::Failed,
        }
    }
}
