//! Rigorous enclosures of the EKF's model ([`TruckEkfModel`]: Euler (12), measurement (14)) and
//! of its Jacobians over boxes of states, for the nonlinear set-membership filter `smf-nl`
//! ([`SecondOrderModel`]).
//!
//! The same model as [`crate::planar`] — wheel kinematics, slip angles and ratios
//! ([`crate::kinematics`]), Pac89 curves at static loads with dual tyres lumped
//! ([`crate::tyre`]), body forces (1), the Euler step (12) and `a_y = ΣF_Y/m` (14) — is
//! evaluated in interval forward-mode AD ([`Dual`]`<3>` in `[V_x, V_y, γ]`), which gives the
//! value and the Jacobian enclosures over the box at once ([`Dual`]`<0>`: the value alone).
//! Inputs (`δ`, wheel speeds) and parameters are points; `sin δ`, `cos δ`, `ω·R_e` and `180/π`
//! are enclosed, so the enclosures hold the exact real model.
//!
//! The slip ratio `s = (ωR_e − v_l)/max(|ωR_e|, |v_l|, v_min)` has a kink at free rolling
//! `|ωR_e| = |v_l|`, where the model is Lipschitz but not differentiable: [`Dual::max`] encloses
//! the generalised (Clarke) gradient there, and the Hessians are declared invalid
//! ([`TaylorEnclosure::set_hessian_invalid`]) — the filter bounds the remainder by the
//! mean-value form (N2'). The slip angle `α = δ − atan2(v, u)` is enclosed as `δ − atan(v/u)`,
//! valid for `u > 0`; a box on which a wheel's `u` can be `≤ 0` (or `V_x ≤ 0`, where the model is
//! undefined) gives unbounded enclosures.

use intervals::Dual;
use models::{Interval, ModelError, SecondOrderModel, TaylorEnclosure, check_enclosure_dims};
use nalgebra::DVector;

use crate::curve_enclosure::EnclosedWheel;
use crate::planar::{INPUT_DIM, OUTPUT_DIM, STATE_DIM, TruckEkfModel, TruckInput};

/// `ΣF_X`, `ΣF_Y` \[N\] and `M_z = Σ(x_j F_Yj − y_j F_Xj)` \[N m\] (1) over the box.
struct BodyForces<const N: usize> {
    fx: Dual<N>,
    fy: Dual<N>,
    mz: Dual<N>,
}

impl TruckEkfModel {
    fn read_input(u: &DVector<f64>) -> Result<TruckInput, ModelError> {
        models::error::check_dims("u", u, INPUT_DIM, 1)?;
        let input = TruckInput::from_dvector(u)?;
        input.validate()?;
        Ok(input)
    }

    /// The body forces over the box `x` (interval forward-mode AD: with the Jacobian for
    /// `N = 3`, the value alone for `N = 0`). With `lateral_only`, `ΣF_Y` alone (`fx`, `mz` are
    /// left at 0): the measurement (14) needs no more, and the longitudinal force of an
    /// unsteered wheel does not enter `ΣF_Y`.
    fn enclosed_forces<const N: usize>(
        &self,
        x: &[Interval],
        input: &TruckInput,
        lateral_only: bool,
    ) -> Result<BodyForces<N>, ModelError> {
        let planar = self.planar();
        let (p, g) = (planar.params(), planar.geometry());
        let [vx, vy, gamma] = std::array::from_fn(|i| Dual::<N>::variable(x[i], i));
        let v_min = Interval::point(p.min_speed);
        let delta = Interval::point(input.delta);
        let (sin_d, cos_d) = (delta.sin(), delta.cos());
        let zero = Dual::<N>::from(0.0);
        let mut out = BodyForces { fx: zero, fy: zero, mz: zero };
        for (j, EnclosedWheel { lateral, longitudinal }) in self.enclosed_curves().iter().enumerate() {
            // Wheel-centre velocities and slips (kinematics.rs).
            let u = vx - gamma * g.y[j];
            let v = vy + gamma * g.x[j];
            if u.value.lo() <= 0.0 {
                // atan2(v, u) ≠ atan(v/u) there, and V_x ≤ 0 is outside the model.
                return Ok(BodyForces { fx: unbounded(), fy: unbounded(), mz: unbounded() });
            }
            // Steered: δ_j = δ; otherwise δ_j = 0 exactly (cos 1, sin 0: no products).
            let alpha = if g.steered[j] { delta - (v / u).atan() } else { -(v / u).atan() };
            // Pac89 in degrees and percent (tyre.rs), lumped.
            let fy = lateral.force(alpha);
            if lateral_only && !g.steered[j] {
                out.fy = out.fy + fy;
                continue;
            }
            let omega_re = Interval::point(input.omega[j]) * p.rolling_radius;
            let vl = if g.steered[j] { u * cos_d + v * sin_d } else { u };
            // The slip ratio is a function of v_l alone: one derivative, the chain rule once.
            let floor = omega_re.abs().max(v_min);
            let slip = vl.map_scalar(|w| (omega_re - w) / Dual::constant(floor).max(w.abs()));
            let fx = longitudinal.force(slip);
            let (big_x, big_y) =
                if g.steered[j] { (fx * cos_d - fy * sin_d, fx * sin_d + fy * cos_d) } else { (fx, fy) };
            out.fx = out.fx + big_x;
            out.fy = out.fy + big_y;
            if !lateral_only {
                out.mz = out.mz + big_y * g.x[j] - big_x * g.y[j];
            }
        }
        Ok(out)
    }
}

