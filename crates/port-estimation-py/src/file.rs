//! `port_estimation.read_model`: the model files of `port-est` (`a`, `b`, `c` or equations, `q`, `r`, `p0`,
//! `x0`, the input range and the `[mhe]` table), read by `port_est::parse_model`, so that a file
//! means the same in Python as on the command line, with the same `file:line:column` errors.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use estimators::registry;
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{mat_out, vec_out};
use crate::errors::value_error;
use crate::estimator::{Estimator, Initial};
use crate::model::Model;

/// A ``port-est`` model file: the model (matrices or equations) and the estimators' data.
///
/// Attributes
/// ----------
/// model : Model
///     ``Model(a, b, c)``, or the model written as equations.
/// x0, P0, Q, R : ndarray
///     The file's ``x0``, ``p0``, ``q``, ``r`` (read-only copies).
/// u_lower, u_upper : ndarray or None
///     The input range, if given.
/// has_mhe : bool
///     Whether the file has an ``[mhe]`` table (the settings of ``rmhe`` and ``mhe``).
/// has_log : bool
///     Whether the file has a ``[log]`` table (how ``read_bag`` reads a ROS 2 bag for it).
/// path : str
///     The file it was read from.
///
/// ``estimator(name, **settings)`` builds a registry estimator from the file, as
/// ``port-est filter --estimator NAME`` does; ``read_bag(path)`` reads a ROS 2 bag through the
/// file's ``[log]`` table, as ``port-est filter --input run.mcap`` does.
#[pyclass(frozen, module = "port_estimation")]
pub struct ModelFile {
    file: port_est::Model,
    model: Py<Model>,
    text: String,
}

impl ModelFile {
    fn parse(py: Python<'_>, path: &Path, text: String) -> PyResult<Self> {
        let file = port_est::parse_model(path, &text).map_err(|e| value_error(e.to_string()))?;
        let model = match &file.dynamics {
            port_est::model::Dynamics::Equations(m) => {
                Model::from_equation_file(text.clone(), path.display().to_string(), Arc::clone(m))
            }
            _ => {
                let linear = file.linear().ok_or_else(|| value_error("the model file's matrices are missing"))?;
                Model::from_matrices(linear.a().clone(), linear.b().clone(), linear.c().clone())?
            }
        };
        Ok(Self { file, model: Py::new(py, model)?, text })
    }
}

#[pymethods]
impl ModelFile {
    /// Builds the registry estimator ``name`` from the file: its ``x0``, ``p0``, ``q``, ``r``, its
    /// bounds, ``[mhe]`` and ``[ukf]`` tables where the estimator takes them and its
    /// ``[estimator.NAME]`` table over them; ``settings`` add to or override them
    /// (``solver="faer-ipm"``, ``horizon=8``...), read by the same code as ``port-est``'s tables.
    /// The default is the improved set-membership filter, as for ``port-est filter``.
    #[pyo3(signature = (name = registry::names::SMF, **settings))]
    fn estimator(&self, py: Python<'_>, name: &str, settings: Option<&Bound<'_, PyDict>>) -> PyResult<Estimator> {
        // The file's initial data as the estimator's kind reads them (boxes for the
        // constrained-zonotope filters).
        let kind = registry::entry(name).map_or(estimators::EstimateKind::Gaussian, |e| e.kind);
        let setup = self.file.setup(kind);
        let (x0, p0, q, r) = (
            vec_out(py, setup.x0.as_slice())?.into_any(),
            mat_out(py, &setup.p0)?.into_any(),
            mat_out(py, &setup.process_noise)?.into_any(),
            mat_out(py, &setup.measurement_noise)?.into_any(),
        );
        let initial = Initial { x0: Some(&x0), P0: Some(&p0), Q: Some(&q), R: Some(&r) };
        Estimator::create(py, name, self.model.bind(py), initial, settings, Some(&self.file))
    }

