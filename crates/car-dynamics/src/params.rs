//! Physical parameters of the single-track car (`docs/robust-mhe.md` §1 and §3) and their
//! validation.

use models::validate::positive;

use crate::error::CarError;

/// Parameters of the linear single-track ("bicycle") car of eqs (1)–(5) (R, Rajamani, *Vehicle
/// Dynamics and Control*, 2nd ed., ch. 2).
///
/// `C_f` and `C_r` are **per-axle** cornering stiffnesses (both tyres of an axle together),
/// positive magnitudes: the axle forces are `F_yf = C_f (δ_f − β − a r/v_x)` and
/// `F_yr = C_r (−β + b r/v_x)` (eq (2)). The struct is plain data:
/// [`CarParams::validate`] (called by [`crate::CarModel::new`]) checks it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CarParams {
    /// Mass `m` \[kg\].
    pub mass: f64,
    /// Yaw inertia `I_z` about the vertical axis through the CG \[kg m²\].
    pub yaw_inertia: f64,
    /// Distance `a` from the CG to the front axle \[m\].
    pub front_axle_distance: f64,
    /// Distance `b` from the CG to the rear axle \[m\].
    pub rear_axle_distance: f64,
    /// Front-axle cornering stiffness `C_f` \[N/rad\].
    pub front_cornering_stiffness: f64,
    /// Rear-axle cornering stiffness `C_r` \[N/rad\].
    pub rear_cornering_stiffness: f64,
    /// Constant longitudinal speed `v_x` \[m/s\].
    pub speed: f64,
}

/// The paper's constant speed `v_x = 25 m/s` (P).
pub const DIGEST_SPEED: f64 = 25.0;

impl CarParams {
    /// The digest's default set (A, note (1) of the parameter table): a CarSim 2019.1
    /// "C-Class, Hatchback" export — `m = 1501 kg`, `I_z = 2192.0895 kg m²`,
    /// `a = 1.049563 m`, `b = 1.860437 m` (wheelbase 2.910 m), `C_f = 159 055.1 N/rad`,
    /// `C_r = 92 776.5 N/rad` (per axle, linearised at 0.5° slip and static load) — at the
    /// paper's `v_x = 25 m/s` (P). The digest's `A_c`, `B_c` test vector is computed with it.
    #[must_use]
    pub fn digest_default() -> Self {
        Self {
            mass: 1501.0,
            yaw_inertia: 2192.0895,
            front_axle_distance: 1.049563,
            rear_axle_distance: 1.860437,
            front_cornering_stiffness: 159_055.1,
            rear_cornering_stiffness: 92_776.5,
            speed: DIGEST_SPEED,
        }
    }

    /// The digest's alternative set (A, note (2)): CarSim C-Class sprung-mass values that recur
    /// in public code — `m = 1270 kg`, `I_z = 1536.7 kg m²`, `a = 1.015 m`, `b = 1.895 m` —
    /// at `v_x = 25 m/s`.
    ///
    /// **Decision.** The digest gives no cornering stiffnesses consistent with this set. This
    /// crate borrows `C_f`, `C_r` of [`CarParams::digest_default`] (A), so the set differs from
    /// the default only in mass, inertia and geometry. The car stays understeering
    /// (`b C_r − a C_f > 0`), hence stable at every speed.
    #[must_use]
    pub fn digest_alternative() -> Self {
        Self {
            mass: 1270.0,
            yaw_inertia: 1536.7,
            front_axle_distance: 1.015,
            rear_axle_distance: 1.895,
            ..Self::digest_default()
        }
    }

    /// The same parameters at another longitudinal speed `v_x` \[m/s\] (validated later).
    #[must_use]
    pub fn with_speed(self, speed: f64) -> Self {
        Self { speed, ..self }
    }

    /// Wheelbase `a + b` \[m\] (not validated).
    #[must_use]
    pub fn wheelbase(&self) -> f64 {
        self.front_axle_distance + self.rear_axle_distance
    }

