//! Load cases: the carrier with `n = 0, 1, 2` containers (paper §1: `m`, `h` and the inertias
//! change with the load while the formulas stay the same; the paper gives values only for
//! `n = 1`, Table 1).
//!
//! # Assumptions
//!
//! * A container is a laden 40 ft box of mass [`CONTAINER_MASS`] = 25 t, a uniform solid box of
//!   [`CONTAINER_LENGTH`] × [`CONTAINER_WIDTH`] × [`CONTAINER_HEIGHT`] = 12.19 × 2.44 × 2.59 m.
//! * Every container is centred over the carrier's CG longitudinally and laterally, so the CG
//!   stays on the same vertical line: the row distances `L_i` and the yaw parallel-axis terms do
//!   not change, and only vertical offsets enter the roll inertia.
//! * A carried container hangs under the frame with its CG [`FIRST_CONTAINER_CG_HEIGHT`] = 4.5 m
//!   above the roll axis (its bottom 3.205 m above the roll axis, enough to pass over one stacked
//!   container). With two containers the second is locked *under* the first (a 1-over-2 carrier
//!   lifts its load under the frame; the spreader holds the top box at the same height), so its
//!   CG is one container height lower, at [`SECOND_CONTAINER_CG_HEIGHT`] = 1.91 m.
//! * The empty carrier is Table 1 minus the first container, so that `n = 1` reproduces Table 1
//!   **exactly** (`n = 1` *is* [`CarrierParams::paper_preset`]); `n = 2` is Table 1 plus the
//!   second container. Resulting empty carrier: 64 t, CG 9.352 m above the roll axis.
//! * Tyre cornering stiffnesses, roll stiffness and roll damping do not change with the load
//!   (as in the paper's formulas). In reality cornering stiffness grows with wheel load; this
//!   model ignores it.
//!
//! With these assumptions all three load cases are open-loop stable from 2 to 10 m/s
//! (`K_φ = 15.7·10⁶ N m/rad` exceeds `m g h` in every case: 5.9, 7.0 and 7.4 ·10⁶ N m/rad).

use crate::error::DynamicsError;
use crate::params::{CarrierParams, RollInertia};

/// Mass of one laden 40 ft container \[kg\] (assumption).
pub const CONTAINER_MASS: f64 = 25_000.0;
/// Length of a 40 ft container \[m\].
pub const CONTAINER_LENGTH: f64 = 12.19;
/// Width of a container \[m\].
pub const CONTAINER_WIDTH: f64 = 2.44;
/// Height of a (high-cube) container \[m\].
pub const CONTAINER_HEIGHT: f64 = 2.59;
/// Height of the first (or only) container's CG above the roll axis \[m\] (assumption).
pub const FIRST_CONTAINER_CG_HEIGHT: f64 = 4.5;
/// Height of the second container's CG above the roll axis \[m\]: one container height below
/// the first (assumption).
pub const SECOND_CONTAINER_CG_HEIGHT: f64 = FIRST_CONTAINER_CG_HEIGHT - CONTAINER_HEIGHT;
/// Largest supported number of containers.
pub const MAX_CONTAINERS: usize = 2;

/// Mass properties of a rigid body whose CG lies on the carrier's vertical CG line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidBody {
    /// Mass \[kg\].
    pub mass: f64,
    /// CG height above the roll axis \[m\].
    pub cg_height: f64,
    /// Roll inertia about the longitudinal axis through its own CG \[kg m²\].
    pub roll_inertia_cg: f64,
    /// Yaw inertia about the vertical axis through its own CG \[kg m²\].
    pub yaw_inertia: f64,
}

impl RigidBody {
    /// A container (uniform box) with its CG at `cg_height` above the roll axis:
    /// `I_x = m (W² + H²)/12`, `I_z = m (L² + W²)/12`.
    #[must_use]
    pub fn container(cg_height: f64) -> Self {
        let m = CONTAINER_MASS;
        let (l, w, h) = (CONTAINER_LENGTH, CONTAINER_WIDTH, CONTAINER_HEIGHT);
        Self {
            mass: m,
            cg_height,
            roll_inertia_cg: m * (w * w + h * h) / 12.0,
            yaw_inertia: m * (l * l + w * w) / 12.0,
        }
    }

    /// The mass properties of Table 1 (carrier with one container).
    #[must_use]
    pub fn of_params(p: &CarrierParams) -> Self {
        Self { mass: p.mass, cg_height: p.cg_height, roll_inertia_cg: p.roll_inertia_cg(), yaw_inertia: p.yaw_inertia }
    }

    /// Roll inertia about the roll axis, `I_xeq = I_x + m h²`.
    #[must_use]
    pub fn roll_inertia_eq(&self) -> f64 {
        self.roll_inertia_cg + self.mass * self.cg_height * self.cg_height
    }

    /// The union of two bodies on the same vertical line (parallel-axis theorem):
    /// `m = m₁ + m₂`, `h = (m₁h₁ + m₂h₂)/m`, `I_x = Σ (I_x,i + m_i (h_i − h)²)`, `I_z = I_z1 + I_z2`.
    #[must_use]
    pub fn combine(&self, other: &Self) -> Self {
        let mass = self.mass + other.mass;
        let cg_height = (self.mass * self.cg_height + other.mass * other.cg_height) / mass;
        let d1 = self.cg_height - cg_height;
        let d2 = other.cg_height - cg_height;
        Self {
            mass,
            cg_height,
            roll_inertia_cg: self.roll_inertia_cg + self.mass * d1 * d1 + other.roll_inertia_cg + other.mass * d2 * d2,
            yaw_inertia: self.yaw_inertia + other.yaw_inertia,
        }
    }

