//! Physical parameters of the straddle carrier (paper §1, Table 1) and their validation.

use models::validate::{non_negative, positive};

use crate::error::DynamicsError;

/// How the roll inertia is given: about the CG (`I_x`) or about the roll axis
/// (`I_xeq = I_x + m h²`, parallel-axis theorem, paper §1).
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum RollInertia {
    /// `I_x` \[kg m²\], roll inertia about the longitudinal axis through the CG.
    AboutCg(f64),
    /// `I_xeq` \[kg m²\], roll inertia about the roll axis; `I_x = I_xeq − m h²` must stay
    /// positive, which [`CarrierParams::validate`] checks.
    AboutRollAxis(f64),
}

/// Parameters of the four-row, eight-wheel straddle-carrier model (paper §1, Table 1).
///
/// Rows 1 and 2 are ahead of the CG, rows 3 and 4 behind it; all row distances are positive
/// magnitudes. Arrays indexed by row hold rows 1..4 in that order. The struct is plain data:
/// [`CarrierParams::validate`] (called by [`crate::CarrierModel::new`]) checks it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CarrierParams {
    /// Total mass `m` \[kg\].
    pub mass: f64,
    /// Height `h` of the CG above the roll axis \[m\].
    pub cg_height: f64,
    /// Distances `L_1..L_4` of the rows from the CG \[m\] (rows 1, 2 ahead; rows 3, 4 behind).
    pub row_distances: [f64; 4],
    /// Cornering stiffnesses `K_l1..K_l4` of the left wheels \[N/rad\].
    pub stiffness_left: [f64; 4],
    /// Cornering stiffnesses `K_r1..K_r4` of the right wheels \[N/rad\].
    pub stiffness_right: [f64; 4],
    /// Roll stiffness `K_φ` \[N m/rad\].
    pub roll_stiffness: f64,
    /// Roll damping `C_φ` \[N m s/rad\] (zero allowed).
    pub roll_damping: f64,
    /// Yaw inertia `I_z` about the vertical axis through the CG \[kg m²\].
    pub yaw_inertia: f64,
    /// Roll inertia, about the CG or about the roll axis.
    pub roll_inertia: RollInertia,
    /// Constant forward speed `v` \[m/s\].
    pub speed: f64,
    /// Gravitational acceleration `g` \[m/s²\].
    pub gravity: f64,
}

const ROW_NAMES: [&str; 4] = [
    "L_1 (distance of row 1 from the CG)",
    "L_2 (distance of row 2 from the CG)",
    "L_3 (distance of row 3 from the CG)",
    "L_4 (distance of row 4 from the CG)",
];
const LEFT_NAMES: [&str; 4] = [
    "K_l1 (cornering stiffness, left wheel of row 1)",
    "K_l2 (cornering stiffness, left wheel of row 2)",
    "K_l3 (cornering stiffness, left wheel of row 3)",
    "K_l4 (cornering stiffness, left wheel of row 4)",
];
const RIGHT_NAMES: [&str; 4] = [
    "K_r1 (cornering stiffness, right wheel of row 1)",
    "K_r2 (cornering stiffness, right wheel of row 2)",
    "K_r3 (cornering stiffness, right wheel of row 3)",
    "K_r4 (cornering stiffness, right wheel of row 4)",
];

