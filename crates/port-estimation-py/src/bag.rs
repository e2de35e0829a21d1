//! `port_estimation.read_bag` and `inspect_bag`: ROS 2 bags (MCAP) read by the `ros-bag` crate
//! into the arrays `Estimator.run` takes (`u`, `y` with NaN where unmeasured, `measured`), with
//! the GIL released. Rows stream in Rust into flat tables that become the arrays without a copy:
//! no Python object per row.

use std::path::{Path, PathBuf};
use std::time::Instant;

use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyMapping, PyString, PyTuple};
use ros_bag::{Bag, LogSpec, Mapping, Row, Rows, Stamps};

use crate::convert::{column_out, table_out};
use crate::errors::{BagError, Guarded, broken, guard, value_error};
use crate::run::SLICE;

/// The rows of a bag as read (`Row`s flattened, row-major).
#[derive(Default)]
struct Tables {
    rows: usize,
    k: Vec<i64>,
    t_ns: Vec<i64>,
    t: Vec<f64>,
    u: Vec<f64>,
    y: Vec<f64>,
    measured: Vec<bool>,
}

impl Tables {
    fn push(&mut self, row: Row) {
        self.rows += 1;
        self.k.push(i64::try_from(row.k).unwrap_or(i64::MAX));
        self.t_ns.push(row.t_ns);
        self.t.push(row.t);
        self.u.extend_from_slice(&row.u);
        self.y.extend_from_slice(&row.y);
        self.measured.extend_from_slice(&row.measured);
    }

    /// Reads rows for about `SLICE`; `true` once they are all read.
    fn fill(&mut self, rows: &mut Rows<'_>) -> ros_bag::Result<bool> {
        let began = Instant::now();
        let mut n = 0u32;
        for row in rows.by_ref() {
            self.push(row?);
            n = n.wrapping_add(1);
            if n % 256 == 0 && began.elapsed() >= SLICE {
                return Ok(false);
            }
        }
        Ok(true)
    }
}

/// The rows of a bag as arrays (``read_bag``), one row per step.
///
/// Attributes
/// ----------
/// u : ndarray, shape (T, p)
///     The inputs of each step, in the order of ``inputs`` (each held from its topic's latest
///     message at or before the step's time).
/// y : ndarray, shape (T, m)
///     The outputs measured in each step's window, in the order of ``outputs``; NaN where not
///     measured.
/// measured : ndarray of bool, shape (T, m)
///     Which outputs were measured: ``est.run(log.u, log.y, measured=log.measured)``.
/// t : ndarray, shape (T,)
///     Each step's time (s, in the stamps' epoch); ``t_ns`` the same in integer nanoseconds.
/// k : ndarray of int64, shape (T,)
///     The steps, from 0.
/// inputs, outputs : list[str]
///     The mapping keys, in the order of the columns.
/// header_stamped : dict[str, bool]
///     Each mapped topic and whether its messages were stamped by ``header.stamp``.
/// path : str
///     The bag.
///
/// All arrays are read-only.
#[pyclass(frozen, module = "port_estimation")]
pub struct BagLog {
    path: PathBuf,
    inputs: Vec<String>,
    outputs: Vec<String>,
    header_stamped: Vec<(String, bool)>,
    k: Py<PyArray1<i64>>,
    t_ns: Py<PyArray1<i64>>,
    t: Py<PyArray1<f64>>,
    u: Py<PyArray2<f64>>,
    y: Py<PyArray2<f64>>,
    measured: Py<PyArray2<bool>>,
    rows: usize,
}

