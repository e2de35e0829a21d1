//! The low-speed 3-DOF model in the canonical form of docs/dp-vessel.md (5)–(14)
//! (reconstructed):
//!
//! ```text
//! x = [x, y, ψ, u, v, r],   τ = [τ_X, τ_Y, τ_N],   y = h(x) = [x, y, ψ]   (15)
//! ẋ = f(x) + g(x) τ:  η' = R(ψ) ν,   ν' = M⁻¹ (τ − D ν)                    (1)–(4)
//! ```
//!
//! [`Vessel`] is the continuous model ([`models::DifferentiableContinuousModel`]);
//! [`DiscreteVessel`] its sampled version, Euler at `δ = 0.1 s` as the paper's discrete model
//! (16)–(20) `F(x, τ) = x + δ (f(x) + g(x) τ)` or RK4 as an option, through
//! [`models::Discretized`]. Heading is not wrapped (the experiment stays near 0°).

use models::error::{check_dims, check_finite};
use models::{
    Angles, ContinuousModel, DifferentiableContinuousModel, DifferentiableModel, Dims, DiscreteModel, Discretized,
    Integrator, ModelError,
};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

use crate::error::VesselError;
use crate::params::{SiMatrices, VesselParams};

/// States `[x (north, m), y (east, m), ψ (heading, rad), u (surge, m/s), v (sway, m/s), r (yaw rate, rad/s)]`.
pub const STATE_DIM: usize = 6;
/// Inputs `[τ_X (surge force, N), τ_Y (sway force, N), τ_N (yaw moment, N m)]`.
pub const INPUT_DIM: usize = 3;
/// Outputs `[x, y, ψ]` (15).
pub const OUTPUT_DIM: usize = 3;
/// The paper's sampling period `δ = 0.1 s` **\[P\]**.
pub const PAPER_SAMPLE_PERIOD: f64 = 0.1;
/// State names for tables and figures.
pub const STATE_NAMES: [&str; STATE_DIM] = ["x", "y", "psi", "u", "v", "r"];

/// The rotation `R(ψ)` from body to earth-fixed (north-east) axes, (1)–(4).
#[must_use]
pub fn rotation(psi: f64) -> Matrix3<f64> {
    let (s, c) = psi.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

/// The continuous low-speed model `η' = R(ψ) ν`, `M ν' + D ν = τ` with validated SI matrices.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vessel {
    params: VesselParams,
    si: SiMatrices,
}

fn check_state_input(x: &DVector<f64>, u: &DVector<f64>) -> Result<(), ModelError> {
    check_dims("x", x, STATE_DIM, 1)?;
    check_dims("u (tau)", u, INPUT_DIM, 1)?;
    check_finite("x", x)?;
    check_finite("u (tau)", u)
}

impl Vessel {
    /// The model of `params`.
    ///
    /// # Errors
    /// As [`VesselParams::validate`].
    pub fn new(params: VesselParams) -> Result<Self, VesselError> {
        let si = params.validate()?;
        Ok(Self { params, si })
    }

    /// The parameters.
    #[must_use]
    pub fn params(&self) -> &VesselParams {
        &self.params
    }

    /// The SI matrices `M`, `D`, `M⁻¹`, `M⁻¹ D`.
    #[must_use]
    pub fn matrices(&self) -> &SiMatrices {
        &self.si
    }

    /// `(η', ν')` at `(x, τ)` without checks (fixed-size; the checked path is
    /// [`ContinuousModel::derivative`]).
    #[must_use]
    pub fn derivative_parts(&self, x: &[f64; STATE_DIM], tau: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
        let nu = Vector3::new(x[3], x[4], x[5]);
        let eta_dot = rotation(x[2]) * nu;
        let nu_dot = self.si.m_inv * tau - self.si.m_inv_d * nu;
        (eta_dot, nu_dot)
    }

    /// Samples the model at `ts` with `integrator` (Euler is the paper's (16)–(20)).
    ///
    /// # Errors
    /// [`VesselError::Model`] for an invalid period or RK4 without sub-steps.
    pub fn discretize(self, ts: f64, integrator: Integrator) -> Result<DiscreteVessel, VesselError> {
        Ok(DiscreteVessel { inner: Discretized::new(self, ts, integrator)? })
    }
}

impl ContinuousModel for Vessel {
    fn dims(&self) -> Dims {
        Dims::new(STATE_DIM, INPUT_DIM, OUTPUT_DIM)
    }

    /// `ẋ = f(x) + g(x) τ` (5)–(14). Allocation-free.
    fn derivative(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        check_state_input(x, u)?;
        check_dims("dx/dt", out, STATE_DIM, 1)?;
        let xs: [f64; STATE_DIM] = std::array::from_fn(|i| x[i]);
        let (eta_dot, nu_dot) = self.derivative_parts(&xs, &Vector3::new(u[0], u[1], u[2]));
        for i in 0..3 {
            out[i] = eta_dot[i];
            out[3 + i] = nu_dot[i];
        }
        Ok(())
    }

