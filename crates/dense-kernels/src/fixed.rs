//! Const-generic twins of the general kernels that give their numbers in every case.
//!
//! [`crate::small`] drops the general kernels' skip of a zero multiplier, which changes the
//! result where a skipped term would have been `0 · ∞` or would have turned a `−0` into `+0`.
//! These kernels keep that skip (and every other operation, in the same order), so a caller that
//! must reproduce the general path bit for bit — including on overflowed or signed-zero data —
//! can use them: the loops still have constant trip counts, keep their output column in
//! registers and drop the bounds checks. Slices may be longer than the stated size; only the
//! leading entries are read or written.

/// `out = alpha · a · b + beta · out` for `a` `R × K`, `b` `K × C`, `out` `R × C`
/// ([`crate::mul_nn`]'s numbers).
#[inline(always)]
pub fn mul_nn<const R: usize, const K: usize, const C: usize>(
    alpha: f64,
    a: &[f64],
    b: &[f64],
    beta: f64,
    out: &mut [f64],
) {
    let b = &b[..K * C];
    mul_strided::<R, K, C>(alpha, a, |j, l| b[j * K + l], beta, out);
}

/// `out = alpha · a · bᵀ + beta · out` for `a` `R × K`, `b` `C × K`, `out` `R × C`
/// ([`crate::mul_nt`]'s numbers).
#[inline(always)]
pub fn mul_nt<const R: usize, const K: usize, const C: usize>(
    alpha: f64,
    a: &[f64],
    b: &[f64],
    beta: f64,
    out: &mut [f64],
) {
    let b = &b[..K * C];
    mul_strided::<R, K, C>(alpha, a, |j, l| b[l * C + j], beta, out);
}

#[inline(always)]
fn mul_strided<const R: usize, const K: usize, const C: usize>(
    alpha: f64,
    a: &[f64],
    b: impl Fn(usize, usize) -> f64,
    beta: f64,
    out: &mut [f64],
) {
    let a = &a[..R * K];
    let out = &mut out[..R * C];
    for j in 0..C {
        let oc = &mut out[j * R..(j + 1) * R];
        let mut acc = [0.0; R];
        start(&mut acc, oc, beta);
        for l in 0..K {
            let s = alpha * b(j, l);
            if s != 0.0 {
                let ac = &a[l * R..(l + 1) * R];
                for i in 0..R {
                    acc[i] += s * ac[i];
                }
            }
        }
        oc.copy_from_slice(&acc);
    }
}

/// `acc = beta · col` as the general path scales its output (`0` and `1` exactly).
#[inline(always)]
fn start<const R: usize>(acc: &mut [f64; R], col: &[f64], beta: f64) {
    if beta == 1.0 {
        acc.copy_from_slice(col);
    } else if beta != 0.0 {
        for i in 0..R {
            acc[i] = col[i] * beta;
        }
    }
}

/// `out = alpha · a · x + beta · out` for `a` `R × K` ([`crate::gemv`]'s numbers).
#[inline(always)]
pub fn gemv<const R: usize, const K: usize>(alpha: f64, a: &[f64], x: &[f64], beta: f64, out: &mut [f64]) {
    mul_nn::<R, K, 1>(alpha, a, x, beta, out);
}

/// [`gemv`] with the column count `x.len()` known only at run time (a model's input count).
#[inline(always)]
pub fn gemv_cols<const R: usize>(alpha: f64, a: &[f64], x: &[f64], beta: f64, out: &mut [f64]) {
    let out = &mut out[..R];
    let mut acc = [0.0; R];
    start(&mut acc, out, beta);
    for (ac, &xl) in a.chunks_exact(R.max(1)).zip(x) {
        let s = alpha * xl;
        if s != 0.0 {
            for i in 0..R {
                acc[i] += s * ac[i];
            }
        }
    }
    out.copy_from_slice(&acc);
}

/// `out = I − l · c` for `l` `N × M`, `c` `M × N` ([`crate::i_minus_lc`]'s numbers).
#[inline(always)]
pub fn i_minus_lc<const N: usize, const M: usize>(l: &[f64], c: &[f64], out: &mut [f64]) {
    mul_nn::<N, M, N>(-1.0, l, c, 0.0, out);
    for i in 0..N {
        out[i * N + i] += 1.0;
    }
}