impl BagLog {
    fn new(
        py: Python<'_>,
        path: PathBuf,
        (inputs, outputs): (Vec<String>, Vec<String>),
        header_stamped: Vec<(String, bool)>,
        tables: Tables,
    ) -> PyResult<Self> {
        let Tables { rows, k, t_ns, t, u, y, measured } = tables;
        let (p, m) = (inputs.len(), outputs.len());
        Ok(Self {
            path,
            k: column_out(py, k)?.unbind(),
            t_ns: column_out(py, t_ns)?.unbind(),
            t: column_out(py, t)?.unbind(),
            u: table_out(py, u, rows, p)?.unbind(),
            y: table_out(py, y, rows, m)?.unbind(),
            measured: table_out(py, measured, rows, m)?.unbind(),
            inputs,
            outputs,
            header_stamped,
            rows,
        })
    }
}

#[pymethods]
impl BagLog {
    /// The inputs, shape (T, p).
    #[getter]
    fn u(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        self.u.clone_ref(py)
    }

    /// The outputs, shape (T, m); NaN where not measured.
    #[getter]
    fn y(&self, py: Python<'_>) -> Py<PyArray2<f64>> {
        self.y.clone_ref(py)
    }

    /// Which outputs each step measured, shape (T, m).
    #[getter]
    fn measured(&self, py: Python<'_>) -> Py<PyArray2<bool>> {
        self.measured.clone_ref(py)
    }

    /// The steps' times (s), shape (T,).
    #[getter]
    fn t(&self, py: Python<'_>) -> Py<PyArray1<f64>> {
        self.t.clone_ref(py)
    }

    /// The steps' times (ns), shape (T,).
    #[getter]
    fn t_ns(&self, py: Python<'_>) -> Py<PyArray1<i64>> {
        self.t_ns.clone_ref(py)
    }

    /// The steps, from 0, shape (T,).
    #[getter]
    fn k(&self, py: Python<'_>) -> Py<PyArray1<i64>> {
        self.k.clone_ref(py)
    }

    /// The input keys, in the order of the columns of ``u``.
    #[getter]
    fn inputs(&self) -> Vec<String> {
        self.inputs.clone()
    }

    /// The output keys, in the order of the columns of ``y``.
    #[getter]
    fn outputs(&self) -> Vec<String> {
        self.outputs.clone()
    }

