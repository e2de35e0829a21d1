//! `port_estimation.Estimator`: any estimator of the registry, by name, over a [`Model`]. A thin
//! layer: the name selects a row of `estimators::registry::ESTIMATORS`, the keywords become the
//! row's settings by their kind ([`crate::settings`]), and every call runs the Rust estimator with
//! the GIL released and under `catch_unwind`.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard};

use estimators::registry::{self, EstimatorEntry};
use estimators::{AnyEstimator, DataChecks, Dims, EstimatorError, InconsistencyPolicy, Setup};
use nalgebra::{DMatrix, DVector};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{mat_out, measurement, measurement_table, square, table, vec_out, vector};
use crate::errors::{Guarded, broken, estimator_error, guard, no_panic, panicked, value_error};
use crate::estimate::Estimate;
use crate::model::{Model, SharedModel};
use crate::run::{MAX_RUN_VALUES, RunOutput, RunResult, SLICE, run_log};
use crate::settings::settings;

/// A state estimator from the registry, by name (``estimators()`` lists them).
///
/// ``Estimator(name, model, x0=None, P0=None, Q=None, R=None, **settings)`` builds the estimator
/// ``name`` for ``model``. What ``P0``, ``Q`` and ``R`` mean depends on the estimator: covariances for
/// the Kalman filters, ellipsoid shapes for the set-membership filters (``w`` in
/// ``{w : w' Q^-1 w <= 1}``), weights for the moving-horizon estimators. Each may be a matrix, its
/// diagonal or a scalar ``s`` meaning ``s·I``; they default to ``x0 = 0``, ``P0 = I``, ``Q = I``,
/// ``R = I`` (filterpy's defaults).
///
/// Four concepts, as in filterpy: the sizes (``dim_x``, ``dim_u``, ``dim_z``, from the model), the
/// attributes (``x``, ``P``, ``Q``, ``R``), ``predict(u)`` and ``update(y)``; ``step(u, y)`` is one of
/// each, and ``run(us, ys)`` filters a whole log in Rust. One step consumes the input ``u[k]`` and
/// the measurement ``y[k+1]`` taken after it, and returns the estimate of ``x[k+1]``.
///
/// Parameters
/// ----------
/// name : str
///     A registry name (``estimators()`` lists them with what each needs and takes).
/// model : Model
///     The model the estimator steps on (it must offer the capability the estimator needs).
/// x0 : array_like, shape (n,), optional
///     Initial centre (mean).
/// P0, Q : array_like, shape (n, n), (n,) or scalar, optional
///     Initial covariance or shape, process noise.
/// R : array_like, shape (m, m), (m,) or scalar, optional
///     Measurement noise.
/// **settings
///     The estimator's own settings (``estimators()`` lists them): ``solver`` and ``inconsistency``
///     of the set-membership filters, ``u_lower``/``u_upper`` of ``yang-li``, the noise boxes and
///     window of the moving-horizon estimators, ``alpha``/``beta``/``kappa`` of the UKF, ``fis`` of
///     the fuzzy-adaptive filter.
///
/// Attributes
/// ----------
/// x : ndarray, shape (n,)
///     The current centre (a read-only copy).
/// P : ndarray, shape (n, n)
///     The current covariance or shape (a read-only copy).
/// estimate : Estimate
///     The current estimate with its bounds, status and details.
/// Q, R : ndarray
///     The noise matrices the estimator was built with.
/// dim_x, dim_u, dim_z : int
///     States, inputs and measurement length (``dim_z`` includes the fuzzy-adaptive filter's two
///     receiver-status columns).
/// name, kind : str
///     The registry name and the kind of estimate.
/// model : Model
///     The model used when a call gives none.
///
/// Raises
/// ------
/// ValueError
///     Bad input: dimensions, NaN or infinity, a matrix that is not symmetric positive definite,
///     an unknown estimator, solver or setting, a model without the needed capability.
/// NumericalError
///     A step failed numerically.
/// InconsistentDataError
///     A set-membership step's measurement contradicts the bounds (``.step``, ``.excess``).
///
/// After any exception the estimator's state is what it was before the call.
///
/// Examples
/// --------
/// >>> import numpy as np, port_estimation as pe
/// >>> model = pe.Model([[1.0, 0.1], [0.0, 1.0]], [[0.0], [0.1]], [[1.0, 0.0]])
/// >>> smf = pe.Estimator("smf", model, P0=1.0, Q=1e-4, R=1e-2)
/// >>> e = smf.step([0.5], [0.02])
/// >>> e.kind, e.status
/// ('guaranteed ellipsoid', 'converged')
#[pyclass(subclass, frozen, module = "port_estimation")]
pub struct Estimator {
    inner: Mutex<AnyEstimator>,
    /// Calls waiting for `inner` (a long `run` lets them in between its stretches of rows).
    waiting: AtomicUsize,
    entry: &'static EstimatorEntry,
    model: Py<Model>,
    setup: Setup,
    dims: Dims,
}

