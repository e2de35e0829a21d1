//! ROS 2 bags (MCAP) as logs: the model file's `[log]` table maps each input and output to a
//! topic's field, `--input run.mcap` runs the estimator over the rows the `ros-bag` crate makes of
//! them, and `port-est inspect run.mcap` lists what a mapping can use.
//!
//! ```toml
//! [log]
//! ts = 0.01                  # one step every 10 ms (or `driving = "/imu"`: one per message)
//! stamps = "header"          # `header.stamp` where the message has one (default: "log", the log time)
//! reorder_window = 1.0       # seconds by which topics may lag one another in the file (default 1)
//!
//! [log.fields]
//! steer = { topic = "/steering", field = "data" }
//! gnss_x = { topic = "/gnss/odom", field = "pose.pose.position.x" }
//! ```
//!
//! Every input and output of the model is mapped (a model of matrices names them `u1…`, `y1…`).
//! An output without a message in a step's window is not measured there (a partial step). A
//! position in a bag is `BAG:ROW:COLUMN` of the table of rows the mapping makes: row 1 is the
//! first step, column 1 is `k`, then the inputs, then the outputs.
//!
//! `--output est.mcap` writes the estimates as a bag (`BagOutput`): the estimate `x_{k+1}` of
//! row `k` is stamped at the end of the row's window (`ros_bag::Row::end_ns`: `t_k + ts` at a
//! fixed step, the next driving message's stamp per message), the time of the last measurement it
//! could use. `--copy-topics` copies the input's topics beside it, interleaved by log time.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use crate::data::{DataRow, RowSource};
use crate::error::{Error, Location};
use crate::model::Model;

/// MCAP's magic bytes.
const MAGIC: &[u8] = b"\x89MCAP0\r\n";

/// Whether `path` is an MCAP file: its extension `.mcap`, or a regular file whose first bytes are
/// MCAP's magic (a pipe is never peeked at: its bytes would be gone).
#[must_use]
pub fn is_bag(path: &Path) -> bool {
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("mcap")) {
        return true;
    }
    if !std::fs::metadata(path).is_ok_and(|m| m.is_file()) {
        return false;
    }
    let mut head = [0u8; 8];
    std::fs::File::open(path).and_then(|mut f| f.read_exact(&mut head)).is_ok() && head == MAGIC
}

/// A `ros-bag` error as this crate's, the path said once (some of its messages start with it).
fn bag_error(path: &Path, e: ros_bag::Error) -> Error {
    let text = e.to_string();
    let prefix = format!("{}: ", path.display());
    let message = text.strip_prefix(&prefix).map_or(text.clone(), str::to_owned);
    Error::File { path: path.to_owned(), message }
}

/// Opens a bag, a directory refused by name (memory-mapping one fails obscurely).
pub(crate) fn open(path: &Path) -> Result<ros_bag::Bag, Error> {
    if path.is_dir() {
        return Err(Error::File { path: path.to_owned(), message: "is a directory, not an MCAP bag".into() });
    }
    ros_bag::Bag::open(path).map_err(|e| bag_error(path, e))
}

/// The model's `[log]` mapping, or an error saying that a bag needs one.
pub(crate) fn log_spec<'m>(model: &'m Model, path: &Path) -> Result<&'m ros_bag::LogSpec, Error> {
    model.log.as_ref().ok_or_else(|| Error::File {
        path: model.path().to_owned(),
        message: format!(
            "{} is an MCAP bag: the model file needs a `[log]` table mapping its inputs and outputs to topics \
             (`port-est inspect {}` lists them; see crates/port-est/README.md)",
            path.display(),
            path.display()
        ),
    })
}

/// The rows `spec` makes of `bag` (read from `path`), as a [`RowSource`].
pub(crate) fn bag_rows<'b>(bag: &'b ros_bag::Bag, spec: &ros_bag::LogSpec, path: &Path) -> Result<BagRows<'b>, Error> {
    let rows = bag.rows(spec).map_err(|e| bag_error(path, e))?;
    let mut columns = vec!["k".to_owned()];
    columns.extend(spec.input_keys().into_iter().chain(spec.output_keys()).map(str::to_owned));
    let (p, m) = (spec.inputs().len(), spec.outputs().len());
    Ok(BagRows { rows, path: path.to_owned(), columns, p, m, read: 0, end_ns: 0 })
}

