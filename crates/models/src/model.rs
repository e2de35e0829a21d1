//! Model traits: what an estimator or the simulator may ask of a model.
//!
//! Conventions: one step maps `x_k` to `x_{k+1} = f(x_k, u_k) (+ w_k)`; the measurement after
//! the step is `y_{k+1} = h(x_{k+1}, u_k) (+ v_{k+1})`. A time-varying model is handed to an
//! estimator step by step (the model valid for that step), so the traits carry no time index;
//! [`LinearTimeVarying`] produces the matrices of each step for the simulator and the
//! reproduction.
//!
//! * [`DiscreteModel`]: `f` and `h` only (UKF, MHE, simulation);
//! * [`DifferentiableModel`]: plus the Jacobians `F = ∂f/∂x`, `H = ∂h/∂x` (EKF);
//! * [`LinearModel`]: `f = A x + B u`, `h = C x` (Kalman and set-membership filters); every
//!   linear model is a differentiable discrete model through blanket implementations.
//!
//! Evaluations write into caller-provided buffers and do not allocate for linear models.

use nalgebra::{DMatrix, DVector};

use crate::angles::Angles;
pub use crate::dims::Dims;
use crate::error::{ModelError, check_dims, check_finite};

/// A discrete-time model `x_{k+1} = f(x_k, u_k)`, `y = h(x, u)`.
pub trait DiscreteModel {
    /// The model's dimensions.
    fn dims(&self) -> Dims;
    /// Writes `f(x, u)` (length `n`) into `out`.
    ///
    /// # Errors
    /// A [`ModelError`] naming the quantity when the model cannot be evaluated there.
    fn f(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError>;
    /// Writes `h(x, u)` (length `m`) into `out`.
    ///
    /// # Errors
    /// As [`DiscreteModel::f`].
    fn h(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError>;
    /// Which states and outputs are angles (module [`crate::angles`]); none by default.
    fn angles(&self) -> Angles<'_> {
        Angles::NONE
    }
}

/// A discrete model with analytic Jacobians `F = ∂f/∂x` (`n × n`) and `H = ∂h/∂x` (`m × n`).
/// [`check_jacobians`] compares them with central differences (for tests).
pub trait DifferentiableModel: DiscreteModel {
    /// Writes `∂f/∂x` at `(x, u)` into `out` (`n × n`).
    ///
    /// # Errors
    /// As [`DiscreteModel::f`].
    fn f_jacobian(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError>;
    /// Writes `∂h/∂x` at `(x, u)` into `out` (`m × n`).
    ///
    /// # Errors
    /// As [`DiscreteModel::f`].
    fn h_jacobian(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError>;

    /// `f(x, u)` and `∂f/∂x` at the same point, as an EKF prediction needs them. The default
    /// calls [`DiscreteModel::f`] and [`DifferentiableModel::f_jacobian`]; models whose
    /// evaluation is expensive (tyre forces) override it to share the work.
    ///
    /// # Errors
    /// As [`DiscreteModel::f`].
    fn f_with_jacobian(
        &self,
        x: &DVector<f64>,
        u: &DVector<f64>,
        out: &mut DVector<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<(), ModelError> {
        self.f(x, u, out)?;
        self.f_jacobian(x, u, jacobian)
    }

    /// `h(x, u)` and `∂h/∂x` at the same point (see [`DifferentiableModel::f_with_jacobian`]).
    ///
    /// # Errors
    /// As [`DiscreteModel::f`].
    fn h_with_jacobian(
        &self,
        x: &DVector<f64>,
        u: &DVector<f64>,
        out: &mut DVector<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<(), ModelError> {
        self.h(x, u, out)?;
        self.h_jacobian(x, u, jacobian)
    }
}

/// A linear step `x_{k+1} = A x_k + B u_k`, `y_{k+1} = C x_{k+1}`: `A` is `n × n`, `B` is
/// `n × p`, `C` is `m × n` (the output matrix of the measurement taken after the step).
pub trait LinearModel {
    /// `A_k`.
    fn a(&self) -> &DMatrix<f64>;
    /// `B_k`.
    fn b(&self) -> &DMatrix<f64>;
    /// `C_{k+1}`.
    fn c(&self) -> &DMatrix<f64>;
    /// Which states and outputs are angles (module [`crate::angles`]); none by default.
    fn angles(&self) -> Angles<'_> {
        Angles::NONE
    }

    /// Checks the three matrices' shapes against each other and their entries for NaN/∞.
    ///
    /// # Errors
    /// [`ModelError::DimensionMismatch`] or [`ModelError::NonFiniteEntry`] naming the matrix.
    fn validate(&self) -> Result<Dims, ModelError> {
        let (a, b, c) = (self.a(), self.b(), self.c());
        let n = a.nrows();
        check_dims("A", a, n, n)?;
        check_dims("B", b, n, b.ncols())?;
        check_dims("C", c, c.nrows(), n)?;
        check_finite("A", a)?;
        check_finite("B", b)?;
        check_finite("C", c)?;
        Ok(Dims::new(n, b.ncols(), c.nrows()))
    }
}

fn check_len(what: &str, v: &DVector<f64>, len: usize) -> Result<(), ModelError> {
    check_dims(what, v, len, 1)
}

impl<T: LinearModel + ?Sized> DiscreteModel for T {
    fn dims(&self) -> Dims {
        Dims::new(self.a().nrows(), self.b().ncols(), self.c().nrows())
    }

    fn f(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        let d = DiscreteModel::dims(self);
        check_dims("A", self.a(), d.states, d.states)?;
        check_len("x", x, d.states)?;
        check_len("u", u, d.inputs)?;
        check_len("f(x, u)", out, d.states)?;
        dense_kernels::gemv(1.0, self.a(), x, 0.0, out);
        dense_kernels::gemv(1.0, self.b(), u, 1.0, out);
        Ok(())
    }

    fn h(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        let d = DiscreteModel::dims(self);
        check_dims("C", self.c(), d.outputs, d.states)?;
        check_len("x", x, d.states)?;
        check_len("h(x, u)", out, d.outputs)?;
        dense_kernels::gemv(1.0, self.c(), x, 0.0, out);
        Ok(())
    }

    fn angles(&self) -> Angles<'_> {
        LinearModel::angles(self)
    }
}

impl<T: LinearModel + ?Sized> DifferentiableModel for T {
    fn f_jacobian(&self, _x: &DVector<f64>, _u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        check_dims("F", out, self.a().nrows(), self.a().ncols())?;
        out.copy_from(self.a());
        Ok(())
    }

    fn h_jacobian(&self, _x: &DVector<f64>, _u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        check_dims("H", out, self.c().nrows(), self.c().ncols())?;
        out.copy_from(self.c());
        Ok(())
    }
}

/// The matrices of one step, borrowed (a time-varying model costs nothing per step).
#[derive(Debug, Clone, Copy)]
pub struct StepModel<'a> {
    /// `A_k`.
    pub a: &'a DMatrix<f64>,
    /// `B_k`.
    pub b: &'a DMatrix<f64>,
    /// `C_{k+1}`.
    pub c: &'a DMatrix<f64>,
}

impl<'a> StepModel<'a> {
    /// Bundles the three matrices.
    #[must_use]
    pub fn new(a: &'a DMatrix<f64>, b: &'a DMatrix<f64>, c: &'a DMatrix<f64>) -> Self {
        Self { a, b, c }
    }
}

impl LinearModel for StepModel<'_> {
    fn a(&self) -> &DMatrix<f64> {
        self.a
    }
    fn b(&self) -> &DMatrix<f64> {
        self.b
    }
    fn c(&self) -> &DMatrix<f64> {
        self.c
    }
}

/// The matrices of one time index `k`, owned: `A_k`, `B_k` propagate `x_k` to `x_{k+1}`;
/// `C_k` measures `x_k`.
#[derive(Debug, Clone, PartialEq)]
pub struct StepMatrices {
    /// `A_k` (n × n).
    pub a: DMatrix<f64>,
    /// `B_k` (n × p).
    pub b: DMatrix<f64>,
    /// `C_k` (m × n).
    pub c: DMatrix<f64>,
}

impl StepMatrices {
    /// Borrowed view for an estimator step.
    #[must_use]
    pub fn as_step(&self) -> StepModel<'_> {
        StepModel::new(&self.a, &self.b, &self.c)
    }
}

