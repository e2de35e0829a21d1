//! Residuals and termination measures of an iterate, the termination tests, and the outcome
//! written into the caller's solution.

use crate::solver::{SdpSolution, SolveStatus, SolverSettings};

use super::{State, Workspace, combine, traces};
use crate::ipm::dense;

/// Tolerances of one level (strict, or relaxed by `reduced_tol_factor`).
pub(super) struct Tols {
    gap_abs: f64,
    gap_rel: f64,
    feas: f64,
    infeas: f64,
}

impl Tols {
    pub(super) fn new(s: &SolverSettings, factor: f64) -> Self {
        Self {
            gap_abs: s.tol_gap_abs * factor,
            gap_rel: s.tol_gap_rel * factor,
            feas: s.tol_feas * factor,
            infeas: s.tol_infeas * factor,
        }
    }
}

/// `merit ≤ 1` means the strict optimality test passes; `merit ≤ reduced_tol_factor` the relaxed.
pub(super) fn merit(st: &State, tol: &Tols) -> f64 {
    let gap = (st.gap_abs / tol.gap_abs).min(st.gap_rel / tol.gap_rel);
    let m = (st.pres / tol.feas).max(st.dres / tol.feas).max(gap);
    if m.is_nan() { f64::INFINITY } else { m }
}

/// Termination test on the last residual evaluation.
pub(super) fn classify(st: &State, tol: &Tols, relaxed: bool) -> Option<SolveStatus> {
    let finite = st.pobj.is_finite() && st.dobj.is_finite();
    if finite && st.pres <= tol.feas && st.dres <= tol.feas && (st.gap_abs <= tol.gap_abs || st.gap_rel <= tol.gap_rel)
    {
        return Some(if relaxed { SolveStatus::AlmostSolved } else { SolveStatus::Solved });
    }
    if st.pinf <= tol.infeas {
        return Some(if relaxed { SolveStatus::AlmostPrimalInfeasible } else { SolveStatus::PrimalInfeasible });
    }
    if st.dinf <= tol.infeas {
        return Some(if relaxed { SolveStatus::AlmostDualInfeasible } else { SolveStatus::DualInfeasible });
    }
    None
}

impl Workspace {
    /// Residuals, objectives and termination measures of the current iterate.
    #[inline(always)]
    pub(super) fn residuals(&mut self, st: &mut State) {
        let m = self.m;
        // r_z = A(x) − X − F₀τ ; A*(Y).
        self.coef[0] = -st.tau;
        self.coef[1..].copy_from_slice(&self.x);
        self.tr.fill(0.0);
        let mut rz2 = 0.0;
        let mut xy = 0.0;
        let (mut xx, mut yy) = (0.0, 0.0);
        for blk in &mut self.blocks {
            combine((&blk.nz_p1, &blk.nz_p2, &blk.nz_v, &blk.nz_start), &self.coef, &mut blk.rz);
            for (r, x) in blk.rz.iter_mut().zip(&blk.x) {
                *r -= x;
            }
            rz2 += dense::norm2(&blk.rz);
            xy += dense::dot(&blk.x, &blk.y);
            xx += dense::norm2(&blk.x);
            yy += dense::norm2(&blk.y);
        }
        for blk in &mut self.blocks {
            traces(blk, &blk.y, &mut self.tr);
        }
        let mut rx2 = 0.0;
        let mut aty2 = 0.0;
        let mut cx = 0.0;
        for i in 0..m {
            self.rx[i] = -self.tr[i + 1] + self.c[i] * st.tau;
            rx2 += self.rx[i] * self.rx[i];
            aty2 += self.tr[i + 1] * self.tr[i + 1];
            cx += self.c[i] * self.x[i];
        }
        st.rtau = -cx + self.tr[0] - st.kappa;
        st.mu = (xy + st.tau * st.kappa) / (self.nu + 1.0);
        st.pobj = cx / st.tau;
        st.dobj = self.tr[0] / st.tau;
        // Relative residuals as in Clarabel: scaled by the norms of the data and of the point.
        let nx = dense::norm2(&self.x).sqrt() / st.tau;
        st.pres = rz2.sqrt() / st.tau / (st.norm_f0 + nx + xx.sqrt() / st.tau).max(1.0);
        st.dres = rx2.sqrt() / st.tau / (st.norm_c + nx + yy.sqrt() / st.tau).max(1.0);
        st.gap_abs = (st.pobj - st.dobj).abs();
        // The crate's relative gap (`SdpSolution::relative_gap`).
        st.gap_rel = st.gap_abs / (1.0 + st.pobj.abs() + st.dobj.abs());
        st.pinf = if self.tr[0] > 0.0 { aty2.sqrt() / self.tr[0] } else { f64::INFINITY };
        st.dinf = if cx < 0.0 {
            // ‖A(x) − X‖ (only needed for a candidate improving ray).
            self.coef[0] = 0.0;
            let mut dinf_num = 0.0;
            for blk in &mut self.blocks {
                combine((&blk.nz_p1, &blk.nz_p2, &blk.nz_v, &blk.nz_start), &self.coef, &mut blk.tmp);
                for (t, x) in blk.tmp.iter_mut().zip(&blk.x) {
                    *t -= x;
                }
                dinf_num += dense::norm2(&blk.tmp);
            }
            dinf_num.sqrt() / (-cx)
        } else {
            f64::INFINITY
        };
    }

    pub(super) fn write_solution(&self, status: SolveStatus, st: &State, iterations: u32, sol: &mut SdpSolution) {
        sol.status = status;
        sol.iterations = iterations;
        let (xscale, yscale) = match status {
            SolveStatus::PrimalInfeasible | SolveStatus::AlmostPrimalInfeasible => (0.0, 1.0 / self.tr[0]),
            SolveStatus::DualInfeasible | SolveStatus::AlmostDualInfeasible => {
                let cx = dense::dot(&self.c, &self.x);
                (-1.0 / cx, 0.0)
            }
            _ => (1.0 / st.tau, 1.0 / st.tau),
        };
        // A zero scale marks the part that is not the certificate: exactly zero.
        let scaled = |v: f64, scale: f64| if scale == 0.0 { 0.0 } else { v * scale };
        for (s, x) in sol.x.iter_mut().zip(&self.x) {
            *s = scaled(*x, xscale);
        }
        for (dst, blk) in sol.dual.iter_mut().zip(&self.blocks) {
            let out = dst.as_mut_slice();
            if blk.psd {
                for (o, y) in out.iter_mut().zip(&blk.y) {
                    *o = scaled(*y, yscale);
                }
            } else {
                out.fill(0.0);
                for i in 0..blk.n {
                    out[i + i * blk.n] = scaled(blk.y[i], yscale);
                }
            }
        }
        match status {
            SolveStatus::PrimalInfeasible | SolveStatus::AlmostPrimalInfeasible => {
                sol.primal_objective = f64::INFINITY;
                sol.dual_objective = f64::INFINITY;
                sol.primal_residual = f64::NAN;
                sol.dual_residual = st.pinf;
            }
            SolveStatus::DualInfeasible | SolveStatus::AlmostDualInfeasible => {
                sol.primal_objective = f64::NEG_INFINITY;
                sol.dual_objective = f64::NEG_INFINITY;
                sol.primal_residual = st.dinf;
                sol.dual_residual = f64::NAN;
            }
            _ => {
                sol.primal_objective = st.pobj;
                sol.dual_objective = st.dobj;
                sol.primal_residual = st.pres;
                sol.dual_residual = st.dres;
            }
        }
    }
}