    /// Reads a ROS 2 bag (MCAP) as the file's ``[log]`` table maps it (the table ``port-est filter
    /// --input run.mcap`` reads, parsed by the same code): a ``BagLog`` whose ``u`` and ``y`` have
    /// the model's inputs and outputs in the model's order, for ``self.estimator(...).run(log.u,
    /// log.y, measured=log.measured)``. ``start`` (s) or ``start_ns`` (ns) place step 0 of a fixed
    /// step (``ts``), as for ``read_bag``.
    ///
    /// Raises ValueError if the file has no ``[log]`` table, and what ``read_bag`` raises.
    #[pyo3(signature = (path, *, start = None, start_ns = None))]
    fn read_bag(
        &self,
        py: Python<'_>,
        path: PathBuf,
        start: Option<f64>,
        start_ns: Option<i64>,
    ) -> PyResult<crate::bag::BagLog> {
        let Some(spec) = &self.file.log else {
            return Err(value_error(format!(
                "{}: no [log] table: a bag is read through a `[log]` table mapping the model's inputs and outputs \
                 to topics (or give the mapping to read_bag)",
                self.file.path().display()
            )));
        };
        crate::bag::read_with(py, path, spec, (start, start_ns))
    }

    /// Whether the file has a ``[log]`` table (``read_bag`` reads a bag through it).
    #[getter]
    fn has_log(&self) -> bool {
        self.file.log.is_some()
    }

    /// The model: ``Model(a, b, c)``, or the file's equations.
    #[getter]
    fn model(&self, py: Python<'_>) -> Py<Model> {
        self.model.clone_ref(py)
    }

    /// ``x0``.
    #[getter]
    fn x0<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        vec_out(py, self.file.x0.as_slice())
    }

    /// ``p0``.
    #[getter(P0)]
    fn p0<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        mat_out(py, &self.file.p0)
    }

    /// ``q``.
    #[getter(Q)]
    fn q<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        mat_out(py, &self.file.q)
    }

    /// ``r``.
    #[getter(R)]
    fn r<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        mat_out(py, &self.file.r)
    }

    /// ``u_lower``, if given.
    #[getter]
    fn u_lower<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray1<f64>>>> {
        self.file.input_range.as_ref().map(|(lo, _)| vec_out(py, lo.as_slice())).transpose()
    }

    /// ``u_upper``, if given.
    #[getter]
    fn u_upper<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray1<f64>>>> {
        self.file.input_range.as_ref().map(|(_, hi)| vec_out(py, hi.as_slice())).transpose()
    }

    /// Whether the file has an ``[mhe]`` table.
    #[getter]
    fn has_mhe(&self) -> bool {
        self.file.mhe.is_some()
    }

    /// The file it was read from.
    #[getter]
    fn path(&self) -> PathBuf {
        self.file.path().to_owned()
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String, PathBuf))> {
        let parse = py.import("port_estimation")?.getattr("parse_model")?;
        Ok((parse, (self.text.clone(), self.file.path().to_owned())))
    }

    fn __repr__(&self) -> String {
        format!(
            "ModelFile({:?}: {} states, {} inputs, {} outputs{}{})",
            self.file.path().display().to_string(),
            self.file.states(),
            self.file.inputs(),
            self.file.outputs(),
            if self.file.mhe.is_some() { ", [mhe]" } else { "" },
            if self.file.log.is_some() { ", [log]" } else { "" }
        )
    }
}

/// Reads a ``port-est`` model file (TOML: ``a``, ``b``, ``c``, ``q``, ``r``, ``p0``, ``x0``, optional
/// ``u_lower``/``u_upper`` and ``[mhe]``). A malformed file raises ValueError at its
/// ``file:line:column``.
#[pyfunction]
pub fn read_model(py: Python<'_>, path: PathBuf) -> PyResult<ModelFile> {
    match std::fs::read_to_string(&path) {
        Ok(text) => ModelFile::parse(py, &path, text),
        // port-est's reader says where (a missing file, the first byte that is not UTF-8).
        Err(e) => Err(value_error(
            port_est::read_model(&path).err().map_or_else(|| format!("{}: {e}", path.display()), |e| e.to_string()),
        )),
    }
}

/// Parses the text of a ``port-est`` model file (``path`` names it in errors).
#[pyfunction]
#[pyo3(signature = (text, path = PathBuf::from("<string>")))]
pub fn parse_model(py: Python<'_>, text: String, path: PathBuf) -> PyResult<ModelFile> {
    ModelFile::parse(py, &path, text)
}
