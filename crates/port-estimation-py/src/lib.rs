//! The native module `port_estimation._native` of the Python package `port_estimation`: a thin
//! binding layer over the workspace's estimators, in the style of polars and pydantic-core.
//!
//! * [`model`]: `Model` — a linear model from NumPy arrays or a vehicle model of the workspace,
//!   behind `models::AnyModel`; [`file`](mod@file): the model files of `port-est`.
//! * [`estimator`]: `Estimator(name, model, x0=, P0=, Q=, R=, **settings)` — any row of
//!   `estimators::registry::ESTIMATORS`, its keywords mapped to the row's settings by their
//!   `SettingsKind` ([`settings`]); `predict`, `update`, `step` return an `Estimate`
//!   ([`estimate`]); `run` filters a whole log in Rust with the GIL released ([`run`]).
//! * [`classes`]: `KalmanFilter`, `SetMembershipFilter`, … — `Estimator` with the name from
//!   `registry::names`.
//! * [`bag`]: `read_bag` — a ROS 2 bag (MCAP) as the arrays `run` takes, by the `ros-bag` crate;
//!   `inspect_bag` lists its topics and fields.
//! * [`errors`]: `ValueError` for bad input, `EstimationError`, `NumericalError`,
//!   `InconsistentDataError`, `RunError`, `BagError`; no panic reaches Python.
//!
//! The binding knows no estimator by name: everything it offers comes from the registry's table,
//! so a new row of the table is a new estimator in Python. The Python side
//! (`python/port_estimation/`) adds the type stubs and the Dask fleet batch (`fleet.py`).

pub mod bag;
pub mod classes;
pub mod convert;
pub mod errors;
pub mod estimate;
pub mod estimator;
pub mod file;
pub mod model;
pub mod run;
pub mod settings;

use pyo3::prelude::*;

/// Every estimator of the registry: a list of dicts with its ``name``, ``kind`` (of estimate),
/// ``summary``, what it ``needs`` of the model (``"linear"``, ``"differentiable"``, ``"discrete"``),
/// its ``settings`` (in words), the keywords it takes (``keywords``, with their meanings in
/// ``keyword_help``), ``extra_measurements`` (the
/// measurement columns beyond the model's outputs) and ``details`` (the numbers each step reports in
/// ``Estimate.details`` and ``RunResult.details``, name to meaning, in order).
#[pyfunction(name = "estimators")]
fn estimator_table(py: Python<'_>) -> PyResult<Vec<Bound<'_, pyo3::types::PyDict>>> {
    ::estimators::registry::ESTIMATORS
        .iter()
        .map(|e| {
            let d = pyo3::types::PyDict::new(py);
            d.set_item("name", e.name)?;
            d.set_item("kind", e.kind.label())?;
            d.set_item("summary", e.summary)?;
            d.set_item("needs", e.needs.label())?;
            d.set_item("settings", e.settings.describe())?;
            d.set_item("keywords", settings::setting_names(e.settings))?;
            let help = pyo3::types::PyDict::new(py);
            for k in e.settings.keywords() {
                help.set_item(k.name, k.meaning)?;
            }
            d.set_item("keyword_help", help)?;
            d.set_item("extra_measurements", e.extra_measurements)?;
            let details = pyo3::types::PyDict::new(py);
            for f in e.details {
                details.set_item(f.name, f.meaning)?;
            }
            d.set_item("details", details)?;
            Ok(d)
        })
        .collect()
}

/// The solvers of the set-membership filters' semidefinite program in this build
/// (``solver=``): the exact two-multiplier method first, then the SDP backends.
#[pyfunction]
fn solvers() -> Vec<&'static str> {
    ::estimators::SmfSolver::names()
}

/// Guaranteed (set-membership) and stochastic state estimation for port vehicles.
#[pymodule(name = "_native")]
fn native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<model::Model>()?;
    m.add_class::<file::ModelFile>()?;
    m.add_class::<estimate::Estimate>()?;
    m.add_class::<run::RunResult>()?;
    m.add_class::<estimator::Estimator>()?;
    m.add_class::<bag::BagLog>()?;
    m.add_class::<bag::BagInfo>()?;
    m.add_class::<classes::KalmanFilter>()?;
    m.add_class::<classes::ExtendedKalmanFilter>()?;
    m.add_class::<classes::UnscentedKalmanFilter>()?;
    m.add_class::<classes::SetMembershipFilter>()?;
    m.add_class::<classes::MovingHorizonEstimator>()?;
    m.add_class::<classes::NonlinearMHE>()?;
    m.add_class::<classes::FuzzyKalmanFilter>()?;
    m.add_function(wrap_pyfunction!(estimator_table, m)?)?;
    m.add_function(wrap_pyfunction!(solvers, m)?)?;
    m.add_function(wrap_pyfunction!(file::read_model, m)?)?;
    m.add_function(wrap_pyfunction!(file::parse_model, m)?)?;
    m.add_function(wrap_pyfunction!(bag::read_bag, m)?)?;
    m.add_function(wrap_pyfunction!(bag::inspect_bag, m)?)?;
    m.add("EstimationError", py.get_type::<errors::EstimationError>())?;
    m.add("NumericalError", py.get_type::<errors::NumericalError>())?;
    m.add("InconsistentDataError", py.get_type::<errors::InconsistentDataError>())?;
    m.add("RunError", py.get_type::<errors::RunError>())?;
    m.add("BagError", py.get_type::<errors::BagError>())?;
    m.add("MAX_RUN_VALUES", run::MAX_RUN_VALUES)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