    /// `h(x) = [x, y, ψ]` (15).
    fn output(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        check_dims("x", x, STATE_DIM, 1)?;
        check_dims("h(x)", out, OUTPUT_DIM, 1)?;
        check_finite("x", x)?;
        for i in 0..OUTPUT_DIM {
            out[i] = x[i];
        }
        Ok(())
    }

    /// The heading `ψ`: state 2 and output 2.
    fn angles(&self) -> Angles<'_> {
        VESSEL_ANGLES
    }
}

/// The vessel's angles: the heading `ψ` (state 2, output 2).
pub const VESSEL_ANGLES: Angles<'static> = Angles::new(&[2], &[2]);

impl DifferentiableContinuousModel for Vessel {
    /// `∂f/∂x`: the kinematic rows `∂(R(ψ) ν)/∂(ψ, ν)` and the kinetic block `−M⁻¹ D`
    /// (`g(x) τ` does not depend on `x`). Allocation-free.
    fn derivative_jacobian(
        &self,
        x: &DVector<f64>,
        u: &DVector<f64>,
        out: &mut DMatrix<f64>,
    ) -> Result<(), ModelError> {
        check_state_input(x, u)?;
        check_dims("df/dx", out, STATE_DIM, STATE_DIM)?;
        out.fill(0.0);
        let (s, c) = x[2].sin_cos();
        let (uu, vv) = (x[3], x[4]);
        out[(0, 2)] = -uu * s - vv * c;
        out[(0, 3)] = c;
        out[(0, 4)] = -s;
        out[(1, 2)] = uu * c - vv * s;
        out[(1, 3)] = s;
        out[(1, 4)] = c;
        out[(2, 5)] = 1.0;
        for i in 0..3 {
            for j in 0..3 {
                out[(3 + i, 3 + j)] = -self.si.m_inv_d[(i, j)];
            }
        }
        Ok(())
    }

    /// `∂h/∂x = [I₃ 0]`.
    fn output_jacobian(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        check_dims("x", x, STATE_DIM, 1)?;
        check_dims("dh/dx", out, OUTPUT_DIM, STATE_DIM)?;
        out.fill(0.0);
        for i in 0..OUTPUT_DIM {
            out[(i, i)] = 1.0;
        }
        Ok(())
    }
}

/// The sampled vessel `x_{k+1} = F(x_k, τ_k)`, `y = h(x)`: Euler (the paper's (16)–(20);
/// allocation-free) or RK4 (allocates its stages per call), with the exact Jacobian of the
/// scheme.
#[derive(Debug, Clone)]
pub struct DiscreteVessel {
    inner: Discretized<Vessel>,
}

impl DiscreteVessel {
    /// The paper's discrete model: Euler at `δ = 0.1 s` (16)–(20).
    ///
    /// # Errors
    /// As [`Vessel::new`].
    pub fn paper(params: VesselParams) -> Result<Self, VesselError> {
        Vessel::new(params)?.discretize(PAPER_SAMPLE_PERIOD, Integrator::Euler)
    }

    /// The continuous model.
    #[must_use]
    pub fn vessel(&self) -> &Vessel {
        self.inner.continuous()
    }

    /// The sampling period `δ`.
    #[must_use]
    pub fn ts(&self) -> f64 {
        self.inner.ts()
    }

    /// The integrator.
    #[must_use]
    pub fn integrator(&self) -> Integrator {
        self.inner.integrator()
    }
}

impl DiscreteModel for DiscreteVessel {
    fn dims(&self) -> Dims {
        Dims::new(STATE_DIM, INPUT_DIM, OUTPUT_DIM)
    }
    fn f(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        self.inner.f(x, u, out)
    }
    fn h(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        self.inner.h(x, u, out)
    }
    fn angles(&self) -> Angles<'_> {
        VESSEL_ANGLES
    }
}

impl DifferentiableModel for DiscreteVessel {
    /// Euler: `I + δ ∂f/∂x`; RK4: the chain rule through the stages.
    fn f_jacobian(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        self.inner.f_jacobian(x, u, out)
    }
    fn h_jacobian(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        self.inner.h_jacobian(x, u, out)
    }
}

