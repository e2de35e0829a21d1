//! Rigorous enclosures of a model over a box of states: the value, the Jacobian and the Hessians
//! of `f` (or `h`), for the nonlinear set-membership filter's bound on its linearisation
//! remainder (Lagrange form: `f(x) = f(x̂) + J(x̂)(x − x̂) + ½ (x − x̂)ᵀ H(ξ) (x − x̂)`, `ξ` in
//! the box).
//!
//! A model offers them by implementing [`SecondOrderModel`]; every linear model does (zero
//! Hessians). "Rigorous" means: for every state in the box (and the given input), the exact
//! real value of each entry lies in its interval — floating-point rounding included
//! (crate `intervals`).

use intervals::Interval;
use nalgebra::DVector;

use crate::error::ModelError;
use crate::model::{DifferentiableModel, LinearModel};

/// Enclosures of a vector function with `rows` entries of `n` states and of its first and second
/// derivatives with respect to the states, over a box.
#[derive(Debug, Clone, PartialEq)]
pub struct TaylorEnclosure {
    rows: usize,
    n: usize,
    value: Vec<Interval>,
    jacobian: Vec<Interval>,
    hessian: Vec<Interval>,
    hessian_valid: bool,
}

impl TaylorEnclosure {
    /// Zero enclosures for `rows` entries of `n` states (allocates `rows·(1 + n + n²)` intervals
    /// once).
    #[must_use]
    pub fn new(rows: usize, n: usize) -> Self {
        let zero = Interval::ZERO;
        Self {
            rows,
            n,
            value: vec![zero; rows],
            jacobian: vec![zero; rows * n],
            hessian: vec![zero; rows * n * n],
            hessian_valid: true,
        }
    }

    /// `(rows, n)`.
    #[must_use]
    pub fn dims(&self) -> (usize, usize) {
        (self.rows, self.n)
    }

    /// Sets every enclosure to `[0, 0]` and marks the Hessians valid.
    pub fn clear(&mut self) {
        for v in self.value.iter_mut().chain(&mut self.jacobian).chain(&mut self.hessian) {
            *v = Interval::ZERO;
        }
        self.hessian_valid = true;
    }

    /// Declares that the function is not twice differentiable on the box (a kink of `abs` or
    /// `max` inside it, say): the Hessian enclosures say nothing, and a user of the enclosure
    /// bounds the remainder by the mean-value form with the Jacobian's enclosure over the box,
    /// valid for any Lipschitz function whose Jacobian enclosure holds its generalised (Clarke)
    /// Jacobian.
    pub fn set_hessian_invalid(&mut self) {
        self.hessian_valid = false;
    }

    /// Whether the Hessian enclosures hold (see [`TaylorEnclosure::set_hessian_invalid`]).
    #[must_use]
    pub fn hessian_valid(&self) -> bool {
        self.hessian_valid
    }

    /// The value of entry `i`.
    #[must_use]
    pub fn value(&self, i: usize) -> Interval {
        self.value[i]
    }

    /// `∂(entry i)/∂x_j`.
    #[must_use]
    pub fn jacobian(&self, i: usize, j: usize) -> Interval {
        self.jacobian[i * self.n + j]
    }

    /// `∂²(entry i)/∂x_j∂x_k`.
    #[must_use]
    pub fn hessian(&self, i: usize, j: usize, k: usize) -> Interval {
        self.hessian[(i * self.n + j) * self.n + k]
    }

    /// Sets the value of entry `i`.
    pub fn set_value(&mut self, i: usize, v: Interval) {
        self.value[i] = v;
    }

    /// Sets `∂(entry i)/∂x_j`.
    pub fn set_jacobian(&mut self, i: usize, j: usize, v: Interval) {
        self.jacobian[i * self.n + j] = v;
    }

    /// Sets `∂²(entry i)/∂x_j∂x_k` and its symmetric twin.
    pub fn set_hessian(&mut self, i: usize, j: usize, k: usize, v: Interval) {
        let n = self.n;
        self.hessian[(i * n + j) * n + k] = v;
        self.hessian[(i * n + k) * n + j] = v;
    }

    /// Whether every value enclosure is bounded (what [`SecondOrderModel::f_value_enclosure`]
    /// promises).
    #[must_use]
    pub fn values_bounded(&self) -> bool {
        self.value.iter().all(|v| v.is_bounded())
    }

    /// Whether every enclosure is bounded (an undefined or overflowing operation somewhere on the
    /// box makes one unbounded).
    #[must_use]
    pub fn is_bounded(&self) -> bool {
        self.value.iter().chain(&self.jacobian).chain(&self.hessian).all(|v| v.is_bounded())
    }
}

