//! The experiment's cases (digest §5): the nominal slalom and the four mismatch cases, each
//! saying on which side (the truth or the EKF) its change applies.

use truck_dynamics::{Pac89Tyre, TruckParams};

/// One case of the experiment: the truth's vehicle data and what the EKF is given.
#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    /// Identifier (file names, `summary.json`).
    pub id: &'static str,
    /// Title (tables, legends).
    pub title: &'static str,
    /// A shorter label (bar-chart groups).
    pub short: &'static str,
    /// On which side the change applies, and how.
    pub applies_to: &'static str,
    /// The vehicle data of the truth simulation (the EKF always uses
    /// [`TruckParams::digest_preset`]).
    pub truth_params: TruckParams,
    /// Error added to the EKF's initial lateral speed `V̂_y0` \[m/s\].
    pub vy0_error: f64,
    /// Relative standard deviation of the multiplicative Gaussian noise on each wheel speed fed
    /// to the EKF (`ω̃ = ω·(1 + σ·n)`, independent per wheel and step).
    pub wheel_speed_noise: f64,
}

/// The five cases, nominal first.
#[must_use]
pub fn all() -> Vec<Case> {
    let nominal = TruckParams::digest_preset();
    let heavier = TruckParams { mass: 1.1 * nominal.mass, yaw_inertia: 1.1 * nominal.yaw_inertia, ..nominal };
    let slippery = TruckParams { tyre: Pac89Tyre { friction_scale: 0.8, ..nominal.tyre }, ..nominal };
    let base = Case {
        id: "nominal",
        title: "nominal",
        short: "nominal",
        applies_to: "nothing changed: the truth and the EKF share the vehicle data (the truth model is still richer)",
        truth_params: nominal,
        vy0_error: 0.0,
        wheel_speed_noise: 0.0,
    };
    vec![
        base.clone(),
        Case {
            id: "mass_inertia",
            title: "m, I_z +10 %",
            short: "m, Iz +10 %",
            applies_to: "truth: m = 27 500 kg and I_z = 1.65e5 kg·m² (static loads +10 % with them); the EKF keeps \
                         25 000 kg and 1.5e5 kg·m²; the truth's speed-controller gains stay those of the nominal \
                         vehicle",
            truth_params: heavier,
            ..base.clone()
        },
        Case {
            id: "friction",
            title: "μ ×0.8",
            short: "μ ×0.8",
            applies_to: "truth: tyre friction scale λ_μ = 0.8 (peak factor D × 0.8, slip stiffness BCD kept, as \
                         PAC2002's λ_μ); the EKF's tyres keep λ_μ = 1",
            truth_params: slippery,
            ..base.clone()
        },
        Case {
            id: "vy0_error",
            title: "V_y0 error 0.3 m/s",
            short: "Vy0 +0.3 m/s",
            applies_to: "EKF: initial estimate V̂_y0 = 0.3 m/s while the truth starts at V_y = 0 (an initial β error \
                         of 0.88°); P0 unchanged",
            vy0_error: 0.3,
            ..base.clone()
        },
        Case {
            id: "wheel_noise",
            title: "0.1 % wheel-speed noise",
            short: "ω noise 0.1 %",
            applies_to: "EKF inputs: each of the six wheel speeds fed to the EKF is multiplied by (1 + 0.001·n), n \
                         standard normal, independent per wheel and step; the truth's wheels are exact",
            wheel_speed_noise: 1e-3,
            ..base
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cases_are_distinct_and_valid() {
        let cases = all();
        assert_eq!(cases.len(), 5);
        assert_eq!(cases[0].id, "nominal");
        for c in &cases {
            c.truth_params.validate().unwrap();
        }
        for (i, a) in cases.iter().enumerate() {
            for b in &cases[i + 1..] {
                assert_ne!(a.id, b.id);
                assert_ne!(a, b);
            }
        }
        // Each mismatch case changes exactly one thing relative to the nominal case.
        let n = &cases[0];
        let changes = |c: &Case| {
            usize::from(c.truth_params != n.truth_params)
                + usize::from(c.vy0_error != 0.0)
                + usize::from(c.wheel_speed_noise != 0.0)
        };
        assert_eq!(changes(n), 0);
        for c in &cases[1..] {
            assert_eq!(changes(c), 1, "{}", c.id);
        }
    }
}