/// `x ← x · G⁻ᵀ` for `x` `R × M` and a lower-triangular `M × M` `g`
/// ([`crate::solve_right_lower_t`]'s numbers).
#[inline(always)]
pub fn solve_right_lower_t<const R: usize, const M: usize>(x: &mut [f64], g: &[f64]) {
    let g = &g[..M * M];
    let x = &mut x[..R * M];
    for j in 0..M {
        let mut acc = [0.0; R];
        acc.copy_from_slice(&x[j * R..(j + 1) * R]);
        for k in 0..j {
            let s = g[k * M + j];
            if s != 0.0 {
                let yk = &x[k * R..(k + 1) * R];
                for i in 0..R {
                    acc[i] -= s * yk[i];
                }
            }
        }
        let d = 1.0 / g[j * M + j];
        for (v, a) in x[j * R..(j + 1) * R].iter_mut().zip(acc) {
            *v = a * d;
        }
    }
}

/// `x ← x · G⁻¹` for `x` `R × M` and a lower-triangular `M × M` `g`
/// ([`crate::solve_right_lower`]'s numbers).
#[inline(always)]
pub fn solve_right_lower<const R: usize, const M: usize>(x: &mut [f64], g: &[f64]) {
    let g = &g[..M * M];
    let x = &mut x[..R * M];
    for j in (0..M).rev() {
        let mut acc = [0.0; R];
        acc.copy_from_slice(&x[j * R..(j + 1) * R]);
        for k in j + 1..M {
            let s = g[j * M + k];
            if s != 0.0 {
                let yk = &x[k * R..(k + 1) * R];
                for i in 0..R {
                    acc[i] -= s * yk[i];
                }
            }
        }
        let d = 1.0 / g[j * M + j];
        for (v, a) in x[j * R..(j + 1) * R].iter_mut().zip(acc) {
            *v = a * d;
        }
    }
}

