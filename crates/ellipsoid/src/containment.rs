//! Exact ellipsoid-in-ellipsoid containment.
//!
//! `𝓔(c₂, P₂) ⊆ 𝓔(c₁, P₁)` iff `max_{x ∈ 𝓔(c₂,P₂)} (x − c₁)ᵀ P₁⁻¹ (x − c₁) ≤ 1`. With
//! `x = c₂ + L₂ u`, `‖u‖ ≤ 1`, the objective is `‖d + M u‖²` with `d = L₁⁻¹ (c₂ − c₁)` and
//! `M = L₁⁻¹ L₂`, i.e. `f(u) = uᵀ A u + 2 bᵀ u + ‖d‖²` with `A = Mᵀ M ⪰ 0`, `b = Mᵀ d`.
//! Maximising this convex function over the unit ball is a trust-region subproblem
//! (minimise `−f`), solved exactly:
//!
//! * Eigendecompose `A = Q diag(λ_i) Qᵀ`, `λ₁ = max λ_i`, `γ_i = λ₁ − λ_i ≥ 0`, `β = Qᵀ b`.
//! * Lagrangian duality (exact for the trust-region subproblem): for every `ν ≥ λ₁`,
//!   `f(u) ≤ f(u) + ν(1 − ‖u‖²) ≤ ν + ‖d‖² + bᵀ(ν I − A)⁻¹ b`, so with `ν = λ₁ + t`,
//!   `max f = min_{t > 0} g(t)`, `g(t) = λ₁ + t + ‖d‖² + Σ β_i² / (t + γ_i)`.
//! * `g` is convex with `g'(t) = 1 − φ(t)`, `φ(t) = Σ β_i² / (t + γ_i)²` decreasing: the
//!   minimiser solves the secular equation `φ(t) = 1` (safeguarded Newton on
//!   `1/√φ − 1`, bracketed in `(0, ‖β‖]`).
//! * Hard case: when `β` has no component on the top eigenspace and `φ(0) ≤ 1`, the
//!   minimum is at `t = 0`; the maximiser is `w_i = β_i/γ_i` off the top eigenspace plus a
//!   top-eigenvector component of length `√(1 − φ(0))`.
//!
//! Every `g(t)` is an upper bound of the maximum and the recovered `u` gives a lower bound
//! (a point of the inner ellipsoid); they agree at the solution up to rounding.

use nalgebra::{DVector, SymmetricEigen};

use crate::error::{EllipsoidError, Result};
use crate::linalg::{forward_sub, forward_sub_mat, symmetrize};
use crate::{CONTAINMENT_TOLERANCE, Ellipsoid};

/// Solution of the trust-region subproblem.
struct Farthest {
    /// The dual value `g(t*)` (an upper bound, equal to the maximum up to rounding).
    upper: f64,
    /// The maximiser on the boundary of the inner ellipsoid.
    point: DVector<f64>,
}

/// `β²/x` with `0/0 = 0` and `β²/0 = ∞` for `β ≠ 0`.
fn ratio(num: f64, den: f64) -> f64 {
    if den > 0.0 {
        num / den
    } else if num == 0.0 {
        0.0
    } else {
        f64::INFINITY
    }
}

