//! The Gaussian estimate the Kalman-type filters publish ([`GaussianEstimate`]), and the linear
//! algebra of the Kalman and extended Kalman steps, at the filter's sizes.
//!
//! [`StepKernels`] is chosen once per filter from `(n, m)`: for `n ≤` [`MAX_STATES`] (the
//! vehicles' filters have 3 to 13 states) and `m ≤` [`MAX_OUTPUTS`] the
//! const-generic instances of [`dense_kernels::small`] (constant trip counts, no bounds checks,
//! output columns in registers), otherwise the general runtime-size kernels. Both perform the
//! same operations in the same order, so they give the same numbers (tested on every dispatched
//! size).

use nalgebra::{DMatrix, DVector};

use dense_kernels as dense;
use dense_kernels::PivotFailure;
use dense_kernels::small;

use crate::checks::{GateVerdict, InnovationGate, name_worst_output};
use crate::error::EstimatorError;
use crate::traits::{DataCheck, Estimate, EstimateKind, SolveOutcome, StepDetails, StepStatus};
use crate::validate::all_finite;

/// A Gaussian estimate after a step (Kalman, extended, unscented and adaptive filters): mean,
/// covariance, per-state standard deviations, the step's status and the filter's details.
#[derive(Debug, Clone, PartialEq)]
pub struct GaussianEstimate {
    /// Posterior mean `x̂_{k+1}`.
    pub center: DVector<f64>,
    /// Posterior covariance `P_{k+1}` (symmetric).
    pub covariance: DMatrix<f64>,
    /// `√P_ii`.
    pub std_dev: DVector<f64>,
    /// How the step ended ([`SolveOutcome::Converged`] for a measurement update,
    /// [`SolveOutcome::Predicted`] for a prediction; a fallback when a guard was needed).
    pub status: StepStatus,
    /// The filter's own details ([`StepDetails::NONE`] for the Kalman filters).
    pub details: StepDetails,
}

impl GaussianEstimate {
    /// The initial estimate `(x0, P0)` with the given details.
    pub(crate) fn initial(x0: DVector<f64>, p0: DMatrix<f64>, details: StepDetails) -> Self {
        let std_dev = p0.diagonal().map(|v| v.max(0.0).sqrt());
        Self { center: x0, covariance: p0, std_dev, status: StepStatus::INITIAL, details }
    }

    /// Recomputes `std_dev` from the covariance.
    pub(crate) fn refresh_std_dev(&mut self) {
        let n = self.center.len();
        for (sd, v) in self.std_dev.iter_mut().zip(self.covariance.as_slice().iter().step_by(n + 1)) {
            *sd = v.max(0.0).sqrt();
        }
    }
}

impl Estimate for GaussianEstimate {
    fn kind(&self) -> EstimateKind {
        EstimateKind::Gaussian
    }
    fn center(&self) -> &DVector<f64> {
        &self.center
    }
    fn shape(&self) -> &DMatrix<f64> {
        &self.covariance
    }
    fn bounds(&self, i: usize) -> Option<(f64, f64)> {
        (i < self.center.len()).then(|| (self.center[i] - self.std_dev[i], self.center[i] + self.std_dev[i]))
    }
    fn status(&self) -> StepStatus {
        self.status
    }
    fn details(&self) -> StepDetails {
        self.details
    }
}

/// Publishes a prediction `(x⁻, P⁻)` as the estimate (swapping buffers) after checking that it is
/// finite; on error nothing changes. Shared by the prediction-only steps of the Kalman and the
/// extended Kalman filter.
pub(crate) fn commit_prediction(
    est: &mut GaussianEstimate,
    x_pred: &mut DVector<f64>,
    p_pred: &mut DMatrix<f64>,
) -> Result<(), EstimatorError> {
    if !all_finite(x_pred.as_slice()) || !all_finite(p_pred.as_slice()) {
        return Err(EstimatorError::NumericalFailure("the prediction is not finite"));
    }
    std::mem::swap(&mut est.center, x_pred);
    std::mem::swap(&mut est.covariance, p_pred);
    est.refresh_std_dev();
    est.status = StepStatus::unchecked(SolveOutcome::Predicted);
    Ok(())
}