/// `x ← (G Gᵀ)⁻¹ x` for a vector `x` and the lower `N × N` factor `g`
/// ([`crate::cholesky_solve`]'s numbers).
#[inline(always)]
pub fn cholesky_solve<const N: usize>(g: &[f64], x: &mut [f64]) {
    let g = &g[..N * N];
    let x = &mut x[..N];
    for i in 0..N {
        let mut s = x[i];
        for k in 0..i {
            s -= g[k * N + i] * x[k];
        }
        x[i] = s / g[i * N + i];
    }
    for i in (0..N).rev() {
        let mut s = x[i];
        for k in i + 1..N {
            s -= g[i * N + k] * x[k];
        }
        x[i] = s / g[i * N + i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    /// Entries with zeros of both signs, and (with `wild`) infinities and a NaN.
    fn rand(r: usize, c: usize, seed: u64, wild: bool) -> DMatrix<f64> {
        let mut s = seed;
        DMatrix::from_fn(r, c, |_, _| {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let v = ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5;
            match (s >> 60, wild) {
                (0 | 1, _) => 0.0,
                (2, _) => -0.0,
                (3, true) => f64::INFINITY,
                (4, true) => f64::NEG_INFINITY,
                (5, true) if (s >> 56) & 3 == 0 => f64::NAN,
                _ => v,
            }
        })
    }

    /// The bits of each entry, every NaN as one (LLVM may commute an addition's operands, which
    /// picks another NaN's payload).
    fn bits(a: &[f64]) -> Vec<u64> {
        a.iter().map(|v| if v.is_nan() { f64::NAN.to_bits() } else { v.to_bits() }).collect()
    }

    fn check<const R: usize, const K: usize, const C: usize>() {
        for seed in 0..40u64 {
            let wild = seed % 2 == 1;
            let seed = seed * 1000 + (100 * R + 10 * K + C) as u64;
            let (a, b, bt) = (rand(R, K, seed, wild), rand(K, C, seed + 1, wild), rand(C, K, seed + 2, wild));
            for alpha in [1.0, -2.5] {
                for beta in [0.0, 1.0, 0.5] {
                    let start = rand(R, C, seed + 3, wild);
                    let (mut g, mut s) = (start.clone(), start.clone());
                    crate::mul_nn(alpha, &a, &b, beta, &mut g);
                    mul_nn::<R, K, C>(alpha, a.as_slice(), b.as_slice(), beta, s.as_mut_slice());
                    assert_eq!(bits(g.as_slice()), bits(s.as_slice()), "mul_nn {R}×{K}×{C}");
                    let (mut g, mut s) = (start.clone(), start);
                    crate::mul_nt(alpha, &a, &bt, beta, &mut g);
                    mul_nt::<R, K, C>(alpha, a.as_slice(), bt.as_slice(), beta, s.as_mut_slice());
                    assert_eq!(bits(g.as_slice()), bits(s.as_slice()), "mul_nt {R}×{K}×{C}");
                    let x: DVector<f64> = rand(K, 1, seed + 4, wild).column(0).into_owned();
                    let start: DVector<f64> = rand(R, 1, seed + 5, wild).column(0).into_owned();
                    let (mut g, mut s, mut t) = (start.clone(), start.clone(), start);
                    crate::gemv(alpha, &a, &x, beta, &mut g);
                    gemv::<R, K>(alpha, a.as_slice(), x.as_slice(), beta, s.as_mut_slice());
                    gemv_cols::<R>(alpha, a.as_slice(), x.as_slice(), beta, t.as_mut_slice());
                    assert_eq!(bits(g.as_slice()), bits(s.as_slice()), "gemv {R}×{K}");
                    assert_eq!(bits(g.as_slice()), bits(t.as_slice()), "gemv_cols {R}×{K}");
                }
            }
            // Solves with a triangular factor holding zeros; I − L C.
            let mut g = rand(K, K, seed + 6, wild);
            for j in 0..K {
                g[(j, j)] = 1.5 + j as f64;
            }
            let x = rand(R, K, seed + 7, wild);
            let (mut xg, mut xs) = (x.clone(), x.clone());
            crate::solve_right_lower_t(&mut xg, &g);
            solve_right_lower_t::<R, K>(xs.as_mut_slice(), g.as_slice());
            assert_eq!(bits(xg.as_slice()), bits(xs.as_slice()), "solve_right_lower_t {R}×{K}");
            let (mut xg, mut xs) = (x.clone(), x);
            crate::solve_right_lower(&mut xg, &g);
            solve_right_lower::<R, K>(xs.as_mut_slice(), g.as_slice());
            assert_eq!(bits(xg.as_slice()), bits(xs.as_slice()), "solve_right_lower {R}×{K}");
            let xv: DVector<f64> = rand(K, 1, seed + 8, wild).column(0).into_owned();
            let (mut xg, mut xs) = (xv.clone(), xv);
            crate::cholesky_solve(g.as_slice(), K, xg.as_mut_slice());
            cholesky_solve::<K>(g.as_slice(), xs.as_mut_slice());
            assert_eq!(bits(xg.as_slice()), bits(xs.as_slice()), "cholesky_solve {K}");
            let (l, c) = (rand(R, K, seed + 9, wild), rand(K, R, seed + 10, wild));
            let (mut og, mut os) = (DMatrix::zeros(R, R), DMatrix::from_element(R, R, 3.0));
            crate::i_minus_lc(&l, &c, &mut og);
            i_minus_lc::<R, K>(l.as_slice(), c.as_slice(), os.as_mut_slice());
            assert_eq!(bits(og.as_slice()), bits(os.as_slice()), "i_minus_lc {R}×{K}");
        }
    }

    macro_rules! each {
        ($([$($s:literal),*])*) => { $( check::<$($s),*>(); )* };
    }

    #[test]
    fn every_kernel_gives_the_general_bits_on_zeros_infinities_and_nan() {
        each!([1, 1, 1] [3, 3, 3] [4, 4, 4] [4, 3, 4] [4, 4, 3] [3, 4, 3] [4, 3, 3] [6, 3, 6] [8, 5, 8] [13, 3, 13]
            [13, 13, 3] [3, 13, 3] [9, 2, 9]);
    }
}
