//! Angle measurements in the set-membership filters: `y = wrap(h(x) + v)`.
//!
//! The sensor reports `h(x) + v` modulo 2π. Given an enclosure `[lo, hi]` of `h(x) + v` over every
//! state the predicted set admits and every noise in `V`, the measurement's branch is the one
//! representative `y + 2πk` in it (`models::angle_branch`); the filters then use that value as
//! an ordinary measurement. Soundness: `f64`'s `2π` and the sum are rounded, so the shifted value
//! is published with an error bound that the filters add to the measurement's interval. An
//! enclosure at least 2π wide cannot choose a branch: the guarantee is lost (typed); no
//! representative in it: the data contradict the set (the filters' inconsistency policy).

use intervals::Interval;
use nalgebra::DVector;

use crate::error::EstimatorError;

/// What [`branch`] found.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Branch {
    /// Every angle output has its branch (written into the output buffer).
    Chosen,
    /// An angle output has no representative in its enclosure: the data contradict the set.
    Contradicted,
}

/// Copies `y` into `out` and moves each angle output `i` to its branch in `enclosure(i)`
/// widened by `v_half[i]`; `err[i]` receives a bound on the rounding of the shifted value (0 for
/// an entry left as measured). Allocation-free.
///
/// # Errors
/// [`EstimatorError::GuaranteeLost`] at `step` when an enclosure spans 2π.
pub(crate) fn branch(
    angle_outputs: &[usize],
    y: &DVector<f64>,
    mut enclosure: impl FnMut(usize) -> Interval,
    v_half: &[f64],
    out: &mut DVector<f64>,
    err: &mut [f64],
    step: u64,
) -> Result<Branch, EstimatorError> {
    out.copy_from(y);
    err.fill(0.0);
    let mut verdict = Branch::Chosen;
    for &i in angle_outputs {
        let h = enclosure(i) + Interval::new(-v_half[i], v_half[i]);
        match models::angle_branch(y[i], h.lo(), h.hi()) {
            Ok(Some(shifted)) => {
                if shifted != y[i] {
                    err[i] = shift_error(y[i], shifted);
                    out[i] = shifted;
                }
            }
            Ok(None) => verdict = Branch::Contradicted,
            Err(width) => {
                return Err(EstimatorError::GuaranteeLost {
                    step,
                    reason: format!(
                        "angle output {i}: the predicted enclosure of h plus the noise bound is {width:e} rad wide \
                         (not below 2π), so the measured angle's branch cannot be chosen"
                    ),
                });
            }
        }
    }
    Ok(verdict)
}

/// A bound on the rounding of `shifted`, the representative `y + 2πk` computed in `f64` (0 when
/// nothing was shifted).
pub(crate) fn shift_error(y: f64, shifted: f64) -> f64 {
    if shifted == y {
        return 0.0;
    }
    let turns = ((shifted - y) / std::f64::consts::TAU).round().abs();
    // |fl(2π) − 2π| < 2.5e-16 per turn; the product and the sum rounded.
    intervals::up(2.0 * f64::EPSILON * (shifted.abs() + turns * (std::f64::consts::TAU + 1.0)))
}

/// The measurement `y ± err` as an interval (a point when `err` is 0).
pub(crate) fn measured(y: f64, err: f64) -> Interval {
    if err == 0.0 { Interval::point(y) } else { Interval::centered(y, err) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn branches_shift_and_bound_their_rounding() {
        let y = DVector::from_vec(vec![5.0, -3.1]);
        let mut out = DVector::zeros(2);
        let mut err = [1.0; 2];
        let enclosure = |_| Interval::new(3.0, 3.2);
        let b = branch(&[1], &y, enclosure, &[0.05, 0.05], &mut out, &mut err, 7).unwrap();
        assert_eq!(b, Branch::Chosen);
        assert_eq!(out[0], 5.0);
        assert_eq!(err[0], 0.0);
        // The exact representative 2π − 3.1 lies within err of the shifted value.
        let exact = 2.0 * PI - 3.1;
        assert!((out[1] - exact).abs() <= err[1] && err[1] < 1e-14, "{} {}", out[1], err[1]);
        assert!(measured(out[1], err[1]).contains(out[1]));
        // A reading on no branch of the enclosure contradicts it; a wide one loses the guarantee.
        let far = DVector::from_vec(vec![0.0, 1.0]);
        assert_eq!(branch(&[1], &far, enclosure, &[0.05, 0.05], &mut out, &mut err, 7).unwrap(), Branch::Contradicted);
        let wide = |_| Interval::new(-3.0, 3.0);
        let e = branch(&[1], &far, wide, &[0.5, 0.5], &mut out, &mut err, 7).unwrap_err();
        assert!(matches!(e, EstimatorError::GuaranteeLost { step: 7, .. }), "{e}");
    }
}
