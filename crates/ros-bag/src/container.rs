//! The MCAP container: the file memory-mapped, its records walked here (so that every record has
//! its byte offset) and parsed by the `mcap` crate. A chunk is decompressed whole into a buffer
//! that grows with the bytes the decoder actually produces (never reserved from the size the
//! file declares), at most the declared size and the limit, and its CRC checked before any of its
//! records is used; an uncompressed chunk is read in place.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

use mcap::records::op;

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

/// Little-endian fields of a record body, every length checked against the bytes left before
/// anything is taken or allocated. (The `mcap` crate's parser reserves a string's declared
/// length before reading it: a damaged length would ask for up to 4 GiB.)
struct Fields<'a> {
    b: &'a [u8],
}

impl<'a> Fields<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        if n > self.b.len() {
            return Err(format!("its {what} needs {n} bytes, {} remain in the record", self.b.len()));
        }
        let (x, rest) = self.b.split_at(n);
        self.b = rest;
        Ok(x)
    }

    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], String> {
        let mut a = [0; N];
        a.copy_from_slice(self.take(N, what)?);
        Ok(a)
    }

    fn u16(&mut self, what: &str) -> Result<u16, String> {
        Ok(u16::from_le_bytes(self.array(what)?))
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        Ok(u32::from_le_bytes(self.array(what)?))
    }

    fn u64(&mut self, what: &str) -> Result<u64, String> {
        Ok(u64::from_le_bytes(self.array(what)?))
    }

    /// A `uint32` length, then that many bytes.
    fn bytes(&mut self, what: &str) -> Result<&'a [u8], String> {
        let n = self.u32(what)? as usize;
        self.take(n, what)
    }

    fn string(&mut self, what: &str) -> Result<String, String> {
        let b = self.bytes(what)?;
        String::from_utf8(b.to_vec()).map_err(|_| format!("its {what} is not UTF-8"))
    }
}

/// A schema, channel or message record as an item (other records: `None`).
fn parse_item(opcode: u8, body: &[u8], location: Location) -> Result<Option<Item<'_>>, String> {
    let mut f = Fields { b: body };
    Ok(Some(match opcode {
        op::SCHEMA => Item::Schema(SchemaRec {
            id: f.u16("id")?,
            name: f.string("name")?,
            encoding: f.string("encoding")?,
            data: f.bytes("data")?.to_vec(),
        }),
        op::CHANNEL => {
            let id = f.u16("id")?;
            let schema_id = f.u16("schema id")?;
            let topic = f.string("topic")?;
            let message_encoding = f.string("message encoding")?;
            let mut m = Fields { b: f.bytes("metadata")? };
            let mut metadata = BTreeMap::new();
            while !m.b.is_empty() {
                let k = m.string("metadata key")?;
                metadata.insert(k, m.string("metadata value")?);
            }
            Item::Channel(ChannelRec { id, schema_id, topic, message_encoding, metadata })
        }
        op::MESSAGE => Item::Message(RawMessage {
            channel_id: f.u16("channel id")?,
            sequence: f.u32("sequence")?,
            log_time: f.u64("log time")?,
            publish_time: f.u64("publish time")?,
            data: Cow::Borrowed(f.b),
            location,
        }),
        _ => return Ok(None),
    }))
}

/// A chunk record's header.
struct ChunkHeader {
    uncompressed_size: u64,
    uncompressed_crc: u32,
    compression: String,
}

fn parse_chunk(body: &[u8]) -> Result<(ChunkHeader, &[u8]), String> {
    let mut f = Fields { b: body };
    f.u64("start time")?;
    f.u64("end time")?;
    let uncompressed_size = f.u64("uncompressed size")?;
    let uncompressed_crc = f.u32("CRC")?;
    let compression = f.string("compression")?;
    let n = f.u64("records' size")?;
    let records = f.take(usize::try_from(n).unwrap_or(usize::MAX), "records")?;
    Ok((ChunkHeader { uncompressed_size, uncompressed_crc, compression }, records))
}

/// The records of one chunk.
struct ChunkRecords<'a> {
    data: Cow<'a, [u8]>,
    pos: usize,
    offset: u64,
}

