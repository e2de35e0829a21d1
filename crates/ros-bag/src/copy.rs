//! A bag's topics copied into an estimate bag: schemas, channels and messages unchanged (the
//! message bytes, sequence numbers, log and publish times as they are), streamed from the source
//! in file order and interleaved with the estimates by log time.

use std::collections::{BTreeMap, HashMap};

use mcap::records::MessageHeader;

use crate::bag::Bag;
use crate::container::{ChannelRec, Item, RawMessage, SchemaRec, Walker, chain};
use crate::error::{Error, Result};
use crate::writer::EstimateWriter;

/// Which topics a [`TopicCopy`] copies.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Selection {
    /// Every topic but the estimates' own.
    All { own: String },
    /// These.
    Only(Vec<String>),
}

impl Selection {
    fn wants(&self, topic: &str) -> bool {
        match self {
            Self::All { own } => topic != own,
            Self::Only(t) => t.iter().any(|x| x == topic),
        }
    }
}

/// Copies topics of a bag into an [`EstimateWriter`] as its estimates are written: before the
/// estimate at time `t`, [`TopicCopy::until`] copies the source's messages up to log time `t`, so
/// that the output holds data and estimates in one time order (as far as the source is in log-time
/// order: the copy follows the source's file order, never sorts). [`TopicCopy::rest`] copies what
/// is left. One chunk of the source is decompressed at a time; nothing else is kept.
///
/// ```no_run
/// use ros_bag::{Bag, Estimate, EstimateLayout, EstimateWriter, TopicCopy};
///
/// let bag = Bag::open("run.mcap")?;
/// let mut out = EstimateWriter::create("est.mcap", EstimateLayout::new("/estimate", ["px"]))?;
/// let mut copy = TopicCopy::all(&bag, &out);
/// for (k, t_ns) in [(0u64, 1_700_000_000_010_000_000i64), (1, 1_700_000_000_020_000_000)] {
///     copy.until(&mut out, t_ns as u64)?;
///     out.write(&Estimate::new(k, t_ns, &[1.0]))?;
/// }
/// copy.rest(&mut out)?;
/// out.finish()?;
/// # Ok::<(), ros_bag::Error>(())
/// ```
#[derive(Debug)]
pub struct TopicCopy<'b> {
    walker: Walker<'b>,
    selection: Selection,
    channels: BTreeMap<u16, ChannelRec>,
    schemas: BTreeMap<u16, SchemaRec>,
    /// Source channel → output channel (`None`: not copied).
    ids: HashMap<u16, Option<u16>>,
    /// Source schema → output schema.
    schema_ids: HashMap<u16, u16>,
    /// A message read past the time asked for, copied at the next call.
    pending: Option<RawMessage<'b>>,
    done: bool,
    copied: u64,
}

impl<'b> TopicCopy<'b> {
    fn new(bag: &'b Bag, selection: Selection) -> Self {
        Self {
            walker: bag.walker(),
            selection,
            channels: bag.channels.clone(),
            schemas: bag.schemas.clone(),
            ids: HashMap::new(),
            schema_ids: HashMap::new(),
            pending: None,
            done: false,
            copied: 0,
        }
    }

    /// Every topic of `bag` but `out`'s estimate topic (a bag written by an earlier run holds
    /// estimates of its own on it: they are not copied beside the new ones).
    pub fn all(bag: &'b Bag, out: &EstimateWriter) -> Self {
        Self::new(bag, Selection::All { own: out.topic().to_owned() })
    }

    /// The topics `topics` of `bag`.
    ///
    /// # Errors
    /// [`Error::UnknownTopic`] (key `copy`) for a topic the bag does not have, with the topics it
    /// has; [`Error::Config`] for `out`'s estimate topic (two channels would share it).
    pub fn only(bag: &'b Bag, topics: &[&str], out: &EstimateWriter) -> Result<Self> {
        let available = bag.topics();
        if let Some(t) = topics.iter().find(|t| !available.iter().any(|a| a == *t)) {
            return Err(Error::UnknownTopic { key: "copy".into(), topic: (*t).to_owned(), available });
        }
        if topics.contains(&out.topic()) {
            return Err(Error::Config(format!(
                "the topic `{}` is the estimates' own: it is not copied beside them",
                out.topic()
            )));
        }
        Ok(Self::new(bag, Selection::Only(topics.iter().map(|t| (*t).to_owned()).collect())))
    }

