//! Whole logs: `Estimator.run(us, ys)` steps through every row inside Rust, with the GIL
//! released, and returns the estimates as arrays, so that Python's per-call overhead is paid
//! once per log instead of once per step.
//!
//! Memory is bounded: the result holds `3·T·n + T` floats, a `T`-long status list and the
//! estimator's detail columns; a log with `T·n` above [`MAX_RUN_VALUES`] is refused before
//! anything is allocated (split it: `run` continues from the current state, so consecutive runs
//! over the pieces give the same numbers as one run).

use std::time::{Duration, Instant};

use estimators::{AnyEstimator, AnyModel, EstimateKind, EstimatorError, StepStatus};
use nalgebra::DVector;
use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString, PyTuple};

use crate::convert::{column_out, table_out};

/// The largest `T·n` (rows times states) one `run` call accepts: 2²⁶ = 67 108 864, about 1.6 GB
/// of results (`3·T·n` floats for centres and bounds).
pub const MAX_RUN_VALUES: usize = 1 << 26;

/// The estimates of a whole log, in Rust.
pub struct RunOutput {
    rows: usize,
    states: usize,
    kind: EstimateKind,
    center: Vec<f64>,
    lower: Vec<f64>,
    upper: Vec<f64>,
    trace: Vec<f64>,
    codes: Vec<u16>,
    statuses: Vec<StepStatus>,
    details: Vec<(&'static str, Vec<f64>)>,
    /// The mask of the run's measurements (`rows × m`, row-major), if it had one.
    measured: Option<(Vec<bool>, usize)>,
}

/// How long one stretch of [`run_log`] may run before it returns for the caller to look at
/// Python's signals (Ctrl-C) with the GIL held: 50 ms.
pub const SLICE: Duration = Duration::from_millis(50);

impl RunOutput {
    /// Empty tables of `rows` rows for the estimates of `est` (allocated here: the caller checks
    /// `rows · n` against [`MAX_RUN_VALUES`] first).
    pub fn new(est: &AnyEstimator, rows: usize) -> Self {
        let n = est.dims().states;
        let fields = est.estimate().details().fields();
        Self {
            rows,
            states: n,
            kind: est.estimate().kind(),
            center: vec![0.0; rows * n],
            lower: vec![f64::NAN; rows * n],
            upper: vec![f64::NAN; rows * n],
            trace: vec![f64::NAN; rows],
            codes: vec![0; rows],
            statuses: Vec::new(),
            details: fields.iter().map(|f| (f.name, vec![f64::NAN; rows])).collect(),
            measured: None,
        }
    }