/// Decompresses a chunk's records: `Err` says why not.
fn decompress<'a>(header: &ChunkHeader, data: &'a [u8], limit: usize) -> Result<Cow<'a, [u8]>, String> {
    let declared = header.uncompressed_size;
    let cap = usize::try_from(declared)
        .ok()
        .filter(|&n| n <= limit)
        .ok_or_else(|| format!("declares {declared} uncompressed bytes, more than the limit of {limit}"))?;
    let out: Cow<'a, [u8]> = match header.compression.as_str() {
        "" => Cow::Borrowed(data),
        name @ ("zstd" | "lz4") => {
            let mut out = Vec::new();
            let read = match name {
                "zstd" => zstd::stream::read::Decoder::with_buffer(data)
                    .and_then(|d| d.take(cap as u64 + 1).read_to_end(&mut out)),
                _ => lz4::Decoder::new(data).and_then(|d| d.take(cap as u64 + 1).read_to_end(&mut out)),
            };
            read.map_err(|e| format!("{name} data does not decompress: {e}"))?;
            Cow::Owned(out)
        }
        other => return Err(format!("compression `{other}` is not supported (zstd, lz4 or none)")),
    };
    if out.len() != cap {
        return Err(format!("holds {} bytes of records, not the {declared} it declares", out.len()));
    }
    if header.uncompressed_crc != 0 {
        let crc = crc32fast::hash(&out);
        if crc != header.uncompressed_crc {
            return Err(format!("CRC {crc:08x} of its records is not the {:08x} it declares", header.uncompressed_crc));
        }
    }
    Ok(out)
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
            let at = Location { offset: c.offset, in_chunk: Some(c.pos as u64) };
            let left = c.data.len() - c.pos;
            if left == 0 {
                self.chunk = None;
                return None;
            }
            let header = c.data.get(c.pos..c.pos + OPCODE_LEN);
            let len = header.map(|h| u64::from_le_bytes([h[1], h[2], h[3], h[4], h[5], h[6], h[7], h[8]]));
            let (opcode, len) = match (header, len) {
                (Some(h), Some(len)) if len <= (left - OPCODE_LEN) as u64 => (h[0], len as usize),
                _ => {
                    let detail = format!("a record inside the chunk runs past its end ({left} bytes left)");
                    self.chunk = None;
                    self.done = true;
                    return Some(Err(self.corrupt("chunk", at, detail)));
                }
            };
            let start = c.pos + OPCODE_LEN;
            c.pos = start + len;
            if !matches!(opcode, op::SCHEMA | op::CHANNEL | op::MESSAGE) {
                continue;
            }
            let parsed = match &c.data {
                Cow::Borrowed(d) => parse_item(opcode, &d[start..start + len], at),
                Cow::Owned(d) => parse_item(opcode, &d[start..start + len], at).map(|i| i.map(owned)),
            };
            match parsed {
                Ok(Some(it)) => return Some(Ok(it)),
                Ok(None) => {}
                Err(detail) => {
                    self.chunk = None;
                    self.done = true;
                    return Some(Err(self.corrupt(record_name(opcode), at, detail)));
                }
            }
        }
    }
}

/// An item that borrows nothing.
fn owned(item: Item<'_>) -> Item<'static> {
    match item {
        Item::Schema(s) => Item::Schema(s),
        Item::Channel(c) => Item::Channel(c),
        Item::Message(m) => Item::Message(RawMessage { data: Cow::Owned(m.data.into_owned()), ..m }),
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
                op::SCHEMA | op::CHANNEL | op::MESSAGE => match parse_item(opcode, body, at) {
                    Ok(Some(it)) => return Some(Ok(it)),
                    Ok(None) => {}
                    Err(detail) => {
                        self.done = true;
                        return Some(Err(self.corrupt(name, at, detail)));
                    }
                },
                op::CHUNK => match parse_chunk(body).and_then(|(h, data)| decompress(&h, data, self.max_chunk)) {
                    Ok(data) => self.chunk = Some(ChunkRecords { data, pos: 0, offset: start as u64 }),
                    Err(detail) => {
                        self.done = true;
                        return Some(Err(self.corrupt(name, at, detail)));
                    }
                },
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
