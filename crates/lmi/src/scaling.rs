//! Scaling of a problem before a backend solves it (the method is described under
//! "Equilibration" in [`SolverSettings`](crate::SolverSettings)).
//!
//! Three factors, each a power of two, so that scaling the data and mapping the answer back are
//! exact: `d` for every `Fᵢ` (`i ≥ 1`), `s₀` for `F₀` and `s_c` for the objective (applied to
//! `d cᵢ`). Each brings the geometric mean of the magnitudes of its nonzero data to about 1; a
//! factor within [`DEAD_ZONE`] binary orders of 1 is left at 1, so that moderately scaled
//! problems are solved exactly as given. The factors are computed from the values of each solve
//! (a filter's problem changes its numbers at every step), in `O(entries)`, without allocating.
//!
//! The dead zone keeps the answers of moderately scaled problems exactly as they were (all of
//! SDPLIB's subset and the filter's LMIs are inside it); its price is that inside it the
//! backends' absolute floors (`max(1, ·)` in the relative residuals, `tol_gap_abs`) still act, so
//! data of typical magnitude `2^-8` can lose up to that factor of relative accuracy; beyond it
//! every problem is brought to magnitude 1.
//!
//! Why three global factors and not one per variable or per block (Ruiz): the backends' relative
//! residuals are normalised by `‖x‖` and `‖Y‖`, and per-variable factors change the relative
//! weight of the components of `x` and `Y`, which loosens the accuracy of well-scaled problems in
//! their own units. Three global factors are exactly what a uniform rescaling of `c`, of the
//! `Fᵢ` or of all data changes, and a problem and such a rescaling of it get the same answer.

use crate::problem::{Entry, SdpProblem};
use crate::solver::{SdpSolution, SolveStatus};

/// Factors `2^k` with `|k|` up to this are not applied (the problem is moderately scaled).
const DEAD_ZONE: i32 = 8;

/// Factors stay within `2^±MAX_EXP`, so that products of two of them stay normal numbers.
const MAX_EXP: i32 = 500;

/// The power of two `2^e` (exact; `|e| ≤ 1022`).
fn pow2(e: i32) -> f64 {
    f64::from_bits(((e + 1023) as u64) << 52)
}

/// `log₂|v|` to within 0.09 for finite nonzero `v`: the binary exponent plus the mantissa's
/// linear interpolation (no transcendental function on the common path).
fn approx_log2(v: f64) -> f64 {
    let bits = v.abs().to_bits();
    let exp = ((bits >> 52) & 0x7ff) as i32;
    if exp == 0 {
        // Subnormal: rare, take the slow path.
        return v.abs().log2();
    }
    let mantissa = f64::from_bits((bits & ((1u64 << 52) - 1)) | (1023u64 << 52));
    f64::from(exp - 1023) + (mantissa - 1.0)
}

/// Accumulates `log₂` magnitudes of nonzero finite values; [`LogMean::exponent`] is the
/// exponent `k` such that `2^k` brings their geometric mean to about 1.
#[derive(Default)]
struct LogMean {
    sum: f64,
    count: f64,
}

impl LogMean {
    fn add(&mut self, v: f64) {
        if v != 0.0 && v.is_finite() {
            self.sum += approx_log2(v);
            self.count += 1.0;
        }
    }

    /// `-round(mean log₂|v|) + shift`, `0` within the dead zone or without data, clamped.
    fn exponent(&self, shift: f64) -> i32 {
        if self.count == 0.0 {
            return 0;
        }
        let k = (-(self.sum / self.count + shift)).round().clamp(-f64::from(MAX_EXP), f64::from(MAX_EXP)) as i32;
        if k.abs() <= DEAD_ZONE { 0 } else { k }
    }
}

/// The scaling factors of one problem (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Equilibration {
    /// `d`, the factor of every `Fᵢ`, `i ≥ 1` (and of `c`).
    f: f64,
    /// `s₀`, the factor of `F₀`.
    f0: f64,
    /// `s_c`, the factor of the objective.
    obj: f64,
}

impl Default for Equilibration {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Equilibration {
    /// No scaling.
    pub(crate) const IDENTITY: Self = Self { f: 1.0, f0: 1.0, obj: 1.0 };

    /// The factors for `problem`'s values ([`Equilibration::IDENTITY`] unless `enabled`). Reads
    /// every entry once; does not allocate.
    pub(crate) fn compute(problem: &SdpProblem, enabled: bool) -> Self {
        if !enabled {
            return Self::IDENTITY;
        }
        let (mut fi, mut f0, mut c) = (LogMean::default(), LogMean::default(), LogMean::default());
        for e in problem.entries() {
            if e.mat == 0 { f0.add(e.value) } else { fi.add(e.value) }
        }
        for &v in problem.c() {
            c.add(v);
        }
        let kf = fi.exponent(0.0);
        let k0 = f0.exponent(0.0);
        // c is scaled by d first: the mean of log₂|d cᵢ| is the mean of log₂|cᵢ| plus kf.
        let kc = c.exponent(f64::from(kf));
        Self { f: pow2(kf), f0: pow2(k0), obj: pow2(kc) }
    }

