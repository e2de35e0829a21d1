//! Const-generic kernels for sizes known at compile time: the hot-path products, the Cholesky
//! factorisation and the triangular solves of the crate root and [`crate::cholesky`], on
//! column-major slices whose dimensions are type parameters.
//!
//! A caller chooses the instance once (for example a filter, from its state and output counts)
//! and calls it on every step; each loop then has a constant trip count, so the compiler unrolls
//! it, keeps the output column in registers and drops the bounds checks.
//!
//! **Same numbers as the general path.** Every kernel performs the same floating-point operations
//! in the same order as its runtime-size counterpart, so the results are equal. The one
//! difference: these kernels do not skip a zero multiplier, so an infinite or NaN entry that
//! the general path would have skipped propagates here (and `+0`/`−0` may differ).
//!
//! Slices may be longer than the stated size; only the leading entries are read or written.

use crate::spd::{PD_RELATIVE_TOLERANCE, PivotFailure};

/// `out = alpha · a · b + beta · out` for `a` `R × K`, `b` `K × C`, `out` `R × C`.
#[inline(always)]
pub fn mul_nn<const R: usize, const K: usize, const C: usize>(
    alpha: f64,
    a: &[f64],
    b: &[f64],
    beta: f64,
    out: &mut [f64],
) {
    let b = &b[..K * C];
    // b[l, j] is at j·K + l.
    mul_strided::<R, K, C>(alpha, a, |j, l| b[j * K + l], beta, out);
}

/// `out = alpha · a · bᵀ + beta · out` for `a` `R × K`, `b` `C × K`, `out` `R × C`.
#[inline(always)]
pub fn mul_nt<const R: usize, const K: usize, const C: usize>(
    alpha: f64,
    a: &[f64],
    b: &[f64],
    beta: f64,
    out: &mut [f64],
) {
    let b = &b[..K * C];
    // bᵀ[l, j] = b[j, l] is at l·C + j.
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
        scaled_start(&mut acc, oc, beta);
        for l in 0..K {
            let s = alpha * b(j, l);
            let ac = &a[l * R..(l + 1) * R];
            for i in 0..R {
                acc[i] += s * ac[i];
            }
        }
        oc.copy_from_slice(&acc);
    }
}

/// `acc = beta · col` as the general path scales its output (`0` and `1` exactly).
#[inline(always)]
fn scaled_start<const R: usize>(acc: &mut [f64; R], col: &[f64], beta: f64) {
    if beta == 1.0 {
        acc.copy_from_slice(col);
    } else if beta != 0.0 {
        for i in 0..R {
            acc[i] = col[i] * beta;
        }
    }
}

/// The largest row count of [`mul_rows`], the general products' register kernel.
pub const MAX_ROWS: usize = 8;

/// The general products' kernel with `R` rows fixed: `out = alpha · a · B + beta · out` for `a`
/// `R × k`, `B[l, j] = b[j·stride.0 + l·stride.1]` with `c` columns (`(k, c)` at run time). Like
/// the general path it skips zero multipliers, so the numbers are the general path's exactly.
#[inline]
pub fn mul_rows<const R: usize>(
    alpha: f64,
    a: &[f64],
    b: &[f64],
    (k, c): (usize, usize),
    stride: (usize, usize),
    beta: f64,
    out: &mut [f64],
) {
    let a = &a[..R * k];
    for (j, oc) in out[..R * c].chunks_exact_mut(R.max(1)).enumerate() {
        let mut acc = [0.0; R];
        scaled_start(&mut acc, oc, beta);
        for (l, ac) in a.chunks_exact(R.max(1)).enumerate() {
            let s = alpha * b[j * stride.0 + l * stride.1];
            if s != 0.0 {
                for i in 0..R {
                    acc[i] += s * ac[i];
                }
            }
        }
        oc.copy_from_slice(&acc);
    }
}

/// `out = alpha · a · x + beta · out` for `a` `R × k` with `k = x.len()` (rows fixed, columns at
/// run time: the input count of a model, for example).
#[inline(always)]
pub fn gemv<const R: usize>(alpha: f64, a: &[f64], x: &[f64], beta: f64, out: &mut [f64]) {
    let out = &mut out[..R];
    let mut acc = [0.0; R];
    scaled_start(&mut acc, out, beta);
    for (ac, &xl) in a.chunks_exact(R).zip(x) {
        let s = alpha * xl;
        for i in 0..R {
            acc[i] += s * ac[i];
        }
    }
    out.copy_from_slice(&acc);
}

/// `a ← (a + aᵀ)/2` for `a` `N × N`.
#[inline(always)]
pub fn symmetrize<const N: usize>(a: &mut [f64]) {
    let a = &mut a[..N * N];
    for j in 0..N {
        for i in j + 1..N {
            let v = 0.5 * (a[j * N + i] + a[i * N + j]);
            a[j * N + i] = v;
            a[i * N + j] = v;
        }
    }
}