    /// Each mapped topic and whether its messages were stamped by ``header.stamp``.
    #[getter]
    fn header_stamped<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (topic, header) in &self.header_stamped {
            d.set_item(topic, header)?;
        }
        Ok(d)
    }

    /// The bag.
    #[getter]
    fn path(&self) -> String {
        self.path.display().to_string()
    }

    fn __len__(&self) -> usize {
        self.rows
    }

    /// Rebuilds a log from its tables (pickling).
    #[staticmethod]
    #[pyo3(name = "_restore")]
    fn restore(
        py: Python<'_>,
        path: PathBuf,
        names: (Vec<String>, Vec<String>),
        header_stamped: Vec<(String, bool)>,
        times: (PyReadonlyArray1<'_, i64>, PyReadonlyArray1<'_, i64>, PyReadonlyArray1<'_, f64>),
        tables: (PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, f64>, PyReadonlyArray2<'_, bool>),
    ) -> PyResult<Self> {
        let ((k, t_ns, t), (u, y, measured)) = (times, tables);
        let rows = k.len();
        let (p, m) = (names.0.len(), names.1.len());
        let agree = t_ns.len() == rows
            && t.len() == rows
            && u.shape() == [rows, p]
            && y.shape() == [rows, m]
            && measured.shape() == [rows, m];
        if !agree {
            return Err(value_error("cannot restore a BagLog from tables of different sizes"));
        }
        let tables = Tables {
            rows,
            k: k.to_vec()?,
            t_ns: t_ns.to_vec()?,
            t: t.to_vec()?,
            u: u.as_array().iter().copied().collect(),
            y: y.as_array().iter().copied().collect(),
            measured: measured.as_array().iter().copied().collect(),
        };
        Self::new(py, path, names, header_stamped, tables)
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let restore = py.import("port_estimation")?.getattr("BagLog")?.getattr("_restore")?;
        let args = (
            self.path.clone(),
            (self.inputs.clone(), self.outputs.clone()),
            self.header_stamped.clone(),
            (self.k.clone_ref(py), self.t_ns.clone_ref(py), self.t.clone_ref(py)),
            (self.u.clone_ref(py), self.y.clone_ref(py), self.measured.clone_ref(py)),
        )
            .into_pyobject(py)?;
        Ok((restore, args))
    }

    fn __repr__(&self) -> String {
        format!(
            "BagLog({:?}: {} rows, inputs {:?}, outputs {:?})",
            self.path.display().to_string(),
            self.rows,
            self.inputs,
            self.outputs
        )
    }
}

/// The `(key, topic, field)` mappings of `obj` (`{key: "topic:field" | (topic, field)}`).
fn mappings(obj: Option<&Bound<'_, PyAny>>, what: &str) -> PyResult<Vec<Mapping>> {
    let Some(obj) = obj else { return Ok(Vec::new()) };
    let form = "\"topic:field\" or a (topic, field) pair";
    let map = obj
        .cast::<PyMapping>()
        .map_err(|_| value_error(format!("{what} must be a mapping of names to {form}, got {}", type_name(obj))))?;
    let mut out = Vec::new();
    for item in map.items()?.iter() {
        let (key, value): (Bound<'_, PyAny>, Bound<'_, PyAny>) = item.extract()?;
        let key: String = key
            .extract()
            .map_err(|_| value_error(format!("{what}: the keys must be strings, got {}", type_name(&key))))?;
        let bad = |why: &str| value_error(format!("{what}[{key:?}]: {why}; write {form}"));
        let (topic, field) = if let Ok(s) = value.cast::<PyString>() {
            let s = s.to_str()?;
            match s.split_once(':') {
                Some((t, f)) if !f.contains(':') => (t.to_owned(), f.to_owned()),
                _ => return Err(bad(&format!("{s:?} is not \"topic:field\""))),
            }
        } else {
            value.extract::<(String, String)>().map_err(|_| bad(&format!("got {}", type_name(&value))))?
        };
        if topic.is_empty() || field.is_empty() {
            return Err(bad("the topic and the field must not be empty"));
        }
        out.push(Mapping { key, topic, field });
    }
    Ok(out)
}

fn type_name(obj: &Bound<'_, PyAny>) -> String {
    obj.get_type().name().map_or_else(|_| "?".to_owned(), |n| n.to_string())
}

/// Nanoseconds of `seconds` (a time or a span), or a `ValueError` naming `what`.
fn nanoseconds(seconds: f64, what: &str) -> PyResult<i64> {
    let ns = (seconds * 1e9).round();
    if ns.is_finite() && (-9.2e18..9.2e18).contains(&ns) {
        Ok(ns as i64)
    } else {
        Err(value_error(format!("{what} = {seconds} s is not a usable time")))
    }
}

/// `spec` with step 0 at `start` (s) or `start_ns` (ns), if given (a fixed step only).
fn with_start(spec: LogSpec, start: Option<f64>, start_ns: Option<i64>) -> PyResult<LogSpec> {
    if (start.is_some() || start_ns.is_some()) && !matches!(spec.time_base(), ros_bag::TimeBase::FixedStep { .. }) {
        return Err(value_error("start= and start_ns= apply to a fixed step (ts=), not to driving="));
    }
    match (start, start_ns) {
        (Some(_), Some(_)) => Err(value_error("give start= (s) or start_ns= (ns), not both")),
        (Some(s), None) => Ok(spec.start_ns(nanoseconds(s, "start")?)),
        (None, Some(ns)) => Ok(spec.start_ns(ns)),
        (None, None) => Ok(spec),
    }
}

/// The spec the arguments of `read_bag` ask for.
fn spec(
    (inputs, outputs): (Vec<Mapping>, Vec<Mapping>),
    (ts, driving): (Option<f64>, Option<String>),
    stamps: &str,
    (start, start_ns): (Option<f64>, Option<i64>),
    reorder_window: Option<f64>,
) -> PyResult<LogSpec> {
    let mut spec = match (ts, driving) {
        (Some(ts), None) => {
            if !(ts.is_finite() && ts > 0.0) {
                return Err(value_error(format!("ts = {ts}: the step must be a positive number of seconds")));
            }
            LogSpec::fixed_step(ts)
        }
        (None, Some(topic)) => LogSpec::per_message(topic),
        (Some(_), Some(_)) => {
            return Err(value_error(
                "give ts= (a fixed step, seconds) or driving= (a topic: one step per message), not both",
            ));
        }
        (None, None) => {
            return Err(value_error(
                "give one of ts= (a fixed step, seconds) or driving= (a topic: one step per message)",
            ));
        }
    };
    spec = with_start(spec, start, start_ns)?;
    spec = spec.stamps(match stamps {
        "log" => Stamps::LogTime,
        "header" => Stamps::Header,
        other => return Err(value_error(format!("stamps = {other:?}: \"log\" (the log time) or \"header\""))),
    });
    if let Some(w) = reorder_window {
        if !(w.is_finite() && w >= 0.0) {
            return Err(value_error(format!("reorder_window = {w}: a number of seconds, at least 0")));
        }
        spec = spec.reorder_window(w);
    }
    for m in inputs {
        spec = spec.input(m.key, m.topic, m.field);
    }
    for m in outputs {
        spec = spec.output(m.key, m.topic, m.field);
    }
    Ok(spec)
}

/// The Python exception of `e` reading `path`; `rows_read` once rows were being read.
fn bag_error(py: Python<'_>, path: &Path, e: &ros_bag::Error, rows_read: Option<usize>) -> PyErr {
    use ros_bag::Error as E;
    if let E::Io { source, .. } = e {
        // OSError(errno, strerror, filename) is the subclass of the errno (FileNotFoundError, …).
        return match source.raw_os_error() {
            Some(errno) => {
                let text = source.to_string();
                let strerror = text.split(" (os error").next().unwrap_or(&text).to_owned();
                PyOSError::new_err((errno, strerror, path.display().to_string()))
            }
            None => PyOSError::new_err(e.to_string()),
        };
    }
    let text = e.to_string();
    let has_path = matches!(e, E::NotMcap { .. } | E::Corrupt { .. } | E::Write { .. });
    let mut message = if has_path { text } else { format!("{}: {text}", path.display()) };
    // The mapping does not fit the bag (or the arguments): refused before any row.
    if matches!(
        e,
        E::Config(_) | E::UnknownTopic { .. } | E::BadFieldPath { .. } | E::UnknownField { .. } | E::NonNumeric { .. }
    ) {
        return value_error(message);
    }
    if let Some(n) = rows_read {
        message.push_str(&format!(" ({n} row{} read before it)", if n == 1 { "" } else { "s" }));
    }
    let (offset, topic, key) = match e {
        E::Corrupt { location, .. } => (Some(location.offset), None, None),
        E::Undecodable { topic, location, .. }
        | E::OutOfOrder { topic, location, .. }
        | E::Late { topic, location, .. }
        | E::ZeroStamp { topic, location, .. } => (Some(location.offset), Some(topic), None),
        E::MissingField { key, topic, location, .. } => (Some(location.offset), Some(topic), Some(key)),
        E::NeverPublished { key, topic } => (None, Some(topic), Some(key)),
        E::UnsupportedEncoding { topic, .. } | E::Backlog { topic, .. } => (None, Some(topic), None),
        _ => (None, None, None),
    };
    let err = BagError::new_err(message);
    let value = err.value(py);
    // Setting attributes on a fresh exception cannot fail short of memory exhaustion.
    let _ = value.setattr("path", path.display().to_string());
    let _ = value.setattr("rows_read", rows_read.unwrap_or(0));
    let _ = value.setattr("offset", offset);
    let _ = value.setattr("topic", topic);
    let _ = value.setattr("key", key);
    err
}

/// Runs `f` with the GIL released; a panic becomes an `EstimationError`.
fn detached<T: Send>(py: Python<'_>, f: impl FnOnce() -> T + Send) -> PyResult<T> {
    match py.detach(|| guard(f)) {
        Guarded::Ran(v) => Ok(v),
        Guarded::Broken(what) => Err(broken(format!("internal error reading the bag ({what}); please report this"))),
    }
}

fn open(py: Python<'_>, path: &Path) -> PyResult<Bag> {
    detached(py, || Bag::open(path))?.map_err(|e| bag_error(py, path, &e, None))
}

/// Reads a ROS 2 bag (MCAP: CDR messages with ``ros2msg`` schemas, or JSON) into per-step arrays.
///
/// ``inputs`` and ``outputs`` map each model input and output, in order, to a topic's numeric
/// field: ``{"a": "/imu:linear_acceleration.x", "gnss_x": ("/gnss/odom", "pose.pose.position.x")}``
/// (``inspect_bag`` lists the fields). The time base is one of ``ts`` (a step every ``ts`` seconds
/// from the first mapped message, or from ``start``/``start_ns``; inputs held from their latest
/// message at or before the step, an output measured by the latest message in ``(t, t + ts]``)
/// or ``driving`` (a step per message of that topic). ``stamps="header"`` times messages by their
/// ``header.stamp`` where they have one (the log time otherwise); ``reorder_window`` (s, default
/// 1) is how far topics may lag one another in the file.
///
/// Returns a ``BagLog``: ``est.run(log.u, log.y, measured=log.measured)`` filters it. The file
/// is read in Rust with the GIL released (Ctrl-C stops it). A model file's ``[log]`` table is the
/// same mapping written once: ``ModelFile.read_bag(path)`` reads a bag through it.
///
/// Raises ValueError for bad arguments and a mapping that does not fit the bag (an unknown topic
/// lists the topics, an unknown field the numeric fields), OSError (FileNotFoundError, …) when
/// the file cannot be opened, and ``BagError`` for a file that cannot be read as asked (naming the
/// byte offset, topic or key; ``.rows_read`` the rows read before a damaged record).
#[pyfunction]
#[pyo3(signature = (
    path, inputs, outputs, *, ts = None, driving = None, stamps = "log", start = None, start_ns = None,
    reorder_window = None
))]
pub fn read_bag(
    py: Python<'_>,
    path: PathBuf,
    inputs: Option<&Bound<'_, PyAny>>,
    outputs: Option<&Bound<'_, PyAny>>,
    ts: Option<f64>,
    driving: Option<String>,
    stamps: &str,
    start: Option<f64>,
    start_ns: Option<i64>,
    reorder_window: Option<f64>,
) -> PyResult<BagLog> {
    let maps = (mappings(inputs, "inputs")?, mappings(outputs, "outputs")?);
    let spec = spec(maps, (ts, driving), stamps, (start, start_ns), reorder_window)?;
    read_spec(py, path, &spec)
}

