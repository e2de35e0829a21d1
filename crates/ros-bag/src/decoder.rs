//! One channel's decoder: the mapped numbers (and the header stamp, when asked for) out of each
//! message, by the channel's encoding and schema.

use serde_json::Value;

use crate::cdr::{DecodeError, Plan, Unresolved};
use crate::container::{ChannelRec, SchemaRec};
use crate::error::{Error, Result};
use crate::json::{self, JsonPlan};
use crate::msgdef;
use crate::path::{self, Segment};

#[derive(Debug, Clone)]
enum Kind {
    Cdr(Box<Plan>),
    Json(JsonPlan),
}

/// Decodes the mapped fields of one channel into slots `0..n`, and the header stamp into the
/// two slots after them.
#[derive(Debug, Clone)]
pub(crate) struct Decoder {
    kind: Kind,
    n: usize,
    header: bool,
}

/// What a channel's encoding and schema are, for decoding or listing fields.
pub(crate) enum Format {
    Cdr(Plan),
    Json(Option<Value>),
}

fn schema_name(schema: Option<&SchemaRec>) -> String {
    schema.map_or_else(String::new, |s| s.name.clone())
}

/// The format of a channel, or the error saying why it cannot be decoded.
pub(crate) fn format(channel: &ChannelRec, schema: Option<&SchemaRec>) -> Result<Format> {
    let unsupported = || Error::UnsupportedEncoding {
        topic: channel.topic.clone(),
        message_encoding: channel.message_encoding.clone(),
        schema_encoding: schema.map_or_else(String::new, |s| s.encoding.clone()),
    };
    let schema_error =
        |reason: String| Error::Schema { schema: schema_name(schema), line: 0, text: String::new(), reason };
    match (channel.message_encoding.as_str(), schema) {
        ("cdr", Some(s)) if s.encoding == "ros2msg" => {
            let text = std::str::from_utf8(&s.data).map_err(|e| schema_error(format!("not UTF-8: {e}")))?;
            let types = msgdef::parse(&s.name, text)?;
            Ok(Format::Cdr(Plan::new(types).map_err(schema_error)?))
        }
        ("json", None) => Ok(Format::Json(None)),
        ("json", Some(s)) if s.encoding.is_empty() => Ok(Format::Json(None)),
        ("json", Some(s)) if s.encoding == "jsonschema" => {
            let v: Value = serde_json::from_slice(&s.data).map_err(|e| schema_error(format!("not JSON: {e}")))?;
            Ok(Format::Json(Some(v)))
        }
        _ => Err(unsupported()),
    }
}

/// The numeric field paths a mapping can use on a channel (compact: `a[0..=8]`, `a[i]`).
pub(crate) fn numeric_fields(format: &Format) -> Vec<String> {
    match format {
        Format::Cdr(plan) => plan.types().numeric_paths(true),
        Format::Json(Some(s)) => json::schema_paths(s),
        Format::Json(None) => Vec::new(),
    }
}

fn stamp_paths() -> [Vec<Segment>; 2] {
    let seg = |n: &str| Segment { name: n.to_owned(), index: None };
    [vec![seg("header"), seg("stamp"), seg("sec")], vec![seg("header"), seg("stamp"), seg("nanosec")]]
}

impl Decoder {
    /// A decoder of `keys` (mapping key, field path) on `channel`; with `want_header`, the
    /// message's `header.stamp` too when its type has one.
    pub(crate) fn new(
        channel: &ChannelRec,
        schema: Option<&SchemaRec>,
        keys: &[(String, String)],
        want_header: bool,
    ) -> Result<Self> {
        let format = format(channel, schema)?;
        let n = keys.len();
        let unresolved = |key: &str, field: &str, u: Unresolved, available: &dyn Fn() -> Vec<String>| match u {
            Unresolved::Unknown(reason) => Error::UnknownField {
                key: key.to_owned(),
                topic: channel.topic.clone(),
                field: field.to_owned(),
                reason,
                available: available(),
            },
            Unresolved::NonNumeric(found) => {
                Error::NonNumeric { key: key.to_owned(), topic: channel.topic.clone(), field: field.to_owned(), found }
            }
        };
        match format {
            Format::Cdr(mut plan) => {
                let types = plan.types().clone();
                let available = || types.numeric_paths(true);
                for (slot, (key, field)) in keys.iter().enumerate() {
                    let segs = path::parse(key, field)?;
                    plan.select(&segs, slot).map_err(|u| unresolved(key, field, u, &available))?;
                }
                let mut header = false;
                if want_header {
                    let [sec, nsec] = stamp_paths();
                    let mut probe = plan.clone();
                    if probe.select(&sec, n).is_ok() && probe.select(&nsec, n + 1).is_ok() {
                        plan = probe;
                        header = true;
                    }
                }
                Ok(Self { kind: Kind::Cdr(Box::new(plan)), n, header })
            }
            Format::Json(schema_value) => {
                let mut plan = JsonPlan::default();
                let described = schema_value.as_ref().filter(|s| json::schema_describes(s));
                for (slot, (key, field)) in keys.iter().enumerate() {
                    let segs = path::parse(key, field)?;
                    if let Some(s) = described {
                        json::check_path(s, &segs).map_err(|u| unresolved(key, field, u, &|| json::schema_paths(s)))?;
                    }
                    plan.select(segs, slot);
                }
                let mut header = false;
                if let (true, Some(s)) = (want_header, described) {
                    let [sec, nsec] = stamp_paths();
                    if json::check_path(s, &sec).is_ok() && json::check_path(s, &nsec).is_ok() {
                        plan.select(sec, n);
                        plan.select(nsec, n + 1);
                        header = true;
                    }
                }
                Ok(Self { kind: Kind::Json(plan), n, header })
            }
        }
    }

    /// Whether messages are stamped from `header.stamp`.
    pub(crate) fn header(&self) -> bool {
        self.header
    }

    /// Decodes a message into `out` (length `n + 2`); returns the header stamp in ns if used.
    pub(crate) fn decode(&self, data: &[u8], out: &mut [f64]) -> Result<Option<i64>, DecodeError> {
        match &self.kind {
            Kind::Cdr(plan) => plan.decode(data, out)?,
            Kind::Json(plan) => plan.decode(data, out)?,
        }
        if !self.header {
            return Ok(None);
        }
        let (sec, nsec) = (out[self.n], out[self.n + 1]);
        if !(sec.is_finite() && nsec.is_finite() && sec.abs() < 1e11 && (0.0..1e10).contains(&nsec)) {
            return Err(DecodeError::Corrupt(format!("header.stamp {sec} s {nsec} ns is not a time")));
        }
        Ok(Some(sec as i64 * 1_000_000_000 + nsec as i64))
    }
}