impl CarrierParams {
    /// The paper's Table 1 (one container, `v = 6 m/s`, `g = 9.81 m/s²`).
    ///
    /// **Reading of the roll inertia.** Table 1 lists `I_xeq = 2 119 600 kg m²`, but with
    /// `m h² = 89 000 · 7.9891² ≈ 5.68·10⁶ kg m²` the literal reading gives
    /// `I_x = I_xeq − m h² < 0`: no rigid body has that (parallel-axis theorem), and the model
    /// built from it is unstable (an eigenvalue near +5.8). The preset therefore reads the
    /// table value as the roll inertia **about the CG**, `I_x = 2 119 600 kg m²`, so that
    /// `I_xeq = I_x + m h² ≈ 7.80·10⁶ kg m²`. With this reading the model is open-loop stable
    /// (eigenvalues ≈ −28.2, −5.9, −0.075 ± 1.05j at 6 m/s). The literal reading is still
    /// expressible as [`RollInertia::AboutRollAxis`]`(2_119_600.0)` and is rejected by
    /// [`CarrierParams::validate`].
    #[must_use]
    pub fn paper_preset() -> Self {
        Self {
            mass: 89_000.0,
            cg_height: 7.9891,
            row_distances: [3.85, 1.95, 1.95, 3.85],
            stiffness_left: [560_000.0, 560_000.0, 460_000.0, 460_000.0],
            stiffness_right: [560_000.0, 560_000.0, 460_000.0, 460_000.0],
            roll_stiffness: 15.7e6,
            roll_damping: 3.0e5,
            yaw_inertia: 1_052_500.0,
            roll_inertia: RollInertia::AboutCg(2_119_600.0),
            speed: 6.0,
            gravity: 9.81,
        }
    }

    /// The same parameters at another forward speed `v` \[m/s\] (validated later).
    #[must_use]
    pub fn with_speed(self, speed: f64) -> Self {
        Self { speed, ..self }
    }

    /// The same parameters with the roll inertia given about the roll axis, `I_xeq` \[kg m²\];
    /// validation then requires `I_x = I_xeq − m h² > 0`.
    #[must_use]
    pub fn with_roll_inertia_eq(self, i_xeq: f64) -> Self {
        Self { roll_inertia: RollInertia::AboutRollAxis(i_xeq), ..self }
    }

    /// `m h²` \[kg m²\], the parallel-axis term.
    #[must_use]
    pub fn parallel_axis_term(&self) -> f64 {
        self.mass * self.cg_height * self.cg_height
    }

    /// Roll inertia about the CG, `I_x` \[kg m²\] (not validated: may be non-positive before
    /// [`CarrierParams::validate`] succeeds).
    #[must_use]
    pub fn roll_inertia_cg(&self) -> f64 {
        match self.roll_inertia {
            RollInertia::AboutCg(i_x) => i_x,
            RollInertia::AboutRollAxis(i_xeq) => i_xeq - self.parallel_axis_term(),
        }
    }

    /// Roll inertia about the roll axis, `I_xeq = I_x + m h²` \[kg m²\] (not validated).
    #[must_use]
    pub fn roll_inertia_eq(&self) -> f64 {
        match self.roll_inertia {
            RollInertia::AboutCg(i_x) => i_x + self.parallel_axis_term(),
            RollInertia::AboutRollAxis(i_xeq) => i_xeq,
        }
    }

