//! `port_estimation.Model`: what an estimator steps on — a linear model `(A, B, C)` from NumPy
//! arrays, or one of the workspace's vehicle models — behind [`models::AnyModel`], so that every
//! registry estimator takes the capability it needs from it. A model remembers how it was built
//! (its recipe), which is how it pickles (to Dask workers, say).

use std::sync::Arc;

use car_dynamics::{CarModel, CarParams};
use carrier_dynamics::{CarrierModel, CarrierParams};
use equation_models::EquationModel;
use models::{Angles, AnyModel, Capability, ConstantModel, Dims, Integrator};
use nalgebra::{DMatrix, DVector};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyTuple;
use truck_dynamics::{TruckEkfModel, TruckParams};
use vessel_dynamics::{DiscreteVessel, Vessel, VesselParams};

use crate::convert::{mat_out, matrix, vec_out, vector};
use crate::errors::{no_panic, value_error};

/// A model shared with the estimators (and with worker threads while the GIL is released).
pub type SharedModel = Arc<dyn AnyModel + Send + Sync>;

/// How a model was built: enough to build it again.
#[derive(Debug, Clone)]
enum Recipe {
    /// `(A, B, C)` and the indices of the angle states and angle outputs.
    Linear(DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, Vec<usize>, Vec<usize>),
    Truck {
        ts: f64,
    },
    Vessel {
        ts: f64,
        rk4_substeps: Option<usize>,
    },
    Carrier {
        speed: f64,
        load: usize,
        ts: f64,
    },
    Car {
        speed: f64,
        ts: f64,
    },
    /// A model file of equations (`equation-models`): its text and the name errors give it.
    Equations {
        text: String,
        file: String,
    },
    /// A `port-est` model file of equations: as [`Recipe::Equations`], with the noise keys of
    /// `port-est` (`q`, `r`, `p0`, `x0`, …) beside the equations.
    EquationFile {
        text: String,
        file: String,
    },
}

/// A discrete-time model ``x[k+1] = f(x[k], u[k]) + w[k]``, ``y[k+1] = h(x[k+1], u[k]) + v[k+1]``.
///
/// ``Model(A, B, C)`` is the linear time-invariant model ``f = A x + B u``, ``h = C x`` (``A`` is
/// n×n, ``B`` n×p — ``n × 0`` for no input — and ``C`` m×n). The vehicle models of the workspace are
/// built by the static methods ``Model.truck``, ``Model.vessel``, ``Model.carrier`` and
/// ``Model.car``; ``read_model(path)`` reads a ``port-est`` model file; ``Model.from_equations(text)``
/// compiles a nonlinear model written as equations (states, inputs, outputs, parameters, ``[f]`` or
/// ``[dxdt]`` with Euler or RK4, ``[h]``; exact symbolic Jacobians; a linear one is recognised as
/// linear — the format is in ``crates/equation-models/README.md``).
///
/// Every estimator runs on the models that offer what it needs (``capability``): the Kalman,
/// set-membership, moving-horizon and fuzzy-adaptive filters need a linear model, the EKF and the
/// nonlinear MHE Jacobians (``differentiable``), the UKF only ``f`` and ``h`` (``discrete``).
/// For a time-varying linear model pass the step's ``Model(A_k, B_k, C_k)`` as ``model=`` to
/// ``predict``/``update``/``step``.
///
/// Attributes
/// ----------
/// dims : tuple[int, int, int]
///     ``(n, p, m)``: states, inputs, outputs.
/// capability : str
///     ``"linear"``, ``"differentiable"`` or ``"discrete"``.
/// A, B, C : ndarray or None
///     The matrices of a linear model (read-only copies), None otherwise.
///
/// Examples
/// --------
/// >>> import numpy as np, port_estimation as pe
/// >>> m = pe.Model(np.array([[1.0, 0.1], [0.0, 1.0]]), np.array([[0.0], [0.1]]), np.array([[1.0, 0.0]]))
/// >>> m.dims
/// (2, 1, 1)
/// >>> m.f([1.0, 2.0], [0.5])
/// array([1.2 , 2.05])
#[pyclass(frozen, module = "port_estimation")]
pub struct Model {
    inner: SharedModel,
    recipe: Recipe,
    description: String,
}

