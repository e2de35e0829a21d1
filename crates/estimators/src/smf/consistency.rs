//! Consistency of the data with the noise bounds: the one thing a set-membership filter can
//! *prove*.
//!
//! If `x_k ∈ 𝓔(x̂_k, P_k)`, `w_k ∈ 𝓔(0, Q)` and `v_{k+1} ∈ 𝓔(0, R)`, the innovation
//! `e = y_{k+1} − C (A x̂_k + B u_k)` lies in the Minkowski sum
//!
//! ```text
//! 𝓢 = 𝓔(0, M₁) ⊕ 𝓔(0, M₂) ⊕ 𝓔(0, M₃),    M₁ = C A P_k Aᵀ Cᵀ,  M₂ = C Q Cᵀ,  M₃ = R.
//! ```
//!
//! `e ∉ 𝓢` exactly when a direction `d` separates it: `g(d) = dᵀe − Σᵢ √(dᵀ Mᵢ d) > 0` (support
//! functions). Then no state in the published set, no admissible noise and the model explain the
//! measurement: the data contradict the assumptions at this step or earlier (a measurement
//! outlier, a biased sensor, process noise beyond its bound, a wrong model), and every set
//! published from now on would be meaningless.
//!
//! The search: `𝓢` is the intersection of its outer ellipsoids `𝓔(0, S(τ))`,
//! `S(τ) = Σ Mᵢ/τᵢ`, `τ` on the simplex, and `δ(τ) = eᵀ S(τ)⁻¹ e` is concave in `τ`; its
//! maximiser satisfies `τᵢ ∝ √(dᵀ Mᵢ d)` with `d = S(τ)⁻¹ e`, the fixed point iterated here
//! (from the filter's `τ`), each iterate's `d` tested as a separating direction. The same iterate
//! proves consistency when `eᵢ = (Mᵢ/τᵢ) d` (which sum to `e`) each lie in their ellipsoid,
//! `dᵀ Mᵢ d ≤ τᵢ²`: usually at the first iterate, so a consistent step costs one `m × m`
//! factorisation.
//!
//! Inconsistency is declared only when `g(d) > 10⁻⁷ (dᵀe + Σ √(dᵀ Mᵢ d))`: a relative margin far
//! above the rounding errors of these few products, so a declared inconsistency is a proof for
//! data that respected their bounds to that margin. The check allocates nothing.

use nalgebra::{DMatrix, DVector};

use super::kernels::{Kernels, StepFns};

/// Relative margin of the proof (`check`): inconsistency needs `g(d) > MARGIN · (dᵀe + Σ √(dᵀ Mᵢ d))`.
pub const MARGIN: f64 = 1e-7;

/// Fixed-point iterations of the search.
const MAX_ITERATIONS: usize = 30;

/// Whether the step's data were consistent with the noise bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Consistency {
    /// No separating direction was found (for the initial set: not checked yet).
    Consistent,
    /// Not checked ([`InconsistencyPolicy::Off`]).
    NotChecked,
    /// The measurement is provably incompatible with the predicted set and the noise bounds.
    Inconsistent {
        /// How far outside: `g(d) / Σ √(dᵀ Mᵢ d)` for the best direction found (0 on the
        /// boundary; 1 means the innovation is twice as far out as the set reaches).
        excess: f64,
    },
}

impl Consistency {
    /// Whether the data were consistent.
    #[must_use]
    pub fn is_consistent(self) -> bool {
        !matches!(self, Consistency::Inconsistent { .. })
    }
}

pub use crate::checks::InconsistencyPolicy;

/// Buffers of the check (`m` outputs, `n` states).
#[derive(Debug, Clone)]
pub(crate) struct ConsistencyWork {
    cx: DMatrix<f64>,
    m1: DMatrix<f64>,
    m2: DMatrix<f64>,
    s: DMatrix<f64>,
    pub(crate) z: DVector<f64>,
    e: DVector<f64>,
    d: DVector<f64>,
    t: DVector<f64>,
    /// The kernels of this size (module [`super::kernels`]).
    pub(crate) fns: StepFns,
}

impl ConsistencyWork {
    pub(crate) fn new(n: usize, m: usize) -> Self {
        Self {
            cx: DMatrix::zeros(m, n),
            m1: DMatrix::zeros(m, m),
            m2: DMatrix::zeros(m, m),
            s: DMatrix::zeros(m, m),
            z: DVector::zeros(n),
            e: DVector::zeros(m),
            d: DVector::zeros(m),
            t: DVector::zeros(m),
            fns: StepFns::for_sizes(n, m),
        }
    }
}

