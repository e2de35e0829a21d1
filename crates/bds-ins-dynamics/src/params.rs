//! Parameters of the INS error model (10) and of its process noise, validated
//! (`docs/bds-ins-fuzzy-kf.md` §1 and §3).

use models::validate::{finite, non_negative, positive};

use crate::error::BdsInsError;

/// Earth rotation rate `Ω` \[rad/s\] (WGS-84).
pub const EARTH_RATE: f64 = 7.292115e-5;
/// Earth radius `R` \[m\] (WGS-84 equatorial).
pub const EARTH_RADIUS: f64 = 6_378_137.0;
/// Gravity `g` \[m/s²\] (A, the digest's value).
pub const GRAVITY: f64 = 9.7803;
/// The digest's latitude `L = 31° N` (Shanghai; A) \[rad\].
pub const DIGEST_LATITUDE: f64 = 31.0 * std::f64::consts::PI / 180.0;
/// One degree per hour in rad/s.
pub const DEG_PER_HOUR: f64 = std::f64::consts::PI / 180.0 / 3600.0;
/// One arc second in rad.
pub const ARCSEC: f64 = std::f64::consts::PI / 180.0 / 3600.0;
/// The largest |latitude| accepted \[rad\] (89°): the planar model has `tan L`.
pub const MAX_LATITUDE: f64 = 89.0 * std::f64::consts::PI / 180.0;

/// The Earth terms of the error model.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Earth {
    /// A rotating Earth (`Ω` = [`InsParams::earth_rate`], radius [`InsParams::earth_radius`]) at
    /// latitude `L` \[rad\], `|L| ≤ 89°`.
    Rotating {
        /// Latitude `L` \[rad\], north positive.
        latitude: f64,
    },
    /// The "flat" option of the digest: `Ω = 0` and `1/R = 0` (no Earth rate, no Schuler loop);
    /// for tests with closed forms.
    Flat,
}

/// The frame in which the accelerometer biases `∇` and gyro drifts `ε` of the state are
/// constant (the digest's decision 3).
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum BiasFrame {
    /// Constants in the navigation frame E/N/U (the paper's choice, P): state entries 7–12 are
    /// `∇E, ∇N, ∇U, εE, εN, εU`.
    Navigation,
    /// Constants in the body frame (right, forward, up) of a level vehicle whose azimuth (heading
    /// clockwise from north) is `azimuth` \[rad\]: state entries 7–12 are `∇R, ∇F, ∇U, εR, εF, εU`
    /// and enter the model rotated by `C_b^n` (A). A turning route rebuilds the model with the
    /// current azimuth each step.
    Body {
        /// Vehicle azimuth \[rad\], clockwise from north.
        azimuth: f64,
    },
}

/// Parameters of the continuous error model (10): Earth terms, gravity, specific force and bias
/// frame. Plain data; [`InsParams::validate`] (called by [`crate::InsErrorModel::new`]) checks it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InsParams {
    /// Rotating Earth at a latitude, or flat.
    pub earth: Earth,
    /// `Ω` \[rad/s\] (used only with [`Earth::Rotating`]).
    pub earth_rate: f64,
    /// `R` \[m\] (used only with [`Earth::Rotating`]).
    pub earth_radius: f64,
    /// Gravity `g` \[m/s²\]; the vertical specific force `f_U = g`.
    pub gravity: f64,
    /// Horizontal specific force `[f_E, f_N]` \[m/s²\] (zero at constant velocity, the paper's
    /// case).
    pub specific_force: [f64; 2],
    /// Frame of the constant biases.
    pub bias_frame: BiasFrame,
}

impl InsParams {
    /// The digest's parameters: rotating Earth at 31° N, `g = 9.7803 m/s²`, constant velocity
    /// (`f_E = f_N = 0`), biases constant in the navigation frame.
    #[must_use]
    pub fn digest() -> Self {
        Self {
            earth: Earth::Rotating { latitude: DIGEST_LATITUDE },
            earth_rate: EARTH_RATE,
            earth_radius: EARTH_RADIUS,
            gravity: GRAVITY,
            specific_force: [0.0, 0.0],
            bias_frame: BiasFrame::Navigation,
        }
    }

    /// The digest's parameters with the flat option (`Ω = 0`, `1/R = 0`).
    #[must_use]
    pub fn flat() -> Self {
        Self { earth: Earth::Flat, ..Self::digest() }
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`BdsInsError`] naming the parameter: a non-finite value, a non-positive `g`, `Ω` < 0 or
    /// `R` ≤ 0 (rotating Earth), `|L|` above 89°.
    pub fn validate(&self) -> Result<(), BdsInsError> {
        positive("g (gravity)", self.gravity)?;
        finite("f_E (east specific force)", self.specific_force[0])?;
        finite("f_N (north specific force)", self.specific_force[1])?;
        if let Earth::Rotating { latitude } = self.earth {
            finite("L (latitude)", latitude)?;
            if latitude.abs() > MAX_LATITUDE {
                return Err(BdsInsError::OutOfRange {
                    name: "L (latitude, rad)",
                    value: latitude,
                    lo: -MAX_LATITUDE,
                    hi: MAX_LATITUDE,
                });
            }
            non_negative("Ω (Earth rate)", self.earth_rate)?;
            positive("R (Earth radius)", self.earth_radius)?;
        }
        if let BiasFrame::Body { azimuth } = self.bias_frame {
            finite("ψ (vehicle azimuth of the body-frame biases)", azimuth)?;
        }
        Ok(())
    }

