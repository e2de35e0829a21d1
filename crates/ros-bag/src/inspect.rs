//! What a bag holds: per topic its type, encoding, message count, rate, first and last time and
//! the numeric field paths a mapping can use.

use std::collections::BTreeMap;
use std::fmt;

use crate::bag::Bag;
use crate::container::Item;
use crate::decoder;
use crate::error::{Error, secs};

/// One topic of a bag.
#[derive(Debug, Clone, PartialEq)]
pub struct TopicInfo {
    /// The topic.
    pub topic: String,
    /// The message type (the schema's name, `sensor_msgs/msg/Imu`); empty without a schema.
    pub message_type: String,
    /// The message encoding (`cdr`, `json`).
    pub message_encoding: String,
    /// The schema encoding (`ros2msg`, `jsonschema`); empty without a schema.
    pub schema_encoding: String,
    /// Messages read.
    pub count: u64,
    /// Log time of the first message (ns).
    pub first_ns: Option<u64>,
    /// Log time of the last message (ns).
    pub last_ns: Option<u64>,
    /// The numeric field paths (`a[0..=8]` for a fixed array, `a[i]` for a sequence); empty when
    /// the topic cannot be decoded (see `fields_error`).
    pub numeric_fields: Vec<String>,
    /// Why the fields cannot be listed (an unsupported encoding, a bad schema).
    pub fields_error: Option<String>,
}

impl TopicInfo {
    /// Mean rate (Hz) over the log times: `(count − 1) / (last − first)`.
    pub fn rate_hz(&self) -> Option<f64> {
        let (a, b) = (self.first_ns?, self.last_ns?);
        (self.count > 1 && b > a).then(|| (self.count - 1) as f64 / ((b - a) as f64 / 1e9))
    }
}

/// A bag's topics ([`Bag::inspect`]); [`fmt::Display`] prints a plain table.
#[derive(Debug)]
pub struct Inspection {
    /// The topics, sorted by name.
    pub topics: Vec<TopicInfo>,
    /// The damage that stopped the count early (the counts are those before it).
    pub error: Option<Error>,
}

impl Bag {
    /// Counts every message of the data section (by log time) and lists each topic's fields.
    /// A damaged file gives the counts up to the damage and the error in
    /// [`Inspection::error`].
    pub fn inspect(&self) -> Inspection {
        let mut channels = self.channels.clone();
        let mut schemas = self.schemas.clone();
        let mut stats: BTreeMap<u16, (u64, u64, u64)> = BTreeMap::new();
        let mut error = None;
        for it in self.walker() {
            match it {
                Ok(Item::Message(m)) => {
                    let e = stats.entry(m.channel_id).or_insert((0, m.log_time, m.log_time));
                    e.0 += 1;
                    e.1 = e.1.min(m.log_time);
                    e.2 = e.2.max(m.log_time);
                }
                Ok(Item::Channel(c)) => {
                    channels.entry(c.id).or_insert(c);
                }
                Ok(Item::Schema(s)) => {
                    schemas.entry(s.id).or_insert(s);
                }
                Err(e) => {
                    error = Some(e);
                    break;
                }
            }
        }
        let mut by_topic: BTreeMap<String, TopicInfo> = BTreeMap::new();
        for c in channels.values() {
            let schema = if c.schema_id == 0 { None } else { schemas.get(&c.schema_id) };
            let (count, first, last) = match stats.get(&c.id) {
                Some(&(n, a, b)) => (n, Some(a), Some(b)),
                None => (0, None, None),
            };
            let info = by_topic.entry(c.topic.clone()).or_insert_with(|| {
                let (numeric_fields, fields_error) = match decoder::format(c, schema) {
                    Ok(f) => (decoder::numeric_fields(&f), None),
                    Err(e) => (Vec::new(), Some(e.to_string())),
                };
                TopicInfo {
                    topic: c.topic.clone(),
                    message_type: schema.map_or_else(String::new, |s| s.name.clone()),
                    message_encoding: c.message_encoding.clone(),
                    schema_encoding: schema.map_or_else(String::new, |s| s.encoding.clone()),
                    count: 0,
                    first_ns: None,
                    last_ns: None,
                    numeric_fields,
                    fields_error,
                }
            });
            info.count += count;
            info.first_ns = match (info.first_ns, first) {
                (Some(x), Some(y)) => Some(x.min(y)),
                (x, y) => x.or(y),
            };
            info.last_ns = match (info.last_ns, last) {
                (Some(x), Some(y)) => Some(x.max(y)),
                (x, y) => x.or(y),
            };
        }
        Inspection { topics: by_topic.into_values().collect(), error }
    }
}

impl fmt::Display for Inspection {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let header = ["topic", "type", "encoding", "messages", "rate (Hz)", "first (s)", "last (s)"];
        let time =
            |t: Option<u64>| t.map_or_else(|| "-".to_owned(), |t| secs(t as i64).trim_end_matches(" s").to_owned());
        let rows: Vec<[String; 7]> = self
            .topics
            .iter()
            .map(|t| {
                [
                    t.topic.clone(),
                    t.message_type.clone(),
                    format!(
                        "{}/{}",
                        t.message_encoding,
                        if t.schema_encoding.is_empty() { "-" } else { &t.schema_encoding }
                    ),
                    t.count.to_string(),
                    t.rate_hz().map_or_else(|| "-".to_owned(), |r| format!("{r:.2}")),
                    time(t.first_ns),
                    time(t.last_ns),
                ]
            })
            .collect();
        let mut width = header.map(str::len);
        for r in &rows {
            for (w, c) in width.iter_mut().zip(r) {
                *w = (*w).max(c.chars().count());
            }
        }
        let line = |f: &mut fmt::Formatter<'_>, cells: &[&str]| -> fmt::Result {
            let mut s = String::new();
            for (i, (c, w)) in cells.iter().zip(width).enumerate() {
                if i > 0 {
                    s.push_str("  ");
                }
                // Numbers right-aligned, text left-aligned.
                if (3..7).contains(&i) { s.push_str(&format!("{c:>w$}")) } else { s.push_str(&format!("{c:<w$}")) }
            }
            writeln!(f, "{}", s.trim_end())
        };
        line(f, &header)?;
        for (r, t) in rows.iter().zip(&self.topics) {
            line(f, &r.each_ref().map(String::as_str))?;
            match &t.fields_error {
                Some(e) => writeln!(f, "    fields: cannot be read: {e}")?,
                None if t.numeric_fields.is_empty() => writeln!(f, "    fields: (none listed)")?,
                None => writeln!(f, "    fields: {}", t.numeric_fields.join(", "))?,
            }
        }
        if let Some(e) = &self.error {
            writeln!(f, "stopped early: {e}")?;
        }
        Ok(())
    }
}
