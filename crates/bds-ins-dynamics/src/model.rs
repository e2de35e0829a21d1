//! The 13-state planar INS error model (10) (R: local-level φ-angle model), its exact
//! discretisation (1) and the measurement (11), (13) of INS − BDS differences
//! (`docs/bds-ins-fuzzy-kf.md` §1).
//!
//! State, in the paper's order (0-based indices, [`idx`]):
//!
//! ```text
//! X = [δx (E, m), δy (N, m), δvE, δvN, δψ, δθx, δθy, ∇E, ∇N, ∇U, εE, εN, εU]
//! ```
//!
//! with `δθx = φE`, `δθy = φN`, `δψ = φU` (the azimuth heading error). Continuous model (10):
//!
//! ```text
//! δx'  = δvE                       δy' = δvN
//! δvE' =  2Ω sinL δvN − g δθy + fN δψ + ∇E + w_aE
//! δvN' = −2Ω sinL δvE + g δθx − fE δψ + ∇N + w_aN
//! δθx' = −δvN/R + Ω sinL δθy − Ω cosL δψ − εE − w_gE
//! δθy' =  δvE/R − Ω sinL δθx − εN − w_gN
//! δψ'  =  tanL δvE/R + Ω cosL δθx − εU − w_gU
//! ∇' = 0 (+ walk),   ε' = 0 (+ walk)
//! ```
//!
//! Discretisation (1): `Φ = e^{F T}`, `Q_k = ∫₀ᵀ e^{Fτ} G q Gᵀ e^{Fᵀτ} dτ` by Van Loan's method
//! ([`models::van_loan`], exact). Measurement (13):
//! `z = [x_INS − x_BDS, y_INS − y_BDS, wrap(ψ_INS − ψ_BDS)] = H X + V` with the explicit
//! `H[0][0] = H[1][1] = H[2][4] = 1` (the paper's `[I₃ O₁₀]` is dimensionally inconsistent and
//! would pick `δvE`).

use nalgebra::{DMatrix, DVector};

use models::LinearModel;

use crate::error::BdsInsError;
use crate::params::{InsNoise, InsParams};

/// Number of states `n = 13`.
pub const STATES: usize = 13;
/// Number of measurements `m = 3` (east, north, heading differences).
pub const MEASUREMENTS: usize = 3;
/// Number of white-noise inputs of `G`: `[w_aE, w_aN, w_gE, w_gN, w_gU]` and the six bias walks.
pub const NOISE_INPUTS: usize = 11;

/// 0-based indices of the state entries, in the paper's order.
pub mod idx {
    /// East position error `δx` \[m\].
    pub const DX: usize = 0;
    /// North position error `δy` \[m\].
    pub const DY: usize = 1;
    /// East velocity error `δvE` \[m/s\].
    pub const DVE: usize = 2;
    /// North velocity error `δvN` \[m/s\].
    pub const DVN: usize = 3;
    /// Azimuth heading error `δψ = φU` \[rad\].
    pub const DPSI: usize = 4;
    /// East tilt `δθx = φE` \[rad\].
    pub const DTHX: usize = 5;
    /// North tilt `δθy = φN` \[rad\].
    pub const DTHY: usize = 6;
    /// Accelerometer bias, east (or body right) \[m/s²\].
    pub const ACC_E: usize = 7;
    /// Accelerometer bias, north (or body forward) \[m/s²\].
    pub const ACC_N: usize = 8;
    /// Accelerometer bias, up \[m/s²\]: drives nothing in the planar model (unobservable).
    pub const ACC_U: usize = 9;
    /// Gyro drift, east (or body right) \[rad/s\].
    pub const GYRO_E: usize = 10;
    /// Gyro drift, north (or body forward) \[rad/s\].
    pub const GYRO_N: usize = 11;
    /// Gyro drift, up \[rad/s\].
    pub const GYRO_U: usize = 12;
}

/// Short names of the state entries (file headers, reports).
pub const STATE_NAMES: [&str; STATES] =
    ["dx", "dy", "dvE", "dvN", "dpsi", "dthx", "dthy", "accE", "accN", "accU", "gyroE", "gyroN", "gyroU"];

/// The continuous INS error model (10) with its process noise: validated parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InsErrorModel {
    params: InsParams,
    noise: InsNoise,
}

impl InsErrorModel {
    /// Validates `params` and `noise`.
    ///
    /// # Errors
    /// [`BdsInsError`] naming the offending parameter.
    pub fn new(params: InsParams, noise: InsNoise) -> Result<Self, BdsInsError> {
        params.validate()?;
        noise.validate()?;
        Ok(Self { params, noise })
    }

    /// The model's parameters.
    #[must_use]
    pub fn params(&self) -> &InsParams {
        &self.params
    }

