//! The estimator's model: the planar three-axle body `x = [V_x, V_y, γ]` with Pac89 tyres at
//! static loads, driven by the road-wheel angle and the six measured wheel speeds (paper
//! eq (1), digest §2–§3), its Euler discretisation (12), the measurement `[V_x, a_y, γ]` (14)
//! and the analytic Jacobians `J` (13) and `H` (15).

use models::error::check_dims;
use models::{ContinuousModel, DifferentiableContinuousModel, DifferentiableModel, Dims, DiscreteModel, ModelError};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

use crate::curve_enclosure::{EnclosedWheel, enclosed_curves};
use crate::error::{TruckError, finite_input};
use crate::kinematics::{Geometry, WHEELS, wheel_gradients, wheel_kinematics};
use crate::params::TruckParams;
use crate::tyre::LumpedCurves;

/// States: `x = [V_x, V_y, γ]` (m/s, m/s, rad/s).
pub const STATE_DIM: usize = 3;
/// Inputs: `u = [δ, ω_L1, ω_R1, ω_L2, ω_R2, ω_L3, ω_R3]` (rad, rad/s).
pub const INPUT_DIM: usize = 7;
/// Outputs: `y = [V_x, a_y, γ]` (m/s, m/s², rad/s), eq (14).
pub const OUTPUT_DIM: usize = 3;
/// The paper's sampling and filter period `T = 1 ms` **\[P\]**.
pub const PAPER_SAMPLE_PERIOD: f64 = 1e-3;

/// Names of the states, as they appear in error messages.
pub const STATE_NAMES: [&str; STATE_DIM] = ["V_x (longitudinal speed)", "V_y (lateral speed)", "gamma (yaw rate)"];
/// Names of the six wheel speeds, in the order of [`crate::WHEEL_NAMES`].
pub(crate) const WHEEL_SPEED_NAMES: [&str; 6] = [
    "omega_L1 (wheel speed)",
    "omega_R1 (wheel speed)",
    "omega_L2 (wheel speed)",
    "omega_R2 (wheel speed)",
    "omega_L3 (wheel speed)",
    "omega_R3 (wheel speed)",
];
/// Names of the inputs, as they appear in error messages.
pub const INPUT_NAMES: [&str; INPUT_DIM] = join(["delta (road-wheel angle)"], WHEEL_SPEED_NAMES);