    /// Keeps the run's mask (`rows × m`, row-major) for the result.
    pub fn with_mask(mut self, mask: Option<Vec<bool>>, m: usize) -> Self {
        self.measured = mask.map(|mask| (mask, m));
        self
    }
}

/// Runs `est` over rows `start..` of `us` (row-major, `p` per row) and `ys` (`m` per row, the
/// estimator's measurement length) into `out`, for at most about `slice` of time; returns the
/// first row not yet run (`out.rows` when done).
///
/// # Errors
/// The row at which a step failed and the estimator's error; the estimator then holds the
/// estimate after the previous row.
pub fn run_log(
    est: &mut AnyEstimator,
    model: &dyn AnyModel,
    (us, ys, measured): (&[f64], &[f64], Option<&[bool]>),
    out: &mut RunOutput,
    start: usize,
    slice: Duration,
) -> Result<usize, (usize, EstimatorError)> {
    let d = est.dims();
    // (The estimator's measurement length: the fuzzy-adaptive filter's counts its receiver status.)
    let (n, p, m) = (d.states, d.inputs, d.outputs);
    let kind = out.kind;
    let began = Instant::now();
    let (mut u, mut y) = (DVector::zeros(p), DVector::zeros(m));
    for k in start..out.rows {
        // The clock is read every 64 rows (a step takes microseconds).
        if k > start && (k - start) % 64 == 0 && began.elapsed() >= slice {
            return Ok(k);
        }
        u.copy_from_slice(&us[k * p..(k + 1) * p]);
        y.copy_from_slice(&ys[k * m..(k + 1) * m]);
        let mask = measured.map(|all| &all[k * m..(k + 1) * m]).filter(|row| !row.iter().all(|&b| b));
        let e = match mask {
            None => est.step(model, &u, &y),
            Some(row) => est.step_partial(model, &u, &y, row),
        }
        .map_err(|e| (k, e))?;
        out.center[k * n..(k + 1) * n].copy_from_slice(e.center().as_slice());
        if kind != EstimateKind::Point {
            for i in 0..n {
                if let Some((lo, hi)) = e.bounds(i) {
                    out.lower[k * n + i] = lo;
                    out.upper[k * n + i] = hi;
                }
            }
            out.trace[k] = e.shape().trace();
        }
        let status = e.status();
        out.codes[k] = match out.statuses.iter().position(|s| *s == status) {
            Some(i) => i as u16,
            None => {
                out.statuses.push(status);
                (out.statuses.len() - 1) as u16
            }
        };
        let mut j = 0;
        e.details().for_each_field(&mut |_, value| {
            if let Some((_, column)) = out.details.get_mut(j) {
                column[k] = value.unwrap_or(f64::NAN);
            }
            j += 1;
        });
    }
    Ok(out.rows)
}

/// The estimates of a whole log (``Estimator.run``), one row per step.
///
/// Attributes
/// ----------
/// center : ndarray, shape (T, n)
///     The centres (means) after each step: row ``k`` estimates ``x[k+1]`` from ``us[k]``, ``ys[k]``.
/// lower, upper : ndarray, shape (T, n)
///     ``center -/+ sqrt(diag(shape))`` (one standard deviation, or the guaranteed interval); NaN for
///     point estimates.
/// trace : ndarray, shape (T,)
///     The trace of the shape matrix (covariance or ellipsoid); NaN for point estimates.
/// status : list[str]
///     Each step's status label (as ``Estimate.status``).
/// clean : ndarray of bool, shape (T,)
///     Whether each step ended cleanly.
/// details : dict[str, ndarray]
///     The estimator's own numbers per step (``tau1``...; NaN where a step has none).
/// measured : ndarray of bool, shape (T, m), or None
///     Which outputs each step used (the run's mask), or None when every output was measured.
/// kind : str
///     The estimates' kind.
///
/// All arrays are read-only.
#[pyclass(frozen, module = "port_estimation")]
pub struct RunResult {
    center: Py<PyArray2<f64>>,
    lower: Py<PyArray2<f64>>,
    upper: Py<PyArray2<f64>>,
    trace: Py<PyArray1<f64>>,
    status: Py<PyList>,
    clean: Py<PyArray1<bool>>,
    details: Py<PyDict>,
    measured: Option<Py<PyArray2<bool>>>,
    kind: EstimateKind,
    rows: usize,
}

impl RunResult {
    /// Moves the Rust results into NumPy arrays (no copies of the float tables).
    pub fn from_output(py: Python<'_>, out: RunOutput) -> PyResult<Self> {
        let RunOutput { rows, states, kind, center, lower, upper, trace, codes, statuses, details, measured } = out;
        let measured = measured.map(|(mask, m)| table_out(py, mask, rows, m).map(Bound::unbind)).transpose()?;
        let labels: Vec<Bound<'_, PyString>> = statuses.iter().map(|s| PyString::new(py, &s.label())).collect();
        let status = PyList::new(py, codes.iter().map(|c| &labels[usize::from(*c)]))?;
        let clean: Vec<bool> = codes.iter().map(|c| statuses[usize::from(*c)].is_clean()).collect();
        let d = PyDict::new(py);
        for (name, column) in details {
            d.set_item(name, column_out(py, column)?)?;
        }
        Ok(Self {
            center: table_out(py, center, rows, states)?.unbind(),
            lower: table_out(py, lower, rows, states)?.unbind(),
            upper: table_out(py, upper, rows, states)?.unbind(),
            trace: column_out(py, trace)?.unbind(),
            status: status.unbind(),
            clean: column_out(py, clean)?.unbind(),
            details: d.unbind(),
            measured,
            kind,
            rows,
        })
    }
}

#[pymethods]
impl RunResult {
    /// The centres, shape (T, n).
    #[getter]
    fn center(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        self.center.clone_ref(py)
    }

    /// The lower bounds, shape (T, n) (NaN for point estimates).
    #[getter]
    fn lower(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        self.lower.clone_ref(py)
    }

    /// The upper bounds, shape (T, n) (NaN for point estimates).
    #[getter]
    fn upper(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        self.upper.clone_ref(py)
    }

    /// The traces of the shape matrices, shape (T,) (NaN for point estimates).
    #[getter]
    fn trace(&self, py: Python<'_>) -> Py<PyArray1<f64>> {
        self.trace.clone_ref(py)
    }

    /// The status label of every step.
    #[getter]
    fn status(&self, py: Python<'_>) -> Py<PyList> {
        self.status.clone_ref(py)
    }

