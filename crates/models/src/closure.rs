//! A model from two closures, `f(x, u)` and `h(x, u)`, whose Jacobians come from forward-mode
//! automatic differentiation ([`Dual`]): no hand-written derivative.
//!
//! The closures take the state as `&[Dual<N>; N]` (seeded with the identity, so that each
//! result's `eps` is a row of the Jacobian) and the input as `&[f64]`, and return arrays of
//! [`Dual`]s; plain numbers mix freely on either side (`1.0 - x[0]`, `x[3] * x[2].cos() * 0.1`), and
//! a row that depends on the inputs only is `u[0].into()`. `f` is either the step map itself
//! ([`ClosureModel::discrete`]) or a right-hand side `ẋ = f_c(x, u)` integrated over a
//! sampling period by explicit Euler or RK4 ([`ClosureModel::continuous`]; the Jacobian is
//! then the exact derivative of the integration scheme, as for the equation models).
//!
//! Every evaluation runs on the stack: nothing is allocated after construction (an estimator
//! step on a closure model allocates nothing when the estimator's does not). Every call checks
//! the sizes of its vectors and buffers and the finiteness of its arguments and results: a
//! wrong size or a NaN/∞ is a [`ModelError`] naming the vector and the row, never a panic.
//!
//! ```
//! use models::{Angles, ClosureModel, DifferentiableModel, Integrator, check_jacobians};
//! use nalgebra::{DMatrix, DVector};
//!
//! // A kinematic bicycle (x, y, heading, speed; inputs acceleration and steering), RK4 at 10 ms.
//! let (lf, lr) = (1.5, 2.0);
//! let model = ClosureModel::continuous(2, 0.01, Integrator::Rk4 { substeps: 1 }, |x, u| {
//!     let beta = (lr / (lf + lr) * u[1].tan()).atan();
//!     [x[3] * (x[2] + beta).cos(), x[3] * (x[2] + beta).sin(), x[3] / lr * beta.sin(), u[0].into()]
//! }, |x, _| [x[0], x[1], x[2]])?
//! .with_angles(Angles::new(&[2], &[2]))?;
//! let (x, u) = (DVector::from_vec(vec![1.0, 2.0, 0.3, 5.0]), DVector::from_vec(vec![0.5, 0.1]));
//! let mut jacobian = DMatrix::zeros(4, 4);
//! model.f_jacobian(&x, &u, &mut jacobian)?;
//! assert!(check_jacobians(&model, &x, &u)?.f_error < 1e-8);
//! # Ok::<(), models::ModelError>(())
//! ```

use std::fmt;

use nalgebra::{DMatrix, DVector};

use crate::angles::Angles;
use crate::capability::AnyModel;
use crate::continuous::{Integrator, MAX_RK4_SUBSTEPS};
use crate::dual::Dual;
use crate::error::{ModelError, check_dims, check_finite};
use crate::model::{DifferentiableModel, Dims, DiscreteModel};

/// A model of `N` states and `M` outputs from the closures `f` and `h` (module documentation);
/// a [`DiscreteModel`], a [`DifferentiableModel`] and an [`AnyModel`].
pub struct ClosureModel<const N: usize, const M: usize, F, H> {
    inputs: usize,
    /// `None`: `f` is the step map; else the sampling period and the integrator of `ẋ = f`.
    time: Option<(f64, Integrator)>,
    f: F,
    h: H,
    angle_states: Vec<usize>,
    angle_outputs: Vec<usize>,
}

impl<const N: usize, const M: usize, F, H> fmt::Debug for ClosureModel<N, M, F, H> {
    fn fmt(&self, fm: &mut fmt::Formatter<'_>) -> fmt::Result {
        fm.debug_struct("ClosureModel")
            .field("dims", &Dims::new(N, self.inputs, M))
            .field("time", &self.time)
            .field("angle_states", &self.angle_states)
            .field("angle_outputs", &self.angle_outputs)
            .finish_non_exhaustive()
    }
}

