//! Forward-mode automatic differentiation in `f64`: a [`Dual`] carries a value and its gradient
//! with respect to `N` variables, so that evaluating an expression on [`Dual::variable`]s gives
//! the expression's value and its exact partial derivatives (up to rounding) at once.
//!
//! Written here rather than taken from the `num-dual` crate (which was evaluated: well kept, the
//! same `nalgebra`, no allocation for a const-generic gradient), because a model's closures
//! mix plain numbers into their expressions on both sides (`1.0 - x[0]`, `0.5 * x[1]`): no crate
//! can implement `f64 * ItsDual` for a dual type defined elsewhere, and `num-dual` does not,
//! so half of such expressions would not compile. Here the elementary functions are inherent
//! methods (no trait to import), and no operation panics. The gradient is an array: no
//! operation allocates.
//!
//! Conventions where a function has no derivative (as the equation models'): `abs` has
//! derivative 0 at 0; `min`/`max` take the first argument's at a tie. A function applied to a
//! value whose gradient is zero keeps a zero gradient even where its derivative is infinite
//! (`sqrt` of a constant 0).
//!
//! ```
//! use models::Dual;
//!
//! // f(a, b) = a·sin(b) + 1 at (2, 0): ∂f/∂a = sin 0 = 0, ∂f/∂b = 2 cos 0 = 2.
//! let (a, b) = (Dual::<2>::variable(2.0, 0), Dual::<2>::variable(0.0, 1));
//! let f = a * b.sin() + 1.0;
//! assert_eq!((f.re, f.eps), (1.0, [0.0, 2.0]));
//! ```

use std::iter::Sum;
use std::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

/// A value `re` and its gradient `eps` (`∂/∂x_j`, `j < N`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dual<const N: usize> {
    /// The value.
    pub re: f64,
    /// The partial derivatives.
    pub eps: [f64; N],
}

impl<const N: usize> Default for Dual<N> {
    fn default() -> Self {
        Self::constant(0.0)
    }
}

impl<const N: usize> From<f64> for Dual<N> {
    fn from(re: f64) -> Self {
        Self::constant(re)
    }
}

impl<const N: usize> Dual<N> {
    /// A constant: zero gradient.
    #[must_use]
    pub const fn constant(re: f64) -> Self {
        Self { re, eps: [0.0; N] }
    }

    /// Variable `j` at `re`: gradient `e_j` (a constant when `j ≥ N`).
    #[must_use]
    pub fn variable(re: f64, j: usize) -> Self {
        let mut d = Self::constant(re);
        if let Some(e) = d.eps.get_mut(j) {
            *e = 1.0;
        }
        d
    }

    /// `g(self)` with value `re` and derivative `slope`: `∇g(a) = g'(a) ∇a`; a zero gradient
    /// entry stays zero whatever the slope.
    #[inline]
    fn chain(self, re: f64, slope: f64) -> Self {
        Self { re, eps: self.eps.map(|e| if e == 0.0 { 0.0 } else { e * slope }) }
    }

    /// `g(self, other)` with value `re` and partial derivatives `da`, `db` (zero gradient entries
    /// contribute nothing whatever their partial).
    #[inline]
    fn chain2(self, other: Self, re: f64, da: f64, db: f64) -> Self {
        let mut eps = [0.0; N];
        for (j, e) in eps.iter_mut().enumerate() {
            let (a, b) = (self.eps[j], other.eps[j]);
            *e = if a == 0.0 { 0.0 } else { a * da } + if b == 0.0 { 0.0 } else { b * db };
        }
        Self { re, eps }
    }

