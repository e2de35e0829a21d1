//! The compiled model: `f`, `h`, their exact Jacobians, and the matrices when it is linear.

use std::path::Path;

use models::{AnyModel, ConstantModel, DifferentiableModel, Dims, DiscreteModel, LinearModel, ModelError};
use nalgebra::{DMatrix, DVector};

use crate::compiled::{Compiled, EvalFailure};
use crate::error::EquationError;
use crate::file::{Discretization, Equation, Spec, TimeModel, read};
use crate::limits::{COMPILE_STACK_BYTES, MAX_COMPILE_SECONDS, MAX_FILE_BYTES};
use std::sync::mpsc::RecvTimeoutError;
use std::time::Duration;

/// One compiled equation and its partial derivatives.
#[derive(Debug, Clone)]
struct Row {
    label: String,
    value: Compiled,
    /// `(slot, ∂/∂slot)` for the slots the equation mentions; `None` when the expression library
    /// cannot differentiate one of its functions.
    partials: Option<Vec<(usize, Compiled)>>,
}

/// A nonlinear model read from a TOML model file (see the crate documentation for the format).
///
/// `f` is the `[f]` map, or one Euler, RK4 or exact zero-order-hold step of `[dxdt]` over `ts`;
/// `h` is `[h]`. The Jacobians are exact: symbolic partial derivatives, through the chain rule of
/// the integration scheme for `[dxdt]`. A model whose equations are all linear in the states and inputs (no
/// constant term, `h` free of inputs) also offers its matrices ([`AnyModel::linear`]).
#[derive(Debug, Clone)]
pub struct EquationModel {
    states: Vec<String>,
    inputs: Vec<String>,
    outputs: Vec<String>,
    parameters: Vec<(String, f64)>,
    time: TimeModel,
    rhs: Vec<Row>,
    out: Vec<Row>,
    /// Why the model has no Jacobians (a function the expression library cannot differentiate).
    not_differentiable: Option<String>,
    /// `(A_d, B_d)` of an exact zero-order hold.
    zoh: Option<(DMatrix<f64>, DMatrix<f64>)>,
    linear: Option<ConstantModel>,
}

fn compile(eq: &Equation, n_slots: usize) -> Result<Row, EquationError> {
    let value = Compiled::parse(&eq.text, n_slots).map_err(|message| {
        if message.starts_with("panicked") {
            EquationError::Internal { location: eq.location.clone(), equation: eq.label.clone(), message }
        } else {
            EquationError::Parse { location: eq.location.clone(), equation: eq.label.clone(), message }
        }
    })?;
    let partials = value.partials().ok();
    Ok(Row { label: eq.label.clone(), value, partials })
}

type Rows = (Vec<Row>, Vec<Row>);

/// Compiles every equation on a worker thread with a large stack, within the time budget.
fn compile_all(spec: &Spec) -> Result<Rows, EquationError> {
    let (rhs, out) = (spec.rhs.clone(), spec.out.clone());
    let n_slots = spec.states.len() + spec.inputs.len();
    let first = spec.rhs.first().cloned();
    let (send, receive) = std::sync::mpsc::channel();
    let worker = std::thread::Builder::new()
        .name("equation-models-compile".to_owned())
        .stack_size(COMPILE_STACK_BYTES)
        .spawn(move || {
            let result = (|| {
                let rhs = rhs.iter().map(|e| compile(e, n_slots)).collect::<Result<Vec<_>, _>>()?;
                let out = out.iter().map(|e| compile(e, n_slots)).collect::<Result<Vec<_>, _>>()?;
                Ok::<_, EquationError>((rhs, out))
            })();
            // The receiver may have given up (time budget): nothing to do then.
            let _ = send.send(result);
        });
    let internal = |message: String| match &first {
        Some(eq) => EquationError::Internal { location: eq.location.clone(), equation: eq.label.clone(), message },
        None => EquationError::Io { file: String::new(), message },
    };
    if let Err(e) = worker {
        return Err(internal(format!("cannot start the compiling thread: {e}")));
    }
    match receive.recv_timeout(Duration::from_secs(MAX_COMPILE_SECONDS)) {
        Ok(result) => result,
        Err(RecvTimeoutError::Timeout) => Err(EquationError::TooSlow {
            location: first.map_or_else(|| crate::error::Location::of_offset("", "", 0), |eq| eq.location),
            seconds: MAX_COMPILE_SECONDS,
        }),
        Err(RecvTimeoutError::Disconnected) => Err(internal("the compiling thread stopped".to_owned())),
    }
}

