//! Rigorous enclosures of the EKF's model ([`TruckEkfModel`]: Euler (12), measurement (14)) and
//! of its Jacobians over boxes of states, for the nonlinear set-membership filter `smf-nl`
//! ([`SecondOrderModel`]).
//!
//! The same model as [`crate::planar`] — wheel kinematics, slip angles and ratios
//! ([`crate::kinematics`]), Pac89 curves at static loads with dual tyres lumped
//! ([`crate::tyre`]), body forces (1), the Euler step (12) and `a_y = ΣF_Y/m` (14) — is
//! evaluated in interval forward-mode AD ([`Dual`]`<3>` in `[V_x, V_y, γ]`), which gives the
//! value and the Jacobian enclosures over the box at once. Inputs (`δ`, wheel speeds) and
//! parameters are points; `sin δ`, `cos δ`, `ω·R_e` and `180/π` are enclosed, so the enclosures
//! hold the exact real model.
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

use crate::kinematics::WHEELS;
use crate::planar::{INPUT_DIM, OUTPUT_DIM, STATE_DIM, TruckEkfModel, TruckInput};
use crate::tyre::MagicFormula;

/// A function of the state `[V_x, V_y, γ]` with its gradient, enclosed over a box.
type D3 = Dual<STATE_DIM>;

/// Interval enclosures of a Magic Formula curve's coefficients, with the slip's unit and the
/// lumping folded in.
struct Curve {
    /// `B·unit` (unit: degrees per radian or percent per unit slip).
    b_unit: Interval,
    /// `B·S_H`.
    b_sh: Interval,
    c: Interval,
    /// `1 − E`.
    one_minus_e: Interval,
    e: Interval,
    /// `n·k·D` (`n·k`: tyres at the position times the fade below the load clamp).
    d_scaled: Interval,
    /// `n·k·S_V`.
    sv_scaled: Interval,
}

impl Curve {
    fn new((mf, scale): (MagicFormula, f64), unit: Interval) -> Self {
        let (b, e, scale) = (Interval::point(mf.b), Interval::point(mf.e), Interval::point(scale));
        Self {
            b_unit: b * unit,
            b_sh: b * mf.sh,
            c: Interval::point(mf.c),
            one_minus_e: Interval::point(1.0) - e,
            e,
            d_scaled: scale * mf.d,
            sv_scaled: scale * mf.sv,
        }
    }

    /// `n·k·(D·sin(C·atan θ) + S_V)`, `θ = (1 − E)·B·x + E·atan(B·x)` (= `B·x − E·(B·x −
    /// atan(B·x))`, eq (3)–(4)), `B·x = B·unit·slip + B·S_H`: the same function as tyre.rs with
    /// fewer occurrences of the variables, so a tighter enclosure.
    fn force(&self, slip: D3) -> D3 {
        let bx = slip * self.b_unit + self.b_sh;
        let theta = bx * self.one_minus_e + bx.atan() * self.e;
        (theta.atan() * self.c).sin() * self.d_scaled + self.sv_scaled
    }
}

/// `ΣF_X`, `ΣF_Y` \[N\] and `M_z = Σ(x_j F_Yj − y_j F_Xj)` \[N m\] (1) over the box.
struct BodyForces {
    fx: D3,
    fy: D3,
    mz: D3,
}

/// `180/π` enclosed (`π` lies within one ulp of `f64`'s `PI`).
fn degrees_per_radian() -> Interval {
    let pi = std::f64::consts::PI;
    Interval::point(180.0) / Interval::new(intervals::down(pi), intervals::up(pi))
}

impl TruckEkfModel {
    fn read_input(u: &DVector<f64>) -> Result<TruckInput, ModelError> {
        models::error::check_dims("u", u, INPUT_DIM, 1)?;
        let input = TruckInput::from_dvector(u)?;
        input.validate()?;
        Ok(input)
    }

