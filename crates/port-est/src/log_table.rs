//! The model file's `[log]` table as written: how each input and output of the model is read from
//! a topic's field of a ROS 2 bag (module [`crate::bag`] runs the estimators over it), turned into
//! `ros_bag`'s `LogSpec` with every mistake at its key's span.

use std::collections::BTreeMap;

use serde::Deserialize;
use toml::Spanned;

/// The `[log]` table as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct LogTable {
    ts: Option<Spanned<f64>>,
    driving: Option<Spanned<String>>,
    stamps: Option<Spanned<String>>,
    reorder_window: Option<Spanned<f64>>,
    fields: Option<Spanned<BTreeMap<String, Spanned<FieldSource>>>>,
}

/// One mapping: a topic and a field path in its messages.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct FieldSource {
    topic: String,
    field: String,
}

type Span = std::ops::Range<usize>;

impl LogTable {
    /// The reading of a bag this table asks for, for a model with these input and output names;
    /// an error at the span of the key it is about (`whole`: the table's).
    pub(crate) fn spec(
        &self,
        whole: Span,
        inputs: &[String],
        outputs: &[String],
    ) -> Result<ros_bag::LogSpec, (Span, String)> {
        let mut spec = match (&self.ts, &self.driving) {
            (Some(ts), None) => {
                let v = *ts.get_ref();
                if !(v.is_finite() && v > 0.0) {
                    return Err((ts.span(), format!("`ts` = {v}: the step must be a positive number of seconds")));
                }
                ros_bag::LogSpec::fixed_step(v)
            }
            (None, Some(topic)) => ros_bag::LogSpec::per_message(topic.get_ref().clone()),
            _ => {
                return Err((
                    whole,
                    "[log]: give one of `ts` (a fixed step, seconds) or `driving` (a topic: one step per message)"
                        .into(),
                ));
            }
        };
        if let Some(s) = &self.stamps {
            spec = spec.stamps(match s.get_ref().as_str() {
                "log" => ros_bag::Stamps::LogTime,
                "header" => ros_bag::Stamps::Header,
                other => {
                    return Err((s.span(), format!("`stamps` = {other:?}: \"log\" (the log time) or \"header\"")));
                }
            });
        }
        if let Some(w) = &self.reorder_window {
            let v = *w.get_ref();
            if !(v.is_finite() && v >= 0.0) {
                return Err((w.span(), format!("`reorder_window` = {v}: a number of seconds, at least 0")));
            }
            spec = spec.reorder_window(v);
        }
        let Some(fields) = &self.fields else {
            return Err((
                whole,
                "[log]: a table `[log.fields]` maps each input and output to `{ topic, field }`".into(),
            ));
        };
        let known: Vec<&str> = inputs.iter().chain(outputs).map(String::as_str).collect();
        for (name, source) in fields.get_ref() {
            if !known.contains(&name.as_str()) {
                let message = format!(
                    "[log.fields]: `{name}` is not an input or output of the model (they are: {})",
                    known.join(", ")
                );
                return Err((source.span(), message));
            }
        }
        let find = |name: &String| {
            fields.get_ref().get(name).map(Spanned::get_ref).ok_or_else(|| {
                let message = format!("[log.fields]: no topic for `{name}` (every input and output is mapped)");
                (fields.span(), message)
            })
        };
        for name in inputs {
            let f = find(name)?;
            spec = spec.input(name.clone(), f.topic.clone(), f.field.clone());
        }
        for name in outputs {
            let f = find(name)?;
            spec = spec.output(name.clone(), f.topic.clone(), f.field.clone());
        }
        Ok(spec)
    }
}
