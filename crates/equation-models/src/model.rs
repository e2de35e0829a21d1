//! The compiled model: `f`, `h`, their exact Jacobians, and the matrices when it is linear.

use std::path::Path;
use std::sync::mpsc::RecvTimeoutError;
use std::time::Duration;

use models::{Angles, AnyModel, ConstantModel, DifferentiableModel, Dims, DiscreteModel, LinearModel, ModelError};
use nalgebra::{DMatrix, DVector};

use crate::error::{EquationError, Location};
use crate::file::{Discretization, Equation, Spec, TimeModel, read};
use crate::graph::{Graph, Seeds};
use crate::limits::{COMPILE_STACK_BYTES, MAX_COMPILE_SECONDS, MAX_FILE_BYTES};
use crate::scratch::with_scratch;
use crate::tape::Tape;

/// The equations of one section (`[f]`/`[dxdt]`, or `[h]`): their labels, the nodes of their
/// values and the nodes they need, in evaluation order.
#[derive(Debug, Clone)]
pub(crate) struct Rows {
    pub(crate) labels: Vec<String>,
    pub(crate) roots: Vec<u32>,
    pub(crate) schedule: Vec<u32>,
    /// The schedule compiled for the filters' evaluations.
    pub(crate) tape: Tape,
}

impl Rows {
    fn new(graph: &Graph, equations: &[Equation], varies: &[bool]) -> Self {
        let roots: Vec<u32> = equations.iter().map(|e| e.root).collect();
        let schedule = graph.schedule(&roots);
        let tape = Tape::new(graph, &schedule, varies);
        Self { labels: equations.iter().map(|e| e.label.clone()).collect(), schedule, roots, tape }
    }
}

/// A nonlinear model read from a TOML model file (see the crate documentation for the format).
///
/// `f` is the `[f]` map, or one Euler, RK4 or exact zero-order-hold step of `[dxdt]` over `ts`;
/// `h` is `[h]`. The Jacobians are exact: forward-mode chain rule through the compiled graph,
/// and through the integration scheme for `[dxdt]`. A model whose equations are all linear in
/// the states and inputs (no constant term, `h` free of inputs) also offers its matrices
/// ([`AnyModel::linear`]).
#[derive(Debug, Clone)]
pub struct EquationModel {
    pub(crate) states: Vec<String>,
    pub(crate) inputs: Vec<String>,
    outputs: Vec<String>,
    parameters: Vec<(String, f64)>,
    pub(crate) time: TimeModel,
    pub(crate) graph: Graph,
    pub(crate) rhs: Rows,
    pub(crate) out: Rows,
    /// Per node: whether it depends on a state (the nodes whose derivatives are propagated).
    pub(crate) varies: Vec<bool>,
    /// `(A_d, B_d)` of an exact zero-order hold.
    pub(crate) zoh: Option<(DMatrix<f64>, DMatrix<f64>)>,
    linear: Option<ConstantModel>,
    angle_states: Vec<usize>,
    angle_outputs: Vec<usize>,
}

/// Dependencies of every node (see [`Graph::dependencies`]).
struct Deps {
    dep: Vec<u64>,
    nonlinear: Vec<u64>,
    words: usize,
}

impl Deps {
    fn has(set: &[u64], words: usize, node: u32, slot: usize) -> bool {
        set[node as usize * words + slot / 64] >> (slot % 64) & 1 == 1
    }
}

