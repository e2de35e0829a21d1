//! The data of the paper's experiment that belong to the vehicle: sampling period, initial
//! state, noise boxes `W`, `V` (eqs (6), (7), (11)) and the double-lane-change manoeuvre that
//! replaces the paper's CarSim truth (`docs/robust-mhe.md` §1, §3). Estimator settings (`P_0`,
//! `Q`, `R`, `α`, `N`) belong to the estimator, not to this crate.

use nalgebra::{DVector, Vector4};

use crate::error::CarError;
use crate::model::STATE_DIM;
use models::{ModelError, Noise};

/// The paper's sampling period `T_s = 0.5 s` (P).
pub const DIGEST_SAMPLING_PERIOD: f64 = 0.5;

/// The paper's true initial state `x(0) = [Y, φ, β, r] = [−2, 0, 0, 0]` (P; `Y_0 = −2 m`).
pub const DIGEST_INITIAL_STATE: [f64; STATE_DIM] = [-2.0, 0.0, 0.0, 0.0];

/// Number of sampling periods of the run: 20 s at 0.5 s, states `k = 0..=40` (A).
pub const DIGEST_STEPS: usize = 40;

/// Amplitude of the double lane change's steering sine \[rad\] (A).
pub const DOUBLE_LANE_CHANGE_AMPLITUDE: f64 = 0.0081;

/// The unknown-but-bounded noise sets of eqs (6), (7), (11) as boxes: `w ∈ W`, `v ∈ V`.
///
/// The paper gives no state constraint set `X`, so there is none (A).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoiseBounds {
    /// Half-widths of the process-noise box `W = Π [−w̄_i, w̄_i]`, in state order `[Y, φ, β, r]`
    /// (m, rad, rad, rad/s).
    pub process_half_widths: [f64; STATE_DIM],
    /// Half-width `v̄` of the measurement-noise interval `V = [−v̄, v̄]` \[m\].
    pub measurement_half_width: f64,
}

impl NoiseBounds {
    /// The paper's sets (P): `W = [−0.1, 0.1]⁴`, `V = [−1, 1]`.
    #[must_use]
    pub fn digest() -> Self {
        Self { process_half_widths: [0.1; STATE_DIM], measurement_half_width: 1.0 }
    }

    /// The half-widths of `W` as a vector.
    #[must_use]
    pub fn process_vector(&self) -> Vector4<f64> {
        Vector4::from(self.process_half_widths)
    }

    /// Whether `w` lies in the closed box `W` (`false` for NaN entries).
    #[must_use]
    pub fn process_contains(&self, w: &Vector4<f64>) -> bool {
        w.iter().zip(&self.process_half_widths).all(|(wi, h)| wi.abs() <= *h)
    }

    /// Whether `v` lies in the closed interval `V` (`false` for NaN).
    #[must_use]
    pub fn measurement_contains(&self, v: f64) -> bool {
        v.abs() <= self.measurement_half_width
    }

    /// I.i.d. uniform process noise on `W` (the paper's case (a): `w_k ~ U(W)`), for
    /// `models::simulate_ltv`.
    ///
    /// # Errors
    /// [`CarError::Model`]`(`[`ModelError::InvalidHalfWidth`]`)` for a negative or non-finite
    /// half-width.
    pub fn process_noise(&self) -> Result<Noise, CarError> {
        Ok(Noise::uniform_box(DVector::from_row_slice(&self.process_half_widths))?)
    }

    /// I.i.d. uniform measurement noise on `V` (`v_k ~ U[−1, 1]` for the paper's set).
    ///
    /// # Errors
    /// As [`NoiseBounds::process_noise`].
    pub fn measurement_noise(&self) -> Result<Noise, CarError> {
        Ok(Noise::uniform_box(DVector::from_element(1, self.measurement_half_width))?)
    }
}

/// Front steering angle `δ_f(t)` \[rad\] of the double lane change (A; the paper's truth came
/// from CarSim and an MPC-planned path, both unavailable):
///
/// ```text
/// δ_f(t) =  0.0081 sin(2π (t − 2)/4)     for 2 ≤ t < 6 s
/// δ_f(t) = −0.0081 sin(2π (t − 10)/4)    for 10 ≤ t < 14 s
/// δ_f(t) =  0                            otherwise
/// ```
///
/// On the linear ZOH model at 0.5 s this moves `Y` from −2 m to about +2 m and back (V).
/// A NaN time gives NaN; infinite times give 0.
#[must_use]
pub fn double_lane_change(t: f64) -> f64 {
    let period = 4.0;
    let phase = |t0: f64| 2.0 * std::f64::consts::PI * (t - t0) / period;
    if t.is_nan() {
        f64::NAN
    } else if (2.0..6.0).contains(&t) {
        DOUBLE_LANE_CHANGE_AMPLITUDE * phase(2.0).sin()
    } else if (10.0..14.0).contains(&t) {
        -DOUBLE_LANE_CHANGE_AMPLITUDE * phase(10.0).sin()
    } else {
        0.0
    }
}

