//! The fallback of a step whose solver failed: clamping `τ` onto the simplex, the previous or
//! central `τ` with its closed-form gain, or pure prediction (module documentation of
//! [`crate::smf`], "Fallback").

use nalgebra::DMatrix;

use super::gain::GainWork;
use super::two_multiplier::TAU_FLOOR;
use super::update::UpdateStatus;

/// Why a step did not use the solver's `(L, τ)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum FallbackReason {
    /// The solver ended with this status.
    Status(UpdateStatus),
    /// The solver returned an error.
    SolverError,
    /// `(L, τ)` was not usable: not finite, `τ` outside the simplex by more than `10⁻⁶`, a
    /// non-zero closed-form `L` with `τ₃ = 0`, no closed-form gain for `τ`, or a certified set
    /// that is not finite (see the module documentation).
    InvalidSolution,
    /// The per-step time budget was exceeded.
    TimeBudget,
}

/// The closed-form gain (G1) with its buffers and the data it needs, loaded on first use.
pub(crate) struct GainCtx<'a> {
    pub(crate) work: &'a mut GainWork,
    pub(crate) loaded: bool,
    pub(crate) x1: &'a DMatrix<f64>,
    pub(crate) q: &'a DMatrix<f64>,
    pub(crate) c: &'a DMatrix<f64>,
    pub(crate) r: &'a DMatrix<f64>,
}

impl GainCtx<'_> {
    /// Writes the closed-form gain for `tau` into `l`; `false` (and `l` untouched) if it fails.
    pub(crate) fn closed_form(&mut self, tau: [f64; 3], l: &mut DMatrix<f64>) -> bool {
        if !self.loaded {
            self.work.load(self.x1, self.q, self.c);
            self.loaded = true;
        }
        if self.work.gain(tau, self.c, self.r) && self.work.l.iter().all(|v| v.is_finite()) {
            l.copy_from(&self.work.l);
            true
        } else {
            false
        }
    }

    /// The fallback: the previous `τ` (or `(⅓, ⅓, ⅓)` if it is not usable) with its closed-form
    /// gain, or pure prediction `τ = (½, ½, 0)`, `L = 0` if that gain fails. Writes `L` into
    /// `l` and returns `τ` (clamped).
    pub(crate) fn fallback(&mut self, warm: [f64; 3], l: &mut DMatrix<f64>) -> [f64; 3] {
        let centre = clamp_tau([1.0; 3]).unwrap_or([0.25; 3]);
        let tau = clamp_tau(warm).filter(|t| t[2] > 0.0).unwrap_or(centre);
        if self.closed_form(tau, l) {
            tau
        } else {
            l.fill(0.0);
            clamp_tau([1.0, 1.0, 0.0]).unwrap_or([0.25, 0.25, 0.0])
        }
    }
}

/// How far outside the simplex a solver's `τ` may be (rounding, interior-point feasibility
/// tolerances) before it is treated as invalid rather than clamped.
const SIMPLEX_TOLERANCE: f64 = 1e-6;

/// `τ₃` below this is treated as 0: it is below the rounding unit `ε·TAU_FLOOR` of the smallest
/// allowed `τ₁`, `τ₂`, so it does not register in `Στ`, and `1/τ₃` would risk overflow.
pub(crate) const TAU3_ZERO: f64 = f64::EPSILON * TAU_FLOOR;

/// Whether a solver's `τ` is on the simplex up to [`SIMPLEX_TOLERANCE`]: no entry below
/// `−10⁻⁶`, `Στ ≤ 1 + 10⁻⁶` (false for non-finite entries or an overflowing sum).
pub(crate) fn near_simplex(tau: [f64; 3]) -> bool {
    tau.iter().all(|v| *v >= -SIMPLEX_TOLERANCE) && tau[0] + tau[1] + tau[2] <= 1.0 + SIMPLEX_TOLERANCE
}

