//! Reading a model file: the TOML tables checked, names declared, expressions compiled.

use std::borrow::Cow;
use std::collections::HashSet;
use std::ops::Range;

use toml::Spanned;
use toml::de::{DeTable, DeValue};

use crate::error::{EquationError, Location};
use crate::graph::Graph;
use crate::limits::{MAX_FILE_BYTES, MAX_NAMES, MAX_SYMBOLS, MAX_TOTAL_OPERATORS};
use crate::parse::{Meaning, ParseError, is_identifier, is_reserved, parse_into};

/// How time advances in a model.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum TimeModel {
    /// `[f]`: the equations are the discrete map itself.
    Discrete,
    /// `[dxdt]`: the equations are a continuous right-hand side, integrated over `ts`.
    Continuous {
        /// The sampling period (positive, finite).
        ts: f64,
        /// The integration scheme of one step.
        discretization: Discretization,
    },
}

/// The integration scheme of a `[dxdt]` model (one step per sampling period).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Discretization {
    /// Explicit Euler: `x + ts·g(x, u)`.
    Euler,
    /// Classical fourth-order Runge–Kutta, `u` held over the step.
    Rk4,
    /// Exact zero-order hold of linear equations `ẋ = A x + B u`:
    /// `e^{A ts} x + ∫₀^{ts} e^{Aτ} dτ B u` (only for linear `[dxdt]`).
    Zoh,
}

/// One equation: its label (`f.x`), the location of its key and the node of its value.
#[derive(Debug, Clone)]
pub(crate) struct Equation {
    pub label: String,
    pub location: Location,
    pub root: u32,
}

/// A model file read and checked, its expressions compiled into one graph.
#[derive(Debug, Clone)]
pub(crate) struct Spec {
    pub states: Vec<String>,
    pub inputs: Vec<String>,
    pub outputs: Vec<String>,
    pub parameters: Vec<(String, f64)>,
    pub time: TimeModel,
    /// Every definition and equation, compiled.
    pub graph: Graph,
    /// One equation per state, in the order of the states.
    pub rhs: Vec<Equation>,
    /// One equation per output, in the order of the outputs.
    pub out: Vec<Equation>,
    /// Indices of the states and of the outputs declared in `angles` (sorted).
    pub angle_states: Vec<usize>,
    pub angle_outputs: Vec<usize>,
    /// The `discretization` key of `[model]` (the `[model]` table without it): where a zero-order
    /// hold of nonlinear equations is refused.
    pub discretization_at: Location,
}

type Entry<'t, 'i> = (&'t Spanned<Cow<'i, str>>, &'t Spanned<DeValue<'i>>);

struct Ctx<'a> {
    file: &'a str,
    text: &'a str,
}

impl Ctx<'_> {
    fn at(&self, span: &Range<usize>) -> Location {
        Location::of_offset(self.file, self.text, span.start)
    }

    fn format(&self, span: &Range<usize>, message: impl Into<String>) -> EquationError {
        EquationError::Format { location: self.at(span), message: message.into() }
    }
}

fn find<'t, 'i>(table: &'t DeTable<'i>, name: &str) -> Option<Entry<'t, 'i>> {
    table.iter().find(|(k, _)| k.get_ref().as_ref() == name)
}

/// Entries of a table in file order.
fn in_file_order<'t, 'i>(table: &'t DeTable<'i>) -> Vec<Entry<'t, 'i>> {
    let mut entries: Vec<_> = table.iter().collect();
    entries.sort_by_key(|(k, _)| k.span().start);
    entries
}

fn as_table<'t, 'i>(cx: &Ctx<'_>, entry: Entry<'t, 'i>) -> Result<&'t DeTable<'i>, EquationError> {
    entry
        .1
        .get_ref()
        .as_table()
        .ok_or_else(|| cx.format(&entry.0.span(), format!("`{}` must be a table", entry.0.get_ref())))
}

fn number(cx: &Ctx<'_>, key: &str, value: &Spanned<DeValue<'_>>) -> Result<f64, EquationError> {
    let span = value.span();
    let parsed = match value.get_ref() {
        DeValue::Integer(i) => i64::from_str_radix(&i.as_str().replace('_', ""), i.radix()).ok().map(|v| v as f64),
        DeValue::Float(f) => f.as_str().replace('_', "").parse::<f64>().ok(),
        _ => return Err(cx.format(&span, format!("`{key}` must be a number"))),
    };
    match parsed {
        Some(v) if v.is_finite() => Ok(v),
        _ => Err(cx.format(&span, format!("`{key}` must be a finite number"))),
    }
}