/// One call on the estimator.
enum Call {
    Predict(DVector<f64>),
    Update(DVector<f64>),
    Step(DVector<f64>, DVector<f64>),
    /// A step with the outputs of the mask only.
    Partial(DVector<f64>, DVector<f64>, Vec<bool>),
}

/// The estimator's initial data from keywords (filterpy's defaults for what is not given).
#[allow(non_snake_case)]
pub struct Initial<'a, 'py> {
    /// `x0`.
    pub x0: Option<&'a Bound<'py, PyAny>>,
    /// `P0`.
    pub P0: Option<&'a Bound<'py, PyAny>>,
    /// `Q`.
    pub Q: Option<&'a Bound<'py, PyAny>>,
    /// `R`.
    pub R: Option<&'a Bound<'py, PyAny>>,
}

impl Initial<'_, '_> {
    fn setup(&self, d: Dims) -> PyResult<Setup> {
        let (n, m) = (d.states, d.outputs);
        Ok(Setup {
            x0: self.x0.map_or_else(|| Ok(DVector::zeros(n)), |v| vector(v, "x0", n))?,
            p0: self.P0.map_or_else(|| Ok(DMatrix::identity(n, n)), |v| square(v, "P0", n))?,
            process_noise: self.Q.map_or_else(|| Ok(DMatrix::identity(n, n)), |v| square(v, "Q", n))?,
            measurement_noise: self.R.map_or_else(|| Ok(DMatrix::identity(m, m)), |v| square(v, "R", m))?,
            inputs: d.inputs,
        })
    }
}

impl Estimator {
    /// Builds the estimator `name` for `model`.
    ///
    /// # Errors
    /// `ValueError` for an unknown name, a model without the capability, bad initial data or
    /// settings; the estimator's construction errors.
    pub fn create(
        py: Python<'_>,
        name: &str,
        model: &Bound<'_, Model>,
        initial: Initial<'_, '_>,
        given: Option<&Bound<'_, PyDict>>,
        file: Option<&port_est::Model>,
    ) -> PyResult<Self> {
        no_panic(|| Self::create_unguarded(py, name, model, initial, given, file))
    }

