//! Symmetric eigendecomposition for the small dense blocks of the interior-point method.
//!
//! Householder tridiagonalisation followed by the implicit QL algorithm with Wilkinson-type
//! shifts (the `tred2`/`tql2` pair of EISPACK, after Bowdler, Martin, Reinsch and Wilkinson,
//! *Handbook for Automatic Computation II*, as in JAMA). For the block orders this solver is
//! meant for (a few dozen rows) a tight scalar loop beats a general-purpose blocked
//! implementation by a wide margin: the per-call overhead of the latter dominates at `n ≈ 16`.
//! Everything works in place on caller buffers; nothing allocates.

/// Eigen-decomposes the symmetric matrix whose lower triangle is stored column-major in `a`.
///
/// On return `d` holds the eigenvalues (unsorted) and, if `want_vectors`, `a` holds the
/// orthonormal eigenvectors as columns (`a[:, j]` belongs to `d[j]`); otherwise `a` is
/// overwritten with intermediate data. `e` is scratch of length `n`. Returns `false` if the QL
/// iteration did not converge or met a non-finite value.
#[inline(always)]
pub(crate) fn sym_eig(a: &mut [f64], n: usize, d: &mut [f64], e: &mut [f64], want_vectors: bool) -> bool {
    if n == 0 {
        return true;
    }
    if n == 1 {
        d[0] = a[0];
        if want_vectors {
            a[0] = 1.0;
        }
        return a[0].is_finite() && d[0].is_finite();
    }
    tred2(a, n, d, e, want_vectors);
    tql2(a, n, d, e, want_vectors)
}

/// The smallest eigenvalue of the symmetric matrix whose lower triangle is in `a` (destroyed).
#[cfg(test)]
pub(crate) fn sym_min_eig(a: &mut [f64], n: usize, d: &mut [f64], e: &mut [f64]) -> Option<f64> {
    if !sym_eig(a, n, d, e, false) {
        return None;
    }
    Some(d[..n].iter().copied().fold(f64::INFINITY, f64::min))
}

// `v[k + j n]` is V[k][j] of the Algol/JAMA formulation.
#[inline(always)]
fn tred2(v: &mut [f64], n: usize, d: &mut [f64], e: &mut [f64], want_vectors: bool) {
    for j in 0..n {
        d[j] = v[(n - 1) + j * n];
    }
    for i in (1..n).rev() {
        let mut scale = 0.0;
        let mut h = 0.0;
        for k in 0..i {
            scale += d[k].abs();
        }
        if scale == 0.0 {
            e[i] = d[i - 1];
            for j in 0..i {
                d[j] = v[(i - 1) + j * n];
                v[i + j * n] = 0.0;
                v[j + i * n] = 0.0;
            }
        } else {
            for k in 0..i {
                d[k] /= scale;
                h += d[k] * d[k];
            }
            let mut f = d[i - 1];
            let mut g = h.sqrt();
            if f > 0.0 {
                g = -g;
            }
            e[i] = scale * g;
            h -= f * g;
            d[i - 1] = f - g;
            e[..i].fill(0.0);
            for j in 0..i {
                f = d[j];
                v[j + i * n] = f;
                let col = &v[j * n..j * n + i];
                g = e[j] + col[j] * f;
                for ((cv, dk), ek) in col[j + 1..].iter().zip(&d[j + 1..i]).zip(&mut e[j + 1..i]) {
                    g += cv * dk;
                    *ek += cv * f;
                }
                e[j] = g;
            }
            f = 0.0;
            for j in 0..i {
                e[j] /= h;
                f += e[j] * d[j];
            }
            let hh = f / (h + h);
            for j in 0..i {
                e[j] -= hh * d[j];
            }
            for j in 0..i {
                f = d[j];
                g = e[j];
                let col = &mut v[j * n..j * n + n];
                for ((cv, ek), dk) in col[j..i].iter_mut().zip(&e[j..i]).zip(&d[j..i]) {
                    *cv -= f * ek + g * dk;
                }
                d[j] = col[i - 1];
                col[i] = 0.0;
            }
        }
        d[i] = h;
    }
    if want_vectors {
        for i in 0..n - 1 {
            v[(n - 1) + i * n] = v[i + i * n];
            v[i + i * n] = 1.0;
            let h = d[i + 1];
            if h != 0.0 {
                for k in 0..=i {
                    d[k] = v[k + (i + 1) * n] / h;
                }
                let (left, right) = v.split_at_mut((i + 1) * n);
                let vi1 = &right[..=i];
                for j in 0..=i {
                    let vj = &mut left[j * n..j * n + i + 1];
                    let g: f64 = vi1.iter().zip(vj.iter()).map(|(a, b)| a * b).sum();
                    for (x, dk) in vj.iter_mut().zip(&d[..=i]) {
                        *x -= g * dk;
                    }
                }
            }
            for k in 0..=i {
                v[k + (i + 1) * n] = 0.0;
            }
        }
        for j in 0..n {
            d[j] = v[(n - 1) + j * n];
            v[(n - 1) + j * n] = 0.0;
        }
        v[(n - 1) + (n - 1) * n] = 1.0;
    } else {
        for j in 0..n {
            d[j] = v[j + j * n];
        }
    }
    e[0] = 0.0;
}