/// Declared names: one namespace for states, inputs, outputs, parameters and definitions.
struct Names<'a> {
    cx: &'a Ctx<'a>,
    seen: HashSet<String>,
}

impl Names<'_> {
    fn declare(&mut self, name: &str, span: &Range<usize>) -> Result<(), EquationError> {
        let location = self.cx.at(span);
        if !is_identifier(name) {
            return Err(EquationError::InvalidName {
                location,
                name: name.to_owned(),
                reason: "not an identifier (ASCII letters, digits and `_`, not starting with a digit)".to_owned(),
            });
        }
        if is_reserved(name) {
            return Err(EquationError::InvalidName {
                location,
                name: name.to_owned(),
                reason: "a function or constant of the expression language has that name".to_owned(),
            });
        }
        if !self.seen.insert(name.to_owned()) {
            return Err(EquationError::DuplicateName { location, name: name.to_owned() });
        }
        Ok(())
    }

    fn list(
        &mut self,
        model: &DeTable<'_>,
        key: &str,
        required: bool,
        model_span: &Range<usize>,
    ) -> Result<Vec<String>, EquationError> {
        let cx = self.cx;
        let Some((k, v)) = find(model, key) else {
            return if required {
                Err(cx.format(model_span, format!("[model] needs `{key}`")))
            } else {
                Ok(Vec::new())
            };
        };
        let array =
            v.get_ref().as_array().ok_or_else(|| cx.format(&k.span(), format!("`{key}` must be an array of names")))?;
        if array.len() > MAX_NAMES {
            return Err(EquationError::LimitExceeded {
                location: cx.at(&k.span()),
                what: format!("the number of {key}"),
                size: array.len(),
                limit: MAX_NAMES,
            });
        }
        let mut names = Vec::with_capacity(array.len());
        for item in array.iter() {
            let name =
                item.get_ref().as_str().ok_or_else(|| cx.format(&item.span(), format!("`{key}` must hold strings")))?;
            self.declare(name, &item.span())?;
            names.push(name.to_owned());
        }
        Ok(names)
    }
}

fn parse_error(location: Location, equation: &str, e: ParseError) -> EquationError {
    let equation = equation.to_owned();
    match e {
        ParseError::UnknownSymbol(symbol) => EquationError::UnknownSymbol { location, equation, symbol },
        ParseError::UnknownFunction(function) => EquationError::UnknownFunction { location, equation, function },
        ParseError::Syntax(message) => EquationError::Parse { location, equation, message },
        ParseError::Limit { what, size, limit } => {
            EquationError::LimitExceeded { location, what: format!("equation `{equation}`: {what}"), size, limit }
        }
    }
}

