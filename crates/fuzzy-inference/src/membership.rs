//! Triangular and trapezoidal membership functions.

use crate::FuzzyError;

/// A piecewise-linear membership function.
///
/// Both shapes are evaluated as a trapezoid with corners `[a, b, c, d]` (a triangle `(a, b, c)` is
/// `[a, b, b, c]`): 0 outside `[a, d]`, rising linearly on `[a, b]`, 1 on `[b, c]`, falling on
/// `[c, d]`. A vertical edge (`a = b` or `c = d`) belongs to the set (membership 1 at `x = a = b`), as in
/// scikit-fuzzy's `trimf`/`trapmf`. Input sets may have infinite shoulders: `a = b = -inf` (full
/// membership below `c`) or `c = d = +inf` (full membership above `b`).
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum MembershipFunction {
    /// `tri(a, b, c)`: 0 at `a` and `c`, 1 at `b`.
    Triangle {
        /// Left foot.
        a: f64,
        /// Peak.
        b: f64,
        /// Right foot.
        c: f64,
    },
    /// `trap(a, b, c, d)`: 0 at `a` and `d`, 1 on `[b, c]`.
    Trapezoid {
        /// Left foot.
        a: f64,
        /// Left shoulder.
        b: f64,
        /// Right shoulder.
        c: f64,
        /// Right foot.
        d: f64,
    },
}

impl MembershipFunction {
    /// `tri(a, b, c)`.
    pub const fn triangle(a: f64, b: f64, c: f64) -> Self {
        Self::Triangle { a, b, c }
    }

    /// `trap(a, b, c, d)`.
    pub const fn trapezoid(a: f64, b: f64, c: f64, d: f64) -> Self {
        Self::Trapezoid { a, b, c, d }
    }

    /// The corners `[a, b, c, d]` of the equivalent trapezoid.
    pub const fn corners(&self) -> [f64; 4] {
        match *self {
            Self::Triangle { a, b, c } => [a, b, b, c],
            Self::Trapezoid { a, b, c, d } => [a, b, c, d],
        }
    }

    /// The membership degree of `x`, in `[0, 1]` (for a validated function and a non-NaN `x`).
    pub fn degree(&self, x: f64) -> f64 {
        degree(&self.corners(), x)
    }

    /// Checks the corners: no NaN, non-decreasing, and infinite corners only as shoulders
    /// (`a = b = -inf`, `c = d = +inf`). `context` names the set in the error.
    pub fn validate(&self, context: &dyn Fn() -> String) -> Result<(), FuzzyError> {
        let corners = self.corners();
        let [a, b, c, d] = corners;
        if corners.iter().any(|v| v.is_nan()) {
            return Err(FuzzyError::NanCorner { context: context(), corners });
        }
        if !(a <= b && b <= c && c <= d) {
            return Err(FuzzyError::NonMonotoneCorners { context: context(), corners });
        }
        let bad_left = a.is_infinite() && a != b;
        let bad_right = d.is_infinite() && c != d;
        if bad_left || bad_right || b == f64::INFINITY || c == f64::NEG_INFINITY {
            return Err(FuzzyError::InfiniteCorner { context: context(), corners });
        }
        Ok(())
    }
}

/// The trapezoid `[a, b, c, d]` at `x` (see [`MembershipFunction`]).
#[inline]
pub(crate) fn degree(&[a, b, c, d]: &[f64; 4], x: f64) -> f64 {
    if x < a || x > d {
        0.0
    } else if x < b {
        // a <= x < b: a finite and a < b.
        (x - a) / (b - a)
    } else if x <= c {
        1.0
    } else {
        // c < x <= d: c finite and c < d.
        (d - x) / (d - c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shapes_and_edges() {
        let t = MembershipFunction::triangle(2.0, 3.0, 4.0);
        assert_eq!(t.degree(2.0), 0.0);
        assert_eq!(t.degree(2.5), 0.5);
        assert_eq!(t.degree(3.0), 1.0);
        assert_eq!(t.degree(3.75), 0.25);
        assert_eq!(t.degree(4.0), 0.0);
        assert_eq!(t.degree(5.0), 0.0);
        let z = MembershipFunction::trapezoid(0.0, 0.0, 3.0, 5.0);
        assert_eq!(z.degree(0.0), 1.0);
        assert_eq!(z.degree(-0.1), 0.0);
        assert_eq!(z.degree(4.0), 0.5);
        let pb = MembershipFunction::trapezoid(14.0, 18.0, f64::INFINITY, f64::INFINITY);
        assert_eq!(pb.degree(16.0), 0.5);
        assert_eq!(pb.degree(1e300), 1.0);
        assert_eq!(pb.degree(f64::INFINITY), 1.0);
        let all = MembershipFunction::trapezoid(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::INFINITY);
        assert!(all.validate(&String::new).is_ok());
        assert_eq!(all.degree(-1e300), 1.0);
    }

    #[test]
    fn validation_names_the_problem() {
        let ctx = || "set X".to_owned();
        assert!(matches!(
            MembershipFunction::triangle(1.0, 0.0, 2.0).validate(&ctx),
            Err(FuzzyError::NonMonotoneCorners { .. })
        ));
        assert!(matches!(
            MembershipFunction::triangle(f64::NAN, 0.0, 2.0).validate(&ctx),
            Err(FuzzyError::NanCorner { .. })
        ));
        assert!(matches!(
            MembershipFunction::trapezoid(0.0, 1.0, 2.0, f64::INFINITY).validate(&ctx),
            Err(FuzzyError::InfiniteCorner { .. })
        ));
        assert!(matches!(
            MembershipFunction::triangle(f64::NEG_INFINITY, 0.0, 2.0).validate(&ctx),
            Err(FuzzyError::InfiniteCorner { .. })
        ));
        let e = MembershipFunction::trapezoid(0.0, 2.0, 1.0, 3.0).validate(&ctx).unwrap_err();
        assert!(e.to_string().starts_with("set X: corners must be non-decreasing"), "{e}");
    }
}
