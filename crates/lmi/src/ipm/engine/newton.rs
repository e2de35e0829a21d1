//! One predictor–corrector step: the Newton solves through the factored Schur matrix, the
//! corrector's accuracy check with one step of iterative refinement, and the update. The
//! per-block formulas of each direction are in [`nt`], [`hkm`] and [`nonneg`].

use super::step_length::STEP_FRACTION;
use super::{State, Workspace, Ws, combine, hkm, nonneg, nt, traces};
use crate::ipm::dense;

/// Sentinel returned by `step` when the normal equations lost too much accuracy.
pub(super) const NEED_PRECISION: f64 = -1.0;

/// `‖e₁‖²/‖d_x‖²` (relative residual of the corrector's first equation before refinement, squared)
/// beyond which the QR-based factor is used.
const PRECISION_LOSS: f64 = 1e-6;

impl Workspace {
    /// One predictor–corrector step; returns the step length taken, or `None` on breakdown.
    #[inline(always)]
    pub(super) fn step(&mut self, st: &mut State) -> Option<f64> {
        let m = self.m;
        for i in 0..m {
            let b = self.mhat[i + 1];
            self.cb[i] = self.c[i] + b;
            self.q[i] = b - self.c[i];
        }
        dense::cholesky_solve(&self.lfac, m, &mut self.q);
        // β − (b + c)ᵀq, computed block by block from H = F₀ − A(q) (NT: ‖TᵀHT‖²) instead of by
        // the subtraction (no cancellation).
        self.coef[0] = 1.0;
        for i in 0..m {
            self.coef[i + 1] = -self.q[i];
        }
        st.den0 = 0.0;
        for blk in &mut self.blocks {
            combine((&blk.nz_p1, &blk.nz_p2, &blk.nz_v, &blk.nz_start), &self.coef, &mut blk.tmp2);
            if blk.psd && self.hkm_on {
                hkm::add_tau_term(blk, &mut st.den0);
            } else if blk.psd {
                nt::add_tau_term(blk, &mut st.den0);
            } else {
                nonneg::add_tau_term(blk, &mut st.den0);
            }
        }
        // Predictor (affine scaling): w_s = −Λ.
        for blk in &mut self.blocks {
            if blk.psd && self.hkm_on {
                hkm::affine_rhs(blk);
            } else if blk.psd {
                nt::affine_rhs(blk);
            } else {
                nonneg::affine_rhs(blk);
            }
        }
        let dk = -st.tau * st.kappa;
        self.direction(st, 1.0, dk, Ws::Affine, false)?;
        st.dtau_a = st.dtau;
        st.dkappa_a = st.dkappa;
        for blk in &mut self.blocks {
            blk.dxs_a.copy_from_slice(&blk.dxs);
            blk.dys_a.copy_from_slice(&blk.dys);
        }
        let alpha_a = self.max_step(st, 1.0, true)?;
        let sigma = (1.0 - alpha_a).powi(3).clamp(0.0, 1.0);
        let smu = sigma * st.mu;
        // Corrector: λ ∘ (Δx̃ + Δỹ) = −λ∘λ + σμI − Δx̃ₐ∘Δỹₐ.
        for blk in &mut self.blocks {
            if blk.psd && self.hkm_on {
                hkm::corrector_rhs(blk, smu);
            } else if blk.psd {
                nt::corrector_rhs(blk, smu);
            } else {
                nonneg::corrector_rhs(blk, smu);
            }
        }
        let dk = -st.tau * st.kappa + smu - st.dtau_a * st.dkappa_a;
        self.direction(st, 1.0 - sigma, dk, Ws::Given, true)?;
        if !self.precise && self.loss > PRECISION_LOSS {
            return Some(NEED_PRECISION);
        }
        let alpha = (STEP_FRACTION * self.max_step(st, 1.0 / STEP_FRACTION, false)?).min(1.0);
        // Update: X += α ΔX (ΔX = E), Y += α T Δỹ Tᵀ.
        for i in 0..m {
            self.x[i] += alpha * self.dx[i];
        }
        for blk in &mut self.blocks {
            for (x, e) in blk.x.iter_mut().zip(&blk.e) {
                *x += alpha * e;
            }
            for (y, dy) in blk.y.iter_mut().zip(&blk.dy) {
                *y += alpha * dy;
            }
        }
        st.tau += alpha * st.dtau;
        st.kappa += alpha * st.dkappa;
        if !(st.tau > 0.0 && st.kappa > 0.0) {
            return None;
        }
        Some(alpha)
    }