/// Reads and compiles on a worker thread, within the time budget.
fn compile_in_worker(text: &str, file: &str, foreign: &[&str]) -> Result<EquationModel, EquationError> {
    if text.len() > MAX_FILE_BYTES {
        return Err(EquationError::FileTooLarge { file: file.to_owned(), size: text.len(), limit: MAX_FILE_BYTES });
    }
    let (owned_text, owned_file) = (text.to_owned(), file.to_owned());
    let owned_foreign: Vec<String> = foreign.iter().map(|s| (*s).to_owned()).collect();
    let (send, receive) = std::sync::mpsc::channel();
    let worker = std::thread::Builder::new()
        .name("equation-models-compile".to_owned())
        .stack_size(COMPILE_STACK_BYTES)
        .spawn(move || {
            let foreign: Vec<&str> = owned_foreign.iter().map(String::as_str).collect();
            let result = read(&owned_text, &owned_file, &foreign).and_then(EquationModel::from_spec);
            // The receiver may have given up (time budget): nothing to do then.
            let _ = send.send(result);
        });
    if let Err(e) = worker {
        return Err(EquationError::Io {
            file: file.to_owned(),
            message: format!("cannot start the compiling thread: {e}"),
        });
    }
    match receive.recv_timeout(Duration::from_secs(MAX_COMPILE_SECONDS)) {
        Ok(result) => result,
        Err(RecvTimeoutError::Timeout) => {
            Err(EquationError::TooSlow { location: Location::of_offset(file, text, 0), seconds: MAX_COMPILE_SECONDS })
        }
        Err(RecvTimeoutError::Disconnected) => {
            Err(EquationError::Io { file: file.to_owned(), message: "the compiling thread stopped".to_owned() })
        }
    }
}

impl EquationModel {
    /// Reads a model from the text of a model file; `file` names it in error locations.
    ///
    /// # Errors
    /// An [`EquationError`] at the `file:line:column` of the offending key.
    pub fn from_toml_str(text: &str, file: &str) -> Result<Self, EquationError> {
        compile_in_worker(text, file, &[])
    }

