//! Closed intervals `[lo, hi]` of `f64` with outward rounding: every operation returns an interval
//! that contains the exact result of the operation on every pair of real numbers of its operands.
//!
//! Why not a library: `inari`, the well-kept Rust interval crate, needs a Haswell target CPU set by
//! the consuming crate and GMP/MPFR (a C build) for its elementary functions, against the
//! workspace's rule that the default build needs no system library. The filter needs few
//! operations, written here with a documented error model:
//!
//! * `+ − × ÷` and `sqrt` are correctly rounded in IEEE 754 (error ≤ ½ ulp): each bound is moved
//!   outward by one ulp ([`down`], [`up`]), which encloses the exact result.
//! * `sin`, `cos`, `atan`, `exp`, `ln`, `tanh` come from the platform's math library, assumed
//!   accurate to 1 ulp (glibc documents ≤ 1 ulp for these on x86-64): bounds are moved outward by
//!   [`LIBM_ULPS`] ulps, and clamped to the function's range.
//! * An operation that is undefined somewhere on its operands (division by an interval holding 0,
//!   `sqrt` or `ln` of negative numbers) returns [`Interval::ENTIRE`] (`[-∞, +∞]`), which the
//!   caller detects with [`Interval::is_bounded`]; NaN operands give `ENTIRE` too. Enclosures are
//!   never silently narrowed.

#![warn(missing_docs)]

mod dual;

pub use dual::Dual;

use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::fmt;
use std::ops::{Add, Div, Mul, Neg, Sub};

/// Ulps by which the bounds of a math-library function are widened (twice its assumed accuracy).
pub const LIBM_ULPS: u32 = 2;

/// The distance kept from an extremum of `sin`, `cos` before an interval counts as lying where
/// the function is monotone (far above the rounding of the bounds and of `π/2`, `π`).
const MONOTONE_MARGIN: f64 = 1e-6;

/// The next `f64` above `x` (`+∞` stays; NaN stays NaN).
#[must_use]
#[inline]
pub fn up(x: f64) -> f64 {
    if x.is_nan() || x == f64::INFINITY {
        return x;
    }
    if x == 0.0 {
        return f64::from_bits(1); // the smallest positive subnormal, from +0 and −0 alike
    }
    let bits = x.to_bits();
    f64::from_bits(if x > 0.0 { bits + 1 } else { bits - 1 })
}

/// The next `f64` below `x`.
#[must_use]
#[inline]
pub fn down(x: f64) -> f64 {
    -up(-x)
}

/// `n` ulps above `x` (`n ≤ 4`).
#[inline]
fn up_n(mut x: f64, n: u32) -> f64 {
    debug_assert!(n <= 4);
    if x.is_finite() && x.abs() >= 16.0 * f64::MIN_POSITIVE {
        // Away from 0 the bits of a finite `f64` are ordered as its magnitude: `n` ulps are `n`
        // steps of the bits (past `f64::MAX` they reach +∞, then NaN patterns, which `min` maps
        // to +∞).
        let bits = x.to_bits();
        let stepped = if x > 0.0 { bits + u64::from(n) } else { bits - u64::from(n) };
        return f64::from_bits(stepped).min(f64::INFINITY);
    }
    for _ in 0..n {
        x = up(x);
    }
    x
}

/// `n` ulps below `x` (`n ≤ 4`).
#[inline]
fn down_n(x: f64, n: u32) -> f64 {
    -up_n(-x, n)
}

/// A closed interval `[lo, hi]` (`lo ≤ hi`, either may be infinite).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    lo: f64,
    hi: f64,
}

impl Interval {
    /// `[-∞, +∞]`: what an undefined or overflowing operation returns.
    pub const ENTIRE: Interval = Interval { lo: f64::NEG_INFINITY, hi: f64::INFINITY };
    /// `[0, 0]`.
    pub const ZERO: Interval = Interval { lo: 0.0, hi: 0.0 };

    /// `[lo, hi]`; [`Interval::ENTIRE`] when a bound is NaN or `lo > hi`.
    #[must_use]
    #[inline]
    pub fn new(lo: f64, hi: f64) -> Self {
        if lo.is_nan() || hi.is_nan() || lo > hi { Self::ENTIRE } else { Self { lo, hi } }
    }

    /// The point `[x, x]` (`ENTIRE` for NaN).
    #[must_use]
    #[inline]
    pub fn point(x: f64) -> Self {
        Self::new(x, x)
    }

    /// `[c − r, c + r]` rounded outward (`r ≥ 0`).
    #[must_use]
    #[inline]
    pub fn centered(c: f64, r: f64) -> Self {
        Self::new(down(c - r), up(c + r))
    }

