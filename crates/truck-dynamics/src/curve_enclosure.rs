//! Interval enclosures of the tyres' Magic Formula curves at their static loads, with the slip's
//! unit and the lumping folded in: the wheel-level part of the EKF model's enclosures
//! ([`crate::enclosure`]), computed once with the model ([`crate::planar::TruckEkfModel`]).

use intervals::Dual;
use models::Interval;

use crate::kinematics::WHEELS;
use crate::tyre::{LumpedCurves, MagicFormula};

/// Interval enclosures of a Magic Formula curve's coefficients, with the slip's unit and the
/// lumping folded in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Curve {
    /// `B·unit` (unit: degrees per radian or percent per unit slip).
    b_unit: Interval,
    /// `B·S_H`.
    b_sh: Interval,
    c: Interval,
    /// `1 − E`.
    one_minus_e: Interval,
    e: Interval,
    /// `n·k·D` (`n·k`: tyres at the position times the fade below the load clamp).
    d_scaled: Interval,
    /// `n·k·S_V`.
    sv_scaled: Interval,
}

impl Curve {
    fn new(mf: &MagicFormula, scale: Interval, unit: Interval) -> Self {
        let (b, e) = (Interval::point(mf.b), Interval::point(mf.e));
        Self {
            b_unit: b * unit,
            b_sh: b * mf.sh,
            c: Interval::point(mf.c),
            one_minus_e: Interval::point(1.0) - e,
            e,
            d_scaled: scale * mf.d,
            sv_scaled: scale * mf.sv,
        }
    }

    /// `n·k·(D·sin(C·atan θ) + S_V)`, `θ = (1 − E)·B·x + E·atan(B·x)` (= `B·x − E·(B·x −
    /// atan(B·x))`, eq (3)–(4)), `B·x = B·unit·slip + B·S_H`: the same function as tyre.rs with
    /// fewer occurrences of the variables, so a tighter enclosure.
    pub(crate) fn force<const N: usize>(&self, slip: Dual<N>) -> Dual<N> {
        if N == 0 {
            return Dual::constant(self.curve(Dual::<0>::constant(slip.value)).value);
        }
        // One derivative through the curve, then the chain rule once (`Dual::map_scalar`).
        slip.map_scalar(|s| self.curve(s))
    }

    /// The curve of [`Curve::force`] on any number of gradient entries.
    fn curve<const M: usize>(&self, slip: Dual<M>) -> Dual<M> {
        let bx = slip * self.b_unit + self.b_sh;
        let theta = bx * self.one_minus_e + bx.atan() * self.e;
        (theta.atan() * self.c).sin() * self.d_scaled + self.sv_scaled
    }
}

/// The enclosed curves of one wheel position at its static load.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct EnclosedWheel {
    pub(crate) lateral: Curve,
    pub(crate) longitudinal: Curve,
}

/// The enclosed curves of every wheel position (computed once, with the model).
pub(crate) fn enclosed_curves(curves: &[LumpedCurves; WHEELS]) -> [EnclosedWheel; WHEELS] {
    let (deg, percent) = (degrees_per_radian(), Interval::point(100.0));
    std::array::from_fn(|j| {
        let c = &curves[j];
        // n·k, the lumping and the fade, enclosed.
        let scale = Interval::point(c.n) * c.k;
        EnclosedWheel {
            lateral: Curve::new(&c.lateral, scale, deg),
            longitudinal: Curve::new(&c.longitudinal, scale, percent),
        }
    })
}

/// `180/π` enclosed (`π` lies within one ulp of `f64`'s `PI`).
fn degrees_per_radian() -> Interval {
    let pi = std::f64::consts::PI;
    Interval::point(180.0) / Interval::new(intervals::down(pi), intervals::up(pi))
}
