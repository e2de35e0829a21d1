//! Angles: which states and outputs of a model are angles in radians, defined modulo 2π.
//!
//! A model declares them once ([`crate::DiscreteModel::angles`], default none) and every
//! estimator does the rest: innovations and residuals of angle outputs are wrapped to
//! `(−π, π]` ([`wrap_angle`]), the unscented filter's means of angle rows are circular and
//! their deviations wrapped, the set-membership filters choose the branch of an angle
//! measurement from the predicted enclosure of `h`, and the simulator publishes angle outputs
//! wrapped, as a sensor does. Angle *states* are never wrapped by an estimator: a heading
//! estimate stays continuous (it may leave `(−π, π]` after a full turn), so the model's `f`
//! must accept any real angle, as trigonometric models do.

use std::f64::consts::{PI, TAU};

use crate::dims::Dims;
use crate::error::ModelError;

/// The angle states and angle outputs of a model, as sorted, distinct indices.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Angles<'a> {
    /// Indices of the states that are angles.
    pub states: &'a [usize],
    /// Indices of the outputs that are angles.
    pub outputs: &'a [usize],
}

impl<'a> Angles<'a> {
    /// No angle anywhere (the default of every model).
    pub const NONE: Angles<'static> = Angles { states: &[], outputs: &[] };

    /// The declaration `states`, `outputs`.
    #[must_use]
    pub const fn new(states: &'a [usize], outputs: &'a [usize]) -> Self {
        Self { states, outputs }
    }

    /// Whether nothing is declared an angle.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.states.is_empty() && self.outputs.is_empty()
    }

    /// Checks the indices against the model's dimensions: each below `n` (states) or `m`
    /// (outputs), strictly increasing.
    ///
    /// # Errors
    /// [`ModelError::InvalidAngles`] naming the list and the index.
    pub fn validate(&self, dims: Dims) -> Result<(), ModelError> {
        for (what, list, len) in [("states", self.states, dims.states), ("outputs", self.outputs, dims.outputs)] {
            for (i, &k) in list.iter().enumerate() {
                if k >= len {
                    return Err(ModelError::InvalidAngles { what, index: k, reason: "out of range" });
                }
                if i > 0 && list[i - 1] >= k {
                    return Err(ModelError::InvalidAngles { what, index: k, reason: "not strictly increasing" });
                }
            }
        }
        Ok(())
    }

    /// Wraps the angle outputs of `residual` (a vector of length `m`, e.g. an innovation) to
    /// `(−π, π]`; other entries unchanged. Allocation-free.
    pub fn wrap_outputs(&self, residual: &mut [f64]) {
        for &k in self.outputs {
            if let Some(r) = residual.get_mut(k) {
                *r = wrap_angle(*r);
            }
        }
    }

    /// Replaces each angle output `y_k` by its representative nearest `reference_k`,
    /// `reference_k + wrap(y_k − reference_k)`: the measurement unwrapped to the branch of a
    /// prediction, so that an estimator minimising `y − h(x)` sees residuals in `(−π, π]`.
    pub fn unwrap_outputs(&self, y: &mut [f64], reference: &[f64]) {
        for &k in self.outputs {
            if let (Some(yk), Some(&r)) = (y.get_mut(k), reference.get(k)) {
                let d = wrap_angle(*yk - r);
                if d != *yk - r {
                    *yk = r + d;
                }
            }
        }
    }
}

/// Wraps an angle to `(−π, π]`; an angle already there is returned unchanged (bit for bit), NaN
/// stays NaN, ±∞ gives NaN.
#[must_use]
pub fn wrap_angle(a: f64) -> f64 {
    if a > -PI && a <= PI {
        return a;
    }
    let r = a.rem_euclid(TAU);
    if r > PI { r - TAU } else { r }
}