    /// The lower bound.
    #[must_use]
    #[inline]
    pub fn lo(self) -> f64 {
        self.lo
    }

    /// The upper bound.
    #[must_use]
    #[inline]
    pub fn hi(self) -> f64 {
        self.hi
    }

    /// Whether both bounds are finite.
    #[must_use]
    #[inline]
    pub fn is_bounded(self) -> bool {
        self.lo.is_finite() && self.hi.is_finite()
    }

    /// Whether `x` lies in the interval.
    #[must_use]
    #[inline]
    pub fn contains(self, x: f64) -> bool {
        self.lo <= x && x <= self.hi
    }

    /// The largest magnitude `max(|lo|, |hi|)`: every element's absolute value is at most this.
    #[must_use]
    #[inline]
    pub fn mag(self) -> f64 {
        self.lo.abs().max(self.hi.abs())
    }

    /// An upper bound of the width `hi − lo`.
    #[must_use]
    #[inline]
    pub fn width(self) -> f64 {
        up(self.hi - self.lo)
    }

    /// The smallest interval holding both.
    #[must_use]
    #[inline]
    pub fn hull(self, other: Interval) -> Self {
        Self { lo: self.lo.min(other.lo), hi: self.hi.max(other.hi) }
    }

    /// `x ∩ y`, `None` when they do not meet.
    #[must_use]
    #[inline]
    pub fn meet(self, other: Interval) -> Option<Interval> {
        let (lo, hi) = (self.lo.max(other.lo), self.hi.min(other.hi));
        (lo <= hi).then_some(Self { lo, hi })
    }

    /// The midpoint (0 when it is not finite) and a radius rounded up so that
    /// `[mid − rad, mid + rad]` holds the interval.
    #[must_use]
    #[inline]
    pub fn mid_rad(self) -> (f64, f64) {
        let m = 0.5 * self.lo + 0.5 * self.hi;
        let m = if m.is_finite() { m } else { 0.0 };
        (m, up(up(self.hi - m).max(up(m - self.lo))))
    }

    /// `|x|` (exact: no rounding).
    #[must_use]
    #[inline]
    pub fn abs(self) -> Self {
        if self.lo >= 0.0 {
            self
        } else if self.hi <= 0.0 {
            -self
        } else {
            Self { lo: 0.0, hi: self.hi.max(-self.lo) }
        }
    }

    /// `max(x, y)` over both intervals (exact).
    #[must_use]
    #[inline]
    pub fn max(self, other: Interval) -> Self {
        Self::new(self.lo.max(other.lo), self.hi.max(other.hi))
    }

    /// `min(x, y)` over both intervals (exact).
    #[must_use]
    #[inline]
    pub fn min(self, other: Interval) -> Self {
        Self::new(self.lo.min(other.lo), self.hi.min(other.hi))
    }

    /// Whether every element is `≥` every element of `other` (`lo ≥ other.hi`).
    #[must_use]
    #[inline]
    pub fn certainly_ge(self, other: Interval) -> bool {
        self.lo >= other.hi
    }

    /// `x²` (tighter than `x * x` when the interval holds 0).
    #[must_use]
    #[inline]
    pub fn sqr(self) -> Self {
        let (a, b) = (self.lo.abs(), self.hi.abs());
        let big = up(a.max(b) * a.max(b));
        if self.lo <= 0.0 && self.hi >= 0.0 {
            Self::new(0.0, big)
        } else {
            Self::new(down(a.min(b) * a.min(b)).max(0.0), big)
        }
    }

    /// `√x` (`ENTIRE` if the interval holds negative numbers).
    #[must_use]
    pub fn sqrt(self) -> Self {
        if self.lo < 0.0 {
            return Self::ENTIRE;
        }
        Self::new(down(self.lo.sqrt()).max(0.0), up(self.hi.sqrt()))
    }

    /// `e^x`.
    #[must_use]
    pub fn exp(self) -> Self {
        Self::new(down_n(self.lo.exp(), LIBM_ULPS).max(0.0), up_n(self.hi.exp(), LIBM_ULPS))
    }

    /// `ln x` (`ENTIRE` if the interval holds numbers ≤ 0).
    #[must_use]
    pub fn ln(self) -> Self {
        if self.lo <= 0.0 {
            return Self::ENTIRE;
        }
        Self::new(down_n(self.lo.ln(), LIBM_ULPS), up_n(self.hi.ln(), LIBM_ULPS))
    }