    /// As [`EquationModel::from_toml_str`], for a model file shared with another reader: the
    /// top-level keys and tables named in `foreign` (the noise description and settings that
    /// `port-est` reads, say) are skipped instead of refused as unknown.
    ///
    /// # Errors
    /// As [`EquationModel::from_toml_str`].
    pub fn from_toml_str_with_foreign_keys(text: &str, file: &str, foreign: &[&str]) -> Result<Self, EquationError> {
        compile_in_worker(text, file, foreign)
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
        let mut graph = spec.graph;
        graph.finish();
        let (dep, nonlinear, words) = graph.dependencies();
        let deps = Deps { dep, nonlinear, words };
        for (eq, name) in spec.out.iter().zip(&spec.outputs) {
            if !(0..n).any(|s| Deps::has(&deps.dep, words, eq.root, s)) {
                return Err(EquationError::Unobservable { location: eq.location.clone(), output: name.clone() });
            }
        }
        let varies: Vec<bool> =
            (0..graph.len() as u32).map(|i| (0..n).any(|s| Deps::has(&deps.dep, words, i, s))).collect();
        let (rhs, out) = (Rows::new(&graph, &spec.rhs, &varies), Rows::new(&graph, &spec.out, &varies));
        let mut model = Self {
            states: spec.states,
            inputs: spec.inputs,
            outputs: spec.outputs,
            parameters: spec.parameters,
            time: spec.time,
            graph,
            rhs,
            out,
            varies,
            zoh: None,
            linear: None,
            angle_states: spec.angle_states,
            angle_outputs: spec.angle_outputs,
        };
        if let TimeModel::Continuous { ts, discretization: Discretization::Zoh } = model.time {
            let (ac, bc) = model.coefficients(&model.rhs, &deps).map_err(|(equation, reason)| {
                EquationError::ZohNotLinear { location: spec.discretization_at.clone(), equation, reason }
            })?;
            let d = models::zoh_discretize(&ac, &bc, ts).map_err(|e| EquationError::ZohFailed {
                location: spec.discretization_at.clone(),
                message: e.to_string(),
            })?;
            model.zoh = Some((d.a_p, d.b_p));
        }
        model.linear = model.linear_matrices(&deps).and_then(|m| m.with_angles(model.angles()).ok());
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

    /// Why the model offers no Jacobians, if it does not. Always `None`: every function of
    /// the language has a derivative wherever it is differentiable (see the crate's README for
    /// the choices at kinks and jumps), so every model is differentiable.
    #[must_use]
    pub fn not_differentiable(&self) -> Option<&str> {
        None
    }

    /// Whether the equations were recognised as linear ([`AnyModel::linear`] offers `A`, `B`, `C`).
    #[must_use]
    pub fn is_linear(&self) -> bool {
        self.linear.is_some()
    }

    fn dims_(&self) -> Dims {
        Dims::new(self.states.len(), self.inputs.len(), self.outputs.len())
    }

    fn failure(&self, label: &str, derivative_of: Option<usize>, x: &[f64], u: &[f64], value: f64) -> ModelError {
        let mut values = String::new();
        for (name, v) in self.states.iter().zip(x).chain(self.inputs.iter().zip(u)) {
            if !values.is_empty() {
                values.push_str(", ");
            }
            values.push_str(&format!("{name} = {v}"));
        }
        let what = match derivative_of {
            Some(j) => format!("d({label})/d{}", self.states[j]),
            None => label.to_owned(),
        };
        ModelError::Evaluation(format!("equation `{what}` evaluates to {value} at {values}"))
    }

    fn check(&self, x: &DVector<f64>, u: &DVector<f64>) -> Result<(), ModelError> {
        let d = self.dims_();
        models::error::check_dims("x", x, d.states, 1)?;
        models::error::check_dims("u", u, d.inputs, 1)
    }

    /// Scratch numbers an evaluation needs: the nodes' values and derivatives, then the step's
    /// stage vectors and matrices.
    fn scratch_len(&self) -> usize {
        let n = self.states.len();
        self.graph.len() * (n + 1) + 6 * n + 4 * n * n
    }

    /// Evaluates `rows` at `(x, u)`: their values into `out` and, with `jac`, their derivatives
    /// with respect to the states (row-major, `rows × n`). `values` and `grads` are scratch of
    /// one number and `n` numbers per node.
    fn eval(
        &self,
        rows: &Rows,
        x: &[f64],
        u: &[f64],
        values: &mut [f64],
        grads: &mut [f64],
        out: &mut [f64],
        jac: Option<&mut [f64]>,
    ) -> Result<(), ModelError> {
        let n = x.len();
        values[..n].copy_from_slice(x);
        values[n..n + u.len()].copy_from_slice(u);
        if jac.is_some() {
            rows.tape.run_derivatives(n, values, grads);
        } else {
            rows.tape.run_values(values);
        }
        for (k, (o, &r)) in out.iter_mut().zip(&rows.roots).enumerate() {
            let v = values[r as usize];
            if !v.is_finite() {
                return Err(self.failure(&rows.labels[k], None, x, u, v));
            }
            *o = v;
        }
        if let Some(jac) = jac {
            for (k, &r) in rows.roots.iter().enumerate() {
                let row = &mut jac[k * n..(k + 1) * n];
                if self.varies[r as usize] {
                    row.copy_from_slice(&grads[r as usize * n..(r as usize + 1) * n]);
                    if let Some(j) = row.iter().position(|d| !d.is_finite()) {
                        return Err(self.failure(&rows.labels[k], Some(j), x, u, row[j]));
                    }
                } else {
                    row.fill(0.0);
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
        let nodes = self.graph.len();
        with_scratch(nodes, |buf| {
            self.eval(&self.rhs, x.as_slice(), u.as_slice(), buf, &mut [], out.as_mut_slice(), None)
        })
    }

    /// `h` and, if asked, `∂h/∂x`.
    fn measure(
        &self,
        x: &DVector<f64>,
        u: &DVector<f64>,
        out: Option<&mut DVector<f64>>,
        jac: Option<&mut DMatrix<f64>>,
    ) -> Result<(), ModelError> {
        self.check(x, u)?;
        let (n, m) = (self.states.len(), self.outputs.len());
        if let Some(o) = &out {
            models::error::check_dims("h(x, u)", *o, m, 1)?;
        }
        if let Some(j) = &jac {
            models::error::check_dims("H", *j, m, n)?;
        }
        let nodes = self.graph.len();
        let (mut out, mut jac) = (out, jac);
        with_scratch(nodes * (n + 1) + m * (n + 1), |buf| {
            let (values, rest) = buf.split_at_mut(nodes);
            let (grads, rest) = rest.split_at_mut(nodes * n);
            let (y, rows) = rest.split_at_mut(m);
            let want = jac.is_some();
            self.eval(&self.out, x.as_slice(), u.as_slice(), values, grads, y, want.then_some(&mut *rows))?;
            if let Some(o) = out.as_deref_mut() {
                o.as_mut_slice().copy_from_slice(y);
            }
            if let Some(j) = jac.as_deref_mut() {
                for ((i, c), e) in (0..m).flat_map(|i| (0..n).map(move |c| (i, c))).zip(rows.iter()) {
                    j[(i, c)] = *e;
                }
            }
            Ok(())
        })
    }

    /// One step into `out` and, if asked, its Jacobian.
    fn step(
        &self,
        x: &DVector<f64>,
        u: &DVector<f64>,
        out: Option<&mut DVector<f64>>,
        jac: Option<&mut DMatrix<f64>>,
    ) -> Result<(), ModelError> {
        self.check(x, u)?;
        let n = x.len();
        if let Some(o) = &out {
            models::error::check_dims("f(x, u)", *o, n, 1)?;
        }
        if let Some(j) = &jac {
            models::error::check_dims("F", *j, n, n)?;
        }
        let ts = match self.time {
            TimeModel::Continuous { discretization: Discretization::Zoh, .. } => return self.zoh_step(x, u, out, jac),
            TimeModel::Continuous { ts, .. } => ts,
            TimeModel::Discrete => 0.0,
        };
        let nodes = self.graph.len();
        let (mut out, mut jac) = (out, jac);
        with_scratch(self.scratch_len(), |buf| {
            let (values, rest) = buf.split_at_mut(nodes);
            let (grads, rest) = rest.split_at_mut(nodes * n);
            let (next, rest) = rest.split_at_mut(n);
            let (xs, rest) = rest.split_at_mut(n);
            let (k, rest) = rest.split_at_mut(4 * n);
            let (jst, rest) = rest.split_at_mut(n * n);
            let (prev, rest) = rest.split_at_mut(n * n);
            let (sum, tmp) = rest.split_at_mut(n * n);
            let want = jac.is_some();
            let (us, xv) = (u.as_slice(), x.as_slice());
            match self.time {
                TimeModel::Discrete => {
                    self.eval(&self.rhs, xv, us, values, grads, next, want.then_some(&mut *prev))?;
                }
                TimeModel::Continuous { discretization: Discretization::Euler, .. } => {
                    let k1 = &mut k[..n];
                    self.eval(&self.rhs, xv, us, values, grads, k1, want.then_some(&mut *prev))?;
                    for i in 0..n {
                        next[i] = xv[i] + k1[i] * ts;
                    }
                    if want {
                        for i in 0..n {
                            for c in 0..n {
                                let id = if i == c { 1.0 } else { 0.0 };
                                prev[i * n + c] = id + prev[i * n + c] * ts;
                            }
                        }
                    }
                }
                TimeModel::Continuous { .. } => {
                    // Classical RK4, the input held; the Jacobian by the chain rule through the
                    // stages: D1 = J(x1), D_s = J(x_s) (I + c_s D_{s-1}).
                    let weights = [1.0, 2.0, 2.0, 1.0];
                    let offsets = [0.0, ts / 2.0, ts / 2.0, ts];
                    xs.copy_from_slice(xv);
                    for s in 0..4 {
                        if s > 0 {
                            for i in 0..n {
                                xs[i] = xv[i] + k[(s - 1) * n + i] * offsets[s];
                            }
                        }
                        let ks = &mut k[s * n..(s + 1) * n];
                        self.eval(&self.rhs, xs, us, values, grads, ks, want.then_some(&mut *jst))?;
                        if want {
                            if s == 0 {
                                prev.copy_from_slice(jst);
                                sum.copy_from_slice(jst);
                            } else {
                                // tmp = I + c_s D_{s-1}; D_s = J(x_s) tmp.
                                for i in 0..n {
                                    for c in 0..n {
                                        let id = if i == c { 1.0 } else { 0.0 };
                                        tmp[i * n + c] = id + prev[i * n + c] * offsets[s];
                                    }
                                }
                                // Row-major D_s = J(x_s) tmp, read column-major as D_sᵀ = tmpᵀ Jᵀ.
                                dense_kernels::mul_slices(n, n, n, tmp, jst, prev);
                                for (a, &d) in sum.iter_mut().zip(prev.iter()) {
                                    *a += d * weights[s];
                                }
                            }
                        }
                    }
                    for i in 0..n {
                        let (k1, k2, k3, k4) = (k[i], k[n + i], k[2 * n + i], k[3 * n + i]);
                        next[i] = xv[i] + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (ts / 6.0);
                    }
                    if want {
                        for i in 0..n {
                            for c in 0..n {
                                let id = if i == c { 1.0 } else { 0.0 };
                                prev[i * n + c] = id + sum[i * n + c] * (ts / 6.0);
                            }
                        }
                    }
                }
            }
            if let Some(row) = next.iter().position(|v| !v.is_finite()) {
                return Err(ModelError::NonFiniteEntry { what: "f(x, u)".to_owned(), row, col: 0 });
            }
            if let Some(o) = out.as_deref_mut() {
                o.as_mut_slice().copy_from_slice(next);
            }
            if let Some(j) = jac.as_deref_mut() {
                for i in 0..n {
                    for c in 0..n {
                        j[(i, c)] = prev[i * n + c];
                    }
                }
            }
            Ok(())
        })
    }

    /// The exact zero-order hold `A_d x + B_d u` (and `A_d`).
    fn zoh_step(
        &self,
        x: &DVector<f64>,
        u: &DVector<f64>,
        out: Option<&mut DVector<f64>>,
        jac: Option<&mut DMatrix<f64>>,
    ) -> Result<(), ModelError> {
        let (a, b) = self
            .zoh
            .as_ref()
            .ok_or_else(|| ModelError::Evaluation("zero-order hold without its matrices".to_owned()))?;
        if let Some(out) = out {
            let n = x.len();
            with_scratch(n, |buf| {
                let mut bu = nalgebra::DVectorViewMut::from_slice(buf, n);
                a.mul_to(x, out);
                b.mul_to(u, &mut bu);
                *out += &bu;
                models::error::check_finite("f(x, u)", &*out)
            })?;
        }
        if let Some(j) = jac {
            j.copy_from(a);
        }
        Ok(())
    }

    /// The coefficients of `rows` on the states and on the inputs when every row is linear
    /// (structurally linear in every slot, zero at zero); else the first row that is not and why.
    fn coefficients(&self, rows: &Rows, deps: &Deps) -> Result<(DMatrix<f64>, DMatrix<f64>), (String, String)> {
        let (n, p) = (self.states.len(), self.inputs.len());
        let slots = n + p;
        let nodes = self.graph.len();
        let mut values = vec![0.0; nodes];
        self.graph.run(&rows.schedule, &mut values, None);
        let name = |s: usize| if s < n { &self.states[s] } else { &self.inputs[s - n] };
        for (label, &r) in rows.labels.iter().zip(&rows.roots) {
            let fail = |reason: String| (label.clone(), reason);
            let v = values[r as usize];
            if !v.is_finite() {
                return Err(fail("cannot be evaluated at zero states and inputs".to_owned()));
            }
            if v != 0.0 {
                return Err(fail(format!("has a constant term (it is {v} at zero states and inputs)")));
            }
            if let Some(s) = (0..slots).find(|&s| Deps::has(&deps.nonlinear, deps.words, r, s)) {
                return Err(fail(format!("is not linear in `{}` (its derivative is not a constant)", name(s))));
            }
        }
        // The derivatives at zero, in chunks of slots.
        const CHUNK: usize = 16;
        let mut coefficients = DMatrix::zeros(rows.roots.len(), slots);
        let mut grads = vec![0.0; nodes * CHUNK.min(slots.max(1))];
        for lo in (0..slots).step_by(CHUNK) {
            let width = CHUNK.min(slots - lo);
            let varies: Vec<bool> =
                (0..nodes as u32).map(|i| (lo..lo + width).any(|s| Deps::has(&deps.dep, deps.words, i, s))).collect();
            values.fill(0.0);
            let seeds = Seeds { lo, width, varies: &varies };
            self.graph.run(&rows.schedule, &mut values, Some((&mut grads, &seeds)));
            for (k, &r) in rows.roots.iter().enumerate() {
                if !varies[r as usize] {
                    continue;
                }
                for c in 0..width {
                    let d = grads[r as usize * width + c];
                    if !d.is_finite() {
                        let reason = format!("is not linear in `{}` (its derivative is not a constant)", name(lo + c));
                        return Err((rows.labels[k].clone(), reason));
                    }
                    coefficients[(k, lo + c)] = d;
                }
            }
        }
        let (mx, mu) = (coefficients.columns(0, n).into_owned(), coefficients.columns(n, p).into_owned());
        Ok((mx, mu))
    }

    /// `A`, `B`, `C` when every equation is linear in the states and inputs, vanishes at zero
    /// (no constant term) and `h` does not depend on the inputs.
    fn linear_matrices(&self, deps: &Deps) -> Option<ConstantModel> {
        let (a, b) = match (&self.zoh, self.time) {
            (Some((a, b)), _) => (a.clone(), b.clone()),
            (None, TimeModel::Continuous { ts, discretization }) => {
                let (ac, bc) = self.coefficients(&self.rhs, deps).ok()?;
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
            (None, _) => self.coefficients(&self.rhs, deps).ok()?,
        };
        let (c, d_out) = self.coefficients(&self.out, deps).ok()?;
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
        self.step(x, u, Some(out), None)
    }

    fn h(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DVector<f64>) -> Result<(), ModelError> {
        self.measure(x, u, Some(out), None)
    }

    /// The `angles` of the model file's `[model]` table.
    fn angles(&self) -> Angles<'_> {
        Angles::new(&self.angle_states, &self.angle_outputs)
    }
}

impl DifferentiableModel for EquationModel {
    fn f_jacobian(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        self.step(x, u, None, Some(out))
    }

    fn h_jacobian(&self, x: &DVector<f64>, u: &DVector<f64>, out: &mut DMatrix<f64>) -> Result<(), ModelError> {
        self.measure(x, u, None, Some(out))
    }

    fn f_with_jacobian(
        &self,
        x: &DVector<f64>,
        u: &DVector<f64>,
        out: &mut DVector<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<(), ModelError> {
        self.step(x, u, Some(out), Some(jacobian))
    }

    fn h_with_jacobian(
        &self,
        x: &DVector<f64>,
        u: &DVector<f64>,
        out: &mut DVector<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<(), ModelError> {
        self.measure(x, u, Some(out), Some(jacobian))
    }
}

impl AnyModel for EquationModel {
    fn discrete(&self) -> &dyn DiscreteModel {
        self
    }

    fn differentiable(&self) -> Option<&dyn DifferentiableModel> {
        Some(self)
    }

    /// Interval enclosures of `f`, `h` and their Jacobians over boxes (module `enclosure`), for
    /// the nonlinear set-membership filter.
    fn second_order(&self) -> Option<&dyn models::SecondOrderModel> {
        Some(self)
    }

    fn linear(&self) -> Option<&dyn LinearModel> {
        self.linear.as_ref().map(|m| m as &dyn LinearModel)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::graph::Op;
    use crate::ops::Fun;

    #[test]
    fn a_definition_is_evaluated_once_for_all_its_users() {
        let text = "[model]\nstates = [\"x\", \"y\"]\noutputs = [\"o\"]\n[definitions]\nd = \"sin(x) * y\"\n\
                    [f]\nx = \"d + x\"\ny = \"d * d - y\"\n[h]\no = \"d\"\n";
        let m = EquationModel::from_toml_str(text, "d.toml").unwrap();
        let sines =
            |rows: &Rows| rows.schedule.iter().filter(|&&i| matches!(m.graph.op(i), Op::Unary(Fun::Sin, _))).count();
        assert_eq!((sines(&m.rhs), sines(&m.out)), (1, 1));
        // sin, the product d, then d + x, d * d, d * d - y.
        assert_eq!(m.rhs.schedule.len(), 5);
        assert_eq!(m.out.schedule.len(), 2);
    }
}
