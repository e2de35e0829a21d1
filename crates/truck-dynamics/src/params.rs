//! All parameters of the truck (body, tyres, and the truth model's extras) in one validated
//! struct (digest §4, §5).

use models::validate::{non_negative, positive};

use crate::error::TruckError;
use crate::tyre::Pac89Tyre;

/// Parameters of the three-axle port container truck (6×4: axle 1 steered, axles 2–3 driven
/// with dual tyres), for both the estimator's model ([`crate::PlanarTruck`]) and the truth
/// model ([`crate::TruthModel`]).
///
/// Plain data; [`TruckParams::validate`] (called by the models' constructors) checks it. The
/// fields marked *truth only* are ignored by the estimator's model, which keeps the paper's
/// simpler model (static loads, no relaxation, no drag).
///
/// Every value of [`TruckParams::digest_preset`] is an **assumption \[A\]** or
/// **reconstruction \[R\]** of the digest: the paper's Table 1 is lost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruckParams {
    /// Mass `m` \[kg\].
    pub mass: f64,
    /// Yaw inertia `I_z` about the CG \[kg m²\].
    pub yaw_inertia: f64,
    /// `[a, b, c]`: distances from the CG to axle 1 (ahead) and axles 2, 3 (behind) \[m\];
    /// wheel positions are `x_j = (a, a, −b, −b, −c, −c)`.
    pub axle_distances: [f64; 3],
    /// Tracks `[T1, T2, T3]` of axles 1–3 \[m\]; `y_j = ±T_i/2` (left positive).
    pub tracks: [f64; 3],
    /// Effective rolling radius `R_e` \[m\].
    pub rolling_radius: f64,
    /// Tyres per wheel position on axles 1–3 (`[1, 2, 2]`: single front, dual rear); a position
    /// with `n` tyres gives `n·F(F_z/n)` (digest decision 3).
    pub tyres_per_position: [u32; 3],
    /// Gravitational acceleration `g` \[m/s²\].
    pub gravity: f64,
    /// The tyre (coefficients, load clamp, friction scale).
    pub tyre: Pac89Tyre,
    /// Low-speed guard `v_min` \[m/s\] of the slip denominators (digest §6.6: 0.1 m/s):
    /// `s = (ωR_e − v_l)/max(|ωR_e|, |v_l|, v_min)`, and `u² + v²` is floored at `v_min²` in
    /// `∂α/∂x`.
    pub min_speed: f64,
    /// *Truth only.* CG height `h_cg` for quasi-static load transfer \[m\] (0 disables it).
    pub cg_height: f64,
    /// *Truth only.* Lateral relaxation length `σ_α` \[m\].
    pub relaxation_length: f64,
    /// *Truth only.* Spin inertia `J_w` of one tyre with its wheel \[kg m²\]; a position with
    /// `n` tyres has `n·J_w`.
    pub wheel_inertia: f64,
    /// *Truth only.* Rolling-resistance coefficient `f_r` (torque `f_r·F_z·R_e` on each wheel).
    pub rolling_resistance: f64,
    /// *Truth only.* Drag area `C_d·A` \[m²\].
    pub drag_area: f64,
    /// *Truth only.* Air density `ρ` \[kg/m³\].
    pub air_density: f64,
    /// *Truth only.* Proportional gain of the speed controller \[N m per m/s\] (total drive
    /// torque on axles 2–3).
    pub speed_kp: f64,
    /// *Truth only.* Integral gain of the speed controller \[N m per m\].
    pub speed_ki: f64,
}

const AXLE_NAMES: [&str; 3] = ["a (CG to axle 1 distance)", "b (CG to axle 2 distance)", "c (CG to axle 3 distance)"];
const TRACK_NAMES: [&str; 3] = ["T1 (track of axle 1)", "T2 (track of axle 2)", "T3 (track of axle 3)"];
const TYRE_COUNT_NAMES: [&str; 3] = [
    "n1 (tyres per wheel position, axle 1)",
    "n2 (tyres per wheel position, axle 2)",
    "n3 (tyres per wheel position, axle 3)",
];