#[inline(always)]
fn tql2(v: &mut [f64], n: usize, d: &mut [f64], e: &mut [f64], want_vectors: bool) -> bool {
    for i in 1..n {
        e[i - 1] = e[i];
    }
    e[n - 1] = 0.0;
    let mut f = 0.0;
    let mut tst1: f64 = 0.0;
    let eps = f64::EPSILON;
    for l in 0..n {
        tst1 = tst1.max(d[l].abs() + e[l].abs());
        if !tst1.is_finite() {
            return false;
        }
        let mut m = l;
        while m < n {
            if e[m].abs() <= eps * tst1 {
                break;
            }
            m += 1;
        }
        if m > l {
            let mut iter = 0;
            loop {
                iter += 1;
                if iter > 60 {
                    return false;
                }
                let mut g = d[l];
                let mut p = (d[l + 1] - g) / (2.0 * e[l]);
                let mut r = hypot(p, 1.0);
                if p < 0.0 {
                    r = -r;
                }
                d[l] = e[l] / (p + r);
                d[l + 1] = e[l] * (p + r);
                let dl1 = d[l + 1];
                let mut h = g - d[l];
                for di in d.iter_mut().take(n).skip(l + 2) {
                    *di -= h;
                }
                f += h;
                p = d[m];
                let mut c = 1.0;
                let mut c2 = c;
                let mut c3 = c;
                let el1 = e[l + 1];
                let mut s = 0.0;
                let mut s2 = 0.0;
                for i in (l..m).rev() {
                    c3 = c2;
                    c2 = c;
                    s2 = s;
                    g = c * e[i];
                    h = c * p;
                    r = hypot(p, e[i]);
                    e[i + 1] = s * r;
                    s = e[i] / r;
                    c = p / r;
                    p = c * d[i] - s * g;
                    d[i + 1] = h + s * (c * g + s * d[i]);
                    if want_vectors {
                        let (lo, hi) = v.split_at_mut((i + 1) * n);
                        let vi = &mut lo[i * n..i * n + n];
                        let vi1 = &mut hi[..n];
                        for k in 0..n {
                            let hk = vi1[k];
                            vi1[k] = s * vi[k] + c * hk;
                            vi[k] = c * vi[k] - s * hk;
                        }
                    }
                }
                p = -s * s2 * c3 * el1 * e[l] / dl1;
                e[l] = s * p;
                d[l] = c * p;
                if !p.is_finite() {
                    return false;
                }
                if e[l].abs() <= eps * tst1 {
                    break;
                }
            }
        }
        d[l] += f;
        e[l] = 0.0;
    }
    true
}

/// Largest `α ∈ (0, cap]` with `I + αS ⪰ 0`, for the symmetric `S` whose lower triangle is in
/// `a` (destroyed); `w` is scratch of the same size, `d`, `e` of length `n`.
///
/// First one Cholesky test of `I + cap·S` (the usual case near the end: the full step is
/// feasible). Otherwise `S` is reduced to tridiagonal form and its smallest eigenvalue is
/// bracketed by bisection on Sturm counts to a relative accuracy of `10⁻⁴`; the returned step
/// uses the lower end of the bracket, so it never exceeds the true maximum step.
#[inline(always)]
pub(crate) fn max_step(a: &mut [f64], w: &mut [f64], n: usize, cap: f64, d: &mut [f64], e: &mut [f64]) -> Option<f64> {
    if n == 0 {
        return Some(cap);
    }
    for j in 0..n {
        for i in j..n {
            w[i + j * n] = cap * a[i + j * n] + if i == j { 1.0 } else { 0.0 };
        }
    }
    if cholesky_lower_ok(w, n) {
        return Some(cap);
    }
    tred2(a, n, d, e, false);
    // Tridiagonal: diagonal d[i], off-diagonal e[i] between rows i − 1 and i (e[0] = 0).
    let mut lo = f64::INFINITY;
    for i in 0..n {
        let r = e[i].abs() + if i + 1 < n { e[i + 1].abs() } else { 0.0 };
        lo = lo.min(d[i] - r);
    }
    if !lo.is_finite() {
        return None;
    }
    let mut hi = -1.0 / cap;
    if sturm_below(d, e, n, hi) == 0 {
        // The Cholesky test failed by rounding only.
        return Some(cap);
    }
    if lo >= hi {
        lo = hi - hi.abs().max(1e-300);
    }
    // Multisection: four Sturm counts per pass (independent recurrences, so their divisions
    // overlap), shrinking the bracket five-fold. Invariant: no eigenvalue below `lo`, one below `hi`.
    while hi - lo > 1e-4 * lo.abs() {
        let h = 0.2 * (hi - lo);
        let x = [lo + h, lo + 2.0 * h, lo + 3.0 * h, lo + 4.0 * h];
        let below = sturm_below4(d, e, n, x);
        match below.iter().position(|&b| b) {
            Some(0) => hi = x[0],
            Some(k) => {
                lo = x[k - 1];
                hi = x[k];
            }
            None => lo = x[3],
        }
    }
    Some((-1.0 / lo).min(cap))
}

