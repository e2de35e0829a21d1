//! The Gauss–Newton step of [`NonlinearMhe`](super::NonlinearMhe) with boxes on the disturbances
//! `ω_j ≈ d_j + Δ_{j+1} − A_j Δ_j` and the measurement residuals `ν_j ≈ e_j − C_j Δ_j`
//! (linearised at the iterate), as a QP in `Δ` solved by Clarabel's pure-Rust path:
//!
//! ```text
//! minimise ½ Δᵀ H Δ + gᵀ Δ   subject to   lo ≤ ω ≤ hi,  lo ≤ ν ≤ hi   (finite sides only)
//! ```
//!
//! with the window's Gauss–Newton matrix `H` and gradient `g`. The problem is assembled in
//! compressed-column form on every call (this path allocates).

use clarabel_qp::algebra::CscMatrix;
use clarabel_qp::solver::{DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus};
use nalgebra::DVector;

use super::window::{Span, Weights, Window};

/// Outcome of a constrained Gauss–Newton step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum ConstrainedStep {
    /// The step is in the window's `step`.
    Solved,
    /// The linearised boxes cannot all hold.
    Infeasible,
    /// Clarabel failed (or panicked) otherwise.
    Failed,
}

/// The box of a residual, `[lo, hi]` per component.
pub(super) type Bounds = (DVector<f64>, DVector<f64>);

/// Sparse rows `Σ a_c Δ_c ≤ b`.
type Rows = Vec<(Vec<(usize, f64)>, f64)>;

/// A CSC matrix of `nrows` rows from its columns of `(row, value)` (sorted here).
fn to_csc(nrows: usize, cols: &[Vec<(usize, f64)>]) -> CscMatrix<f64> {
    let mut colptr = vec![0];
    let mut rowval = Vec::new();
    let mut nzval = Vec::new();
    for col in cols {
        let mut sorted = col.clone();
        sorted.sort_by_key(|&(r, _)| r);
        for (r, v) in sorted {
            rowval.push(r);
            nzval.push(v);
        }
        colptr.push(rowval.len());
    }
    CscMatrix::new(nrows, cols.len(), colptr, rowval, nzval)
}

/// The upper triangle of `H` by columns: the diagonal blocks `D_j` (built by the caller) and
/// above them `O_{j−1}ᵀ = −A_{j−1}ᵀ Q⁻¹` (block `(j − 1, j)`).
fn hessian_columns(win: &Window, wts: &Weights<'_>, n: usize, len: usize) -> Vec<Vec<(usize, f64)>> {
    let mut cols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n * len];
    for j in 0..len {
        for c in 0..n {
            let col = &mut cols[j * n + c];
            if j > 0 {
                for r in 0..n {
                    let mut v = 0.0;
                    for k in 0..n {
                        v -= win.a[j - 1][(k, r)] * wts.q_inv[(k, c)];
                    }
                    if v != 0.0 {
                        col.push(((j - 1) * n + r, v));
                    }
                }
            }
            for r in 0..=c {
                let v = win.d[j][(r, c)];
                if v != 0.0 {
                    col.push((j * n + r, v));
                }
            }
        }
    }
    cols
}