impl Ellipsoid {
    fn farthest(&self, other: &Self) -> Result<Farthest> {
        if self.dim() != other.dim() {
            return Err(EllipsoidError::DimensionMismatch {
                what: "inner ellipsoid",
                expected: self.dim(),
                found: other.dim(),
            });
        }
        let n = self.dim();
        let l1 = self.cholesky_factor();
        let l2 = other.cholesky_factor();
        let d = forward_sub(l1, &(other.center() - self.center()));
        let m = forward_sub_mat(l1, l2);
        let a = symmetrize(&(m.transpose() * &m));
        let b = m.transpose() * &d;
        let eig = SymmetricEigen::try_new(a, f64::EPSILON, 1000 * n.max(1))
            .ok_or(EllipsoidError::EigenDecomposition { what: "Mᵀ M (M = L₁⁻¹ L₂)" })?;
        let top = eig.eigenvalues.imax();
        let lam1 = eig.eigenvalues[top].max(0.0);
        let gamma: Vec<f64> = eig.eigenvalues.iter().map(|l| (lam1 - l).max(0.0)).collect();
        let beta = eig.eigenvectors.transpose() * &b;
        let beta2: Vec<f64> = beta.iter().map(|x| x * x).collect();
        let dd = d.norm_squared();

        let phi = |t: f64| -> f64 { beta2.iter().zip(&gamma).map(|(b2, g)| ratio(*b2, (t + g) * (t + g))).sum() };
        let dphi =
            |t: f64| -> f64 { beta2.iter().zip(&gamma).map(|(b2, g)| ratio(*b2, (t + g) * (t + g) * (t + g))).sum() };
        let dual =
            |t: f64| -> f64 { lam1 + t + dd + beta2.iter().zip(&gamma).map(|(b2, g)| ratio(*b2, t + g)).sum::<f64>() };

        let phi0 = phi(0.0);
        let t = if phi0 <= 1.0 {
            0.0
        } else {
            // φ(‖β‖) ≤ Σβ²/‖β‖² = 1, φ(0⁺) > 1: the root is in (0, ‖β‖].
            let (mut lo, mut hi) = (0.0_f64, beta2.iter().sum::<f64>().sqrt());
            let mut t = hi;
            for _ in 0..200 {
                let p = phi(t);
                let psi = 1.0 / p.sqrt() - 1.0;
                if psi < 0.0 {
                    lo = t;
                } else {
                    hi = t;
                }
                if psi.abs() <= 1e-15 || hi - lo <= 1e-16 * hi {
                    break;
                }
                let dpsi = dphi(t) / (p * p.sqrt());
                let next = t - psi / dpsi;
                t = if next.is_finite() && next > lo && next < hi { next } else { 0.5 * (lo + hi) };
            }
            t
        };
        let upper = dual(t);

        // Primal maximiser.
        let mut w = DVector::from_iterator(
            n,
            beta.iter().zip(&gamma).map(|(b, g)| if t + g > 0.0 { b / (t + g) } else { 0.0 }),
        );
        if t == 0.0 {
            let rest = (1.0 - w.norm_squared()).max(0.0);
            w[top] += rest.sqrt();
        }
        let mut u = &eig.eigenvectors * w;
        let norm = u.norm();
        if norm > 0.0 && norm.is_finite() {
            u /= norm;
        } else {
            u = eig.eigenvectors.column(top).into_owned();
        }
        let point = other.center() + l2 * u;
        Ok(Farthest { upper, point })
    }

    /// `max_{x ∈ other} (x − c)ᵀ P⁻¹ (x − c)`: the largest normalised distance (w.r.t.
    /// `self`) of a point of `other`. Exact up to rounding (see the
    /// [module documentation](crate::containment)); `other ⊆ self` iff it is at most 1.
    ///
    /// The value returned is the larger of the dual bound and the distance of the recovered
    /// maximiser, so it is never below the distance of a point actually found in `other`.
    pub fn max_normalized_distance(&self, other: &Self) -> Result<f64> {
        let f = self.farthest(other)?;
        let primal = self.normalized_distance(&f.point)?;
        Ok(f.upper.max(primal))
    }

    /// A point of `other` (on its boundary) maximising the normalised distance w.r.t. `self`,
    /// with that distance — for diagnostics, e.g. the point that violates containment.
    pub fn farthest_point(&self, other: &Self) -> Result<(DVector<f64>, f64)> {
        let f = self.farthest(other)?;
        let primal = self.normalized_distance(&f.point)?;
        Ok((f.point, primal))
    }

