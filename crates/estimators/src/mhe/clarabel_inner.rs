//! Clarabel's interior-point QP path (pure Rust, no BLAS) as the inner solver of the coordinate
//! rotation's minimisation step (44), for comparison with the active-set solver
//! ([`InnerSolver::Clarabel`](crate::mhe::InnerSolver::Clarabel)). Allocates per solve.

use clarabel_qp::algebra::CscMatrix;
use clarabel_qp::solver::{DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus};

use crate::mhe::window::WindowProblem;

/// Why a Clarabel QP gave no solution.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum QpFailure {
    /// The constraints cannot all hold.
    Infeasible,
    /// Clarabel did not report a solution (or panicked).
    Failed,
}

/// The `rows × columns.len()` sparse matrix whose column `c` holds the `(row, value)` entries of
/// `columns[c]` (rows increasing within a column).
pub(crate) fn csc_from_columns(rows: usize, columns: &[Vec<(usize, f64)>]) -> CscMatrix<f64> {
    let mut colptr = Vec::with_capacity(columns.len() + 1);
    let (mut rowval, mut nzval) = (Vec::new(), Vec::new());
    colptr.push(0);
    for col in columns {
        for &(r, v) in col {
            rowval.push(r);
            nzval.push(v);
        }
        colptr.push(rowval.len());
    }
    CscMatrix::new(rows, columns.len(), colptr, rowval, nzval)
}

/// Solves `min ½ zᵀ H z − bᵀ z` over the window's box with Clarabel; `Ok(iterations)` with the
/// solution in `z`, `Err(())` if Clarabel does not report a solution (or panics).
pub(crate) fn solve_box_qp(w: &WindowProblem, z: &mut [f64]) -> Result<usize, ()> {
    solve_qp(w, z, None).map_err(|_| ())
}

/// As [`solve_box_qp`], and with `outputs = Some((v_lo, v_hi))` also the output constraints
/// `v_lo ≤ y − C x_j(z) ≤ v_hi` of every measured sample (the paper's (11) read literally).
pub(crate) fn solve_qp(
    w: &WindowProblem,
    z: &mut [f64],
    outputs: Option<(&[f64], &[f64])>,
) -> Result<usize, QpFailure> {
    let nz = w.nz;
    let (h, b, lo, hi) = (&w.h[..nz * nz], &w.b[..nz], &w.lo[..nz], &w.hi[..nz]);
    // P: upper triangle of H (column c holds rows r ≤ c; H is stored by its lower triangle).
    let mut colptr = Vec::with_capacity(nz + 1);
    let mut rowval = Vec::new();
    let mut nzval = Vec::new();
    colptr.push(0);
    for c in 0..nz {
        for r in 0..=c {
            let v = h[r * nz + c];
            if v != 0.0 {
                rowval.push(r);
                nzval.push(v);
            }
        }
        colptr.push(rowval.len());
    }
    let p = CscMatrix::new(nz, nz, colptr, rowval, nzval);
    let q: Vec<f64> = b.iter().map(|v| -v).collect();
    // Bounds as rows of A z ≤ bb: z_i ≤ hi_i and −z_i ≤ −lo_i, for finite bounds.
    let mut a_col: Vec<Vec<(usize, f64)>> = vec![Vec::new(); nz];
    let mut bb = Vec::new();
    for i in 0..nz {
        if hi[i].is_finite() {
            a_col[i].push((bb.len(), 1.0));
            bb.push(hi[i]);
        }
        if lo[i].is_finite() {
            a_col[i].push((bb.len(), -1.0));
            bb.push(-lo[i]);
        }
    }
    if let Some((v_lo, v_hi)) = outputs {
        let m = v_lo.len();
        for j in 0..w.len {
            if !w.measured[j] {
                continue;
            }
            for i in 0..m {
                // e = ỹ − a z ≤ v_hi  ⇔  −a z ≤ v_hi − ỹ;   e ≥ v_lo  ⇔  a z ≤ ỹ − v_lo.
                let row = w.row(j, i);
                let y = w.y_tilde[j * m + i];
                let (r_hi, r_lo) = (bb.len(), bb.len() + 1);
                for (c, &a) in row.iter().enumerate() {
                    if a != 0.0 {
                        a_col[c].push((r_hi, -a));
                        a_col[c].push((r_lo, a));
                    }
                }
                bb.push(v_hi[i] - y);
                bb.push(y - v_lo[i]);
            }
        }
    }
    let rows = bb.len();
    let a = csc_from_columns(rows, &a_col);
    let cones = if rows > 0 { vec![NonnegativeConeT(rows)] } else { Vec::new() };
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .presolve_enable(false)
        .tol_gap_abs(1e-12)
        .tol_gap_rel(1e-12)
        .tol_feas(1e-12)
        .build()
        .map_err(|_| QpFailure::Failed)?;
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let mut solver = DefaultSolver::new(&p, &q, &a, &bb, &cones, settings).ok()?;
        solver.solve();
        Some((solver.solution.status, solver.solution.x.clone(), solver.solution.iterations as usize))
    }));
    match result {
        Ok(Some((SolverStatus::Solved | SolverStatus::AlmostSolved, x, iterations)))
            if x.len() == nz && x.iter().all(|v| v.is_finite()) =>
        {
            for i in 0..nz {
                z[i] = x[i].clamp(lo[i], hi[i]);
            }
            Ok(iterations)
        }
        Ok(Some((SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible, ..))) => {
            Err(QpFailure::Infeasible)
        }
        _ => Err(QpFailure::Failed),
    }
}