impl<const N: usize, const M: usize, F, H> ClosureModel<N, M, F, H>
where
    F: Fn(&[Dual<N>; N], &[f64]) -> [Dual<N>; N],
    H: Fn(&[Dual<N>; N], &[f64]) -> [Dual<N>; M],
{
    /// A discrete-time model: `x_{k+1} = f(x_k, u_k)`, `y = h(x, u)`, with `inputs` inputs.
    ///
    /// # Errors
    /// None today; a `Result` as [`ClosureModel::continuous`].
    pub fn discrete(inputs: usize, f: F, h: H) -> Result<Self, ModelError> {
        Ok(Self { inputs, time: None, f, h, angle_states: Vec::new(), angle_outputs: Vec::new() })
    }

    /// A continuous-time model `ẋ = f(x, u)`, `y = h(x, u)` sampled at `ts` with `integrator`
    /// (the input held over the period).
    ///
    /// # Errors
    /// [`ModelError::InvalidSamplingPeriod`] unless `ts` is positive and finite;
    /// [`ModelError::InvalidSubsteps`] unless RK4 has 1 to [`MAX_RK4_SUBSTEPS`] sub-steps.
    pub fn continuous(inputs: usize, ts: f64, integrator: Integrator, f: F, h: H) -> Result<Self, ModelError> {
        if !(ts.is_finite() && ts > 0.0) {
            return Err(ModelError::InvalidSamplingPeriod(ts));
        }
        if let Integrator::Rk4 { substeps } = integrator {
            if !(1..=MAX_RK4_SUBSTEPS).contains(&substeps) {
                return Err(ModelError::InvalidSubsteps { substeps, max: MAX_RK4_SUBSTEPS });
            }
        }
        Ok(Self { inputs, time: Some((ts, integrator)), f, h, angle_states: Vec::new(), angle_outputs: Vec::new() })
    }

    /// The same model with the states and outputs of `angles` declared angles (module
    /// [`crate::angles`]).
    ///
    /// # Errors
    /// [`ModelError::InvalidAngles`] for an index outside the model or out of order.
    pub fn with_angles(mut self, angles: Angles<'_>) -> Result<Self, ModelError> {
        angles.validate(Dims::new(N, self.inputs, M))?;
        self.angle_states = angles.states.to_vec();
        self.angle_outputs = angles.outputs.to_vec();
        Ok(self)
    }

    /// The sampling period and integrator of a continuous model, `None` for a discrete one.
    #[must_use]
    pub fn sampling(&self) -> Option<(f64, Integrator)> {
        self.time
    }

    /// `x` and `u` checked (sizes, finiteness), `x` seeded with the identity.
    fn seeded(&self, x: &DVector<f64>, u: &DVector<f64>) -> Result<[Dual<N>; N], ModelError> {
        check_dims("x", x, N, 1)?;
        check_dims("u", u, self.inputs, 1)?;
        check_finite("x", x)?;
        check_finite("u", u)?;
        Ok(std::array::from_fn(|j| Dual::variable(x[j], j)))
    }

    /// One step `x⁺` on duals: its values and `∂x⁺/∂x`.
    fn step(&self, x: &DVector<f64>, u: &DVector<f64>) -> Result<[Dual<N>; N], ModelError> {
        let (x, u) = (self.seeded(x, u)?, u.as_slice());
        let Some((ts, integrator)) = self.time else {
            return Ok((self.f)(&x, u));
        };
        let axpy =
            |x: &[Dual<N>; N], a: f64, k: &[Dual<N>; N]| -> [Dual<N>; N] { std::array::from_fn(|i| x[i] + k[i] * a) };
        match integrator {
            Integrator::Euler => Ok(axpy(&x, ts, &(self.f)(&x, u))),
            Integrator::Rk4 { substeps } => {
                let h = ts / substeps as f64;
                let mut xc = x;
                for _ in 0..substeps {
                    let k1 = (self.f)(&xc, u);
                    let k2 = (self.f)(&axpy(&xc, h / 2.0, &k1), u);
                    let k3 = (self.f)(&axpy(&xc, h / 2.0, &k2), u);
                    let k4 = (self.f)(&axpy(&xc, h, &k3), u);
                    xc = std::array::from_fn(|i| xc[i] + (k1[i] + k2[i] * 2.0 + k3[i] * 2.0 + k4[i]) * (h / 6.0));
                }
                Ok(xc)
            }
        }
    }

    /// `h` on duals: its values and `∂h/∂x`.
    fn measure(&self, x: &DVector<f64>, u: &DVector<f64>) -> Result<[Dual<N>; M], ModelError> {
        let x = self.seeded(x, u)?;
        Ok((self.h)(&x, u.as_slice()))
    }
}