fn unbounded<const N: usize>() -> Dual<N> {
    Dual { value: Interval::ENTIRE, grad: [Interval::ENTIRE; N] }
}

/// Writes the values and, for `N = 3`, the Jacobian (for `N = 0` it stays zero).
fn write<const N: usize>(out: &mut TaylorEnclosure, rows: [Dual<N>; 3]) {
    out.clear();
    for (i, r) in rows.iter().enumerate() {
        out.set_value(i, r.value);
        for (j, g) in r.grad.iter().enumerate() {
            out.set_jacobian(i, j, *g);
        }
    }
    // The slip ratio's max has its kink at free rolling: first order only (N2').
    out.set_hessian_invalid();
}

impl TruckEkfModel {
    /// `F(x) = x + T·f_c(x, u)` (12) over the box.
    fn enclosed_step<const N: usize>(&self, x: &[Interval], u: &DVector<f64>) -> Result<[Dual<N>; 3], ModelError> {
        let input = Self::read_input(u)?;
        let f = self.enclosed_forces::<N>(x, &input, false)?;
        let p = self.planar().params();
        let t = Interval::point(self.ts());
        let [vx, vy, gamma] = std::array::from_fn(|i| Dual::<N>::variable(x[i], i));
        let dvx = vy * gamma + f.fx / p.mass;
        let dvy = f.fy / p.mass - vx * gamma;
        let dgamma = f.mz / p.yaw_inertia;
        Ok([vx + dvx * t, vy + dvy * t, gamma + dgamma * t])
    }

    /// `h(x) = [V_x, ΣF_Y/m, γ]` (14) over the box.
    fn enclosed_output<const N: usize>(&self, x: &[Interval], u: &DVector<f64>) -> Result<[Dual<N>; 3], ModelError> {
        let input = Self::read_input(u)?;
        let f = self.enclosed_forces::<N>(x, &input, true)?;
        let mass = self.planar().params().mass;
        Ok([Dual::variable(x[0], 0), f.fy / mass, Dual::variable(x[2], 2)])
    }
}

impl SecondOrderModel for TruckEkfModel {
    /// `F(x) = x + T·f_c(x, u)` (12) and `∂F/∂x` over the box; Hessians invalid.
    fn f_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        check_enclosure_dims("f enclosure", STATE_DIM, STATE_DIM, x, out)?;
        write(out, self.enclosed_step::<STATE_DIM>(x, u)?);
        Ok(())
    }

    /// `h(x) = [V_x, ΣF_Y/m, γ]` (14) and `∂h/∂x` over the box; Hessians invalid.
    fn h_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        check_enclosure_dims("h enclosure", OUTPUT_DIM, STATE_DIM, x, out)?;
        write(out, self.enclosed_output::<STATE_DIM>(x, u)?);
        Ok(())
    }

    /// (12) over the box, without the Jacobian (about a quarter of the work).
    fn f_value_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        check_enclosure_dims("f enclosure", STATE_DIM, STATE_DIM, x, out)?;
        write::<0>(out, self.enclosed_step::<0>(x, u)?);
        Ok(())
    }

    /// (14) over the box, without the Jacobian.
    fn h_value_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        check_enclosure_dims("h enclosure", OUTPUT_DIM, STATE_DIM, x, out)?;
        write::<0>(out, self.enclosed_output::<0>(x, u)?);
        Ok(())
    }
}