/// The linearised boxes as rows `a·Δ ≤ b` (one per finite side).
fn constraint_rows(win: &Window, span: &Span<'_>, w_box: Option<&Bounds>, v_box: Option<&Bounds>) -> Rows {
    let Span { rings, start, len, .. } = *span;
    let n = win.x[0].len();
    let mut rows = Rows::new();
    if let Some((lo, hi)) = w_box {
        for j in 0..len.saturating_sub(1) {
            for i in 0..n {
                let dj = win.x[j + 1][i] - win.fx[j][i];
                let mut row: Vec<(usize, f64)> = vec![((j + 1) * n + i, 1.0)];
                for k in 0..n {
                    let a = win.a[j][(i, k)];
                    if a != 0.0 {
                        row.push((j * n + k, -a));
                    }
                }
                if hi[i].is_finite() {
                    rows.push((row.clone(), hi[i] - dj));
                }
                if lo[i].is_finite() {
                    rows.push((row.iter().map(|&(c, v)| (c, -v)).collect(), dj - lo[i]));
                }
            }
        }
    }
    if let Some((lo, hi)) = v_box {
        for j in 0..len {
            let sl = rings.slot(start + j);
            if !rings.has_y[sl] {
                continue;
            }
            let measured = rings.measured(sl);
            for i in 0..lo.len() {
                // An unmeasured output of a partial sample has no residual to bound.
                if measured.is_some_and(|mask| !mask[i]) {
                    continue;
                }
                let e = rings.y[sl][i] - win.hx[j][i];
                // ν = e − C Δ ≤ hi  ⇔  −C Δ ≤ hi − e;   ν ≥ lo  ⇔  C Δ ≤ e − lo.
                let c = &win.c[j];
                let row: Vec<(usize, f64)> =
                    (0..n).filter(|&k| c[(i, k)] != 0.0).map(|k| (j * n + k, c[(i, k)])).collect();
                if hi[i].is_finite() {
                    rows.push((row.iter().map(|&(c, v)| (c, -v)).collect(), hi[i] - e));
                }
                if lo[i].is_finite() {
                    rows.push((row, e - lo[i]));
                }
            }
        }
    }
    rows
}

