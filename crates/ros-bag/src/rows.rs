//! Per-step rows from a bag: the mapping, the time base, and the streaming alignment.

use std::collections::{BTreeMap, HashMap, VecDeque};

use crate::bag::Bag;
use crate::cdr::DecodeError;
use crate::container::{ChannelRec, Item, RawMessage, SchemaRec, Walker};
use crate::decoder::Decoder;
use crate::error::{Error, Result};

/// One model input or output read from a topic's field.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Mapping {
    /// The model's name for it (`gnss_x`).
    pub key: String,
    /// The topic (`/gnss/odom`).
    pub topic: String,
    /// The field path in the topic's message (`pose.pose.position.x`, `data[2]`).
    pub field: String,
}

/// How steps are made.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum TimeBase {
    /// A step every `ts` seconds (rounded to whole nanoseconds) from `start_ns`, by default the
    /// stamp of the first message of a mapped topic in the file.
    FixedStep {
        /// The step (s).
        ts: f64,
        /// The time of step 0 (ns since the epoch of the stamps).
        start_ns: Option<i64>,
    },
    /// One step per message of this topic, at its stamp.
    PerMessage {
        /// The driving topic.
        topic: String,
    },
}

/// Which time stamps a message.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Stamps {
    /// The MCAP log time (when the recorder received the message).
    #[default]
    LogTime,
    /// The message's `header.stamp` (sec + nanosec) where its type has a header; the log time
    /// for topics without one.
    Header,
}

/// What to read from a bag: the inputs and outputs, the time base, the stamps.
///
/// ```
/// use ros_bag::{LogSpec, Stamps};
/// let spec = LogSpec::fixed_step(0.01)
///     .input("a", "/imu", "linear_acceleration.x")
///     .output("gnss_x", "/gnss/odom", "pose.pose.position.x")
///     .stamps(Stamps::Header);
/// assert_eq!(spec.output_keys(), ["gnss_x"]);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct LogSpec {
    inputs: Vec<Mapping>,
    outputs: Vec<Mapping>,
    time_base: TimeBase,
    stamps: Stamps,
    reorder_window: f64,
    max_backlog: usize,
}

/// The default reorder window (s): see [`LogSpec::reorder_window`].
pub const DEFAULT_REORDER_WINDOW: f64 = 1.0;

/// The default limit on messages waiting for their step (see [`Error::Backlog`]).
pub const DEFAULT_MAX_BACKLOG: usize = 1_000_000;

impl LogSpec {
    /// A spec with this time base and no mappings yet.
    pub fn new(time_base: TimeBase) -> Self {
        Self {
            inputs: Vec::new(),
            outputs: Vec::new(),
            time_base,
            stamps: Stamps::LogTime,
            reorder_window: DEFAULT_REORDER_WINDOW,
            max_backlog: DEFAULT_MAX_BACKLOG,
        }
    }

    /// Fixed steps of `ts` seconds from the first mapped message.
    pub fn fixed_step(ts: f64) -> Self {
        Self::new(TimeBase::FixedStep { ts, start_ns: None })
    }

    /// One step per message of `topic`.
    pub fn per_message(topic: impl Into<String>) -> Self {
        Self::new(TimeBase::PerMessage { topic: topic.into() })
    }

    /// Step 0 at `start_ns` (fixed steps only; ignored otherwise).
    pub fn start_ns(mut self, start: i64) -> Self {
        if let TimeBase::FixedStep { start_ns, .. } = &mut self.time_base {
            *start_ns = Some(start);
        }
        self
    }

    /// Adds an input.
    pub fn input(mut self, key: impl Into<String>, topic: impl Into<String>, field: impl Into<String>) -> Self {
        self.inputs.push(Mapping { key: key.into(), topic: topic.into(), field: field.into() });
        self
    }

    /// Adds an output.
    pub fn output(mut self, key: impl Into<String>, topic: impl Into<String>, field: impl Into<String>) -> Self {
        self.outputs.push(Mapping { key: key.into(), topic: topic.into(), field: field.into() });
        self
    }

    /// Which stamps to use (log time by default).
    pub fn stamps(mut self, stamps: Stamps) -> Self {
        self.stamps = stamps;
        self
    }

    /// How far (s) a message's stamp may lie before the latest stamp already read (of any mapped
    /// topic) and still count: a step is published once a stamp later than its window's end by
    /// more than this has been read. 1 s by default; 0 when the file is in stamp order.
    pub fn reorder_window(mut self, seconds: f64) -> Self {
        self.reorder_window = seconds;
        self
    }