/// `dᵀ M d`.
#[inline(always)]
fn quad<K: Kernels>(m: &DMatrix<f64>, d: &DVector<f64>, t: &mut DVector<f64>, len: usize) -> f64 {
    K::gemv_mm(1.0, m, d, 0.0, t);
    dense_kernels::dot(&d.as_slice()[..len], &t.as_slice()[..len]).max(0.0)
}

/// Solves `S d = e` into `w.d` for `S = Σ Mᵢ/τᵢ` (factorised in `w.s`); `false` if `S` is not
/// numerically positive definite.
#[inline(always)]
fn direction<K: Kernels>(w: &mut ConsistencyWork, r: &DMatrix<f64>, tau: [f64; 3]) -> bool {
    let m = K::dims(w.z.len(), w.d.len()).1;
    let mm = m * m;
    let (m1, m2) = (&w.m1.as_slice()[..mm], &w.m2.as_slice()[..mm]);
    dense_kernels::lin2(&mut w.s.as_mut_slice()[..mm], 1.0 / tau[0], m1, 1.0 / tau[1], m2);
    dense_kernels::add_scaled(&mut w.s.as_mut_slice()[..mm], 1.0 / tau[2], &r.as_slice()[..mm]);
    if K::cholesky_m(&mut w.s).is_err() {
        return false;
    }
    w.d.as_mut_slice()[..m].copy_from_slice(&w.e.as_slice()[..m]);
    K::cholesky_solve_m(&w.s, &mut w.d);
    true
}

/// What the data check reads: the output matrix `c`, the predicted shape `x1 = A P Aᵀ`, the noise
/// shapes `q`, `r`, the measurement `y` and the multipliers `tau` the search starts from.
#[derive(Clone, Copy)]
pub(crate) struct CheckInput<'a> {
    pub(crate) c: &'a DMatrix<f64>,
    pub(crate) x1: &'a DMatrix<f64>,
    pub(crate) q: &'a DMatrix<f64>,
    pub(crate) r: &'a DMatrix<f64>,
    pub(crate) y: &'a DVector<f64>,
    pub(crate) tau: [f64; 3],
}

/// Checks the measurement against the prediction `w.z = A x̂ + B u` (set by the caller) and the
/// shapes of `input` (module documentation).
pub(crate) fn check(w: &mut ConsistencyWork, input: &CheckInput<'_>) -> Consistency {
    (w.fns.check)(w, input)
}