/// Opens the bag at `path` and runs `run` over the rows the model's `[log]` table makes of it.
///
/// # Errors
/// A model without a `[log]` table, a bag that cannot be read or mapped (the `ros-bag` error:
/// the record and byte offset, the topic or the mapping key), and `run`'s error.
pub fn run_on_bag<T>(
    model: &Model,
    path: &Path,
    run: impl FnOnce(&mut dyn RowSource) -> Result<T, Error>,
) -> Result<T, Error> {
    let spec = log_spec(model, path)?;
    let bag = open(path)?;
    run(&mut bag_rows(&bag, spec, path)?)
}

/// The rows of a bag as a [`RowSource`].
pub struct BagRows<'b> {
    rows: ros_bag::Rows<'b>,
    path: PathBuf,
    columns: Vec<String>,
    p: usize,
    m: usize,
    /// Rows read so far.
    read: u64,
    /// The end of the last row's window (ns).
    end_ns: i64,
}

impl RowSource for BagRows<'_> {
    fn read_row(&mut self, row: &mut DataRow) -> Result<bool, Error> {
        let Some(next) = self.rows.next() else { return Ok(false) };
        let r = next.map_err(|e| bag_error(&self.path, e))?;
        if r.u.len() != self.p || r.y.len() != self.m || row.u.len() != self.p || row.y.len() < self.m {
            return Err(Error::File { path: self.path.clone(), message: "the bag's rows do not fit the model".into() });
        }
        self.read += 1;
        self.end_ns = r.end_ns;
        row.k = r.k;
        row.u.as_mut_slice().copy_from_slice(&r.u);
        for (i, (&v, &measured)) in r.y.iter().zip(&r.measured).enumerate() {
            row.y[i] = if measured { v } else { 0.0 };
            row.measured[i] = measured;
        }
        Ok(true)
    }

    fn locate(&self, column: Option<usize>) -> Location {
        Location::new(&self.path, self.read, 1 + column.unwrap_or(0) as u64)
    }

    fn columns(&self) -> &[String] {
        &self.columns
    }

    fn inputs(&self) -> usize {
        self.p
    }

    /// `x_{k+1}` is estimated from the measurements up to the end of the step's window: `t_k +
    /// ts` at a fixed step, the next driving message's stamp per message.
    fn estimate_time_ns(&self) -> Option<i64> {
        Some(self.end_ns)
    }
}

/// Whether `port-est filter` writes its estimates as a bag (`--output est.mcap`).
#[must_use]
pub fn writes_bag(output: &Path) -> bool {
    output.extension().is_some_and(|e| e.eq_ignore_ascii_case("mcap"))
}

/// The topic of the estimates in a bag written by `port-est filter`.
pub const ESTIMATE_TOPIC: &str = "/estimate";

/// An error copying topics: the output's when writing failed, else the input's.
fn copy_error(input: &Path, output: &Path, e: ros_bag::Error) -> Error {
    match e {
        ros_bag::Error::Write { .. } | ros_bag::Error::Io { .. } => bag_error(output, e),
        other => bag_error(input, other),
    }
}

/// Estimates written as a bag: one JSON message per step on [`ESTIMATE_TOPIC`], stamped at the
/// end of the step's window, with the centre, the bounds (guaranteed sets) or standard
/// deviations (Gaussian estimates) per state, and the status; with the input bag's topics copied
/// beside them when asked, interleaved by log time.
pub(crate) struct BagOutput<'b> {
    writer: ros_bag::EstimateWriter,
    copy: Option<ros_bag::TopicCopy<'b>>,
    path: PathBuf,
    /// The input bag's path.
    input: PathBuf,
    kind: estimators::EstimateKind,
    x: Vec<f64>,
    a: Vec<f64>,
    b: Vec<f64>,
    status: String,
}

