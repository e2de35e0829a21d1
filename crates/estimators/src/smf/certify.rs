//! Certification of the published set (module documentation of [`crate::smf`],
//! "Certification"): the shape recomputed from the `(L, τ)` used and inflated by a bound on the
//! rounding errors, so that containment never depends on solver accuracy.

use nalgebra::{DMatrix, DVector};

use models::StepModel;

use super::filter::SetEstimate;
use super::kernels::{Kernels, StepFns};

/// The certification inflation: `P_{k+1} = (1 + relative) Φ̂ + absolute · I`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Inflation {
    /// `s`, the relative factor from the centre's rounding error.
    pub relative: f64,
    /// `ε`, added to the diagonal.
    pub absolute: f64,
}

pub(crate) const U: f64 = f64::EPSILON / 2.0;

pub(crate) fn gamma(k: usize) -> f64 {
    let ku = k as f64 * U;
    ku / (1.0 - ku)
}

/// An upper bound of the Frobenius norm of `a` (four partial sums of squares). The computed sum
/// of the squares falls short of the exact one by at most `γ_{len+1}` relatively, the square root
/// and the product below by one rounding each; `1 + 2γ_{len+3}` covers all three (after its own
/// rounding).
pub(crate) fn fro_upper(a: &[f64]) -> f64 {
    let mut s = [0.0f64; 4];
    let mut chunks = a.chunks_exact(4);
    for c in &mut chunks {
        for (s, v) in s.iter_mut().zip(c) {
            *s += v * v;
        }
    }
    let mut t = (s[0] + s[1]) + (s[2] + s[3]);
    for v in chunks.remainder() {
        t += v * v;
    }
    t.sqrt() * (1.0 + 2.0 * gamma(a.len() + 3))
}

/// Buffers of the certification.
#[derive(Debug, Clone)]
pub(crate) struct CertWork {
    pub(crate) z: DVector<f64>,
    pub(crate) k: DMatrix<f64>,
    pub(crate) t: DMatrix<f64>,
    pub(crate) kx: DMatrix<f64>,
    pub(crate) lr: DMatrix<f64>,
    pub(crate) p_new: DMatrix<f64>,
    pub(crate) x_new: DVector<f64>,
    /// The kernels of this size (module [`super::kernels`]).
    pub(crate) fns: StepFns,
}

impl CertWork {
    /// Buffers for `n` states and `m` outputs.
    pub(crate) fn new(n: usize, m: usize) -> Self {
        let nn = || DMatrix::zeros(n, n);
        Self {
            z: DVector::zeros(n),
            k: nn(),
            t: nn(),
            kx: nn(),
            lr: DMatrix::zeros(n, m),
            p_new: nn(),
            x_new: DVector::zeros(n),
            fns: StepFns::for_sizes(n, m),
        }
    }
}

/// What a certification reads: the step's model, the gain `L` and multipliers `τ` of the update,
/// the predicted shape `X₁ = A P Aᵀ`, the noise shapes, the estimate before the step and the
/// step's data.
#[derive(Clone, Copy)]
pub(crate) struct CertInput<'a> {
    pub(crate) model: &'a StepModel<'a>,
    pub(crate) l: &'a DMatrix<f64>,
    pub(crate) tau: [f64; 3],
    pub(crate) x1: &'a DMatrix<f64>,
    pub(crate) q: &'a DMatrix<f64>,
    pub(crate) r: &'a DMatrix<f64>,
    pub(crate) est: &'a SetEstimate,
    pub(crate) u: &'a DVector<f64>,
    pub(crate) y: &'a DVector<f64>,
}

/// Computes the certified `P_{k+1}` into `cw.p_new` and the centre into `cw.x_new` from
/// `(L, τ)` (module documentation, "Certification"). `None` if the shape, the centre or the
/// inflation is not finite. `τ` must come from [`clamp_tau`] and `L` must be 0 if `τ₃ = 0`.
pub(crate) fn certify(cw: &mut CertWork, input: &CertInput<'_>) -> Option<Inflation> {
    (cw.fns.certify)(cw, input)
}