/// Clamps `τ` onto the feasible simplex (see the module documentation): negatives to 0,
/// rescaled to `Στ = 1` (largest entry first, so nothing overflows), `τ₃ <` [`TAU3_ZERO`] to 0,
/// then `τ₁, τ₂ ≥` [`TAU_FLOOR`] with the excess taken off the largest entry. Guarantees
/// `τ₁, τ₂ ≥ TAU_FLOOR`, `τ₃ = 0` or `τ₃ ≥ TAU3_ZERO`, and `fl(fl(τ₁ + τ₂) + τ₃) ≤ 1 − 2ε`, which
/// puts the exact sum of the three stored numbers below 1 (its rounding error is at most
/// `γ₂ ≈ 2.2·10⁻¹⁶`). `None` if an entry is not finite or none is positive.
pub(crate) fn clamp_tau(tau: [f64; 3]) -> Option<[f64; 3]> {
    const LIMIT: f64 = 1.0 - 2.0 * f64::EPSILON;
    if tau.iter().any(|v| !v.is_finite()) {
        return None;
    }
    let mut t = tau.map(|v| v.max(0.0));
    let top = t[0].max(t[1]).max(t[2]);
    if top <= 0.0 {
        return None;
    }
    // Renormalise: divide by the largest entry (now all in [0, 1], the largest exactly 1), then
    // by the sum (in [1, 3]).
    t = t.map(|v| v / top);
    let sum = t[0] + t[1] + t[2];
    t = t.map(|v| v / sum);
    if t[2] < TAU3_ZERO {
        t[2] = 0.0;
    }
    t[0] = t[0].max(TAU_FLOOR);
    t[1] = t[1].max(TAU_FLOOR);
    // The largest entry is at least ⅓ − 2·TAU_FLOOR: taking the excess (at most 2·TAU_FLOOR plus
    // rounding) off it keeps it far above every floor.
    let big = if t[0] >= t[1] && t[0] >= t[2] {
        0
    } else if t[1] >= t[2] {
        1
    } else {
        2
    };
    for _ in 0..8 {
        let s = t[0] + t[1] + t[2];
        if s <= LIMIT {
            return Some(t);
        }
        t[big] -= (s - LIMIT).max(t[big] * f64::EPSILON);
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clamp_tau_lands_on_the_simplex_with_the_floors() {
        let f = TAU_FLOOR;
        let sub = 1e-320;
        let inputs = [
            [1e308, 1e308, 1e308],
            [0.5, 0.5, sub],
            [0.0, 0.0, 1e300],
            [1.0 / 3.0; 3],
            [0.5, 0.5, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [f, f, 1.0 - 2.0 * f],
            [1e-13, 1e-13, 1.0],
            [-1.0, 0.3, 0.7],
            [0.2, 0.3, 0.5],
            [2e-7, 3e-7, 5e-7],
            [sub, sub, sub],
            [sub, 0.0, 0.0],
            [0.6, 0.6, 1e-29],
            [0.6, 0.6, 1e-27],
            [f64::MAX, f64::MAX, 0.0],
            [0.999_999_999_999, 1e-15, 1e-15],
        ];
        for tau in inputs {
            let t = clamp_tau(tau).unwrap_or_else(|| panic!("{tau:?}"));
            assert!(t[0] >= f && t[1] >= f, "{tau:?} → {t:?}");
            assert!(t[2] == 0.0 || t[2] >= TAU3_ZERO, "{tau:?} → {t:?}");
            // fl sum ≤ 1 − 2ε: the exact sum is below 1 (its rounding error is ≤ γ₂).
            assert!(t[0] + t[1] + t[2] <= 1.0 - 2.0 * f64::EPSILON, "{tau:?} → {t:?}");
            // The renormalised point, up to the floors.
            assert!(t[0] + t[1] + t[2] >= 1.0 - 4.0 * f, "{tau:?} → {t:?}");
        }
        // Proportions are kept when no floor binds.
        let t = clamp_tau([2e-7, 3e-7, 5e-7]).unwrap();
        for (got, want) in t.iter().zip([0.2, 0.3, 0.5]) {
            assert!((got - want).abs() < 1e-15, "{t:?}");
        }
        // τ₃ below ε·TAU_FLOOR is zero; just above it is kept.
        assert_eq!(clamp_tau([0.5, 0.5, sub]).unwrap()[2], 0.0);
        assert_eq!(clamp_tau([0.6, 0.6, 1e-29]).unwrap()[2], 0.0);
        assert!(clamp_tau([0.6, 0.6, 1e-27]).unwrap()[2] > 0.0);
        // Nothing usable.
        for tau in [[0.0; 3], [-1.0, -2.0, 0.0], [f64::NAN, 0.5, 0.5], [f64::INFINITY, 0.0, 0.0]] {
            assert_eq!(clamp_tau(tau), None, "{tau:?}");
        }
    }

    #[test]
    fn near_simplex_flags_results_far_outside() {
        assert!(near_simplex([0.3, 0.3, 0.4]));
        assert!(near_simplex([0.3, 0.3, 0.4 + 1e-7]));
        assert!(near_simplex([1e-5; 3]));
        assert!(!near_simplex([1e308; 3]));
        assert!(!near_simplex([0.0, 0.0, 1e300]));
        assert!(!near_simplex([0.5, 0.6, 0.0]));
        assert!(!near_simplex([-1e-3, 0.5, 0.5]));
        assert!(!near_simplex([f64::NAN, 0.5, 0.5]));
    }
}