/// The constrained Gauss–Newton step at the window's linearisation (after
/// [`Window::linearise`]), into the window's `step`.
pub(super) fn constrained_step(
    win: &mut Window,
    span: &Span<'_>,
    w_box: Option<&Bounds>,
    v_box: Option<&Bounds>,
) -> ConstrainedStep {
    let (wts, len) = (&span.wts, span.len);
    let n = win.x[0].len();
    let nv = n * len;
    win.build_blocks(span, 0.0);
    let cols = hessian_columns(win, wts, n, len);
    let q: Vec<f64> = win.g[..len].iter().flat_map(|g| g.iter().copied()).collect();
    let rows = constraint_rows(win, span, w_box, v_box);
    let mut a_cols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); nv];
    for (r, (row, _)) in rows.iter().enumerate() {
        for &(c, v) in row {
            a_cols[c].push((r, v));
        }
    }
    let b: Vec<f64> = rows.iter().map(|r| r.1).collect();
    let p = to_csc(nv, &cols);
    let a = to_csc(rows.len(), &a_cols);
    let cones = if rows.is_empty() { Vec::new() } else { vec![NonnegativeConeT(rows.len())] };
    let Ok(settings) =
        DefaultSettingsBuilder::default().verbose(false).tol_gap_abs(1e-12).tol_gap_rel(1e-12).tol_feas(1e-10).build()
    else {
        return ConstrainedStep::Failed;
    };
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings).ok()?;
        solver.solve();
        Some((solver.solution.status, solver.solution.x.clone()))
    }));
    match outcome {
        Ok(Some((SolverStatus::Solved | SolverStatus::AlmostSolved, x))) if x.iter().all(|v| v.is_finite()) => {
            for j in 0..len {
                for i in 0..n {
                    win.step[j][i] = x[j * n + i];
                }
            }
            ConstrainedStep::Solved
        }
        Ok(Some((SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible, _))) => {
            ConstrainedStep::Infeasible
        }
        _ => ConstrainedStep::Failed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mhe::nonlinear::window::tests::Case;

    /// The linearised disturbances `ω_j` and residuals `ν_j` at `x + Δ` (exact for the linear
    /// model of the case).
    fn residuals(cs: &Case) -> (Vec<DVector<f64>>, Vec<Option<DVector<f64>>>) {
        let w = &cs.window;
        let omega = (0..cs.len - 1).map(|j| &w.x[j + 1] - &w.fx[j] + &w.step[j + 1] - &w.a[j] * &w.step[j]).collect();
        let nu = (0..cs.len)
            .map(|j| {
                let sl = cs.rings.slot(cs.start + j);
                cs.rings.has_y[sl].then(|| &cs.rings.y[sl] - &w.hx[j] - &w.c[j] * &w.step[j])
            })
            .collect();
        (omega, nu)
    }

    fn linearised(len: usize) -> Case {
        let mut cs = Case::new(len);
        let (start, len) = (cs.start, cs.len);
        let (win, rings, wts, model) = cs.parts();
        win.linearise(model, &Span { rings, wts, start, len }).unwrap();
        cs
    }

    #[test]
    fn loose_boxes_give_the_gauss_newton_step() {
        let mut cs = linearised(4);
        let (start, len) = (cs.start, cs.len);
        let (win, rings, wts, _) = cs.parts();
        let mut free = win.clone();
        assert!(free.factor_and_solve(&Span { rings, wts, start, len }, 0.0));
        let wide = (DVector::from_element(3, -1e3), DVector::from_element(3, f64::INFINITY));
        let v_wide = (DVector::from_element(2, f64::NEG_INFINITY), DVector::from_element(2, 1e3));
        let mut boxed = win.clone();
        let got = constrained_step(&mut boxed, &Span { rings, wts, start, len }, Some(&wide), Some(&v_wide));
        assert_eq!(got, ConstrainedStep::Solved);
        for j in 0..len {
            assert!((&boxed.step[j] - &free.step[j]).amax() < 1e-7, "Δ_{j}");
        }
        // No box at all: no constraint rows, the same step.
        assert_eq!(constrained_step(win, &Span { rings, wts, start, len }, None, None), ConstrainedStep::Solved);
        for j in 0..len {
            assert!((&win.step[j] - &free.step[j]).amax() < 1e-7, "Δ_{j}");
        }
    }

    #[test]
    fn binding_boxes_hold_at_the_step() {
        let mut cs = linearised(4);
        let (start, len) = (cs.start, cs.len);
        let w_box = (DVector::from_element(3, -0.05), DVector::from_element(3, 0.05));
        let v_box = (DVector::from_element(2, -0.2), DVector::from_element(2, 0.2));
        let (win, rings, wts, _) = cs.parts();
        let mut free = win.clone();
        assert!(free.factor_and_solve(&Span { rings, wts, start, len }, 0.0));
        let got = constrained_step(win, &Span { rings, wts, start, len }, Some(&w_box), Some(&v_box));
        assert_eq!(got, ConstrainedStep::Solved);
        let (omega, nu) = residuals(&cs);
        let tol = 1e-7;
        assert!(omega.iter().all(|w| w.iter().all(|v| v.abs() <= 0.05 + tol)), "{omega:?}");
        assert!(nu.iter().flatten().all(|r| r.iter().all(|v| v.abs() <= 0.2 + tol)), "{nu:?}");
        // Some bound is active, so the step is not the unconstrained one.
        let active = omega.iter().any(|w| w.iter().any(|v| (v.abs() - 0.05).abs() < 1e-6))
            || nu.iter().flatten().any(|r| r.iter().any(|v| (v.abs() - 0.2).abs() < 1e-6));
        assert!(active);
        assert!((0..len).any(|j| (&cs.window.step[j] - &free.step[j]).amax() > 1e-6));
    }

    #[test]
    fn contradictory_boxes_are_infeasible() {
        // No disturbance and no measurement error allowed: the trajectory is fixed by x_0 (3
        // unknowns) while three samples of 2 measurements each must be matched exactly.
        let mut cs = linearised(4);
        let (start, len) = (cs.start, cs.len);
        let w_box = (DVector::from_element(3, -1e-9), DVector::from_element(3, 1e-9));
        let v_box = (DVector::from_element(2, -1e-9), DVector::from_element(2, 1e-9));
        let (win, rings, wts, _) = cs.parts();
        let got = constrained_step(win, &Span { rings, wts, start, len }, Some(&w_box), Some(&v_box));
        assert_eq!(got, ConstrainedStep::Infeasible);
    }
}