/// Reads the bag at `path` as `spec` says (``read_bag``, ``ModelFile.read_bag``); `start`,
/// `start_ns` set step 0 of a fixed step.
pub(crate) fn read_with(
    py: Python<'_>,
    path: PathBuf,
    spec: &LogSpec,
    (start, start_ns): (Option<f64>, Option<i64>),
) -> PyResult<BagLog> {
    read_spec(py, path, &with_start(spec.clone(), start, start_ns)?)
}

fn read_spec(py: Python<'_>, path: PathBuf, spec: &LogSpec) -> PyResult<BagLog> {
    let names = (
        spec.input_keys().into_iter().map(str::to_owned).collect(),
        spec.output_keys().into_iter().map(str::to_owned).collect(),
    );
    let bag = open(py, &path)?;
    let mut rows = detached(py, || bag.rows(spec))?.map_err(|e| bag_error(py, &path, &e, None))?;
    let mut tables = Tables::default();
    // Stretches of about `SLICE` with the GIL released, Python's signals looked at between them.
    while !detached(py, || tables.fill(&mut rows))?.map_err(|e| bag_error(py, &path, &e, Some(tables.rows)))? {
        py.check_signals()?;
    }
    let header_stamped = rows.header_stamped();
    BagLog::new(py, path, names, header_stamped, tables)
}

