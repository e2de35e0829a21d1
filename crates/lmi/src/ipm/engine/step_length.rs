//! Step lengths: the largest step that keeps every block and `τ`, `κ` in their cones.

use super::{State, Workspace};
use crate::ipm::eig::{max_step, max_step_coarse, max_step_pencil};

/// Relative accuracy of the HKM corrector's step length (Cholesky bisection; the step taken is
/// the feasible end of the bracket, so at worst this fraction shorter than the boundary's).
const HKM_STEP_RTOL: f64 = 1.0 / 64.0;

/// Cholesky-test halvings of the predictor's step, which only sets `σ` (step known to within
/// 1/4; three halvings cost more tests and gave no fewer iterations on the filter LMI and SDPLIB).
const PREDICTOR_HALVINGS: u32 = 2;

/// Fraction of the step to the boundary of the cone that is taken.
pub(super) const STEP_FRACTION: f64 = 0.99;

impl Workspace {
    /// Largest `α` keeping `Λ + αΔx̃`, `Λ + αΔỹ`, `τ + αΔτ`, `κ + αΔκ` nonnegative.
    /// With `coarse`, dense blocks use a few Cholesky tests instead of an eigenvalue bracket.
    #[inline(always)]
    pub(super) fn max_step(&mut self, st: &State, cap: f64, coarse: bool) -> Option<f64> {
        let mut alpha = cap;
        if st.dtau < 0.0 {
            alpha = alpha.min(-st.tau / st.dtau);
        }
        if st.dkappa < 0.0 {
            alpha = alpha.min(-st.kappa / st.dkappa);
        }
        for blk in &mut self.blocks {
            let n = blk.n;
            for primal in [true, false] {
                let dir = if primal { &blk.dxs } else { &blk.dys };
                if blk.psd && self.hkm_on {
                    // Cholesky tests of X + αΔX (Y + αΔY) directly; the corrector's step to
                    // within HKM_STEP_RTOL.
                    let base = if primal { &blk.x } else { &blk.y };
                    alpha = if coarse {
                        max_step_pencil(base, dir, &mut blk.tmp2, n, alpha, PREDICTOR_HALVINGS, f64::INFINITY)
                    } else {
                        max_step_pencil(base, dir, &mut blk.tmp2, n, alpha, 0, HKM_STEP_RTOL)
                    };
                } else if blk.psd {
                    for j in 0..n {
                        let sj = blk.lis[j];
                        for i in j..n {
                            blk.tmp[i + j * n] = dir[i + j * n] * sj * blk.lis[i];
                        }
                    }
                    alpha = if coarse {
                        max_step_coarse(&blk.tmp, &mut blk.tmp2, n, alpha, PREDICTOR_HALVINGS)
                    } else {
                        max_step(&mut blk.tmp, &mut blk.tmp2, n, alpha, &mut blk.ev, &mut blk.ee)?
                    };
                } else {
                    for i in 0..n {
                        if dir[i] < 0.0 {
                            alpha = alpha.min(-blk.lam[i] / dir[i]);
                        }
                    }
                }
            }
        }
        if alpha.is_nan() { None } else { Some(alpha) }
    }
}
