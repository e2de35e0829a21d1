//! The window problem of [`NonlinearMhe`](super::NonlinearMhe): the samples it reads (rings),
//! its cost, the linearisation, and the block-tridiagonal Gauss–Newton system with its block
//! Cholesky factorisation and solve.
//!
//! With `d_j = x_{j+1} − f_j`, `e_j = y_j − h_j`, `A_j = ∂f/∂x`, `C_j = ∂h/∂x` at the states
//! `x_0 … x_{L−1}` of the window, half the gradient of the cost is
//!
//! ```text
//! g_j = [j = 0] P_s⁻¹ (x_0 − x̄_s) + [j > 0] Q⁻¹ d_{j−1} − A_jᵀ Q⁻¹ d_j − C_jᵀ R⁻¹ e_j
//! ```
//!
//! and the Gauss–Newton matrix is block tridiagonal: diagonal blocks
//! `D_j = [j = 0] P_s⁻¹ + [j > 0] Q⁻¹ + A_jᵀ Q⁻¹ A_j + C_jᵀ R⁻¹ C_j` (terms of samples that exist),
//! below them `O_j = −Q⁻¹ A_j`.

use nalgebra::{DMatrix, DVector};

use dense_kernels as dense;
use models::DifferentiableModel;

use crate::error::EstimatorError;

/// The last `N + 2` samples by absolute index `k` at slot `k mod (N + 2)`: the input `u_k` of the
/// transition `k → k + 1`, the measurement `y_k` if one was taken, and the input passed with it
/// (for `h`).
#[derive(Debug, Clone)]
pub(super) struct Rings {
    pub(super) u: Vec<DVector<f64>>,
    pub(super) y: Vec<DVector<f64>>,
    pub(super) uh: Vec<DVector<f64>>,
    pub(super) has_y: Vec<bool>,
    /// A partial measurement (some outputs only): its mask (`m` per slot, in `mask`) and its
    /// weight `W = (R_SS)⁻¹` embedded in `m × m` (zero rows and columns for the others), which
    /// replaces `R⁻¹` for that sample; the unmeasured entries of `y` are 0.
    pub(super) partial: Vec<bool>,
    pub(super) mask: Vec<bool>,
    pub(super) w: Vec<DMatrix<f64>>,
}

impl Rings {
    /// Rings of `cap` slots for `p` inputs and `m` outputs, without measurements.
    pub(super) fn new(cap: usize, p: usize, m: usize) -> Self {
        Self {
            u: vec![DVector::zeros(p); cap],
            y: vec![DVector::zeros(m); cap],
            uh: vec![DVector::zeros(p); cap],
            has_y: vec![false; cap],
            partial: vec![false; cap],
            mask: vec![true; cap * m],
            w: vec![DMatrix::zeros(m, m); cap],
        }
    }

    /// The slot of sample `k`.
    pub(super) fn slot(&self, k: usize) -> usize {
        k % self.has_y.len()
    }

    /// The measurement weight of the sample at slot `sl`: `r_inv`, or a partial one's `W`.
    pub(super) fn weight<'a>(&'a self, sl: usize, r_inv: &'a DMatrix<f64>) -> &'a DMatrix<f64> {
        if self.partial[sl] { &self.w[sl] } else { r_inv }
    }

    /// The mask of a partial measurement at slot `sl` (`None`: every output, or none).
    pub(super) fn measured(&self, sl: usize) -> Option<&[bool]> {
        let m = self.y[sl].len();
        self.partial[sl].then(|| &self.mask[sl * m..(sl + 1) * m])
    }
}

/// The weights of the window cost and the arrival prior `(x̄_s, P_s⁻¹)` of its first state.
#[derive(Debug, Clone, Copy)]
pub(super) struct Weights<'a> {
    pub(super) q_inv: &'a DMatrix<f64>,
    pub(super) r_inv: &'a DMatrix<f64>,
    pub(super) prior_mean: &'a DVector<f64>,
    pub(super) prior_inv: &'a DMatrix<f64>,
}

