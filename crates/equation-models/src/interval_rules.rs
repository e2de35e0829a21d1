//! The operations and functions of the expression language on intervals (crate `intervals`,
//! outward rounding): enclosures of each value and of each derivative over a box, for the
//! nonlinear set-membership filter's remainder bound (`models::SecondOrderModel`).
//!
//! Where a function is not differentiable inside the interval (`abs` at 0, `min`/`max` where the
//! arguments may tie) the derivative's enclosure holds the generalised (Clarke) derivative — the
//! hull of the one-sided ones — which is what the mean-value bound needs. Where a function jumps
//! inside the interval (`floor`, `signum`, …, `tan` at its poles, `atan2` across its cut) or is
//! undefined there, the result is [`Interval::ENTIRE`]: no bound, said so by the filter.

use std::f64::consts::{FRAC_PI_2, PI};

use intervals::{Interval, LIBM_ULPS, down, up};

use crate::ops::{Bin, Fun};

fn widen_down(x: f64) -> f64 {
    (0..LIBM_ULPS).fold(x, |v, _| down(v))
}

fn widen_up(x: f64) -> f64 {
    (0..LIBM_ULPS).fold(x, |v, _| up(v))
}

/// `f` increasing on `a` (a math-library function accurate to 1 ulp).
fn increasing(a: Interval, f: fn(f64) -> f64) -> Interval {
    Interval::new(widen_down(f(a.lo())), widen_up(f(a.hi())))
}

/// `f` decreasing on `a`.
fn decreasing(a: Interval, f: fn(f64) -> f64) -> Interval {
    Interval::new(widen_down(f(a.hi())), widen_up(f(a.lo())))
}

/// Whether `a` lies in `[lo, hi]`.
fn within(a: Interval, lo: f64, hi: f64) -> bool {
    a.lo() >= lo && a.hi() <= hi
}

/// A piecewise-constant function `f` (value `f` on the piece, slope `slope`): exact while `a`
/// stays in one piece (`f(lo) == f(hi)` and `same` says no jump lies between), else no bound.
fn piecewise(a: Interval, f: fn(f64) -> f64, same: bool) -> Interval {
    if same && a.is_bounded() { Interval::point(f(a.lo())) } else { Interval::ENTIRE }
}

/// Whether `a` may hold a point `offset + k·period` (tested with a margin: may only say yes).
fn holds_lattice(a: Interval, offset: f64, period: f64) -> bool {
    if !a.is_bounded() {
        return true;
    }
    let margin = 1e-9 * (1.0 + a.mag());
    let k = ((a.lo() - offset - margin) / period).ceil();
    k * period + offset <= a.hi() + margin
}

/// `f(a)` on intervals.
pub(crate) fn apply(f: Fun, a: Interval) -> Interval {
    let one = Interval::point(1.0);
    match f {
        Fun::Abs => {
            if a.lo() >= 0.0 {
                a
            } else if a.hi() <= 0.0 {
                -a
            } else {
                Interval::new(0.0, a.mag())
            }
        }
        Fun::Signum => {
            if a.lo() > 0.0 {
                one
            } else if a.hi() < 0.0 {
                -one
            } else {
                Interval::ENTIRE
            }
        }
        Fun::Floor => piecewise(a, f64::floor, a.lo().floor() == a.hi().floor()),
        Fun::Ceil => piecewise(a, f64::ceil, a.lo().ceil() == a.hi().ceil()),
        Fun::Round => piecewise(a, f64::round, a.lo().round() == a.hi().round()),
        Fun::Trunc => piecewise(a, f64::trunc, a.lo().trunc() == a.hi().trunc()),
        Fun::Fract => {
            if a.is_bounded() && a.lo().trunc() == a.hi().trunc() && !(a.lo() < 0.0 && a.hi() > 0.0) {
                a - a.lo().trunc()
            } else {
                Interval::ENTIRE
            }
        }
        Fun::Sin => a.sin(),
        Fun::Cos => a.cos(),
        Fun::Tan => {
            if holds_lattice(a, FRAC_PI_2, PI) {
                Interval::ENTIRE
            } else {
                increasing(a, f64::tan)
            }
        }
        Fun::Asin if within(a, -1.0, 1.0) => increasing(a, f64::asin),
        Fun::Acos if within(a, -1.0, 1.0) => decreasing(a, f64::acos),
        Fun::Atan => a.atan(),
        Fun::Sinh => increasing(a, f64::sinh),
        Fun::Cosh => {
            let top = widen_up(a.lo().cosh().max(a.hi().cosh()));
            if a.lo() <= 0.0 && a.hi() >= 0.0 {
                Interval::new(1.0, top)
            } else {
                Interval::new(widen_down(a.lo().abs().min(a.hi().abs()).cosh()).max(1.0), top)
            }
        }
        Fun::Tanh => a.tanh(),
        Fun::Asinh => increasing(a, f64::asinh),
        Fun::Acosh if a.lo() >= 1.0 => increasing(a, f64::acosh),
        Fun::Atanh if a.lo() > -1.0 && a.hi() < 1.0 => increasing(a, f64::atanh),
        Fun::Exp => a.exp(),
        Fun::Sqrt => a.sqrt(),
        Fun::Cbrt => increasing(a, f64::cbrt),
        Fun::Ln => a.ln(),
        Fun::Log2 if a.lo() > 0.0 => increasing(a, f64::log2),
        Fun::Log10 if a.lo() > 0.0 => increasing(a, f64::log10),
        Fun::Asin | Fun::Acos | Fun::Acosh | Fun::Atanh | Fun::Log2 | Fun::Log10 => Interval::ENTIRE,
    }
}

