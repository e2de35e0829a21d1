//! Continuous-time models `ẋ = f_c(x, u)`, `y = h(x, u)` and their discretisation: explicit
//! Euler, classical RK4 (with sub-steps), and, for linear models, exact zero-order hold and
//! Van Loan's discrete process noise.

use nalgebra::{DMatrix, DVector};

use crate::angles::Angles;
use crate::discretize::{expm, zoh_discretize};
use crate::error::{ModelError, check_dims, check_finite};
use crate::model::{DifferentiableModel, Dims, DiscreteModel, StepMatrices};

/// A continuous-time model `ẋ = f_c(x, u)`, `y = h(x, u)`.
pub trait ContinuousModel {
    /// The model's dimensions.
    fn dims(&self) -> Dims;
    /// Writes `ẋ = f_c(x, u)` into `out`.
    ///
    /// # Errors
    /// A [`ModelError`] naming the quantity when the model cannot be evaluated there.
    fn derivative(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError>;
    /// Writes `y = h(x, u)` into `out`.
    ///
    /// # Errors
    /// As [`ContinuousModel::derivative`].
    fn output(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError>;
    /// Which states and outputs are angles (module [`crate::angles`]); none by default.
    fn angles(&self) -> Angles<'_> {
        Angles::NONE
    }
}

/// A continuous model with analytic Jacobians `∂f_c/∂x` and `∂h/∂x`.
pub trait DifferentiableContinuousModel: ContinuousModel {
    /// Writes `∂f_c/∂x` (`n × n`) into `out`.
    ///
    /// # Errors
    /// As [`ContinuousModel::derivative`].
    fn derivative_jacobian(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DMatrix<f64>)
    -> Result<(), ModelError>;
    /// Writes `∂h/∂x` (`m × n`) into `out`.
    ///
    /// # Errors
    /// As [`ContinuousModel::derivative`].
    fn output_jacobian(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError>;
}

/// The most RK4 sub-steps per sampling period ([`Discretized::new`]).
pub const MAX_RK4_SUBSTEPS: usize = 10_000;

/// How a continuous model is integrated over one sampling period (input held constant).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Integrator {
    /// `x⁺ = x + T_s f_c(x, u)`; allocation-free.
    Euler,
    /// Classical fourth-order Runge–Kutta with `substeps` equal sub-steps of `T_s / substeps`;
    /// allocates its stage vectors per call.
    Rk4 {
        /// Sub-steps per sampling period (at least 1).
        substeps: usize,
    },
}

/// A continuous model sampled at `T_s` with an [`Integrator`]: a [`DiscreteModel`] (and a
/// [`DifferentiableModel`] when the continuous model has Jacobians; the discrete Jacobian is
/// the exact derivative of the integration scheme).
#[derive(Debug, Clone)]
pub struct Discretized<M> {
    model: M,
    ts: f64,
    integrator: Integrator,
}

impl<M: ContinuousModel> Discretized<M> {
    /// Samples `model` at `ts` with `integrator`.
    ///
    /// # Errors
    /// [`ModelError::InvalidSamplingPeriod`] unless `ts` is positive and finite;
    /// [`ModelError::InvalidSubsteps`] unless RK4 has 1 to [`MAX_RK4_SUBSTEPS`] sub-steps (every
    /// evaluation runs them all: a bound keeps one call's time bounded).
    pub fn new(model: M, ts: f64, integrator: Integrator) -> Result<Self, ModelError> {
        if !(ts.is_finite() && ts > 0.0) {
            return Err(ModelError::InvalidSamplingPeriod(ts));
        }
        if let Integrator::Rk4 { substeps } = integrator {
            if !(1..=MAX_RK4_SUBSTEPS).contains(&substeps) {
                return Err(ModelError::InvalidSubsteps { substeps, max: MAX_RK4_SUBSTEPS });
            }
        }
        Ok(Self { model, ts, integrator })
    }

    /// The continuous model.
    pub fn continuous(&self) -> &M {
        &self.model
    }

    /// The sampling period.
    #[must_use]
    pub fn ts(&self) -> f64 {
        self.ts
    }

    /// The integrator.
    #[must_use]
    pub fn integrator(&self) -> Integrator {
        self.integrator
    }
}

fn check_vec(what: &str, v: &DVector<f64>, n: usize) -> Result<(), ModelError> {
    check_dims(what, v, n, 1)
}

impl<M: ContinuousModel> DiscreteModel for Discretized<M> {
    fn dims(&self) -> Dims {
        self.model.dims()
    }

    fn angles(&self) -> Angles<'_> {
        self.model.angles()
    }

