//! First-order forward-mode automatic differentiation in interval arithmetic: [`Dual`] carries
//! an enclosure of a function's value and of its gradient with respect to `N` variables over a
//! box of those variables.
//!
//! Evaluating an expression on [`Dual::variable`]s that enclose a box gives, for every point `x`
//! of the box, `f(x) ∈ value` and `∇f(x) ∈ grad` (componentwise): each rule below is the chain
//! rule with every factor replaced by its enclosure over the box, e.g.
//!
//! ```text
//! (a·b)' = a'·[b] + b'·[a]        (a/b)' = (a' − [a/b]·b')/[b]        (D1)
//! g(a)'  = [g'([a])]·a'           for g = sin, cos, atan, exp, sqrt, sqr   (D2)
//! ```
//!
//! Where a function has a kink (`abs` at 0, `max`/`min` where the branches cross) and the kink
//! can lie in the box, the gradient enclosure is the componentwise hull of the branches'
//! gradients (D3), which holds Clarke's generalised gradient: the mean-value inclusion
//! `f(x) − f(y) ∈ [∇f](B)·(x − y)` then holds for every Lipschitz `f` on the box (Lebourg).
//! An undefined operation on the box (division by an interval holding 0, `sqrt` of negative
//! numbers) gives unbounded enclosures ([`Dual::is_bounded`]).

use std::ops::{Add, Div, Mul, Neg, Sub};

use crate::Interval;

/// An enclosure of a function's value and of its gradient with respect to `N` variables.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dual<const N: usize> {
    /// The value's enclosure.
    pub value: Interval,
    /// The enclosures of `∂/∂x_j`, `j < N`.
    pub grad: [Interval; N],
}

impl<const N: usize> Dual<N> {
    /// A constant (zero gradient).
    #[must_use]
    pub fn constant(value: Interval) -> Self {
        Self { value, grad: [Interval::ZERO; N] }
    }

    /// Variable `j` ranging over `value` (gradient `e_j`; `j ≥ N` gives a constant).
    #[must_use]
    pub fn variable(value: Interval, j: usize) -> Self {
        let mut d = Self::constant(value);
        if let Some(g) = d.grad.get_mut(j) {
            *g = Interval::point(1.0);
        }
        d
    }

    /// `g(self)` for a scalar function `g` written on [`Dual`]`<1>`: `g` is evaluated once on
    /// the variable `self.value` (its derivative enclosed over the value), then the chain rule
    /// `∇(g∘a) = [g']·∇a` (D2) is applied once — an enclosure as tight as carrying the `N`
    /// gradient entries through each of `g`'s operations or tighter (interval arithmetic is
    /// subdistributive; equal up to rounding where nothing is shared), for about `1/N` of the
    /// work.
    #[must_use]
    #[inline]
    pub fn map_scalar(self, g: impl FnOnce(Dual<1>) -> Dual<1>) -> Self {
        let outer = g(Dual::variable(self.value, 0));
        let slope = outer.grad[0];
        Self { value: outer.value, grad: self.grad.map(|d| scale(d, slope)) }
    }

    /// Whether the value and every gradient entry are bounded.
    #[must_use]
    pub fn is_bounded(&self) -> bool {
        self.value.is_bounded() && self.grad.iter().all(|g| g.is_bounded())
    }

    /// `g(self)` with `g'` enclosed by `slope()` over the value (D2); `slope` is not evaluated
    /// for `N = 0` (a value-only enclosure).
    #[inline]
    fn chain(self, value: Interval, slope: impl FnOnce() -> Interval) -> Self {
        if N == 0 {
            return Self::constant(value);
        }
        let slope = slope();
        Self { value, grad: self.grad.map(|g| scale(g, slope)) }
    }

    /// `x²`.
    #[must_use]
    pub fn sqr(self) -> Self {
        self.chain(self.value.sqr(), || self.value * 2.0)
    }

    /// `√x` (unbounded if the value can be ≤ 0, where the derivative is).
    #[must_use]
    pub fn sqrt(self) -> Self {
        let s = self.value.sqrt();
        self.chain(s, || Interval::point(0.5) / s)
    }

    /// `sin x`.
    #[must_use]
    pub fn sin(self) -> Self {
        self.chain(self.value.sin(), || self.value.cos())
    }

    /// `cos x`.
    #[must_use]
    pub fn cos(self) -> Self {
        self.chain(self.value.cos(), || -self.value.sin())
    }

    /// `atan x`, `atan' = 1/(1 + x²)`.
    #[must_use]
    pub fn atan(self) -> Self {
        self.chain(self.value.atan(), || {
            let slope = Interval::point(1.0) / (Interval::point(1.0) + self.value.sqr());
            // 1/(1 + x²) ∈ (0, 1]: clamp what the rounding may have added.
            Interval::new(slope.lo().max(0.0), slope.hi().min(1.0))
        })
    }

    /// `e^x`.
    #[must_use]
    pub fn exp(self) -> Self {
        let e = self.value.exp();
        self.chain(e, || e)
    }

    /// `|x|`: the sign's enclosure times the gradient, `[−1, 1]·x'` where 0 can be inside (D3).
    #[must_use]
    pub fn abs(self) -> Self {
        let sign = if self.value.lo() >= 0.0 {
            Interval::point(1.0)
        } else if self.value.hi() <= 0.0 {
            Interval::point(-1.0)
        } else {
            Interval::new(-1.0, 1.0)
        };
        self.chain(self.value.abs(), || sign)
    }

