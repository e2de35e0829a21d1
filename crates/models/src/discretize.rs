//! Matrix exponential and exact zero-order-hold discretisation (the carrier paper's eqs
//! (10)–(11), `docs/carrier-smf.md`).

use nalgebra::{DMatrix, SMatrix};

use crate::error::{ModelError, check_dims, check_finite};

/// Padé degrees and the 1-norm bounds `θ_m` up to which the degree-`m` approximant is accurate
/// to double precision (Higham 2005, Table 2.3).
const THETA: [(usize, f64); 4] = [
    (3, 1.495_585_217_958_292e-2),
    (5, 2.539_398_330_063_23e-1),
    (7, 9.504_178_996_162_932e-1),
    (9, 2.097_847_961_257_068e0),
];
const THETA_13: f64 = 5.371_920_351_148_152;

const B3: [f64; 4] = [120.0, 60.0, 12.0, 1.0];
const B5: [f64; 6] = [30_240.0, 15_120.0, 3_360.0, 420.0, 30.0, 1.0];
const B7: [f64; 8] = [17_297_280.0, 8_648_640.0, 1_995_840.0, 277_200.0, 25_200.0, 1_512.0, 56.0, 1.0];
const B9: [f64; 10] = [
    17_643_225_600.0,
    8_821_612_800.0,
    2_075_673_600.0,
    302_702_400.0,
    30_270_240.0,
    2_162_160.0,
    110_880.0,
    3_960.0,
    90.0,
    1.0,
];
const B13: [f64; 14] = [
    64_764_752_532_480_000.0,
    32_382_376_266_240_000.0,
    7_771_770_303_897_600.0,
    1_187_353_796_428_800.0,
    129_060_195_264_000.0,
    10_559_470_521_600.0,
    670_442_572_800.0,
    33_522_128_640.0,
    1_323_241_920.0,
    40_840_800.0,
    960_960.0,
    16_380.0,
    182.0,
    1.0,
];

/// Maximum absolute column sum.
fn one_norm(m: &DMatrix<f64>) -> f64 {
    m.column_iter().map(|c| c.iter().map(|x| x.abs()).sum::<f64>()).fold(0.0, f64::max)
}

/// `U` (odd part) and `V` (even part) of the degree-`m` Padé numerator for m ∈ {3, 5, 7, 9}:
/// `p(A) = V + U`, `q(A) = V − U`.
fn pade_low(a: &DMatrix<f64>, coeffs: &[f64]) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = a.nrows();
    let a2 = a * a;
    let mut power = DMatrix::identity(n, n); // A^{2k}
    let mut odd = DMatrix::zeros(n, n);
    let mut even = DMatrix::zeros(n, n);
    for k in 0..coeffs.len() / 2 {
        if k > 0 {
            power = &power * &a2;
        }
        even += &power * coeffs[2 * k];
        odd += &power * coeffs[2 * k + 1];
    }
    (a * odd, even)
}

/// `U`, `V` of the degree-13 Padé approximant (Higham 2005, eq (2.12) evaluation scheme).
fn pade13(a: &DMatrix<f64>) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = a.nrows();
    let b = &B13;
    let id = DMatrix::<f64>::identity(n, n);
    let a2 = a * a;
    let a4 = &a2 * &a2;
    let a6 = &a4 * &a2;
    let u_inner = &a6 * (&a6 * b[13] + &a4 * b[11] + &a2 * b[9]) + &a6 * b[7] + &a4 * b[5] + &a2 * b[3] + &id * b[1];
    let u = a * u_inner;
    let v = &a6 * (&a6 * b[12] + &a4 * b[10] + &a2 * b[8]) + &a6 * b[6] + &a4 * b[4] + &a2 * b[2] + &id * b[0];
    (u, v)
}

/// `r = q⁻¹ p` with `p = V + U`, `q = V − U`.
fn solve_pade(u: &DMatrix<f64>, v: &DMatrix<f64>) -> Result<DMatrix<f64>, ModelError> {
    let p = v + u;
    let q = v - u;
    q.lu().solve(&p).ok_or(ModelError::SingularPadeDenominator)
}

