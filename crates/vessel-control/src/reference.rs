//! The set point `y_d(t)` and its first two derivatives, as the controller's Taylor prediction
//! (44)–(49) needs them: a literal step (run A of docs/dp-vessel.md §4, `y_d' = y_d'' = 0`) or
//! the third-order reference filter of §4 (run B, assumed):
//!
//! ```text
//! y_d''' = ω³ (r − y_d) − 3ω² y_d' − 3ω y_d''      (a triple pole at −ω: no overshoot)
//! ```
//!
//! discretised exactly (zero-order hold of the target `r` over each period).

use nalgebra::{DMatrix, Matrix3, Vector3};

use crate::error::{ControlError, check_finite};

/// The reference at one instant: `y_d`, `ẏ_d`, `ÿ_d` for `[x, y, ψ]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceSample {
    /// `y_d`.
    pub y: Vector3<f64>,
    /// `ẏ_d`.
    pub y_dot: Vector3<f64>,
    /// `ÿ_d`.
    pub y_ddot: Vector3<f64>,
}

impl ReferenceSample {
    /// A constant reference `y` (zero derivatives).
    #[must_use]
    pub fn hold(y: Vector3<f64>) -> Self {
        Self { y, y_dot: Vector3::zeros(), y_ddot: Vector3::zeros() }
    }
}

/// The third-order reference filter, the same on each axis, sampled exactly at `δ`.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceFilter {
    omega: f64,
    ad: Matrix3<f64>,
    bd: nalgebra::Vector3<f64>,
    /// Per axis `[y_d, ẏ_d, ÿ_d]` (columns are axes).
    state: Matrix3<f64>,
}

impl ReferenceFilter {
    /// The digest's filter bandwidth `ω = 0.07 rad/s` **\[A\]**.
    pub const DIGEST_OMEGA: f64 = 0.07;

    /// A filter of bandwidth `omega` sampled at `ts`, at rest at `initial`.
    ///
    /// # Errors
    /// [`ControlError::InvalidParameter`] for a non-positive `omega` or `ts`;
    /// [`ControlError::NonFinite`] for `initial`.
    pub fn new(omega: f64, ts: f64, initial: Vector3<f64>) -> Result<Self, ControlError> {
        if !(omega.is_finite() && omega > 0.0) {
            return Err(ControlError::InvalidParameter {
                name: "omega (reference filter bandwidth)",
                value: omega,
                requirement: "positive and finite",
            });
        }
        if !(ts.is_finite() && ts > 0.0) {
            return Err(ControlError::InvalidParameter {
                name: "sampling period",
                value: ts,
                requirement: "positive and finite",
            });
        }
        check_finite("initial reference", initial.as_slice())?;
        let w = omega;
        let a = DMatrix::from_row_slice(3, 3, &[0.0, 1.0, 0.0, 0.0, 0.0, 1.0, -w * w * w, -3.0 * w * w, -3.0 * w]);
        let b = DMatrix::from_row_slice(3, 1, &[0.0, 0.0, w * w * w]);
        let zoh = models::zoh_discretize(&a, &b, ts)?;
        let ad = Matrix3::from_fn(|i, j| zoh.a_p[(i, j)]);
        let bd = Vector3::from_fn(|i, _| zoh.b_p[(i, 0)]);
        let mut state = Matrix3::zeros();
        state.set_row(0, &initial.transpose());
        Ok(Self { omega, ad, bd, state })
    }

    /// The bandwidth `ω`.
    #[must_use]
    pub fn omega(&self) -> f64 {
        self.omega
    }

    /// The current output.
    #[must_use]
    pub fn sample(&self) -> ReferenceSample {
        ReferenceSample {
            y: self.state.row(0).transpose(),
            y_dot: self.state.row(1).transpose(),
            y_ddot: self.state.row(2).transpose(),
        }
    }

    /// Advances one period towards `target` (held over the period).
    pub fn advance(&mut self, target: &Vector3<f64>) {
        self.state = self.ad * self.state + self.bd * target.transpose();
    }
}