/// [`check`] with the kernels `K`.
pub(crate) fn check_with<K: Kernels>(w: &mut ConsistencyWork, input: &CheckInput<'_>) -> Consistency {
    let CheckInput { c, x1, q, r, y, tau } = *input;
    let m = K::dims(c.ncols(), c.nrows()).1;
    // e = y − C z; M₁ = C X₁ Cᵀ; M₂ = C Q Cᵀ.
    w.e.as_mut_slice()[..m].copy_from_slice(&y.as_slice()[..m]);
    K::gemv_mn(-1.0, c, &w.z, 1.0, &mut w.e);
    K::mul_nn_mnn(1.0, c, x1, 0.0, &mut w.cx);
    K::mul_nt_mnm(1.0, &w.cx, c, 0.0, &mut w.m1);
    K::mul_nn_mnn(1.0, c, q, 0.0, &mut w.cx);
    K::mul_nt_mnm(1.0, &w.cx, c, 0.0, &mut w.m2);
    K::symmetrize_m(&mut w.m1);
    K::symmetrize_m(&mut w.m2);
    if w.e.as_slice()[..m].iter().any(|v| !v.is_finite()) {
        return Consistency::Consistent;
    }
    // Fixed-point search from the filter's τ (kept inside the simplex). Each iterate gives two
    // certificates: d separates e from 𝓢 (inconsistent), or eᵢ = (Mᵢ/τᵢ) d decomposes
    // e = Σ eᵢ with eᵢᵀ Mᵢ⁻¹ eᵢ = dᵀMᵢd/τᵢ² ≤ 1 for every i (consistent).
    let mut t = tau.map(|v| v.max(1e-6));
    let sum = t[0] + t[1] + t[2];
    t = t.map(|v| v / sum);
    let mut previous = f64::NAN;
    for _ in 0..MAX_ITERATIONS {
        if !direction::<K>(w, r, t) {
            return Consistency::Consistent;
        }
        let delta = dense_kernels::dot(&w.e.as_slice()[..m], &w.d.as_slice()[..m]);
        let h = [
            quad::<K>(&w.m1, &w.d, &mut w.t, m).sqrt(),
            quad::<K>(&w.m2, &w.d, &mut w.t, m).sqrt(),
            quad::<K>(r, &w.d, &mut w.t, m).sqrt(),
        ];
        let support = h[0] + h[1] + h[2];
        let g = delta - support;
        if !(g.is_finite() && support.is_finite()) {
            return Consistency::Consistent;
        }
        if g > MARGIN * (delta.abs() + support) {
            return Consistency::Inconsistent { excess: g / support.max(f64::MIN_POSITIVE) };
        }
        if (0..3).all(|i| h[i] <= t[i]) || (delta - previous).abs() <= 1e-12 * delta.abs() || support <= 0.0 {
            return Consistency::Consistent;
        }
        previous = delta;
        // τᵢ ∝ √(dᵀ Mᵢ d), kept off the faces.
        t = h.map(|v| (v / support).max(1e-9));
        let s = t[0] + t[1] + t[2];
        t = t.map(|v| v / s);
    }
    Consistency::Consistent
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact membership of `e` in the sum of three discs of radii `r₁, r₂, r₃` (scalar shapes
    /// times the identity in 2-D): `|e| ≤ r₁ + r₂ + r₃`.
    #[test]
    fn separates_exactly_for_spheres_and_gates_the_easy_cases() {
        let n = 2;
        let c = DMatrix::identity(2, 2);
        let x1 = DMatrix::identity(2, 2) * 0.04; // radius 0.2
        let q = DMatrix::identity(2, 2) * 0.09; // radius 0.3
        let r = DMatrix::identity(2, 2) * 0.25; // radius 0.5: total 1.0
        let mut w = ConsistencyWork::new(n, 2);
        for (dist, inside) in [(0.3, true), (0.99, true), (0.999_99, true), (1.001, false), (1.5, false), (40.0, false)]
        {
            w.z.fill(0.0);
            let y = DVector::from_vec(vec![dist * 0.6, dist * 0.8]);
            let got = check(&mut w, &CheckInput { c: &c, x1: &x1, q: &q, r: &r, y: &y, tau: [1.0 / 3.0; 3] });
            assert_eq!(got.is_consistent(), inside, "|e| = {dist}: {got:?}");
            if let Consistency::Inconsistent { excess } = got {
                // For spheres every direction along e is optimal: excess = |e| − 1 exactly.
                assert!((excess - (dist - 1.0)).abs() < 1e-6 * dist, "{dist}: excess {excess}");
            }
        }
    }

    #[test]
    fn anisotropic_sums_are_checked_against_sampled_support_functions() {
        // Random-ish shapes in 2-D; the exact test is max over directions of dᵀe − Σ √(dᵀMᵢd).
        let c = DMatrix::from_row_slice(2, 3, &[1.0, 0.2, 0.0, 0.0, 1.0, -0.5]);
        let x1 = DMatrix::from_row_slice(3, 3, &[0.3, 0.1, 0.0, 0.1, 0.2, 0.05, 0.0, 0.05, 0.1]);
        let q = DMatrix::from_row_slice(3, 3, &[0.01, 0.0, 0.0, 0.0, 0.02, 0.0, 0.0, 0.0, 0.5]);
        let r = DMatrix::from_row_slice(2, 2, &[0.05, 0.01, 0.01, 0.02]);
        let m1 = &c * &x1 * c.transpose();
        let m2 = &c * &q * c.transpose();
        let exact = |e: &DVector<f64>| {
            (0..20_000)
                .map(|k| {
                    let a = k as f64 * std::f64::consts::TAU / 20_000.0;
                    let d = DVector::from_vec(vec![a.cos(), a.sin()]);
                    d.dot(e) - [&m1, &m2, &r].iter().map(|m| (d.dot(&(*m * &d))).sqrt()).sum::<f64>()
                })
                .fold(f64::NEG_INFINITY, f64::max)
        };
        let mut w = ConsistencyWork::new(3, 2);
        for k in 0..40 {
            let a = k as f64 * 0.37;
            for scale in [0.5, 0.9, 1.1, 2.0] {
                let dir = DVector::from_vec(vec![a.cos(), a.sin()]);
                // Scale relative to the support in that direction, so both outcomes occur.
                let h: f64 = [&m1, &m2, &r].iter().map(|m| (dir.dot(&(*m * &dir))).sqrt()).sum();
                let y = &dir * (h * scale);
                w.z.fill(0.0);
                let got = check(&mut w, &CheckInput { c: &c, x1: &x1, q: &q, r: &r, y: &y, tau: [0.2, 0.3, 0.5] });
                let g = exact(&y);
                if g > 1e-3 {
                    assert!(!got.is_consistent(), "k = {k}, scale {scale}: exact g = {g}, got {got:?}");
                }
                if g < -1e-9 {
                    assert!(got.is_consistent(), "k = {k}, scale {scale}: exact g = {g}, got {got:?}");
                }
            }
        }
    }
}