    /// Computes a search direction for `d_x = −η r_x`, `d_z = −η r_z`, `d_τ = −η r_τ`, the
    /// scaled complementarity `w_s` (`ws`) and `d_κ`. The final (corrector) direction also gets
    /// `ΔY` and, when the equations `(1)` and `(3)` it should satisfy are off by more than a
    /// small fraction of their right-hand side (ill-conditioned Schur matrix near the end), one
    /// step of iterative refinement on the full Newton system.
    #[inline(always)]
    fn direction(&mut self, st: &mut State, eta: f64, dkappa: f64, ws: Ws, last: bool) -> Option<()> {
        let m = self.m;
        for i in 0..m {
            self.rhs[i] = -eta * self.rx[i];
        }
        let dtau_rhs = -eta * st.rtau;
        let (mut dt, mut dk) = self.kkt_solve(st, eta, dtau_rhs, dkappa, ws, last)?;
        if last {
            // Residuals of (1) −A*(ΔY) + cΔτ = d_x and (3) −cᵀΔx + tr(F₀ΔY) − Δκ = d_τ.
            self.tr.fill(0.0);
            for blk in &self.blocks {
                traces(blk, &blk.dy, &mut self.tr);
            }
            let mut e1 = 0.0;
            let mut r1 = 0.0;
            let mut cdx = 0.0;
            for i in 0..m {
                let r = self.rhs[i] + self.tr[i + 1] - self.c[i] * dt;
                r1 += self.rhs[i] * self.rhs[i];
                self.rhs[i] = r;
                e1 += r * r;
                cdx += self.c[i] * self.dx[i];
            }
            let e3 = dtau_rhs + cdx - self.tr[0] + dk;
            self.loss = if r1 > 0.0 { e1 / r1 } else { 0.0 };
            if e1 > 1e-14 * r1 || e3.abs() > 1e-7 * dtau_rhs.abs() {
                self.dx2.copy_from_slice(&self.dx);
                for blk in &mut self.blocks {
                    blk.e2.copy_from_slice(&blk.e);
                    blk.dxs2.copy_from_slice(&blk.dxs);
                    blk.dys2.copy_from_slice(&blk.dys);
                    blk.dy2.copy_from_slice(&blk.dy);
                }
                let (dt2, dk2) = self.kkt_solve(st, 0.0, e3, 0.0, Ws::Zero, true)?;
                dt += dt2;
                dk += dk2;
                for (a, b) in self.dx.iter_mut().zip(&self.dx2) {
                    *a += b;
                }
                for blk in &mut self.blocks {
                    for (a, b) in blk.e.iter_mut().zip(&blk.e2) {
                        *a += b;
                    }
                    for (a, b) in blk.dxs.iter_mut().zip(&blk.dxs2) {
                        *a += b;
                    }
                    for (a, b) in blk.dys.iter_mut().zip(&blk.dys2) {
                        *a += b;
                    }
                    for (a, b) in blk.dy.iter_mut().zip(&blk.dy2) {
                        *a += b;
                    }
                }
            }
        }
        st.dtau = dt;
        st.dkappa = dk;
        Some(())
    }

    /// One solve of the Newton system with `d_x` in `rhs`, `d_z = −η r_z`, `d_τ`, `w_s` as
    /// selected by `ws`, and `d_κ`. Writes `Δx` (`dx`), `ΔX` (`e`), `Δx̃`, `Δỹ` and, if `with_dy`,
    /// `ΔY`; returns `(Δτ, Δκ)`.
    #[inline(always)]
    fn kkt_solve(
        &mut self,
        st: &State,
        eta: f64,
        dtau_rhs: f64,
        dkappa: f64,
        ws: Ws,
        with_dy: bool,
    ) -> Option<(f64, f64)> {
        let m = self.m;
        self.tr.fill(0.0);
        for blk in &mut self.blocks {
            let n = blk.n;
            // G = T w_s Tᵀ + D d_z D.
            match ws {
                Ws::Zero => blk.g.fill(0.0),
                Ws::Given if blk.psd && self.hkm_on => {
                    for (g, (w, r)) in blk.g.iter_mut().zip(blk.ws.iter().zip(&blk.drd)) {
                        *g = w - eta * r;
                    }
                }
                Ws::Affine if blk.psd => {
                    for (g, (y, r)) in blk.g.iter_mut().zip(blk.y.iter().zip(&blk.drd)) {
                        *g = -y - eta * r;
                    }
                }
                _ if !blk.psd => {
                    for i in 0..n {
                        blk.g[i] = blk.d[i] * blk.ws[i] - eta * blk.drd[i];
                    }
                }
                _ => {
                    dense::congruence(&mut blk.g, &mut blk.tmp, &blk.t, &blk.ws, n, false);
                    for (g, r) in blk.g.iter_mut().zip(&blk.drd) {
                        *g -= eta * r;
                    }
                }
            }
            traces(blk, &blk.g, &mut self.tr);
        }
        for i in 0..m {
            self.p[i] = self.rhs[i] + self.tr[i + 1];
        }
        let g0 = self.tr[0];
        dense::cholesky_solve(&self.lfac, m, &mut self.p);
        let cbp = dense::dot(&self.cb, &self.p);
        let num = dtau_rhs + cbp - g0 + dkappa / st.tau;
        let den = st.den0 + st.kappa / st.tau;
        if den.is_nan() || den <= 0.0 || !num.is_finite() {
            return None;
        }
        let dtau = num / den;
        let dkap = (dkappa - st.kappa * dtau) / st.tau;
        for i in 0..m {
            self.dx[i] = self.p[i] + self.q[i] * dtau;
        }
        self.coef[0] = -dtau;
        self.coef[1..].copy_from_slice(&self.dx);
        for blk in &mut self.blocks {
            combine((&blk.nz_p1, &blk.nz_p2, &blk.nz_v, &blk.nz_start), &self.coef, &mut blk.e);
            if eta != 0.0 {
                for (e, r) in blk.e.iter_mut().zip(&blk.rz) {
                    *e += eta * r;
                }
            }
            if blk.psd && self.hkm_on {
                hkm::recover_direction(blk, ws, with_dy);
            } else if blk.psd {
                nt::recover_direction(blk, ws, with_dy);
            } else {
                nonneg::recover_direction(blk, ws, with_dy);
            }
        }
        Some((dtau, dkap))
    }
}