impl Model {
    /// The model for the estimators.
    pub fn shared(&self) -> SharedModel {
        Arc::clone(&self.inner)
    }

    /// `(n, p, m)`.
    pub fn model_dims(&self) -> Dims {
        self.inner.discrete().dims()
    }

    /// A linear model from validated matrices, without angles.
    pub fn from_matrices(a: DMatrix<f64>, b: DMatrix<f64>, c: DMatrix<f64>) -> PyResult<Self> {
        Self::linear_with_angles(a, b, c, Vec::new(), Vec::new())
    }

    /// A linear model whose states `angle_states` and outputs `angle_outputs` are angles.
    fn linear_with_angles(
        a: DMatrix<f64>,
        b: DMatrix<f64>,
        c: DMatrix<f64>,
        mut angle_states: Vec<usize>,
        mut angle_outputs: Vec<usize>,
    ) -> PyResult<Self> {
        angle_states.sort_unstable();
        angle_outputs.sort_unstable();
        let m = ConstantModel::new(a.clone(), b.clone(), c.clone())
            .and_then(|m| m.with_angles(Angles::new(&angle_states, &angle_outputs)))
            .map_err(|e| value_error(e.to_string()))?;
        let (n, p, q) = (a.nrows(), b.ncols(), c.nrows());
        Ok(Self {
            inner: Arc::new(m),
            recipe: Recipe::Linear(a, b, c, angle_states, angle_outputs),
            description: format!("linear model, {n} states, {p} inputs, {q} outputs"),
        })
    }

    /// The equations of a `port-est` model file, already compiled (`model`), with the file's text
    /// to rebuild them when unpickled.
    pub fn from_equation_file(text: String, file: String, model: Arc<EquationModel>) -> Self {
        let description = format!("equations of {file}");
        Self { inner: model, recipe: Recipe::EquationFile { text, file }, description }
    }

    #[allow(non_snake_case)]
    fn from_array_likes(
        A: &Bound<'_, PyAny>,
        B: &Bound<'_, PyAny>,
        C: &Bound<'_, PyAny>,
        angles: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let a = matrix(A, "A", None, None)?;
        let n = a.nrows();
        if a.ncols() != n {
            return Err(value_error(format!("A must be square, got shape ({n}, {})", a.ncols())));
        }
        let b = matrix(B, "B", Some(n), None)?;
        let c = matrix(C, "C", None, Some(n))?;
        let (states, outputs) = match angles {
            Some(a) if !a.is_none() => angle_indices(a)?,
            _ => (Vec::new(), Vec::new()),
        };
        Self::linear_with_angles(a, b, c, states, outputs)
    }