    /// Whether each step ended cleanly, shape (T,).
    #[getter]
    fn clean(&self, py: Python<'_>) -> Py<PyArray1<bool>> {
        self.clean.clone_ref(py)
    }

    /// The estimator's own numbers per step, by name.
    #[getter]
    fn details(&self, py: Python<'_>) -> Py<PyDict> {
        self.details.clone_ref(py)
    }

    /// Which outputs each step used, shape (T, m), or None when every output was measured.
    #[getter]
    fn measured(&self, py: Python<'_>) -> Option<Py<PyArray2<bool>>> {
        self.measured.as_ref().map(|m| m.clone_ref(py))
    }

    /// The estimates' kind.
    #[getter]
    fn kind(&self) -> &'static str {
        self.kind.label()
    }

    fn __len__(&self) -> usize {
        self.rows
    }

    /// Rebuilds a result from its tables (pickling: a result may come back from a Dask task).
    #[staticmethod]
    #[pyo3(name = "_restore", signature = (center, lower, upper, trace, status, clean, details, kind, measured = None))]
    #[allow(clippy::too_many_arguments)]
    fn restore(
        py: Python<'_>,
        center: PyReadonlyArray2<'_, f64>,
        lower: PyReadonlyArray2<'_, f64>,
        upper: PyReadonlyArray2<'_, f64>,
        trace: PyReadonlyArray1<'_, f64>,
        status: Vec<String>,
        clean: PyReadonlyArray1<'_, bool>,
        details: &Bound<'_, PyDict>,
        kind: &str,
        measured: Option<PyReadonlyArray2<'_, bool>>,
    ) -> PyResult<Self> {
        let kinds = [
            EstimateKind::Gaussian,
            EstimateKind::GuaranteedEllipsoid,
            EstimateKind::GuaranteedConstrainedZonotope,
            EstimateKind::Point,
        ];
        let kind = kinds
            .into_iter()
            .find(|k| k.label() == kind)
            .ok_or_else(|| crate::errors::value_error(format!("cannot restore a RunResult of kind {kind:?}")))?;
        let (rows, states) = (center.shape()[0], center.shape()[1]);
        let sizes_agree = [lower.shape(), upper.shape()].iter().all(|s| *s == [rows, states])
            && trace.len() == rows
            && clean.len() == rows
            && status.len() == rows;
        if !sizes_agree {
            return Err(crate::errors::value_error("cannot restore a RunResult from tables of different lengths"));
        }
        let table = |a: &PyReadonlyArray2<'_, f64>| -> PyResult<Py<PyArray2<f64>>> {
            Ok(table_out(py, a.as_array().iter().copied().collect(), rows, states)?.unbind())
        };
        let d = PyDict::new(py);
        for (name, column) in details.iter() {
            let column: PyReadonlyArray1<'_, f64> = column.extract()?;
            if column.len() != rows {
                return Err(crate::errors::value_error(format!("detail {name} has {} rows, not {rows}", column.len())));
            }
            d.set_item(name, column_out(py, column.as_array().to_vec())?)?;
        }
        Ok(Self {
            center: table(&center)?,
            lower: table(&lower)?,
            upper: table(&upper)?,
            trace: column_out(py, trace.as_array().to_vec())?.unbind(),
            status: PyList::new(py, status)?.unbind(),
            clean: column_out(py, clean.as_array().to_vec())?.unbind(),
            details: d.unbind(),
            measured: match measured {
                Some(mask) if mask.shape()[0] == rows => {
                    let m = mask.shape()[1];
                    Some(table_out(py, mask.as_array().iter().copied().collect(), rows, m)?.unbind())
                }
                Some(_) => {
                    return Err(crate::errors::value_error("cannot restore a RunResult: the mask's rows differ"));
                }
                None => None,
            },
            kind,
            rows,
        })
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        // A module-level function of the package, so that pickle finds it by name.
        let restore = py.import("port_estimation")?.getattr("_restore_run_result")?;
        let args = (
            self.center.clone_ref(py),
            self.lower.clone_ref(py),
            self.upper.clone_ref(py),
            self.trace.clone_ref(py),
            self.status.clone_ref(py),
            self.clean.clone_ref(py),
            self.details.clone_ref(py),
            self.kind.label(),
            self.measured.as_ref().map(|m| m.clone_ref(py)),
        )
            .into_pyobject(py)?;
        Ok((restore, args))
    }

    fn __repr__(&self) -> String {
        format!("RunResult(kind={:?}, rows={})", self.kind.label(), self.rows)
    }
}