impl LinearModel for StepMatrices {
    fn a(&self) -> &DMatrix<f64> {
        &self.a
    }
    fn b(&self) -> &DMatrix<f64> {
        &self.b
    }
    fn c(&self) -> &DMatrix<f64> {
        &self.c
    }
}

/// A discrete-time linear time-varying model: the matrices of every time index `k` (speed or
/// load may change along a run).
pub trait LinearTimeVarying {
    /// The model's dimensions (fixed along the run).
    fn dims(&self) -> Dims;
    /// `(A_k, B_k, C_k)` of time index `k`.
    ///
    /// # Errors
    /// Whatever building the model at `k` may fail with (e.g. an invalid speed).
    fn matrices(&self, k: usize) -> Result<StepMatrices, ModelError>;
}

/// A time-invariant linear model `(A, B, C)`, validated.
#[derive(Debug, Clone, PartialEq)]
pub struct ConstantModel {
    matrices: StepMatrices,
    angle_states: Vec<usize>,
    angle_outputs: Vec<usize>,
}

impl ConstantModel {
    /// Validates dimensions (`A` n × n, `B` n × p, `C` m × n) and finiteness.
    ///
    /// # Errors
    /// [`ModelError::DimensionMismatch`] or [`ModelError::NonFiniteEntry`] naming the matrix.
    pub fn new(a: DMatrix<f64>, b: DMatrix<f64>, c: DMatrix<f64>) -> Result<Self, ModelError> {
        let matrices = StepMatrices { a, b, c };
        matrices.validate()?;
        Ok(Self { matrices, angle_states: Vec::new(), angle_outputs: Vec::new() })
    }