    fn build(recipe: Recipe) -> PyResult<Self> {
        let err = |e: &dyn std::fmt::Display| value_error(e.to_string());
        let (inner, description): (SharedModel, String) = match &recipe {
            Recipe::Linear(a, b, c, s, o) => {
                return Self::linear_with_angles(a.clone(), b.clone(), c.clone(), s.clone(), o.clone());
            }
            Recipe::Truck { ts } => {
                let m = TruckEkfModel::new(TruckParams::digest_preset(), *ts).map_err(|e| err(&e))?;
                (Arc::new(m), format!("3-axle port truck, Pacejka tyres, Euler at {ts} s"))
            }
            Recipe::Vessel { ts, rk4_substeps } => {
                let integrator = match rk4_substeps {
                    Some(substeps) => Integrator::Rk4 { substeps: *substeps },
                    None => Integrator::Euler,
                };
                let vessel = Vessel::new(VesselParams::paper()).map_err(|e| err(&e))?;
                let m: DiscreteVessel = vessel.discretize(*ts, integrator).map_err(|e| err(&e))?;
                let scheme = rk4_substeps.map_or_else(|| "Euler".to_owned(), |s| format!("RK4 ({s} sub-steps)"));
                (Arc::new(m), format!("supply vessel, 3-DOF low-speed model, {scheme} at {ts} s"))
            }
            Recipe::Carrier { speed, load, ts } => {
                let params = CarrierParams::for_load(*load).map_err(|e| err(&e))?.with_speed(*speed);
                let d = CarrierModel::new(params).and_then(|m| m.discretize(*ts)).map_err(|e| err(&e))?;
                let (a, b, c) = d.to_dynamic();
                let m = ConstantModel::new(a, b, c).map_err(|e| err(&e))?;
                (Arc::new(m), format!("straddle carrier, {load} container(s), {speed} m/s, exact ZOH at {ts} s"))
            }
            Recipe::Car { speed, ts } => {
                let params = CarParams::digest_default().with_speed(*speed);
                let m = CarModel::new(params).and_then(|m| m.discretize(*ts)).map_err(|e| err(&e))?;
                (Arc::new(m), format!("single-track car, {speed} m/s, exact ZOH at {ts} s"))
            }
            Recipe::Equations { text, file } => {
                let m = EquationModel::from_toml_str(text, file).map_err(|e| err(&e))?;
                (Arc::new(m), format!("equations of {file}"))
            }
            Recipe::EquationFile { text, file } => {
                let m = EquationModel::from_toml_str_with_foreign_keys(text, file, &port_est::model::NOISE_KEYS)
                    .map_err(|e| err(&e))?;
                (Arc::new(m), format!("equations of {file}"))
            }
        };
        Ok(Self { inner, recipe, description })
    }

    fn input(&self, u: Option<&Bound<'_, PyAny>>) -> PyResult<DVector<f64>> {
        let p = self.model_dims().inputs;
        match u {
            Some(u) => vector(u, "u", p),
            None => Ok(DVector::zeros(p)),
        }
    }

    /// A Jacobian with `rows` rows at `(x, u)` by `evaluate` (`F` or `H`); ValueError for a model
    /// without Jacobians.
    fn jacobian<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        u: Option<&Bound<'py, PyAny>>,
        rows: usize,
        evaluate: impl FnOnce(
            &dyn models::DifferentiableModel,
            &DVector<f64>,
            &DVector<f64>,
            &mut DMatrix<f64>,
        ) -> Result<(), models::ModelError>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        no_panic(|| {
            let (x, u) = (self.state(x)?, self.input(u)?);
            let m = self
                .inner
                .differentiable()
                .ok_or_else(|| value_error("this model has no Jacobians (capability \"discrete\")"))?;
            let mut out = DMatrix::zeros(rows, self.model_dims().states);
            evaluate(m, &x, &u, &mut out).map_err(model_error)?;
            mat_out(py, &out)
        })
    }

    fn state(&self, x: &Bound<'_, PyAny>) -> PyResult<DVector<f64>> {
        vector(x, "x", self.model_dims().states)
    }

    fn linear_matrix<'py>(&self, py: Python<'py>, which: usize) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        match self.inner.linear() {
            Some(l) => Ok(Some(mat_out(py, [l.a(), l.b(), l.c()][which])?)),
            None => Ok(None),
        }
    }
}