/// `out = I − l · c` for `l` `N × M`, `c` `M × N`.
#[inline(always)]
pub fn i_minus_lc<const N: usize, const M: usize>(l: &[f64], c: &[f64], out: &mut [f64]) {
    mul_nn::<N, M, N>(-1.0, l, c, 0.0, out);
    for i in 0..N {
        out[i * N + i] += 1.0;
    }
}

/// In-place lower Cholesky factor of the `N × N` matrix in `a` at the workspace's pivot rule
/// ([`crate::cholesky_in_place`]): the lower triangle is read and overwritten by `G`; on success
/// the strict upper triangle is zeroed, on failure the columns before the failing pivot hold the
/// partial factor.
#[inline(always)]
pub fn cholesky<const N: usize>(a: &mut [f64]) -> Result<(), PivotFailure> {
    let a = &mut a[..N * N];
    let scale = PD_RELATIVE_TOLERANCE * N as f64;
    for j in 0..N {
        let diag = a[j * N + j];
        let threshold = scale * diag;
        let mut s = diag;
        for k in 0..j {
            s -= a[k * N + j] * a[k * N + j];
        }
        if !s.is_finite() || s <= threshold || s <= 0.0 {
            return Err(PivotFailure { pivot: j, value: s, threshold });
        }
        let d = s.sqrt();
        a[j * N + j] = d;
        for i in j + 1..N {
            let mut v = a[j * N + i];
            for k in 0..j {
                v -= a[k * N + i] * a[k * N + j];
            }
            let v = v / d;
            if !v.is_finite() {
                return Err(PivotFailure { pivot: j, value: s, threshold });
            }
            a[j * N + i] = v;
        }
    }
    for j in 0..N {
        a[j * N..j * N + j].fill(0.0);
    }
    Ok(())
}

/// `x ← G⁻¹ x` (forward substitution) for the lower-triangular `N × N` factor `g` and a vector
/// `x` of length `N`.
#[inline(always)]
pub fn solve_lower<const N: usize>(g: &[f64], x: &mut [f64]) {
    let g = &g[..N * N];
    let x = &mut x[..N];
    for i in 0..N {
        let mut s = x[i];
        for k in 0..i {
            s -= g[k * N + i] * x[k];
        }
        x[i] = s / g[i * N + i];
    }
}

/// `x ← x · G⁻ᵀ` for `x` `R × M` and a lower-triangular `M × M` factor `g` (solves `Y Gᵀ = X`
/// column by column).
#[inline(always)]
pub fn solve_right_lower_t<const R: usize, const M: usize>(x: &mut [f64], g: &[f64]) {
    let g = &g[..M * M];
    let x = &mut x[..R * M];
    for j in 0..M {
        let mut acc = [0.0; R];
        acc.copy_from_slice(&x[j * R..(j + 1) * R]);
        for k in 0..j {
            let s = g[k * M + j];
            let yk = &x[k * R..(k + 1) * R];
            for i in 0..R {
                acc[i] -= s * yk[i];
            }
        }
        let d = 1.0 / g[j * M + j];
        for (v, a) in x[j * R..(j + 1) * R].iter_mut().zip(acc) {
            *v = a * d;
        }
    }
}