    /// The body forces over the box `x` (interval forward-mode AD, Jacobian included).
    fn enclosed_forces(&self, x: &[Interval], input: &TruckInput) -> Result<BodyForces, ModelError> {
        let planar = self.planar();
        let (p, g, loads) = (planar.params(), planar.geometry(), planar.static_loads());
        let [vx, vy, gamma] = std::array::from_fn(|i| D3::variable(x[i], i));
        let deg = degrees_per_radian();
        let v_min = Interval::point(p.min_speed);
        let delta = Interval::point(input.delta);
        let (sin_d, cos_d) = (delta.sin(), delta.cos());
        let zero = D3::from(0.0);
        let mut out = BodyForces { fx: zero, fy: zero, mz: zero };
        let mut curves: Option<((u32, f64), Curve, Curve)> = None;
        for j in 0..WHEELS {
            // The curves at the position's load (left and right of an axle usually share them).
            let key = (g.tyres[j], loads[j]);
            if curves.as_ref().is_none_or(|(k, _, _)| *k != key) {
                let lateral = Curve::new(p.tyre.lateral_lumped_curve(key.0, key.1)?, deg);
                let percent = Interval::point(100.0);
                curves = Some((key, lateral, Curve::new(p.tyre.longitudinal_lumped_curve(key.0, key.1)?, percent)));
            }
            let Some((_, lateral, longitudinal)) = curves.as_ref() else { continue };
            // Wheel-centre velocities and slips (kinematics.rs).
            let u = vx - gamma * g.y[j];
            let v = vy + gamma * g.x[j];
            if u.value.lo() <= 0.0 {
                // atan2(v, u) ≠ atan(v/u) there, and V_x ≤ 0 is outside the model.
                return Ok(BodyForces { fx: unbounded(), fy: unbounded(), mz: unbounded() });
            }
            let omega_re = Interval::point(input.omega[j]) * p.rolling_radius;
            // Steered: δ_j = δ; otherwise δ_j = 0 exactly (cos 1, sin 0: no products).
            let (alpha, vl) =
                if g.steered[j] { (delta - (v / u).atan(), u * cos_d + v * sin_d) } else { (-(v / u).atan(), u) };
            let denominator = D3::constant(omega_re.abs().max(v_min)).max(vl.abs());
            let slip = (omega_re - vl) / denominator;
            // Pac89 in degrees and percent (tyre.rs), lumped.
            let fy = lateral.force(alpha);
            let fx = longitudinal.force(slip);
            let (big_x, big_y) =
                if g.steered[j] { (fx * cos_d - fy * sin_d, fx * sin_d + fy * cos_d) } else { (fx, fy) };
            out.fx = out.fx + big_x;
            out.fy = out.fy + big_y;
            out.mz = out.mz + big_y * g.x[j] - big_x * g.y[j];
        }
        Ok(out)
    }
}

fn unbounded() -> D3 {
    D3 { value: Interval::ENTIRE, grad: [Interval::ENTIRE; STATE_DIM] }
}

fn write(out: &mut TaylorEnclosure, rows: [D3; 3]) {
    out.clear();
    for (i, r) in rows.iter().enumerate() {
        out.set_value(i, r.value);
        for j in 0..STATE_DIM {
            out.set_jacobian(i, j, r.grad[j]);
        }
    }
    // The slip ratio's max has its kink at free rolling: first order only (N2').
    out.set_hessian_invalid();
}

impl SecondOrderModel for TruckEkfModel {
    /// `F(x) = x + T·f_c(x, u)` (12) and `∂F/∂x` over the box; Hessians invalid.
    fn f_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        check_enclosure_dims("f enclosure", STATE_DIM, STATE_DIM, x, out)?;
        let input = Self::read_input(u)?;
        let f = self.enclosed_forces(x, &input)?;
        let p = self.planar().params();
        let t = Interval::point(self.ts());
        let [vx, vy, gamma] = std::array::from_fn(|i| D3::variable(x[i], i));
        let dvx = vy * gamma + f.fx / p.mass;
        let dvy = f.fy / p.mass - vx * gamma;
        let dgamma = f.mz / p.yaw_inertia;
        write(out, [vx + dvx * t, vy + dvy * t, gamma + dgamma * t]);
        Ok(())
    }

    /// `h(x) = [V_x, ΣF_Y/m, γ]` (14) and `∂h/∂x` over the box; Hessians invalid.
    fn h_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        check_enclosure_dims("h enclosure", OUTPUT_DIM, STATE_DIM, x, out)?;
        let input = Self::read_input(u)?;
        let f = self.enclosed_forces(x, &input)?;
        let mass = self.planar().params().mass;
        write(out, [D3::variable(x[0], 0), f.fy / mass, D3::variable(x[2], 2)]);
        Ok(())
    }
}
