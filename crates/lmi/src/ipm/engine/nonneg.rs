//! Nonnegative blocks: their diagonal scaling, Schur contributions and block formulas of the
//! Newton step, the same for the NT and HKM directions.

use super::Ws;
use crate::ipm::workspace::BlockWs;

/// Schur contributions `Σ_r Fᵢ[r] d_r² Fⱼ[r]` of a nonnegative block (NT and HKM alike).
#[inline(always)]
pub(super) fn assemble_diag(blk: &BlockWs, mhat: &mut [f64], fbuf: &mut [f64], mp: usize) {
    let w = &mut fbuf[..blk.n];
    w.fill(0.0); // the dense path of another block may have left values here
    for j in 0..mp {
        let rj = blk.range(j);
        if rj.is_empty() {
            continue;
        }
        for k in rj.clone() {
            let r = blk.ents[k].row;
            w[r] = blk.val[k] * blk.d[r] * blk.d[r];
        }
        for i in j..mp {
            let mut s = 0.0;
            for k in blk.range(i) {
                s += blk.val[k] * w[blk.ents[k].row];
            }
            mhat[i + j * mp] += s;
        }
        for k in rj {
            w[blk.ents[k].row] = 0.0;
        }
    }
}

/// Diagonal (NT = HKM) scaling of a nonnegative block; `false` if an iterate is not positive.
#[inline(always)]
pub(super) fn scale_diag(blk: &mut BlockWs) -> bool {
    for i in 0..blk.n {
        let (x, y) = (blk.x[i], blk.y[i]);
        if !(x > 0.0 && y > 0.0) {
            return false;
        }
        blk.lam[i] = (x * y).sqrt();
        blk.d[i] = (y / x).sqrt();
        blk.t[i] = blk.d[i].sqrt();
        blk.drd[i] = blk.d[i] * blk.d[i] * blk.rz[i];
    }
    true
}

/// Adds `Σ (dᵢ Hᵢ)²` to `den`, `H = F₀ − A(q)` in `tmp2`: the block's part of the `τ` row's
/// coefficient.
#[inline(always)]
pub(super) fn add_tau_term(blk: &BlockWs, den: &mut f64) {
    for i in 0..blk.n {
        let v = blk.d[i] * blk.tmp2[i];
        *den += v * v;
    }
}

/// The predictor's scaled right-hand side `w_s = −λ`.
#[inline(always)]
pub(super) fn affine_rhs(blk: &mut BlockWs) {
    for i in 0..blk.n {
        blk.ws[i] = -blk.lam[i];
    }
}

/// The corrector's scaled right-hand side `w_s = (−λ∘λ + σμ − Δx̃ₐ∘Δỹₐ) / λ`; `smu = σμ`.
#[inline(always)]
pub(super) fn corrector_rhs(blk: &mut BlockWs, smu: f64) {
    for i in 0..blk.n {
        let r = -blk.lam[i] * blk.lam[i] + smu - blk.dxs_a[i] * blk.dys_a[i];
        blk.ws[i] = r / blk.lam[i];
    }
}

/// From `Δx` (`e`): `Δx̃ = dΔx`, `Δỹ = w_s − Δx̃` and, if `with_dy`, `Δy = dΔỹ`.
#[inline(always)]
pub(super) fn recover_direction(blk: &mut BlockWs, ws: Ws, with_dy: bool) {
    let n = blk.n;
    for i in 0..n {
        blk.dxs[i] = blk.d[i] * blk.e[i];
    }
    if ws == Ws::Zero {
        for (dy, dx) in blk.dys.iter_mut().zip(&blk.dxs) {
            *dy = -dx;
        }
    } else {
        for (dy, (w, dx)) in blk.dys.iter_mut().zip(blk.ws.iter().zip(&blk.dxs)) {
            *dy = w - dx;
        }
    }
    if with_dy {
        for i in 0..n {
            blk.dy[i] = blk.d[i] * blk.dys[i];
        }
    }
}