    /// `atan x`.
    #[must_use]
    pub fn atan(self) -> Self {
        let limit = up(FRAC_PI_2);
        // A point needs one evaluation (atan is increasing).
        let (lo, hi) = if self.lo == self.hi {
            let v = self.lo.atan();
            (v, v)
        } else {
            (self.lo.atan(), self.hi.atan())
        };
        Self::new(down_n(lo, LIBM_ULPS).max(-limit), up_n(hi, LIBM_ULPS).min(limit))
    }

    /// `tanh x`.
    #[must_use]
    pub fn tanh(self) -> Self {
        Self::new(down_n(self.lo.tanh(), LIBM_ULPS).max(-1.0), up_n(self.hi.tanh(), LIBM_ULPS).min(1.0))
    }

    /// `sin x`: the extremes inside the interval (`+1` at `π/2 + 2kπ`, `−1` at `−π/2 + 2kπ`), else
    /// the end values.
    #[must_use]
    pub fn sin(self) -> Self {
        // Within (−π/2, π/2), with a margin, sin increases: no extreme inside.
        if self.lo > -FRAC_PI_2 + MONOTONE_MARGIN && self.hi < FRAC_PI_2 - MONOTONE_MARGIN {
            return self.monotone(f64::sin, true);
        }
        self.periodic(f64::sin, FRAC_PI_2, -FRAC_PI_2)
    }

    /// `cos x`: the extremes inside the interval (`+1` at `2kπ`, `−1` at `π + 2kπ`), else the end
    /// values.
    #[must_use]
    pub fn cos(self) -> Self {
        // Within (0, π), with a margin, cos decreases; within (−π, 0) it increases.
        if self.lo > MONOTONE_MARGIN && self.hi < PI - MONOTONE_MARGIN {
            return self.monotone(f64::cos, false);
        }
        if self.lo > -PI + MONOTONE_MARGIN && self.hi < -MONOTONE_MARGIN {
            return self.monotone(f64::cos, true);
        }
        self.periodic(f64::cos, 0.0, PI)
    }

    /// `g` over an interval on which it is monotone (increasing or not), values in `[−1, 1]`.
    #[inline]
    fn monotone(self, g: fn(f64) -> f64, increasing: bool) -> Self {
        let (ga, gb) = if self.lo == self.hi {
            let v = g(self.lo);
            (v, v)
        } else {
            (g(self.lo), g(self.hi))
        };
        let (lo, hi) = if increasing { (ga, gb) } else { (gb, ga) };
        Self::new(down_n(lo, LIBM_ULPS).max(-1.0), up_n(hi, LIBM_ULPS).min(1.0))
    }

    /// A `2π`-periodic function with values in `[−1, 1]`, its maxima at `max_at + 2kπ` and minima
    /// at `min_at + 2kπ`, monotone between them.
    fn periodic(self, g: fn(f64) -> f64, max_at: f64, min_at: f64) -> Self {
        if !self.is_bounded() || self.width() >= TAU {
            return Self::new(-1.0, 1.0);
        }
        let (a, b) = (self.lo, self.hi);
        let (ga, gb) = if a == b {
            let v = g(a);
            (v, v)
        } else {
            (g(a), g(b))
        };
        let mut lo = down_n(ga.min(gb), LIBM_ULPS).max(-1.0);
        let mut hi = up_n(ga.max(gb), LIBM_ULPS).min(1.0);
        // Extremes inside, tested with a margin, so that a point near a bound counts as inside
        // (an enclosure may only grow; the shifts by π/2, π are not exact either).
        let margin = 1e-9 * (1.0 + a.abs().max(b.abs()));
        let holds = |offset: f64| {
            let k = ((a - offset - margin) / TAU).ceil();
            k * TAU + offset <= b + margin
        };
        if holds(max_at) {
            hi = 1.0;
        }
        if holds(min_at) {
            lo = -1.0;
        }
        Self::new(lo, hi)
    }
}

impl fmt::Display for Interval {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "[{:e}, {:e}]", self.lo, self.hi)
    }
}

impl From<f64> for Interval {
    fn from(x: f64) -> Self {
        Self::point(x)
    }
}

impl Neg for Interval {
    type Output = Interval;
    #[inline]
    fn neg(self) -> Interval {
        Interval { lo: -self.hi, hi: -self.lo }
    }
}

impl Add for Interval {
    type Output = Interval;
    #[inline]
    fn add(self, o: Interval) -> Interval {
        Interval::new(down(self.lo + o.lo), up(self.hi + o.hi))
    }
}

impl Sub for Interval {
    type Output = Interval;
    #[inline]
    fn sub(self, o: Interval) -> Interval {
        Interval::new(down(self.lo - o.hi), up(self.hi - o.lo))
    }
}