/// The samples one window solve reads: `len` of the rings' slots from sample `start`, and the
/// weights of its cost.
#[derive(Debug, Clone, Copy)]
pub(super) struct Span<'a> {
    pub(super) rings: &'a Rings,
    pub(super) wts: Weights<'a>,
    pub(super) start: usize,
    pub(super) len: usize,
}

/// The Gauss–Newton iterate of a window of up to `N + 1` states and its buffers (allocated once).
#[derive(Debug, Clone)]
pub(super) struct Window {
    n: usize,
    /// The iterate `x_0 … x_{L−1}`.
    pub(super) x: Vec<DVector<f64>>,
    x_trial: Vec<DVector<f64>>,
    /// `A_j`, `C_j` at the iterate.
    pub(super) a: Vec<DMatrix<f64>>,
    pub(super) c: Vec<DMatrix<f64>>,
    /// `f(x_j, u_j)` and `h(x_j, u_j)` of the last cost or linearisation.
    pub(super) fx: Vec<DVector<f64>>,
    pub(super) hx: Vec<DVector<f64>>,
    /// The diagonal blocks `D_j`, after factorisation the block Cholesky factors `L_j`.
    pub(super) d: Vec<DMatrix<f64>>,
    /// `W_j = O_{j−1} L_{j−1}⁻ᵀ`.
    w: Vec<DMatrix<f64>>,
    /// Half the gradient, `g_j`.
    pub(super) g: Vec<DVector<f64>>,
    /// The step `Δ_j`.
    pub(super) step: Vec<DVector<f64>>,
    tmp_n: DVector<f64>,
    tmp_n2: DVector<f64>,
    tmp_m: DVector<f64>,
    tmp_m2: DVector<f64>,
    tmp_nm: DMatrix<f64>,
    tmp_nn: DMatrix<f64>,
}

/// `xᵀ A x`.
fn quad(a: &DMatrix<f64>, x: &DVector<f64>) -> f64 {
    let n = x.len();
    let mut s = 0.0;
    for c in 0..n {
        for r in 0..n {
            s += x[r] * a[(r, c)] * x[c];
        }
    }
    s
}

/// `max_j ‖v_j‖∞`, at least `floor`.
fn max_abs(v: &[DVector<f64>], floor: f64) -> f64 {
    v.iter().fold(floor, |a, s| a.max(s.amax()))
}

impl Window {
    /// Buffers for `n` states, `m` outputs and windows of up to `len_max` states.
    pub(super) fn new(n: usize, m: usize, len_max: usize) -> Self {
        let vn = |k: usize| vec![DVector::zeros(k); len_max];
        Self {
            n,
            x: vn(n),
            x_trial: vn(n),
            a: vec![DMatrix::zeros(n, n); len_max],
            c: vec![DMatrix::zeros(m, n); len_max],
            fx: vn(n),
            hx: vn(m),
            d: vec![DMatrix::zeros(n, n); len_max],
            w: vec![DMatrix::zeros(n, n); len_max],
            g: vn(n),
            step: vn(n),
            tmp_n: DVector::zeros(n),
            tmp_n2: DVector::zeros(n),
            tmp_m: DVector::zeros(m),
            tmp_m2: DVector::zeros(m),
            tmp_nm: DMatrix::zeros(n, m),
            tmp_nn: DMatrix::zeros(n, n),
        }
    }