impl TruckParams {
    /// The digest's vehicle (§4, §5). **Assumed \[A\]**: `m = 25 000 kg` (laden 6×4 rigid),
    /// `I_z = 1.5·10⁵ kg m²`, `a, b, c = 3.5, 0.6, 1.95 m`, `T1 = 2.04 m`, `T2 = T3 = 1.83 m`,
    /// `R_e = 0.52 m`, tyres `[1, 2, 2]`, `g = 9.81`, `v_min = 0.1 m/s`, `h_cg = 1.4 m`,
    /// `J_w = 14 kg m²`, `C_d·A = 5 m²`, `ρ = 1.2 kg/m³` (this crate's choice; the digest gives no
    /// `ρ`), speed PI `k_p = 2·m·R_e·ω_n`, `k_i = m·R_e·ω_n²` with `ω_n = 1 rad/s` (a critically
    /// damped speed loop; this crate's choice). **Reconstructed \[R\]** from the tyre file:
    /// the tyre ([`Pac89Tyre::truck`]), `σ_α = 0.65 m` (`PTY1·R_0`), `f_r = 0.008` (`QSY1`).
    #[must_use]
    pub fn digest_preset() -> Self {
        let (mass, re, wn) = (25_000.0, 0.52, 1.0);
        Self {
            mass,
            yaw_inertia: 1.5e5,
            axle_distances: [3.5, 0.6, 1.95],
            tracks: [2.04, 1.83, 1.83],
            rolling_radius: re,
            tyres_per_position: [1, 2, 2],
            gravity: 9.81,
            tyre: Pac89Tyre::truck(),
            min_speed: 0.1,
            cg_height: 1.4,
            relaxation_length: 0.65,
            wheel_inertia: 14.0,
            rolling_resistance: 0.008,
            drag_area: 5.0,
            air_density: 1.2,
            speed_kp: 2.0 * mass * re * wn,
            speed_ki: mass * re * wn * wn,
        }
    }

    /// Distance from axle 1 to the centre of the rear tandem, `L = a + (b + c)/2` \[m\].
    #[must_use]
    pub fn tandem_wheelbase(&self) -> f64 {
        let [a, b, c] = self.axle_distances;
        a + 0.5 * (b + c)
    }

    /// Static axle loads `[W1, W2, W3]` \[N\], with the rear tandem equalised **\[A\]** (a
    /// walking-beam / equalising suspension): `W1 = m·g·(b + c)/2/L`, `W2 = W3 = (m·g − W1)/2`.
    /// Digest §4: 65.49 kN and 89.88 kN for the preset.
    #[must_use]
    pub fn static_axle_loads(&self) -> [f64; 3] {
        let [_, b, c] = self.axle_distances;
        let weight = self.mass * self.gravity;
        let w1 = weight * 0.5 * (b + c) / self.tandem_wheelbase();
        let w_rear = 0.5 * (weight - w1);
        [w1, w_rear, w_rear]
    }

    /// Static loads of the six wheel positions `L1, R1, L2, R2, L3, R3` \[N\] (half an axle load
    /// each; digest §4: 32.74 kN and 44.94 kN).
    #[must_use]
    pub fn static_loads(&self) -> [f64; 6] {
        let w = self.static_axle_loads();
        [0.5 * w[0], 0.5 * w[0], 0.5 * w[1], 0.5 * w[1], 0.5 * w[2], 0.5 * w[2]]
    }

