//! The MCAP container: the file memory-mapped, its top-level records walked here (so that every
//! record has its byte offset), chunks decompressed one at a time by the `mcap` crate's
//! sans-I/O reader with a record-length limit.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::path::Path;

use mcap::records::{Record, op};
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};

use crate::error::{Error, Location};

/// A schema record.
#[derive(Debug, Clone)]
pub(crate) struct SchemaRec {
    pub id: u16,
    pub name: String,
    pub encoding: String,
    pub data: Vec<u8>,
}

/// A channel record.
#[derive(Debug, Clone)]
pub(crate) struct ChannelRec {
    pub id: u16,
    pub schema_id: u16,
    pub topic: String,
    pub message_encoding: String,
    pub metadata: BTreeMap<String, String>,
}

/// A message: its header, its bytes (borrowed from the map outside chunks) and where it lies.
#[derive(Debug)]
pub(crate) struct RawMessage<'a> {
    pub channel_id: u16,
    pub sequence: u32,
    pub log_time: u64,
    pub publish_time: u64,
    pub data: Cow<'a, [u8]>,
    pub location: Location,
}

#[derive(Debug)]
pub(crate) enum Item<'a> {
    Schema(SchemaRec),
    Channel(ChannelRec),
    Message(RawMessage<'a>),
}

const OPCODE_LEN: usize = 9;

fn record_name(opcode: u8) -> &'static str {
    match opcode {
        op::HEADER => "header record",
        op::FOOTER => "footer record",
        op::SCHEMA => "schema record",
        op::CHANNEL => "channel record",
        op::MESSAGE => "message record",
        op::CHUNK => "chunk",
        op::MESSAGE_INDEX => "message index record",
        op::CHUNK_INDEX => "chunk index record",
        op::ATTACHMENT => "attachment record",
        op::STATISTICS => "statistics record",
        op::METADATA => "metadata record",
        op::DATA_END => "data end record",
        _ => "record",
    }
}

/// An error and its sources in one line.
pub(crate) fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut src = e.source();
    while let Some(x) = src {
        s.push_str(": ");
        s.push_str(&x.to_string());
        src = x.source();
    }
    s
}

/// Turns a schema, channel or message record into an item (others: `None`).
fn item<'a>(record: Record<'a>, location: Location) -> Option<Item<'a>> {
    match record {
        Record::Schema { header, data } => Some(Item::Schema(SchemaRec {
            id: header.id,
            name: header.name,
            encoding: header.encoding,
            data: data.into_owned(),
        })),
        Record::Channel(c) => Some(Item::Channel(ChannelRec {
            id: c.id,
            schema_id: c.schema_id,
            topic: c.topic,
            message_encoding: c.message_encoding,
            metadata: c.metadata,
        })),
        Record::Message { header, data } => Some(Item::Message(RawMessage {
            channel_id: header.channel_id,
            sequence: header.sequence,
            log_time: header.log_time,
            publish_time: header.publish_time,
            data,
            location,
        })),
        _ => None,
    }
}

/// The records of one chunk, decompressed one at a time.
struct ChunkRecords<'a> {
    reader: LinearReader,
    /// The chunk record's bytes not yet given to the reader.
    feed: &'a [u8],
    offset: u64,
    /// Offset of the next record in the uncompressed data.
    inner: u64,
}

/// Walks the top-level records of `buf[start..end]`, descending into chunks.
pub(crate) struct Walker<'a> {
    buf: &'a [u8],
    path: &'a Path,
    pos: usize,
    end: usize,
    max_chunk: usize,
    chunk: Option<ChunkRecords<'a>>,
    done: bool,
    /// Whether running out of bytes before a data-end record is truncation (the data section).
    data_section: bool,
}

impl<'a> Walker<'a> {
    /// The data section: after the magic, up to the data-end record.
    pub(crate) fn data(buf: &'a [u8], path: &'a Path, max_chunk: usize) -> Self {
        Self {
            buf,
            path,
            pos: mcap::MAGIC.len(),
            end: buf.len(),
            max_chunk,
            chunk: None,
            done: false,
            data_section: true,
        }
    }

    /// The summary section, if the footer points at one.
    pub(crate) fn summary(buf: &'a [u8], path: &'a Path, max_chunk: usize) -> Option<Self> {
        let magic = mcap::MAGIC.len();
        let footer_len = OPCODE_LEN + 20;
        if buf.len() < 2 * magic + footer_len || !buf.ends_with(mcap::MAGIC) {
            return None;
        }
        let footer = buf.len() - magic - footer_len;
        if buf[footer] != op::FOOTER || buf.get(footer + 1..footer + 9)? != 20u64.to_le_bytes() {
            return None;
        }
        let start = u64::from_le_bytes(buf.get(footer + 9..footer + 17)?.try_into().ok()?);
        let start = usize::try_from(start).ok()?;
        if start < magic || start > footer {
            return None;
        }
        Some(Self { buf, path, pos: start, end: footer, max_chunk, chunk: None, done: false, data_section: false })
    }

    fn corrupt(&self, record: &str, location: Location, detail: String) -> Error {
        Error::Corrupt { path: self.path.to_owned(), record: record.to_owned(), location, detail }
    }