/// The names `a` then `b`, for lists of names built from others in constants.
pub(crate) const fn join<const A: usize, const B: usize, const N: usize>(
    a: [&'static str; A],
    b: [&'static str; B],
) -> [&'static str; N] {
    assert!(A + B == N, "join: the lengths do not add up");
    let mut out = [""; N];
    let mut i = 0;
    while i < N {
        out[i] = if i < A { a[i] } else { b[i - A] };
        i += 1;
    }
    out
}

/// The estimator's inputs at one step: road-wheel angle and the six wheel speeds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruckInput {
    /// Road-wheel angle `δ` of axle 1 \[rad\] (positive turns left).
    pub delta: f64,
    /// Wheel speeds `ω_j` of `L1, R1, L2, R2, L3, R3` \[rad/s\].
    pub omega: [f64; WHEELS],
}

impl TruckInput {
    /// Free rolling at speed `vx` \[m/s\] (`ω_j = vx/R_e`, zero slip when driving straight).
    #[must_use]
    pub fn free_rolling(delta: f64, vx: f64, rolling_radius: f64) -> Self {
        Self { delta, omega: [vx / rolling_radius; WHEELS] }
    }

    /// As the input vector `[δ, ω_1..ω_6]`.
    #[must_use]
    pub fn to_dvector(&self) -> DVector<f64> {
        let mut u = DVector::zeros(INPUT_DIM);
        u[0] = self.delta;
        for j in 0..WHEELS {
            u[1 + j] = self.omega[j];
        }
        u
    }

    /// From the input vector `[δ, ω_1..ω_6]`.
    ///
    /// # Errors
    /// [`ModelError::DimensionMismatch`] naming `u` unless it has 7 entries.
    pub fn from_dvector(u: &DVector<f64>) -> Result<Self, ModelError> {
        check_dims("u", u, INPUT_DIM, 1)?;
        Ok(Self { delta: u[0], omega: std::array::from_fn(|j| u[1 + j]) })
    }

    /// The mirror image about the body's x axis: `δ → −δ`, left and right wheel speeds swapped.
    #[must_use]
    pub fn mirrored(&self) -> Self {
        let w = self.omega;
        Self { delta: -self.delta, omega: [w[1], w[0], w[3], w[2], w[5], w[4]] }
    }

    /// Checks that `δ` and every wheel speed are finite.
    ///
    /// # Errors
    /// [`TruckError::NonFiniteInput`] naming the input.
    pub fn validate(&self) -> Result<(), TruckError> {
        finite_input(INPUT_NAMES[0], self.delta)?;
        for j in 0..WHEELS {
            finite_input(INPUT_NAMES[1 + j], self.omega[j])?;
        }
        Ok(())
    }
}

/// Sideslip angle `β = atan(V_y/V_x)` \[rad\], paper eq (2) **\[P\]**.
///
/// # Errors
/// [`TruckError::NonFiniteInput`] for a non-finite speed, [`TruckError::NonPositiveSpeed`] for
/// `V_x ≤ 0`.
pub fn sideslip(vx: f64, vy: f64) -> Result<f64, TruckError> {
    finite_input(STATE_NAMES[0], vx)?;
    finite_input(STATE_NAMES[1], vy)?;
    if vx <= 0.0 {
        return Err(TruckError::NonPositiveSpeed { name: STATE_NAMES[0], value: vx });
    }
    Ok((vy / vx).atan())
}

/// Checks a body state: finite, and `V_x > 0` (a forward-driving model: `β` divides by `V_x`,
/// and the slip conventions assume forward motion).
pub(crate) fn check_body_state(x: [f64; 3]) -> Result<(), TruckError> {
    for i in 0..3 {
        finite_input(STATE_NAMES[i], x[i])?;
    }
    if x[0] <= 0.0 {
        return Err(TruckError::NonPositiveSpeed { name: STATE_NAMES[0], value: x[0] });
    }
    Ok(())
}

/// Sums of the body-axis tyre forces and yaw moment, and their gradients w.r.t. `x`.
#[derive(Debug, Clone, Copy, Default)]
struct BodyForces {
    /// `Σ F_Xj` \[N\].
    fx: f64,
    /// `Σ F_Yj` \[N\].
    fy: f64,
    /// `Σ (x_j·F_Yj − y_j·F_Xj)` \[N m\].
    mz: f64,
    /// `Σ GX_j`.
    grad_fx: [f64; 3],
    /// `Σ GY_j`.
    grad_fy: [f64; 3],
    /// `Σ (x_j·GY_j − y_j·GX_j)`.
    grad_mz: [f64; 3],
}

/// The continuous-time planar model of the estimator (paper eq (1), digest §2):
///
/// ```text
/// dV_x/dt = V_y·γ + (1/m)·Σ F_Xj
/// dV_y/dt = −V_x·γ + (1/m)·Σ F_Yj
/// dγ/dt   = (1/I_z)·Σ (x_j·F_Yj − y_j·F_Xj)
/// F_Xj = F_xj·cos δ_j − F_yj·sin δ_j,   F_Yj = F_xj·sin δ_j + F_yj·cos δ_j
/// F_xj = n_j·F_x0(F_zj/n_j, s_j),      F_yj = n_j·F_y0(F_zj/n_j, α_j)
/// ```
///
/// with static loads `F_zj` ([`TruckParams::static_loads`], **\[A\]**), `α_j` from the state and
/// `s_j` from the state and the measured wheel speeds (digest decision 1). Output
/// `y = [V_x, a_y, γ]` with `a_y = Σ F_Yj / m` (14), the accelerometer at the CG without gravity
/// or roll (decision 7). As a [`ContinuousModel`] its input is `[δ, ω_1..ω_6]`; evaluations do
/// not allocate.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanarTruck {
    params: TruckParams,
    geometry: Geometry,
    loads: [f64; WHEELS],
    curves: [LumpedCurves; WHEELS],
}

impl PlanarTruck {
    /// Validates `params` and precomputes the geometry, the static loads and the tyre curves at
    /// those loads.
    ///
    /// # Errors
    /// The validation error naming the parameter ([`TruckParams::validate`]).
    pub fn new(params: TruckParams) -> Result<Self, TruckError> {
        params.validate()?;
        let (geometry, loads) = (Geometry::new(&params), params.static_loads());
        let mut curves = [params.tyre.lumped_curves(geometry.tyres[0], loads[0])?; WHEELS];
        for (j, c) in curves.iter_mut().enumerate().skip(1) {
            *c = params.tyre.lumped_curves(geometry.tyres[j], loads[j])?;
        }
        Ok(Self { geometry, loads, curves, params })
    }

