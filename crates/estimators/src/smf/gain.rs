//! The closed-form optimal gain (G1) for a fixed `τ`, and `g(τ)` with its gradient and Hessian
//! (the reduction of module [`super::two_multiplier`]); shared by the two-multiplier solver, the
//! fallback and the SDP-backed solver (whose `L` is replaced by this gain).

use nalgebra::DMatrix;

/// Value, gradient and Hessian of `g` on the positive orthant, at one `τ`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Eval {
    pub g: f64,
    pub grad: [f64; 3],
    pub hess: [[f64; 3]; 3],
}

/// Buffers for the closed-form gain (G1) and for `g`, its gradient and Hessian.
#[derive(Debug, Clone)]
pub(crate) struct GainWork {
    x1c: DMatrix<f64>,
    qc: DMatrix<f64>,
    cx1c: DMatrix<f64>,
    cqc: DMatrix<f64>,
    mc: DMatrix<f64>,
    nmat: DMatrix<f64>,
    /// `S`, then its Cholesky factor `G`.
    g: DMatrix<f64>,
    w: DMatrix<f64>,
    /// The gain `L = τ₃ W` of the last evaluation.
    pub l: DMatrix<f64>,
    k: DMatrix<f64>,
    kx: DMatrix<f64>,
    wr: DMatrix<f64>,
    b1: DMatrix<f64>,
    b2: DMatrix<f64>,
    b3: DMatrix<f64>,
    wn: DMatrix<f64>,
    /// The `τ` (bits) whose gain `l`, `k` hold, after a successful [`GainWork::gain`] on the
    /// data of the last [`GainWork::load`].
    gain_tau: Option<[u64; 3]>,
}

impl GainWork {
    pub(crate) fn new(n: usize, m: usize) -> Self {
        let nm = || DMatrix::zeros(n, m);
        let mm = || DMatrix::zeros(m, m);
        Self {
            x1c: nm(),
            qc: nm(),
            cx1c: mm(),
            cqc: mm(),
            mc: nm(),
            nmat: mm(),
            g: mm(),
            w: nm(),
            l: nm(),
            k: DMatrix::zeros(n, n),
            kx: DMatrix::zeros(n, n),
            wr: nm(),
            b1: nm(),
            b2: nm(),
            b3: nm(),
            wn: nm(),
            gain_tau: None,
        }
    }

    /// Precomputes the `τ`-independent products `X₁Cᵀ`, `QCᵀ`, `CX₁Cᵀ`, `CQCᵀ`.
    pub(crate) fn load(&mut self, x1: &DMatrix<f64>, q: &DMatrix<f64>, c: &DMatrix<f64>) {
        self.gain_tau = None;
        dense_kernels::mul_nt(1.0, x1, c, 0.0, &mut self.x1c);
        dense_kernels::mul_nt(1.0, q, c, 0.0, &mut self.qc);
        dense_kernels::mul_nn(1.0, c, &self.x1c, 0.0, &mut self.cx1c);
        dense_kernels::mul_nn(1.0, c, &self.qc, 0.0, &mut self.cqc);
    }

    /// The gain (G1) for `τ` (after [`GainWork::load`]): fills `G`, `W`, `L`, `K`.
    /// `false` if `S` is not numerically positive definite or something is not finite.
    pub(crate) fn gain(&mut self, tau: [f64; 3], c: &DMatrix<f64>, r: &DMatrix<f64>) -> bool {
        self.gain_tau = None;
        let [t1, t2, t3] = tau;
        // M Cᵀ = X₁Cᵀ/τ₁ + QCᵀ/τ₂ and N = C M Cᵀ without forming M.
        dense_kernels::lin2(self.mc.as_mut_slice(), 1.0 / t1, self.x1c.as_slice(), 1.0 / t2, self.qc.as_slice());
        dense_kernels::lin2(self.nmat.as_mut_slice(), 1.0 / t1, self.cx1c.as_slice(), 1.0 / t2, self.cqc.as_slice());
        // S = τ₃ N + R = G Gᵀ.
        dense_kernels::lin2(self.g.as_mut_slice(), t3, self.nmat.as_slice(), 1.0, r.as_slice());
        if dense_kernels::cholesky_in_place(&mut self.g).is_err() {
            return false;
        }
        // W = M Cᵀ G⁻ᵀ G⁻¹, L = τ₃ W, K = I − L C.
        self.w.copy_from(&self.mc);
        dense_kernels::solve_right_lower_t(&mut self.w, &self.g);
        dense_kernels::solve_right_lower(&mut self.w, &self.g);
        dense_kernels::lin2(self.l.as_mut_slice(), t3, self.w.as_slice(), 0.0, self.w.as_slice());
        dense_kernels::i_minus_lc(&self.l, c, &mut self.k);
        let finite = self.w.as_slice().iter().all(|v| v.is_finite());
        if finite {
            self.gain_tau = Some(tau.map(f64::to_bits));
        }
        finite
    }