    /// The most messages kept waiting for their step before [`Error::Backlog`].
    pub fn max_backlog(mut self, messages: usize) -> Self {
        self.max_backlog = messages;
        self
    }

    /// The inputs' keys, in order (the entries of `u`).
    pub fn input_keys(&self) -> Vec<&str> {
        self.inputs.iter().map(|m| m.key.as_str()).collect()
    }

    /// The outputs' keys, in order (the entries of `y`).
    pub fn output_keys(&self) -> Vec<&str> {
        self.outputs.iter().map(|m| m.key.as_str()).collect()
    }

    /// The inputs.
    pub fn inputs(&self) -> &[Mapping] {
        &self.inputs
    }

    /// The outputs.
    pub fn outputs(&self) -> &[Mapping] {
        &self.outputs
    }

    /// The time base.
    pub fn time_base(&self) -> &TimeBase {
        &self.time_base
    }
}

/// One step: `k`, its time, the input `u_k` and the measurement `y_{k+1}` taken after it.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// The step, counted from 0 at the first row.
    pub k: u64,
    /// The step's time (ns, in the stamps' epoch).
    pub t_ns: i64,
    /// The step's time in seconds (`t_ns as f64 / 1e9`).
    pub t: f64,
    /// The end of the step's window (ns): `t_ns + ts` at a fixed step, the next driving message's
    /// stamp per message. The outputs `y` were taken in `(t_ns, end_ns]`, so the estimate
    /// `x_{k+1}` made from them is the state at `end_ns`.
    pub end_ns: i64,
    /// The inputs, in the spec's order: each from its topic's latest message at or before `t`.
    pub u: Vec<f64>,
    /// The outputs, in the spec's order: from the latest message in the step's window; NaN
    /// where not measured.
    pub y: Vec<f64>,
    /// Which outputs were measured in the step's window.
    pub measured: Vec<bool>,
}

/// One mapped topic's state.
#[derive(Debug)]
struct Topic {
    name: String,
    /// (key, field) per slot.
    keys: Vec<(String, String)>,
    has_outputs: bool,
    last: Option<i64>,
    count: u64,
    /// Messages not yet consumed by a step: (stamp, slot values).
    queue: VecDeque<(i64, Vec<f64>)>,
    /// The latest consumed message's values.
    held: Option<Vec<f64>>,
    header_stamped: Option<bool>,
}

#[derive(Debug)]
enum Steps {
    Fixed { ts: i64, t0: Option<i64>, start: Option<i64>, next: u64 },
    PerMessage { topic: usize, times: VecDeque<i64> },
}

/// Rows of a bag, one at a time ([`Bag::rows`]). An error ends the rows: first come the steps
/// whose whole window lies before the last stamp read (with log times, the rows the intact file
/// gives up to there), then the error, once.
#[derive(Debug)]
pub struct Rows<'b> {
    bag: &'b Bag,
    walker: Walker<'b>,
    want_header: bool,
    topics: Vec<Topic>,
    /// Mapped topic index by topic name.
    topic_index: HashMap<String, usize>,
    /// Channels seen in the data section beyond the bag's table.
    extra_channels: BTreeMap<u16, ChannelRec>,
    extra_schemas: BTreeMap<u16, SchemaRec>,
    /// Per channel: `None` not mapped, else (topic, decoder).
    decoders: HashMap<u16, Option<(usize, Decoder)>>,
    inputs: Vec<(usize, usize)>,
    outputs: Vec<(usize, usize)>,
    steps: Steps,
    window: i64,
    window_s: f64,
    frontier: Option<i64>,
    closed_in: Option<i64>,
    closed_out: Option<i64>,
    emitted: u64,
    queued: usize,
    max_backlog: usize,
    eof: bool,
    /// The error that stopped reading, returned once the rows before it are out.
    pending: Option<Error>,
    finished: bool,
    scratch: Vec<f64>,
}

fn to_ns(seconds: f64, what: &str) -> Result<i64> {
    let ns = (seconds * 1e9).round();
    if !ns.is_finite() || !(0.0..9.2e18).contains(&ns) {
        return Err(Error::Config(format!("{what} = {seconds} s is not a usable time")));
    }
    Ok(ns as i64)
}