impl models::AnyModel for DiscreteVessel {
    fn discrete(&self) -> &dyn models::DiscreteModel {
        self
    }
    fn differentiable(&self) -> Option<&dyn models::DifferentiableModel> {
        Some(self)
    }
    /// The Euler model's enclosures (crate::enclosure); none for RK4.
    fn second_order(&self) -> Option<&dyn models::SecondOrderModel> {
        if self.has_enclosures() { Some(self) } else { None }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use models::check_jacobians;

    fn state() -> DVector<f64> {
        DVector::from_vec(vec![12.0, -7.0, 0.7, 0.8, -0.3, 0.02])
    }
    fn tau() -> DVector<f64> {
        DVector::from_vec(vec![3e5, -1e5, 2e6])
    }

    #[test]
    fn euler_step_is_the_papers_formula() {
        let model = DiscreteVessel::paper(VesselParams::paper()).unwrap();
        let si = *model.vessel().matrices();
        let (x, t) = (state(), tau());
        let mut next = DVector::zeros(6);
        model.f(&x, &t, &mut next).unwrap();
        // The digest's f written out (5)–(14), with diagonal M (m23 = m32 = 0).
        let (psi, u, v, r) = (x[2], x[3], x[4], x[5]);
        let (m, d) = (si.m, si.d);
        let f = [
            u * psi.cos() - v * psi.sin(),
            u * psi.sin() + v * psi.cos(),
            r,
            (t[0] - d[(0, 0)] * u) / m[(0, 0)],
            (t[1] - d[(1, 1)] * v - d[(1, 2)] * r) / m[(1, 1)],
            (t[2] - d[(2, 1)] * v - d[(2, 2)] * r) / m[(2, 2)],
        ];
        for i in 0..6 {
            let want = x[i] + 0.1 * f[i];
            assert!((next[i] - want).abs() <= 1e-14 * want.abs().max(1.0), "state {i}");
        }
        let mut y = DVector::zeros(3);
        model.h(&x, &t, &mut y).unwrap();
        assert_eq!(y.as_slice(), &x.as_slice()[..3]);
    }

    #[test]
    fn jacobians_match_finite_differences() {
        for integrator in [Integrator::Euler, Integrator::Rk4 { substeps: 2 }] {
            let model = Vessel::new(VesselParams::paper()).unwrap().discretize(0.1, integrator).unwrap();
            for psi in [0.0, 0.7, -2.5] {
                let mut x = state();
                x[2] = psi;
                let check = check_jacobians(&model, &x, &tau()).unwrap();
                assert!(check.f_error < 1e-8 && check.h_error < 1e-10, "{integrator:?} psi {psi}: {check:?}");
            }
        }
    }

    /// RK4 and Euler agree to first order in δ; RK4 with more sub-steps converges.
    #[test]
    fn rk4_converges_and_euler_is_first_order() {
        let fine =
            Vessel::new(VesselParams::paper()).unwrap().discretize(1.0, Integrator::Rk4 { substeps: 64 }).unwrap();
        let rk = Vessel::new(VesselParams::paper()).unwrap().discretize(1.0, Integrator::Rk4 { substeps: 2 }).unwrap();
        let eu = Vessel::new(VesselParams::paper()).unwrap().discretize(1.0, Integrator::Euler).unwrap();
        let (x, t) = (state(), tau());
        let (mut a, mut b, mut c) = (DVector::zeros(6), DVector::zeros(6), DVector::zeros(6));
        fine.f(&x, &t, &mut a).unwrap();
        rk.f(&x, &t, &mut b).unwrap();
        eu.f(&x, &t, &mut c).unwrap();
        let (e_rk, e_eu) = ((&b - &a).amax(), (&c - &a).amax());
        assert!(e_rk < 1e-7 && e_eu > 1e-4, "RK4 {e_rk:e}, Euler {e_eu:e}");
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let model = DiscreteVessel::paper(VesselParams::paper()).unwrap();
        let mut out = DVector::zeros(6);
        assert!(model.f(&DVector::zeros(5), &tau(), &mut out).is_err());
        assert!(model.f(&state(), &DVector::zeros(2), &mut out).is_err());
        assert!(model.f(&state(), &tau(), &mut DVector::zeros(3)).is_err());
        let mut x = state();
        x[4] = f64::NAN;
        let e = model.f(&x, &tau(), &mut out).unwrap_err();
        assert_eq!(e.to_string(), "x has a non-finite entry at (4, 0)");
        let mut j = DMatrix::zeros(5, 6);
        assert!(model.f_jacobian(&state(), &tau(), &mut j).is_err());
        assert!(Vessel::new(VesselParams::paper()).unwrap().discretize(0.0, Integrator::Euler).is_err());
    }

    #[test]
    fn euler_evaluation_does_not_allocate() {
        let model = DiscreteVessel::paper(VesselParams::paper()).unwrap();
        let (x, t) = (state(), tau());
        let mut out = DVector::zeros(6);
        let mut j = DMatrix::zeros(6, 6);
        model.f(&x, &t, &mut out).unwrap();
        let (_, n) = counting_allocator::count(|| {
            model.f(&x, &t, &mut out).unwrap();
            model.f_jacobian(&x, &t, &mut j).unwrap();
        });
        assert_eq!(n, 0);
    }
}