/// A model that encloses `f` and `h` with their Jacobians and Hessians over boxes of states.
pub trait SecondOrderModel: DifferentiableModel {
    /// Encloses `f(x, u)`, `∂f/∂x` and the Hessians `∂²f_i/∂x²` for every `x` in the box `x`
    /// (one interval per state); `out` has `n` rows. Where `f` is not differentiable on the box
    /// (a kink of `abs`, `max`), the Jacobian enclosure must hold its generalised (Clarke)
    /// Jacobian, and where it is not twice differentiable the model calls
    /// [`TaylorEnclosure::set_hessian_invalid`].
    ///
    /// # Errors
    /// [`ModelError`] for wrong dimensions or a non-finite input. An operation undefined on the
    /// box is not an error: its enclosure is unbounded ([`TaylorEnclosure::is_bounded`]).
    fn f_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError>;

    /// As [`SecondOrderModel::f_enclosure`], for `h(x, u)` (`out` has `m` rows).
    ///
    /// # Errors
    /// As [`SecondOrderModel::f_enclosure`].
    fn h_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError>;

    /// Encloses `f(x, u)` alone over the box: `out`'s values as
    /// [`SecondOrderModel::f_enclosure`]'s, its derivative entries unspecified. The filter asks
    /// for it at the set's centre when the Hessians do not hold on the box (the mean-value bound
    /// needs the value there and the Jacobian over the box only). The default computes the whole
    /// enclosure; a model overrides it where the value alone is cheaper.
    ///
    /// # Errors
    /// As [`SecondOrderModel::f_enclosure`].
    fn f_value_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        self.f_enclosure(x, u, out)
    }

    /// As [`SecondOrderModel::f_value_enclosure`], for `h(x, u)`.
    ///
    /// # Errors
    /// As [`SecondOrderModel::f_enclosure`].
    fn h_value_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        self.h_enclosure(x, u, out)
    }
}

fn mismatch(what: &str, expected: (usize, usize), found: (usize, usize)) -> ModelError {
    ModelError::DimensionMismatch {
        what: what.to_owned(),
        expected_rows: expected.0,
        expected_cols: expected.1,
        rows: found.0,
        cols: found.1,
    }
}

/// Checks a box of `n` states and an enclosure of `rows` entries.
///
/// # Errors
/// [`ModelError::DimensionMismatch`] naming the box or the enclosure.
pub fn check_enclosure_dims(
    what: &str,
    rows: usize,
    n: usize,
    x: &[Interval],
    out: &TaylorEnclosure,
) -> Result<(), ModelError> {
    if x.len() != n {
        return Err(mismatch("x (box)", (n, 1), (x.len(), 1)));
    }
    if out.dims() != (rows, n) {
        return Err(mismatch(what, (rows, n), out.dims()));
    }
    Ok(())
}

/// `Σ_j M_ij x_j (+ Σ_k N_ik u_k)` in interval arithmetic.
fn affine(
    m: &nalgebra::DMatrix<f64>,
    x: &[Interval],
    input: Option<(&nalgebra::DMatrix<f64>, &DVector<f64>)>,
    i: usize,
) -> Interval {
    let mut s = Interval::ZERO;
    for (j, xj) in x.iter().enumerate() {
        s = s + *xj * m[(i, j)];
    }
    if let Some((b, u)) = input {
        for k in 0..u.len() {
            s = s + Interval::point(b[(i, k)]) * u[k];
        }
    }
    s
}

impl<M: LinearModel + ?Sized> SecondOrderModel for M {
    fn f_enclosure(&self, x: &[Interval], u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        let (a, b) = (self.a(), self.b());
        let n = a.nrows();
        check_enclosure_dims("f enclosure", n, n, x, out)?;
        if u.len() != b.ncols() {
            return Err(mismatch("u", (b.ncols(), 1), (u.len(), 1)));
        }
        out.clear();
        for i in 0..n {
            out.set_value(i, affine(a, x, Some((b, u)), i));
            for j in 0..n {
                out.set_jacobian(i, j, Interval::point(a[(i, j)]));
            }
        }
        Ok(())
    }

    fn h_enclosure(&self, x: &[Interval], _u: &DVector<f64>, out: &mut TaylorEnclosure) -> Result<(), ModelError> {
        let c = self.c();
        check_enclosure_dims("h enclosure", c.nrows(), c.ncols(), x, out)?;
        out.clear();
        for i in 0..c.nrows() {
            out.set_value(i, affine(c, x, None, i));
            for j in 0..c.ncols() {
                out.set_jacobian(i, j, Interval::point(c[(i, j)]));
            }
        }
        Ok(())
    }
}