/// What a bag holds (``inspect_bag``): ``topics``, one dict per topic, and ``str()`` the table
/// ``port-est inspect`` prints.
///
/// Each topic's dict: ``topic``, ``type`` (``sensor_msgs/msg/Imu``; empty without a schema),
/// ``message_encoding`` (``cdr``, ``json``), ``schema_encoding``, ``count``, ``rate_hz`` (the mean
/// rate, or None), ``first``/``last`` (log times, s, or None) and ``first_ns``/``last_ns``,
/// ``fields`` (the numeric field paths a mapping can use: ``a[0..=8]`` a fixed array, ``a[i]`` a
/// sequence) and ``fields_error`` (why they cannot be listed, or None). ``error`` is the damage
/// that stopped the count early (the counts are those before it), or None.
#[pyclass(frozen, module = "port_estimation")]
pub struct BagInfo {
    path: PathBuf,
    topics: Py<PyList>,
    error: Option<String>,
    table: String,
}

#[pymethods]
impl BagInfo {
    /// One dict per topic, sorted by name.
    #[getter]
    fn topics(&self, py: Python<'_>) -> Py<PyList> {
        self.topics.clone_ref(py)
    }

    /// The damage that stopped the count early, or None.
    #[getter]
    fn error(&self) -> Option<String> {
        self.error.clone()
    }