/// The set point the controller follows: a literal step to `target`, or `target` through a
/// [`ReferenceFilter`].
#[derive(Debug, Clone, PartialEq)]
pub struct SetPoint {
    target: Vector3<f64>,
    filter: Option<ReferenceFilter>,
}

impl SetPoint {
    /// Run A: `y_d = target` from `t = 0`, `y_d' = y_d'' = 0`.
    ///
    /// # Errors
    /// [`ControlError::NonFinite`] for `target`.
    pub fn step(target: Vector3<f64>) -> Result<Self, ControlError> {
        check_finite("target", target.as_slice())?;
        Ok(Self { target, filter: None })
    }

    /// Run B: `target` through `filter` (which starts where the vessel starts).
    ///
    /// # Errors
    /// [`ControlError::NonFinite`] for `target`.
    pub fn filtered(target: Vector3<f64>, filter: ReferenceFilter) -> Result<Self, ControlError> {
        check_finite("target", target.as_slice())?;
        Ok(Self { target, filter: Some(filter) })
    }

    /// The target.
    #[must_use]
    pub fn target(&self) -> Vector3<f64> {
        self.target
    }

    /// The reference at the current instant.
    #[must_use]
    pub fn current(&self) -> ReferenceSample {
        match &self.filter {
            Some(f) => f.sample(),
            None => ReferenceSample::hold(self.target),
        }
    }

    /// Moves to the next instant.
    pub fn advance(&mut self) {
        if let Some(f) = &mut self.filter {
            f.advance(&self.target);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The step response of a triple pole at −ω: `1 − e^{−ωt}(1 + ωt + (ωt)²/2)`, and its
    /// derivatives `ω e^{−ωt} (ωt)²/2` and `ω² e^{−ωt} (ωt − (ωt)²/2)`.
    #[test]
    fn filter_is_the_exact_triple_pole_step_response() {
        let (w, ts) = (0.07, 0.1);
        let mut f = ReferenceFilter::new(w, ts, Vector3::zeros()).unwrap();
        let target = Vector3::new(50.0, 50.0, 0.0);
        let mut prev = 0.0;
        for k in 0..=3000 {
            let t = k as f64 * ts;
            let s = f.sample();
            let wt = w * t;
            let e = (-wt).exp();
            let y = 50.0 * (1.0 - e * (1.0 + wt + wt * wt / 2.0));
            let yd = 50.0 * w * e * wt * wt / 2.0;
            let ydd = 50.0 * w * w * e * (wt - wt * wt / 2.0);
            assert!(
                (s.y[0] - y).abs() < 1e-9 && (s.y_dot[1] - yd).abs() < 1e-11 && (s.y_ddot[0] - ydd).abs() < 1e-12,
                "t = {t}"
            );
            assert_eq!(s.y[2], 0.0);
            assert!(s.y[0] >= prev - 1e-12 && s.y[0] <= 50.0 + 1e-9, "monotone, no overshoot");
            prev = s.y[0];
            f.advance(&target);
        }
    }

    #[test]
    fn set_points_and_bad_input() {
        let target = Vector3::new(50.0, 50.0, 0.0);
        let mut sp = SetPoint::step(target).unwrap();
        sp.advance();
        assert_eq!(sp.current(), ReferenceSample::hold(target));
        assert!(SetPoint::step(Vector3::new(f64::NAN, 0.0, 0.0)).is_err());
        assert!(ReferenceFilter::new(0.0, 0.1, Vector3::zeros()).is_err());
        assert!(ReferenceFilter::new(0.07, -0.1, Vector3::zeros()).is_err());
        let f = ReferenceFilter::new(0.07, 0.1, Vector3::new(1.0, 2.0, 0.0)).unwrap();
        let sp = SetPoint::filtered(target, f).unwrap();
        assert_eq!(sp.current().y, Vector3::new(1.0, 2.0, 0.0));
    }
}