/// `{"states": [...], "outputs": [...]}` (either key may be left out) as index lists.
fn angle_indices(angles: &Bound<'_, PyAny>) -> PyResult<(Vec<usize>, Vec<usize>)> {
    let dict = angles
        .cast::<pyo3::types::PyDict>()
        .map_err(|_| value_error("angles must be a dict {\"states\": [indices], \"outputs\": [indices]}"))?;
    let (mut states, mut outputs) = (Vec::new(), Vec::new());
    for (key, value) in dict.iter() {
        let key: String = key.extract().map_err(|_| value_error("angles: keys must be \"states\" or \"outputs\""))?;
        let list: Vec<usize> = value
            .extract()
            .map_err(|_| value_error(format!("angles[{key:?}] must be a list of non-negative integer indices")))?;
        match key.as_str() {
            "states" => states = list,
            "outputs" => outputs = list,
            _ => return Err(value_error(format!("angles: unknown key {key:?} (expected \"states\" or \"outputs\")"))),
        }
    }
    Ok((states, outputs))
}

fn model_error(e: models::ModelError) -> PyErr {
    value_error(format!("the model cannot be evaluated there: {e}"))
}

#[pymethods]
impl Model {
    /// A linear time-invariant model ``x[k+1] = A x[k] + B u[k]``, ``y[k+1] = C x[k+1]``.
    ///
    /// ``angles={"states": [i, ...], "outputs": [j, ...]}`` declares which states and outputs are
    /// angles in radians: innovations of angle outputs are wrapped to (−π, π], the UKF's means of
    /// angle rows are circular. Estimators never wrap a state.
    #[new]
    #[allow(non_snake_case)]
    #[pyo3(signature = (A, B, C, *, angles = None))]
    fn new(
        A: &Bound<'_, PyAny>,
        B: &Bound<'_, PyAny>,
        C: &Bound<'_, PyAny>,
        angles: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        no_panic(|| Self::from_array_likes(A, B, C, angles))
    }