/// The data check a gate verdict stands for.
pub(crate) fn data_check(verdict: GateVerdict) -> DataCheck {
    match verdict {
        GateVerdict::Unchecked => DataCheck::NotChecked,
        GateVerdict::Pass => DataCheck::Consistent,
        GateVerdict::FlagAndUse | GateVerdict::Drop => DataCheck::Inconsistent,
    }
}

/// `νᵀ S⁻¹ ν` from the lower Cholesky factor `G` of `S` (`‖G⁻¹ ν‖²`), using `z` (length `m`).
pub(crate) fn nis(g: &DMatrix<f64>, innov: &DVector<f64>, z: &mut DVector<f64>) -> f64 {
    z.copy_from(innov);
    dense::solve_lower(g.as_slice(), g.nrows(), z.as_mut_slice());
    z.iter().map(|v| v * v).sum()
}

/// The largest state count with const-generic kernels.
pub(crate) const MAX_STATES: usize = 13;
/// The largest output count with const-generic kernels.
pub(crate) const MAX_OUTPUTS: usize = 8;

/// `out = sym(a p aᵀ + q)` using the scratch `ap` (all `n × n`).
type PropagateFn = fn(&DMatrix<f64>, &DMatrix<f64>, &DMatrix<f64>, &mut DMatrix<f64>, &mut DMatrix<f64>);
/// `x⁻ = A x + B u` and `P⁻ = sym(A P Aᵀ + Q)` (`a`, `b`, `x`, `p`, `u`, `q`, then the scratch
/// `ap` and the outputs `x⁻`, `P⁻`).
type LinearPredictFn = fn(
    &DMatrix<f64>,
    &DMatrix<f64>,
    &DVector<f64>,
    &DMatrix<f64>,
    &DVector<f64>,
    &DMatrix<f64>,
    &mut DMatrix<f64>,
    &mut DVector<f64>,
    &mut DMatrix<f64>,
);
/// `out = alpha · a · x + beta · out`.
type GemvFn = fn(f64, &DMatrix<f64>, &DVector<f64>, f64, &mut DVector<f64>);
/// The update's linear algebra into the buffers ([`GaussianUpdate::compute`]).
type UpdateFn = fn(
    &mut UpdateBuffers,
    &DVector<f64>,
    &DMatrix<f64>,
    &DMatrix<f64>,
    &DMatrix<f64>,
    &DVector<f64>,
    bool,
) -> Result<f64, PivotFailure>;

/// The kernels of one filter's sizes, chosen once ([`StepKernels::for_sizes`]).
#[derive(Debug, Clone, Copy)]
pub(crate) struct StepKernels {
    /// `P⁻ = sym(A P Aᵀ + Q)`.
    pub(crate) propagate: PropagateFn,
    /// The linear prediction `x⁻ = A x + B u`, `P⁻ = sym(A P Aᵀ + Q)`.
    pub(crate) linear_predict: LinearPredictFn,
    /// Matrix–vector product with `m` rows.
    pub(crate) gemv_m: GemvFn,
    update: UpdateFn,
}

impl StepKernels {
    /// The const-generic kernels for `n ≤` [`MAX_STATES`] states and `m ≤` [`MAX_OUTPUTS`]
    /// outputs, the general ones otherwise.
    pub(crate) fn for_sizes(n: usize, m: usize) -> Self {
        let fixed = (1..=MAX_STATES).contains(&n) && (1..=MAX_OUTPUTS).contains(&m);
        if fixed { by_n(n, m) } else { Self::general() }
    }

    /// The runtime-size kernels.
    pub(crate) fn general() -> Self {
        Self {
            propagate: propagate_general,
            linear_predict: linear_predict_general,
            gemv_m: dense::gemv,
            update: update_general,
        }
    }

    /// Whether these are the const-generic kernels.
    #[cfg(test)]
    pub(crate) fn is_fixed(&self) -> bool {
        !std::ptr::fn_addr_eq(self.update, update_general as UpdateFn)
    }
}

/// The instance for `N` states and `M` outputs.
fn fixed<const N: usize, const M: usize>() -> StepKernels {
    StepKernels {
        propagate: propagate_fixed::<N>,
        linear_predict: linear_predict_fixed::<N>,
        gemv_m: gemv_fixed::<M>,
        update: update_fixed::<N, M>,
    }
}