    /// Whether `other ⊆ self`, decided as
    /// `max_normalized_distance(other) ≤ 1 + CONTAINMENT_TOLERANCE`: `true` means `other` lies
    /// in the copy of `self` scaled by `√(1 + 1e-9)` about its centre.
    pub fn contains_ellipsoid(&self, other: &Self) -> Result<bool> {
        Ok(self.max_normalized_distance(other)? <= 1.0 + CONTAINMENT_TOLERANCE)
    }
}

#[cfg(test)]
mod tests {
    use crate::test_util::v;
    use nalgebra::DMatrix;

    use super::*;

    #[test]
    fn offset_balls() {
        let outer = Ellipsoid::ball(v(&[0.0, 0.0, 0.0]), 2.0).expect("valid");
        let inner = Ellipsoid::ball(v(&[0.5, 0.0, 0.0]), 1.0).expect("valid");
        let m = outer.max_normalized_distance(&inner).expect("ok");
        assert!((m - 0.5625).abs() < 1e-14, "{m}");
        let (p, dist) = outer.farthest_point(&inner).expect("ok");
        assert!((p - v(&[1.5, 0.0, 0.0])).amax() < 1e-12);
        assert!((dist - 0.5625).abs() < 1e-14);
        assert!(outer.contains_ellipsoid(&inner).expect("ok"));
        assert!(!inner.contains_ellipsoid(&outer).expect("ok"));
    }

    #[test]
    fn concentric_hard_case() {
        // d = 0: β = 0, the maximum is the top eigenvalue of M ᵀM.
        let outer = Ellipsoid::ball(v(&[1.0, 1.0]), 1.0).expect("valid");
        let inner = Ellipsoid::axis_aligned(v(&[1.0, 1.0]), &[1.0, 0.5]).expect("valid");
        let m = outer.max_normalized_distance(&inner).expect("ok");
        assert!((m - 1.0).abs() < 1e-15);
        assert!(outer.contains_ellipsoid(&inner).expect("ok"));
        assert!(outer.contains_ellipsoid(&outer).expect("ok"));
    }

    #[test]
    fn off_centre_hard_case() {
        // Inner (0.5 cos θ, 0.1 + 0.1 sin θ) in the unit disc: with s = sin θ the distance
        // is 0.26 + 0.02 s − 0.24 s², maximal at s = 1/24: 0.26 + 0.0004/0.96.
        let outer = Ellipsoid::ball(v(&[0.0, 0.0]), 1.0).expect("valid");
        let inner = Ellipsoid::axis_aligned(v(&[0.0, 0.1]), &[0.5, 0.1]).expect("valid");
        let m = outer.max_normalized_distance(&inner).expect("ok");
        let expected = 0.26 + 0.0004 / 0.96;
        assert!((m - expected).abs() < 1e-14, "{m} vs {expected}");
        let (p, d) = outer.farthest_point(&inner).expect("ok");
        assert!((d - expected).abs() < 1e-14);
        assert!((p[1] - (0.1 + 0.1 / 24.0)).abs() < 1e-14);
    }

    #[test]
    fn tilted_known_value() {
        // A segment-like thin inner ellipse along (1, 1) reaching the unit circle exactly.
        let r = 1.0 / 2f64.sqrt();
        let p = DMatrix::from_row_slice(2, 2, &[0.5, 0.5 - 1e-6, 0.5 - 1e-6, 0.5]);
        let inner = Ellipsoid::new(v(&[0.0, 0.0]), p).expect("valid");
        let outer = Ellipsoid::ball(v(&[0.0, 0.0]), 1.0).expect("valid");
        let m = outer.max_normalized_distance(&inner).expect("ok");
        assert!((m - (1.0 - 1e-6)).abs() < 1e-12, "{m}");
        let (pt, _) = outer.farthest_point(&inner).expect("ok");
        assert!((pt[0].abs() - r).abs() < 1e-6 && (pt[1].abs() - r).abs() < 1e-6);
    }
}