    /// The bag.
    #[getter]
    fn path(&self) -> String {
        self.path.display().to_string()
    }

    fn __len__(&self, py: Python<'_>) -> usize {
        self.topics.bind(py).len()
    }

    fn __str__(&self) -> String {
        self.table.clone()
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        format!("BagInfo({:?}: {} topics)", self.path.display().to_string(), self.topics.bind(py).len())
    }
}

/// Lists a bag's topics: type, encodings, message count, rate, first and last log time and the
/// numeric field paths a mapping can use; ``print(inspect_bag(path))`` prints them as a table.
/// The file is walked once with the GIL released. A damaged file gives the counts up to the
/// damage and ``.error``; a file that cannot be opened raises OSError, one that is not MCAP
/// ``BagError``.
#[pyfunction]
pub fn inspect_bag(py: Python<'_>, path: PathBuf) -> PyResult<BagInfo> {
    let bag = open(py, &path)?;
    let (inspection, table) = detached(py, || {
        let i = bag.inspect();
        let table = i.to_string();
        (i, table)
    })?;
    let seconds = |ns: Option<u64>| ns.map(|n| n as f64 / 1e9);
    let topics = PyList::empty(py);
    for t in &inspection.topics {
        let d = PyDict::new(py);
        d.set_item("topic", &t.topic)?;
        d.set_item("type", &t.message_type)?;
        d.set_item("message_encoding", &t.message_encoding)?;
        d.set_item("schema_encoding", &t.schema_encoding)?;
        d.set_item("count", t.count)?;
        d.set_item("rate_hz", t.rate_hz())?;
        d.set_item("first", seconds(t.first_ns))?;
        d.set_item("last", seconds(t.last_ns))?;
        d.set_item("first_ns", t.first_ns)?;
        d.set_item("last_ns", t.last_ns)?;
        d.set_item("fields", &t.numeric_fields)?;
        d.set_item("fields_error", &t.fields_error)?;
        topics.append(d)?;
    }
    Ok(BagInfo { path, topics: topics.unbind(), error: inspection.error.map(|e| e.to_string()), table })
}