    fn create_unguarded(
        py: Python<'_>,
        name: &str,
        model: &Bound<'_, Model>,
        initial: Initial<'_, '_>,
        given: Option<&Bound<'_, PyDict>>,
        file: Option<&port_est::Model>,
    ) -> PyResult<Self> {
        let entry = registry::lookup(name).map_err(|e| estimator_error(py, &e, None))?;
        let shared = model.get().shared();
        if !entry.needs.is_offered_by(shared.as_ref()) {
            let e = EstimatorError::ModelLacksCapability {
                estimator: entry.name,
                needs: entry.needs,
                offered: models::Capability::of(shared.as_ref()),
            };
            return Err(estimator_error(py, &e, None));
        }
        let d = model.get().model_dims();
        let setup = initial.setup(d)?;
        let settings = settings(py, entry, d, given, file)?;
        let built = py.detach(|| guard(|| entry.build(setup.clone(), settings)));
        let inner = match built {
            // A setting the caller gave as a keyword is the caller's, not the file's.
            Guarded::Ran(Err(e))
                if crate::errors::is_bad_input(&e)
                    && file.is_some()
                    && !e.setting_keyword().is_some_and(|k| given.is_some_and(|d| d.contains(k).unwrap_or(false))) =>
            {
                let message = file.map(|f| f.estimator_error_for(entry.name, e).to_string()).unwrap_or_default();
                return Err(value_error(message));
            }
            Guarded::Ran(r) => r.map_err(|e| estimator_error(py, &e, None))?,
            Guarded::Broken(what) => {
                return Err(broken(format!(
                    "internal error while building {} ({what}); please report this",
                    entry.name
                )));
            }
        };
        let dims = inner.dims();
        Ok(Self {
            inner: Mutex::new(inner),
            waiting: AtomicUsize::new(0),
            entry,
            model: model.clone().unbind(),
            setup,
            dims,
        })
    }

    fn lock(&self) -> PyResult<MutexGuard<'_, AnyEstimator>> {
        self.inner.lock().map_err(|_| {
            broken(
                "the estimator failed internally in an earlier call and cannot be used any more: build a new one"
                    .into(),
            )
        })
    }

    /// The estimator for one call (not `run`'s stretches): counted as waiting meanwhile. `None`
    /// when an earlier call panicked.
    fn lock_for_call(&self) -> Option<MutexGuard<'_, AnyEstimator>> {
        self.waiting.fetch_add(1, Ordering::SeqCst);
        let est = self.inner.lock().ok();
        self.waiting.fetch_sub(1, Ordering::SeqCst);
        est
    }

    fn model_of(&self, model: Option<&Bound<'_, Model>>) -> SharedModel {
        model.map_or_else(|| self.model.get().shared(), |m| m.get().shared())
    }

    /// The length of `y` the estimator consumes (its dims count the fuzzy-adaptive filter's
    /// receiver status).
    fn measurement_len(&self) -> usize {
        self.dims.outputs
    }

    fn input(&self, u: Option<&Bound<'_, PyAny>>) -> PyResult<DVector<f64>> {
        u.map_or_else(|| Ok(DVector::zeros(self.dims.inputs)), |u| vector(u, "u", self.dims.inputs))
    }

    fn call(&self, py: Python<'_>, model: Option<&Bound<'_, Model>>, call: Call) -> PyResult<Estimate> {
        let model = self.model_of(model);
        let ran = py.detach(|| {
            guard(|| {
                let mut est = self.lock_for_call()?;
                let r = match &call {
                    Call::Predict(u) => est.predict(model.as_ref(), u),
                    Call::Update(y) => est.update(model.as_ref(), y),
                    Call::Step(u, y) => est.step(model.as_ref(), u, y),
                    Call::Partial(u, y, measured) => est.step_partial(model.as_ref(), u, y, measured),
                };
                Some(r.map(Estimate::of))
            })
        });
        match ran {
            Guarded::Ran(Some(r)) => r.map_err(|e| estimator_error(py, &e, None)),
            Guarded::Ran(None) => Err(self.lock().err().unwrap_or_else(|| broken("the estimator is unusable".into()))),
            Guarded::Broken(what) => Err(panicked(&what)),
        }
    }

    fn run_rows(
        &self,
        py: Python<'_>,
        us: Option<&Bound<'_, PyAny>>,
        ys: &Bound<'_, PyAny>,
        measured: Option<&Bound<'_, PyAny>>,
        model: Option<&Bound<'_, Model>>,
    ) -> PyResult<RunResult> {
        let (rows, ys, mask) = measurement_table(ys, measured, self.measurement_len())?;
        if rows.checked_mul(self.dims.states).is_none_or(|v| v > MAX_RUN_VALUES) {
            return Err(value_error(format!(
                "a run of {rows} steps of {} states exceeds MAX_RUN_VALUES = {MAX_RUN_VALUES} values per result \
                 table: split the log into consecutive runs",
                self.dims.states
            )));
        }
        let (_, us) = table(us, "us", Some(rows), self.dims.inputs)?;
        let model = self.model_of(model);
        let mut out = self.with_estimator(py, |est| RunOutput::new(est, rows))?;
        let m = self.measurement_len();
        // Stretches of about `SLICE` with the GIL released, Python's signals looked at between
        // them: Ctrl-C stops the run within a fraction of a second.
        let mut next = 0;
        while next < rows {
            let ran = py.detach(|| {
                guard(|| {
                    // Calls from other threads go first (the lock is not fair: without this a
                    // reader would wait for the whole run).
                    while self.waiting.load(Ordering::SeqCst) > 0 {
                        std::thread::yield_now();
                    }
                    let mut est = self.inner.lock().ok()?;
                    Some(run_log(&mut est, model.as_ref(), (&us, &ys, mask.as_deref()), &mut out, next, SLICE))
                })
            });
            next = match ran {
                Guarded::Ran(Some(Ok(k))) => k,
                Guarded::Ran(Some(Err((row, e)))) => return Err(run_error(py, &e, row)),
                Guarded::Ran(None) => {
                    return Err(self.lock().err().unwrap_or_else(|| broken("the estimator is unusable".into())));
                }
                Guarded::Broken(what) => return Err(panicked(&what)),
            };
            if next < rows
                && let Err(interrupt) = py.check_signals()
            {
                // The rows before `next` were filtered; the estimator holds the estimate after them.
                let _ = interrupt.value(py).setattr("row", next);
                return Err(interrupt);
            }
        }
        RunResult::from_output(py, out.with_mask(mask, m))
    }

    /// Runs `f` on the estimator with the GIL released (another thread's `run` may hold it: the
    /// wait must not stop every Python thread).
    fn with_estimator<T: Send>(&self, py: Python<'_>, f: impl FnOnce(&mut AnyEstimator) -> T + Send) -> PyResult<T> {
        match py.detach(|| guard(|| self.lock_for_call().map(|mut est| f(&mut est)))) {
            Guarded::Ran(Some(v)) => Ok(v),
            Guarded::Ran(None) => Err(self.lock().err().unwrap_or_else(|| broken("the estimator is unusable".into()))),
            Guarded::Broken(what) => Err(panicked(&what)),
        }
    }
}