    /// The same model with the states and outputs of `angles` declared angles.
    ///
    /// # Errors
    /// [`ModelError::InvalidAngles`] for an index outside the model or out of order.
    pub fn with_angles(mut self, angles: Angles<'_>) -> Result<Self, ModelError> {
        angles.validate(DiscreteModel::dims(&self))?;
        self.angle_states = angles.states.to_vec();
        self.angle_outputs = angles.outputs.to_vec();
        Ok(self)
    }

    /// The constant matrices.
    #[must_use]
    pub fn matrices(&self) -> &StepMatrices {
        &self.matrices
    }
}

impl LinearModel for ConstantModel {
    fn a(&self) -> &DMatrix<f64> {
        &self.matrices.a
    }
    fn b(&self) -> &DMatrix<f64> {
        &self.matrices.b
    }
    fn c(&self) -> &DMatrix<f64> {
        &self.matrices.c
    }
    fn angles(&self) -> Angles<'_> {
        Angles::new(&self.angle_states, &self.angle_outputs)
    }
}

impl LinearTimeVarying for ConstantModel {
    fn dims(&self) -> Dims {
        DiscreteModel::dims(self)
    }
    fn matrices(&self, _k: usize) -> Result<StepMatrices, ModelError> {
        Ok(self.matrices.clone())
    }
}

/// A time-varying linear model given by a closure `k ↦ (A_k, B_k, C_k)` and its fixed
/// dimensions.
pub struct FnModel<F> {
    dims: Dims,
    f: F,
}

impl<F> FnModel<F>
where
    F: Fn(usize) -> Result<StepMatrices, ModelError>,
{
    /// The dimensions and the per-step closure; the simulator checks every step's matrices
    /// against these dimensions.
    pub fn new(dims: Dims, f: F) -> Self {
        Self { dims, f }
    }
}

impl<F> LinearTimeVarying for FnModel<F>
where
    F: Fn(usize) -> Result<StepMatrices, ModelError>,
{
    fn dims(&self) -> Dims {
        self.dims
    }
    fn matrices(&self, k: usize) -> Result<StepMatrices, ModelError> {
        (self.f)(k)
    }
}

/// The largest relative errors of a model's analytic Jacobians against central differences.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JacobianCheck {
    /// `max |F − F_fd| / max(1, max |F_fd|)`.
    pub f_error: f64,
    /// `max |H − H_fd| / max(1, max |H_fd|)`.
    pub h_error: f64,
}

/// Central-difference Jacobians `(∂f/∂x, ∂h/∂x)` of any discrete model at `(x, u)`, with the
/// step `h_i = rel_step · max(1, |x_i|)` (allocates; for tests and as a reference).
///
/// # Errors
/// Evaluation errors of the model, and a non-positive or non-finite `rel_step`.
pub fn numeric_jacobians<M: DiscreteModel + ?Sized>(
    model: &M,
    x: &DVector<f64>,
    u: &DVector<f64>,
    rel_step: f64,
) -> Result<(DMatrix<f64>, DMatrix<f64>), ModelError> {
    if !(rel_step.is_finite() && rel_step > 0.0) {
        return Err(ModelError::Evaluation(format!("finite-difference step must be positive, got {rel_step}")));
    }
    let d = model.dims();
    check_len("x", x, d.states)?;
    let mut fj = DMatrix::zeros(d.states, d.states);
    let mut hj = DMatrix::zeros(d.outputs, d.states);
    let (mut fp, mut fm) = (DVector::zeros(d.states), DVector::zeros(d.states));
    let (mut hp, mut hm) = (DVector::zeros(d.outputs), DVector::zeros(d.outputs));
    let mut xp = x.clone();
    for j in 0..d.states {
        let h = rel_step * x[j].abs().max(1.0);
        xp[j] = x[j] + h;
        model.f(&xp, u, &mut fp)?;
        model.h(&xp, u, &mut hp)?;
        xp[j] = x[j] - h;
        model.f(&xp, u, &mut fm)?;
        model.h(&xp, u, &mut hm)?;
        xp[j] = x[j];
        fj.set_column(j, &((&fp - &fm) / (2.0 * h)));
        hj.set_column(j, &((&hp - &hm) / (2.0 * h)));
    }
    Ok((fj, hj))
}