    /// Checks every parameter, returning the first violation with the parameter's name:
    /// finiteness of all; `m, I_z, a, c, T_i, R_e, g, v_min, σ_α, J_w > 0`; `b, h_cg, f_r,
    /// C_d·A, ρ, k_p, k_i ≥ 0`; `n_i ≥ 1`; `c > b` (axle 3 behind axle 2); the tyre
    /// ([`Pac89Tyre::validate`]); and usable tyre curves at the static load of every position.
    ///
    /// # Errors
    /// [`TruckError::Parameter`],
    /// [`TruckError::Inconsistent`] or [`TruckError::TyreOutOfRange`].
    pub fn validate(&self) -> Result<(), TruckError> {
        positive("m (mass)", self.mass)?;
        positive("I_z (yaw inertia)", self.yaw_inertia)?;
        positive(AXLE_NAMES[0], self.axle_distances[0])?;
        non_negative(AXLE_NAMES[1], self.axle_distances[1])?;
        positive(AXLE_NAMES[2], self.axle_distances[2])?;
        let [_, b, c] = self.axle_distances;
        if c <= b {
            return Err(TruckError::Inconsistent {
                name: AXLE_NAMES[2],
                reason: format!("axle 3 must be behind axle 2 (c > b), got b = {b}, c = {c}"),
            });
        }
        for (name, &t) in TRACK_NAMES.iter().zip(&self.tracks) {
            positive(name, t)?;
        }
        positive("R_e (effective rolling radius)", self.rolling_radius)?;
        for (name, &n) in TYRE_COUNT_NAMES.iter().zip(&self.tyres_per_position) {
            positive(name, f64::from(n))?;
        }
        positive("g (gravity)", self.gravity)?;
        self.tyre.validate()?;
        positive("v_min (low-speed guard)", self.min_speed)?;
        non_negative("h_cg (CG height)", self.cg_height)?;
        positive("sigma_alpha (tyre relaxation length)", self.relaxation_length)?;
        positive("J_w (wheel spin inertia per tyre)", self.wheel_inertia)?;
        non_negative("f_r (rolling-resistance coefficient)", self.rolling_resistance)?;
        non_negative("CdA (drag area)", self.drag_area)?;
        non_negative("rho (air density)", self.air_density)?;
        non_negative("k_p (speed controller proportional gain)", self.speed_kp)?;
        non_negative("k_i (speed controller integral gain)", self.speed_ki)?;
        for (axle, &w) in self.static_axle_loads().iter().enumerate() {
            let per_tyre_kn = (0.5 * w / f64::from(self.tyres_per_position[axle])).max(self.tyre.fz_min) / 1000.0;
            self.tyre.lateral_curve(per_tyre_kn)?;
            self.tyre.longitudinal_curve(per_tyre_kn)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn message(p: TruckParams) -> String {
        match p.validate() {
            Err(e) => e.to_string(),
            Ok(()) => panic!("expected a validation error for {p:?}"),
        }
    }

    #[test]
    fn preset_is_valid_and_gives_the_digest_loads() {
        let p = TruckParams::digest_preset();
        p.validate().unwrap();
        let fz = p.static_loads();
        assert!((fz[0] - 32_742.8).abs() < 0.1 && fz[0] == fz[1], "{fz:?}");
        for &f in &fz[2..] {
            assert!((f - 44_941.1).abs() < 0.1, "{fz:?}");
        }
        assert!((fz.iter().sum::<f64>() - p.mass * p.gravity).abs() < 1e-6);
    }

    #[test]
    fn every_parameter_is_named_in_its_error() {
        let base = TruckParams::digest_preset;
        let cases: Vec<(TruckParams, &str)> = vec![
            (TruckParams { mass: -25_000.0, ..base() }, "m (mass) must be positive"),
            (TruckParams { mass: f64::NAN, ..base() }, "m (mass) must be finite"),
            (TruckParams { yaw_inertia: 0.0, ..base() }, "I_z (yaw inertia) must be positive"),
            (TruckParams { axle_distances: [0.0, 0.6, 1.95], ..base() }, "a (CG to axle 1 distance) must be positive"),
            (
                TruckParams { axle_distances: [3.5, -0.6, 1.95], ..base() },
                "b (CG to axle 2 distance) must be non-negative",
            ),
            (TruckParams { axle_distances: [3.5, 1.95, 0.6], ..base() }, "axle 3 must be behind axle 2"),
            (TruckParams { tracks: [2.04, 1.83, f64::INFINITY], ..base() }, "T3 (track of axle 3) must be finite"),
            (TruckParams { rolling_radius: 0.0, ..base() }, "R_e (effective rolling radius) must be positive"),
            (TruckParams { tyres_per_position: [1, 0, 2], ..base() }, "n2 (tyres per wheel position, axle 2)"),
            (TruckParams { gravity: -9.81, ..base() }, "g (gravity) must be positive"),
            (
                TruckParams { tyre: Pac89Tyre { friction_scale: -0.8, ..Pac89Tyre::truck() }, ..base() },
                "lambda_mu (tyre friction scale) must be positive",
            ),
            (TruckParams { min_speed: 0.0, ..base() }, "v_min (low-speed guard) must be positive"),
            (TruckParams { cg_height: -1.4, ..base() }, "h_cg (CG height) must be non-negative"),
            (TruckParams { relaxation_length: 0.0, ..base() }, "sigma_alpha (tyre relaxation length) must be positive"),
            (TruckParams { wheel_inertia: -14.0, ..base() }, "J_w (wheel spin inertia per tyre) must be positive"),
            (TruckParams { rolling_resistance: -0.01, ..base() }, "f_r (rolling-resistance coefficient)"),
            (TruckParams { drag_area: f64::NAN, ..base() }, "CdA (drag area) must be finite"),
            (TruckParams { air_density: -1.0, ..base() }, "rho (air density) must be non-negative"),
            (TruckParams { speed_kp: -1.0, ..base() }, "k_p (speed controller proportional gain)"),
            (TruckParams { speed_ki: f64::NAN, ..base() }, "k_i (speed controller integral gain) must be finite"),
            // A 150 t "truck" on single tyres overloads them beyond the tyre data's range.
            (TruckParams { mass: 150_000.0, tyres_per_position: [1, 1, 1], ..base() }, "Pac89 curve at F_z"),
        ];
        for (p, expected) in cases {
            let m = message(p);
            assert!(m.contains(expected), "message {m:?} lacks {expected:?}");
        }
        // Zero CG height, drag, rolling resistance and gains are allowed; b = 0 too.
        TruckParams {
            cg_height: 0.0,
            drag_area: 0.0,
            rolling_resistance: 0.0,
            speed_kp: 0.0,
            speed_ki: 0.0,
            axle_distances: [3.5, 0.0, 1.3],
            ..base()
        }
        .validate()
        .unwrap();
    }
}