/// Whether the symmetric tridiagonal matrix (`d`, `e`) has an eigenvalue below each of `x`
/// (four Sturm sequences evaluated side by side).
#[inline(always)]
fn sturm_below4(d: &[f64], e: &[f64], n: usize, x: [f64; 4]) -> [bool; 4] {
    let mut q = [0.0; 4];
    let mut neg = [false; 4];
    for l in 0..4 {
        q[l] = d[0] - x[l];
        neg[l] = q[l] < 0.0;
    }
    for i in 1..n {
        let e2 = e[i] * e[i];
        let tiny = f64::EPSILON * (e[i].abs() + 1e-300);
        for l in 0..4 {
            let qq = if q[l] == 0.0 { tiny } else { q[l] };
            q[l] = d[i] - x[l] - e2 / qq;
            neg[l] |= q[l] < 0.0;
        }
    }
    neg
}

/// Like [`max_step`] but coarse and cheaper: the largest `α ∈ {cap} ∪ {k·cap/2^halvings}` with
/// `I + αS ⪰ 0`, found by Cholesky tests only (`a` is not modified). Used for the predictor,
/// whose step only sets the centring parameter.
#[inline(always)]
pub(crate) fn max_step_coarse(a: &[f64], w: &mut [f64], n: usize, cap: f64, halvings: u32) -> f64 {
    #[inline(always)]
    fn pd(a: &[f64], w: &mut [f64], n: usize, alpha: f64) -> bool {
        for j in 0..n {
            for i in j..n {
                w[i + j * n] = alpha * a[i + j * n] + if i == j { 1.0 } else { 0.0 };
            }
        }
        cholesky_lower_ok(w, n)
    }
    if pd(a, w, n, cap) {
        return cap;
    }
    let (mut lo, mut hi) = (0.0, cap);
    for _ in 0..halvings {
        let mid = 0.5 * (lo + hi);
        if pd(a, w, n, mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Largest `α ∈ (0, cap]` with `X + αΔ ≻ 0` (lower triangles of `x` and `dir`), found by
/// Cholesky tests alone (HKM direction: no scaled matrix is formed): `cap` first, then at least
/// `halvings` bisections of `[0, cap]`, continued until the bracket `[lo, hi]` has
/// `hi − lo ≤ rtol·hi` (`rtol ≥ 1` stops after the halvings). Returns the feasible end `lo`.
#[inline(always)]
pub(crate) fn max_step_pencil(
    x: &[f64],
    dir: &[f64],
    w: &mut [f64],
    n: usize,
    cap: f64,
    halvings: u32,
    rtol: f64,
) -> f64 {
    #[inline(always)]
    fn pd(x: &[f64], dir: &[f64], w: &mut [f64], n: usize, alpha: f64) -> bool {
        for j in 0..n {
            let r = j * n + j..j * n + n;
            for ((o, a), d) in w[r.clone()].iter_mut().zip(&x[r.clone()]).zip(&dir[r]) {
                *o = a + alpha * d;
            }
        }
        cholesky_lower_ok(w, n)
    }
    if n == 0 || pd(x, dir, w, n, cap) {
        return cap;
    }
    let (mut lo, mut hi) = (0.0, cap);
    // 60 bisections reach the resolution of f64 (a step below 1e-18·cap is no step).
    for k in 0..60 {
        if k >= halvings && hi - lo <= rtol * hi {
            break;
        }
        let mid = 0.5 * (lo + hi);
        if pd(x, dir, w, n, mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// Number of eigenvalues below `x` of the symmetric tridiagonal matrix (`d`, `e`).
#[inline(always)]
fn sturm_below(d: &[f64], e: &[f64], n: usize, x: f64) -> usize {
    let mut count = 0;
    let mut q = d[0] - x;
    if q < 0.0 {
        count += 1;
    }
    for i in 1..n {
        let qq = if q == 0.0 { f64::EPSILON * (e[i].abs() + 1e-300) } else { q };
        q = d[i] - x - e[i] * e[i] / qq;
        if q < 0.0 {
            count += 1;
        }
    }
    count
}

/// In-place Cholesky of the lower triangle of `w` (left-looking, for small orders); returns
/// whether `w` is numerically positive definite. The strict upper triangle is not touched.
#[inline(always)]
pub(crate) fn cholesky_lower_ok(w: &mut [f64], n: usize) -> bool {
    for j in 0..n {
        let (left, right) = w.split_at_mut(j * n);
        let colj = &mut right[..n];
        // colj[j..] -= Σ_{k<j} L[j,k] L[j..,k]; for larger orders four columns k at a time
        // (fewer short loops).
        let mut k0 = 0;
        if n > 20 {
            while k0 + 4 <= j {
                let k = k0;
                let c0 = &left[k * n + j..k * n + n];
                let c1 = &left[(k + 1) * n + j..(k + 1) * n + n];
                let c2 = &left[(k + 2) * n + j..(k + 2) * n + n];
                let c3 = &left[(k + 3) * n + j..(k + 3) * n + n];
                let (l0, l1, l2, l3) = (c0[0], c1[0], c2[0], c3[0]);
                for ((((x, a), b), c), d) in colj[j..].iter_mut().zip(c0).zip(c1).zip(c2).zip(c3) {
                    *x -= (l0 * a + l1 * b) + (l2 * c + l3 * d);
                }
                k0 += 4;
            }
        }
        for k in k0..j {
            let colk = &left[k * n..k * n + n];
            let ljk = colk[j];
            if ljk != 0.0 {
                for (x, y) in colj[j..].iter_mut().zip(&colk[j..]) {
                    *x -= ljk * y;
                }
            }
        }
        let piv = colj[j];
        if piv.is_nan() || piv <= 0.0 {
            return false;
        }
        let r = piv.sqrt();
        colj[j] = r;
        let inv = 1.0 / r;
        for x in &mut colj[j + 1..] {
            *x *= inv;
        }
    }
    true
}

/// `√(a² + b²)` without libm's (slow, fully IEEE-careful) `hypot`; rescales only when the
/// squares could overflow or underflow.
#[inline(always)]
fn hypot(a: f64, b: f64) -> f64 {
    let s = a * a + b * b;
    if s > 1e-290 && s < 1e290 { s.sqrt() } else { a.hypot(b) }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(n: usize, seed: u64) {
        let mut s = seed;
        let mut rnd = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let mut a = vec![0.0; n * n];
        for j in 0..n {
            for i in j..n {
                let v = rnd();
                a[i + j * n] = v;
                a[j + i * n] = v;
            }
        }
        let mut v = a.clone();
        let mut d = vec![0.0; n];
        let mut e = vec![0.0; n];
        assert!(sym_eig(&mut v, n, &mut d, &mut e, true));
        // A V = V diag(d), Vᵀ V = I.
        for j in 0..n {
            for i in 0..n {
                let av: f64 = (0..n).map(|k| a[i + k * n] * v[k + j * n]).sum();
                assert!((av - d[j] * v[i + j * n]).abs() < 1e-12, "n={n}");
                let vv: f64 = (0..n).map(|k| v[k + i * n] * v[k + j * n]).sum();
                assert!((vv - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12);
            }
        }
        let mut w = a.clone();
        let min = sym_min_eig(&mut w, n, &mut vec![0.0; n], &mut e).unwrap();
        let exact = d.iter().copied().fold(f64::INFINITY, f64::min);
        assert!((min - exact).abs() < 1e-12);
        // Maximum step of I + αA: −1/λmin when λmin < 0 (capped).
        for cap in [0.5, 1.0, 1e6] {
            let mut w = a.clone();
            let mut scratch = vec![0.0; n * n];
            let alpha = max_step(&mut w, &mut scratch, n, cap, &mut vec![0.0; n], &mut e).unwrap();
            let expected = if exact < 0.0 { (-1.0 / exact).min(cap) } else { cap };
            assert!(alpha <= expected * (1.0 + 1e-12) && alpha >= expected * (1.0 - 2e-4), "{alpha} {expected}");
        }
    }

    #[test]
    fn eigendecomposition_is_accurate() {
        for n in 1..=20 {
            check(n, n as u64 * 7 + 1);
        }
        check(40, 3);
        // A diagonal matrix and a matrix with repeated eigenvalues.
        let n = 5;
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            a[i + i * n] = 2.0;
        }
        let mut d = vec![0.0; n];
        let mut e = vec![0.0; n];
        assert!(sym_eig(&mut a, n, &mut d, &mut e, true));
        assert!(d.iter().all(|x| (x - 2.0).abs() < 1e-15));
    }
}
