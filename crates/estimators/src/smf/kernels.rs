//! The step's linear algebra compiled per size.
//!
//! The prediction `X₁ = A P Aᵀ`, the data check, the gain (G1) with `g(τ)` and its derivatives,
//! and the certification are each written once, generic over [`Kernels`]: [`General`] runs the
//! runtime-size kernels of `dense_kernels`, [`Fixed`] the const-generic twins of
//! [`dense_kernels::fixed`], which perform the same operations in the same order (zero
//! multipliers skipped alike), so both give the same bits on any data. [`StepFns`] holds one
//! instance of each part, chosen once per filter from `(n, m)`: the fixed one for the vehicles'
//! sizes ([`STATES`] × [`OUTPUTS`]), otherwise the general one.

use nalgebra::{DMatrix, DVector};

use dense_kernels::{self as dense, PivotFailure, fixed, small};

use super::certify::{CertInput, CertWork, Inflation, certify_with};
use super::consistency::{CheckInput, Consistency, ConsistencyWork, check_with};
use super::gain::{Eval, GainWork};
use super::update::UpdateProblem;

/// State counts with a compiled step (the vehicles: truck 3, carrier and car 4, vessel 6,
/// BDS/INS 13).
pub(crate) const STATES: [usize; 4] = [3, 4, 6, 13];
/// Output counts with a compiled step (up to the five of the multi-rate tractor; a partial step
/// measures fewer).
pub(crate) const OUTPUTS: [usize; 5] = [1, 2, 3, 4, 5];

/// The products, solves and factorisations of the step, by shape (`n` states, `m` outputs;
/// `mul_nt_mnm` is `out = α a bᵀ + β out` with `a` `m × n`, `b` `m × n`; `gemv_np` has the input
/// count as its columns). Slices of entrywise kernels are cut to [`Kernels::dims`].
pub(crate) trait Kernels {
    /// `(n, m)`: the compiled sizes, or the given ones for [`General`].
    fn dims(n: usize, m: usize) -> (usize, usize);
    fn mul_nn_nnn(alpha: f64, a: &DMatrix<f64>, b: &DMatrix<f64>, beta: f64, out: &mut DMatrix<f64>);
    fn mul_nt_nnn(alpha: f64, a: &DMatrix<f64>, b: &DMatrix<f64>, beta: f64, out: &mut DMatrix<f64>);
    fn mul_nn_mnn(alpha: f64, a: &DMatrix<f64>, b: &DMatrix<f64>, beta: f64, out: &mut DMatrix<f64>);
    fn mul_nt_mnm(alpha: f64, a: &DMatrix<f64>, b: &DMatrix<f64>, beta: f64, out: &mut DMatrix<f64>);
    fn mul_nt_nnm(alpha: f64, a: &DMatrix<f64>, b: &DMatrix<f64>, beta: f64, out: &mut DMatrix<f64>);
    fn mul_nn_mnm(alpha: f64, a: &DMatrix<f64>, b: &DMatrix<f64>, beta: f64, out: &mut DMatrix<f64>);
    fn mul_nn_nmm(alpha: f64, a: &DMatrix<f64>, b: &DMatrix<f64>, beta: f64, out: &mut DMatrix<f64>);
    fn mul_nn_nnm(alpha: f64, a: &DMatrix<f64>, b: &DMatrix<f64>, beta: f64, out: &mut DMatrix<f64>);
    fn mul_nt_nmn(alpha: f64, a: &DMatrix<f64>, b: &DMatrix<f64>, beta: f64, out: &mut DMatrix<f64>);
    fn gemv_nn(alpha: f64, a: &DMatrix<f64>, x: &DVector<f64>, beta: f64, out: &mut DVector<f64>);
    fn gemv_np(alpha: f64, a: &DMatrix<f64>, x: &DVector<f64>, beta: f64, out: &mut DVector<f64>);
    fn gemv_nm(alpha: f64, a: &DMatrix<f64>, x: &DVector<f64>, beta: f64, out: &mut DVector<f64>);
    fn gemv_mn(alpha: f64, a: &DMatrix<f64>, x: &DVector<f64>, beta: f64, out: &mut DVector<f64>);
    fn gemv_mm(alpha: f64, a: &DMatrix<f64>, x: &DVector<f64>, beta: f64, out: &mut DVector<f64>);
    /// `out = I − L C`, `L` `n × m`.
    fn i_minus_lc(l: &DMatrix<f64>, c: &DMatrix<f64>, out: &mut DMatrix<f64>);
    fn symmetrize_n(a: &mut DMatrix<f64>);
    fn symmetrize_m(a: &mut DMatrix<f64>);
    fn cholesky_m(a: &mut DMatrix<f64>) -> Result<(), PivotFailure>;
    fn cholesky_solve_m(g: &DMatrix<f64>, x: &mut DVector<f64>);
    /// `x ← x G⁻ᵀ`, `x` `n × m`.
    fn solve_right_lower_t_nm(x: &mut DMatrix<f64>, g: &DMatrix<f64>);
    /// `x ← x G⁻¹`, `x` `n × m`.
    fn solve_right_lower_nm(x: &mut DMatrix<f64>, g: &DMatrix<f64>);
}