/// The exception of a step of `run` that failed at `row`: as a single call's, except that a step
/// after the first refusing its row's values raises `RunError` (not `ValueError`, which means
/// nothing was done): the rows before `row` were filtered.
fn run_error(py: Python<'_>, e: &EstimatorError, row: usize) -> PyErr {
    if row > 0 && crate::errors::is_bad_input(e) {
        crate::errors::run_error(py, e, row)
    } else {
        estimator_error(py, e, Some(row))
    }
}

#[pymethods]
impl Estimator {
    #[new]
    #[pyo3(signature = (name, model, *, x0 = None, P0 = None, Q = None, R = None, **settings))]
    #[allow(non_snake_case)]
    fn new(
        py: Python<'_>,
        name: &str,
        model: &Bound<'_, Model>,
        x0: Option<&Bound<'_, PyAny>>,
        P0: Option<&Bound<'_, PyAny>>,
        Q: Option<&Bound<'_, PyAny>>,
        R: Option<&Bound<'_, PyAny>>,
        settings: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<Self> {
        Self::create(py, name, model, Initial { x0, P0, Q, R }, settings, None)
    }

    /// Predicts with the input ``u`` (zeros when None): the estimate of ``x[k+1]`` before its
    /// measurement. For a set-membership filter the set grows to cover every state the model and
    /// the process-noise bound allow; its next ``update`` makes the joint step with this prediction.
    /// ``model`` replaces the estimator's model for this call (a time-varying model's step).
    #[pyo3(signature = (u = None, *, model = None))]
    fn predict(
        &self,
        py: Python<'_>,
        u: Option<&Bound<'_, PyAny>>,
        model: Option<&Bound<'_, Model>>,
    ) -> PyResult<Estimate> {
        no_panic(|| self.call(py, model, Call::Predict(self.input(u)?)))
    }

    /// Updates with the measurement ``y`` (length ``dim_z``) taken after the last prediction. The
    /// moving-horizon estimators offer ``step`` only (an ``EstimationError`` says so).
    #[pyo3(signature = (y, *, model = None))]
    fn update(&self, py: Python<'_>, y: &Bound<'_, PyAny>, model: Option<&Bound<'_, Model>>) -> PyResult<Estimate> {
        no_panic(|| self.call(py, model, Call::Update(vector(y, "y", self.measurement_len())?)))
    }

    /// One step: predict with ``u`` (None: zeros), update with ``y``. Either both happen or, on an
    /// exception, neither.
    ///
    /// A partial measurement (sensors at their own rates, a dropout): ``y`` as a ``numpy.ma``
    /// masked array (masked entries were not measured) or ``measured=`` a boolean array, True where
    /// measured. The update uses the measured rows of ``h`` and the sub-block of ``R``; nothing
    /// measured is a prediction. The Kalman filter, EKF, UKF and the constrained-zonotope filters
    /// take any subset; the others only all or nothing. NaN stays an error in a measured entry.
    #[pyo3(signature = (u, y, *, measured = None, model = None))]
    fn step(
        &self,
        py: Python<'_>,
        u: Option<&Bound<'_, PyAny>>,
        y: &Bound<'_, PyAny>,
        measured: Option<&Bound<'_, PyAny>>,
        model: Option<&Bound<'_, Model>>,
    ) -> PyResult<Estimate> {
        no_panic(|| {
            let u = self.input(u)?;
            match measurement(y, measured, self.measurement_len())? {
                (y, None) => self.call(py, model, Call::Step(u, y)),
                (y, Some(mask)) => self.call(py, model, Call::Partial(u, y, mask)),
            }
        })
    }

    /// Filters a whole log inside Rust with the GIL released: ``us`` has shape ``(T, dim_u)`` (None
    /// when the model has no input), ``ys`` shape ``(T, dim_z)``; row ``k`` is one ``step(us[k], ys[k])``
    /// and the result (a ``RunResult``) holds the same numbers the steps would return. The run
    /// continues from the current estimate and leaves the estimator after the last row.
    ///
    /// Bad input (shapes, NaN or infinity anywhere) raises ValueError before any step, leaving the
    /// estimator unchanged. A step that fails raises its exception with ``.row`` set to the row; the
    /// estimator then holds the estimate after the previous row. ``T * dim_x`` may be at most
    /// ``MAX_RUN_VALUES`` (split longer logs into consecutive runs).
    ///
    /// Partial rows (sensors at their own rates): ``ys`` as a ``numpy.ma`` masked array, or
    /// ``measured=`` a boolean ``(T, dim_z)`` array; each row is then ``step(u, y, measured=row)``.
    #[pyo3(signature = (us, ys, *, measured = None, model = None))]
    fn run(
        &self,
        py: Python<'_>,
        us: Option<&Bound<'_, PyAny>>,
        ys: &Bound<'_, PyAny>,
        measured: Option<&Bound<'_, PyAny>>,
        model: Option<&Bound<'_, Model>>,
    ) -> PyResult<RunResult> {
        no_panic(|| self.run_rows(py, us, ys, measured, model))
    }

    /// How the estimator checks its data against its noise description. ``policy``: ``"error"``
    /// (default: a step whose data contradict the description raises ``InconsistentDataError``,
    /// the estimator unchanged), ``"flag"`` (publish the step marked inconsistent and continue),
    /// ``"restart"`` (Gaussian filters: drop the measurement and publish the prediction; the
    /// set-membership filter: move the set to the data), ``"off"`` (check nothing).
    /// ``gate_probability`` is the Gaussian filters' innovation gate: a measurement whose normalised
    /// innovation squared exceeds the chi-squared quantile of this probability is inconsistent
    /// (default ``1 - 1e-12``). The moving-horizon estimators of linear models check each window
    /// against their boxes ``W`` and ``V``; the nonlinear MHE accepts ``"off"`` only.
    #[pyo3(signature = (policy = "error", *, gate_probability = None))]
    fn set_data_checks(&self, py: Python<'_>, policy: &str, gate_probability: Option<f64>) -> PyResult<()> {
        no_panic(|| {
            let policy = match policy {
                "error" => InconsistencyPolicy::Error,
                "flag" => InconsistencyPolicy::FlagAndContinue,
                "restart" => InconsistencyPolicy::Restart,
                "off" => InconsistencyPolicy::Off,
                other => {
                    return Err(value_error(format!(
                        "policy {other:?}: expected one of \"error\", \"flag\", \"restart\", \"off\""
                    )));
                }
            };
            let gate_probability = gate_probability.unwrap_or(DataChecks::DEFAULT_GATE_PROBABILITY);
            self.with_estimator(py, |est| est.set_data_checks(DataChecks { policy, gate_probability }))?
                .map_err(|e| estimator_error(py, &e, None))
        })
    }

    /// The current centre (mean), a read-only copy, shape (n,).
    #[getter]
    fn x<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let x = self.with_estimator(py, |est| est.estimate().center().as_slice().to_vec())?;
        vec_out(py, &x)
    }