    /// `max(a, b)`: the branch that is certainly larger, else the hull of both gradients (D3).
    #[must_use]
    pub fn max(self, other: Self) -> Self {
        if self.value.certainly_ge(other.value) {
            self
        } else if other.value.certainly_ge(self.value) {
            other
        } else {
            Self { value: self.value.max(other.value), grad: hull(&self.grad, &other.grad) }
        }
    }

    /// `min(a, b)`: as [`Dual::max`].
    #[must_use]
    pub fn min(self, other: Self) -> Self {
        if self.value.certainly_ge(other.value) {
            other
        } else if other.value.certainly_ge(self.value) {
            self
        } else {
            Self { value: self.value.min(other.value), grad: hull(&self.grad, &other.grad) }
        }
    }
}

/// `g·c`, keeping an exact zero gradient entry exact (no outward rounding of `0·c`).
#[inline]
fn scale(g: Interval, c: Interval) -> Interval {
    if g == Interval::ZERO { g } else { g * c }
}

/// `a + b`, exact when either is an exact zero.
#[inline]
fn sum(a: Interval, b: Interval) -> Interval {
    if a == Interval::ZERO {
        b
    } else if b == Interval::ZERO {
        a
    } else {
        a + b
    }
}

fn hull<const N: usize>(a: &[Interval; N], b: &[Interval; N]) -> [Interval; N] {
    std::array::from_fn(|j| a[j].hull(b[j]))
}

impl<const N: usize> From<f64> for Dual<N> {
    fn from(x: f64) -> Self {
        Self::constant(Interval::point(x))
    }
}

impl<const N: usize> Neg for Dual<N> {
    type Output = Self;
    fn neg(self) -> Self {
        Self { value: -self.value, grad: self.grad.map(|g| -g) }
    }
}

impl<const N: usize> Add for Dual<N> {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self { value: self.value + o.value, grad: std::array::from_fn(|j| sum(self.grad[j], o.grad[j])) }
    }
}

impl<const N: usize> Sub for Dual<N> {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Self { value: self.value - o.value, grad: std::array::from_fn(|j| sum(self.grad[j], -o.grad[j])) }
    }
}

impl<const N: usize> Mul for Dual<N> {
    type Output = Self;
    /// (D1): `(a·b)' = a'·[b] + b'·[a]`.
    fn mul(self, o: Self) -> Self {
        Self {
            value: self.value * o.value,
            grad: std::array::from_fn(|j| sum(scale(self.grad[j], o.value), scale(o.grad[j], self.value))),
        }
    }
}

impl<const N: usize> Div for Dual<N> {
    type Output = Self;
    /// (D1): `(a/b)' = (a' − [a/b]·b')/[b]`; unbounded when `[b]` holds 0.
    fn div(self, o: Self) -> Self {
        let q = self.value / o.value;
        let inv = Interval::point(1.0) / o.value;
        Self { value: q, grad: std::array::from_fn(|j| scale(sum(self.grad[j], -scale(o.grad[j], q)), inv)) }
    }
}

/// `Dual ∘ c` and `c ∘ Dual` for a constant `c` (an [`Interval`] or an `f64`): `±` acts on the
/// value only, `×`, `÷` scale the gradient by `[c]`.
macro_rules! with_scalar {
    ($($t:ty => $conv:expr),*) => {$(
        impl<const N: usize> Add<$t> for Dual<N> {
            type Output = Dual<N>;
            fn add(self, o: $t) -> Dual<N> {
                Dual { value: self.value + $conv(o), grad: self.grad }
            }
        }
        impl<const N: usize> Add<Dual<N>> for $t {
            type Output = Dual<N>;
            fn add(self, o: Dual<N>) -> Dual<N> {
                o + self
            }
        }
        impl<const N: usize> Sub<$t> for Dual<N> {
            type Output = Dual<N>;
            fn sub(self, o: $t) -> Dual<N> {
                Dual { value: self.value - $conv(o), grad: self.grad }
            }
        }
        impl<const N: usize> Sub<Dual<N>> for $t {
            type Output = Dual<N>;
            fn sub(self, o: Dual<N>) -> Dual<N> {
                -o + self
            }
        }
        impl<const N: usize> Mul<$t> for Dual<N> {
            type Output = Dual<N>;
            fn mul(self, o: $t) -> Dual<N> {
                Dual { value: self.value * o, grad: self.grad.map(|g| if g == Interval::ZERO { g } else { g * o }) }
            }
        }
        impl<const N: usize> Mul<Dual<N>> for $t {
            type Output = Dual<N>;
            fn mul(self, o: Dual<N>) -> Dual<N> {
                o * self
            }
        }
        impl<const N: usize> Div<$t> for Dual<N> {
            type Output = Dual<N>;
            fn div(self, o: $t) -> Dual<N> {
                let c: Interval = $conv(o);
                let inv = Interval::point(1.0) / c;
                Dual { value: self.value / c, grad: self.grad.map(|g| scale(g, inv)) }
            }
        }
        impl<const N: usize> Div<Dual<N>> for $t {
            type Output = Dual<N>;
            fn div(self, o: Dual<N>) -> Dual<N> {
                Dual::constant($conv(self)) / o
            }
        }
    )*};
}

with_scalar!(Interval => |c: Interval| c, f64 => Interval::point);