    /// The model's noise intensities.
    #[must_use]
    pub fn noise(&self) -> &InsNoise {
        &self.noise
    }

    /// The continuous system matrix `F` (13 × 13) of (10).
    #[must_use]
    pub fn system_matrix(&self) -> DMatrix<f64> {
        use idx::*;
        let p = &self.params;
        let (ws, wc, tan_over_r, inv_r) = p.earth_terms();
        let g = p.gravity;
        let [fe, fn_] = p.specific_force;
        let c = p.bias_rotation();
        let mut f = DMatrix::zeros(STATES, STATES);
        f[(DX, DVE)] = 1.0;
        f[(DY, DVN)] = 1.0;
        // δvE' = 2Ω sinL δvN − g δθy + fN δψ + ∇E
        f[(DVE, DVN)] = 2.0 * ws;
        f[(DVE, DTHY)] = -g;
        f[(DVE, DPSI)] = fn_;
        // δvN' = −2Ω sinL δvE + g δθx − fE δψ + ∇N
        f[(DVN, DVE)] = -2.0 * ws;
        f[(DVN, DTHX)] = g;
        f[(DVN, DPSI)] = -fe;
        // δθx' = −δvN/R + Ω sinL δθy − Ω cosL δψ − εE
        f[(DTHX, DVN)] = -inv_r;
        f[(DTHX, DTHY)] = ws;
        f[(DTHX, DPSI)] = -wc;
        // δθy' = δvE/R − Ω sinL δθx − εN
        f[(DTHY, DVE)] = inv_r;
        f[(DTHY, DTHX)] = -ws;
        // δψ' = tanL δvE/R + Ω cosL δθx − εU
        f[(DPSI, DVE)] = tan_over_r;
        f[(DPSI, DTHX)] = wc;
        // Biases (rotated by C_b^n for body-frame biases; ∇U and εU are vertical either way).
        for i in 0..2 {
            for j in 0..2 {
                f[(DVE + i, ACC_E + j)] = c[i][j];
                f[(DTHX + i, GYRO_E + j)] = -c[i][j];
            }
        }
        f[(DPSI, GYRO_U)] = -1.0;
        f
    }

    /// The noise input matrix `G` (13 × 11) for `[w_aE, w_aN, w_gE, w_gN, w_gU]` followed by the
    /// random walks of `∇E, ∇N, ∇U, εE, εN, εU`.
    #[must_use]
    pub fn noise_input(&self) -> DMatrix<f64> {
        use idx::*;
        let mut g = DMatrix::zeros(STATES, NOISE_INPUTS);
        g[(DVE, 0)] = 1.0;
        g[(DVN, 1)] = 1.0;
        g[(DTHX, 2)] = -1.0;
        g[(DTHY, 3)] = -1.0;
        g[(DPSI, 4)] = -1.0;
        for k in 0..6 {
            g[(ACC_E + k, 5 + k)] = 1.0;
        }
        g
    }

    /// The white-noise intensity `q` (11 × 11, diagonal): `σa²` ×2, `σg²` ×3, then the squared
    /// bias walks.
    #[must_use]
    pub fn noise_intensity(&self) -> DMatrix<f64> {
        let n = &self.noise;
        let (a, w, ab, gb) =
            (n.accel_white.powi(2), n.gyro_white.powi(2), n.accel_bias_walk.powi(2), n.gyro_bias_walk.powi(2));
        DMatrix::from_diagonal(&DVector::from_vec(vec![a, a, w, w, w, ab, ab, ab, gb, gb, gb]))
    }

    /// Exact discretisation (1) at period `ts`: `Φ = e^{F T}` and Van Loan's `Q_k`.
    ///
    /// # Errors
    /// [`BdsInsError::Model`] for a period that is not positive and finite (or an exponential
    /// failure, which finite validated parameters do not cause).
    pub fn discretize(&self, ts: f64) -> Result<DiscreteInsModel, BdsInsError> {
        let (phi, q) = models::van_loan(&self.system_matrix(), &self.noise_input(), &self.noise_intensity(), ts)?;
        Ok(DiscreteInsModel { phi, q, b: DMatrix::zeros(STATES, 0), h: measurement_matrix(), ts })
    }
}

/// The measurement matrix `H` (3 × 13) of (13): `H[0][0] = H[1][1] = H[2][4] = 1` (0-based),
/// so `z = [δx, δy, δψ] + V`.
#[must_use]
pub fn measurement_matrix() -> DMatrix<f64> {
    let mut h = DMatrix::zeros(MEASUREMENTS, STATES);
    h[(0, idx::DX)] = 1.0;
    h[(1, idx::DY)] = 1.0;
    h[(2, idx::DPSI)] = 1.0;
    h
}