impl Bag {
    /// The rows `spec` asks for, one at a time.
    ///
    /// # Errors
    /// Before any row: [`Error::Config`], [`Error::UnknownTopic`], [`Error::BadFieldPath`],
    /// [`Error::UnknownField`], [`Error::NonNumeric`], [`Error::Schema`],
    /// [`Error::UnsupportedEncoding`]. The iterator then yields the errors found while reading.
    pub fn rows(&self, spec: &LogSpec) -> Result<Rows<'_>> {
        if spec.inputs.is_empty() && spec.outputs.is_empty() {
            return Err(Error::Config("no inputs and no outputs are mapped".into()));
        }
        let mut seen = std::collections::HashSet::new();
        for m in spec.inputs.iter().chain(&spec.outputs) {
            if !seen.insert(m.key.as_str()) {
                return Err(Error::Config(format!("the key `{}` is mapped twice", m.key)));
            }
        }
        let window = to_ns(spec.reorder_window, "the reorder window")?;
        let available = self.topics();
        let unknown = |key: &str, topic: &str| Error::UnknownTopic {
            key: key.to_owned(),
            topic: topic.to_owned(),
            available: available.clone(),
        };
        let mut topics: Vec<Topic> = Vec::new();
        let mut topic_index = HashMap::new();
        let mut topic_of = |name: &str, topics: &mut Vec<Topic>| -> usize {
            *topic_index.entry(name.to_owned()).or_insert_with(|| {
                topics.push(Topic {
                    name: name.to_owned(),
                    keys: Vec::new(),
                    has_outputs: false,
                    last: None,
                    count: 0,
                    queue: VecDeque::new(),
                    held: None,
                    header_stamped: None,
                });
                topics.len() - 1
            })
        };
        let mut inputs = Vec::new();
        let mut outputs = Vec::new();
        for (is_output, m) in spec.inputs.iter().map(|m| (false, m)).chain(spec.outputs.iter().map(|m| (true, m))) {
            if !available.contains(&m.topic) {
                return Err(unknown(&m.key, &m.topic));
            }
            let t = topic_of(&m.topic, &mut topics);
            topics[t].keys.push((m.key.clone(), m.field.clone()));
            topics[t].has_outputs |= is_output;
            let slot = topics[t].keys.len() - 1;
            if is_output { outputs.push((t, slot)) } else { inputs.push((t, slot)) }
        }
        let steps = match &spec.time_base {
            TimeBase::FixedStep { ts, start_ns } => {
                let ts = to_ns(*ts, "the step ts")?;
                if ts == 0 {
                    return Err(Error::Config("the step ts must be at least 1 ns".into()));
                }
                Steps::Fixed { ts, t0: None, start: *start_ns, next: 0 }
            }
            TimeBase::PerMessage { topic } => {
                if !available.contains(topic) {
                    return Err(unknown("time base", topic));
                }
                Steps::PerMessage { topic: topic_of(topic, &mut topics), times: VecDeque::new() }
            }
        };
        let mut rows = Rows {
            bag: self,
            walker: self.walker(),
            want_header: spec.stamps == Stamps::Header,
            topics,
            topic_index,
            extra_channels: BTreeMap::new(),
            extra_schemas: BTreeMap::new(),
            decoders: HashMap::new(),
            inputs,
            outputs,
            steps,
            window,
            window_s: spec.reorder_window,
            frontier: None,
            closed_in: None,
            closed_out: None,
            emitted: 0,
            queued: 0,
            max_backlog: spec.max_backlog,
            eof: false,
            pending: None,
            finished: false,
            scratch: Vec::new(),
        };
        // Every known channel of a mapped topic is checked now, before any row.
        let ids: Vec<u16> = self.channels.keys().copied().collect();
        for id in ids {
            rows.decoder(id)?;
        }
        Ok(rows)
    }

    /// All rows `spec` asks for, or the first error.
    ///
    /// # Errors
    /// As [`Bag::rows`] and its iterator.
    pub fn read_rows(&self, spec: &LogSpec) -> Result<Vec<Row>> {
        self.rows(spec)?.collect()
    }
}