    /// `(Ω sin L, Ω cos L, tan L / R, 1 / R)`: zero for the flat option.
    #[must_use]
    pub(crate) fn earth_terms(&self) -> (f64, f64, f64, f64) {
        match self.earth {
            Earth::Rotating { latitude } => {
                let (s, c) = latitude.sin_cos();
                (self.earth_rate * s, self.earth_rate * c, latitude.tan() / self.earth_radius, 1.0 / self.earth_radius)
            }
            Earth::Flat => (0.0, 0.0, 0.0, 0.0),
        }
    }

    /// The horizontal 2 × 2 block of `C_b^n` for the biases: identity in the navigation frame;
    /// `[[cos ψ, sin ψ], [−sin ψ, cos ψ]]` (columns: body right and forward axes in E/N) for
    /// body-frame biases.
    #[must_use]
    pub(crate) fn bias_rotation(&self) -> [[f64; 2]; 2] {
        match self.bias_frame {
            BiasFrame::Navigation => [[1.0, 0.0], [0.0, 1.0]],
            BiasFrame::Body { azimuth } => {
                let (s, c) = azimuth.sin_cos();
                [[c, s], [-s, c]]
            }
        }
    }
}

/// White-noise intensities of the IMU and, optionally, a random walk of the biases.
///
/// The digest's biases are random constants (`∇' = 0`, `ε' = 0`), so their rows of the discrete
/// `Q_k` are zero and `Q_k` is only positive semidefinite. A Kalman filter that requires a
/// positive definite `Q` gets it from a tiny bias random walk ([`InsNoise::with_bias_walk`]);
/// the simulated truth keeps exact constants.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InsNoise {
    /// Accelerometer white noise `σa` \[m/s²/√Hz\] on `w_aE`, `w_aN`.
    pub accel_white: f64,
    /// Gyro white noise `σg` \[rad/s/√Hz\] on `w_gE`, `w_gN`, `w_gU`.
    pub gyro_white: f64,
    /// Random walk of each accelerometer bias \[m/s²/√s\] (0: constants).
    pub accel_bias_walk: f64,
    /// Random walk of each gyro drift \[rad/s/√s\] (0: constants).
    pub gyro_bias_walk: f64,
}

impl InsNoise {
    /// The digest's assumed intensities: `σa = 1e−4 g` (≈ 100 µg/√Hz), `σg = 3 °/h·√s`
    /// (ARW 0.05 °/√h), biases constant.
    #[must_use]
    pub fn digest() -> Self {
        Self { accel_white: 1e-4 * GRAVITY, gyro_white: 3.0 * DEG_PER_HOUR, accel_bias_walk: 0.0, gyro_bias_walk: 0.0 }
    }

    /// The same intensities with bias random walks (see the type's documentation).
    #[must_use]
    pub fn with_bias_walk(self, accel_bias_walk: f64, gyro_bias_walk: f64) -> Self {
        Self { accel_bias_walk, gyro_bias_walk, ..self }
    }

    /// The digest's intensities with the bias walk the reproduction gives its filters so that `Q`
    /// is positive definite: `1e−9 m/s²/√s` and `1e−11 rad/s/√s`, whose effect over 1200 s
    /// (`3.5e−8 m/s²`, `3.5e−10 rad/s`) is 4–5 orders below the biases themselves.
    #[must_use]
    pub fn digest_filter() -> Self {
        Self::digest().with_bias_walk(1e-9, 1e-11)
    }

    /// Checks that every intensity is finite and non-negative.
    ///
    /// # Errors
    /// [`BdsInsError`] naming the intensity.
    pub fn validate(&self) -> Result<(), BdsInsError> {
        non_negative("σa (accelerometer white noise)", self.accel_white)?;
        non_negative("σg (gyro white noise)", self.gyro_white)?;
        non_negative("accelerometer bias random walk", self.accel_bias_walk)?;
        non_negative("gyro bias random walk", self.gyro_bias_walk)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use models::validate::ParamError;

    #[test]
    fn presets_are_valid_and_bad_values_are_named() {
        InsParams::digest().validate().unwrap();
        InsParams::flat().validate().unwrap();
        InsNoise::digest().validate().unwrap();
        InsNoise::digest_filter().validate().unwrap();
        let e = InsParams { gravity: 0.0, ..InsParams::digest() }.validate().unwrap_err();
        assert_eq!(e.to_string(), "parameter g (gravity) must be positive, got 0");
        let e = InsParams { earth: Earth::Rotating { latitude: 1.56 }, ..InsParams::digest() }.validate().unwrap_err();
        assert!(matches!(e, BdsInsError::OutOfRange { .. }), "{e}");
        let e = InsParams { earth: Earth::Rotating { latitude: f64::NAN }, ..InsParams::digest() }.validate();
        assert!(matches!(e, Err(BdsInsError::Parameter(ParamError::NonFinite { .. }))));
        let e = InsParams { bias_frame: BiasFrame::Body { azimuth: f64::INFINITY }, ..InsParams::digest() }.validate();
        assert!(e.is_err());
        // The flat option ignores the Earth constants.
        InsParams { earth_radius: -1.0, ..InsParams::flat() }.validate().unwrap();
        assert!(InsNoise { gyro_white: -1.0, ..InsNoise::digest() }.validate().is_err());
        assert_eq!(InsParams::flat().earth_terms(), (0.0, 0.0, 0.0, 0.0));
    }
}