    /// The messages copied so far.
    pub fn copied(&self) -> u64 {
        self.copied
    }

    /// Copies the source's messages, in file order, up to the first whose log time is after
    /// `log_time_ns` (which waits for the next call); returns how many were copied.
    ///
    /// # Errors
    /// The source's read errors ([`Error::Corrupt`] naming the record and its byte offset), the
    /// writer's ([`Error::Write`]). After an error the output is not to be finished.
    pub fn until(&mut self, out: &mut EstimateWriter, log_time_ns: u64) -> Result<u64> {
        self.copy(out, Some(log_time_ns))
    }

    /// Copies every message left; returns how many.
    ///
    /// # Errors
    /// As [`TopicCopy::until`].
    pub fn rest(&mut self, out: &mut EstimateWriter) -> Result<u64> {
        self.copy(out, None)
    }

    fn copy(&mut self, out: &mut EstimateWriter, limit: Option<u64>) -> Result<u64> {
        let before = self.copied;
        loop {
            let m = match self.pending.take() {
                Some(m) => m,
                None => {
                    if self.done {
                        break;
                    }
                    match self.walker.next() {
                        None => {
                            self.done = true;
                            break;
                        }
                        Some(Err(e)) => {
                            self.done = true;
                            return Err(e);
                        }
                        Some(Ok(Item::Schema(s))) => {
                            self.schemas.entry(s.id).or_insert(s);
                            continue;
                        }
                        Some(Ok(Item::Channel(c))) => {
                            self.channels.entry(c.id).or_insert(c);
                            continue;
                        }
                        Some(Ok(Item::Message(m))) => m,
                    }
                }
            };
            if limit.is_some_and(|t| m.log_time > t) {
                self.pending = Some(m);
                break;
            }
            let Some(id) = self.channel(out, m.channel_id)? else { continue };
            let header = MessageHeader {
                channel_id: id,
                sequence: m.sequence,
                log_time: m.log_time,
                publish_time: m.publish_time,
            };
            let path = out.path().to_owned();
            out.raw()?
                .write_to_known_channel(&header, &m.data)
                .map_err(|e| Error::Write { path, detail: chain(&e) })?;
            self.copied += 1;
        }
        Ok(self.copied - before)
    }

    /// The output channel of source channel `source` (added with its schema on first use), or
    /// `None` if its topic is not copied (or the channel is unknown: the source's messages on it
    /// cannot be decoded by anyone, and are left out).
    fn channel(&mut self, out: &mut EstimateWriter, source: u16) -> Result<Option<u16>> {
        if let Some(&id) = self.ids.get(&source) {
            return Ok(id);
        }
        let Some(c) = self.channels.get(&source).filter(|c| self.selection.wants(&c.topic)) else {
            self.ids.insert(source, None);
            return Ok(None);
        };
        let path = out.path().to_owned();
        let w = |e: mcap::McapError| Error::Write { path: path.clone(), detail: chain(&e) };
        let schema_id = match self.schemas.get(&c.schema_id).filter(|_| c.schema_id != 0) {
            None => 0,
            Some(s) => match self.schema_ids.get(&s.id) {
                Some(&id) => id,
                None => {
                    let id = out.raw()?.add_schema(&s.name, &s.encoding, &s.data).map_err(w)?;
                    self.schema_ids.insert(s.id, id);
                    id
                }
            },
        };
        let id = out.raw()?.add_channel(schema_id, &c.topic, &c.message_encoding, &c.metadata).map_err(w)?;
        self.ids.insert(source, Some(id));
        Ok(Some(id))
    }
}

/// The all-at-once copy, written here beside [`TopicCopy`] (the writer knows nothing of copies).
impl EstimateWriter {
    /// Copies every message of `topics` from `bag` (their channels and schemas too), in file
    /// order, all at once; returns the number of messages copied. [`TopicCopy`] interleaves them
    /// with the estimates by log time instead.
    ///
    /// # Errors
    /// As [`TopicCopy::only`] and [`TopicCopy::rest`].
    pub fn copy_topics(&mut self, bag: &Bag, topics: &[&str]) -> Result<u64> {
        TopicCopy::only(bag, topics, self)?.rest(self)
    }
}
