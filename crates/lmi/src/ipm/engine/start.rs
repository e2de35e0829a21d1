//! Starting points: the default start (as in SDPT3) and the warm start from a stored solution.

use faer::dyn_stack::MemStack;

use crate::ipm::dense;
use crate::ipm::workspace::Workspace;

/// Frobenius norm of `Fᵢ` (all blocks).
fn matrix_norm(ws: &Workspace, i: usize) -> f64 {
    let mut s = 0.0;
    for blk in &ws.blocks {
        for k in blk.range(i) {
            let e = blk.ents[k];
            let f = if e.row == e.col { 1.0 } else { 2.0 };
            s += f * blk.val[k] * blk.val[k];
        }
    }
    s.sqrt()
}

/// `λ` of the warm start: the weight of the previous solution against a multiple of the identity
/// (the carrier's filter steps took 4.0 iterations on average with 0.97 and 0.99, 5.0 with 0.9,
/// against 11–13 from the default start; `docs/sdp.md` §3.7).
pub(crate) const WARM_WEIGHT: f64 = 0.99;

impl Workspace {
    /// Frobenius norm of `F₀`.
    pub(super) fn norm_f0(&self) -> f64 {
        let mut s = 0.0;
        for blk in &self.blocks {
            for k in blk.range(0) {
                let e = blk.ents[k];
                let f = if e.row == e.col { 1.0 } else { 2.0 };
                s += f * blk.val[k] * blk.val[k];
            }
        }
        s.sqrt()
    }

    /// Starting point (as in SDPT3): `x = 0`, `X = ξI`, `Y = ηI` with
    /// `ξ = max(10, √ν, ‖F₀‖, maxᵢ ‖Fᵢ‖)` and `η = max(10, √ν, ν maxᵢ (1 + |cᵢ|)/(1 + ‖Fᵢ‖))`;
    /// `τ = κ = 1`.
    pub(super) fn initialize(&mut self, _stack: &mut MemStack) -> bool {
        let m = self.m;
        let mut fnorm = matrix_norm(self, 0);
        let mut ratio: f64 = 0.0;
        for i in 1..=m {
            let nf = matrix_norm(self, i);
            fnorm = fnorm.max(nf);
            ratio = ratio.max((1.0 + self.c[i - 1].abs()) / (1.0 + nf));
        }
        let root = self.nu.sqrt();
        let xi = 10f64.max(root).max(fnorm);
        let eta = 10f64.max(root).max(self.nu * ratio);
        self.x.fill(0.0);
        for blk in &mut self.blocks {
            blk.x.fill(0.0);
            blk.y.fill(0.0);
            for i in 0..blk.n {
                let k = blk.diag(i);
                blk.x[k] = xi;
                blk.y[k] = eta;
            }
        }
        true
    }

    /// The warm starting point (Skajaa, Andersen and Ye, for the homogeneous embedding), from the
    /// stored solution `(x_w, X_w, Y_w)` of the previous solve: `x = λ x_w`,
    /// `X = λ X_w + (1 − λ) ξ_w I`, `Y = λ Y_w + (1 − λ) η_w I`, `τ = 1`, with `λ` =
    /// [`WARM_WEIGHT`] and `ξ_w`, `η_w` the mean eigenvalues of `X_w`, `Y_w` (`tr/ν`: the default
    /// start's `ξ`, `η` can be orders of magnitude larger than the solution, which would undo the
    /// warm start). Returns `κ = ⟨X, Y⟩/ν`, so that `τκ` is the start's `μ`.
    pub(super) fn warm_point(&mut self) -> f64 {
        let lam = WARM_WEIGHT;
        let (mut tx, mut ty) = (0.0, 0.0);
        for blk in &self.blocks {
            tx += blk.trace(&blk.warm_x);
            ty += blk.trace(&blk.warm_y);
        }
        // A stored solution has positive traces; keep the default start's shift otherwise.
        let shift = |t: f64, cold: f64| if t > 0.0 && t.is_finite() { t } else { cold };
        for (x, w) in self.x.iter_mut().zip(&self.warm_xv) {
            *x = lam * w;
        }
        let mut xy = 0.0;
        for blk in &mut self.blocks {
            // The default start is a multiple of the identity: read its scale before overwriting.
            let (xi, eta) = (blk.x[blk.diag(0)], blk.y[blk.diag(0)]);
            let (xs, ys) = ((1.0 - lam) * shift(tx / self.nu, xi), (1.0 - lam) * shift(ty / self.nu, eta));
            for (x, w) in blk.x.iter_mut().zip(&blk.warm_x) {
                *x = lam * w;
            }
            for (y, w) in blk.y.iter_mut().zip(&blk.warm_y) {
                *y = lam * w;
            }
            for i in 0..blk.n {
                let k = blk.diag(i);
                blk.x[k] += xs;
                blk.y[k] += ys;
            }
            xy += dense::dot(&blk.x, &blk.y);
        }
        xy / self.nu
    }
}