    fn f(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        let n = self.model.dims().states;
        check_vec("x", x, n)?;
        check_vec("f(x, u)", out, n)?;
        match self.integrator {
            Integrator::Euler => {
                self.model.derivative(x, u, out)?;
                out.iter_mut().zip(x.iter()).for_each(|(o, xi)| *o = xi + self.ts * *o);
            }
            Integrator::Rk4 { substeps } => {
                let h = self.ts / substeps as f64;
                let mut xc = x.clone();
                let (mut k1, mut k2, mut k3, mut k4) =
                    (DVector::zeros(n), DVector::zeros(n), DVector::zeros(n), DVector::zeros(n));
                let mut tmp = DVector::zeros(n);
                for _ in 0..substeps {
                    self.model.derivative(&xc, u, &mut k1)?;
                    tmp.copy_from(&xc);
                    tmp.axpy(h / 2.0, &k1, 1.0);
                    self.model.derivative(&tmp, u, &mut k2)?;
                    tmp.copy_from(&xc);
                    tmp.axpy(h / 2.0, &k2, 1.0);
                    self.model.derivative(&tmp, u, &mut k3)?;
                    tmp.copy_from(&xc);
                    tmp.axpy(h, &k3, 1.0);
                    self.model.derivative(&tmp, u, &mut k4)?;
                    for i in 0..n {
                        xc[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
                    }
                }
                out.copy_from(&xc);
            }
        }
        Ok(())
    }

    fn h(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        self.model.output(x, u, out)
    }
}

impl<M: DifferentiableContinuousModel> DifferentiableModel for Discretized<M> {
    /// Euler: `I + T_s ∂f_c/∂x`. RK4: the chain rule through the four stages of every sub-step
    /// (allocates).
    fn f_jacobian(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        let n = self.model.dims().states;
        check_vec("x", x, n)?;
        check_dims("F", out, n, n)?;
        match self.integrator {
            Integrator::Euler => {
                self.model.derivative_jacobian(x, u, out)?;
                out.iter_mut().for_each(|v| *v *= self.ts);
                for i in 0..n {
                    out[(i, i)] += 1.0;
                }
            }
            Integrator::Rk4 { substeps } => {
                let h = self.ts / substeps as f64;
                let id = DMatrix::<f64>::identity(n, n);
                let mut xc = x.clone();
                let mut total = id.clone();
                let mut j = DMatrix::zeros(n, n);
                let (mut k1, mut k2, mut k3, mut k4) =
                    (DVector::zeros(n), DVector::zeros(n), DVector::zeros(n), DVector::zeros(n));
                for _ in 0..substeps {
                    // Stage derivatives D_i = ∂k_i/∂x_c.
                    self.model.derivative(&xc, u, &mut k1)?;
                    self.model.derivative_jacobian(&xc, u, &mut j)?;
                    let d1 = j.clone();
                    let x2 = &xc + &k1 * (h / 2.0);
                    self.model.derivative(&x2, u, &mut k2)?;
                    self.model.derivative_jacobian(&x2, u, &mut j)?;
                    let d2 = &j * (&id + &d1 * (h / 2.0));
                    let x3 = &xc + &k2 * (h / 2.0);
                    self.model.derivative(&x3, u, &mut k3)?;
                    self.model.derivative_jacobian(&x3, u, &mut j)?;
                    let d3 = &j * (&id + &d2 * (h / 2.0));
                    let x4 = &xc + &k3 * h;
                    self.model.derivative(&x4, u, &mut k4)?;
                    self.model.derivative_jacobian(&x4, u, &mut j)?;
                    let d4 = &j * (&id + &d3 * h);
                    let step = &id + (d1 + d2 * 2.0 + d3 * 2.0 + d4) * (h / 6.0);
                    total = step * total;
                    xc += (&k1 + &k2 * 2.0 + &k3 * 2.0 + &k4) * (h / 6.0);
                }
                out.copy_from(&total);
            }
        }
        Ok(())
    }

    fn h_jacobian(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        self.model.output_jacobian(x, u, out)
    }
}

/// A continuous-time linear model `ẋ = A x + B u`, `y = C x`, validated.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearContinuous {
    /// `A` (n × n).
    pub a: DMatrix<f64>,
    /// `B` (n × p).
    pub b: DMatrix<f64>,
    /// `C` (m × n).
    pub c: DMatrix<f64>,
}

impl LinearContinuous {
    /// Validates dimensions and finiteness.
    ///
    /// # Errors
    /// [`ModelError::DimensionMismatch`] or [`ModelError::NonFiniteEntry`] naming the matrix.
    pub fn new(a: DMatrix<f64>, b: DMatrix<f64>, c: DMatrix<f64>) -> Result<Self, ModelError> {
        let n = a.nrows();
        check_dims("A", &a, n, n)?;
        check_dims("B", &b, n, b.ncols())?;
        check_dims("C", &c, c.nrows(), n)?;
        check_finite("A", &a)?;
        check_finite("B", &b)?;
        check_finite("C", &c)?;
        Ok(Self { a, b, c })
    }