/// Compares a model's analytic Jacobians with [`numeric_jacobians`] (step `1e-6`) at `(x, u)`.
///
/// # Errors
/// Evaluation errors of the model.
pub fn check_jacobians<M: DifferentiableModel + ?Sized>(
    model: &M,
    x: &DVector<f64>,
    u: &DVector<f64>,
) -> Result<JacobianCheck, ModelError> {
    let (fd, hd) = numeric_jacobians(model, x, u, 1e-6)?;
    let mut fa = DMatrix::zeros(fd.nrows(), fd.ncols());
    let mut ha = DMatrix::zeros(hd.nrows(), hd.ncols());
    model.f_jacobian(x, u, &mut fa)?;
    model.h_jacobian(x, u, &mut ha)?;
    let rel = |a: &DMatrix<f64>, b: &DMatrix<f64>| (a - b).amax() / b.amax().max(1.0);
    Ok(JacobianCheck { f_error: rel(&fa, &fd), h_error: rel(&ha, &hd) })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_models_are_discrete_and_differentiable() {
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 0.1, -0.2, 0.9]);
        let b = DMatrix::from_row_slice(2, 1, &[0.0, 0.1]);
        let c = DMatrix::from_row_slice(1, 2, &[1.0, 0.0]);
        let m = ConstantModel::new(a.clone(), b.clone(), c.clone()).unwrap();
        let x = DVector::from_vec(vec![1.0, -2.0]);
        let u = DVector::from_vec(vec![3.0]);
        let mut out = DVector::zeros(2);
        m.f(&x, &u, &mut out).unwrap();
        assert!((&out - (&a * &x + &b * &u)).amax() < 1e-15);
        let mut y = DVector::zeros(1);
        m.h(&x, &u, &mut y).unwrap();
        assert_eq!(y[0], 1.0);
        let check = check_jacobians(&m, &x, &u).unwrap();
        assert!(check.f_error < 1e-9 && check.h_error < 1e-9, "{check:?}");
        assert_eq!(DiscreteModel::dims(&m), Dims::new(2, 1, 1));
        // Wrong buffer sizes are errors, not panics.
        let e = m.f(&x, &u, &mut DVector::zeros(3)).unwrap_err();
        assert_eq!(e.to_string(), "f(x, u): expected 2x1, got 3x1");
        let e = m.f(&DVector::zeros(1), &u, &mut out).unwrap_err();
        assert_eq!(e.to_string(), "x: expected 2x1, got 1x1");
    }

    /// A pendulum-like model whose analytic Jacobian is deliberately wrong in one entry.
    struct Pendulum {
        wrong: bool,
    }
    impl DiscreteModel for Pendulum {
        fn dims(&self) -> Dims {
            Dims::new(2, 1, 1)
        }
        fn f(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
            out[0] = x[0] + 0.01 * x[1];
            out[1] = x[1] - 0.01 * (x[0].sin() - u[0]);
            Ok(())
        }
        fn h(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
            out[0] = x[0].sin();
            Ok(())
        }
    }
    impl DifferentiableModel for Pendulum {
        fn f_jacobian(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
            let c = if self.wrong { 1.0 } else { x[0].cos() };
            out.copy_from_slice(&[1.0, -0.01 * c, 0.01, 1.0]);
            Ok(())
        }
        fn h_jacobian(&self, x: &DVector<f64>, _u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
            out[(0, 0)] = x[0].cos();
            out[(0, 1)] = 0.0;
            Ok(())
        }
    }

    #[test]
    fn jacobian_check_catches_a_wrong_derivative() {
        let x = DVector::from_vec(vec![1.2, 0.3]);
        let u = DVector::from_vec(vec![0.0]);
        let good = check_jacobians(&Pendulum { wrong: false }, &x, &u).unwrap();
        assert!(good.f_error < 1e-9 && good.h_error < 1e-9, "{good:?}");
        let bad = check_jacobians(&Pendulum { wrong: true }, &x, &u).unwrap();
        assert!(bad.f_error > 1e-3, "{bad:?}");
        assert!(numeric_jacobians(&Pendulum { wrong: false }, &x, &u, 0.0).is_err());
    }
}