    /// The tyre curves of each wheel position at its static load.
    pub(crate) fn curves(&self) -> &[LumpedCurves; WHEELS] {
        &self.curves
    }

    /// The validated parameters.
    #[must_use]
    pub fn params(&self) -> &TruckParams {
        &self.params
    }

    /// The wheel geometry.
    #[must_use]
    pub fn geometry(&self) -> &Geometry {
        &self.geometry
    }

    /// The static loads `F_zj` \[N\] the model uses.
    #[must_use]
    pub fn static_loads(&self) -> [f64; WHEELS] {
        self.loads
    }

    /// The body forces and (with `gradients`) their gradients. With `lateral_only` only `F_Y` and
    /// its gradient are computed (`F_X`, `M_Z` stay 0): an unsteered wheel's longitudinal force
    /// does not enter `ΣF_Y`, so its curve is not evaluated (its slip is still checked).
    fn body_forces(
        &self,
        x: [f64; 3],
        input: &TruckInput,
        gradients: bool,
        lateral_only: bool,
    ) -> Result<BodyForces, TruckError> {
        check_body_state(x)?;
        input.validate()?;
        let p = &self.params;
        let g = &self.geometry;
        let mut out = BodyForces::default();
        for j in 0..WHEELS {
            let k = wheel_kinematics(g, j, x, input.delta, input.omega[j], p.rolling_radius, p.min_speed);
            if lateral_only && !g.steered[j] {
                // sin δ = 0, cos δ = 1: F_Y = F_y, ∂F_Y = ∂F_y.
                finite_input("s (tyre slip ratio)", k.slip)?;
                let fy = self.curves[j].lateral(k.alpha)?;
                out.fy += fy.force;
                if gradients {
                    let grad = wheel_gradients(g, j, &k, p.min_speed);
                    for i in 0..3 {
                        out.grad_fy[i] += fy.slope * grad.alpha[i];
                    }
                }
                continue;
            }
            let fx = self.curves[j].longitudinal(k.slip)?;
            let fy = self.curves[j].lateral(k.alpha)?;
            let (c, s) = (k.cos_delta, k.sin_delta);
            let big_x = fx.force * c - fy.force * s;
            let big_y = fx.force * s + fy.force * c;
            out.fx += big_x;
            out.fy += big_y;
            out.mz += g.x[j] * big_y - g.y[j] * big_x;
            if gradients {
                let grad = wheel_gradients(g, j, &k, p.min_speed);
                for i in 0..3 {
                    let dfx = fx.slope * grad.slip[i];
                    let dfy = fy.slope * grad.alpha[i];
                    let gx = c * dfx - s * dfy;
                    let gy = s * dfx + c * dfy;
                    out.grad_fx[i] += gx;
                    out.grad_fy[i] += gy;
                    out.grad_mz[i] += g.x[j] * gy - g.y[j] * gx;
                }
            }
        }
        Ok(out)
    }

    /// `ẋ = f_c(x, u)`, eq (1).
    ///
    /// # Errors
    /// [`TruckError::NonFiniteInput`] naming a non-finite state or input,
    /// [`TruckError::NonPositiveSpeed`] for `V_x ≤ 0`, [`TruckError::TyreOutOfRange`].
    pub fn derivative(&self, x: &Vector3<f64>, input: &TruckInput) -> Result<Vector3<f64>, TruckError> {
        let f = self.body_forces([x[0], x[1], x[2]], input, false, false)?;
        Ok(self.derivative_from(x, &f))
    }

    fn derivative_from(&self, x: &Vector3<f64>, f: &BodyForces) -> Vector3<f64> {
        let (m, iz) = (self.params.mass, self.params.yaw_inertia);
        Vector3::new(x[1] * x[2] + f.fx / m, -x[0] * x[2] + f.fy / m, f.mz / iz)
    }

    /// Lateral acceleration at the CG `a_y = Σ F_Yj / m` \[m/s²\] (14).
    ///
    /// # Errors
    /// As [`PlanarTruck::derivative`].
    pub fn lateral_acceleration(&self, x: &Vector3<f64>, input: &TruckInput) -> Result<f64, TruckError> {
        Ok(self.body_forces([x[0], x[1], x[2]], input, false, true)?.fy / self.params.mass)
    }

