//! Estimates written as MCAP: one JSON message per step on one topic, with a JSON schema whose
//! fields are plain numbers named after the states, so that Foxglove and PlotJuggler plot
//! `/estimate.x.px` without plugins. Written through [`atomic_output::AtomicFile`]: the output
//! appears whole on [`EstimateWriter::finish`], or not at all.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use atomic_output::AtomicFile;
use mcap::records::MessageHeader;
use mcap::write::NoSeek;

use crate::container::chain;
use crate::error::{Error, Result};

/// The schema name of the estimate messages.
pub const ESTIMATE_SCHEMA: &str = "port_estimation/Estimate";

/// What each estimate message carries beside the centre `x`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Spread {
    /// The centre only.
    #[default]
    None,
    /// Per-state `lower` and `upper` bounds.
    Bounds,
    /// Per-state standard deviations `std`.
    StdDev,
}

/// The shape of the estimate messages: topic, state names, spread, status.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EstimateLayout {
    topic: String,
    states: Vec<String>,
    spread: Spread,
    status: bool,
}

impl EstimateLayout {
    /// Messages on `topic` with the centre of `states` (in order).
    pub fn new(topic: impl Into<String>, states: impl IntoIterator<Item = impl Into<String>>) -> Self {
        Self {
            topic: topic.into(),
            states: states.into_iter().map(Into::into).collect(),
            spread: Spread::None,
            status: false,
        }
    }

    /// With a spread (bounds or standard deviations).
    pub fn spread(mut self, spread: Spread) -> Self {
        self.spread = spread;
        self
    }

    /// With a `status` string.
    pub fn status(mut self, status: bool) -> Self {
        self.status = status;
        self
    }

    /// The JSON schema of the messages.
    pub fn json_schema(&self) -> String {
        let number = serde_json::json!({ "type": "number" });
        let group: serde_json::Map<String, serde_json::Value> =
            self.states.iter().map(|s| (s.clone(), number.clone())).collect();
        let group = serde_json::json!({ "type": "object", "properties": group });
        let mut props = serde_json::Map::new();
        props.insert("k".into(), serde_json::json!({ "type": "integer" }));
        props.insert("t".into(), number.clone());
        props.insert("x".into(), group.clone());
        match self.spread {
            Spread::None => {}
            Spread::Bounds => {
                props.insert("lower".into(), group.clone());
                props.insert("upper".into(), group);
            }
            Spread::StdDev => {
                props.insert("std".into(), group);
            }
        }
        if self.status {
            props.insert("status".into(), serde_json::json!({ "type": "string" }));
        }
        serde_json::json!({ "title": ESTIMATE_SCHEMA, "type": "object", "properties": props }).to_string()
    }
}

/// One step's estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate<'a> {
    /// The step.
    pub k: u64,
    /// Its time (ns); the message's log and publish time.
    pub t_ns: i64,
    /// The centre, one entry per state.
    pub x: &'a [f64],
    /// Lower bounds ([`Spread::Bounds`]).
    pub lower: Option<&'a [f64]>,
    /// Upper bounds ([`Spread::Bounds`]).
    pub upper: Option<&'a [f64]>,
    /// Standard deviations ([`Spread::StdDev`]).
    pub std_dev: Option<&'a [f64]>,
    /// The step's status (`converged`, …), if the layout has one.
    pub status: Option<&'a str>,
}

impl<'a> Estimate<'a> {
    /// The centre `x` of step `k` at `t_ns`, nothing else.
    pub fn new(k: u64, t_ns: i64, x: &'a [f64]) -> Self {
        Self { k, t_ns, x, lower: None, upper: None, std_dev: None, status: None }
    }
}

/// Writes estimate messages to an MCAP file as they come (chunks of 1 MiB are compressed with
/// zstd and written; nothing else is kept in memory).
pub struct EstimateWriter {
    out: Option<mcap::Writer<NoSeek<AtomicFile>>>,
    path: PathBuf,
    layout: EstimateLayout,
    channel: u16,
    sequence: u32,
    buf: Vec<u8>,
    /// JSON-quoted state names.
    names: Vec<String>,
}

impl std::fmt::Debug for EstimateWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EstimateWriter").field("path", &self.path).field("layout", &self.layout).finish_non_exhaustive()
    }
}

fn push_number(buf: &mut Vec<u8>, v: f64) {
    if v.is_finite() {
        // tidy: invariant — writing a finite f64 into a Vec cannot fail.
        serde_json::to_writer(&mut *buf, &v).expect("a finite number");
    } else {
        buf.extend_from_slice(b"null");
    }
}

