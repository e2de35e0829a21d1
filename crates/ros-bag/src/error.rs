//! The crate's error: every variant names what went wrong and where.

use std::fmt;
use std::path::PathBuf;

/// Where in the file a record lies: the byte offset of the top-level record and, for a record
/// inside a chunk, the offset of the record within the chunk's uncompressed records.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Location {
    /// Byte offset in the file of the top-level record (the chunk, for a record inside one).
    pub offset: u64,
    /// For a record inside a chunk: its offset within the chunk's uncompressed records.
    pub in_chunk: Option<u64>,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.in_chunk {
            None => write!(f, "byte {}", self.offset),
            Some(inner) => {
                write!(f, "chunk at byte {}, record at offset {inner} of its uncompressed data", self.offset)
            }
        }
    }
}

/// Seconds with nanoseconds, for messages: `1700000000.123456789 s`.
pub(crate) fn secs(ns: i64) -> String {
    let sign = if ns < 0 { "-" } else { "" };
    let a = ns.unsigned_abs();
    format!("{sign}{}.{:09} s", a / 1_000_000_000, a % 1_000_000_000)
}

fn list(items: &[String]) -> String {
    if items.is_empty() { "(none)".to_owned() } else { items.join(", ") }
}

/// Everything that can go wrong reading or writing a bag.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The file could not be opened, mapped, written or published.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file does not start with the MCAP magic bytes.
    #[error("{}: not an MCAP file (no MCAP magic at the start)", path.display())]
    NotMcap {
        /// The file.
        path: PathBuf,
    },
    /// A truncated or corrupt record or chunk. Rows read before it stay valid.
    #[error("{}: {record} at {location}: {detail}", path.display())]
    Corrupt {
        /// The file.
        path: PathBuf,
        /// The kind of record (`message`, `chunk`, …).
        record: String,
        /// Where it lies.
        location: Location,
        /// What is wrong with it.
        detail: String,
    },
    /// A mapping names a topic the bag does not have.
    #[error("mapping `{key}`: no topic `{topic}` in the bag; its topics: {}", list(available))]
    UnknownTopic {
        /// The mapping key (`gnss_x`), or `time base` for the driving topic.
        key: String,
        /// The topic asked for.
        topic: String,
        /// The topics the bag has.
        available: Vec<String>,
    },
    /// A field path that is not written correctly (`a..b`, `x[`, …).
    #[error("mapping `{key}`: bad field path `{field}`: {reason}")]
    BadFieldPath {
        /// The mapping key.
        key: String,
        /// The field path as written.
        field: String,
        /// What is wrong.
        reason: String,
    },
    /// A field path the topic's message type does not have (or that is not a number).
    #[error(
        "mapping `{key}`: topic `{topic}` has no numeric field `{field}` ({reason}); its numeric fields: {}",
        list(available)
    )]
    UnknownField {
        /// The mapping key.
        key: String,
        /// The topic.
        topic: String,
        /// The field path asked for.
        field: String,
        /// Why it does not resolve (naming the message type).
        reason: String,
        /// The numeric field paths a mapping can use.
        available: Vec<String>,
    },
    /// A mapped field that holds no number (a string, a message).
    #[error("mapping `{key}`: field `{field}` of topic `{topic}` is a {found}, not a number")]
    NonNumeric {
        /// The mapping key.
        key: String,
        /// The topic.
        topic: String,
        /// The field path.
        field: String,
        /// What the field holds.
        found: String,
    },
    /// A schema (message definition) that cannot be parsed or resolved.
    #[error("schema `{schema}` line {line}: {reason}{}", if text.is_empty() { String::new() } else { format!(" (`{text}`)") })]
    Schema {
        /// The schema's name (`sensor_msgs/msg/Imu`).
        schema: String,
        /// 1-based line in the schema text (0 when the problem has no line).
        line: usize,
        /// The line's text.
        text: String,
        /// What is wrong.
        reason: String,
    },
    /// A topic whose message or schema encoding this crate does not decode.
    #[error(
        "topic `{topic}`: message encoding `{message_encoding}` with schema encoding `{schema_encoding}` is not supported (only `cdr` with `ros2msg`, and `json` with `jsonschema` or no schema)"
    )]
    UnsupportedEncoding {
        /// The topic.
        topic: String,
        /// The channel's message encoding.
        message_encoding: String,
        /// The schema's encoding (empty for none).
        schema_encoding: String,
    },
    /// A message that does not decode with its topic's schema.
    #[error("topic `{topic}`: message logged at {} ({location}) does not decode: {reason}", secs(*log_time as i64))]
    Undecodable {
        /// The topic.
        topic: String,
        /// The message's MCAP log time (ns).
        log_time: u64,
        /// Where the message lies.
        location: Location,
        /// What is wrong.
        reason: String,
    },
    /// A mapped field missing from one message (a JSON key, an index past a sequence's end).
    #[error("mapping `{key}`: topic `{topic}`, message logged at {} ({location}): {reason}", secs(*log_time as i64))]
    MissingField {
        /// The mapping key.
        key: String,
        /// The topic.
        topic: String,
        /// The message's MCAP log time (ns).
        log_time: u64,
        /// Where the message lies.
        location: Location,
        /// What is missing.
        reason: String,
    },
    /// A topic's stamps go backwards.
    #[error("topic `{topic}`: stamp {} after {} ({location}): a topic's messages must not go back in time", secs(*time), secs(*previous))]
    OutOfOrder {
        /// The topic.
        topic: String,
        /// The stamp of the topic's previous message (ns).
        previous: i64,
        /// The stamp of this message (ns).
        time: i64,
        /// Where the message lies.
        location: Location,
    },
    /// A message whose stamp falls in a step already published: it came later in the file than
    /// the reorder window allows.
    #[error(
        "topic `{topic}`: stamp {} ({location}) arrives after the steps up to {} were published, later in the file than the reorder window of {window} s allows",
        secs(*time), secs(*closed)
    )]
    Late {
        /// The topic.
        topic: String,
        /// The message's stamp (ns).
        time: i64,
        /// The end of the last published step's window (ns).
        closed: i64,
        /// The reorder window (s).
        window: f64,
        /// Where the message lies.
        location: Location,
    },
    /// A header stamp of zero (the publisher did not fill it in).
    #[error("topic `{topic}`: header.stamp is zero in the message logged at {} ({location}); read this topic with log times", secs(*log_time as i64))]
    ZeroStamp {
        /// The topic.
        topic: String,
        /// The message's MCAP log time (ns).
        log_time: u64,
        /// Where the message lies.
        location: Location,
    },
    /// Too many messages waiting for their step to close (e.g. a silent driving topic).
    #[error("more than {limit} messages wait for their step to close (the time base's topic `{topic}` is silent?)")]
    Backlog {
        /// The topic whose messages close steps (the driving topic, or the one furthest ahead).
        topic: String,
        /// The limit.
        limit: usize,
    },
    /// An input whose topic had no message: no row can be made.
    #[error("mapping `{key}`: topic `{topic}` has no message, so no step has this input")]
    NeverPublished {
        /// The mapping key.
        key: String,
        /// The topic.
        topic: String,
    },
    /// A mapping or time base that cannot work (no inputs, a bad step, a repeated key, …).
    #[error("{0}")]
    Config(String),
    /// The MCAP writer failed.
    #[error("{}: writing MCAP: {detail}", path.display())]
    Write {
        /// The output file.
        path: PathBuf,
        /// The writer's error.
        detail: String,
    },
}

/// The crate's result.
pub type Result<T, E = Error> = std::result::Result<T, E>;
