//! Factor of the Schur matrix: Cholesky with a small diagonal shift on failure, or, in precision
//! mode, `Rᵀ` from a Householder QR of the scaled constraint matrix.

use faer::dyn_stack::MemStack;

use crate::ipm::dense;
use crate::ipm::workspace::{Ent, Workspace};

impl Workspace {
    /// Cholesky of the `m × m` Schur matrix, with a tiny diagonal shift on failure.
    #[inline(always)]
    pub(super) fn factor_schur(&mut self, stack: &mut MemStack) -> bool {
        let m = self.m;
        let mp = m + 1;
        if m == 0 {
            return true;
        }
        let mut maxdiag: f64 = 0.0;
        for i in 0..m {
            maxdiag = maxdiag.max(self.mhat[(i + 1) * (mp + 1)]);
        }
        for reg in [0.0, 1e-13, 1e-10] {
            for j in 0..m {
                for i in j..m {
                    self.lfac[i + j * m] = self.mhat[(i + 1) + (j + 1) * mp];
                }
                self.lfac[j + j * m] += reg * maxdiag.max(1e-300);
            }
            if dense::cholesky(&mut self.lfac, m, stack) {
                return true;
            }
        }
        false
    }

    /// Factor `Rᵀ` of `M = RᵀR` from a Householder QR of the scaled constraint matrix
    /// `[svec(TᵀFᵢT)]ᵢ` (condition number `√cond(M)`), stored like the Cholesky factor.
    pub(super) fn factor_qr(&mut self, stack: &mut MemStack) -> bool {
        let m = self.m;
        let rows = self.ls_rows;
        if m == 0 {
            return true;
        }
        self.ls.fill(0.0);
        let mut off = 0;
        for blk in &mut self.blocks {
            let n = blk.n;
            if !blk.psd {
                for i in 1..=m {
                    let col = &mut self.ls[(i - 1) * rows + off..(i - 1) * rows + off + n];
                    for k in blk.range(i) {
                        let r = blk.ents[k].row;
                        col[r] += blk.val[k] * blk.d[r];
                    }
                }
                off += n;
                continue;
            }
            // Rows of T, contiguous.
            for a in 0..n {
                for p in 0..n {
                    blk.tmp2[a * n + p] = blk.t[a + p * n];
                }
            }
            let len = n * (n + 1) / 2;
            for i in 1..=m {
                let col = &mut self.ls[(i - 1) * rows + off..(i - 1) * rows + off + len];
                for k in blk.range(i) {
                    let Ent { row: a, col: b } = blk.ents[k];
                    let v = blk.val[k];
                    let ta = &blk.tmp2[a * n..a * n + n];
                    let tb = &blk.tmp2[b * n..b * n + n];
                    let mut idx = 0;
                    for q in 0..n {
                        for p in q..n {
                            let x = if a == b { ta[p] * ta[q] } else { ta[p] * tb[q] + tb[p] * ta[q] };
                            col[idx] += v * x * if p == q { 1.0 } else { std::f64::consts::SQRT_2 };
                            idx += 1;
                        }
                    }
                }
            }
            off += len;
        }
        dense::qr(&mut self.ls, rows, m, &mut self.qcoef, self.qr_bs, stack);
        let mut rmax: f64 = 0.0;
        for j in 0..m {
            rmax = rmax.max(self.ls[j + j * rows].abs());
        }
        for j in 0..m {
            let d = self.ls[j + j * rows];
            if !d.is_finite() || d.abs() <= 1e-15 * rmax {
                return false;
            }
            for i in j..m {
                self.lfac[i + j * m] = self.ls[j + i * rows];
            }
        }
        true
    }
}