/// The runtime-size kernels (any size).
pub(crate) struct General;

/// The kernels of `N` states and `M` outputs.
pub(crate) struct Fixed<const N: usize, const M: usize>;

macro_rules! general_products {
    ($($name:ident => $f:ident;)*) => {
        $(#[inline(always)]
        fn $name(alpha: f64, a: &DMatrix<f64>, b: &DMatrix<f64>, beta: f64, out: &mut DMatrix<f64>) {
            dense::$f(alpha, a, b, beta, out)
        })*
    };
}

macro_rules! fixed_products {
    ($($name:ident => $f:ident <$r:ident, $k:ident, $c:ident>;)*) => {
        $(#[inline(always)]
        fn $name(alpha: f64, a: &DMatrix<f64>, b: &DMatrix<f64>, beta: f64, out: &mut DMatrix<f64>) {
            debug_assert!(a.shape() == ($r, $k) && out.shape() == ($r, $c));
            fixed::$f::<$r, $k, $c>(alpha, a.as_slice(), b.as_slice(), beta, out.as_mut_slice())
        })*
    };
}

impl Kernels for General {
    #[inline(always)]
    fn dims(n: usize, m: usize) -> (usize, usize) {
        (n, m)
    }
    general_products! {
        mul_nn_nnn => mul_nn; mul_nt_nnn => mul_nt; mul_nn_mnn => mul_nn; mul_nt_mnm => mul_nt;
        mul_nt_nnm => mul_nt; mul_nn_mnm => mul_nn; mul_nn_nmm => mul_nn; mul_nn_nnm => mul_nn;
        mul_nt_nmn => mul_nt;
    }
    #[inline(always)]
    fn gemv_nn(alpha: f64, a: &DMatrix<f64>, x: &DVector<f64>, beta: f64, out: &mut DVector<f64>) {
        dense::gemv(alpha, a, x, beta, out)
    }
    #[inline(always)]
    fn gemv_np(alpha: f64, a: &DMatrix<f64>, x: &DVector<f64>, beta: f64, out: &mut DVector<f64>) {
        dense::gemv(alpha, a, x, beta, out)
    }
    #[inline(always)]
    fn gemv_nm(alpha: f64, a: &DMatrix<f64>, x: &DVector<f64>, beta: f64, out: &mut DVector<f64>) {
        dense::gemv(alpha, a, x, beta, out)
    }
    #[inline(always)]
    fn gemv_mn(alpha: f64, a: &DMatrix<f64>, x: &DVector<f64>, beta: f64, out: &mut DVector<f64>) {
        dense::gemv(alpha, a, x, beta, out)
    }
    #[inline(always)]
    fn gemv_mm(alpha: f64, a: &DMatrix<f64>, x: &DVector<f64>, beta: f64, out: &mut DVector<f64>) {
        dense::gemv(alpha, a, x, beta, out)
    }
    #[inline(always)]
    fn i_minus_lc(l: &DMatrix<f64>, c: &DMatrix<f64>, out: &mut DMatrix<f64>) {
        dense::i_minus_lc(l, c, out)
    }
    #[inline(always)]
    fn symmetrize_n(a: &mut DMatrix<f64>) {
        dense::symmetrize(a)
    }
    #[inline(always)]
    fn symmetrize_m(a: &mut DMatrix<f64>) {
        dense::symmetrize(a)
    }
    #[inline(always)]
    fn cholesky_m(a: &mut DMatrix<f64>) -> Result<(), PivotFailure> {
        dense::cholesky_in_place(a)
    }
    #[inline(always)]
    fn cholesky_solve_m(g: &DMatrix<f64>, x: &mut DVector<f64>) {
        dense::cholesky_solve(g.as_slice(), g.nrows(), x.as_mut_slice())
    }
    #[inline(always)]
    fn solve_right_lower_t_nm(x: &mut DMatrix<f64>, g: &DMatrix<f64>) {
        dense::solve_right_lower_t(x, g)
    }
    #[inline(always)]
    fn solve_right_lower_nm(x: &mut DMatrix<f64>, g: &DMatrix<f64>) {
        dense::solve_right_lower(x, g)
    }
}