    /// `b C_r − a C_f` \[N m/rad\]: positive for an understeering car, whose yaw–sideslip modes
    /// are stable at every speed (not validated).
    #[must_use]
    pub fn understeer_moment(&self) -> f64 {
        self.rear_axle_distance * self.rear_cornering_stiffness
            - self.front_axle_distance * self.front_cornering_stiffness
    }

    /// Checks every parameter, returning the first violation with the parameter's name: all
    /// finite and `m, I_z, a, b, C_f, C_r, v_x > 0`.
    ///
    /// Stability is *not* required: an oversteering car above its critical speed is a
    /// legitimate, if unstable, linear model, and [`crate::CarModel::lateral_eigenvalues`]
    /// shows it.
    ///
    /// # Errors
    /// [`CarError::Parameter`] naming the parameter.
    pub fn validate(&self) -> Result<(), CarError> {
        positive("m (mass)", self.mass)?;
        positive("I_z (yaw inertia)", self.yaw_inertia)?;
        positive("a (distance from the CG to the front axle)", self.front_axle_distance)?;
        positive("b (distance from the CG to the rear axle)", self.rear_axle_distance)?;
        positive("C_f (front-axle cornering stiffness)", self.front_cornering_stiffness)?;
        positive("C_r (rear-axle cornering stiffness)", self.rear_cornering_stiffness)?;
        positive("v_x (longitudinal speed)", self.speed)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use models::validate::ParamError;

    fn message(p: CarParams) -> String {
        match p.validate() {
            Err(e) => e.to_string(),
            Ok(()) => panic!("expected a validation error for {p:?}"),
        }
    }

    #[test]
    fn digest_sets_are_valid_and_understeering() {
        for p in [CarParams::digest_default(), CarParams::digest_alternative()] {
            p.validate().unwrap();
            assert!(p.understeer_moment() > 0.0, "{p:?}");
            assert_eq!(p.speed, 25.0);
        }
        assert!((CarParams::digest_default().wheelbase() - 2.910).abs() < 1e-12);
        assert!((CarParams::digest_alternative().wheelbase() - 2.910).abs() < 1e-12);
        // b C_r − a C_f: 5 666.49 (default) and 14 370.54 N m/rad (alternative).
        assert!((CarParams::digest_default().understeer_moment() - 5666.49).abs() < 0.01);
        assert!((CarParams::digest_alternative().understeer_moment() - 14370.54).abs() < 0.01);
    }

    #[test]
    fn every_parameter_is_named_in_its_error() {
        let base = CarParams::digest_default;
        let cases: Vec<(CarParams, &str)> = vec![
            (CarParams { mass: -1501.0, ..base() }, "m (mass) must be positive, got -1501"),
            (CarParams { mass: f64::NAN, ..base() }, "m (mass) must be finite"),
            (CarParams { yaw_inertia: 0.0, ..base() }, "I_z (yaw inertia) must be positive"),
            (
                CarParams { front_axle_distance: -1.0, ..base() },
                "a (distance from the CG to the front axle) must be positive",
            ),
            (
                CarParams { rear_axle_distance: f64::INFINITY, ..base() },
                "b (distance from the CG to the rear axle) must be finite",
            ),
            (
                CarParams { front_cornering_stiffness: 0.0, ..base() },
                "C_f (front-axle cornering stiffness) must be positive",
            ),
            (
                CarParams { rear_cornering_stiffness: -5.0, ..base() },
                "C_r (rear-axle cornering stiffness) must be positive",
            ),
            (base().with_speed(0.0), "v_x (longitudinal speed) must be positive, got 0"),
            (base().with_speed(-25.0), "v_x (longitudinal speed) must be positive"),
            (base().with_speed(f64::NEG_INFINITY), "v_x (longitudinal speed) must be finite"),
        ];
        for (p, expected) in cases {
            let m = message(p);
            assert!(m.contains(expected), "message {m:?} lacks {expected:?}");
        }
        let e = CarParams { mass: -1.0, ..base() }.validate().unwrap_err();
        assert_eq!(e, CarError::Parameter(ParamError::NotPositive { name: "m (mass)", value: -1.0 }));
    }
}