/// `match n { N => match m { M => fixed::<N, M>(), … }, … }` over the table's sizes.
macro_rules! dispatch {
    ($n:expr, $m:expr; [$($N:literal)*] $ms:tt) => {
        match $n {
            $($N => dispatch!(@m $N, $m; $ms),)*
            _ => StepKernels::general(),
        }
    };
    (@m $N:literal, $m:expr; [$($M:literal)*]) => {
        match $m {
            $($M => fixed::<$N, $M>(),)*
            _ => StepKernels::general(),
        }
    };
}

fn by_n(n: usize, m: usize) -> StepKernels {
    dispatch!(n, m; [1 2 3 4 5 6 7 8 9 10 11 12 13] [1 2 3 4 5 6 7 8])
}

fn propagate_general(
    a: &DMatrix<f64>,
    p: &DMatrix<f64>,
    q: &DMatrix<f64>,
    ap: &mut DMatrix<f64>,
    out: &mut DMatrix<f64>,
) {
    dense::mul_nn(1.0, a, p, 0.0, ap);
    out.copy_from(q);
    dense::mul_nt(1.0, ap, a, 1.0, out);
    dense::symmetrize(out);
}

fn linear_predict_general(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    x: &DVector<f64>,
    p: &DMatrix<f64>,
    u: &DVector<f64>,
    q: &DMatrix<f64>,
    ap: &mut DMatrix<f64>,
    x_pred: &mut DVector<f64>,
    p_pred: &mut DMatrix<f64>,
) {
    dense::gemv(1.0, a, x, 0.0, x_pred);
    dense::gemv(1.0, b, u, 1.0, x_pred);
    propagate_general(a, p, q, ap, p_pred);
}

fn linear_predict_fixed<const N: usize>(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    x: &DVector<f64>,
    p: &DMatrix<f64>,
    u: &DVector<f64>,
    q: &DMatrix<f64>,
    ap: &mut DMatrix<f64>,
    x_pred: &mut DVector<f64>,
    p_pred: &mut DMatrix<f64>,
) {
    debug_assert!(b.nrows() == N && b.ncols() == u.len());
    let xp = x_pred.as_mut_slice();
    small::gemv::<N>(1.0, a.as_slice(), x.as_slice(), 0.0, xp);
    small::gemv::<N>(1.0, b.as_slice(), u.as_slice(), 1.0, xp);
    propagate_fixed::<N>(a, p, q, ap, p_pred);
}

#[inline(always)]
fn propagate_fixed<const N: usize>(
    a: &DMatrix<f64>,
    p: &DMatrix<f64>,
    q: &DMatrix<f64>,
    ap: &mut DMatrix<f64>,
    out: &mut DMatrix<f64>,
) {
    let (a, ap) = (a.as_slice(), ap.as_mut_slice());
    small::mul_nn::<N, N, N>(1.0, a, p.as_slice(), 0.0, ap);
    let out = out.as_mut_slice();
    out[..N * N].copy_from_slice(&q.as_slice()[..N * N]);
    small::mul_nt::<N, N, N>(1.0, ap, a, 1.0, out);
    small::symmetrize::<N>(out);
}

fn gemv_fixed<const R: usize>(alpha: f64, a: &DMatrix<f64>, x: &DVector<f64>, beta: f64, out: &mut DVector<f64>) {
    debug_assert!(a.nrows() == R && a.ncols() == x.len() && out.len() == R);
    small::gemv::<R>(alpha, a.as_slice(), x.as_slice(), beta, out.as_mut_slice());
}

/// The update's buffers.
#[derive(Debug, Clone)]
pub(crate) struct UpdateBuffers {
    pht: DMatrix<f64>,
    /// `S`, then its factor; also `m × m` scratch for the noise setters.
    pub(crate) s: DMatrix<f64>,
    k: DMatrix<f64>,
    ikh: DMatrix<f64>,
    /// `n × n` scratch, also for the noise setters.
    pub(crate) tmp: DMatrix<f64>,
    kr: DMatrix<f64>,
    x_new: DVector<f64>,
    p_new: DMatrix<f64>,
    /// `G⁻¹ ν` for the normalised innovation squared.
    z: DVector<f64>,
}