impl EstimateWriter {
    /// Starts `path` (a temporary file beside it until [`EstimateWriter::finish`]).
    ///
    /// # Errors
    /// [`Error::Io`] if the temporary file cannot be made, [`Error::Config`] for a layout
    /// without states or with a repeated state, [`Error::Write`] from the MCAP writer.
    pub fn create(path: impl AsRef<Path>, layout: EstimateLayout) -> Result<Self> {
        let path = path.as_ref().to_owned();
        if layout.states.is_empty() {
            return Err(Error::Config("an estimate layout needs at least one state".into()));
        }
        let mut seen = std::collections::HashSet::new();
        if let Some(s) = layout.states.iter().find(|s| !seen.insert(s.as_str())) {
            return Err(Error::Config(format!("the state `{s}` is named twice")));
        }
        let file = AtomicFile::create(&path).map_err(|source| Error::Io { path: path.clone(), source })?;
        let w = |e: mcap::McapError| Error::Write { path: path.clone(), detail: chain(&e) };
        let mut out = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .compression_threads(0)
            .disable_seeking(true)
            .create(NoSeek::new(file))
            .map_err(w)?;
        let schema = out.add_schema(ESTIMATE_SCHEMA, "jsonschema", layout.json_schema().as_bytes()).map_err(w)?;
        let channel = out.add_channel(schema, &layout.topic, "json", &BTreeMap::new()).map_err(w)?;
        let names = layout.states.iter().map(|s| serde_json::Value::from(s.as_str()).to_string()).collect();
        Ok(Self { out: Some(out), path, layout, channel, sequence: 0, buf: Vec::new(), names })
    }

    fn writer(&mut self) -> Result<&mut mcap::Writer<NoSeek<AtomicFile>>> {
        let path = &self.path;
        self.out.as_mut().ok_or_else(|| Error::Write { path: path.clone(), detail: "already finished".into() })
    }

    fn group(&mut self, name: &str, values: Option<&[f64]>) -> Result<()> {
        let n = self.names.len();
        let Some(values) = values.filter(|v| v.len() == n) else {
            return Err(Error::Config(format!("the estimate's `{name}` must have {n} entries, one per state")));
        };
        self.buf.extend_from_slice(format!(",\"{name}\":{{").as_bytes());
        for (i, (q, v)) in self.names.iter().zip(values).enumerate() {
            if i > 0 {
                self.buf.push(b',');
            }
            self.buf.extend_from_slice(q.as_bytes());
            self.buf.push(b':');
            push_number(&mut self.buf, *v);
        }
        self.buf.push(b'}');
        Ok(())
    }

    /// Writes one step's message.
    ///
    /// # Errors
    /// [`Error::Config`] if a vector's length is not the number of states or the layout's
    /// spread or status is missing, or the time is negative; [`Error::Write`] from the writer.
    pub fn write(&mut self, e: &Estimate<'_>) -> Result<()> {
        let time = u64::try_from(e.t_ns).map_err(|_| {
            Error::Config(format!("step {}: time {} ns is before 1970: MCAP times are unsigned", e.k, e.t_ns))
        })?;
        self.buf.clear();
        self.buf.extend_from_slice(format!("{{\"k\":{},\"t\":", e.k).as_bytes());
        push_number(&mut self.buf, e.t_ns as f64 / 1e9);
        self.group("x", Some(e.x))?;
        match self.layout.spread {
            Spread::None => {}
            Spread::Bounds => {
                self.group("lower", e.lower)?;
                self.group("upper", e.upper)?;
            }
            Spread::StdDev => self.group("std", e.std_dev)?,
        }
        if self.layout.status {
            let Some(s) = e.status else {
                return Err(Error::Config(format!("step {}: the layout has a status but the estimate none", e.k)));
            };
            self.buf.extend_from_slice(b",\"status\":");
            self.buf.extend_from_slice(serde_json::Value::from(s).to_string().as_bytes());
        }
        self.buf.push(b'}');
        let header =
            MessageHeader { channel_id: self.channel, sequence: self.sequence, log_time: time, publish_time: time };
        self.sequence = self.sequence.wrapping_add(1);
        let buf = std::mem::take(&mut self.buf);
        let path = self.path.clone();
        let r = self.writer()?.write_to_known_channel(&header, &buf);
        self.buf = buf;
        r.map_err(|e| Error::Write { path, detail: chain(&e) })
    }

    /// The topic of the estimates.
    pub fn topic(&self) -> &str {
        &self.layout.topic
    }

    /// The path the file is published at.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The MCAP writer, for [`TopicCopy`](crate::TopicCopy).
    pub(crate) fn raw(&mut self) -> Result<&mut mcap::Writer<NoSeek<AtomicFile>>> {
        self.writer()
    }

    /// Finishes the file (summary, footer) and publishes it at its path.
    ///
    /// # Errors
    /// [`Error::Write`] from the writer, [`Error::Io`] if the file cannot be published.
    pub fn finish(mut self) -> Result<()> {
        let path = self.path.clone();
        let mut out =
            self.out.take().ok_or_else(|| Error::Write { path: path.clone(), detail: "already finished".into() })?;
        out.finish().map_err(|e| Error::Write { path: path.clone(), detail: chain(&e) })?;
        let file = out.into_inner().into_inner();
        file.commit().map_err(|source| Error::Io { path, source })
    }
}