    /// `sin`.
    #[must_use]
    pub fn sin(self) -> Self {
        self.chain(self.re.sin(), self.re.cos())
    }
    /// `cos`.
    #[must_use]
    pub fn cos(self) -> Self {
        self.chain(self.re.cos(), -self.re.sin())
    }
    /// `(sin, cos)`.
    #[must_use]
    pub fn sin_cos(self) -> (Self, Self) {
        let (s, c) = self.re.sin_cos();
        (self.chain(s, c), self.chain(c, -s))
    }
    /// `tan`.
    #[must_use]
    pub fn tan(self) -> Self {
        let v = self.re.tan();
        self.chain(v, 1.0 + v * v)
    }
    /// `asin`.
    #[must_use]
    pub fn asin(self) -> Self {
        self.chain(self.re.asin(), 1.0 / (1.0 - self.re * self.re).sqrt())
    }
    /// `acos`.
    #[must_use]
    pub fn acos(self) -> Self {
        self.chain(self.re.acos(), -1.0 / (1.0 - self.re * self.re).sqrt())
    }
    /// `atan`.
    #[must_use]
    pub fn atan(self) -> Self {
        self.chain(self.re.atan(), 1.0 / (1.0 + self.re * self.re))
    }
    /// `atan2(self, other)`: the angle of the point `(other, self)`.
    #[must_use]
    pub fn atan2(self, other: Self) -> Self {
        let r = self.re * self.re + other.re * other.re;
        self.chain2(other, self.re.atan2(other.re), other.re / r, -self.re / r)
    }
    /// `sinh`.
    #[must_use]
    pub fn sinh(self) -> Self {
        self.chain(self.re.sinh(), self.re.cosh())
    }
    /// `cosh`.
    #[must_use]
    pub fn cosh(self) -> Self {
        self.chain(self.re.cosh(), self.re.sinh())
    }
    /// `tanh`.
    #[must_use]
    pub fn tanh(self) -> Self {
        let v = self.re.tanh();
        self.chain(v, 1.0 - v * v)
    }
    /// `exp`.
    #[must_use]
    pub fn exp(self) -> Self {
        let v = self.re.exp();
        self.chain(v, v)
    }
    /// The natural logarithm.
    #[must_use]
    pub fn ln(self) -> Self {
        self.chain(self.re.ln(), 1.0 / self.re)
    }
    /// `log10`.
    #[must_use]
    pub fn log10(self) -> Self {
        self.chain(self.re.log10(), 1.0 / (self.re * std::f64::consts::LN_10))
    }
    /// `sqrt`.
    #[must_use]
    pub fn sqrt(self) -> Self {
        let v = self.re.sqrt();
        self.chain(v, 0.5 / v)
    }
    /// `cbrt`.
    #[must_use]
    pub fn cbrt(self) -> Self {
        let v = self.re.cbrt();
        self.chain(v, 1.0 / (3.0 * v * v))
    }
    /// `self²`.
    #[must_use]
    pub fn sqr(self) -> Self {
        self * self
    }
    /// `self^n`.
    #[must_use]
    pub fn powi(self, n: i32) -> Self {
        let slope = if n == 0 { 0.0 } else { f64::from(n) * self.re.powi(n - 1) };
        self.chain(self.re.powi(n), slope)
    }
    /// `self^p` for a constant `p`.
    #[must_use]
    pub fn powf(self, p: f64) -> Self {
        let slope = if p == 0.0 { 0.0 } else { p * self.re.powf(p - 1.0) };
        self.chain(self.re.powf(p), slope)
    }
    /// `self^p`, both varying.
    #[must_use]
    pub fn pow(self, p: Self) -> Self {
        let v = self.re.powf(p.re);
        let da = if p.re == 0.0 { 0.0 } else { p.re * self.re.powf(p.re - 1.0) };
        self.chain2(p, v, da, v * self.re.ln())
    }
    /// `sqrt(self² + other²)`.
    #[must_use]
    pub fn hypot(self, other: Self) -> Self {
        let v = self.re.hypot(other.re);
        self.chain2(other, v, self.re / v, other.re / v)
    }
    /// `1 / self`.
    #[must_use]
    pub fn recip(self) -> Self {
        self.chain(1.0 / self.re, -1.0 / (self.re * self.re))
    }
    /// `|self|` (derivative 0 at 0).
    #[must_use]
    pub fn abs(self) -> Self {
        let slope = if self.re > 0.0 {
            1.0
        } else if self.re < 0.0 {
            -1.0
        } else {
            0.0
        };
        self.chain(self.re.abs(), slope)
    }
    /// The smaller of the two (`self` at a tie or when `other` is NaN).
    #[must_use]
    pub fn min(self, other: Self) -> Self {
        if self.re <= other.re || other.re.is_nan() { self } else { other }
    }
    /// The larger of the two (`self` at a tie or when `other` is NaN).
    #[must_use]
    pub fn max(self, other: Self) -> Self {
        if self.re >= other.re || other.re.is_nan() { self } else { other }
    }
}

