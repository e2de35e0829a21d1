//! The data check of a moving-horizon window (docs/robust-mhe.md, §2.8): is there a state `x_s`
//! and a disturbance sequence `w_j ∈ W`, one per step (unblocked), with which every measurement of
//! the window fits its box, `y_j − C_j x_j ∈ V`? If not, the data contradict the model and the
//! boxes the estimator was given: a proof, not a statistical test.
//!
//! Two stages. The published window solution is a witness first: its trajectory satisfies the
//! dynamics with disturbances in `W` by construction, so residuals inside `V` prove consistency
//! at the cost of `m` dot products per sample (no allocation). Otherwise the linear programme
//!
//! ```text
//! min t   s.t.  x_{j+1} = A_j x_j + B_j u_j + w_j,   w_lo ≤ w_j ≤ w_hi,
//!               v_lo − t d ≤ y_j − C_j x_j ≤ v_hi + t d   (measured j),   t ≥ 0,
//! ```
//!
//! with `d` the widths of `V`, decides it (Clarabel's LP path, pure Rust; it allocates). Its
//! optimum `t*` is how much `V` must widen, in widths, for the window to fit: the data are called
//! inconsistent when `t* > 10⁻⁶`, so that measurements on the boundary of `V` and the solver's
//! rounding never are. The prior of `x_s` (the arrival cost) is not a hard bound and is left out:
//! the check sees the contradictions inside one window.

use clarabel_qp::algebra::CscMatrix;
use clarabel_qp::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, SupportedConeT, ZeroConeT,
};

use crate::mhe::clarabel_inner::csc_from_columns;

/// The widening of `V` (in box widths) above which a window is inconsistent.
pub(crate) const EXCESS_TOLERANCE: f64 = 1e-6;

/// A window's data for the check. Slices are column-major per sample, as the estimator's rings.
pub(crate) struct WindowData<'a, F>
where
    F: Fn(usize) -> Sample<'a>,
{
    /// States.
    pub n: usize,
    /// Outputs.
    pub m: usize,
    /// Samples in the window (`x_s … x_T`).
    pub len: usize,
    /// Sample `j` of the window.
    pub sample: F,
    /// The process-noise box.
    pub w: (&'a [f64], &'a [f64]),
    /// The measurement-noise box.
    pub v: (&'a [f64], &'a [f64]),
}

/// One sample `j` of a window: the transition to `j + 1` (unused for the last) and the
/// measurement of `x_j`, if any.
#[derive(Clone, Copy)]
pub(crate) struct Sample<'a> {
    /// `A_j` (`n × n`, column-major).
    pub a: &'a [f64],
    /// `B_j u_j`.
    pub bu: &'a [f64],
    /// `C_j` (`m × n`, column-major).
    pub c: &'a [f64],
    /// `y_j` (meaningful when `measured`).
    pub y: &'a [f64],
    /// Whether `x_j` was measured.
    pub measured: bool,
    /// Which outputs of it (a partial measurement's unmeasured rows have no residual to bound).
    pub outputs: &'a [bool],
}

/// What the check found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum WindowCheck {
    /// A disturbance sequence in `W` fits every measurement into `V`.
    Consistent,
    /// None does: `V` must widen by `excess` of its widths.
    Inconsistent {
        /// `t*` of the linear programme.
        excess: f64,
    },
    /// The linear programme gave no answer (numerical trouble): nothing is claimed.
    Undecided,
}

/// Whether the trajectory `traj` (`len` states of `n`) is a witness: every measured residual
/// inside `V` up to rounding.
pub(crate) fn witnesses<'a, F>(data: &WindowData<'a, F>, traj: &[f64]) -> bool
where
    F: Fn(usize) -> Sample<'a>,
{
    let (n, m) = (data.n, data.m);
    let (v_lo, v_hi) = data.v;
    for j in 0..data.len {
        let s = (data.sample)(j);
        if !s.measured {
            continue;
        }
        let x = &traj[j * n..(j + 1) * n];
        for i in 0..m {
            if !s.outputs[i] {
                continue;
            }
            let mut cx = 0.0;
            for k in 0..n {
                cx += s.c[k * m + i] * x[k];
            }
            let e = s.y[i] - cx;
            let slack = 1e-12 * (s.y[i].abs() + cx.abs() + v_lo[i].abs() + v_hi[i].abs());
            if !(e >= v_lo[i] - slack && e <= v_hi[i] + slack) {
                return false;
            }
        }
    }
    true
}

