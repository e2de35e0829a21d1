//! Keyword settings → the registry's typed [`EstimatorSettings`], by the registry's one settings
//! reader ([`registry::read_settings`], the same that reads a model file's tables for
//! `port-est`): what a Python caller writes as `Estimator(name, model, solver="faer-ipm")` or
//! `horizon=10`. This module only converts Python values; every default, choice and limit is the
//! registry's. With a model file, the keywords override its `[estimator.NAME]` table, which
//! overrides its `[mhe]`, `[ukf]` and bounds.

use std::path::PathBuf;

use estimators::Dims;
use estimators::registry::{self, EstimatorEntry, EstimatorSettings, KeywordContext, KeywordSource, SettingsKind};
use port_est::keyword_table::TableReader;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::numbers;
use crate::errors::value_error;

/// How a Python caller raises a moving-horizon window's memory limit.
const RAISE_MEMORY: &str = "memory_limit=...";

/// The keywords each kind of settings takes (for error messages and `estimators()`): the
/// registry's ([`SettingsKind::keywords`]).
pub fn setting_names(kind: SettingsKind) -> Vec<&'static str> {
    kind.keywords().iter().map(|k| k.name).collect()
}

/// The keyword arguments, consumed one by one.
struct Kwargs<'py> {
    dict: Bound<'py, PyDict>,
}

impl<'py> Kwargs<'py> {
    fn new(py: Python<'py>, given: Option<&Bound<'py, PyDict>>) -> PyResult<Self> {
        Ok(Self { dict: given.map_or_else(|| Ok(PyDict::new(py)), |d| d.copy())? })
    }

    /// The value of `key` (None when absent or given as None).
    fn take(&self, key: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
        let value = self.dict.get_item(key)?;
        if value.is_some() {
            self.dict.del_item(key)?;
        }
        Ok(value.filter(|v| !v.is_none()))
    }

    fn extract<T: for<'a> FromPyObject<'a, 'py>>(&self, key: &str, what: &str) -> PyResult<Option<T>> {
        self.take(key)?
            .map(|v| v.extract::<T>().map_err(|_| value_error(format!("setting {key} must be {what}, got {v}"))))
            .transpose()
    }
}

impl KeywordSource for Kwargs<'_> {
    type Error = PyErr;

    fn number(&mut self, key: &'static str) -> PyResult<Option<f64>> {
        self.extract(key, "a number")
    }

    fn count(&mut self, key: &'static str) -> PyResult<Option<usize>> {
        self.extract(key, "a non-negative integer")
    }

    fn flag(&mut self, key: &'static str) -> PyResult<Option<bool>> {
        self.extract(key, "True or False")
    }

    fn text(&mut self, key: &'static str) -> PyResult<Option<String>> {
        self.extract(key, "a string")
    }

    fn path(&mut self, key: &'static str) -> PyResult<Option<PathBuf>> {
        self.extract(key, "a path")
    }

    fn numbers(&mut self, key: &'static str) -> PyResult<Option<Vec<f64>>> {
        self.take(key)?.map(|v| numbers(&v, key)).transpose()
    }

    fn counts(&mut self, key: &'static str) -> PyResult<Option<Vec<usize>>> {
        self.extract(key, "a sequence of non-negative integers")
    }

    fn refuse(&self, key: &str, message: String) -> PyErr {
        value_error(format!("setting {key}: {message}"))
    }

    fn unread(&self) -> Vec<String> {
        self.dict.keys().iter().map(|k| k.to_string()).collect()
    }
}

/// The keywords over a model file's table: a key given as a keyword is read from the keywords
/// (the file's value read and dropped), any other from the file (its errors at the file's
/// `line:column`).
struct OverFile<'py, 't> {
    kwargs: Kwargs<'py>,
    given: Vec<String>,
    file: TableReader<'t>,
}

impl OverFile<'_, '_> {
    fn file_error(e: port_est::error::Error) -> PyErr {
        value_error(e.to_string())
    }
}

/// One getter: the file's value, replaced by the keyword's when one is given.
macro_rules! over_file {
    ($name:ident, $t:ty) => {
        fn $name(&mut self, key: &'static str) -> PyResult<Option<$t>> {
            let from_file = self.file.$name(key).map_err(Self::file_error)?;
            Ok(self.kwargs.$name(key)?.or(from_file))
        }
    };
}

impl KeywordSource for OverFile<'_, '_> {
    type Error = PyErr;

    over_file!(number, f64);
    over_file!(count, usize);
    over_file!(flag, bool);
    over_file!(text, String);
    over_file!(path, PathBuf);
    over_file!(numbers, Vec<f64>);
    over_file!(counts, Vec<usize>);

    fn refuse(&self, key: &str, message: String) -> PyErr {
        if self.given.iter().any(|k| k == key) {
            self.kwargs.refuse(key, message)
        } else {
            Self::file_error(self.file.refuse(key, message))
        }
    }

    fn unread(&self) -> Vec<String> {
        let mut left = self.kwargs.unread();
        left.extend(self.file.unread());
        left
    }
}

/// The settings of `entry` from keywords, over the model file's when the estimator is built from
/// one (`None`: the row has no settings).
///
/// # Errors
/// `ValueError` for an unknown keyword, a value of the wrong type or out of its choices, or a
/// setting the row needs and nobody gave.
pub fn settings(
    py: Python<'_>,
    entry: &'static EstimatorEntry,
    dims: Dims,
    given: Option<&Bound<'_, PyDict>>,
    file: Option<&port_est::Model>,
) -> PyResult<Option<EstimatorSettings>> {
    let mut kwargs = Kwargs::new(py, given)?;
    let name = format!("estimator {}", entry.name);
    match file {
        None => {
            let cx = KeywordContext { raise_memory: RAISE_MEMORY, ..KeywordContext::new(dims) };
            registry::read_settings(entry.settings, &name, &cx, &mut kwargs)
        }
        Some(model) => {
            let given = kwargs.unread();
            // A caller's own memory_limit keyword is theirs to set; a file's stays under the limit
            // the file is read with, as in port-est.
            let mut cx = KeywordContext { raise_memory: RAISE_MEMORY, ..model.keyword_context() };
            if given.iter().any(|k| k == "memory_limit") {
                cx.memory_ceiling = u64::MAX;
            }
            let table = model.settings_table(entry.name);
            let mut source = OverFile { kwargs, given, file: table.reader(&[]) };
            registry::read_settings(entry.settings, &name, &cx, &mut source)
        }
    }
}