    /// The measurement `h(x, u) = [V_x, a_y, γ]` (14).
    ///
    /// # Errors
    /// As [`PlanarTruck::derivative`].
    pub fn measurement(&self, x: &Vector3<f64>, input: &TruckInput) -> Result<Vector3<f64>, TruckError> {
        Ok(Vector3::new(x[0], self.lateral_acceleration(x, input)?, x[2]))
    }

    /// `J = ∂f_c/∂x` (the continuous part of eq (13), digest §3):
    ///
    /// ```text
    /// row 1 = [ΣGX_Vx/m, γ + ΣGX_Vy/m, V_y + ΣGX_γ/m]
    /// row 2 = [−γ + ΣGY_Vx/m, ΣGY_Vy/m, −V_x + ΣGY_γ/m]
    /// row 3 = Σ (x_j·GY_j − y_j·GX_j) / I_z
    /// GX_j = cos δ_j·∂F_xj − sin δ_j·∂F_yj,  GY_j = sin δ_j·∂F_xj + cos δ_j·∂F_yj
    /// ∂F_yj = C_αj·∂α_j,  ∂F_xj = C_sj·∂s_j   (slopes of the lumped tyre, see [`crate::kinematics`])
    /// ```
    ///
    /// # Errors
    /// As [`PlanarTruck::derivative`].
    pub fn jacobian(&self, x: &Vector3<f64>, input: &TruckInput) -> Result<Matrix3<f64>, TruckError> {
        let f = self.body_forces([x[0], x[1], x[2]], input, true, false)?;
        Ok(self.jacobian_from(x, &f))
    }

    fn jacobian_from(&self, x: &Vector3<f64>, f: &BodyForces) -> Matrix3<f64> {
        let (m, iz) = (self.params.mass, self.params.yaw_inertia);
        let (gx, gy, gm) = (&f.grad_fx, &f.grad_fy, &f.grad_mz);
        Matrix3::new(
            gx[0] / m,
            x[2] + gx[1] / m,
            x[1] + gx[2] / m,
            -x[2] + gy[0] / m,
            gy[1] / m,
            -x[0] + gy[2] / m,
            gm[0] / iz,
            gm[1] / iz,
            gm[2] / iz,
        )
    }

    /// `H = ∂h/∂x = [[1, 0, 0], [ΣGY_Vx/m, ΣGY_Vy/m, ΣGY_γ/m], [0, 0, 1]]` (15).
    ///
    /// # Errors
    /// As [`PlanarTruck::derivative`].
    pub fn measurement_jacobian(&self, x: &Vector3<f64>, input: &TruckInput) -> Result<Matrix3<f64>, TruckError> {
        let f = self.body_forces([x[0], x[1], x[2]], input, true, true)?;
        Ok(self.measurement_jacobian_from(&f))
    }

    fn measurement_jacobian_from(&self, f: &BodyForces) -> Matrix3<f64> {
        let m = self.params.mass;
        let gy = &f.grad_fy;
        Matrix3::new(1.0, 0.0, 0.0, gy[0] / m, gy[1] / m, gy[2] / m, 0.0, 0.0, 1.0)
    }
}

/// Reads `x` and `u` from the generic vectors (dimensions checked, no allocation).
fn read(x: &DVector<f64>, u: &DVector<f64>) -> Result<(Vector3<f64>, TruckInput), ModelError> {
    check_dims("x", x, STATE_DIM, 1)?;
    let input = TruckInput::from_dvector(u)?;
    Ok((Vector3::new(x[0], x[1], x[2]), input))
}

fn write_vec(what: &str, out: &mut DVector<f64>, v: &Vector3<f64>) -> Result<(), ModelError> {
    check_dims(what, out, 3, 1)?;
    out.copy_from(v);
    Ok(())
}

fn write_mat(what: &str, out: &mut DMatrix<f64>, m: &Matrix3<f64>) -> Result<(), ModelError> {
    check_dims(what, out, 3, 3)?;
    out.copy_from(m);
    Ok(())
}

impl ContinuousModel for PlanarTruck {
    fn dims(&self) -> Dims {
        Dims::new(STATE_DIM, INPUT_DIM, OUTPUT_DIM)
    }
    fn derivative(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        let (x, input) = read(x, u)?;
        write_vec("dx/dt", out, &PlanarTruck::derivative(self, &x, &input)?)
    }
    fn output(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        let (x, input) = read(x, u)?;
        write_vec("y", out, &self.measurement(&x, &input)?)
    }
}

