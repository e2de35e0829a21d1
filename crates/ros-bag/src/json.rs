//! JSON messages (message encoding `json`), with a `jsonschema` schema or none. Each message is
//! parsed with `serde_json` and the mapped paths looked up in it.

use serde_json::Value;

use crate::cdr::{DecodeError, Unresolved};
use crate::path::Segment;

/// The mapped paths of one JSON topic.
#[derive(Debug, Clone, Default)]
pub(crate) struct JsonPlan {
    paths: Vec<(Vec<Segment>, usize)>,
}

fn type_names(schema: &Value) -> Vec<&str> {
    match schema.get("type") {
        Some(Value::String(s)) => vec![s.as_str()],
        Some(Value::Array(a)) => a.iter().filter_map(Value::as_str).collect(),
        _ => Vec::new(),
    }
}

fn is_numeric(schema: &Value) -> bool {
    type_names(schema).iter().any(|t| matches!(*t, "number" | "integer" | "boolean"))
}

/// Whether a schema says anything about its fields (an empty schema checks nothing).
pub(crate) fn schema_describes(schema: &Value) -> bool {
    schema.get("properties").is_some_and(Value::is_object)
}

/// The numeric field paths a JSON schema declares (arrays as `a[i]`).
pub(crate) fn schema_paths(schema: &Value) -> Vec<String> {
    fn collect(s: &Value, prefix: &str, out: &mut Vec<String>, depth: usize) {
        if depth > 64 || out.len() > 4096 {
            return;
        }
        if let Some(Value::Object(props)) = s.get("properties") {
            for (name, sub) in props {
                let p = format!("{prefix}{name}");
                if is_numeric(sub) {
                    out.push(p.clone());
                }
                if type_names(sub).contains(&"array") {
                    if let Some(items) = sub.get("items") {
                        if is_numeric(items) {
                            out.push(format!("{p}[i]"));
                        }
                        collect(items, &format!("{p}[i]."), out, depth + 1);
                    }
                } else {
                    collect(sub, &format!("{p}."), out, depth + 1);
                }
            }
        }
    }
    let mut out = Vec::new();
    collect(schema, "", &mut out, 0);
    out
}

/// Checks `path` against a schema that describes its fields.
pub(crate) fn check_path(schema: &Value, path: &[Segment]) -> Result<(), Unresolved> {
    let mut s = schema;
    for seg in path {
        let Some(sub) = s.get("properties").and_then(|p| p.get(&seg.name)) else {
            return Err(Unresolved::Unknown(format!("its JSON schema has no field `{}`", seg.name)));
        };
        s = sub;
        if seg.index.is_some() {
            match s.get("items") {
                Some(items) if type_names(s).contains(&"array") => s = items,
                _ => return Err(Unresolved::Unknown(format!("`{}` is not an array", seg.name))),
            }
        }
    }
    if is_numeric(s) {
        Ok(())
    } else if type_names(s).contains(&"string") {
        Err(Unresolved::NonNumeric("string".into()))
    } else {
        Err(Unresolved::Unknown("not a number in the schema".into()))
    }
}

impl JsonPlan {
    pub(crate) fn select(&mut self, path: Vec<Segment>, slot: usize) {
        self.paths.push((path, slot));
    }

    pub(crate) fn decode(&self, data: &[u8], out: &mut [f64]) -> Result<(), DecodeError> {
        let v: Value = serde_json::from_slice(data).map_err(|e| DecodeError::Corrupt(format!("not JSON: {e}")))?;
        for (path, slot) in &self.paths {
            let mut at = &v;
            for seg in path {
                let next = at.get(&seg.name).and_then(|x| match seg.index {
                    None => Some(x),
                    Some(i) => x.get(i),
                });
                let Some(next) = next else {
                    let what = match seg.index {
                        None => format!("no field `{}`", seg.name),
                        Some(i) => format!("no element `{}[{i}]`", seg.name),
                    };
                    return Err(DecodeError::Missing { slot: *slot, reason: format!("the message has {what}") });
                };
                at = next;
            }
            out[*slot] = match at {
                Value::Number(n) => n.as_f64().unwrap_or(f64::NAN),
                Value::Bool(b) => f64::from(u8::from(*b)),
                Value::Null => f64::NAN,
                Value::String(_) => return Err(DecodeError::NonNumeric { slot: *slot, found: "string".into() }),
                Value::Array(_) => return Err(DecodeError::NonNumeric { slot: *slot, found: "array".into() }),
                Value::Object(_) => return Err(DecodeError::NonNumeric { slot: *slot, found: "object".into() }),
            };
        }
        Ok(())
    }
}