    /// ``{"states": [...], "outputs": [...]}``: the indices of the states and outputs that are
    /// angles (declared by ``Model(..., angles=...)``, a model file's ``angles`` or the vehicle).
    #[getter]
    fn angles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        let a = self.inner.discrete().angles();
        let d = pyo3::types::PyDict::new(py);
        d.set_item("states", a.states.to_vec())?;
        d.set_item("outputs", a.outputs.to_vec())?;
        Ok(d)
    }

    /// The truck paper's EKF model (3-axle port truck, Pacejka-89 tyres): state ``[V_x, V_y, gamma]``,
    /// input ``[delta, omega_1..omega_6]`` (steering angle, wheel speeds), measurement
    /// ``[V_x, a_y, gamma]``; forward Euler at ``ts`` (the paper's 1 ms). Differentiable.
    #[staticmethod]
    #[pyo3(signature = (ts = truck_dynamics::PAPER_SAMPLE_PERIOD))]
    fn truck(ts: f64) -> PyResult<Self> {
        Self::build(Recipe::Truck { ts })
    }

    /// The dp-vessel paper's supply vessel: state ``[x, y, psi, u, v, r]``, input the thrust
    /// ``[tau_X, tau_Y, tau_N]``, measurement ``[x, y, psi]``; Euler at ``ts`` (the paper's 0.1 s), or
    /// RK4 with ``rk4_substeps`` sub-steps. Differentiable.
    #[staticmethod]
    #[pyo3(signature = (ts = vessel_dynamics::PAPER_SAMPLE_PERIOD, rk4_substeps = None))]
    fn vessel(ts: f64, rk4_substeps: Option<usize>) -> PyResult<Self> {
        Self::build(Recipe::Vessel { ts, rk4_substeps })
    }

    /// The straddle carrier of the set-membership paper with ``load`` containers (0, 1 or 2; 1 is the
    /// paper's Table 1) at ``speed`` m/s, discretised exactly (zero-order hold) at ``ts`` s: state
    /// ``[beta, gamma, phi, phi_dot]``, the eight steering angles as input, every state measured.
    /// Linear.
    #[staticmethod]
    #[pyo3(signature = (speed = 6.0, load = 1, ts = 1e-3))]
    fn carrier(speed: f64, load: i64, ts: f64) -> PyResult<Self> {
        let load = usize::try_from(load)
            .ok()
            .filter(|&l| l <= 2)
            .ok_or_else(|| value_error(format!("load must be 0, 1 or 2 containers, got {load}")))?;
        Self::build(Recipe::Carrier { speed, load, ts })
    }

    /// The robust-MHE paper's single-track car at ``speed`` m/s, exact zero-order hold at ``ts`` s:
    /// state ``[Y, psi, beta, r]``, front steering angle as input, lateral position measured. Linear.
    #[staticmethod]
    #[pyo3(signature = (speed = car_dynamics::DIGEST_SPEED, ts = car_dynamics::DIGEST_SAMPLING_PERIOD))]
    fn car(speed: f64, ts: f64) -> PyResult<Self> {
        Self::build(Recipe::Car { speed, ts })
    }

    /// A model written as equations: ``text`` is a model file of ``equation-models`` (``[model]``
    /// with ``states``, ``inputs``, ``outputs``; ``[parameters]``, ``[definitions]``; ``[f]`` or
    /// ``[dxdt]`` with ``ts`` and ``discretization``; ``[h]``), ``file`` the name its errors give.
    /// Jacobians are exact (symbolic); a linear model is recognised as linear, so every estimator
    /// that needs a linear model runs on it. A bad file raises ValueError at ``file:line:column``.
    ///
    /// >>> m = pe.Model.from_equations(open("pendulum.toml").read(), "pendulum.toml")  # doctest: +SKIP
    #[staticmethod]
    #[pyo3(signature = (text, file = "<string>"))]
    fn from_equations(py: Python<'_>, text: String, file: &str) -> PyResult<Self> {
        let recipe = Recipe::Equations { text, file: file.to_owned() };
        // Compiling differentiates every equation: up to a few seconds for a large model.
        py.detach(|| no_panic(|| Self::build(recipe)))
    }

    /// ``(n, p, m)``: states, inputs, outputs.
    #[getter]
    fn dims(&self) -> (usize, usize, usize) {
        let d = self.model_dims();
        (d.states, d.inputs, d.outputs)
    }

    /// The strongest capability: ``"linear"`` (A, B, C), ``"differentiable"`` (f, h and their
    /// Jacobians) or ``"discrete"`` (f and h).
    #[getter]
    fn capability(&self) -> &'static str {
        Capability::of(self.inner.as_ref()).label()
    }

    /// What the model is, in words.
    #[getter]
    fn description(&self) -> &str {
        &self.description
    }

    /// ``A`` of a linear model (a read-only copy), None otherwise.
    #[getter(A)]
    fn a<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        self.linear_matrix(py, 0)
    }

    /// ``B`` of a linear model (a read-only copy), None otherwise.
    #[getter(B)]
    fn b<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        self.linear_matrix(py, 1)
    }

    /// ``C`` of a linear model (a read-only copy), None otherwise.
    #[getter(C)]
    fn c<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        self.linear_matrix(py, 2)
    }

    /// ``f(x, u)``, the next state without noise (``u`` defaults to zeros).
    #[pyo3(signature = (x, u = None))]
    fn f<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        u: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        no_panic(|| {
            let (x, u) = (self.state(x)?, self.input(u)?);
            let mut out = DVector::zeros(self.model_dims().states);
            self.inner.discrete().f(&x, &u, &mut out).map_err(model_error)?;
            vec_out(py, out.as_slice())
        })
    }

    /// ``h(x, u)``, the measurement of state ``x`` without noise (``u`` defaults to zeros).
    #[pyo3(signature = (x, u = None))]
    fn h<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        u: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        no_panic(|| {
            let (x, u) = (self.state(x)?, self.input(u)?);
            let mut out = DVector::zeros(self.model_dims().outputs);
            self.inner.discrete().h(&x, &u, &mut out).map_err(model_error)?;
            vec_out(py, out.as_slice())
        })
    }

    /// The Jacobian ``F = df/dx`` at ``(x, u)`` (n×n); ValueError for a model without Jacobians.
    #[pyo3(name = "F", signature = (x, u = None))]
    fn f_jacobian<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        u: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.jacobian(py, x, u, self.model_dims().states, |m, x, u, out| m.f_jacobian(x, u, out))
    }

    /// The Jacobian ``H = dh/dx`` at ``(x, u)`` (m×n); ValueError for a model without Jacobians.
    #[pyo3(name = "H", signature = (x, u = None))]
    fn h_jacobian<'py>(
        &self,
        py: Python<'py>,
        x: &Bound<'py, PyAny>,
        u: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        self.jacobian(py, x, u, self.model_dims().outputs, |m, x, u, out| m.h_jacobian(x, u, out))
    }

    /// Rebuilds a model from its recipe (pickling).
    #[staticmethod]
    #[pyo3(name = "_restore")]
    fn restore(kind: &str, args: &Bound<'_, PyTuple>) -> PyResult<Self> {
        let bad = || value_error(format!("cannot restore a model of kind {kind:?} from {args}"));
        let f = |i: usize| -> PyResult<f64> { args.get_item(i)?.extract() };
        let recipe = match kind {
            "linear" => {
                let m =
                    |i: usize, what: &str| -> PyResult<DMatrix<f64>> { matrix(&args.get_item(i)?, what, None, None) };
                let indices = |i: usize| -> PyResult<Vec<usize>> {
                    if args.len() > i { args.get_item(i)?.extract() } else { Ok(Vec::new()) }
                };
                Recipe::Linear(m(0, "A")?, m(1, "B")?, m(2, "C")?, indices(3)?, indices(4)?)
            }
            "truck" => Recipe::Truck { ts: f(0)? },
            "vessel" => Recipe::Vessel { ts: f(0)?, rk4_substeps: args.get_item(1)?.extract()? },
            "carrier" => Recipe::Carrier { speed: f(0)?, load: args.get_item(1)?.extract()?, ts: f(2)? },
            "car" => Recipe::Car { speed: f(0)?, ts: f(1)? },
            "equations" => Recipe::Equations { text: args.get_item(0)?.extract()?, file: args.get_item(1)?.extract()? },
            "equation-file" => {
                Recipe::EquationFile { text: args.get_item(0)?.extract()?, file: args.get_item(1)?.extract()? }
            }
            _ => return Err(bad()),
        };
        no_panic(|| Self::build(recipe))
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let py = slf.py();
        let this = slf.get();
        // A module-level function of the package, so that pickle finds it by name.
        let restore = py.import("port_estimation")?.getattr("_restore_model")?;
        let args: Bound<'py, PyTuple> = match &this.recipe {
            Recipe::Linear(a, b, c, s, o) => {
                let (a, b, c) = (mat_out(py, a)?, mat_out(py, b)?, mat_out(py, c)?);
                ("linear", (a, b, c, s.clone(), o.clone())).into_pyobject(py)?
            }
            Recipe::Truck { ts } => ("truck", (*ts,)).into_pyobject(py)?,
            Recipe::Vessel { ts, rk4_substeps } => ("vessel", (*ts, *rk4_substeps)).into_pyobject(py)?,
            Recipe::Carrier { speed, load, ts } => ("carrier", (*speed, *load, *ts)).into_pyobject(py)?,
            Recipe::Car { speed, ts } => ("car", (*speed, *ts)).into_pyobject(py)?,
            Recipe::Equations { text, file } => ("equations", (text.as_str(), file.as_str())).into_pyobject(py)?,
            Recipe::EquationFile { text, file } => {
                ("equation-file", (text.as_str(), file.as_str())).into_pyobject(py)?
            }
        };
        Ok((restore, args))
    }

    fn __repr__(&self) -> String {
        let (n, p, m) = self.dims();
        format!("Model({}; n={n}, p={p}, m={m}, {})", self.description, self.capability())
    }
}