impl Rows<'_> {
    /// Each mapped topic and whether its messages are stamped from `header.stamp` (else the log
    /// time).
    pub fn header_stamped(&self) -> Vec<(String, bool)> {
        self.topics.iter().map(|t| (t.name.clone(), t.header_stamped.unwrap_or(false))).collect()
    }

    /// The decoder of channel `id` (built on first use); `None` if the channel is not mapped.
    fn decoder(&mut self, id: u16) -> Result<Option<usize>> {
        if let Some(d) = self.decoders.get(&id) {
            return Ok(d.as_ref().map(|(t, _)| *t));
        }
        let channel = self.bag.channels.get(&id).or_else(|| self.extra_channels.get(&id));
        let Some(channel) = channel else { return Ok(None) };
        let Some(&t) = self.topic_index.get(&channel.topic) else {
            self.decoders.insert(id, None);
            return Ok(None);
        };
        let schema = if channel.schema_id == 0 {
            None
        } else {
            self.bag.schemas.get(&channel.schema_id).or_else(|| self.extra_schemas.get(&channel.schema_id))
        };
        let d = Decoder::new(channel, schema, &self.topics[t].keys, self.want_header)?;
        let topic = &mut self.topics[t];
        topic.header_stamped = Some(topic.header_stamped.unwrap_or(false) || d.header());
        self.decoders.insert(id, Some((t, d)));
        Ok(Some(t))
    }

    fn decode_error(&self, t: usize, msg: &RawMessage<'_>, e: DecodeError) -> Error {
        let topic = &self.topics[t];
        let key_of = |slot: usize| {
            topic.keys.get(slot).cloned().unwrap_or_else(|| ("header.stamp".into(), "header.stamp".into()))
        };
        match e {
            DecodeError::Corrupt(reason) => {
                Error::Undecodable { topic: topic.name.clone(), log_time: msg.log_time, location: msg.location, reason }
            }
            DecodeError::Missing { slot, reason } => Error::MissingField {
                key: key_of(slot).0,
                topic: topic.name.clone(),
                log_time: msg.log_time,
                location: msg.location,
                reason,
            },
            DecodeError::NonNumeric { slot, found } => {
                let (key, field) = key_of(slot);
                Error::NonNumeric { key, topic: topic.name.clone(), field, found }
            }
        }
    }

    fn ingest(&mut self, msg: RawMessage<'_>) -> Result<()> {
        let Some(t) = self.decoder(msg.channel_id)? else { return Ok(()) };
        let n = self.topics[t].keys.len();
        self.scratch.clear();
        self.scratch.resize(n + 2, f64::NAN);
        let Some(Some((_, d))) = self.decoders.get(&msg.channel_id) else { return Ok(()) };
        let stamp = match d.decode(&msg.data, &mut self.scratch) {
            Ok(s) => s,
            Err(e) => return Err(self.decode_error(t, &msg, e)),
        };
        let topic = &self.topics[t];
        let time = match stamp {
            Some(0) => {
                return Err(Error::ZeroStamp {
                    topic: topic.name.clone(),
                    log_time: msg.log_time,
                    location: msg.location,
                });
            }
            Some(s) => s,
            None => i64::try_from(msg.log_time).map_err(|_| Error::Undecodable {
                topic: topic.name.clone(),
                log_time: msg.log_time,
                location: msg.location,
                reason: "log time beyond the year 2262".into(),
            })?,
        };
        if let Some(previous) = topic.last.filter(|&p| time < p) {
            return Err(Error::OutOfOrder { topic: topic.name.clone(), previous, time, location: msg.location });
        }
        // A message that would change a published row. (The driving topic's own stamps only
        // make steps: going back is caught above.)
        let closed = if topic.has_outputs { self.closed_out } else { self.closed_in };
        if let Some(c) = closed.filter(|&c| time <= c && n > 0) {
            return Err(Error::Late {
                topic: topic.name.clone(),
                time,
                closed: c,
                window: self.window_s,
                location: msg.location,
            });
        }
        let topic = &mut self.topics[t];
        topic.last = Some(time);
        topic.count += 1;
        if n > 0 {
            topic.queue.push_back((time, self.scratch[..n].to_vec()));
            self.queued += 1;
        }
        match &mut self.steps {
            Steps::Fixed { t0, start, .. } => {
                if t0.is_none() {
                    *t0 = Some(start.unwrap_or(time));
                }
            }
            Steps::PerMessage { topic: d, times } => {
                if *d == t {
                    times.push_back(time);
                    self.queued += 1;
                }
            }
        }
        self.frontier = Some(self.frontier.map_or(time, |f| f.max(time)));
        if self.queued > self.max_backlog {
            let name = match &self.steps {
                Steps::PerMessage { topic, .. } => self.topics[*topic].name.clone(),
                Steps::Fixed { .. } => self.topics[t].name.clone(),
            };
            return Err(Error::Backlog { topic: name, limit: self.max_backlog });
        }
        Ok(())
    }

    /// The next step's time and window end, if its row can be made now; `Err(())` when there
    /// are no more steps.
    fn ready(&self) -> Result<Option<(i64, i64)>, ()> {
        let (tk, end) = match &self.steps {
            Steps::Fixed { ts, t0: Some(t0), next, .. } => {
                let tk = i128::from(*t0) + i128::from(*ts) * i128::from(*next);
                let Ok(tk) = i64::try_from(tk) else { return Err(()) };
                (tk, tk.saturating_add(*ts))
            }
            Steps::Fixed { t0: None, .. } => return if self.stopped() { Err(()) } else { Ok(None) },
            Steps::PerMessage { times, .. } => match (times.front(), times.get(1)) {
                (Some(&a), Some(&b)) => (a, b),
                _ => return if self.stopped() { Err(()) } else { Ok(None) },
            },
        };
        let Some(frontier) = self.frontier else { return if self.stopped() { Err(()) } else { Ok(None) } };
        if self.pending.is_some() {
            // Reading stopped: the steps whose whole window lies before the last stamp read.
            return if end < frontier { Ok(Some((tk, end))) } else { Err(()) };
        }
        if self.eof {
            let fixed = matches!(self.steps, Steps::Fixed { .. });
            return if fixed && tk > frontier { Err(()) } else { Ok(Some((tk, end))) };
        }
        let settled = i128::from(frontier) - i128::from(self.window) > i128::from(end);
        Ok(settled.then_some((tk, end)))
    }

    /// Makes step (tk, end]; `None` if an input has had no message yet (the step is skipped).
    fn step(&mut self, tk: i64, end: i64) -> Option<Row> {
        let mut u = vec![f64::NAN; self.inputs.len()];
        let mut y = vec![f64::NAN; self.outputs.len()];
        let mut measured = vec![false; self.outputs.len()];
        let mut complete = true;
        for (ti, topic) in self.topics.iter_mut().enumerate() {
            while topic.queue.front().is_some_and(|(s, _)| *s <= tk) {
                topic.held = topic.queue.pop_front().map(|(_, v)| v);
                self.queued -= 1;
            }
            for (i, &(t, slot)) in self.inputs.iter().enumerate() {
                if t == ti {
                    match &topic.held {
                        Some(v) => u[i] = v[slot],
                        None => complete = false,
                    }
                }
            }
            let mut latest = None;
            while topic.queue.front().is_some_and(|(s, _)| *s <= end) {
                latest = topic.queue.pop_front().map(|(_, v)| v);
                self.queued -= 1;
            }
            if let Some(v) = latest {
                for (i, &(t, slot)) in self.outputs.iter().enumerate() {
                    if t == ti {
                        y[i] = v[slot];
                        measured[i] = true;
                    }
                }
                topic.held = Some(v);
            }
        }
        match &mut self.steps {
            Steps::Fixed { next, .. } => *next += 1,
            Steps::PerMessage { times, .. } => {
                times.pop_front();
                self.queued -= 1;
            }
        }
        self.closed_in = Some(tk);
        self.closed_out = Some(end);
        if !complete {
            return None;
        }
        let k = self.emitted;
        self.emitted += 1;
        Some(Row { k, t_ns: tk, t: tk as f64 / 1e9, end_ns: end, u, y, measured })
    }

    fn stopped(&self) -> bool {
        self.eof || self.pending.is_some()
    }

    fn at_end(&mut self) -> Option<Error> {
        if let Some(e) = self.pending.take() {
            return Some(e);
        }
        for &(t, slot) in &self.inputs {
            let topic = &self.topics[t];
            if topic.count == 0 {
                return Some(Error::NeverPublished { key: topic.keys[slot].0.clone(), topic: topic.name.clone() });
            }
        }
        None
    }
}

impl Iterator for Rows<'_> {
    type Item = Result<Row>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if self.finished {
                return None;
            }
            match self.ready() {
                Ok(Some((tk, end))) => {
                    if let Some(row) = self.step(tk, end) {
                        return Some(Ok(row));
                    }
                    continue;
                }
                Ok(None) => {}
                Err(()) => {
                    self.finished = true;
                    return self.at_end().map(Err);
                }
            }
            let item = self.walker.next();
            let result = match item {
                None => {
                    self.eof = true;
                    Ok(())
                }
                Some(Err(e)) => Err(e),
                Some(Ok(Item::Schema(s))) => {
                    self.extra_schemas.entry(s.id).or_insert(s);
                    Ok(())
                }
                Some(Ok(Item::Channel(c))) => {
                    if !self.bag.channels.contains_key(&c.id) {
                        self.extra_channels.entry(c.id).or_insert(c);
                    }
                    Ok(())
                }
                Some(Ok(Item::Message(m))) => self.ingest(m),
            };
            if let Err(e) = result {
                // The rows whose windows closed before the error come first.
                self.pending = Some(e);
            }
        }
    }
}