/// Matrix exponential `e^M` by scaling and squaring with Padé approximants of degree
/// 3, 5, 7, 9 or 13 (Higham, *SIAM J. Matrix Anal. Appl.* 26(4), 2005), on any square size.
///
/// # Errors
/// [`ModelError::DimensionMismatch`] if `m` is not square,
/// [`ModelError::NonFiniteEntry`] for NaN/∞ entries, [`ModelError::ExponentialOverflow`]
/// if the result does not fit in `f64`.
pub fn expm(m: &DMatrix<f64>) -> Result<DMatrix<f64>, ModelError> {
    let n = m.nrows();
    check_dims("matrix to exponentiate", m, n, n)?;
    check_finite("matrix to exponentiate", m)?;
    if n == 0 {
        return Ok(DMatrix::zeros(0, 0));
    }
    let norm = one_norm(m);
    if !norm.is_finite() {
        return Err(ModelError::ExponentialOverflow { norm });
    }
    let result = if let Some(&(degree, _)) = THETA.iter().find(|(_, theta)| norm <= *theta) {
        let coeffs: &[f64] = match degree {
            3 => &B3,
            5 => &B5,
            7 => &B7,
            _ => &B9,
        };
        let (u, v) = pade_low(m, coeffs);
        solve_pade(&u, &v)?
    } else {
        // s = max(0, ⌈log₂(‖M‖₁ / θ₁₃)⌉) squarings (at most about 1030 for finite norms).
        let s = (norm / THETA_13).log2().ceil().max(0.0) as i32;
        let scaled = m * 2f64.powi(-s);
        let (u, v) = pade13(&scaled);
        let mut r = solve_pade(&u, &v)?;
        for _ in 0..s {
            r = &r * &r;
        }
        r
    };
    if result.iter().any(|x| !x.is_finite()) {
        return Err(ModelError::ExponentialOverflow { norm });
    }
    Ok(result)
}

/// Result of [`zoh_discretize`]: `x_{k+1} = A_p x_k + B_p u_k` for inputs held constant over
/// each period.
#[derive(Debug, Clone, PartialEq)]
pub struct ZohDiscretization {
    /// `A_p = e^{A T_s}` (n × n).
    pub a_p: DMatrix<f64>,
    /// `B_p = ∫₀^{T_s} e^{Aτ} dτ B` (n × p).
    pub b_p: DMatrix<f64>,
    /// Sampling period `T_s` \[s\].
    pub ts: f64,
}

/// Exact zero-order-hold discretisation of `ẋ = A x + B u` (paper eqs (10)–(11), with the
/// trailing `B` the paper omits) through the block exponential
/// `exp([[A, B], [0, 0]] T_s) = [[A_p, B_p], [0, I]]`, for any `n` and `p`.
///
/// # Errors
/// [`ModelError::InvalidSamplingPeriod`] unless `ts` is positive and finite;
/// [`ModelError::DimensionMismatch`] if `A` is not square or `B` has another number of rows;
/// [`ModelError::NonFiniteEntry`] for NaN/∞ entries; exponential failures of [`expm`].
pub fn zoh_discretize(a: &DMatrix<f64>, b: &DMatrix<f64>, ts: f64) -> Result<ZohDiscretization, ModelError> {
    if !(ts.is_finite() && ts > 0.0) {
        return Err(ModelError::InvalidSamplingPeriod(ts));
    }
    let n = a.nrows();
    let p = b.ncols();
    check_dims("state matrix A", a, n, n)?;
    check_dims("input matrix B", b, n, p)?;
    check_finite("state matrix A", a)?;
    check_finite("input matrix B", b)?;
    let mut block = DMatrix::zeros(n + p, n + p);
    block.view_mut((0, 0), (n, n)).copy_from(&(a * ts));
    block.view_mut((0, n), (n, p)).copy_from(&(b * ts));
    check_finite("scaled block matrix [[A, B], [0, 0]] T_s", &block)?;
    let e = expm(&block)?;
    Ok(ZohDiscretization { a_p: e.view((0, 0), (n, n)).into_owned(), b_p: e.view((0, n), (n, p)).into_owned(), ts })
}