fn update_general(
    b: &mut UpdateBuffers,
    x_pred: &DVector<f64>,
    p_pred: &DMatrix<f64>,
    h: &DMatrix<f64>,
    r: &DMatrix<f64>,
    innov: &DVector<f64>,
    want_nis: bool,
) -> Result<f64, PivotFailure> {
    dense::mul_nt(1.0, p_pred, h, 0.0, &mut b.pht);
    b.s.copy_from(r);
    dense::mul_nn(1.0, h, &b.pht, 1.0, &mut b.s);
    dense::cholesky_in_place(&mut b.s)?;
    let nis = if want_nis { nis(&b.s, innov, &mut b.z) } else { f64::NAN };
    b.k.copy_from(&b.pht);
    dense::solve_right_lower_t(&mut b.k, &b.s);
    dense::solve_right_lower(&mut b.k, &b.s);
    b.x_new.copy_from(x_pred);
    dense::gemv(1.0, &b.k, innov, 1.0, &mut b.x_new);
    dense::i_minus_lc(&b.k, h, &mut b.ikh);
    dense::mul_nn(1.0, &b.ikh, p_pred, 0.0, &mut b.tmp);
    dense::mul_nt(1.0, &b.tmp, &b.ikh, 0.0, &mut b.p_new);
    dense::mul_nn(1.0, &b.k, r, 0.0, &mut b.kr);
    dense::mul_nt(1.0, &b.kr, &b.k, 1.0, &mut b.p_new);
    dense::symmetrize(&mut b.p_new);
    Ok(nis)
}

/// [`update_general`] with `N` states and `M` outputs fixed.
fn update_fixed<const N: usize, const M: usize>(
    b: &mut UpdateBuffers,
    x_pred: &DVector<f64>,
    p_pred: &DMatrix<f64>,
    h: &DMatrix<f64>,
    r: &DMatrix<f64>,
    innov: &DVector<f64>,
    want_nis: bool,
) -> Result<f64, PivotFailure> {
    let (p_pred, h, r, innov) = (p_pred.as_slice(), h.as_slice(), r.as_slice(), innov.as_slice());
    let (pht, s, k) = (b.pht.as_mut_slice(), b.s.as_mut_slice(), b.k.as_mut_slice());
    small::mul_nt::<N, N, M>(1.0, p_pred, h, 0.0, pht);
    s[..M * M].copy_from_slice(&r[..M * M]);
    small::mul_nn::<M, N, M>(1.0, h, pht, 1.0, s);
    small::cholesky::<M>(s)?;
    let nis = if want_nis {
        let z = b.z.as_mut_slice();
        z[..M].copy_from_slice(&innov[..M]);
        small::solve_lower::<M>(s, z);
        z.iter().map(|v| v * v).sum()
    } else {
        f64::NAN
    };
    k[..N * M].copy_from_slice(&pht[..N * M]);
    small::solve_right_lower_t::<N, M>(k, s);
    small::solve_right_lower::<N, M>(k, s);
    let x_new = b.x_new.as_mut_slice();
    x_new[..N].copy_from_slice(&x_pred.as_slice()[..N]);
    small::gemv::<N>(1.0, k, innov, 1.0, x_new);
    let (ikh, tmp, kr, p_new) =
        (b.ikh.as_mut_slice(), b.tmp.as_mut_slice(), b.kr.as_mut_slice(), b.p_new.as_mut_slice());
    small::i_minus_lc::<N, M>(k, h, ikh);
    small::mul_nn::<N, N, N>(1.0, ikh, p_pred, 0.0, tmp);
    small::mul_nt::<N, N, N>(1.0, tmp, ikh, 0.0, p_new);
    small::mul_nn::<N, M, M>(1.0, k, r, 0.0, kr);
    small::mul_nt::<N, M, N>(1.0, kr, k, 1.0, p_new);
    small::symmetrize::<N>(p_new);
    Ok(nis)
}

/// The failure of a step whose normalised innovation squared `νᵀ S⁻¹ ν` overflows.
pub(crate) const INNOVATION_OVERFLOW: &str =
    "the measurement's normalised innovation overflows (a value beyond floating point's reach of its prediction)";