impl<const N: usize> Neg for Dual<N> {
    type Output = Self;
    fn neg(self) -> Self {
        Self { re: -self.re, eps: self.eps.map(|e| -e) }
    }
}

impl<const N: usize> Add for Dual<N> {
    type Output = Self;
    fn add(mut self, b: Self) -> Self {
        self.re += b.re;
        self.eps.iter_mut().zip(b.eps).for_each(|(e, d)| *e += d);
        self
    }
}

impl<const N: usize> Sub for Dual<N> {
    type Output = Self;
    fn sub(mut self, b: Self) -> Self {
        self.re -= b.re;
        self.eps.iter_mut().zip(b.eps).for_each(|(e, d)| *e -= d);
        self
    }
}

impl<const N: usize> Mul for Dual<N> {
    type Output = Self;
    fn mul(self, b: Self) -> Self {
        self.chain2(b, self.re * b.re, b.re, self.re)
    }
}

impl<const N: usize> Div for Dual<N> {
    type Output = Self;
    fn div(self, b: Self) -> Self {
        let v = self.re / b.re;
        self.chain2(b, v, 1.0 / b.re, -v / b.re)
    }
}

impl<const N: usize> Add<f64> for Dual<N> {
    type Output = Self;
    fn add(mut self, b: f64) -> Self {
        self.re += b;
        self
    }
}

impl<const N: usize> Sub<f64> for Dual<N> {
    type Output = Self;
    fn sub(mut self, b: f64) -> Self {
        self.re -= b;
        self
    }
}

impl<const N: usize> Mul<f64> for Dual<N> {
    type Output = Self;
    fn mul(self, b: f64) -> Self {
        Self { re: self.re * b, eps: self.eps.map(|e| e * b) }
    }
}

impl<const N: usize> Div<f64> for Dual<N> {
    type Output = Self;
    fn div(self, b: f64) -> Self {
        Self { re: self.re / b, eps: self.eps.map(|e| e / b) }
    }
}

impl<const N: usize> Add<Dual<N>> for f64 {
    type Output = Dual<N>;
    fn add(self, b: Dual<N>) -> Dual<N> {
        b + self
    }
}

impl<const N: usize> Sub<Dual<N>> for f64 {
    type Output = Dual<N>;
    fn sub(self, b: Dual<N>) -> Dual<N> {
        -b + self
    }
}

impl<const N: usize> Mul<Dual<N>> for f64 {
    type Output = Dual<N>;
    fn mul(self, b: Dual<N>) -> Dual<N> {
        b * self
    }
}

impl<const N: usize> Div<Dual<N>> for f64 {
    type Output = Dual<N>;
    fn div(self, b: Dual<N>) -> Dual<N> {
        let v = self / b.re;
        b.chain(v, -v / b.re)
    }
}

/// `a op= b` as `a = a op b`, for a [`Dual`] or an `f64` on the right.
macro_rules! assign_ops {
    ($($tr:ident $method:ident $op:tt),*) => {$(
        impl<const N: usize> $tr for Dual<N> {
            fn $method(&mut self, b: Self) {
                *self = *self $op b;
            }
        }
        impl<const N: usize> $tr<f64> for Dual<N> {
            fn $method(&mut self, b: f64) {
                *self = *self $op b;
            }
        }
    )*};
}