    /// The current covariance or shape matrix, a read-only copy, shape (n, n).
    #[getter(P)]
    fn p<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let p = self.with_estimator(py, |est| est.estimate().shape().clone())?;
        mat_out(py, &p)
    }

    /// The current estimate (centre, shape, bounds, status, details).
    #[getter]
    fn estimate(&self, py: Python<'_>) -> PyResult<Estimate> {
        self.with_estimator(py, |est| Estimate::of(est.estimate()))
    }

    /// The process noise the estimator was built with (a read-only copy).
    #[getter(Q)]
    fn q<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        mat_out(py, &self.setup.process_noise)
    }

    /// The measurement noise the estimator was built with (a read-only copy).
    #[getter(R)]
    fn r<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        mat_out(py, &self.setup.measurement_noise)
    }

    /// The number of states ``n``.
    #[getter]
    fn dim_x(&self) -> usize {
        self.dims.states
    }

    /// The number of inputs ``p``.
    #[getter]
    fn dim_u(&self) -> usize {
        self.dims.inputs
    }

    /// The length of a measurement ``y`` (the model's outputs, plus the receiver status of the
    /// fuzzy-adaptive filter).
    #[getter]
    fn dim_z(&self) -> usize {
        self.measurement_len()
    }

    /// The registry name.
    #[getter]
    fn name(&self) -> &'static str {
        self.entry.name
    }

    /// The kind of estimate: ``"gaussian"``, ``"guaranteed ellipsoid"``, ``"guaranteed constrained zonotope"`` or
    /// ``"point"``.
    #[getter]
    fn kind(&self) -> &'static str {
        self.entry.kind.label()
    }

    /// The model used when a call gives none.
    #[getter]
    fn model(&self, py: Python<'_>) -> Py<Model> {
        self.model.clone_ref(py)
    }

    fn __repr__(&self) -> String {
        let d = self.dims;
        format!(
            "Estimator({:?}: {}; n={}, p={}, m={})",
            self.entry.name, self.entry.summary, d.states, d.inputs, d.outputs
        )
    }
}