    /// Exact zero-order hold at `ts`: `A_d = e^{A T_s}`, `B_d = ∫₀^{T_s} e^{Aτ} dτ B`, `C_d = C`.
    ///
    /// # Errors
    /// As [`zoh_discretize`].
    pub fn zoh(&self, ts: f64) -> Result<StepMatrices, ModelError> {
        let d = zoh_discretize(&self.a, &self.b, ts)?;
        Ok(StepMatrices { a: d.a_p, b: d.b_p, c: self.c.clone() })
    }

    /// Explicit Euler at `ts`: `A_d = I + T_s A`, `B_d = T_s B`, `C_d = C`.
    ///
    /// # Errors
    /// [`ModelError::InvalidSamplingPeriod`] unless `ts` is positive and finite.
    pub fn euler(&self, ts: f64) -> Result<StepMatrices, ModelError> {
        if !(ts.is_finite() && ts > 0.0) {
            return Err(ModelError::InvalidSamplingPeriod(ts));
        }
        let n = self.a.nrows();
        Ok(StepMatrices { a: DMatrix::identity(n, n) + &self.a * ts, b: &self.b * ts, c: self.c.clone() })
    }
}

impl ContinuousModel for LinearContinuous {
    fn dims(&self) -> Dims {
        Dims::new(self.a.nrows(), self.b.ncols(), self.c.nrows())
    }
    fn derivative(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        check_vec("x", x, self.a.nrows())?;
        check_vec("u", u, self.b.ncols())?;
        check_vec("dx/dt", out, self.a.nrows())?;
        dense_kernels::gemv(1.0, &self.a, x, 0.0, out);
        dense_kernels::gemv(1.0, &self.b, u, 1.0, out);
        Ok(())
    }
    fn output(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        check_vec("x", x, self.a.nrows())?;
        check_vec("y", out, self.c.nrows())?;
        dense_kernels::gemv(1.0, &self.c, x, 0.0, out);
        Ok(())
    }
}

impl DifferentiableContinuousModel for LinearContinuous {
    fn derivative_jacobian(
        &self,
        _x: &DVector<f64>,
        _u: &DVector<f64>,
        out: &mut DMatrix<f64>,
    ) -> Result<(), ModelError> {
        check_dims("df/dx", out, self.a.nrows(), self.a.ncols())?;
        out.copy_from(&self.a);
        Ok(())
    }
    fn output_jacobian(&self, _x: &DVector<f64>, _u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        check_dims("dh/dx", out, self.c.nrows(), self.c.ncols())?;
        out.copy_from(&self.c);
        Ok(())
    }
}