/// Decides the window by the linear programme of the module documentation.
pub(crate) fn check_window<'a, F>(data: &WindowData<'a, F>) -> WindowCheck
where
    F: Fn(usize) -> Sample<'a>,
{
    let (n, m, len) = (data.n, data.m, data.len);
    let ((w_lo, w_hi), (v_lo, v_hi)) = (data.w, data.v);
    // Unknowns: x_0 … x_{len-1}, w_0 … w_{len-2}, t.
    let x_at = |j: usize, i: usize| j * n + i;
    let w_at = |j: usize, i: usize| n * len + j * n + i;
    let t_at = n * (2 * len - 1);
    let nv = t_at + 1;
    let mut cols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); nv];
    let mut b = Vec::new();
    // Dynamics (zero cone): x_{j+1} − A_j x_j − w_j = B_j u_j.
    for j in 0..len.saturating_sub(1) {
        let s = (data.sample)(j);
        for r in 0..n {
            let row = b.len();
            cols[x_at(j + 1, r)].push((row, 1.0));
            for k in 0..n {
                let a = s.a[k * n + r];
                if a != 0.0 {
                    cols[x_at(j, k)].push((row, -a));
                }
            }
            cols[w_at(j, r)].push((row, -1.0));
            b.push(s.bu[r]);
        }
    }
    let equalities = b.len();
    // The process-noise box.
    for j in 0..len.saturating_sub(1) {
        for i in 0..n {
            if w_hi[i].is_finite() {
                cols[w_at(j, i)].push((b.len(), 1.0));
                b.push(w_hi[i]);
            }
            if w_lo[i].is_finite() {
                cols[w_at(j, i)].push((b.len(), -1.0));
                b.push(-w_lo[i]);
            }
        }
    }
    // The measurements: −C x − d t ≤ v_hi − y and C x − d t ≤ y − v_lo.
    for j in 0..len {
        let s = (data.sample)(j);
        if !s.measured {
            continue;
        }
        for i in 0..m {
            if !s.outputs[i] {
                continue;
            }
            let d = (v_hi[i] - v_lo[i]).max(1e-12 * (1.0 + v_lo[i].abs() + v_hi[i].abs()));
            let (r_hi, r_lo) = (b.len(), b.len() + 1);
            for k in 0..n {
                let c = s.c[k * m + i];
                if c != 0.0 {
                    cols[x_at(j, k)].push((r_hi, -c));
                    cols[x_at(j, k)].push((r_lo, c));
                }
            }
            cols[t_at].push((r_hi, -d));
            cols[t_at].push((r_lo, -d));
            b.push(v_hi[i] - s.y[i]);
            b.push(s.y[i] - v_lo[i]);
        }
    }
    cols[t_at].push((b.len(), -1.0));
    b.push(0.0);
    let rows = b.len();
    let a = csc_from_columns(rows, &cols);
    let p = CscMatrix::zeros((nv, nv));
    let mut q = vec![0.0; nv];
    q[t_at] = 1.0;
    let mut cones: Vec<SupportedConeT<f64>> = Vec::new();
    if equalities > 0 {
        cones.push(ZeroConeT(equalities));
    }
    cones.push(NonnegativeConeT(rows - equalities));
    let Ok(settings) = DefaultSettingsBuilder::default().verbose(false).build() else {
        return WindowCheck::Undecided;
    };
    let solved = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings).ok()?;
        solver.solve();
        Some((solver.solution.status, solver.solution.x.get(t_at).copied()))
    }));
    match solved {
        Ok(Some((SolverStatus::Solved | SolverStatus::AlmostSolved, Some(t)))) if t.is_finite() => {
            if t > EXCESS_TOLERANCE { WindowCheck::Inconsistent { excess: t } } else { WindowCheck::Consistent }
        }
        _ => WindowCheck::Undecided,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scalar random walk `x_{j+1} = x_j + w_j`, `|w| ≤ 1`, measured directly with `|v| ≤ 0.5`.
    fn walk(ys: &[f64]) -> WindowCheck {
        let (a, bu, c) = ([1.0], [0.0], [1.0]);
        let samples: Vec<Sample<'_>> = ys
            .iter()
            .map(|y| Sample { a: &a, bu: &bu, c: &c, y: std::slice::from_ref(y), measured: true, outputs: &[true] })
            .collect();
        let data = WindowData {
            n: 1,
            m: 1,
            len: ys.len(),
            sample: |j| samples[j],
            w: (&[-1.0], &[1.0]),
            v: (&[-0.5], &[0.5]),
        };
        check_window(&data)
    }

    #[test]
    fn a_jump_the_boxes_allow_exactly_is_consistent_and_a_larger_one_is_not() {
        // Two measurements 2 apart: |Δx| ≤ 1 and |v| ≤ 0.5 twice allow exactly 2.
        assert_eq!(walk(&[0.0, 2.0]), WindowCheck::Consistent);
        assert_eq!(walk(&[0.0, 1.0, 2.0, 3.0, 4.0]), WindowCheck::Consistent);
        // 2.2 needs V wider by 0.1 on each side: 0.1 of its width 1.
        match walk(&[0.0, 2.2]) {
            WindowCheck::Inconsistent { excess } => assert!((excess - 0.1).abs() < 1e-7, "{excess}"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn the_witness_accepts_residuals_on_the_boundary_and_refuses_beyond() {
        let (a, bu, c) = ([1.0], [0.0], [1.0]);
        let ys = [0.5, 1.5];
        let samples: Vec<Sample<'_>> = ys
            .iter()
            .map(|y| Sample { a: &a, bu: &bu, c: &c, y: std::slice::from_ref(y), measured: true, outputs: &[true] })
            .collect();
        let data =
            WindowData { n: 1, m: 1, len: 2, sample: |j| samples[j], w: (&[-1.0], &[1.0]), v: (&[-0.5], &[0.5]) };
        assert!(witnesses(&data, &[0.0, 1.0]));
        assert!(!witnesses(&data, &[0.0, 0.9]));
    }
}