impl DifferentiableContinuousModel for PlanarTruck {
    fn derivative_jacobian(
        &self,
        x: &DVector<f64>,
        u: &DVector<f64>,
        out: &mut DMatrix<f64>,
    ) -> Result<(), ModelError> {
        let (x, input) = read(x, u)?;
        write_mat("df/dx", out, &self.jacobian(&x, &input)?)
    }
    fn output_jacobian(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        let (x, input) = read(x, u)?;
        write_mat("dh/dx", out, &self.measurement_jacobian(&x, &input)?)
    }
}

/// The EKF's discrete model: forward Euler at `T` (paper (12), `T = 1 ms` **\[P\]**),
/// `x_{k+1} = x_k + T·f_c(x_k, u_k)`, `F = A = I + T·J` (13), measurement (14) and `H` (15).
/// Implements [`DiscreteModel`] and [`DifferentiableModel`] with input `[δ, ω_1..ω_6]`; `f`,
/// `h` and both Jacobians write into the caller's buffers without allocating.
#[derive(Debug, Clone, PartialEq)]
pub struct TruckEkfModel {
    planar: PlanarTruck,
    ts: f64,
    /// The tyre curves enclosed in intervals, for [`models::SecondOrderModel`].
    enclosed: [EnclosedWheel; WHEELS],
}

impl TruckEkfModel {
    /// Validates `params` and the period `ts` \[s\].
    ///
    /// # Errors
    /// The parameter validation error, or [`ModelError::InvalidSamplingPeriod`] (as
    /// [`TruckError::Model`]) unless `ts` is positive and finite.
    pub fn new(params: TruckParams, ts: f64) -> Result<Self, TruckError> {
        if !(ts.is_finite() && ts > 0.0) {
            return Err(ModelError::InvalidSamplingPeriod(ts).into());
        }
        let planar = PlanarTruck::new(params)?;
        Ok(Self { enclosed: enclosed_curves(planar.curves()), planar, ts })
    }

    /// At the paper's period `T = 1 ms` ([`PAPER_SAMPLE_PERIOD`]).
    ///
    /// # Errors
    /// As [`TruckEkfModel::new`].
    pub fn paper(params: TruckParams) -> Result<Self, TruckError> {
        Self::new(params, PAPER_SAMPLE_PERIOD)
    }

    /// The continuous model.
    #[must_use]
    pub fn planar(&self) -> &PlanarTruck {
        &self.planar
    }

    /// The period `T` \[s\].
    #[must_use]
    pub fn ts(&self) -> f64 {
        self.ts
    }

    /// The tyre curves of each wheel position, enclosed.
    pub(crate) fn enclosed_curves(&self) -> &[EnclosedWheel; WHEELS] {
        &self.enclosed
    }

    /// One Euler step `x + T·f_c(x, u)` (12).
    ///
    /// # Errors
    /// As [`PlanarTruck::derivative`].
    pub fn step(&self, x: &Vector3<f64>, input: &TruckInput) -> Result<Vector3<f64>, TruckError> {
        Ok(x + self.planar.derivative(x, input)? * self.ts)
    }

    /// `A = I + T·J` (13).
    ///
    /// # Errors
    /// As [`PlanarTruck::derivative`].
    pub fn transition_jacobian(&self, x: &Vector3<f64>, input: &TruckInput) -> Result<Matrix3<f64>, TruckError> {
        Ok(Matrix3::identity() + self.planar.jacobian(x, input)? * self.ts)
    }
}

impl DiscreteModel for TruckEkfModel {
    fn dims(&self) -> Dims {
        Dims::new(STATE_DIM, INPUT_DIM, OUTPUT_DIM)
    }
    fn f(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        let (x, input) = read(x, u)?;
        write_vec("f(x, u)", out, &self.step(&x, &input)?)
    }
    fn h(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        let (x, input) = read(x, u)?;
        write_vec("h(x, u)", out, &self.planar.measurement(&x, &input)?)
    }
}

impl DifferentiableModel for TruckEkfModel {
    fn f_jacobian(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        let (x, input) = read(x, u)?;
        write_mat("F", out, &self.transition_jacobian(&x, &input)?)
    }
    fn h_jacobian(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        let (x, input) = read(x, u)?;
        write_mat("H", out, &self.planar.measurement_jacobian(&x, &input)?)
    }