/// The discrete model `X_k = Φ X_{k−1} + W`, `Z = H X + V` at one period: a
/// [`models::LinearModel`] with no input (`B` is 13 × 0), so the workspace's Kalman filters and
/// simulator take it.
#[derive(Debug, Clone, PartialEq)]
pub struct DiscreteInsModel {
    /// `Φ = e^{F T}`.
    pub phi: DMatrix<f64>,
    /// `Q_k` (symmetric; positive semidefinite, positive definite with bias walks).
    pub q: DMatrix<f64>,
    /// `B` (13 × 0: the error model has no input).
    pub b: DMatrix<f64>,
    /// `H` of [`measurement_matrix`].
    pub h: DMatrix<f64>,
    /// The period `T` \[s\].
    pub ts: f64,
}

impl LinearModel for DiscreteInsModel {
    fn a(&self) -> &DMatrix<f64> {
        &self.phi
    }
    fn b(&self) -> &DMatrix<f64> {
        &self.b
    }
    fn c(&self) -> &DMatrix<f64> {
        &self.h
    }
}

pub use models::wrap_angle;

/// The measurement (13) from the INS and BDS solutions `[x_E (m), y_N (m), ψ (rad, azimuth)]`:
/// `[x_INS − x_BDS, y_INS − y_BDS, wrap(ψ_INS − ψ_BDS)]`.
#[must_use]
pub fn measurement(ins: [f64; 3], bds: [f64; 3]) -> [f64; 3] {
    [ins[0] - bds[0], ins[1] - bds[1], wrap_angle(ins[2] - bds[2])]
}

/// Output correction (the INS is never reset, P): `x̂ = x_INS − δx̂`, `ŷ = y_INS − δŷ`,
/// `ψ̂ = wrap(ψ_INS − δψ̂)` from an error-state estimate (length 13).
///
/// # Errors
/// [`BdsInsError::DimensionMismatch`] unless the estimate has 13 entries.
pub fn correct(ins: [f64; 3], error_estimate: &DVector<f64>) -> Result<[f64; 3], BdsInsError> {
    if error_estimate.len() != STATES {
        return Err(BdsInsError::DimensionMismatch {
            what: "error-state estimate",
            expected: STATES,
            found: error_estimate.len(),
        });
    }
    Ok([
        ins[0] - error_estimate[idx::DX],
        ins[1] - error_estimate[idx::DY],
        wrap_angle(ins[2] - error_estimate[idx::DPSI]),
    ])
}

impl models::AnyModel for DiscreteInsModel {
    fn discrete(&self) -> &dyn models::DiscreteModel {
        self
    }
    fn differentiable(&self) -> Option<&dyn models::DifferentiableModel> {
        Some(self)
    }
    fn linear(&self) -> Option<&dyn models::LinearModel> {
        Some(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn headings_wrap_to_the_half_open_interval() {
        assert_eq!(wrap_angle(PI), PI);
        assert_eq!(wrap_angle(-PI), PI);
        assert_eq!(wrap_angle(3.0 * PI), PI);
        assert!((wrap_angle(-3.0 * PI / 2.0) - PI / 2.0).abs() < 1e-15);
        assert!((wrap_angle(0.1 + 4.0 * PI) - 0.1).abs() < 1e-14);
        assert_eq!(wrap_angle(0.0), 0.0);
        assert!(wrap_angle(f64::NAN).is_nan());
        for k in -1000..=1000 {
            let a = k as f64 * 0.0137;
            let w = wrap_angle(a);
            assert!(w > -PI && w <= PI, "{a} → {w}");
            assert!(((a - w) / (2.0 * PI) - ((a - w) / (2.0 * PI)).round()).abs() < 1e-9);
        }
        // Across the ±180° seam the difference is the short way round.
        let z = measurement([0.0, 0.0, 179.9_f64.to_radians()], [0.0, 0.0, (-179.9_f64).to_radians()]);
        assert!((z[2] - (-0.2_f64).to_radians()).abs() < 1e-12, "{}", z[2].to_degrees());
    }

    #[test]
    fn output_correction_subtracts_the_estimated_errors() {
        let mut e = DVector::zeros(STATES);
        e[idx::DX] = 1.5;
        e[idx::DY] = -0.5;
        e[idx::DPSI] = 0.2;
        let c = correct([10.0, 20.0, -PI + 0.1], &e).unwrap();
        assert_eq!((c[0], c[1]), (8.5, 20.5));
        assert!((c[2] - (PI - 0.1)).abs() < 1e-12);
        assert!(correct([0.0; 3], &DVector::zeros(12)).is_err());
    }
}