impl EquationModel {
    /// Reads a model from the text of a model file; `file` names it in error locations.
    ///
    /// # Errors
    /// An [`EquationError`] at the `file:line:column` of the offending key.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Self, EquationError> {
        Self::from_spec(read(text, file, &[])?)
    }

    /// As [`EquationModel::from_toml_str`], for a model file shared with another reader: the
    /// top-level keys and tables named in `foreign` (the noise description and settings that
    /// `port-est` reads, say) are skipped instead of refused as unknown.
    ///
    /// # Errors
    /// As [`EquationModel::from_toml_str`].
    pub fn from_toml_str_with_foreign_keys(text: &str, file: &str, foreign: &[&str]) -> Result<Self, EquationError> {
        Self::from_spec(read(text, file, foreign)?)
    }

    /// Reads a model file (at most [`MAX_FILE_BYTES`] bytes).
    ///
    /// # Errors
    /// [`EquationError::FileTooLarge`], [`EquationError::Io`], or as
    /// [`EquationModel::from_toml_str`].
    pub fn from_file(path: &Path) -> Result<Self, EquationError> {
        use std::io::Read;
        let file = path.display().to_string();
        let io = |e: std::io::Error| EquationError::Io { file: file.clone(), message: e.to_string() };
        let mut bytes = Vec::new();
        std::fs::File::open(path).map_err(io)?.take(MAX_FILE_BYTES as u64 + 1).read_to_end(&mut bytes).map_err(io)?;
        if bytes.len() > MAX_FILE_BYTES {
            return Err(EquationError::FileTooLarge { file, size: bytes.len(), limit: MAX_FILE_BYTES });
        }
        let text = String::from_utf8(bytes)
            .map_err(|e| EquationError::Io { file: file.clone(), message: format!("not UTF-8: {e}") })?;
        Self::from_toml_str(&text, &file)
    }

    fn from_spec(spec: Spec) -> Result<Self, EquationError> {
        let n = spec.states.len();
        let (rhs, out) = compile_all(&spec)?;
        for ((eq, row), name) in spec.out.iter().zip(&out).zip(&spec.outputs) {
            if !row.value.slots().iter().any(|&s| s < n) {
                return Err(EquationError::Unobservable { location: eq.location.clone(), output: name.clone() });
            }
        }
        let not_differentiable = rhs.iter().chain(&out).find(|r| r.partials.is_none()).map(|r| {
            format!("equation `{}` uses a function without a derivative (abs, atan2, min, max, ...)", r.label)
        });
        let mut model = Self {
            states: spec.states,
            inputs: spec.inputs,
            outputs: spec.outputs,
            parameters: spec.parameters,
            time: spec.time,
            rhs,
            out,
            not_differentiable,
            zoh: None,
            linear: None,
        };
        if let TimeModel::Continuous { ts, discretization: Discretization::Zoh } = model.time {
            let (ac, bc) = model.coefficients(&model.rhs).map_err(|(equation, reason)| {
                EquationError::ZohNotLinear { location: spec.discretization_at.clone(), equation, reason }
            })?;
            let d = models::zoh_discretize(&ac, &bc, ts).map_err(|e| EquationError::ZohFailed {
                location: spec.discretization_at.clone(),
                message: e.to_string(),
            })?;
            model.zoh = Some((d.a_p, d.b_p));
        }
        model.linear = model.linear_matrices();
        Ok(model)
    }

    /// The states' names, in order.
    #[must_use]
    pub fn state_names(&self) -> &[String] {
        &self.states
    }

    /// The inputs' names, in order.
    #[must_use]
    pub fn input_names(&self) -> &[String] {
        &self.inputs
    }

    /// The outputs' names, in order.
    #[must_use]
    pub fn output_names(&self) -> &[String] {
        &self.outputs
    }

    /// The parameters and their values, in file order.
    #[must_use]
    pub fn parameters(&self) -> &[(String, f64)] {
        &self.parameters
    }

    /// Discrete map or continuous right-hand side (with `ts` and the scheme).
    #[must_use]
    pub fn time_model(&self) -> TimeModel {
        self.time
    }

    /// Why the model offers no Jacobians, if it does not.
    #[must_use]
    pub fn not_differentiable(&self) -> Option<&str> {
        self.not_differentiable.as_deref()
    }

    /// Whether the equations were recognised as linear ([`AnyModel::linear`] offers `A`, `B`, `C`).
    #[must_use]
    pub fn is_linear(&self) -> bool {
        self.linear.is_some()
    }

    fn dims_(&self) -> Dims {
        Dims::new(self.states.len(), self.inputs.len(), self.outputs.len())
    }

    fn failure(&self, label: &str, x: &[f64], u: &[f64], f: EvalFailure) -> ModelError {
        let mut values = String::new();
        for (name, v) in self.states.iter().zip(x).chain(self.inputs.iter().zip(u)) {
            if !values.is_empty() {
                values.push_str(", ");
            }
            values.push_str(&format!("{name} = {v}"));
        }
        match f {
            EvalFailure::NonFinite(v) => {
                ModelError::Evaluation(format!("equation `{label}` evaluates to {v} at {values}"))
            }
            EvalFailure::Library(e) => ModelError::Evaluation(format!("equation `{label}` at {values}: {e}")),
        }
    }

    fn check(&self, x: &DVector<f64>, u: &DVector<f64>) -> Result<(), ModelError> {
        let d = self.dims_();
        models::error::check_dims("x", x, d.states, 1)?;
        models::error::check_dims("u", u, d.inputs, 1)
    }

    /// Evaluates each row into `out`.
    fn eval_rows(&self, rows: &[Row], x: &[f64], u: &[f64], out: &mut [f64]) -> Result<(), ModelError> {
        for (o, r) in out.iter_mut().zip(rows) {
            *o = r.value.eval(x, u).map_err(|f| self.failure(&r.label, x, u, f))?;
        }
        Ok(())
    }

    /// Writes the Jacobian of `rows` with respect to the states into `out` (rows × n).
    fn jac_rows(&self, rows: &[Row], x: &[f64], u: &[f64], out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        let n = x.len();
        out.fill(0.0);
        for (i, r) in rows.iter().enumerate() {
            let partials = r.partials.as_ref().ok_or_else(|| {
                ModelError::Evaluation(format!("equation `{}` has no derivative (a function without one)", r.label))
            })?;
            for (slot, d) in partials {
                if *slot < n {
                    out[(i, *slot)] = d
                        .eval(x, u)
                        .map_err(|f| self.failure(&format!("d({})/d{}", r.label, self.states[*slot]), x, u, f))?;
                }
            }
        }
        Ok(())
    }

    /// The continuous right-hand side `dx/dt = g(x, u)` of a `[dxdt]` model (the `[f]` map for
    /// a discrete one) at `(x, u)`, into `out`.
    ///
    /// # Errors
    /// A [`ModelError`] on wrong dimensions or a non-finite value (naming the equation and the
    /// variables' values).
    pub fn rhs(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        self.check(x, u)?;
        models::error::check_dims("out", out, self.states.len(), 1)?;
        self.eval_rows(&self.rhs, x.as_slice(), u.as_slice(), out.as_mut_slice())
    }

    fn g(&self, x: &DVector<f64>, u: &[f64]) -> Result<DVector<f64>, ModelError> {
        let mut k = DVector::zeros(x.len());
        self.eval_rows(&self.rhs, x.as_slice(), u, k.as_mut_slice())?;
        Ok(k)
    }

    fn jg(&self, x: &DVector<f64>, u: &[f64]) -> Result<DMatrix<f64>, ModelError> {
        let mut j = DMatrix::zeros(x.len(), x.len());
        self.jac_rows(&self.rhs, x.as_slice(), u, &mut j)?;
        Ok(j)
    }

    /// One step and, if asked, its Jacobian.
    fn step(
        &self,
        x: &DVector<f64>,
        u: &DVector<f64>,
        out: &mut DVector<f64>,
        jac: Option<&mut DMatrix<f64>>,
    ) -> Result<(), ModelError> {
        self.check(x, u)?;
        let n = x.len();
        models::error::check_dims("f(x, u)", out, n, 1)?;
        if let Some(j) = &jac {
            models::error::check_dims("F", *j, n, n)?;
        }
        let us = u.as_slice();
        match self.time {
            TimeModel::Discrete => {
                self.eval_rows(&self.rhs, x.as_slice(), us, out.as_mut_slice())?;
                if let Some(j) = jac {
                    self.jac_rows(&self.rhs, x.as_slice(), us, j)?;
                }
            }
            TimeModel::Continuous { discretization: Discretization::Zoh, .. } => {
                let (a, b) = self
                    .zoh
                    .as_ref()
                    .ok_or_else(|| ModelError::Evaluation("zero-order hold without its matrices".to_owned()))?;
                let next = a * x + b * u;
                models::error::check_finite("f(x, u)", &next)?;
                out.copy_from(&next);
                if let Some(j) = jac {
                    j.copy_from(a);
                }
            }
            TimeModel::Continuous { ts, discretization: Discretization::Euler } => {
                let k = self.g(x, us)?;
                let next = x + &k * ts;
                models::error::check_finite("f(x, u)", &next)?;
                out.copy_from(&next);
                if let Some(j) = jac {
                    let jc = self.jg(x, us)?;
                    j.copy_from(&(DMatrix::identity(n, n) + jc * ts));
                }
            }
            TimeModel::Continuous { ts, discretization: Discretization::Rk4 } => {
                let x1 = x.clone();
                let k1 = self.g(&x1, us)?;
                let x2 = x + &k1 * (ts / 2.0);
                let k2 = self.g(&x2, us)?;
                let x3 = x + &k2 * (ts / 2.0);
                let k3 = self.g(&x3, us)?;
                let x4 = x + &k3 * ts;
                let k4 = self.g(&x4, us)?;
                let next = x + (&k1 + &k2 * 2.0 + &k3 * 2.0 + &k4) * (ts / 6.0);
                models::error::check_finite("f(x, u)", &next)?;
                out.copy_from(&next);
                if let Some(j) = jac {
                    let id = DMatrix::<f64>::identity(n, n);
                    let d1 = self.jg(&x1, us)?;
                    let d2 = self.jg(&x2, us)? * (&id + &d1 * (ts / 2.0));
                    let d3 = self.jg(&x3, us)? * (&id + &d2 * (ts / 2.0));
                    let d4 = self.jg(&x4, us)? * (&id + &d3 * ts);
                    j.copy_from(&(&id + (d1 + d2 * 2.0 + d3 * 2.0 + d4) * (ts / 6.0)));
                }
            }
        }
        Ok(())
    }

    /// The coefficients of `rows` on the states and on the inputs when every row is linear
    /// (constant partial derivatives, zero at zero); else the first row that is not and why.
    fn coefficients(&self, rows: &[Row]) -> Result<(DMatrix<f64>, DMatrix<f64>), (String, String)> {
        let (n, p) = (self.states.len(), self.inputs.len());
        let (zx, zu) = (vec![0.0; n], vec![0.0; p]);
        let (mut mx, mut mu) = (DMatrix::zeros(rows.len(), n), DMatrix::zeros(rows.len(), p));
        for (i, r) in rows.iter().enumerate() {
            let fail = |reason: String| (r.label.clone(), reason);
            match r.value.eval(&zx, &zu) {
                Ok(0.0) => {}
                Ok(v) => return Err(fail(format!("has a constant term (it is {v} at zero states and inputs)"))),
                Err(_) => return Err(fail("cannot be evaluated at zero states and inputs".to_owned())),
            }
            let partials =
                r.partials.as_ref().ok_or_else(|| fail("uses a function without a derivative".to_owned()))?;
            for (slot, dr) in partials {
                let name = if *slot < n { &self.states[*slot] } else { &self.inputs[slot - n] };
                let v = if dr.is_constant() { dr.eval(&zx, &zu).ok() } else { None };
                let v =
                    v.ok_or_else(|| fail(format!("is not linear in `{name}` (its derivative is not a constant)")))?;
                if *slot < n {
                    mx[(i, *slot)] = v;
                } else {
                    mu[(i, slot - n)] = v;
                }
            }
        }
        Ok((mx, mu))
    }

    /// `A`, `B`, `C` when every partial derivative is a constant, every equation vanishes at
    /// zero (no constant term) and `h` does not depend on the inputs.
    fn linear_matrices(&self) -> Option<ConstantModel> {
        let (a, b) = match (&self.zoh, self.time) {
            (Some((a, b)), _) => (a.clone(), b.clone()),
            (None, TimeModel::Continuous { ts, discretization }) => {
                let (ac, bc) = self.coefficients(&self.rhs).ok()?;
                let n = self.states.len();
                let id = DMatrix::<f64>::identity(n, n);
                let ah = &ac * ts;
                let (phi, gamma) = match discretization {
                    Discretization::Rk4 => {
                        let ah2 = &ah * &ah;
                        let ah3 = &ah2 * &ah;
                        let ah4 = &ah3 * &ah;
                        (
                            &id + &ah + &ah2 / 2.0 + &ah3 / 6.0 + &ah4 / 24.0,
                            (&id + &ah / 2.0 + &ah2 / 6.0 + &ah3 / 24.0) * ts,
                        )
                    }
                    // Euler (a zero-order hold has its matrices in `self.zoh`).
                    _ => (&id + &ah, &id * ts),
                };
                (phi, gamma * bc)
            }
            (None, _) => self.coefficients(&self.rhs).ok()?,
        };
        let (c, d_out) = self.coefficients(&self.out).ok()?;
        if d_out.iter().any(|&v| v != 0.0) {
            return None;
        }
        ConstantModel::new(a, b, c).ok()
    }
}