/// The zero-order-hold inputs `u_k = [δ_f(k T_s)]`, `k = 0..steps`, of the double lane change,
/// ready for `models::SimulationConfig::inputs` (`steps` inputs give `steps + 1` states).
///
/// # Errors
/// [`CarError::Model`]`(`[`ModelError::InvalidSamplingPeriod`]`)` unless `ts` is positive and
/// finite.
pub fn double_lane_change_inputs(ts: f64, steps: usize) -> Result<Vec<DVector<f64>>, CarError> {
    if !(ts.is_finite() && ts > 0.0) {
        return Err(ModelError::InvalidSamplingPeriod(ts).into());
    }
    Ok((0..steps).map(|k| DVector::from_element(1, double_lane_change(k as f64 * ts))).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use models::{NoiseDistribution, Xoshiro256StarStar};

    #[test]
    fn double_lane_change_has_the_digest_shape() {
        let a = DOUBLE_LANE_CHANGE_AMPLITUDE;
        for t in [-1.0, 0.0, 1.99, 6.0, 8.0, 9.99, 14.0, 20.0, f64::INFINITY, f64::NEG_INFINITY] {
            assert_eq!(double_lane_change(t), 0.0, "t = {t}");
        }
        assert!(double_lane_change(f64::NAN).is_nan());
        // Peaks a quarter and three quarters into each 4 s window.
        assert!((double_lane_change(3.0) - a).abs() < 1e-15);
        assert!((double_lane_change(5.0) + a).abs() < 1e-15);
        assert!((double_lane_change(11.0) + a).abs() < 1e-15);
        assert!((double_lane_change(13.0) - a).abs() < 1e-15);
        // Continuous at the window edges; the second change mirrors the first.
        assert!(double_lane_change(2.0).abs() < 1e-15 && double_lane_change(5.999_999).abs() < 1e-7);
        for i in 0..=40 {
            let t = 2.0 + 0.1 * f64::from(i);
            assert!((double_lane_change(t) + double_lane_change(t + 8.0)).abs() < 1e-15, "t = {t}");
        }
    }

    #[test]
    fn sampled_inputs_hold_the_value_at_the_sample_start() {
        let u = double_lane_change_inputs(DIGEST_SAMPLING_PERIOD, DIGEST_STEPS).unwrap();
        assert_eq!(u.len(), 40);
        assert!(u.iter().all(|v| v.len() == 1));
        assert_eq!(u[6][0], double_lane_change(3.0));
        assert!((u[6][0] - DOUBLE_LANE_CHANGE_AMPLITUDE).abs() < 1e-15);
        // Non-zero only inside the two windows: k = 5..=11 and 21..=27 (sin(0) = 0 at k = 4, 20).
        let nonzero: Vec<usize> = (0..40).filter(|&k| u[k][0].abs() > 1e-12).collect();
        let want: Vec<usize> = (5..=11).filter(|&k| k != 8).chain((21..=27).filter(|&k| k != 24)).collect();
        assert_eq!(nonzero, want);
        for ts in [0.0, -0.5, f64::NAN] {
            assert!(matches!(
                double_lane_change_inputs(ts, 3),
                Err(CarError::Model(ModelError::InvalidSamplingPeriod(_)))
            ));
        }
    }

    #[test]
    fn digest_noise_boxes() {
        let bounds = NoiseBounds::digest();
        assert_eq!(bounds.process_vector(), Vector4::from_element(0.1));
        assert_eq!(bounds.measurement_half_width, 1.0);
        let w = bounds.process_noise().unwrap();
        let v = bounds.measurement_noise().unwrap();
        assert_eq!((w.dim(), v.dim()), (4, 1));
        assert_eq!(w.distribution(), NoiseDistribution::UniformBox);
        let mut rng = Xoshiro256StarStar::seed_from_u64(3);
        for _ in 0..1000 {
            let s = w.sample(&mut rng);
            assert!(bounds.process_contains(&Vector4::new(s[0], s[1], s[2], s[3])));
            assert!(bounds.measurement_contains(v.sample(&mut rng)[0]));
        }
        assert!(bounds.measurement_contains(-1.0) && !bounds.measurement_contains(1.0 + 1e-12));
        assert!(!bounds.measurement_contains(f64::NAN));
        assert!(!bounds.process_contains(&Vector4::new(0.0, 0.0, 0.1001, 0.0)));
        let bad = NoiseBounds { process_half_widths: [0.1, -0.1, 0.1, 0.1], ..bounds };
        assert_eq!(
            bad.process_noise().unwrap_err(),
            CarError::Model(ModelError::InvalidHalfWidth { index: 1, value: -0.1 })
        );
        let bad = NoiseBounds { measurement_half_width: f64::NAN, ..bounds };
        assert!(bad.measurement_noise().is_err());
    }
}