/// Van Loan's method: for `ẋ = A x + G w` with white noise of intensity `Q_c`
/// (`E[w(t) w(s)ᵀ] = Q_c δ(t − s)`), returns `(A_d, Q_d)` with `A_d = e^{A T_s}` and
/// `Q_d = ∫₀^{T_s} e^{Aτ} G Q_c Gᵀ e^{Aᵀτ} dτ`, from
/// `exp([[−A, G Q_c Gᵀ], [0, Aᵀ]] T_s) = [[·, A_d⁻¹ Q_d], [0, A_dᵀ]]` (Van Loan 1978).
/// `Q_d` is symmetrised.
///
/// # Errors
/// Dimension and finiteness errors naming `A`, `G` or `Q_c`; [`ModelError::InvalidSamplingPeriod`];
/// exponential failures of [`expm`].
pub fn van_loan(
    a: &DMatrix<f64>,
    g: &DMatrix<f64>,
    qc: &DMatrix<f64>,
    ts: f64,
) -> Result<(DMatrix<f64>, DMatrix<f64>), ModelError> {
    if !(ts.is_finite() && ts > 0.0) {
        return Err(ModelError::InvalidSamplingPeriod(ts));
    }
    let n = a.nrows();
    let r = g.ncols();
    check_dims("A", a, n, n)?;
    check_dims("G", g, n, r)?;
    check_dims("Q_c", qc, r, r)?;
    check_finite("A", a)?;
    check_finite("G", g)?;
    check_finite("Q_c", qc)?;
    let mut m = DMatrix::zeros(2 * n, 2 * n);
    m.view_mut((0, 0), (n, n)).copy_from(&(-a * ts));
    m.view_mut((0, n), (n, n)).copy_from(&(g * qc * g.transpose() * ts));
    m.view_mut((n, n), (n, n)).copy_from(&(a.transpose() * ts));
    check_finite("Van Loan block matrix", &m)?;
    let e = expm(&m)?;
    let ad = e.view((n, n), (n, n)).transpose();
    let qd = &ad * e.view((0, n), (n, n));
    let qd = (&qd + qd.transpose()) * 0.5;
    Ok((ad, qd))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::check_jacobians;

    fn oscillator() -> LinearContinuous {
        LinearContinuous::new(
            DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -4.0, -0.4]),
            DMatrix::from_row_slice(2, 1, &[0.0, 1.0]),
            DMatrix::from_row_slice(1, 2, &[1.0, 0.0]),
        )
        .unwrap()
    }

    #[test]
    fn rk4_converges_to_the_exact_zoh_and_euler_is_first_order() {
        let m = oscillator();
        let ts = 0.1;
        let exact = m.zoh(ts).unwrap();
        let x = DVector::from_vec(vec![1.0, -0.5]);
        let u = DVector::from_vec(vec![0.3]);
        let want = &exact.a * &x + &exact.b * &u;
        let mut out = DVector::zeros(2);
        let rk = Discretized::new(m.clone(), ts, Integrator::Rk4 { substeps: 4 }).unwrap();
        rk.f(&x, &u, &mut out).unwrap();
        assert!((&out - &want).amax() < 1e-7, "{}", (&out - &want).amax());
        let eu = Discretized::new(m.clone(), ts, Integrator::Euler).unwrap();
        eu.f(&x, &u, &mut out).unwrap();
        let e = m.euler(ts).unwrap();
        assert!((&out - (&e.a * &x + &e.b * &u)).amax() < 1e-15);
        let err = (&out - &want).amax();
        assert!(err > 1e-4 && err < 0.1, "Euler error {err}");
    }

    #[test]
    fn discretized_jacobians_match_finite_differences() {
        for integrator in [Integrator::Euler, Integrator::Rk4 { substeps: 3 }] {
            let d = Discretized::new(oscillator(), 0.05, integrator).unwrap();
            let check = check_jacobians(&d, &DVector::from_vec(vec![0.2, 0.1]), &DVector::from_vec(vec![1.0])).unwrap();
            assert!(check.f_error < 1e-8 && check.h_error < 1e-8, "{integrator:?}: {check:?}");
        }
        // RK4's Jacobian of a linear model is the RK4 transition matrix, close to e^{A T_s}.
        let d = Discretized::new(oscillator(), 0.05, Integrator::Rk4 { substeps: 1 }).unwrap();
        let mut f = DMatrix::zeros(2, 2);
        d.f_jacobian(&DVector::zeros(2), &DVector::zeros(1), &mut f).unwrap();
        assert!((&f - oscillator().zoh(0.05).unwrap().a).amax() < 1e-6);
    }

    #[test]
    fn van_loan_closed_forms() {
        // Scalar: ẋ = −a x + w, Q_d = q (1 − e^{−2aT}) / (2a).
        let (a, q, t) = (0.7_f64, 2.0, 0.3);
        let (ad, qd) =
            van_loan(&DMatrix::from_element(1, 1, -a), &DMatrix::identity(1, 1), &DMatrix::from_element(1, 1, q), t)
                .unwrap();
        assert!((ad[(0, 0)] - (-a * t).exp()).abs() < 1e-14);
        assert!((qd[(0, 0)] - q * (1.0 - (-2.0 * a * t).exp()) / (2.0 * a)).abs() < 1e-14);
        // Double integrator driven by white acceleration: Q_d = q [[T³/3, T²/2], [T²/2, T]].
        let a2 = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, 0.0, 0.0]);
        let g = DMatrix::from_row_slice(2, 1, &[0.0, 1.0]);
        let (_, qd) = van_loan(&a2, &g, &DMatrix::from_element(1, 1, q), t).unwrap();
        let want = DMatrix::from_row_slice(2, 2, &[t.powi(3) / 3.0, t * t / 2.0, t * t / 2.0, t]) * q;
        assert!((&qd - want).amax() < 1e-14);
        assert!(van_loan(&a2, &g, &DMatrix::identity(2, 2), t).is_err());
        assert!(van_loan(&a2, &g, &DMatrix::identity(1, 1), 0.0).is_err());
    }

    #[test]
    fn invalid_discretisations_are_errors() {
        assert!(Discretized::new(oscillator(), 0.0, Integrator::Euler).is_err());
        assert!(Discretized::new(oscillator(), 0.1, Integrator::Rk4 { substeps: 0 }).is_err());
        assert!(oscillator().euler(f64::NAN).is_err());
        let e = LinearContinuous::new(DMatrix::zeros(2, 2), DMatrix::zeros(3, 1), DMatrix::zeros(1, 2)).unwrap_err();
        assert_eq!(e.to_string(), "B: expected 2x1, got 3x1");
    }
}