impl<const N: usize, const M: usize> Kernels for Fixed<N, M> {
    #[inline(always)]
    fn dims(n: usize, m: usize) -> (usize, usize) {
        debug_assert_eq!((n, m), (N, M));
        (N, M)
    }
    fixed_products! {
        mul_nn_nnn => mul_nn<N, N, N>; mul_nt_nnn => mul_nt<N, N, N>; mul_nn_mnn => mul_nn<M, N, N>;
        mul_nt_mnm => mul_nt<M, N, M>; mul_nt_nnm => mul_nt<N, N, M>; mul_nn_mnm => mul_nn<M, N, M>;
        mul_nn_nmm => mul_nn<N, M, M>; mul_nn_nnm => mul_nn<N, N, M>; mul_nt_nmn => mul_nt<N, M, N>;
    }
    #[inline(always)]
    fn gemv_nn(alpha: f64, a: &DMatrix<f64>, x: &DVector<f64>, beta: f64, out: &mut DVector<f64>) {
        fixed::gemv::<N, N>(alpha, a.as_slice(), x.as_slice(), beta, out.as_mut_slice())
    }
    #[inline(always)]
    fn gemv_np(alpha: f64, a: &DMatrix<f64>, x: &DVector<f64>, beta: f64, out: &mut DVector<f64>) {
        debug_assert!(a.nrows() == N && a.ncols() == x.len());
        fixed::gemv_cols::<N>(alpha, a.as_slice(), x.as_slice(), beta, out.as_mut_slice())
    }
    #[inline(always)]
    fn gemv_nm(alpha: f64, a: &DMatrix<f64>, x: &DVector<f64>, beta: f64, out: &mut DVector<f64>) {
        fixed::gemv::<N, M>(alpha, a.as_slice(), x.as_slice(), beta, out.as_mut_slice())
    }
    #[inline(always)]
    fn gemv_mn(alpha: f64, a: &DMatrix<f64>, x: &DVector<f64>, beta: f64, out: &mut DVector<f64>) {
        fixed::gemv::<M, N>(alpha, a.as_slice(), x.as_slice(), beta, out.as_mut_slice())
    }
    #[inline(always)]
    fn gemv_mm(alpha: f64, a: &DMatrix<f64>, x: &DVector<f64>, beta: f64, out: &mut DVector<f64>) {
        fixed::gemv::<M, M>(alpha, a.as_slice(), x.as_slice(), beta, out.as_mut_slice())
    }
    #[inline(always)]
    fn i_minus_lc(l: &DMatrix<f64>, c: &DMatrix<f64>, out: &mut DMatrix<f64>) {
        fixed::i_minus_lc::<N, M>(l.as_slice(), c.as_slice(), out.as_mut_slice())
    }
    #[inline(always)]
    fn symmetrize_n(a: &mut DMatrix<f64>) {
        small::symmetrize::<N>(a.as_mut_slice())
    }
    #[inline(always)]
    fn symmetrize_m(a: &mut DMatrix<f64>) {
        small::symmetrize::<M>(a.as_mut_slice())
    }
    #[inline(always)]
    fn cholesky_m(a: &mut DMatrix<f64>) -> Result<(), PivotFailure> {
        small::cholesky::<M>(a.as_mut_slice())
    }
    #[inline(always)]
    fn cholesky_solve_m(g: &DMatrix<f64>, x: &mut DVector<f64>) {
        fixed::cholesky_solve::<M>(g.as_slice(), x.as_mut_slice())
    }
    #[inline(always)]
    fn solve_right_lower_t_nm(x: &mut DMatrix<f64>, g: &DMatrix<f64>) {
        fixed::solve_right_lower_t::<N, M>(x.as_mut_slice(), g.as_slice())
    }
    #[inline(always)]
    fn solve_right_lower_nm(x: &mut DMatrix<f64>, g: &DMatrix<f64>) {
        fixed::solve_right_lower::<N, M>(x.as_mut_slice(), g.as_slice())
    }
}