/// The branch of an angle measurement: the one `k` with `y + 2πk` in `[lo, hi]` (an enclosure of
/// `h(x) + v` over every state and noise the set admits), as `Ok(Some(y + 2πk))`; `Ok(None)`
/// when no representative lies in the enclosure (the measurement contradicts the set).
///
/// The enclosure must be narrower than 2π − 4 ulp(π) for the branch to be unique; otherwise
/// `Err(width)`. Rounding: the candidate is tested with a margin of a few ulps so that a
/// representative on the enclosure's edge is kept; two candidates inside is again `Err`.
pub fn angle_branch(y: f64, lo: f64, hi: f64) -> Result<Option<f64>, f64> {
    let width = hi - lo;
    let finite = y.is_finite() && lo.is_finite() && hi.is_finite();
    if !finite || width >= TAU - 8.0 * f64::EPSILON * PI {
        return Err(width);
    }
    let margin = 8.0 * f64::EPSILON * (lo.abs().max(hi.abs()) + PI);
    let k = ((lo - y) / TAU).ceil();
    let mut found = None;
    for kk in [k - 1.0, k, k + 1.0] {
        let cand = y + TAU * kk;
        if cand >= lo - margin && cand <= hi + margin {
            if found.is_some() {
                return Err(width);
            }
            found = Some(cand);
        }
    }
    Ok(found)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_is_identity_inside_and_periodic_outside() {
        for a in [0.0, 0.1, -0.1, 3.0, -3.0, PI, -PI + 1e-15] {
            assert_eq!(wrap_angle(a).to_bits(), a.to_bits());
        }
        assert_eq!(wrap_angle(-PI), PI);
        assert_eq!(wrap_angle(3.0 * PI), PI);
        assert!((wrap_angle(0.1 + 4.0 * PI) - 0.1).abs() < 1e-14);
        assert!((wrap_angle(-3.0 * PI / 2.0) - PI / 2.0).abs() < 1e-15);
        assert!(wrap_angle(f64::NAN).is_nan());
        assert!(wrap_angle(f64::INFINITY).is_nan());
        for i in -2000..2000 {
            let a = f64::from(i) * 0.01;
            let w = wrap_angle(a);
            assert!(w > -PI && w <= PI, "{a} -> {w}");
            let turns = (a - w) / TAU;
            assert!((turns - turns.round()).abs() < 1e-12, "{a} -> {w}");
        }
    }

    #[test]
    fn validation_names_the_list_and_index() {
        let dims = Dims::new(4, 2, 3);
        assert!(Angles::new(&[2], &[1, 2]).validate(dims).is_ok());
        let e = Angles::new(&[4], &[]).validate(dims).unwrap_err();
        assert!(e.to_string().contains("states") && e.to_string().contains('4'), "{e}");
        let e = Angles::new(&[], &[1, 1]).validate(dims).unwrap_err();
        assert!(e.to_string().contains("outputs"), "{e}");
    }

    #[test]
    fn wrapping_and_unwrapping_outputs() {
        let angles = Angles::new(&[], &[1]);
        let mut r = [7.0, 3.2, -7.0];
        angles.wrap_outputs(&mut r);
        assert_eq!(r[0], 7.0);
        assert!((r[1] - (3.2 - TAU)).abs() < 1e-15);
        assert_eq!(r[2], -7.0);
        // A bearing measured at −3.1 just after crossing −π, predicted at 3.1: unwrapped to
        // 2π − 3.1 beside the prediction.
        let mut y = [0.0, -3.1];
        angles.unwrap_outputs(&mut y, &[0.0, 3.1]);
        assert!((y[1] - (TAU - 3.1)).abs() < 1e-15);
        let mut y = [0.0, 0.5];
        angles.unwrap_outputs(&mut y, &[0.0, 0.4]);
        assert_eq!(y[1], 0.5);
    }

    #[test]
    fn branches_are_unique_or_refused() {
        assert_eq!(angle_branch(-3.1, 3.0, 3.3).unwrap(), Some(-3.1 + TAU));
        assert_eq!(angle_branch(0.2, -0.1, 0.3).unwrap(), Some(0.2));
        assert_eq!(angle_branch(1.0, -0.1, 0.3).unwrap(), None);
        assert_eq!(angle_branch(0.2, 12.0, 12.9).unwrap(), Some(0.2 + 2.0 * TAU));
        assert!(angle_branch(0.2, -4.0, 4.0).is_err());
        assert!(angle_branch(0.2, f64::NEG_INFINITY, 0.0).is_err());
        // On the enclosure's edge.
        assert_eq!(angle_branch(0.3, -0.1, 0.3).unwrap(), Some(0.3));
    }
}