impl DiscreteModel for EquationModel {
    fn dims(&self) -> Dims {
        self.dims_()
    }

    fn f(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        self.step(x, u, out, None)
    }

    fn h(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        self.check(x, u)?;
        models::error::check_dims("h(x, u)", out, self.outputs.len(), 1)?;
        self.eval_rows(&self.out, x.as_slice(), u.as_slice(), out.as_mut_slice())
    }
}

impl DifferentiableModel for EquationModel {
    fn f_jacobian(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        let mut fx = DVector::zeros(self.states.len());
        self.step(x, u, &mut fx, Some(out))
    }

    fn h_jacobian(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        self.check(x, u)?;
        models::error::check_dims("H", out, self.outputs.len(), self.states.len())?;
        self.jac_rows(&self.out, x.as_slice(), u.as_slice(), out)
    }

    fn f_with_jacobian(
        &self,
        x: &DVector<f64>,
        u: &DVector<f64>,
        out: &mut DVector<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<(), ModelError> {
        self.step(x, u, out, Some(jacobian))
    }
}

impl AnyModel for EquationModel {
    fn discrete(&self) -> &dyn DiscreteModel {
        self
    }

    fn differentiable(&self) -> Option<&dyn DifferentiableModel> {
        if self.not_differentiable.is_none() { Some(self) } else { None }
    }

    fn linear(&self) -> Option<&dyn LinearModel> {
        self.linear.as_ref().map(|m| m as &dyn LinearModel)
    }
}