    /// The window cost at the iterate (`trial`: at `x + Δ` set by [`Window::set_trial`]) of the
    /// window of `len` states starting at sample `start`, evaluating `f`, `h` into `fx`, `hx`.
    pub(super) fn cost<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        span: &Span<'_>,
        trial: bool,
    ) -> Result<f64, EstimatorError> {
        let Span { rings, wts, start, len } = *span;
        let xs = if trial { &self.x_trial } else { &self.x };
        let mut total = 0.0;
        self.tmp_n.copy_from(&xs[0]);
        self.tmp_n -= wts.prior_mean;
        total += quad(wts.prior_inv, &self.tmp_n);
        for j in 0..len {
            let sl = rings.slot(start + j);
            if j + 1 < len {
                model.f(&xs[j], &rings.u[sl], &mut self.fx[j])?;
                self.tmp_n.copy_from(&xs[j + 1]);
                self.tmp_n -= &self.fx[j];
                total += quad(wts.q_inv, &self.tmp_n);
            }
            if rings.has_y[sl] {
                model.h(&xs[j], &rings.uh[sl], &mut self.hx[j])?;
                self.tmp_m.copy_from(&rings.y[sl]);
                self.tmp_m -= &self.hx[j];
                model.angles().wrap_outputs(self.tmp_m.as_mut_slice());
                total += quad(rings.weight(sl, wts.r_inv), &self.tmp_m);
            }
        }
        Ok(total)
    }

    /// Jacobians `A_j`, `C_j`, residuals and the gradient `g` at the iterate (the blocks `D_j`
    /// are built by [`Window::factor_and_solve`]).
    pub(super) fn linearise<M: DifferentiableModel + ?Sized>(
        &mut self,
        model: &M,
        span: &Span<'_>,
    ) -> Result<(), EstimatorError> {
        let Span { rings, wts, start, len } = *span;
        for j in 0..len {
            let sl = rings.slot(start + j);
            if j + 1 < len {
                model.f_with_jacobian(&self.x[j], &rings.u[sl], &mut self.fx[j], &mut self.a[j])?;
            }
            if rings.has_y[sl] {
                model.h_with_jacobian(&self.x[j], &rings.uh[sl], &mut self.hx[j], &mut self.c[j])?;
            }
        }
        // g_j = ∂Φ/∂x_j / 2.
        for j in 0..len {
            self.g[j].fill(0.0);
        }
        self.tmp_n.copy_from(&self.x[0]);
        self.tmp_n -= wts.prior_mean;
        dense::gemv(1.0, wts.prior_inv, &self.tmp_n, 1.0, &mut self.g[0]);
        for j in 0..len {
            let sl = rings.slot(start + j);
            if j + 1 < len {
                // d_j = x_{j+1} − f_j; g_{j+1} += Q⁻¹ d_j; g_j −= A_jᵀ Q⁻¹ d_j.
                self.tmp_n.copy_from(&self.x[j + 1]);
                self.tmp_n -= &self.fx[j];
                self.tmp_n2.gemv(1.0, wts.q_inv, &self.tmp_n, 0.0);
                self.g[j + 1] += &self.tmp_n2;
                self.g[j].gemv_tr(-1.0, &self.a[j], &self.tmp_n2, 1.0);
            }
            if rings.has_y[sl] {
                self.tmp_m.copy_from(&rings.y[sl]);
                self.tmp_m -= &self.hx[j];
                model.angles().wrap_outputs(self.tmp_m.as_mut_slice());
                self.tmp_m2.gemv(1.0, rings.weight(sl, wts.r_inv), &self.tmp_m, 0.0);
                self.g[j].gemv_tr(-1.0, &self.c[j], &self.tmp_m2, 1.0);
            }
        }
        Ok(())
    }

    /// The diagonal blocks `D_j + μ I` of the Gauss–Newton matrix into `d` (the off-diagonal
    /// blocks are `O_j = −Q⁻¹ A_j`, below the diagonal).
    pub(super) fn build_blocks(&mut self, span: &Span<'_>, mu: f64) {
        let Span { rings, wts, start, len } = *span;
        let n = self.n;
        for j in 0..len {
            let sl = rings.slot(start + j);
            let dj = &mut self.d[j];
            dj.fill(0.0);
            if j == 0 {
                *dj += wts.prior_inv;
            }
            if j > 0 {
                *dj += wts.q_inv;
            }
            if j + 1 < len {
                dense::mul_nn(1.0, wts.q_inv, &self.a[j], 0.0, &mut self.tmp_nn);
                dj.gemm_tr(1.0, &self.a[j], &self.tmp_nn, 1.0);
            }
            if rings.has_y[sl] {
                self.tmp_nm.gemm_tr(1.0, &self.c[j], rings.weight(sl, wts.r_inv), 0.0);
                dense::mul_nn(1.0, &self.tmp_nm, &self.c[j], 1.0, dj);
            }
            for i in 0..n {
                dj[(i, i)] += mu;
            }
        }
    }

    /// Builds `D_j + μ I`, factorises by block Cholesky and solves `H Δ = −g` into `step`
    /// ([`Window::factor_and_back_substitute`]). False if a pivot block is not positive definite.
    pub(super) fn factor_and_solve(&mut self, span: &Span<'_>, mu: f64) -> bool {
        self.build_blocks(span, mu);
        self.factor_and_back_substitute(span.wts.q_inv, span.len)
    }

    /// Block Cholesky of the matrix whose diagonal blocks are in `d` and whose off-diagonal
    /// blocks are `O_j = −Q⁻¹ A_j` (`d` receives the factors `L_j`, `w` the blocks
    /// `W_j = O_{j−1} L_{j−1}⁻ᵀ`), and the solve of `H Δ = −g` into `step`. False if a pivot
    /// block is not positive definite to working precision or the step is not finite.
    pub(super) fn factor_and_back_substitute(&mut self, q_inv: &DMatrix<f64>, len: usize) -> bool {
        let n = self.n;
        // S_0 = D_0; S_j = D_j − W_j W_jᵀ, W_j = O_{j−1} L_{j−1}⁻ᵀ, O_{j−1} = −Q⁻¹ A_{j−1}.
        for j in 0..len {
            if j > 0 {
                dense::mul_nn(-1.0, q_inv, &self.a[j - 1], 0.0, &mut self.w[j]);
                dense::solve_right_lower_t(&mut self.w[j], &self.d[j - 1]);
                let (wj, dj) = (&self.w[j], &mut self.d[j]);
                dense::mul_nt(-1.0, wj, wj, 1.0, dj);
            }
            dense::symmetrize(&mut self.d[j]);
            if dense::cholesky_in_place(&mut self.d[j]).is_err() {
                return false;
            }
        }
        // Forward: y_j = L_j⁻¹ (−g_j − W_j y_{j−1}); backward: Δ_j = L_j⁻ᵀ (y_j − W_{j+1}ᵀ Δ_{j+1}).
        for j in 0..len {
            self.step[j].copy_from(&self.g[j]);
            self.step[j].neg_mut();
            if j > 0 {
                let (prev, cur) = self.step.split_at_mut(j);
                cur[0].gemv(-1.0, &self.w[j], &prev[j - 1], 1.0);
            }
            dense::solve_lower(self.d[j].as_slice(), n, self.step[j].as_mut_slice());
        }
        for j in (0..len).rev() {
            if j + 1 < len {
                let (cur, next) = self.step.split_at_mut(j + 1);
                cur[j].gemv_tr(-1.0, &self.w[j + 1], &next[0], 1.0);
            }
            dense::solve_lower_t(self.d[j].as_slice(), n, self.step[j].as_mut_slice());
        }
        self.step[..len].iter().all(|s| s.iter().all(|v| v.is_finite()))
    }

    /// The largest `|D_j,ii|` (at least `1e−12`): the scale of the Levenberg–Marquardt damping.
    pub(super) fn max_diag(&self, len: usize) -> f64 {
        self.d[..len].iter().fold(1e-12_f64, |a, d| (0..self.n).fold(a, |a, i| a.max(d[(i, i)].abs())))
    }

    /// The step's relative size `‖Δ‖∞ / max(1, ‖x‖∞)`.
    pub(super) fn step_ratio(&self, len: usize) -> f64 {
        max_abs(&self.step[..len], 0.0) / max_abs(&self.x[..len], 1.0)
    }

    /// Whether the step is negligible: `‖Δ‖∞ ≤ tolerance · max(1, ‖x‖∞)`.
    pub(super) fn step_is_negligible(&self, len: usize, tolerance: f64) -> bool {
        max_abs(&self.step[..len], 0.0) <= tolerance * max_abs(&self.x[..len], 1.0)
    }

    /// `x ← x + Δ`.
    pub(super) fn apply_step(&mut self, len: usize) {
        for j in 0..len {
            self.x[j] += &self.step[j];
        }
    }

    /// The trial point `x + Δ`, for [`Window::cost`] with `trial`.
    pub(super) fn set_trial(&mut self, len: usize) {
        for j in 0..len {
            self.x_trial[j].copy_from(&self.x[j]);
            self.x_trial[j] += &self.step[j];
        }
    }

    /// Makes the trial point the iterate.
    pub(super) fn accept_trial(&mut self, len: usize) {
        for j in 0..len {
            std::mem::swap(&mut self.x[j], &mut self.x_trial[j]);
        }
    }

    /// Whether every state of the iterate is finite.
    pub(super) fn is_finite(&self, len: usize) -> bool {
        self.x[..len].iter().all(|x| x.iter().all(|v| v.is_finite()))
    }

    /// The last diagonal block of `H⁻¹`, `(L_last L_lastᵀ)⁻¹`, from the block Cholesky factor.
    pub(super) fn last_covariance(&self, len: usize, out: &mut DMatrix<f64>) {
        dense::cholesky_inverse(self.d[len - 1].as_slice(), self.n, out.as_mut_slice());
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use models::{ConstantModel, DiscreteModel, LinearModel};

    use dense_kernels::test_data::centred_matrix as rand;

    fn spd(n: usize, seed: u64) -> DMatrix<f64> {
        dense_kernels::test_data::spd_matrix(n, seed, 0.5)
    }

    /// A window of `len` states of a random linear model (`n = 3`, `m = 2`, one input) with
    /// measurements at every sample but the second, its weights and a random iterate.
    pub(in crate::mhe::nonlinear) struct Case {
        pub(in crate::mhe::nonlinear) model: ConstantModel,
        pub(in crate::mhe::nonlinear) rings: Rings,
        pub(in crate::mhe::nonlinear) q_inv: DMatrix<f64>,
        pub(in crate::mhe::nonlinear) r_inv: DMatrix<f64>,
        pub(in crate::mhe::nonlinear) prior_mean: DVector<f64>,
        pub(in crate::mhe::nonlinear) prior_inv: DMatrix<f64>,
        pub(in crate::mhe::nonlinear) window: Window,
        pub(in crate::mhe::nonlinear) start: usize,
        pub(in crate::mhe::nonlinear) len: usize,
    }

    impl Case {
        pub(in crate::mhe::nonlinear) fn new(len: usize) -> Self {
            let (n, m) = (3, 2);
            let model = ConstantModel::new(
                DMatrix::identity(n, n) + rand(n, n, 1) * 0.4,
                rand(n, 1, 2),
                rand(m, n, 3) + DMatrix::from_row_slice(m, n, &[1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
            )
            .unwrap();
            let (start, cap) = (5, len + 1);
            let mut rings = Rings::new(cap, 1, m);
            for j in 0..len {
                let sl = rings.slot(start + j);
                rings.u[sl] = rand(1, 1, 10 + j as u64).column(0).into();
                rings.uh[sl] = rand(1, 1, 20 + j as u64).column(0).into();
                rings.y[sl] = rand(m, 1, 30 + j as u64).column(0).into();
                rings.has_y[sl] = j != 1;
            }
            let mut window = Window::new(n, m, len);
            for j in 0..len {
                window.x[j] = rand(n, 1, 40 + j as u64).column(0).into();
            }
            Self {
                model,
                rings,
                q_inv: spd(n, 4),
                r_inv: spd(m, 5),
                prior_mean: rand(n, 1, 6).column(0).into(),
                prior_inv: spd(n, 7),
                window,
                start,
                len,
            }
        }

        /// The window, the rings, the weights and the model, borrowed apart.
        pub(in crate::mhe::nonlinear) fn parts(&mut self) -> (&mut Window, &Rings, Weights<'_>, &ConstantModel) {
            let wts = Weights {
                q_inv: &self.q_inv,
                r_inv: &self.r_inv,
                prior_mean: &self.prior_mean,
                prior_inv: &self.prior_inv,
            };
            (&mut self.window, &self.rings, wts, &self.model)
        }

        /// The dense Gauss–Newton matrix `H` (`nL × nL`) and `g` of the linearised window, assembled
        /// from the definition of the cost: `Jᵀ W J` and `Jᵀ W r` of the stacked residuals.
        pub(in crate::mhe::nonlinear) fn dense_system(&self) -> (DMatrix<f64>, DVector<f64>) {
            let (n, len) = (3, self.len);
            let nv = n * len;
            let (a, c) = (self.model.a(), self.model.c());
            let mut h = DMatrix::zeros(nv, nv);
            let mut g = DVector::zeros(nv);
            let mut add = |rows: &[(usize, DMatrix<f64>)], residual: DVector<f64>, weight: &DMatrix<f64>| {
                // Residual r(x) = (Σ_b J_b x_b) − offset, linear: r is given at the iterate.
                let k = residual.len();
                let mut jac = DMatrix::zeros(k, nv);
                for (block, jb) in rows {
                    jac.view_mut((0, block * n), (k, n)).copy_from(jb);
                }
                h += jac.transpose() * weight * &jac;
                g += jac.transpose() * weight * residual;
            };
            let x = &self.window.x;
            add(&[(0, DMatrix::identity(n, n))], &x[0] - &self.prior_mean, &self.prior_inv);
            let mut fx = DVector::zeros(n);
            let mut hx = DVector::zeros(2);
            for j in 0..len {
                let sl = self.rings.slot(self.start + j);
                if j + 1 < len {
                    self.model.f(&x[j], &self.rings.u[sl], &mut fx).unwrap();
                    add(&[(j, -a.clone()), (j + 1, DMatrix::identity(n, n))], &x[j + 1] - &fx, &self.q_inv);
                }
                if self.rings.has_y[sl] {
                    self.model.h(&x[j], &self.rings.uh[sl], &mut hx).unwrap();
                    add(&[(j, c.clone())], &hx - &self.rings.y[sl], &self.r_inv);
                }
            }
            (h, g)
        }
    }

    #[test]
    fn angle_outputs_enter_the_cost_and_the_gradient_wrapped() {
        // Output 1 an angle: its measurements moved by whole turns leave the window's cost and
        // gradient as they are (the residuals wrapped to (−π, π]); undeclared, they do not.
        let cost_and_gradient = |cs: &mut Case| {
            let (window, rings, wts, model) = cs.parts();
            let cost = window.cost(model, &Span { rings, wts, start: 5, len: 4 }, false).unwrap();
            window.linearise(model, &Span { rings, wts, start: 5, len: 4 }).unwrap();
            (cost, window.g.clone())
        };
        let mut plain = Case::new(4);
        let (cost, g) = cost_and_gradient(&mut plain);
        let mut turned = Case::new(4);
        turned.model = turned.model.clone().with_angles(models::Angles::new(&[], &[1])).unwrap();
        for j in 0..4 {
            let sl = turned.rings.slot(5 + j);
            turned.rings.y[sl][1] += std::f64::consts::TAU * (j as f64 - 1.5).round();
        }
        let (cost_turned, g_turned) = cost_and_gradient(&mut turned);
        assert!((cost_turned - cost).abs() < 1e-12 * cost, "{cost_turned} vs {cost}");
        for (a, b) in g.iter().zip(&g_turned) {
            assert!((a - b).amax() < 1e-12, "{a} vs {b}");
        }
        turned.model = plain.model.clone();
        let (cost_raw, _) = cost_and_gradient(&mut turned);
        assert!(cost_raw > cost + 1.0, "undeclared, the turns count: {cost_raw} vs {cost}");
    }

    #[test]
    fn gradient_and_blocks_are_those_of_the_dense_gauss_newton_system() {
        let mut cs = Case::new(4);
        let (h, g) = cs.dense_system();
        let wts = Weights { q_inv: &cs.q_inv, r_inv: &cs.r_inv, prior_mean: &cs.prior_mean, prior_inv: &cs.prior_inv };
        cs.window.linearise(&cs.model, &Span { rings: &cs.rings, wts, start: cs.start, len: cs.len }).unwrap();
        cs.window.build_blocks(&Span { rings: &cs.rings, wts, start: cs.start, len: cs.len }, 0.0);
        let n = 3;
        for j in 0..cs.len {
            assert!((&cs.window.g[j] - g.rows(j * n, n)).amax() < 1e-12, "g_{j}");
            assert!((&cs.window.d[j] - h.view((j * n, j * n), (n, n))).amax() < 1e-12, "D_{j}");
            if j > 0 {
                let o = -&cs.q_inv * &cs.window.a[j - 1];
                assert!((o - h.view((j * n, (j - 1) * n), (n, n))).amax() < 1e-12, "O_{j}");
            }
        }
        // The cost is ‖r‖²_W: at a step Δ along the exact quadratic, cost(x + Δ) − cost(x) =
        // 2 gᵀΔ + ΔᵀHΔ for this linear model.
        let base =
            cs.window.cost(&cs.model, &Span { rings: &cs.rings, wts, start: cs.start, len: cs.len }, false).unwrap();
        let delta = rand(n * cs.len, 1, 99).column(0).into_owned() * 0.1;
        for j in 0..cs.len {
            cs.window.step[j].copy_from(&delta.rows(j * n, n));
        }
        cs.window.set_trial(cs.len);
        let moved =
            cs.window.cost(&cs.model, &Span { rings: &cs.rings, wts, start: cs.start, len: cs.len }, true).unwrap();
        let expected = 2.0 * g.dot(&delta) + delta.dot(&(&h * &delta));
        assert!((moved - base - expected).abs() < 1e-12 * base.max(1.0), "{} vs {expected}", moved - base);
    }

    #[test]
    fn block_tridiagonal_solve_matches_a_dense_solve() {
        for (len, mu) in [(1, 0.0), (2, 0.0), (5, 0.0), (5, 0.3)] {
            let mut cs = Case::new(len);
            let (h, g) = cs.dense_system();
            let wts =
                Weights { q_inv: &cs.q_inv, r_inv: &cs.r_inv, prior_mean: &cs.prior_mean, prior_inv: &cs.prior_inv };
            cs.window.linearise(&cs.model, &Span { rings: &cs.rings, wts, start: cs.start, len }).unwrap();
            assert!(cs.window.factor_and_solve(&Span { rings: &cs.rings, wts, start: cs.start, len }, mu));
            let damped = &h + DMatrix::identity(3 * len, 3 * len) * mu;
            let chol = damped.clone().cholesky().unwrap();
            let reference = chol.solve(&(-&g));
            for j in 0..len {
                let got = &cs.window.step[j];
                let want = reference.rows(j * 3, 3);
                assert!((got - want).amax() < 1e-10 * reference.amax().max(1.0), "len {len}, μ {mu}, Δ_{j}");
            }
            // The covariance of the last state: the last diagonal block of H⁻¹.
            let mut cov = DMatrix::zeros(3, 3);
            cs.window.last_covariance(len, &mut cov);
            let inverse = chol.inverse();
            let want = inverse.view((3 * (len - 1), 3 * (len - 1)), (3, 3));
            assert!((&cov - want).amax() < 1e-10 * want.amax(), "len {len}");
            assert_eq!(cov, cov.transpose());
        }
    }

    #[test]
    fn an_indefinite_pivot_block_is_refused() {
        let mut cs = Case::new(3);
        let wts = Weights { q_inv: &cs.q_inv, r_inv: &cs.r_inv, prior_mean: &cs.prior_mean, prior_inv: &cs.prior_inv };
        cs.window.linearise(&cs.model, &Span { rings: &cs.rings, wts, start: cs.start, len: cs.len }).unwrap();
        // A large negative damping makes the first block indefinite.
        assert!(!cs.window.factor_and_solve(&Span { rings: &cs.rings, wts, start: cs.start, len: cs.len }, -1e6));
        assert!(cs.window.max_diag(cs.len) > 0.0);
    }

    #[test]
    fn steps_apply_accept_and_measure() {
        let mut w = Window::new(2, 1, 3);
        for j in 0..3 {
            w.x[j].fill(j as f64);
            w.step[j].fill(1e-12);
        }
        assert!(w.step_is_negligible(3, 1e-10));
        assert!(!w.step_is_negligible(3, 1e-13));
        w.set_trial(3);
        w.accept_trial(3);
        assert_eq!(w.x[2][0], 2.0 + 1e-12);
        w.apply_step(2);
        assert!((w.x[1][1] - (1.0 + 2e-12)).abs() < 1e-15);
        assert!(w.is_finite(3));
        w.x[2][1] = f64::NAN;
        assert!(!w.is_finite(3) && w.is_finite(2));
    }
}