/// Reads and checks a model file's text (`file` names it in errors); the top-level keys in
/// `foreign` belong to another reader and are skipped.
pub(crate) fn read(text: &str, file: &str, foreign: &[&str]) -> Result<Spec, EquationError> {
    if text.len() > MAX_FILE_BYTES {
        return Err(EquationError::FileTooLarge { file: file.to_owned(), size: text.len(), limit: MAX_FILE_BYTES });
    }
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let cx = Ctx { file, text };
    let root = DeTable::parse(text).map_err(|e| EquationError::Toml {
        location: cx.at(&e.span().unwrap_or(0..0)),
        message: e.message().to_owned(),
    })?;
    let root = root.get_ref();
    for (k, _) in root.iter() {
        let key = k.get_ref().as_ref();
        if !["model", "parameters", "definitions", "f", "dxdt", "h"].contains(&key) && !foreign.contains(&key) {
            return Err(cx.format(&k.span(), format!("unknown table `{}`", k.get_ref())));
        }
    }
    let model_entry = find(root, "model").ok_or_else(|| cx.format(&(0..0), "the model file needs a [model] table"))?;
    let model_span = model_entry.0.span();
    let model = as_table(&cx, model_entry)?;
    for (k, _) in model.iter() {
        if !["states", "inputs", "outputs", "ts", "discretization", "angles"].contains(&k.get_ref().as_ref()) {
            return Err(cx.format(&k.span(), format!("unknown key `{}` in [model]", k.get_ref())));
        }
    }
    let mut names = Names { cx: &cx, seen: HashSet::new() };
    let states = names.list(model, "states", true, &model_span)?;
    if states.is_empty() {
        return Err(cx.format(&model_span, "[model] declares no state"));
    }
    let inputs = names.list(model, "inputs", false, &model_span)?;
    let outputs = names.list(model, "outputs", true, &model_span)?;
    let (angle_states, angle_outputs) = angle_list(&cx, model, &states, &outputs)?;

    let mut parameters = Vec::new();
    if let Some(entry) = find(root, "parameters") {
        let table = as_table(&cx, entry)?;
        check_count(&cx, entry, table.len())?;
        for (k, v) in in_file_order(table) {
            names.declare(k.get_ref(), &k.span())?;
            parameters.push((k.get_ref().to_string(), number(&cx, k.get_ref(), v)?));
        }
    }

    let n_slots = states.len() + inputs.len();
    let slot = |name: &str| {
        states
            .iter()
            .position(|s| s == name)
            .or_else(|| inputs.iter().position(|s| s == name).map(|i| states.len() + i))
    };
    let mut graph = Graph::new(n_slots);
    let mut total_operators = 0usize;
    let mut definitions: Vec<(String, u32)> = Vec::new();
    // Parses one expression into the graph, within the per-expression and total limits.
    let mut compile = |graph: &mut Graph,
                       definitions: &[(String, u32)],
                       label: &str,
                       location: &Location,
                       source: &str|
     -> Result<u32, EquationError> {
        let (root, operators) = parse_into(source, graph, |n| {
            if let Some(s) = slot(n) {
                Some(Meaning::Node(s as u32))
            } else if let Some((_, p)) = parameters.iter().find(|(p, _)| p == n) {
                Some(Meaning::Value(*p))
            } else {
                definitions.iter().find(|(d, _)| d == n).map(|(_, node)| Meaning::Node(*node))
            }
        })
        .map_err(|e| parse_error(location.clone(), label, e))?;
        total_operators += operators;
        if total_operators > MAX_TOTAL_OPERATORS {
            return Err(EquationError::LimitExceeded {
                location: location.clone(),
                what: "the number of operators of all definitions and equations together".to_owned(),
                size: total_operators,
                limit: MAX_TOTAL_OPERATORS,
            });
        }
        Ok(root)
    };
    if let Some(entry) = find(root, "definitions") {
        let table = as_table(&cx, entry)?;
        check_count(&cx, entry, table.len())?;
        for (k, v) in in_file_order(table) {
            names.declare(k.get_ref(), &k.span())?;
            let label = format!("definitions.{}", k.get_ref());
            let source =
                v.get_ref().as_str().ok_or_else(|| cx.format(&k.span(), format!("`{label}` must be a string")))?;
            let node = compile(&mut graph, &definitions, &label, &cx.at(&k.span()), source)?;
            definitions.push((k.get_ref().to_string(), node));
        }
    }
    let mut expand_equation = |section: &str, k: &Spanned<Cow<'_, str>>, v: &Spanned<DeValue<'_>>| {
        let label = format!("{section}.{}", k.get_ref());
        let location = cx.at(&k.span());
        let source = v.get_ref().as_str().ok_or_else(|| cx.format(&k.span(), format!("`{label}` must be a string")))?;
        let root = compile(&mut graph, &definitions, &label, &location, source)?;
        Ok::<_, EquationError>(Equation { label, location, root })
    };
    let mut section_equations = |section: &str, entry: Entry<'_, '_>, targets: &[String], expected: &str| {
        let table = as_table(&cx, entry)?;
        let mut equations: Vec<Option<Equation>> = vec![None; targets.len()];
        for (k, v) in in_file_order(table) {
            let Some(i) = targets.iter().position(|t| t == k.get_ref().as_ref()) else {
                return Err(EquationError::UnknownTarget {
                    location: cx.at(&k.span()),
                    section: section.to_owned(),
                    name: k.get_ref().to_string(),
                    expected: expected.to_owned(),
                });
            };
            equations[i] = Some(expand_equation(section, k, v)?);
        }
        equations
            .into_iter()
            .zip(targets)
            .map(|(e, name)| {
                e.ok_or_else(|| EquationError::MissingEquation {
                    location: cx.at(&entry.0.span()),
                    section: section.to_owned(),
                    name: name.clone(),
                })
            })
            .collect::<Result<Vec<_>, _>>()
    };

    let (section, entry) = match (find(root, "f"), find(root, "dxdt")) {
        (Some(f), None) => ("f", f),
        (None, Some(d)) => ("dxdt", d),
        (Some(_), Some(d)) => {
            return Err(cx.format(&d.0.span(), "give either [f] (discrete) or [dxdt] (continuous), not both"));
        }
        (None, None) => {
            return Err(cx.format(&model_span, "the model needs [f] (discrete) or [dxdt] (continuous) equations"));
        }
    };
    let rhs = section_equations(section, entry, &states, "state")?;
    let time = time_model(&cx, model, &model_span, section == "dxdt")?;
    let out = match find(root, "h") {
        Some(entry) => section_equations("h", entry, &outputs, "output")?,
        None if outputs.is_empty() => Vec::new(),
        None => {
            return Err(EquationError::MissingEquation {
                location: cx.at(&model_span),
                section: "h".to_owned(),
                name: outputs[0].clone(),
            });
        }
    };
    let discretization_at = cx.at(&find(model, "discretization").map_or(model_span.clone(), |(k, _)| k.span()));
    Ok(Spec {
        states,
        inputs,
        outputs,
        parameters,
        time,
        graph,
        rhs,
        out,
        angle_states,
        angle_outputs,
        discretization_at,
    })
}