/// `x ← x · G⁻¹` for `x` `R × M` and a lower-triangular `M × M` factor `g` (solves `Y G = X`,
/// last column first).
#[inline(always)]
pub fn solve_right_lower<const R: usize, const M: usize>(x: &mut [f64], g: &[f64]) {
    let g = &g[..M * M];
    let x = &mut x[..R * M];
    for j in (0..M).rev() {
        let mut acc = [0.0; R];
        acc.copy_from_slice(&x[j * R..(j + 1) * R]);
        for k in j + 1..M {
            let s = g[j * M + k];
            let yk = &x[k * R..(k + 1) * R];
            for i in 0..R {
                acc[i] -= s * yk[i];
            }
        }
        let d = 1.0 / g[j * M + j];
        for (v, a) in x[j * R..(j + 1) * R].iter_mut().zip(acc) {
            *v = a * d;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    fn rand(r: usize, c: usize, seed: u64) -> DMatrix<f64> {
        let mut m = crate::test_data::centred_matrix(r, c, seed);
        // A zero multiplier, which the general path skips.
        m[(r - 1, 0)] = 0.0;
        m
    }

    fn spd(n: usize, seed: u64) -> DMatrix<f64> {
        let h = rand(n, n, seed);
        &h * h.transpose() + DMatrix::identity(n, n) * 0.1
    }

    /// Products: the general kernels' numbers exactly, for every `alpha`, `beta` path.
    fn products<const R: usize, const K: usize, const C: usize>() {
        let seed = (100 * R + 10 * K + C) as u64;
        let (a, b, bt) = (rand(R, K, seed), rand(K, C, seed + 1), rand(C, K, seed + 2));
        for alpha in [1.0, -2.5] {
            for beta in [0.0, 1.0, 0.5] {
                let start = rand(R, C, seed + 3);
                let (mut g, mut s) = (start.clone(), start.clone());
                crate::mul_nn(alpha, &a, &b, beta, &mut g);
                mul_nn::<R, K, C>(alpha, a.as_slice(), b.as_slice(), beta, s.as_mut_slice());
                assert_eq!(g, s, "mul_nn {R}×{K}×{C}, alpha {alpha}, beta {beta}");
                let (mut g, mut s) = (start.clone(), start);
                crate::mul_nt(alpha, &a, &bt, beta, &mut g);
                mul_nt::<R, K, C>(alpha, a.as_slice(), bt.as_slice(), beta, s.as_mut_slice());
                assert_eq!(g, s, "mul_nt {R}×{K}×{C}, alpha {alpha}, beta {beta}");
                let x = rand(K, 1, seed + 4).column(0).into_owned();
                let start = rand(R, 1, seed + 5).column(0).into_owned();
                let (mut g, mut s) = (start.clone(), start);
                crate::gemv(alpha, &a, &x, beta, &mut g);
                gemv::<R>(alpha, a.as_slice(), x.as_slice(), beta, s.as_mut_slice());
                assert_eq!(g, s, "gemv {R}×{K}, alpha {alpha}, beta {beta}");
            }
        }
    }

    /// Factorisation, solves, `I − L C`, symmetrisation: the general kernels' numbers exactly.
    fn square<const N: usize, const R: usize>() {
        let seed = (10 * N + R) as u64;
        let a = spd(N, seed);
        let mut g = a.clone();
        crate::cholesky_in_place(&mut g).unwrap();
        let mut s = a.clone();
        cholesky::<N>(s.as_mut_slice()).unwrap();
        assert_eq!(g, s, "cholesky {N}");
        let x = rand(N, 1, seed + 2);
        let (mut xg, mut xs) = (x.clone(), x);
        crate::solve_lower(g.as_slice(), N, xg.as_mut_slice());
        solve_lower::<N>(s.as_slice(), xs.as_mut_slice());
        assert_eq!(xg, xs, "solve_lower {N}");
        let x = rand(R, N, seed + 3);
        let (mut xg, mut xs) = (x.clone(), x.clone());
        crate::solve_right_lower_t(&mut xg, &g);
        solve_right_lower_t::<R, N>(xs.as_mut_slice(), s.as_slice());
        assert_eq!(xg, xs, "solve_right_lower_t {R}×{N}");
        let (mut xg, mut xs) = (x.clone(), x);
        crate::solve_right_lower(&mut xg, &g);
        solve_right_lower::<R, N>(xs.as_mut_slice(), s.as_slice());
        assert_eq!(xg, xs, "solve_right_lower {R}×{N}");
        let (l, c) = (rand(R, N, seed + 4), rand(N, R, seed + 5));
        let (mut og, mut os) = (DMatrix::zeros(R, R), DMatrix::from_element(R, R, 3.0));
        crate::i_minus_lc(&l, &c, &mut og);
        i_minus_lc::<R, N>(l.as_slice(), c.as_slice(), os.as_mut_slice());
        assert_eq!(og, os, "i_minus_lc {R}×{N}");
        let m = rand(N, N, seed + 6);
        let (mut mg, mut ms) = (m.clone(), m);
        crate::symmetrize(&mut mg);
        symmetrize::<N>(ms.as_mut_slice());
        assert_eq!(mg, ms, "symmetrize {N}");
        // A failing pivot: the same report.
        if N > 1 {
            let mut bad = a.clone();
            bad[(N - 1, N - 1)] = -1.0;
            let mut bs = bad.clone();
            assert_eq!(crate::cholesky_in_place(&mut bad).unwrap_err(), cholesky::<N>(bs.as_mut_slice()).unwrap_err());
        }
    }

    macro_rules! each {
        ($f:ident; $([$($s:literal),*])*) => { $( $f::<$($s),*>(); )* };
    }

    #[test]
    fn products_match_the_general_kernels() {
        each!(products; [1, 1, 1] [1, 3, 2] [2, 2, 2] [3, 4, 3] [4, 4, 4] [4, 3, 4] [4, 4, 3] [3, 4, 4]
            [5, 2, 7] [6, 6, 3] [6, 3, 6] [7, 8, 1] [8, 8, 8] [8, 5, 8] [13, 13, 6]);
    }

    #[test]
    fn factorisation_and_solves_match_the_general_kernels() {
        each!(square; [1, 1] [1, 4] [2, 3] [3, 3] [3, 4] [4, 4] [4, 3] [5, 6] [6, 6] [7, 2] [8, 8] [8, 13]);
    }

    #[test]
    fn slices_longer_than_the_size_are_fine() {
        let a = [1.0, 2.0, 3.0, 4.0, 99.0];
        let mut out = [0.0, 0.0, 5.0];
        gemv::<2>(1.0, &a[..4], &[1.0, 1.0], 0.0, &mut out);
        assert_eq!(out, [4.0, 6.0, 5.0]);
    }
}
