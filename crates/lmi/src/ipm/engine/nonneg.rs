//! Nonnegative blocks: their diagonal scaling and Schur contributions, the same for the NT and
//! HKM directions.

use super::super::workspace::BlockWs;

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