/// `angles = ["psi", "bearing_1"]` in `[model]`: names of states and outputs that are angles in
/// radians, as sorted indices `(states, outputs)`. Each name must be a state or an output, once.
fn angle_list(
    cx: &Ctx<'_>,
    model: &DeTable<'_>,
    states: &[String],
    outputs: &[String],
) -> Result<(Vec<usize>, Vec<usize>), EquationError> {
    let Some((k, v)) = find(model, "angles") else {
        return Ok((Vec::new(), Vec::new()));
    };
    let array = v
        .get_ref()
        .as_array()
        .ok_or_else(|| cx.format(&k.span(), "`angles` must be an array of state and output names"))?;
    let (mut on_states, mut on_outputs) = (Vec::new(), Vec::new());
    for item in array.iter() {
        let name = item.get_ref().as_str().ok_or_else(|| cx.format(&item.span(), "`angles` must hold strings"))?;
        let (list, index) = if let Some(i) = states.iter().position(|s| s == name) {
            (&mut on_states, i)
        } else if let Some(i) = outputs.iter().position(|s| s == name) {
            (&mut on_outputs, i)
        } else {
            return Err(cx.format(&item.span(), format!("`{name}` in `angles` is neither a state nor an output")));
        };
        if list.contains(&index) {
            return Err(cx.format(&item.span(), format!("`{name}` appears twice in `angles`")));
        }
        list.push(index);
    }
    on_states.sort_unstable();
    on_outputs.sort_unstable();
    Ok((on_states, on_outputs))
}

fn check_count(cx: &Ctx<'_>, entry: Entry<'_, '_>, count: usize) -> Result<(), EquationError> {
    if count > MAX_SYMBOLS {
        return Err(EquationError::LimitExceeded {
            location: cx.at(&entry.0.span()),
            what: format!("the number of entries of [{}]", entry.0.get_ref()),
            size: count,
            limit: MAX_SYMBOLS,
        });
    }
    Ok(())
}

fn time_model(
    cx: &Ctx<'_>,
    model: &DeTable<'_>,
    model_span: &Range<usize>,
    continuous: bool,
) -> Result<TimeModel, EquationError> {
    let ts = find(model, "ts");
    let disc = find(model, "discretization");
    if !continuous {
        if let Some((k, _)) = disc {
            return Err(cx.format(&k.span(), "`discretization` applies only to [dxdt] models"));
        }
        return Ok(TimeModel::Discrete);
    }
    let Some((k, v)) = ts else {
        return Err(EquationError::SamplingPeriod {
            location: cx.at(model_span),
            message: "a [dxdt] model needs the sampling period `ts` in [model]".to_owned(),
        });
    };
    let value = number(cx, "ts", v).map_err(|_| EquationError::SamplingPeriod {
        location: cx.at(&k.span()),
        message: "`ts` must be a finite number".to_owned(),
    })?;
    if value <= 0.0 {
        return Err(EquationError::SamplingPeriod {
            location: cx.at(&k.span()),
            message: format!("`ts` must be positive, got {value}"),
        });
    }
    let discretization = match disc {
        None => Discretization::Rk4,
        Some((k, v)) => match v.get_ref().as_str() {
            Some("euler") => Discretization::Euler,
            Some("rk4") => Discretization::Rk4,
            Some("zoh") => Discretization::Zoh,
            _ => return Err(cx.format(&k.span(), "`discretization` must be \"euler\", \"rk4\" or \"zoh\"")),
        },
    };
    Ok(TimeModel::Continuous { ts: value, discretization })
}