/// `f'(a)` on intervals, given `v ⊇ f(a)`.
pub(crate) fn derivative(f: Fun, a: Interval, v: Interval) -> Interval {
    let one = Interval::point(1.0);
    match f {
        Fun::Abs => {
            if a.lo() > 0.0 {
                one
            } else if a.hi() < 0.0 {
                -one
            } else {
                Interval::new(-1.0, 1.0)
            }
        }
        // Constant on a piece (apply gave no bound otherwise).
        Fun::Signum | Fun::Floor | Fun::Round | Fun::Ceil | Fun::Trunc => {
            if v.is_bounded() {
                Interval::ZERO
            } else {
                Interval::ENTIRE
            }
        }
        Fun::Fract => {
            if v.is_bounded() {
                one
            } else {
                Interval::ENTIRE
            }
        }
        Fun::Sin => a.cos(),
        Fun::Cos => -a.sin(),
        Fun::Tan => one + v.sqr(),
        Fun::Asin => one / (one - a.sqr()).sqrt(),
        Fun::Acos => -(one / (one - a.sqr()).sqrt()),
        Fun::Atan => one / (one + a.sqr()),
        Fun::Sinh => apply(Fun::Cosh, a),
        Fun::Cosh => apply(Fun::Sinh, a),
        Fun::Tanh => one - v.sqr(),
        Fun::Asinh => one / (a.sqr() + one).sqrt(),
        Fun::Acosh => one / (a.sqr() - one).sqrt(),
        Fun::Atanh => one / (one - a.sqr()),
        Fun::Exp => v,
        Fun::Sqrt => Interval::point(0.5) / v,
        Fun::Cbrt => one / (v.sqr() * 3.0),
        Fun::Ln => one / a,
        Fun::Log2 => one / (a * std::f64::consts::LN_2),
        Fun::Log10 => one / (a * std::f64::consts::LN_10),
    }
}

/// An enclosure of π/2.
fn half_pi() -> Interval {
    Interval::new(down(FRAC_PI_2), up(FRAC_PI_2))
}

/// `a^k` for an integer `k` (exact monotone bounds for even powers).
fn powi(a: Interval, k: i64) -> Interval {
    if k == 0 {
        return Interval::point(1.0);
    }
    let m = k.unsigned_abs();
    let mut r = if m % 2 == 0 {
        let base = a.sqr();
        let mut r = Interval::point(1.0);
        for _ in 0..m / 2 {
            r = r * base;
        }
        r
    } else {
        let mut r = a;
        for _ in 1..m {
            r = r * a;
        }
        r
    };
    if k < 0 {
        r = Interval::point(1.0) / r;
    }
    r
}

/// The integer exponent of a point interval, if it is one (small enough to multiply out).
fn integer_exponent(b: Interval) -> Option<i64> {
    let e = b.lo();
    (b.lo() == b.hi() && e.fract() == 0.0 && e.abs() <= 64.0).then_some(e as i64)
}

/// `g(a, b)` on intervals.
pub(crate) fn bin_apply(g: Bin, a: Interval, b: Interval) -> Interval {
    match g {
        Bin::Add => a + b,
        Bin::Sub => a - b,
        Bin::Mul => a * b,
        Bin::Div => a / b,
        Bin::Pow => match integer_exponent(b) {
            Some(k) => powi(a, k),
            None if a.lo() > 0.0 => (b * a.ln()).exp(),
            None => Interval::ENTIRE,
        },
        Bin::Atan2 => {
            if b.lo() > 0.0 {
                (a / b).atan()
            } else if a.lo() > 0.0 {
                half_pi() - (b / a).atan()
            } else if a.hi() < 0.0 {
                -half_pi() - (b / a).atan()
            } else {
                // The cut (b ≤ 0, a = 0) or the origin may lie in the box.
                Interval::ENTIRE
            }
        }
        Bin::Min => Interval::new(a.lo().min(b.lo()), a.hi().min(b.hi())),
        Bin::Max => Interval::new(a.lo().max(b.lo()), a.hi().max(b.hi())),
    }
}

/// `(∂g/∂a, ∂g/∂b)` on intervals, given `v ⊇ g(a, b)`; `need_a`, `need_b` say which are used.
pub(crate) fn bin_partials(
    g: Bin,
    a: Interval,
    b: Interval,
    v: Interval,
    need_a: bool,
    need_b: bool,
) -> (Interval, Interval) {
    let (one, zero) = (Interval::point(1.0), Interval::ZERO);
    match g {
        Bin::Add => (one, one),
        Bin::Sub => (one, -one),
        Bin::Mul => (b, a),
        Bin::Div => (one / b, -(v / b)),
        Bin::Pow => {
            let da = if need_a {
                match integer_exponent(b) {
                    Some(k) => powi(a, k - 1) * (k as f64),
                    None => b * bin_apply(Bin::Pow, a, b - 1.0),
                }
            } else {
                zero
            };
            let db = if need_b { v * a.ln() } else { zero };
            (da, db)
        }
        Bin::Atan2 => {
            let r = a.sqr() + b.sqr();
            (b / r, -(a / r))
        }
        Bin::Min | Bin::Max => {
            let a_wins = if g == Bin::Min { a.hi() < b.lo() } else { a.lo() > b.hi() };
            let b_wins = if g == Bin::Min { b.hi() < a.lo() } else { b.lo() > a.hi() };
            if a_wins {
                (one, zero)
            } else if b_wins {
                (zero, one)
            } else {
                // Either may be the active one: the hull of both one-sided derivatives.
                let both = Interval::new(0.0, 1.0);
                (both, both)
            }
        }
    }
}