    /// The inverse of [`RigidBody::combine`]: what remains of `self` when `part` is taken away.
    /// (Not validated here; [`crate::CarrierModel::new`] validates the resulting parameters.)
    #[must_use]
    pub fn remove(&self, part: &Self) -> Self {
        let mass = self.mass - part.mass;
        let cg_height = (self.mass * self.cg_height - part.mass * part.cg_height) / mass;
        let d_part = part.cg_height - self.cg_height;
        let d_rest = cg_height - self.cg_height;
        Self {
            mass,
            cg_height,
            roll_inertia_cg: self.roll_inertia_cg
                - part.roll_inertia_cg
                - part.mass * d_part * d_part
                - mass * d_rest * d_rest,
            yaw_inertia: self.yaw_inertia - part.yaw_inertia,
        }
    }
}

/// The empty carrier: Table 1 minus the first container (see the module assumptions).
#[must_use]
pub fn empty_carrier() -> RigidBody {
    RigidBody::of_params(&CarrierParams::paper_preset()).remove(&RigidBody::container(FIRST_CONTAINER_CG_HEIGHT))
}

impl CarrierParams {
    /// Table 1 with `containers` = 0, 1 or 2 containers (mass, CG height, `I_x`, `I_z` from the
    /// load model of [`crate::load`]; everything else, including `v = 6 m/s`, from Table 1).
    /// `containers = 1` returns exactly [`CarrierParams::paper_preset`].
    ///
    /// # Errors
    /// [`DynamicsError::UnsupportedLoad`] for more than [`MAX_CONTAINERS`] containers.
    pub fn for_load(containers: usize) -> Result<Self, DynamicsError> {
        let preset = Self::paper_preset();
        let body = match containers {
            0 => empty_carrier(),
            1 => return Ok(preset),
            2 => RigidBody::of_params(&preset).combine(&RigidBody::container(SECOND_CONTAINER_CG_HEIGHT)),
            _ => return Err(DynamicsError::UnsupportedLoad { containers }),
        };
        Ok(Self {
            mass: body.mass,
            cg_height: body.cg_height,
            yaw_inertia: body.yaw_inertia,
            roll_inertia: RollInertia::AboutCg(body.roll_inertia_cg),
            ..preset
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::CarrierModel;

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs().max(1e-300)
    }

    #[test]
    fn one_container_is_exactly_table_1() {
        assert_eq!(CarrierParams::for_load(1).unwrap(), CarrierParams::paper_preset());
    }

    #[test]
    fn load_cases_are_consistent_and_physical() {
        let p: Vec<CarrierParams> = (0..=2).map(|n| CarrierParams::for_load(n).unwrap()).collect();
        // Mass linear in n, exactly (integers in f64).
        assert_eq!(p[0].mass, 64_000.0);
        assert_eq!(p[1].mass - p[0].mass, CONTAINER_MASS);
        assert_eq!(p[2].mass - p[1].mass, CONTAINER_MASS);
        for q in &p {
            q.validate().unwrap();
            assert!(q.roll_inertia_cg() > 0.0 && q.yaw_inertia > 0.0);
            // Every load case is statically roll-stable.
            assert!(q.roll_stiffness > q.mass * q.gravity * q.cg_height);
        }
        // The empty carrier plus both containers equals the n = 2 case (built from Table 1).
        let two = empty_carrier()
            .combine(&RigidBody::container(FIRST_CONTAINER_CG_HEIGHT))
            .combine(&RigidBody::container(SECOND_CONTAINER_CG_HEIGHT));
        let want = RigidBody::of_params(&p[2]);
        assert!(rel(two.mass, want.mass) < 1e-14);
        assert!(rel(two.cg_height, want.cg_height) < 1e-12);
        assert!(rel(two.roll_inertia_cg, want.roll_inertia_cg) < 1e-10);
        assert!(rel(two.yaw_inertia, want.yaw_inertia) < 1e-12);
        assert!(rel(two.roll_inertia_eq(), p[2].roll_inertia_eq()) < 1e-12);
        // The empty carrier's CG is above the container's: loading lowers the CG.
        assert!(p[0].cg_height > p[1].cg_height && p[1].cg_height > p[2].cg_height);
        assert!((p[0].cg_height - 9.352).abs() < 1e-3, "{}", p[0].cg_height);
    }

    #[test]
    fn more_than_two_containers_is_rejected() {
        let e = CarrierParams::for_load(3).unwrap_err();
        assert_eq!(e, DynamicsError::UnsupportedLoad { containers: 3 });
        assert_eq!(e.to_string(), "unsupported load of 3 containers: the load model covers 0, 1 or 2");
    }

    #[test]
    fn all_loads_are_stable_from_2_to_10_m_per_s() {
        for n in 0..=2 {
            for v in [2.0, 4.0, 6.0, 8.0, 10.0] {
                let model = CarrierModel::new(CarrierParams::for_load(n).unwrap().with_speed(v)).unwrap();
                let eig = model.eigenvalues().unwrap();
                for l in eig.iter() {
                    assert!(l.re < 0.0, "n = {n}, v = {v}: eigenvalue {l}");
                }
            }
        }
    }
}