/// The measurement update shared by the Kalman and the extended Kalman filter, with its buffers:
///
/// ```text
/// S = H P⁻ Hᵀ + R = G Gᵀ,   K = P⁻ Hᵀ S⁻¹  (two triangular solves with G)
/// x⁺ = x⁻ + K ν,            P⁺ = (I − K H) P⁻ (I − K H)ᵀ + K R Kᵀ   (Joseph form)
/// ```
///
/// for an innovation `ν` computed by the caller (`y − C x⁻` or `y − h(x⁻)`). Allocation-free.
#[derive(Debug, Clone)]
pub(crate) struct GaussianUpdate {
    /// The buffers (the noise setters use `s` and `tmp` as scratch).
    pub(crate) buf: UpdateBuffers,
    /// The kernels of the filter's sizes.
    pub(crate) kernels: StepKernels,
}

impl GaussianUpdate {
    /// Buffers and kernels for `n` states and `m` outputs.
    pub(crate) fn new(n: usize, m: usize) -> Self {
        Self::with_kernels(n, m, StepKernels::for_sizes(n, m))
    }

    /// Buffers for `n` states and `m` outputs with the given kernels.
    pub(crate) fn with_kernels(n: usize, m: usize, kernels: StepKernels) -> Self {
        let buf = UpdateBuffers {
            pht: DMatrix::zeros(n, m),
            s: DMatrix::zeros(m, m),
            k: DMatrix::zeros(n, m),
            ikh: DMatrix::zeros(n, n),
            tmp: DMatrix::zeros(n, n),
            kr: DMatrix::zeros(n, m),
            x_new: DVector::zeros(n),
            p_new: DMatrix::zeros(n, n),
            z: DVector::zeros(m),
        };
        Self { buf, kernels }
    }

    /// Computes `x⁺`, `P⁺` from `x⁻`, `P⁻`, `H`, `R` and `ν` into the buffers and returns the
    /// normalised innovation squared `νᵀ S⁻¹ ν` (NaN unless `want_nis`); nothing else changes, so
    /// a failure leaves the filter as it was.
    pub(crate) fn compute(
        &mut self,
        x_pred: &DVector<f64>,
        p_pred: &DMatrix<f64>,
        h: &DMatrix<f64>,
        r: &DMatrix<f64>,
        innov: &DVector<f64>,
        want_nis: bool,
    ) -> Result<f64, EstimatorError> {
        // The normalised innovation is computed whatever the gate: one that overflows is a
        // measurement beyond floating point's reach of its prediction (a corrupt cell), refused at
        // its own step even with the data check off — accepted, it would move the estimate
        // out of range and fail a later step instead.
        let nis = (self.kernels.update)(&mut self.buf, x_pred, p_pred, h, r, innov, true)
            .map_err(|_| EstimatorError::NumericalFailure("innovation covariance is not positive definite"))?;
        if !nis.is_finite() {
            return Err(EstimatorError::NumericalFailure(INNOVATION_OVERFLOW));
        }
        if !all_finite(self.buf.x_new.as_slice()) || !all_finite(self.buf.p_new.as_slice()) {
            return Err(EstimatorError::NumericalFailure("the estimate is not finite"));
        }
        Ok(if want_nis { nis } else { f64::NAN })
    }

    /// Publishes the computed `x⁺`, `P⁺` into `est` (swaps buffers), status converged.
    pub(crate) fn commit(&mut self, est: &mut GaussianEstimate) {
        std::mem::swap(&mut est.center, &mut self.buf.x_new);
        std::mem::swap(&mut est.covariance, &mut self.buf.p_new);
        est.refresh_std_dev();
        est.status = StepStatus::unchecked(SolveOutcome::Converged);
    }