    fn next_in_chunk(&mut self) -> Option<Result<Item<'a>, Error>> {
        let c = self.chunk.as_mut()?;
        loop {
            let at = Location { offset: c.offset, in_chunk: Some(c.inner) };
            match c.reader.next_event() {
                None => {
                    self.chunk = None;
                    return None;
                }
                Some(Ok(LinearReadEvent::ReadRequest(n))) => {
                    let n = n.min(c.feed.len());
                    c.reader.insert(n).copy_from_slice(&c.feed[..n]);
                    c.reader.notify_read(n);
                    c.feed = &c.feed[n..];
                }
                Some(Ok(LinearReadEvent::Record { data, opcode })) => {
                    c.inner += (OPCODE_LEN + data.len()) as u64;
                    if !matches!(opcode, op::SCHEMA | op::CHANNEL | op::MESSAGE) {
                        continue;
                    }
                    let parsed = mcap::parse_record(opcode, data).map(Record::into_owned);
                    match parsed {
                        Ok(r) => {
                            if let Some(it) = item(r, at) {
                                return Some(Ok(it));
                            }
                        }
                        Err(e) => {
                            let name = record_name(opcode);
                            self.chunk = None;
                            self.done = true;
                            return Some(Err(self.corrupt(name, at, chain(&e))));
                        }
                    }
                }
                Some(Err(e)) => {
                    self.chunk = None;
                    self.done = true;
                    return Some(Err(self.corrupt("chunk", at, chain(&e))));
                }
            }
        }
    }
}

impl std::fmt::Debug for Walker<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Walker").field("pos", &self.pos).field("end", &self.end).finish_non_exhaustive()
    }
}

impl<'a> Iterator for Walker<'a> {
    type Item = Result<Item<'a>, Error>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            if self.chunk.is_some() {
                match self.next_in_chunk() {
                    Some(x) => return Some(x),
                    None => continue,
                }
            }
            if self.done {
                return None;
            }
            let at = Location { offset: self.pos as u64, in_chunk: None };
            let left = self.end.saturating_sub(self.pos);
            if left == 0 && !self.data_section {
                self.done = true;
                return None;
            }
            if left < OPCODE_LEN {
                self.done = true;
                let detail = format!(
                    "the file ends after {left} bytes of a record header, without a data end record: truncated"
                );
                return Some(Err(self.corrupt("record", at, detail)));
            }
            let opcode = self.buf[self.pos];
            let mut len_bytes = [0; 8];
            len_bytes.copy_from_slice(&self.buf[self.pos + 1..self.pos + OPCODE_LEN]);
            let len = u64::from_le_bytes(len_bytes);
            let name = record_name(opcode);
            if len > (left - OPCODE_LEN) as u64 {
                self.done = true;
                let detail =
                    format!("claims {len} bytes but {} remain: the file is truncated or corrupt", left - OPCODE_LEN);
                return Some(Err(self.corrupt(name, at, detail)));
            }
            let start = self.pos;
            let body_end = start + OPCODE_LEN + len as usize;
            let body = &self.buf[start + OPCODE_LEN..body_end];
            self.pos = body_end;
            match opcode {
                op::SCHEMA | op::CHANNEL | op::MESSAGE => match mcap::parse_record(opcode, body) {
                    Ok(r) => {
                        if let Some(it) = item(r, at) {
                            return Some(Ok(it));
                        }
                    }
                    Err(e) => {
                        self.done = true;
                        return Some(Err(self.corrupt(name, at, chain(&e))));
                    }
                },
                op::CHUNK => {
                    let options = LinearReaderOptions::default()
                        .with_skip_start_magic(true)
                        .with_skip_end_magic(true)
                        .with_prevalidate_chunk_crcs(true)
                        .with_record_length_limit(self.max_chunk);
                    self.chunk = Some(ChunkRecords {
                        reader: LinearReader::new_with_options(options),
                        feed: &self.buf[start..body_end],
                        offset: start as u64,
                        inner: 0,
                    });
                }
                op::DATA_END | op::FOOTER if self.data_section => {
                    self.done = true;
                    return None;
                }
                _ => {}
            }
        }
    }
}

/// The schemas and channels of a file: from its summary section when it has a readable one,
/// otherwise from a walk of the data section (up to any damage).
pub(crate) fn channels(
    buf: &[u8],
    path: &Path,
    max_chunk: usize,
) -> (BTreeMap<u16, SchemaRec>, BTreeMap<u16, ChannelRec>) {
    let mut schemas = BTreeMap::new();
    let mut channels = BTreeMap::new();
    let mut take = |walker: Walker<'_>| -> bool {
        for it in walker {
            match it {
                Ok(Item::Schema(s)) => {
                    schemas.entry(s.id).or_insert(s);
                }
                Ok(Item::Channel(c)) => {
                    channels.entry(c.id).or_insert(c);
                }
                Ok(Item::Message(_)) => {}
                Err(_) => return false,
            }
        }
        true
    };
    let from_summary = Walker::summary(buf, path, max_chunk).is_some_and(&mut take);
    if !from_summary {
        take(Walker::data(buf, path, max_chunk));
    }
    (schemas, channels)
}