impl<'b> BagOutput<'b> {
    /// Starts `path` (published by [`BagOutput::finish`] only) for the states of `model` and
    /// estimates of `kind`, copying `copy` topics of `input` beside them.
    pub(crate) fn create(
        path: &Path,
        model: &Model,
        kind: estimators::EstimateKind,
        input: &'b ros_bag::Bag,
        copy: &crate::CopyTopics,
    ) -> Result<Self, Error> {
        use estimators::EstimateKind as K;
        let n = model.states();
        let names: Vec<String> = match &model.dynamics {
            crate::model::Dynamics::Equations(m) if m.state_names().len() == n => m.state_names().to_vec(),
            _ => (1..=n).map(|i| format!("x{i}")).collect(),
        };
        let spread = match kind {
            K::Gaussian => ros_bag::Spread::StdDev,
            K::GuaranteedEllipsoid | K::GuaranteedConstrainedZonotope => ros_bag::Spread::Bounds,
            _ => ros_bag::Spread::None,
        };
        let layout = ros_bag::EstimateLayout::new(ESTIMATE_TOPIC, names).spread(spread).status(true);
        let writer = ros_bag::EstimateWriter::create(path, layout).map_err(|e| bag_error(path, e))?;
        let copy = match copy {
            crate::CopyTopics::None => None,
            crate::CopyTopics::All => Some(ros_bag::TopicCopy::all(input, &writer)),
            crate::CopyTopics::Only(topics) => {
                let topics: Vec<&str> = topics.iter().map(String::as_str).collect();
                let copy = ros_bag::TopicCopy::only(input, &topics, &writer)
                    .map_err(|e| Error::Usage(format!("--copy-topics: {}", bag_error(input.path(), e))))?;
                Some(copy)
            }
        };
        Ok(Self {
            writer,
            copy,
            path: path.to_owned(),
            input: input.path().to_owned(),
            kind,
            x: vec![0.0; n],
            a: vec![0.0; n],
            b: vec![0.0; n],
            status: String::new(),
        })
    }

    /// Writes the estimate of step `k` at `t_ns` (after the copied messages up to `t_ns`), its
    /// status followed by `measured` (`+measured:…`, as in the CSV output).
    pub(crate) fn write(
        &mut self,
        k: u64,
        t_ns: i64,
        e: &dyn estimators::Estimate,
        measured: Option<&str>,
    ) -> Result<(), Error> {
        use estimators::EstimateKind as K;
        use std::fmt::Write as _;
        if let Some(copy) = &mut self.copy {
            let at = u64::try_from(t_ns).unwrap_or(0);
            copy.until(&mut self.writer, at).map_err(|e| copy_error(&self.input, &self.path, e))?;
        }
        let n = self.x.len();
        for i in 0..n {
            self.x[i] = e.center()[i];
            match self.kind {
                K::Gaussian => self.a[i] = e.shape()[(i, i)].max(0.0).sqrt(),
                _ => (self.a[i], self.b[i]) = e.bounds(i).unwrap_or((f64::NAN, f64::NAN)),
            }
        }
        self.status.clear();
        let _ = write!(self.status, "{}{}", e.status(), measured.unwrap_or(""));
        let mut m = ros_bag::Estimate::new(k, t_ns, &self.x);
        m.status = Some(&self.status);
        match self.kind {
            K::Gaussian => m.std_dev = Some(&self.a),
            K::GuaranteedEllipsoid | K::GuaranteedConstrainedZonotope => {
                m.lower = Some(&self.a);
                m.upper = Some(&self.b);
            }
            _ => {}
        }
        self.writer.write(&m).map_err(|e| bag_error(&self.path, e))
    }

    /// Copies the rest of the input's topics and publishes the bag.
    pub(crate) fn finish(mut self) -> Result<(), Error> {
        if let Some(copy) = &mut self.copy {
            copy.rest(&mut self.writer).map_err(|e| copy_error(&self.input, &self.path, e))?;
        }
        self.writer.finish().map_err(|e| bag_error(&self.path, e))
    }
}

/// `port-est inspect BAG.mcap`: each topic's type, encoding, message count, rate and the numeric
/// field paths a `[log]` mapping can use.
///
/// # Errors
/// A file that is not an MCAP bag; a damaged one after what could be read is listed.
pub fn inspect(path: &Path, out: &mut dyn Write) -> Result<(), Error> {
    let bag = open(path)?;
    let inspection = bag.inspect();
    // A closed pipe is not an error of ours.
    let text = inspection.to_string();
    let _ = write!(out, "{text}{}", if text.ends_with('\n') { "" } else { "\n" });
    match inspection.error {
        Some(e) => match bag_error(path, e) {
            Error::File { path, message } => {
                Err(Error::File { path, message: format!("{message} (the topics above were read before it)") })
            }
            other => Err(other),
        },
        None => Ok(()),
    }
}