    /// Checks every parameter, returning the first violation with the parameter's name:
    /// finiteness of all; `m, L_i, K_li, K_ri, K_φ, I_z, I_x (or I_xeq), v, g > 0`;
    /// `h ≥ 0`, `C_φ ≥ 0`; and, when the roll inertia is given about the roll axis,
    /// `I_x = I_xeq − m h² > 0`.
    ///
    /// Static roll stability (`K_φ > m g h`) is *not* required: a top-heavy carrier is a
    /// legitimate, if unstable, linear model, and its eigenvalues show it.
    pub fn validate(&self) -> Result<(), DynamicsError> {
        positive("m (mass)", self.mass)?;
        non_negative("h (CG height above the roll axis)", self.cg_height)?;
        for (name, &l) in ROW_NAMES.iter().zip(&self.row_distances) {
            positive(name, l)?;
        }
        for (name, &k) in LEFT_NAMES.iter().zip(&self.stiffness_left) {
            positive(name, k)?;
        }
        for (name, &k) in RIGHT_NAMES.iter().zip(&self.stiffness_right) {
            positive(name, k)?;
        }
        positive("K_phi (roll stiffness)", self.roll_stiffness)?;
        non_negative("C_phi (roll damping)", self.roll_damping)?;
        positive("I_z (yaw inertia)", self.yaw_inertia)?;
        match self.roll_inertia {
            RollInertia::AboutCg(i_x) => positive("I_x (roll inertia about the CG)", i_x)?,
            RollInertia::AboutRollAxis(i_xeq) => {
                positive("I_xeq (roll inertia about the roll axis)", i_xeq)?;
                let m_h2 = self.parallel_axis_term();
                let i_x = i_xeq - m_h2;
                if i_x <= 0.0 || !i_x.is_finite() {
                    return Err(DynamicsError::NonPhysicalRollInertia { i_xeq, m_h2, i_x });
                }
            }
        }
        positive("v (forward speed)", self.speed)?;
        positive("g (gravity)", self.gravity)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn message(p: CarrierParams) -> String {
        match p.validate() {
            Err(e) => e.to_string(),
            Ok(()) => panic!("expected a validation error for {p:?}"),
        }
    }

    #[test]
    fn preset_is_valid_and_reads_table_value_as_i_x() {
        let p = CarrierParams::paper_preset();
        p.validate().unwrap();
        assert_eq!(p.roll_inertia_cg(), 2_119_600.0);
        let i_xeq = p.roll_inertia_eq();
        assert!((i_xeq - 7.8e6).abs() < 0.01e6, "I_xeq = {i_xeq}");
        // Round trip through the I_xeq constructor.
        let q = p.with_roll_inertia_eq(i_xeq);
        q.validate().unwrap();
        assert!((q.roll_inertia_cg() - 2_119_600.0).abs() < 1e-6);
    }

    #[test]
    fn literal_table_reading_is_rejected() {
        let p = CarrierParams::paper_preset().with_roll_inertia_eq(2_119_600.0);
        let e = p.validate().unwrap_err();
        assert!(matches!(e, DynamicsError::NonPhysicalRollInertia { i_x, .. } if i_x < 0.0));
        let m = e.to_string();
        assert!(m.contains("I_x = I_xeq - m h^2"), "{m}");
        assert!(m.contains("I_xeq = 2119600"), "{m}");
    }

    #[test]
    fn every_parameter_is_named_in_its_error() {
        let base = CarrierParams::paper_preset;
        let cases: Vec<(CarrierParams, &str)> = vec![
            (CarrierParams { mass: 0.0, ..base() }, "m (mass) must be positive"),
            (CarrierParams { mass: f64::NAN, ..base() }, "m (mass) must be finite"),
            (CarrierParams { cg_height: -1.0, ..base() }, "h (CG height above the roll axis) must be non-negative"),
            (CarrierParams { cg_height: f64::INFINITY, ..base() }, "h (CG height above the roll axis) must be finite"),
            (
                CarrierParams { row_distances: [3.85, 1.95, -1.95, 3.85], ..base() },
                "L_3 (distance of row 3 from the CG) must be positive",
            ),
            (
                CarrierParams { stiffness_left: [5.6e5, 5.6e5, 4.6e5, 0.0], ..base() },
                "K_l4 (cornering stiffness, left wheel of row 4) must be positive",
            ),
            (
                CarrierParams { stiffness_right: [f64::NAN, 5.6e5, 4.6e5, 4.6e5], ..base() },
                "K_r1 (cornering stiffness, right wheel of row 1) must be finite",
            ),
            (CarrierParams { roll_stiffness: -1.0, ..base() }, "K_phi (roll stiffness) must be positive"),
            (CarrierParams { roll_damping: -1.0, ..base() }, "C_phi (roll damping) must be non-negative"),
            (CarrierParams { yaw_inertia: 0.0, ..base() }, "I_z (yaw inertia) must be positive"),
            (
                CarrierParams { roll_inertia: RollInertia::AboutCg(0.0), ..base() },
                "I_x (roll inertia about the CG) must be positive",
            ),
            (base().with_roll_inertia_eq(-5.0), "I_xeq (roll inertia about the roll axis) must be positive"),
            (base().with_speed(0.0), "v (forward speed) must be positive"),
            (base().with_speed(f64::INFINITY), "v (forward speed) must be finite"),
            (CarrierParams { gravity: -9.81, ..base() }, "g (gravity) must be positive"),
        ];
        for (p, expected) in cases {
            let m = message(p);
            assert!(m.contains(expected), "message {m:?} lacks {expected:?}");
        }
        // Zero damping and zero CG height are allowed.
        CarrierParams { roll_damping: 0.0, cg_height: 0.0, ..base() }.validate().unwrap();
    }
}
