//! The data of the two experiments of `docs/bds-ins-fuzzy-kf.md` §3: the paper's simulation (a)
//! (P setup, A details) and the field-test analogue (b) (A).

use nalgebra::{DMatrix, DVector};

use crate::bds::{RtkStatus, Zone};
use crate::model::STATES;
use crate::params::{ARCSEC, DEG_PER_HOUR, GRAVITY};

/// Filter period `T = 1 s` (P).
pub const PAPER_PERIOD: f64 = 1.0;
/// Duration of the simulation, 1200 s (P), i.e. 1200 epochs at 1 Hz.
pub const PAPER_EPOCHS: usize = 1200;
/// The noise increases after this epoch (600 s, P).
pub const PAPER_SWITCH_EPOCH: usize = 600;
/// Vehicle speed, due east \[m/s\] (P).
pub const PAPER_SPEED: f64 = 10.0;
/// Satellites used throughout the simulation (A: "other parameters unchanged").
pub const PAPER_SATELLITES: u32 = 20;
/// Nominal BDS horizontal standard deviation `σ0` \[m\] (A), also the FIS's `d` scale.
pub const SIGMA0: f64 = 0.2;
/// Nominal BDS heading standard deviation \[rad\] (0.2°, A).
pub const HEADING_SIGMA0: f64 = 0.2 * std::f64::consts::PI / 180.0;
/// Scripted FIS distance after 600 s \[m\] (A: the paper's value is lost).
pub const SCRIPTED_D_AFTER: f64 = 0.5;
/// Scripted FIS distance up to 600 s \[m\] (A: well inside `d = PS`).
pub const SCRIPTED_D_BEFORE: f64 = 0.05;

/// The initial standard deviations of (P, §3): position 2 m, velocity 0.1 m/s, platform 20″ each,
/// accelerometer bias 1e−4 g, gyro drift 3 °/h, in state order.
#[must_use]
pub fn initial_sigma() -> [f64; STATES] {
    let (a, g, p) = (1e-4 * GRAVITY, 3.0 * DEG_PER_HOUR, 20.0 * ARCSEC);
    [2.0, 2.0, 0.1, 0.1, p, p, p, a, a, a, g, g, g]
}

/// The truth's initial error state: every entry at its listed value (`+1σ`, as the paper lists
/// them; gyro drift: the constant 3 °/h per axis). The filters start from `X̂0 = 0`.
#[must_use]
pub fn initial_error() -> DVector<f64> {
    DVector::from_row_slice(&initial_sigma())
}

/// `P0 = diag(σ0²)` of [`initial_sigma`].
#[must_use]
pub fn initial_covariance() -> DMatrix<f64> {
    DMatrix::from_diagonal(&DVector::from_iterator(STATES, initial_sigma().iter().map(|s| s * s)))
}

/// The nominal measurement covariance `R0 = diag(0.2², 0.2², (0.2°)²)` (A).
#[must_use]
pub fn nominal_r() -> DMatrix<f64> {
    DMatrix::from_diagonal(&DVector::from_vec(vec![SIGMA0 * SIGMA0, SIGMA0 * SIGMA0, HEADING_SIGMA0 * HEADING_SIGMA0]))
}

/// The two readings of the paper's "noise five times larger after 600 s" (decision 4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum NoiseIncrease {
    /// The variance is five times larger (`σ × √5`): R is the "pre-estimate" (literal reading).
    Variance,
    /// The standard deviation is five times larger (variance × 25).
    StdDev,
}

impl NoiseIncrease {
    /// The factor on the standard deviations.
    #[must_use]
    pub fn sigma_factor(self) -> f64 {
        match self {
            NoiseIncrease::Variance => 5f64.sqrt(),
            NoiseIncrease::StdDev => 5.0,
        }
    }

    /// The factor on the covariance.
    #[must_use]
    pub fn variance_factor(self) -> f64 {
        self.sigma_factor().powi(2)
    }

    /// A short label.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            NoiseIncrease::Variance => "variance ×5",
            NoiseIncrease::StdDev => "std ×5",
        }
    }
}

/// The paper's simulation as two zones: 600 epochs RTK fixed with `R0`, then 600 epochs with
/// `rtk_after` (float, A; also run single) and the noise increased as `increase` says; 20
/// satellites throughout, white noise only.
#[must_use]
pub fn paper_zones(increase: NoiseIncrease, rtk_after: RtkStatus) -> Vec<Zone> {
    let f = increase.sigma_factor();
    vec![
        Zone::white("0–600 s", PAPER_SWITCH_EPOCH, RtkStatus::Fixed, PAPER_SATELLITES, SIGMA0, HEADING_SIGMA0),
        Zone::white(
            "600–1200 s",
            PAPER_EPOCHS - PAPER_SWITCH_EPOCH,
            rtk_after,
            PAPER_SATELLITES,
            f * SIGMA0,
            f * HEADING_SIGMA0,
        ),
    ]
}

/// Correlation time of the field analogue's Gauss–Markov bias \[s\] (A).
pub const FIELD_BIAS_TAU: f64 = 30.0;

/// The field-test analogue (b) route A→B→C→D at 10 m/s, for the occlusion scale `s` \[m\]:
///
/// * open, 300 s: fixed, N = 22, σ = 0.03 m, heading 0.1°;
/// * fully occluded (under a quay crane), 120 s: single, N = 5, white σ = 0.5·s plus a
///   Gauss–Markov bias of σ_b = s (τ = 30 s), heading 0.5°;
/// * half occluded (between container stacks), 180 s: float, N = 10, white σ = 0.25·s plus a bias
///   of σ_b = 0.5·s (τ = 30 s), heading 0.25°.
#[must_use]
pub fn field_zones(s: f64) -> Vec<Zone> {
    let deg = std::f64::consts::PI / 180.0;
    vec![
        Zone::white("open", 300, RtkStatus::Fixed, 22, 0.03, 0.1 * deg),
        Zone {
            bias_sigma: s,
            bias_tau: FIELD_BIAS_TAU,
            ..Zone::white("fully occluded", 120, RtkStatus::Single, 5, 0.5 * s, 0.5 * deg)
        },
        Zone {
            bias_sigma: 0.5 * s,
            bias_tau: FIELD_BIAS_TAU,
            ..Zone::white("half occluded", 180, RtkStatus::Float, 10, 0.25 * s, 0.25 * deg)
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_match_the_note() {
        let s = initial_sigma();
        assert_eq!((s[0], s[2]), (2.0, 0.1));
        assert!((s[4] - 9.696e-5).abs() < 1e-8, "20″ = {} rad", s[4]);
        assert!((s[7] - 9.7803e-4).abs() < 1e-12);
        assert!((s[10] - 1.4544e-5).abs() < 1e-9, "3 °/h = {} rad/s", s[10]);
        assert_eq!(initial_covariance()[(0, 0)], 4.0);
        assert!((nominal_r()[(0, 0)] - 0.04).abs() < 1e-15);
        assert!((NoiseIncrease::Variance.variance_factor() - 5.0).abs() < 1e-12);
        assert_eq!(NoiseIncrease::StdDev.variance_factor(), 25.0);
        let z = paper_zones(NoiseIncrease::Variance, RtkStatus::Float);
        assert_eq!(z.iter().map(|z| z.epochs).sum::<usize>(), PAPER_EPOCHS);
        assert_eq!(field_zones(0.2).iter().map(|z| z.epochs).sum::<usize>(), 600);
    }
}