    /// Whether `l`, `k` already hold the gain for exactly this `τ` (same data, same `R`: the
    /// caller passes the `R` of the last load throughout).
    pub(crate) fn has_gain_for(&self, tau: [f64; 3]) -> bool {
        self.gain_tau == Some(tau.map(f64::to_bits))
    }

    /// `g(τ)`, (D1) and (D2) after [`GainWork::load`]. `None` if the gain fails.
    pub(crate) fn eval(
        &mut self,
        tau: [f64; 3],
        x1: &DMatrix<f64>,
        q: &DMatrix<f64>,
        c: &DMatrix<f64>,
        r: &DMatrix<f64>,
    ) -> Option<Eval> {
        if !self.gain(tau, c, r) {
            return None;
        }
        let [t1, t2, t3] = tau;
        // tr T₁ = ⟨K X₁, K⟩/τ₁, tr T₂ = ⟨K Q, K⟩/τ₂, tr(W R Wᵀ) = ⟨W R, W⟩.
        dense_kernels::mul_nn(1.0, &self.k, x1, 0.0, &mut self.kx);
        let tr1 = dense_kernels::dot(self.kx.as_slice(), self.k.as_slice()) / t1;
        dense_kernels::mul_nn(1.0, &self.k, q, 0.0, &mut self.kx);
        let tr2 = dense_kernels::dot(self.kx.as_slice(), self.k.as_slice()) / t2;
        dense_kernels::mul_nn(1.0, &self.w, r, 0.0, &mut self.wr);
        let wrw = dense_kernels::dot(self.wr.as_slice(), self.w.as_slice());
        let g = tr1 + tr2 + t3 * wrw;
        let grad = [-tr1 / t1, -tr2 / t2, -wrw];
        // βᵢ = ãᵢ G⁻ᵀ.
        dense_kernels::mul_nn(1.0 / t1, &self.k, &self.x1c, 0.0, &mut self.b1);
        dense_kernels::solve_right_lower_t(&mut self.b1, &self.g);
        dense_kernels::mul_nn(1.0 / t2, &self.k, &self.qc, 0.0, &mut self.b2);
        dense_kernels::solve_right_lower_t(&mut self.b2, &self.g);
        self.b3.copy_from(&self.wr);
        dense_kernels::solve_right_lower_t(&mut self.b3, &self.g); // −β₃
        dense_kernels::mul_nn(1.0, &self.w, &self.nmat, 0.0, &mut self.wn);
        dense_kernels::solve_right_lower_t(&mut self.wn, &self.g);
        let d = |a: &DMatrix<f64>, b: &DMatrix<f64>| dense_kernels::dot(a.as_slice(), b.as_slice());
        let h11 = 2.0 * (tr1 - t3 * d(&self.b1, &self.b1)) / (t1 * t1);
        let h22 = 2.0 * (tr2 - t3 * d(&self.b2, &self.b2)) / (t2 * t2);
        let h12 = -2.0 * t3 * d(&self.b1, &self.b2) / (t1 * t2);
        let h13 = 2.0 * d(&self.b1, &self.b3) / t1;
        let h23 = 2.0 * d(&self.b2, &self.b3) / t2;
        let h33 = 2.0 * d(&self.wn, &self.b3);
        let hess = [[h11, h12, h13], [h12, h22, h23], [h13, h23, h33]];
        if !g.is_finite() || grad.iter().chain(hess.iter().flatten()).any(|v| !v.is_finite()) {
            return None;
        }
        Some(Eval { g, grad, hess })
    }
}