/// Writes the values of `rows` into `out` and, if asked, their gradients into `jacobian`, after
/// checking the buffers' sizes and that every value (and gradient) is finite: the first
/// non-finite one is named by its row (and column).
fn write<const N: usize>(
    (value, derivative): (&str, &str),
    rows: &[Dual<N>],
    out: Option<&mut DVector<f64>>,
    jacobian: Option<&mut DMatrix<f64>>,
) -> Result<(), ModelError> {
    if let Some(out) = &out {
        check_dims(value, *out, rows.len(), 1)?;
    }
    if let Some(jacobian) = &jacobian {
        check_dims(derivative, *jacobian, rows.len(), N)?;
    }
    if let Some(row) = rows.iter().position(|r| !r.re.is_finite()) {
        return Err(ModelError::NonFiniteEntry { what: value.to_owned(), row, col: 0 });
    }
    if let Some(out) = out {
        out.iter_mut().zip(rows).for_each(|(o, r)| *o = r.re);
    }
    if let Some(jacobian) = jacobian {
        for (row, r) in rows.iter().enumerate() {
            if let Some(col) = r.eps.iter().position(|d| !d.is_finite()) {
                return Err(ModelError::NonFiniteEntry { what: derivative.to_owned(), row, col });
            }
            for (col, &d) in r.eps.iter().enumerate() {
                jacobian[(row, col)] = d;
            }
        }
    }
    Ok(())
}

const F_NAMES: (&str, &str) = ("f(x, u)", "F = df/dx");
const H_NAMES: (&str, &str) = ("h(x, u)", "H = dh/dx");

impl<const N: usize, const M: usize, F, H> DiscreteModel for ClosureModel<N, M, F, H>
where
    F: Fn(&[Dual<N>; N], &[f64]) -> [Dual<N>; N],
    H: Fn(&[Dual<N>; N], &[f64]) -> [Dual<N>; M],
{
    fn dims(&self) -> Dims {
        Dims::new(N, self.inputs, M)
    }

    fn f(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        write(F_NAMES, &self.step(x, u)?, Some(out), None)
    }

    fn h(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        write(H_NAMES, &self.measure(x, u)?, Some(out), None)
    }

    fn angles(&self) -> Angles<'_> {
        Angles::new(&self.angle_states, &self.angle_outputs)
    }
}

impl<const N: usize, const M: usize, F, H> DifferentiableModel for ClosureModel<N, M, F, H>
where
    F: Fn(&[Dual<N>; N], &[f64]) -> [Dual<N>; N],
    H: Fn(&[Dual<N>; N], &[f64]) -> [Dual<N>; M],
{
    fn f_jacobian(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        write(F_NAMES, &self.step(x, u)?, None, Some(out))
    }

    fn h_jacobian(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        write(H_NAMES, &self.measure(x, u)?, None, Some(out))
    }

    fn f_with_jacobian(
        &self,
        x: &DVector<f64>,
        u: &DVector<f64>,
        out: &mut DVector<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<(), ModelError> {
        write(F_NAMES, &self.step(x, u)?, Some(out), Some(jacobian))
    }

    fn h_with_jacobian(
        &self,
        x: &DVector<f64>,
        u: &DVector<f64>,
        out: &mut DVector<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<(), ModelError> {
        write(H_NAMES, &self.measure(x, u)?, Some(out), Some(jacobian))
    }
}

impl<const N: usize, const M: usize, F, H> AnyModel for ClosureModel<N, M, F, H>
where
    F: Fn(&[Dual<N>; N], &[f64]) -> [Dual<N>; N],
    H: Fn(&[Dual<N>; N], &[f64]) -> [Dual<N>; M],
{
    fn discrete(&self) -> &dyn DiscreteModel {
        self
    }
    fn differentiable(&self) -> Option<&dyn DifferentiableModel> {
        Some(self)
    }
}

#[cfg(test)]
mod tests;