assign_ops!(AddAssign add_assign +, SubAssign sub_assign -, MulAssign mul_assign *, DivAssign div_assign /);

impl<const N: usize> Sum for Dual<N> {
    fn sum<I: Iterator<Item = Self>>(iter: I) -> Self {
        iter.fold(Self::constant(0.0), |a, b| a + b)
    }
}

#[cfg(test)]
mod tests {
    use super::Dual;

    type D = Dual<1>;
    type Unary = (&'static str, fn(D) -> D);
    type Binary = (&'static str, fn(D, D) -> D);

    /// `g'(a)` by the dual number against a central difference of `g` on `f64`.
    fn check(name: &str, g: impl Fn(D) -> D, a: f64) {
        let d = g(D::variable(a, 0)).eps[0];
        let h = 1e-6 * a.abs().max(1.0);
        let fd = (g(D::constant(a + h)).re - g(D::constant(a - h)).re) / (2.0 * h);
        assert!((d - fd).abs() <= 1e-7 * fd.abs().max(1.0), "{name} at {a}: {d} vs {fd}");
    }

    #[test]
    fn every_function_differentiates_as_central_differences() {
        let c = D::constant(0.7);
        let unary: [Unary; 22] = [
            ("sin", D::sin),
            ("cos", D::cos),
            ("sin_cos", |a| a.sin_cos().0 + a.sin_cos().1 * 2.0),
            ("tan", D::tan),
            ("asin", D::asin),
            ("acos", D::acos),
            ("atan", D::atan),
            ("sinh", D::sinh),
            ("cosh", D::cosh),
            ("tanh", D::tanh),
            ("exp", D::exp),
            ("ln", D::ln),
            ("log10", D::log10),
            ("sqrt", D::sqrt),
            ("cbrt", D::cbrt),
            ("sqr", D::sqr),
            ("powi", |a| a.powi(3)),
            ("powf", |a| a.powf(2.5)),
            ("recip", D::recip),
            ("abs", |a| (a - 0.5).abs()),
            ("mixed", |a| (1.0 - a) * 0.5 / (2.0 + a) - 3.0 / a + (a + 1.0) * (a - 2.0)),
            ("assign", |a| {
                let mut b = a;
                b += 1.0;
                b *= a;
                b -= a * 0.5;
                b /= 2.0 + a;
                b
            }),
        ];
        for (name, g) in unary {
            for a in [0.3, 0.45, 0.8] {
                check(name, g, a);
            }
        }
        let binary: [Binary; 5] = [
            ("atan2", D::atan2),
            ("hypot", D::hypot),
            ("pow", D::pow),
            ("div", |a, b| a / b),
            ("sum", |a, b| [a, b, a * b].into_iter().sum()),
        ];
        for (name, g) in binary {
            for a in [0.3, 0.8] {
                check(name, |x| g(x, c), a);
                check(name, |x| g(c, x), a);
            }
        }
    }

    #[test]
    fn kinks_and_constants_follow_the_conventions() {
        assert_eq!(D::variable(0.0, 0).abs().eps, [0.0]);
        let (a, b) = (D::variable(1.0, 0), D::constant(1.0));
        assert_eq!(a.min(b).eps, [1.0]);
        assert_eq!(b.max(a).eps, [0.0]);
        // sqrt of a constant 0: value 0, no spurious NaN in the gradient.
        assert_eq!(Dual::<2>::constant(0.0).sqrt().eps, [0.0, 0.0]);
        // An index past the gradient is a constant, not a panic.
        assert_eq!(Dual::<2>::variable(3.0, 5), Dual::<2>::constant(3.0));
        assert_eq!(Dual::<2>::from(4.0), Dual::<2>::default() + 4.0);
    }
}
