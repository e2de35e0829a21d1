//! The closed-form optimal gain (G1) for a fixed `τ`, and `g(τ)` with its gradient and Hessian
//! (the reduction of module [`super::two_multiplier`]); shared by the two-multiplier solver, the
//! fallback and the SDP-backed solver (whose `L` is replaced by this gain).

use nalgebra::DMatrix;

use super::kernels::{Kernels, StepFns};
use super::update::UpdateProblem;

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
    /// The kernels of this size (module [`super::kernels`]).
    pub(crate) fns: StepFns,
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
            fns: StepFns::for_sizes(n, m),
        }
    }

    /// Precomputes the `τ`-independent products `X₁Cᵀ`, `QCᵀ`, `CX₁Cᵀ`, `CQCᵀ`.
    pub(crate) fn load(&mut self, x1: &DMatrix<f64>, q: &DMatrix<f64>, c: &DMatrix<f64>) {
        (self.fns.load)(self, x1, q, c)
    }

    /// [`GainWork::load`] with the kernels `K`.
    pub(crate) fn load_with<K: Kernels>(&mut self, x1: &DMatrix<f64>, q: &DMatrix<f64>, c: &DMatrix<f64>) {
        self.gain_tau = None;
        K::mul_nt_nnm(1.0, x1, c, 0.0, &mut self.x1c);
        K::mul_nt_nnm(1.0, q, c, 0.0, &mut self.qc);
        K::mul_nn_mnm(1.0, c, &self.x1c, 0.0, &mut self.cx1c);
        K::mul_nn_mnm(1.0, c, &self.qc, 0.0, &mut self.cqc);
    }

    /// The gain (G1) for `τ` (after [`GainWork::load`]): fills `G`, `W`, `L`, `K`.
    /// `false` if `S` is not numerically positive definite or something is not finite.
    pub(crate) fn gain(&mut self, tau: [f64; 3], c: &DMatrix<f64>, r: &DMatrix<f64>) -> bool {
        (self.fns.gain)(self, tau, c, r)
    }

    /// [`GainWork::gain`] with the kernels `K`.
    pub(crate) fn gain_with<K: Kernels>(&mut self, tau: [f64; 3], c: &DMatrix<f64>, r: &DMatrix<f64>) -> bool {
        self.gain_tau = None;
        let [t1, t2, t3] = tau;
        let (n, m) = K::dims(self.l.nrows(), self.l.ncols());
        let (nm, mm) = (n * m, m * m);
        // M Cᵀ = X₁Cᵀ/τ₁ + QCᵀ/τ₂ and N = C M Cᵀ without forming M.
        let (x1c, qc) = (&self.x1c.as_slice()[..nm], &self.qc.as_slice()[..nm]);
        dense_kernels::lin2(&mut self.mc.as_mut_slice()[..nm], 1.0 / t1, x1c, 1.0 / t2, qc);
        let (cx1c, cqc) = (&self.cx1c.as_slice()[..mm], &self.cqc.as_slice()[..mm]);
        dense_kernels::lin2(&mut self.nmat.as_mut_slice()[..mm], 1.0 / t1, cx1c, 1.0 / t2, cqc);
        // S = τ₃ N + R = G Gᵀ.
        let (nmat, r) = (&self.nmat.as_slice()[..mm], &r.as_slice()[..mm]);
        dense_kernels::lin2(&mut self.g.as_mut_slice()[..mm], t3, nmat, 1.0, r);
        if K::cholesky_m(&mut self.g).is_err() {
            return false;
        }
        // W = M Cᵀ G⁻ᵀ G⁻¹, L = τ₃ W, K = I − L C.
        self.w.as_mut_slice()[..nm].copy_from_slice(&self.mc.as_slice()[..nm]);
        K::solve_right_lower_t_nm(&mut self.w, &self.g);
        K::solve_right_lower_nm(&mut self.w, &self.g);
        let w = &self.w.as_slice()[..nm];
        dense_kernels::lin2(&mut self.l.as_mut_slice()[..nm], t3, w, 0.0, w);
        K::i_minus_lc(&self.l, c, &mut self.k);
        let finite = w.iter().all(|v| v.is_finite());
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

    /// `g(τ)`, (D1) and (D2) of `pr`'s `X₁`, `Q`, `C`, `R` after [`GainWork::load`]. `None` if the gain fails.
    pub(crate) fn eval(&mut self, tau: [f64; 3], pr: &UpdateProblem<'_>) -> Option<Eval> {
        (self.fns.eval)(self, tau, pr)
    }

    /// [`GainWork::eval`] with the kernels `K`.
    pub(crate) fn eval_with<K: Kernels>(&mut self, tau: [f64; 3], pr: &UpdateProblem<'_>) -> Option<Eval> {
        let UpdateProblem { x1, q, c, r, .. } = *pr;
        if !self.gain_with::<K>(tau, c, r) {
            return None;
        }
        let [t1, t2, t3] = tau;
        let (n, m) = K::dims(self.l.nrows(), self.l.ncols());
        let (nn, nm) = (n * n, n * m);
        let dot = |a: &DMatrix<f64>, b: &DMatrix<f64>, len: usize| {
            dense_kernels::dot(&a.as_slice()[..len], &b.as_slice()[..len])
        };
        // tr T₁ = ⟨K X₁, K⟩/τ₁, tr T₂ = ⟨K Q, K⟩/τ₂, tr(W R Wᵀ) = ⟨W R, W⟩.
        K::mul_nn_nnn(1.0, &self.k, x1, 0.0, &mut self.kx);
        let tr1 = dot(&self.kx, &self.k, nn) / t1;
        K::mul_nn_nnn(1.0, &self.k, q, 0.0, &mut self.kx);
        let tr2 = dot(&self.kx, &self.k, nn) / t2;
        K::mul_nn_nmm(1.0, &self.w, r, 0.0, &mut self.wr);
        let wrw = dot(&self.wr, &self.w, nm);
        let g = tr1 + tr2 + t3 * wrw;
        let grad = [-tr1 / t1, -tr2 / t2, -wrw];
        // βᵢ = ãᵢ G⁻ᵀ.
        K::mul_nn_nnm(1.0 / t1, &self.k, &self.x1c, 0.0, &mut self.b1);
        K::solve_right_lower_t_nm(&mut self.b1, &self.g);
        K::mul_nn_nnm(1.0 / t2, &self.k, &self.qc, 0.0, &mut self.b2);
        K::solve_right_lower_t_nm(&mut self.b2, &self.g);
        self.b3.as_mut_slice()[..nm].copy_from_slice(&self.wr.as_slice()[..nm]);
        K::solve_right_lower_t_nm(&mut self.b3, &self.g); // −β₃
        K::mul_nn_nmm(1.0, &self.w, &self.nmat, 0.0, &mut self.wn);
        K::solve_right_lower_t_nm(&mut self.wn, &self.g);
        let d = |a: &DMatrix<f64>, b: &DMatrix<f64>| dot(a, b, nm);
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