    /// One evaluation of the tyre forces and their slopes for both `f` and `F` (the EKF's
    /// prediction).
    fn f_with_jacobian(
        &self,
        x: &DVector<f64>,
        u: &DVector<f64>,
        out: &mut DVector<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<(), ModelError> {
        let (x, input) = read(x, u)?;
        let forces = self.planar.body_forces([x[0], x[1], x[2]], &input, true, false)?;
        let next = x + self.planar.derivative_from(&x, &forces) * self.ts;
        let jac = Matrix3::identity() + self.planar.jacobian_from(&x, &forces) * self.ts;
        check_dims("F", jacobian, 3, 3)?;
        write_vec("f(x, u)", out, &next)?;
        jacobian.copy_from(&jac);
        Ok(())
    }

    /// One evaluation of the tyre forces and their slopes for both `h` and `H` (the EKF's update).
    fn h_with_jacobian(
        &self,
        x: &DVector<f64>,
        u: &DVector<f64>,
        out: &mut DVector<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<(), ModelError> {
        let (x, input) = read(x, u)?;
        let forces = self.planar.body_forces([x[0], x[1], x[2]], &input, true, true)?;
        let y = Vector3::new(x[0], forces.fy / self.planar.params.mass, x[2]);
        let h = self.planar.measurement_jacobian_from(&forces);
        check_dims("H", jacobian, 3, 3)?;
        write_vec("h(x, u)", out, &y)?;
        jacobian.copy_from(&h);
        Ok(())
    }
}

impl models::AnyModel for TruckEkfModel {
    fn discrete(&self) -> &dyn models::DiscreteModel {
        self
    }
    fn differentiable(&self) -> Option<&dyn models::DifferentiableModel> {
        Some(self)
    }
    fn second_order(&self) -> Option<&dyn models::SecondOrderModel> {
        Some(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use models::check_jacobians;

    fn model() -> TruckEkfModel {
        TruckEkfModel::paper(TruckParams::digest_preset()).unwrap()
    }

    /// States and inputs covering straight running, cornering both ways, drive slip on the rear
    /// axles, brake slip on the front axle and a large sideslip.
    fn cases() -> Vec<(Vector3<f64>, TruckInput)> {
        let re = TruckParams::digest_preset().rolling_radius;
        let v = 70.0 / 3.6;
        let w = |f: [f64; 6]| f.map(|k| k * v / re);
        vec![
            // Off the free-rolling surface |ωR_e| = |v_l|, where s is C¹ but not C² (central
            // differences are only first-order accurate there).
            (
                Vector3::new(v, 0.0, 0.0),
                TruckInput { delta: 0.0, omega: w([0.9995, 0.9995, 1.002, 1.002, 1.002, 1.002]) },
            ),
            (
                Vector3::new(v, 0.12, 0.08),
                TruckInput { delta: 0.02, omega: w([0.995, 0.998, 1.004, 1.006, 1.003, 1.005]) },
            ),
            (
                Vector3::new(v, -0.3, -0.09),
                TruckInput { delta: -0.026, omega: w([0.99, 0.985, 1.01, 1.02, 1.015, 1.012]) },
            ),
            (Vector3::new(8.0, 0.6, 0.25), TruckInput { delta: 0.12, omega: [14.0, 16.0, 16.5, 17.5, 16.0, 17.0] }),
            (Vector3::new(25.0, -1.5, 0.05), TruckInput { delta: 0.08, omega: [45.0, 44.0, 49.0, 50.0, 48.0, 49.5] }),
        ]
    }

    /// Central differences of the continuous derivative and of `a_y`, relative to the largest
    /// entry of the analytic matrix.
    #[test]
    fn analytic_j_and_h_match_central_differences_to_1e_7() {
        let m = model();
        let p = m.planar();
        for (x, input) in cases() {
            let j = p.jacobian(&x, &input).unwrap();
            let h = p.measurement_jacobian(&x, &input).unwrap();
            let (mut jfd, mut hfd) = (Matrix3::zeros(), Matrix3::zeros());
            for i in 0..3 {
                let step = 1e-6 * x[i].abs().max(1.0);
                let (mut xp, mut xm) = (x, x);
                xp[i] += step;
                xm[i] -= step;
                let d = (p.derivative(&xp, &input).unwrap() - p.derivative(&xm, &input).unwrap()) / (2.0 * step);
                jfd.set_column(i, &d);
                let y = (p.measurement(&xp, &input).unwrap() - p.measurement(&xm, &input).unwrap()) / (2.0 * step);
                hfd.set_column(i, &y);
            }
            let ej = (j - jfd).amax() / jfd.amax();
            let eh = (h - hfd).amax() / hfd.amax();
            assert!(ej < 1e-7, "J at {x:?}, {input:?}: rel error {ej}\n{j}\n{jfd}");
            assert!(eh < 1e-7, "H at {x:?}, {input:?}: rel error {eh}\n{h}\n{hfd}");
            // The generic check of the discrete model (F = I + T J, H).
            let c = check_jacobians(&m, &DVector::from_column_slice(x.as_slice()), &input.to_dvector()).unwrap();
            assert!(c.f_error < 1e-7 && c.h_error < 1e-7, "{c:?}");
        }
    }

    #[test]
    fn euler_step_and_trait_buffers() {
        let m = model();
        for (x, input) in cases() {
            let (xd, ud) = (DVector::from_column_slice(x.as_slice()), input.to_dvector());
            let mut out = DVector::zeros(3);
            m.f(&xd, &ud, &mut out).unwrap();
            let want = x + m.planar().derivative(&x, &input).unwrap() * 1e-3;
            assert_eq!(out.as_slice(), want.as_slice());
            m.h(&xd, &ud, &mut out).unwrap();
            assert_eq!(out[0], x[0]);
            assert_eq!(out[2], x[2]);
            let mut fj = DMatrix::zeros(3, 3);
            m.f_jacobian(&xd, &ud, &mut fj).unwrap();
            let a = m.transition_jacobian(&x, &input).unwrap();
            assert_eq!(fj.as_slice(), a.as_slice());
            // a_y = dV_y/dt + V_x γ.
            let d = m.planar().derivative(&x, &input).unwrap();
            assert!((out[1] - (d[1] + x[0] * x[2])).abs() < 1e-12);
        }
        let (x, u) = (DVector::from_element(3, 10.0), DVector::from_element(7, 19.0));
        let e = m.f(&x, &u, &mut DVector::zeros(4)).unwrap_err();
        assert_eq!(e.to_string(), "f(x, u): expected 3x1, got 4x1");
        let e = m.h(&x, &DVector::zeros(6), &mut DVector::zeros(3)).unwrap_err();
        assert_eq!(e.to_string(), "u: expected 7x1, got 6x1");
        let e = m.f_jacobian(&x, &u, &mut DMatrix::zeros(2, 3)).unwrap_err();
        assert_eq!(e.to_string(), "F: expected 3x3, got 2x3");
    }

    #[test]
    fn the_continuous_model_discretises_through_models() {
        use models::{Discretized, Integrator};
        let m = model();
        let euler = Discretized::new(m.planar().clone(), 1e-3, Integrator::Euler).unwrap();
        let rk4 = Discretized::new(m.planar().clone(), 1e-3, Integrator::Rk4 { substeps: 1 }).unwrap();
        for (x, input) in cases() {
            let (xd, ud) = (DVector::from_column_slice(x.as_slice()), input.to_dvector());
            let (mut a, mut b) = (DVector::zeros(3), DVector::zeros(3));
            m.f(&xd, &ud, &mut a).unwrap();
            euler.f(&xd, &ud, &mut b).unwrap();
            assert!((&a - &b).amax() < 1e-12);
            let (mut fa, mut fb) = (DMatrix::zeros(3, 3), DMatrix::zeros(3, 3));
            m.f_jacobian(&xd, &ud, &mut fa).unwrap();
            euler.f_jacobian(&xd, &ud, &mut fb).unwrap();
            assert!((&fa - &fb).amax() < 1e-12);
            // RK4 differs from Euler by O(T²) and its chained Jacobian is consistent too.
            rk4.f(&xd, &ud, &mut b).unwrap();
            assert!((&a - &b).amax() < 1e-4);
            let c = check_jacobians(&rk4, &xd, &ud).unwrap();
            assert!(c.f_error < 1e-7 && c.h_error < 1e-7, "{c:?}");
        }
    }

    #[test]
    fn mirroring_the_steering_mirrors_vy_and_yaw_rate() {
        let p = model();
        let p = p.planar();
        for (x, input) in cases() {
            let mx = Vector3::new(x[0], -x[1], -x[2]);
            let d = p.derivative(&x, &input).unwrap();
            let md = p.derivative(&mx, &input.mirrored()).unwrap();
            let tol = 1e-12 * d.amax().max(1.0);
            assert!((d[0] - md[0]).abs() < tol && (d[1] + md[1]).abs() < tol && (d[2] + md[2]).abs() < tol);
            let ay = p.lateral_acceleration(&x, &input).unwrap();
            assert!((ay + p.lateral_acceleration(&mx, &input.mirrored()).unwrap()).abs() < tol);
        }
        // A left steer gives a left (positive) yaw acceleration and lateral acceleration.
        let v = 19.44;
        let input = TruckInput::free_rolling(0.02, v, 0.52);
        let d = p.derivative(&Vector3::new(v, 0.0, 0.0), &input).unwrap();
        assert!(d[2] > 0.0 && p.lateral_acceleration(&Vector3::new(v, 0.0, 0.0), &input).unwrap() > 0.0);
    }

    #[test]
    fn bad_states_and_inputs_are_named_errors() {
        let m = model();
        let x = DVector::from_vec(vec![19.44, 0.0, 0.0]);
        let u = TruckInput::free_rolling(0.0, 19.44, 0.52).to_dvector();
        let mut out = DVector::zeros(3);
        let expect = |r: Result<(), ModelError>, what: &str| {
            let e = r.unwrap_err();
            assert!(matches!(e, ModelError::Evaluation(_)), "{e:?}");
            assert!(e.to_string().contains(what), "{e} lacks {what}");
        };
        let mut bad = u.clone();
        bad[0] = f64::NAN;
        expect(m.f(&x, &bad, &mut out), "delta (road-wheel angle) must be finite");
        let mut bad = u.clone();
        bad[4] = f64::NAN;
        expect(m.h(&x, &bad, &mut out), "omega_R2 (wheel speed) must be finite");
        for vx in [0.0, -3.0] {
            let xb = DVector::from_vec(vec![vx, 0.0, 0.0]);
            expect(m.f(&xb, &u, &mut out), "V_x (longitudinal speed) must be positive");
            expect(m.f_jacobian(&xb, &u, &mut DMatrix::zeros(3, 3)), "V_x (longitudinal speed) must be positive");
        }
        let xb = DVector::from_vec(vec![19.0, f64::INFINITY, 0.0]);
        expect(m.h_jacobian(&xb, &u, &mut DMatrix::zeros(3, 3)), "V_y (lateral speed) must be finite");
        let e = TruckEkfModel::new(TruckParams::digest_preset(), 0.0).unwrap_err();
        assert_eq!(e.to_string(), "sampling period T_s must be positive and finite, got 0");
        let e = TruckEkfModel::paper(TruckParams { rolling_radius: 0.0, ..TruckParams::digest_preset() }).unwrap_err();
        assert!(e.to_string().contains("R_e (effective rolling radius) must be positive"));
        assert!(matches!(sideslip(0.0, 1.0), Err(TruckError::NonPositiveSpeed { .. })));
        assert!((sideslip(20.0, 0.2).unwrap() - 0.01f64.atan()).abs() < 1e-15);
    }

    #[test]
    fn free_rolling_straight_gives_no_force() {
        let p = model();
        let d =
            p.planar().derivative(&Vector3::new(19.44, 0.0, 0.0), &TruckInput::free_rolling(0.0, 19.44, 0.52)).unwrap();
        assert!(d.amax() < 1e-9, "{d}");
    }

    #[test]
    fn combined_evaluations_equal_the_separate_ones() {
        let m = model();
        for (x, input) in cases() {
            let (xv, uv) = (DVector::from_column_slice(x.as_slice()), input.to_dvector());
            let (mut f1, mut f2) = (DVector::zeros(3), DVector::zeros(3));
            let (mut j1, mut j2) = (DMatrix::zeros(3, 3), DMatrix::zeros(3, 3));
            m.f(&xv, &uv, &mut f1).unwrap();
            m.f_jacobian(&xv, &uv, &mut j1).unwrap();
            m.f_with_jacobian(&xv, &uv, &mut f2, &mut j2).unwrap();
            assert_eq!((&f1, &j1), (&f2, &j2));
            m.h(&xv, &uv, &mut f1).unwrap();
            m.h_jacobian(&xv, &uv, &mut j1).unwrap();
            m.h_with_jacobian(&xv, &uv, &mut f2, &mut j2).unwrap();
            assert_eq!((&f1, &j1), (&f2, &j2));
        }
    }
}