    /// The value of `e` in the scaled problem.
    #[inline]
    pub(crate) fn entry(&self, e: &Entry) -> f64 {
        e.value * if e.mat == 0 { self.f0 } else { self.f }
    }

    /// An objective coefficient in the scaled problem. The product of two factors is a normal
    /// number; a scaled value overflows only if the data are within `2^500` of `f64::MAX`.
    #[inline]
    pub(crate) fn cost(&self, c: f64) -> f64 {
        c * (self.f * self.obj)
    }

    /// The factor from an objective of the scaled problem to the original's: `1/(s₀ s_c)`.
    pub(crate) fn objective_factor(&self) -> f64 {
        1.0 / (self.f0 * self.obj)
    }

    /// Whether every factor is 1.
    pub(crate) fn is_identity(&self) -> bool {
        *self == Self::IDENTITY
    }

    /// Maps `x` and `Y` of the scaled problem, in `sol`, back to the original problem:
    /// `x = d x' / s₀` and `Y = Y' / s_c` for an (approximate) optimum. An infeasibility
    /// certificate keeps its normalisation: `Y = s₀ Y'` (so `tr(F₀Y) = tr(F₀'Y')`),
    /// `x = s_c d x'` (so `cᵀx = c'ᵀx'`). Objectives are left to the caller.
    pub(crate) fn unscale(&self, sol: &mut SdpSolution) {
        if self.is_identity() {
            return;
        }
        let (x_factor, y_factor) = match sol.status {
            SolveStatus::PrimalInfeasible | SolveStatus::AlmostPrimalInfeasible => (self.f / self.f0, self.f0),
            SolveStatus::DualInfeasible | SolveStatus::AlmostDualInfeasible => (self.f * self.obj, 1.0 / self.obj),
            _ => (self.f / self.f0, 1.0 / self.obj),
        };
        sol.x.iter_mut().for_each(|x| *x *= x_factor);
        for y in &mut sol.dual {
            y.iter_mut().for_each(|v| *v *= y_factor);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::problem::Block;

    fn e(mat: usize, row: usize, value: f64) -> Entry {
        Entry { mat, block: 0, row, col: row, value }
    }

    fn problem(c: Vec<f64>, entries: Vec<Entry>) -> SdpProblem {
        SdpProblem::new(vec![Block::Nonneg(4)], c, entries).unwrap()
    }

    #[test]
    fn factors_are_powers_of_two_from_geometric_means() {
        // Fᵢ magnitudes 1e-12 and 4e-12 (mean ≈ 2e-12 ≈ 2^-38.9), F₀ 1e30, c 3e-9 · d.
        let p = problem(vec![3e-9, 0.0], vec![e(0, 0, 1e30), e(1, 0, 1e-12), e(2, 1, -4e-12)]);
        let q = Equilibration::compute(&p, true);
        for f in [q.f, q.f0, q.obj] {
            assert!(f > 0.0 && f.log2().fract() == 0.0, "{f} is not a power of two");
        }
        assert_eq!(q.f, pow2(39));
        let scaled: Vec<f64> = p.entries().iter().map(|ent| q.entry(ent).abs()).collect();
        assert!(scaled.iter().all(|v| (0.25..=4.0).contains(v)), "{scaled:?}");
        assert!((0.5..=2.0).contains(&q.cost(3e-9).abs()), "{}", q.cost(3e-9));
        assert_eq!(q.objective_factor(), 1.0 / (q.f0 * q.obj));
        // Moderately scaled data (factors within the dead zone) and disabled scaling: identity.
        let p = problem(vec![5.0, 0.1], vec![e(0, 0, 12.0), e(1, 0, 0.07), e(2, 1, 3.0)]);
        assert!(Equilibration::compute(&p, true).is_identity());
        let p = problem(vec![1e9], vec![e(1, 0, 1e-9)]);
        assert!(!Equilibration::compute(&p, true).is_identity());
        assert!(Equilibration::compute(&p, false).is_identity());
    }

    #[test]
    fn extreme_values_are_clamped_not_overflowed() {
        let p = problem(vec![1e300, 1.0], vec![e(1, 0, 1e-300), e(2, 1, 5e-324), e(0, 2, f64::MAX)]);
        let q = Equilibration::compute(&p, true);
        for f in [q.f, q.f0, q.obj] {
            assert!(f.is_finite() && f >= pow2(-MAX_EXP) && f <= pow2(MAX_EXP), "{f}");
        }
        assert!(p.entries().iter().all(|ent| q.entry(ent).is_finite() && q.entry(ent) != 0.0), "{q:?}");
        assert!(q.cost(1e300).is_finite() && q.cost(1.0) != 0.0 && q.objective_factor().is_finite());
    }

    #[test]
    fn log2_approximation() {
        for v in [1.0, 0.9, -3.5, 1e-300, 5e-324, 1e300, f64::MAX] {
            assert!((approx_log2(v) - v.abs().log2()).abs() < 0.09, "{v}");
        }
        assert_eq!(approx_log2(8.0), 3.0);
        assert_eq!(pow2(-3), 0.125);
        assert_eq!(pow2(10), 1024.0);
    }
}