/// [`zoh_discretize`] for fixed-size matrices (e.g. the carrier's 4 × 4 and 4 × 8), returning
/// `(A_p, B_p)`.
///
/// # Errors
/// As [`zoh_discretize`].
pub fn zoh_discretize_fixed<const N: usize, const P: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SMatrix<f64, N, P>,
    ts: f64,
) -> Result<(SMatrix<f64, N, N>, SMatrix<f64, N, P>), ModelError> {
    let d = zoh_discretize(
        &DMatrix::from_column_slice(N, N, a.as_slice()),
        &DMatrix::from_column_slice(N, P, b.as_slice()),
        ts,
    )?;
    Ok((
        SMatrix::<f64, N, N>::from_column_slice(d.a_p.as_slice()),
        SMatrix::<f64, N, P>::from_column_slice(d.b_p.as_slice()),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn max_rel_err(got: &DMatrix<f64>, want: &DMatrix<f64>) -> f64 {
        let scale = want.amax().max(1e-300);
        (got - want).amax() / scale
    }

    #[test]
    fn diagonal_matrix_across_all_pade_degrees() {
        // Norms from 1e-4 (degree 3) to 40 (degree 13 with squaring).
        for &lam in &[1e-4, 0.1, 0.5, 1.5, 4.0, 40.0] {
            let d: [f64; 3] = [-lam, 0.3 * lam, -2.0 * lam];
            let m = DMatrix::from_diagonal(&nalgebra::DVector::from_row_slice(&d));
            let want = DMatrix::from_diagonal(&nalgebra::DVector::from_iterator(3, d.iter().map(|x| x.exp())));
            let err = max_rel_err(&expm(&m).unwrap(), &want);
            assert!(err < 1e-13, "lambda = {lam}: {err}");
        }
    }

    #[test]
    fn rotation_and_agreement_with_nalgebra() {
        for &(omega, t) in &[(2.0_f64, 0.001_f64), (2.0, 0.7), (3.0, 5.0)] {
            let m = DMatrix::from_row_slice(2, 2, &[0.0, omega * t, -omega * t, 0.0]);
            let (c, s) = ((omega * t).cos(), (omega * t).sin());
            let want = DMatrix::from_row_slice(2, 2, &[c, s, -s, c]);
            let got = expm(&m).unwrap();
            assert!((&got - &want).amax() < 1e-13, "{got} vs {want}");
            assert!((&got - m.exp()).amax() < 1e-13);
        }
    }

    #[test]
    fn double_integrator_closed_form() {
        let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]);
        let b = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
        for t in [1e-3, 0.1, 2.0, 30.0] {
            let d = zoh_discretize(&a, &b, t).unwrap();
            let want_a = DMatrix::from_row_slice(2, 2, &[1.0, t, 0.0, 1.0]);
            let want_b = DMatrix::from_row_slice(2, 1, &[t * t / 2.0, t]);
            assert!(max_rel_err(&d.a_p, &want_a) < 1e-14, "{}", d.a_p);
            assert!(max_rel_err(&d.b_p, &want_b) < 1e-14, "{}", d.b_p);
            assert_eq!(d.ts, t);
        }
    }

    #[test]
    fn scalar_and_rotation_zoh_closed_forms() {
        // ẋ = −a x + u: A_p = e^{−aT}, B_p = (1 − e^{−aT})/a.
        let (a, t) = (3.0_f64, 0.4);
        let d = zoh_discretize(&DMatrix::from_element(1, 1, -a), &DMatrix::from_element(1, 1, 1.0), t).unwrap();
        assert!((d.a_p[(0, 0)] - (-a * t).exp()).abs() < 1e-15);
        assert!((d.b_p[(0, 0)] - (1.0 - (-a * t).exp()) / a).abs() < 1e-15);
        // Rotation A = [[0, ω], [−ω, 0]], B = I: ∫₀^T e^{Aτ} dτ = [[s, 1 − c], [c − 1, s]]/ω.
        let (w, t) = (2.5_f64, 0.9);
        let a = DMatrix::from_row_slice(2, 2, &[0.0, w, -w, 0.0]);
        let d = zoh_discretize(&a, &DMatrix::identity(2, 2), t).unwrap();
        let (c, s) = ((w * t).cos(), (w * t).sin());
        let want_b = DMatrix::from_row_slice(2, 2, &[s, 1.0 - c, c - 1.0, s]) / w;
        assert!((&d.b_p - want_b).amax() < 1e-14);
    }

    #[test]
    fn error_paths_name_the_problem() {
        let a = DMatrix::identity(2, 2);
        let b = DMatrix::zeros(2, 1);
        for ts in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let e = zoh_discretize(&a, &b, ts).unwrap_err();
            assert!(matches!(e, ModelError::InvalidSamplingPeriod(_)));
            assert!(e.to_string().starts_with("sampling period T_s must be positive and finite, got"));
        }
        let e = zoh_discretize(&DMatrix::zeros(2, 3), &b, 1.0).unwrap_err();
        assert_eq!(e.to_string(), "state matrix A: expected 2x2, got 2x3");
        let e = zoh_discretize(&a, &DMatrix::zeros(3, 1), 1.0).unwrap_err();
        assert_eq!(e.to_string(), "input matrix B: expected 2x1, got 3x1");
        let mut bad = a.clone();
        bad[(1, 0)] = f64::NAN;
        let e = zoh_discretize(&bad, &b, 1.0).unwrap_err();
        assert_eq!(e.to_string(), "state matrix A has a non-finite entry at (1, 0)");
        let mut bad_b = b.clone();
        bad_b[(0, 0)] = f64::NEG_INFINITY;
        let e = zoh_discretize(&a, &bad_b, 1.0).unwrap_err();
        assert_eq!(e.to_string(), "input matrix B has a non-finite entry at (0, 0)");
        let huge = DMatrix::from_element(1, 1, 1e300);
        let e = zoh_discretize(&huge, &DMatrix::zeros(1, 0), 1e10).unwrap_err();
        assert_eq!(e.to_string(), "scaled block matrix [[A, B], [0, 0]] T_s has a non-finite entry at (0, 0)");
        let e = expm(&DMatrix::from_element(1, 1, 1000.0)).unwrap_err();
        assert_eq!(e.to_string(), "matrix exponential overflowed: e^M has non-finite entries (1-norm of M = 1000)");
        let e = expm(&DMatrix::from_element(2, 2, 1e308)).unwrap_err();
        assert_eq!(e.to_string(), "matrix exponential overflowed: e^M has non-finite entries (1-norm of M = inf)");
        let e = expm(&DMatrix::zeros(2, 3)).unwrap_err();
        assert_eq!(e.to_string(), "matrix to exponentiate: expected 2x2, got 2x3");
        let e = expm(&DMatrix::from_element(1, 1, f64::NAN)).unwrap_err();
        assert_eq!(e.to_string(), "matrix to exponentiate has a non-finite entry at (0, 0)");
        // A singular Padé denominator (not reachable through expm's scaling) is an error.
        let e = solve_pade(&DMatrix::identity(2, 2), &DMatrix::identity(2, 2)).unwrap_err();
        assert_eq!(e.to_string(), "matrix exponential: the Pade denominator q(M) is singular");
        // Empty systems are fine.
        assert_eq!(expm(&DMatrix::zeros(0, 0)).unwrap().nrows(), 0);
        let d = zoh_discretize(&a, &DMatrix::zeros(2, 0), 0.1).unwrap();
        assert_eq!(d.b_p.shape(), (2, 0));
    }
}