/// [`certify`] with the kernels `K`.
pub(crate) fn certify_with<K: Kernels>(cw: &mut CertWork, input: &CertInput<'_>) -> Option<Inflation> {
    let CertInput { model, l, tau, x1, q, r, est, u, y } = *input;
    let (n, m) = K::dims(l.nrows(), l.ncols());
    let (nn, nm) = (n * n, n * m);
    K::i_minus_lc(l, model.c, &mut cw.k);
    let fro = |a: &DMatrix<f64>, len: usize| fro_upper(&a.as_slice()[..len]);
    let (na, nb, nc, nl, nk) =
        (fro(model.a, nn), fro_upper(model.b.as_slice()), fro(model.c, nm), fro(l, nm), fro(&cw.k, nn));
    let (nx1, nq, nr, np) = (fro(x1, nn), fro(q, nn), fro(r, m * m), fro(&est.shape, nn));
    let e_x = gamma(2 * n) * na * na * np;
    let e_k = gamma(m + 1) * ((n as f64).sqrt() + nl * nc);
    let kappa = nk + e_k;
    let lin = 2.0 * nk * e_k + e_k * e_k;
    // T₁ = K X₁ Kᵀ/τ₁.
    K::mul_nn_nnn(1.0, &cw.k, x1, 0.0, &mut cw.kx);
    K::mul_nt_nnn(1.0 / tau[0], &cw.kx, &cw.k, 0.0, &mut cw.p_new);
    let nt1 = fro(&cw.p_new, nn);
    let mut err = (gamma(2 * n + 2) * nk * nk * nx1 + lin * nx1 + kappa * kappa * e_x) / tau[0];
    // T₂ = K Q Kᵀ/τ₂.
    K::mul_nn_nnn(1.0, &cw.k, q, 0.0, &mut cw.kx);
    K::mul_nt_nnn(1.0 / tau[1], &cw.kx, &cw.k, 0.0, &mut cw.t);
    let nt2 = fro(&cw.t, nn);
    err += (gamma(2 * n + 2) * nk * nk * nq + lin * nq) / tau[1];
    dense_kernels::add_scaled(&mut cw.p_new.as_mut_slice()[..nn], 1.0, &cw.t.as_slice()[..nn]);
    let mut nt3 = 0.0;
    if tau[2] > 0.0 {
        // T₃ = L R Lᵀ/τ₃.
        K::mul_nn_nmm(1.0, l, r, 0.0, &mut cw.lr);
        K::mul_nt_nmn(1.0 / tau[2], &cw.lr, l, 0.0, &mut cw.t);
        nt3 = fro(&cw.t, nn);
        err += gamma(2 * m + 2) * nl * nl * nr / tau[2];
        dense_kernels::add_scaled(&mut cw.p_new.as_mut_slice()[..nn], 1.0, &cw.t.as_slice()[..nn]);
    }
    err += gamma(4) * (nt1 + nt2 + nt3);
    K::symmetrize_n(&mut cw.p_new);
    let nphi = fro(&cw.p_new, nn);
    let eps2 = 2.0 * err + 4.0 * U * nphi;
    // Centre: z = A x̂ + B ū, x̂⁺ = K̂ z + L y.
    K::gemv_nn(1.0, model.a, &est.center, 0.0, &mut cw.z);
    K::gemv_np(1.0, model.b, u, 1.0, &mut cw.z);
    K::gemv_nn(1.0, &cw.k, &cw.z, 0.0, &mut cw.x_new);
    K::gemv_nm(1.0, l, y, 1.0, &mut cw.x_new);
    let nxh = fro_upper(&est.center.as_slice()[..n]);
    let nu = fro_upper(u.as_slice());
    let nz = fro_upper(&cw.z.as_slice()[..n]);
    let ny = fro_upper(&y.as_slice()[..m]);
    let e_z = gamma(n + u.len()) * (na * nxh + nb * nu);
    let rho = 2.0 * (gamma(n + m + 1) * (nk * nz + nl * ny) + e_k * nz + kappa * e_z);
    let trc = cw.p_new.trace() + n as f64 * eps2;
    let s = if rho > 0.0 && trc > 0.0 { rho * (n as f64 / trc).sqrt() } else { 0.0 };
    let nc_pub = nphi + (n as f64).sqrt() * eps2;
    let extra = if s > 0.0 { (1.0 + 1.0 / s) * rho * rho } else { 0.0 };
    let absolute = (1.0 + s) * eps2 + extra + 4.0 * U * (1.0 + s) * nc_pub;
    if s > 0.0 {
        cw.p_new.iter_mut().for_each(|v| *v *= 1.0 + s);
    }
    for i in 0..n {
        cw.p_new[(i, i)] += absolute;
    }
    let finite = cw.p_new.iter().chain(cw.x_new.iter()).all(|v| v.is_finite());
    (finite && absolute.is_finite() && s.is_finite()).then_some(Inflation { relative: s, absolute })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fro_upper_bounds_the_norm_from_above_and_tightly() {
        // Exact norms: integer entries whose squares and their sums are exact.
        let cases: [(&[f64], f64); 4] =
            [(&[3.0, 4.0], 5.0), (&[1.0, 2.0, 2.0], 3.0), (&[1.0; 49], 7.0), (&[2.0, 3.0, 6.0, 0.0, 0.0], 7.0)];
        for (a, exact) in cases {
            let b = fro_upper(a);
            assert!(b >= exact && b <= exact * (1.0 + 1e-13), "{a:?}: {b} against {exact}");
        }
        assert_eq!(fro_upper(&[]), 0.0);
        // Entries whose squares round: 0.1 (k = 10 000 of them, norm 10 exactly in real
        // arithmetic up to the representation of 0.1, which is above 0.1 by 5.55e-18).
        let a = vec![0.1; 10_000];
        assert!(fro_upper(&a) >= 10.0 && fro_upper(&a) <= 10.0 * (1.0 + 1e-11));
    }
}