    /// Publishes by the gate's verdict on `nis` at `step`: the computed update, or (the gate drops
    /// the measurement) the prediction `(x⁻, P⁻)` from the buffers; the status says what the gate
    /// found. On error nothing changes.
    pub(crate) fn commit_gated(
        &mut self,
        gate: &InnovationGate,
        (nis, innov): (f64, &DVector<f64>),
        step: u64,
        est: &mut GaussianEstimate,
        x_pred: &mut DVector<f64>,
        p_pred: &mut DMatrix<f64>,
    ) -> Result<(), EstimatorError> {
        let verdict = gate.judge(nis, step).map_err(|e| name_worst_output(e, innov, &self.buf.s))?;
        if verdict == GateVerdict::Drop {
            commit_prediction(est, x_pred, p_pred)?;
        } else {
            self.commit(est);
        }
        est.status.data = data_check(verdict);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use dense_kernels::test_data::centred_matrix as rand;

    fn spd(n: usize, seed: u64) -> DMatrix<f64> {
        dense_kernels::test_data::spd_matrix(n, seed, 0.1)
    }

    /// Every dispatched size gives exactly the general path's numbers: prediction, innovation,
    /// update (with and without the NIS), on random data with a sparse `H` (zero multipliers,
    /// which the general path skips).
    #[test]
    fn every_dispatched_size_matches_the_general_path() {
        for n in 1..=MAX_STATES {
            for m in 1..=MAX_OUTPUTS {
                let seed = (10 * n + m) as u64;
                let fixed = StepKernels::for_sizes(n, m);
                let general = StepKernels::general();
                assert!(fixed.is_fixed() && !general.is_fixed(), "n = {n}, m = {m}");
                let (a, p, q, r) = (rand(n, n, seed), spd(n, seed + 1), spd(n, seed + 2), spd(m, seed + 3));
                let mut h = rand(m, n, seed + 4);
                h[(0, 0)] = 0.0;
                let (b, u, x) =
                    (rand(n, 3, seed + 5), rand(3, 1, seed + 6).column(0).into_owned(), rand(n, 1, seed + 7));
                let x = x.column(0).into_owned();
                let y = rand(m, 1, seed + 8).column(0).into_owned();

                let run = |k: StepKernels, want_nis: bool| {
                    let (mut ap, mut p_pred) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
                    let mut x_pred = DVector::from_element(n, 7.0);
                    (k.linear_predict)(&a, &b, &x, &p, &u, &q, &mut ap, &mut x_pred, &mut p_pred);
                    let (mut ap2, mut p_pred2) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
                    (k.propagate)(&a, &p, &q, &mut ap2, &mut p_pred2);
                    assert_eq!(p_pred, p_pred2);
                    let mut innov = y.clone();
                    (k.gemv_m)(-1.0, &h, &x_pred, 1.0, &mut innov);
                    let mut upd = GaussianUpdate::with_kernels(n, m, k);
                    let nis = upd.compute(&x_pred, &p_pred, &h, &r, &innov, want_nis).unwrap();
                    (x_pred, p_pred, innov, nis, upd.buf.x_new, upd.buf.p_new)
                };
                for want_nis in [false, true] {
                    let (f, g) = (run(fixed, want_nis), run(general, want_nis));
                    assert_eq!((&f.0, &f.1, &f.2), (&g.0, &g.1, &g.2), "prediction, n = {n}, m = {m}");
                    assert_eq!(f.3.to_bits(), g.3.to_bits(), "NIS, n = {n}, m = {m}");
                    assert_eq!((&f.4, &f.5), (&g.4, &g.5), "update, n = {n}, m = {m}");
                    assert!(f.5.iter().all(|v| v.is_finite()));
                }
            }
        }
        // Beyond the table: the general kernels.
        for (n, m) in [(0, 1), (1, 0), (14, 3), (3, 9), (13, 9)] {
            assert!(!StepKernels::for_sizes(n, m).is_fixed());
        }
    }

    /// An innovation covariance that is not positive definite fails on both paths alike.
    #[test]
    fn an_indefinite_innovation_covariance_fails_on_both_paths() {
        let (n, m) = (3, 2);
        let (x, p) = (DVector::zeros(n), DMatrix::identity(n, n));
        let h = rand(m, n, 5);
        let r = -DMatrix::identity(m, m) * 10.0;
        for k in [StepKernels::for_sizes(n, m), StepKernels::general()] {
            let mut upd = GaussianUpdate::with_kernels(n, m, k);
            assert!(matches!(
                upd.compute(&x, &p, &h, &r, &DVector::zeros(m), true),
                Err(EstimatorError::NumericalFailure(_))
            ));
        }
    }
}