/// `X₁ = A P Aᵀ` with the scratch `ap = A P`.
type X1Fn = fn(&DMatrix<f64>, &DMatrix<f64>, &mut DMatrix<f64>, &mut DMatrix<f64>);
/// `z = A x + B u`.
type CentreFn = fn(&DMatrix<f64>, &DMatrix<f64>, &DVector<f64>, &DVector<f64>, &mut DVector<f64>);
/// The data check ([`super::consistency::check`]).
type CheckFn = fn(&mut ConsistencyWork, &CheckInput<'_>) -> Consistency;
type LoadFn = fn(&mut GainWork, &DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>);
type GainFn = fn(&mut GainWork, [f64; 3], &DMatrix<f64>, &DMatrix<f64>) -> bool;
type EvalFn = fn(&mut GainWork, [f64; 3], &UpdateProblem<'_>) -> Option<Eval>;
/// The certification ([`super::certify::certify`]).
type CertifyFn = fn(&mut CertWork, &CertInput<'_>) -> Option<Inflation>;

/// One instance of each part of the step, chosen once ([`StepFns::for_sizes`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct StepFns {
    pub(crate) x1: X1Fn,
    pub(crate) centre: CentreFn,
    pub(crate) check: CheckFn,
    pub(crate) load: LoadFn,
    pub(crate) gain: GainFn,
    pub(crate) eval: EvalFn,
    pub(crate) certify: CertifyFn,
    /// Whether these are the compiled sizes' instances.
    pub(crate) fixed: bool,
}

impl StepFns {
    /// The compiled instance for `(n, m)` in [`STATES`] × [`OUTPUTS`], the general one otherwise.
    pub(crate) fn for_sizes(n: usize, m: usize) -> Self {
        if !(STATES.contains(&n) && OUTPUTS.contains(&m)) {
            return Self::general();
        }
        macro_rules! by {
            ([$($n:literal)*] $ms:tt) => { match n { $($n => by!(@m $n, $ms),)* _ => Self::general() } };
            (@m $n:literal, [$($m:literal)*]) => { match m { $($m => table::<Fixed<$n, $m>>(true),)* _ => Self::general() } };
        }
        by!([3 4 6 13] [1 2 3 4 5])
    }

    /// The runtime-size instance.
    pub(crate) fn general() -> Self {
        table::<General>(false)
    }
}

fn table<K: Kernels>(fixed: bool) -> StepFns {
    StepFns {
        x1: x1::<K>,
        centre: centre::<K>,
        check: check_with::<K>,
        load: GainWork::load_with::<K>,
        gain: GainWork::gain_with::<K>,
        eval: GainWork::eval_with::<K>,
        certify: certify_with::<K>,
        fixed,
    }
}

fn x1<K: Kernels>(a: &DMatrix<f64>, p: &DMatrix<f64>, ap: &mut DMatrix<f64>, x1: &mut DMatrix<f64>) {
    K::mul_nn_nnn(1.0, a, p, 0.0, ap);
    K::mul_nt_nnn(1.0, ap, a, 0.0, x1);
}

fn centre<K: Kernels>(a: &DMatrix<f64>, b: &DMatrix<f64>, x: &DVector<f64>, u: &DVector<f64>, z: &mut DVector<f64>) {
    K::gemv_nn(1.0, a, x, 0.0, z);
    K::gemv_np(1.0, b, u, 1.0, z);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_lists_exactly_the_compiled_sizes() {
        for n in 1..=14 {
            for m in 1..=9 {
                let fixed = STATES.contains(&n) && OUTPUTS.contains(&m);
                assert_eq!(StepFns::for_sizes(n, m).fixed, fixed, "({n}, {m})");
            }
        }
    }
}
