//! Outer ellipsoidal bounds of Minkowski sums.
//!
//! For `p > 0`, `𝓔(c₁, P₁) ⊕ 𝓔(c₂, P₂) ⊆ 𝓔(c₁ + c₂, (1 + 1/p) P₁ + (1 + p) P₂)`.
//! Proof: for `x = c₁ + c₂ + e₁ + e₂` and any `d`, `dᵀ(e₁ + e₂) ≤ √(dᵀP₁d) + √(dᵀP₂d)` and
//! `(a + b)² ≤ (1 + 1/p) a² + (1 + p) b²` (from `2ab ≤ a²/p + p b²`), so the support
//! function of the sum is dominated by that of the bound.
//!
//! The trace of the bound is `τ(p) = (1 + 1/p) tr P₁ + (1 + p) tr P₂`, convex in `p > 0`
//! with `τ'(p) = tr P₂ − tr P₁ / p²`; hence the trace-optimal parameter is
//! `p* = √(tr P₁ / tr P₂)` and `τ(p*) = (√tr P₁ + √tr P₂)²`.

use crate::Ellipsoid;
use crate::error::{EllipsoidError, Result};

impl Ellipsoid {
    fn check_same_dim(&self, other: &Self, what: &'static str) -> Result<()> {
        if self.dim() == other.dim() {
            Ok(())
        } else {
            Err(EllipsoidError::DimensionMismatch { what, expected: self.dim(), found: other.dim() })
        }
    }

    /// The outer bound `𝓔(c₁ + c₂, (1 + 1/p) P₁ + (1 + p) P₂)` of `self ⊕ other`
    /// (`self = 𝓔(c₁, P₁)`, `other = 𝓔(c₂, P₂)`), valid for every finite `p > 0`.
    pub fn minkowski_sum_outer(&self, other: &Self, p: f64) -> Result<Self> {
        self.check_same_dim(other, "second Minkowski operand")?;
        if !(p.is_finite() && p > 0.0) {
            return Err(EllipsoidError::InvalidParameter { name: "p", value: p, expected: "a finite positive number" });
        }
        let shape = self.shape() * (1.0 + 1.0 / p) + other.shape() * (1.0 + p);
        Self::from_computed(
            self.center() + other.center(),
            &shape,
            "Minkowski-sum centre c₁ + c₂",
            |pivot, value| EllipsoidError::DegenerateResult { operation: "Minkowski-sum bound", pivot, value },
        )
    }

    /// The trace-minimising parameter `p* = √(tr P₁) / √(tr P₂)` of
    /// [`Ellipsoid::minkowski_sum_outer`] (`P₁` of `self`, `P₂` of `other`).
    pub fn minkowski_min_trace_parameter(&self, other: &Self) -> Result<f64> {
        self.check_same_dim(other, "second Minkowski operand")?;
        let p = self.trace().sqrt() / other.trace().sqrt();
        if p.is_finite() && p > 0.0 {
            Ok(p)
        } else {
            Err(EllipsoidError::InvalidParameter {
                name: "p* = √(tr P₁ / tr P₂)",
                value: p,
                expected: "a finite positive ratio (the traces differ too much in scale)",
            })
        }
    }

    /// The trace-minimal member of the family, with its parameter `p*`; its trace is
    /// `(√tr P₁ + √tr P₂)²`.
    pub fn minkowski_sum_min_trace(&self, other: &Self) -> Result<(Self, f64)> {
        let p = self.minkowski_min_trace_parameter(other)?;
        Ok((self.minkowski_sum_outer(other, p)?, p))
    }
}

/// The trace-optimal weights `(τ₁, τ₂)`, `τ₁ + τ₂ = 1`, of the outer bound `P₁/τ₁ + P₂/τ₂` of
/// `𝓔(0, P₁) ⊕ 𝓔(0, P₂)` from the two traces: `τ₁ = √tr P₁ / (√tr P₁ + √tr P₂)` (the same family
/// as [`Ellipsoid::minkowski_sum_outer`] with `p = τ₁/τ₂`), `(½, ½)` when both traces vanish.
/// Allocation-free: the set-membership filter's prediction uses it on its buffers.
#[must_use]
pub fn min_trace_weights(trace_1: f64, trace_2: f64) -> (f64, f64) {
    let (s1, s2) = (trace_1.max(0.0).sqrt(), trace_2.max(0.0).sqrt());
    let t1 = if s1 + s2 > 0.0 { s1 / (s1 + s2) } else { 0.5 };
    (t1, 1.0 - t1)
}

#[cfg(test)]
mod tests {
    use nalgebra::{DMatrix, DVector};

    use super::*;

    #[test]
    fn weights_are_the_parameter_of_the_min_trace_bound() {
        let a = Ellipsoid::axis_aligned(DVector::zeros(2), &[2.0, 1.0]).unwrap();
        let b = Ellipsoid::axis_aligned(DVector::zeros(2), &[0.5, 0.3]).unwrap();
        let (t1, t2) = min_trace_weights(a.trace(), b.trace());
        let p = a.minkowski_min_trace_parameter(&b).unwrap();
        // P₁/τ₁ + P₂/τ₂ is the bound with parameter p: 1/τ₁ = 1 + 1/p, 1/τ₂ = 1 + p.
        assert!((1.0 / t1 - (1.0 + 1.0 / p)).abs() < 1e-14 && (1.0 / t2 - (1.0 + p)).abs() < 1e-14);
        assert_eq!(t1 + t2, 1.0);
        assert_eq!(min_trace_weights(0.0, 0.0), (0.5, 0.5));
    }

    #[test]
    fn sum_of_balls_is_exact_at_optimum() {
        let a = Ellipsoid::ball(DVector::from_vec(vec![1.0, 0.0, -1.0]), 1.0).expect("valid");
        let b = Ellipsoid::ball(DVector::from_vec(vec![0.0, 2.0, 1.0]), 3.0).expect("valid");
        let (s, p) = a.minkowski_sum_min_trace(&b).expect("ok");
        assert!((p - 1.0 / 3.0).abs() < 1e-15);
        assert_eq!(s.center(), &DVector::from_vec(vec![1.0, 2.0, 0.0]));
        assert!((s.shape() - DMatrix::identity(3, 3) * 16.0).amax() < 1e-13);
        // Non-optimal p is larger: (1 + 1)·1 + (1 + 1)·9 = 20 per axis.
        let s1 = a.minkowski_sum_outer(&b, 1.0).expect("ok");
        assert!((s1.trace() - 60.0).abs() < 1e-12);
    }

    #[test]
    fn axis_aligned_trace_formula() {
        let a = Ellipsoid::axis_aligned(DVector::zeros(2), &[2.0, 1.0]).expect("valid");
        let b = Ellipsoid::axis_aligned(DVector::zeros(2), &[1.0, 1.0]).expect("valid");
        let (s, p) = a.minkowski_sum_min_trace(&b).expect("ok");
        assert!((p - (5f64 / 2.0).sqrt()).abs() < 1e-15);
        let expected = (5f64.sqrt() + 2f64.sqrt()).powi(2);
        assert!((s.trace() - expected).abs() < 1e-12);
    }
}