impl Mul for Interval {
    type Output = Interval;
    #[inline]
    fn mul(self, o: Interval) -> Interval {
        // 0 × ∞ is taken as 0 (an infinite bound stands for "unbounded", and the other factor
        // is exactly 0 there). The signs of the bounds say which products are the extremes.
        let p = |x: f64, y: f64| if x == 0.0 || y == 0.0 { 0.0 } else { x * y };
        let (a, b, c, d) = (self.lo, self.hi, o.lo, o.hi);
        let (lo, hi) = if a >= 0.0 {
            if c >= 0.0 {
                (p(a, c), p(b, d))
            } else if d <= 0.0 {
                (p(b, c), p(a, d))
            } else {
                (p(b, c), p(b, d))
            }
        } else if b <= 0.0 {
            if c >= 0.0 {
                (p(a, d), p(b, c))
            } else if d <= 0.0 {
                (p(b, d), p(a, c))
            } else {
                (p(a, d), p(a, c))
            }
        } else if c >= 0.0 {
            (p(a, d), p(b, d))
        } else if d <= 0.0 {
            (p(b, c), p(a, c))
        } else {
            (p(a, d).min(p(b, c)), p(a, c).max(p(b, d)))
        };
        Interval::new(down(lo), up(hi))
    }
}

impl Div for Interval {
    type Output = Interval;
    #[inline]
    fn div(self, o: Interval) -> Interval {
        let (a, b, c, d) = (self.lo, self.hi, o.lo, o.hi);
        // The divisor's sign is fixed: the signs of the dividend's bounds say which quotients are
        // the extremes.
        let (lo, hi) = if c > 0.0 {
            (if a >= 0.0 { a / d } else { a / c }, if b >= 0.0 { b / c } else { b / d })
        } else if d < 0.0 {
            (if b >= 0.0 { b / d } else { b / c }, if a >= 0.0 { a / c } else { a / d })
        } else {
            return Interval::ENTIRE;
        };
        Interval::new(down(lo), up(hi))
    }
}

macro_rules! with_f64 {
    ($($tr:ident $f:ident),*) => {$(
        impl $tr<f64> for Interval {
            type Output = Interval;
            #[inline]
            fn $f(self, o: f64) -> Interval {
                $tr::$f(self, Interval::point(o))
            }
        }
        impl $tr<Interval> for f64 {
            type Output = Interval;
            #[inline]
            fn $f(self, o: Interval) -> Interval {
                $tr::$f(Interval::point(self), o)
            }
        }
    )*};
}

with_f64!(Add add, Sub sub, Div div);

impl Interval {
    /// `x·c` for a number `c` known exactly: two products, ordered by the sign of `c` (the common
    /// case of a model's constants, cheaper than `x * Interval::point(c)`, the same enclosure).
    #[must_use]
    #[inline]
    pub fn times(self, c: f64) -> Interval {
        if c > 0.0 {
            Interval::new(down(self.lo * c), up(self.hi * c))
        } else if c < 0.0 {
            Interval::new(down(self.hi * c), up(self.lo * c))
        } else if c == 0.0 {
            // 0 × an unbounded bound is 0, as in `Mul`.
            Interval::ZERO
        } else {
            Interval::ENTIRE
        }
    }
}

impl Mul<f64> for Interval {
    type Output = Interval;
    #[inline]
    fn mul(self, c: f64) -> Interval {
        self.times(c)
    }
}

impl Mul<Interval> for f64 {
    type Output = Interval;
    #[inline]
    fn mul(self, x: Interval) -> Interval {
        x.times(self)
    }
}

#[cfg(test)]
mod tests {
    use super::{down, down_n, up, up_n};

    #[test]
    fn steps_of_the_bits_are_steps_of_up_and_down() {
        let mut values = vec![
            1.0,
            -1.0,
            f64::MAX,
            -f64::MAX,
            f64::MIN_POSITIVE,
            16.0 * f64::MIN_POSITIVE,
            -16.0 * f64::MIN_POSITIVE,
            1e-310,
            0.0,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        let mut x = 0.7f64;
        for _ in 0..200 {
            x = (x * 3.9 * (1.0 - x)).abs();
            values.push((x - 0.5) * 10f64.powi((x * 600.0) as i32 - 300));
        }
        for &v in &values {
            for n in 0..=4 {
                let (mut u, mut d) = (v, v);
                for _ in 0..n {
                    u = up(u);
                    d = down(d);
                }
                assert_eq!(up_n(v, n).to_bits(), u.to_bits(), "up_n({v:e}, {n})");
                assert_eq!(down_n(v, n).to_bits(), d.to_bits(), "down_n({v:e}, {n})");
            }
        }
    }
}
