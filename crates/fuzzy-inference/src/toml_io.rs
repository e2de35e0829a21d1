//! Loading a system from TOML.
//!
//! ```toml
//! default_output = 25.0          # crisp output when no rule fires
//! defuzzifier = "exact"          # optional: "exact" (default), { sampled = 1000 }, { grid = 33 }
//!
//! [[inputs]]
//! name = "N"
//! range = [0.0, 100.0]
//! sets = [
//!     { name = "Z", trapezoid = [0.0, 0.0, 3.0, 5.0] },
//!     { name = "PB", trapezoid = [14.0, 18.0, inf, inf] },
//! ]
//!
//! [output]
//! name = "log10_t"
//! universe = [-0.7, 2.1]
//! scale = "log10"                # optional: "linear" (default) or "log10"
//! sets = [{ name = "Z", triangle = [-0.7, 0.0, 0.7] }]
//!
//! [[rules]]
//! if = { N = "PB" }
//! then = "Z"
//! ```
//!
//! Errors carry `file:line:column`: of the TOML parser's span for syntax and layout errors, of the
//! offending `[[inputs]]` entry, `[output]` table, `[[rules]]` entry, `default_output` or
//! `defuzzifier` value for invalid content. A consumer that feeds fixed quantities loads with
//! [`FuzzySystem::from_toml_str_for`]: inputs are then matched to its quantities by name.

use std::collections::BTreeMap;
use std::io::Read as _;
use std::path::Path;

use serde::Deserialize;
use toml::Spanned;

use crate::{
    Antecedent, Defuzzifier, FuzzyError, FuzzySystem, InputVariable, Interface, LoadError, Location,
    MembershipFunction, OutputScale, OutputVariable, Rule,
};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileSystem {
    default_output: Spanned<f64>,
    #[serde(default)]
    defuzzifier: Option<Spanned<FileDefuzzifier>>,
    inputs: Vec<Spanned<FileInput>>,
    output: Spanned<FileOutput>,
    rules: Vec<Spanned<FileRule>>,
}

#[derive(Deserialize)]
#[serde(rename_all = "lowercase")]
enum FileDefuzzifier {
    Exact,
    Sampled(usize),
    Grid(usize),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileSet {
    name: String,
    #[serde(default)]
    triangle: Option<[f64; 3]>,
    #[serde(default)]
    trapezoid: Option<[f64; 4]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileInput {
    name: String,
    range: (f64, f64),
    sets: Vec<Spanned<FileSet>>,
}

#[derive(Deserialize, Default)]
#[serde(rename_all = "lowercase")]
enum FileScale {
    #[default]
    Linear,
    Log10,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileOutput {
    name: String,
    universe: (f64, f64),
    #[serde(default)]
    scale: FileScale,
    sets: Vec<Spanned<FileSet>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileRule {
    #[serde(rename = "if")]
    antecedents: BTreeMap<String, String>,
    then: String,
}

fn convert_sets(
    file: &str,
    text: &str,
    sets: Vec<Spanned<FileSet>>,
) -> Result<Vec<(String, MembershipFunction)>, LoadError> {
    sets.into_iter()
        .map(|s| {
            let at = Location::at(file, text, s.span().start);
            let s = s.into_inner();
            let mf = match (s.triangle, s.trapezoid) {
                (Some([a, b, c]), None) => MembershipFunction::triangle(a, b, c),
                (None, Some([a, b, c, d])) => MembershipFunction::trapezoid(a, b, c, d),
                _ => {
                    return Err(LoadError::Syntax {
                        location: at,
                        message: format!("set `{}`: give exactly one of `triangle` or `trapezoid`", s.name),
                    });
                }
            };
            Ok((s.name, mf))
        })
        .collect()
}

/// The largest system file [`FuzzySystem::from_toml_file`] reads (it is read whole): 16 MiB, far
/// above a system of [`crate::MAX_RULES`] rules (about 60 bytes a rule).
pub const MAX_FILE_BYTES: u64 = 16 << 20;

impl FuzzySystem {
    /// Loads a system from TOML text (layout in the crate's `systems/bds_ins.toml`); `origin` names the
    /// source in error locations.
    ///
    /// # Errors
    /// [`LoadError::Syntax`] for invalid TOML or layout, [`LoadError::Invalid`] for an invalid system
    /// (the [`FuzzyError`] of [`FuzzySystem::new`], more than [`crate::MAX_RULES`] rules, a
    /// defuzzifier beyond its limits), both with `file:line:column`.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<FuzzySystem, LoadError> {
        load(text, origin, None)
    }

    /// Loads a system for a consumer that feeds it the quantities of `interface`: as
    /// [`FuzzySystem::from_toml_str`], then [`FuzzySystem::bind`] (the inputs found by name and put
    /// in the interface's order, whatever the order of the file's `[[inputs]]` blocks).
    ///
    /// # Errors
    /// As [`FuzzySystem::from_toml_str`]; an input that names no quantity (or the second one naming
    /// the same) at its `[[inputs]]` block, a quantity without an input at the first block, outputs
    /// the interface cannot use at `[output]`.
    pub fn from_toml_str_for(text: &str, origin: &str, interface: &Interface) -> Result<FuzzySystem, LoadError> {
        load(text, origin, Some(interface))
    }

    /// Loads a system from a TOML file (see [`FuzzySystem::from_toml_str`]).
    ///
    /// # Errors
    /// [`LoadError::Io`] if the file cannot be read, [`LoadError::TooLarge`] beyond
    /// [`MAX_FILE_BYTES`], otherwise as [`FuzzySystem::from_toml_str`].
    pub fn from_toml_file(path: impl AsRef<Path>) -> Result<FuzzySystem, LoadError> {
        let path = path.as_ref();
        load(&read_capped(path)?, &path.display().to_string(), None)
    }

    /// Loads a system from a TOML file for `interface` (see [`FuzzySystem::from_toml_str_for`]).
    ///
    /// # Errors
    /// As [`FuzzySystem::from_toml_file`] and [`FuzzySystem::from_toml_str_for`].
    pub fn from_toml_file_for(path: impl AsRef<Path>, interface: &Interface) -> Result<FuzzySystem, LoadError> {
        let path = path.as_ref();
        load(&read_capped(path)?, &path.display().to_string(), Some(interface))
    }
}

/// The text of `path`, at most [`MAX_FILE_BYTES`] of it (an endless file such as `/dev/zero` is
/// refused after reading that much).
fn read_capped(path: &Path) -> Result<String, LoadError> {
    let io = |source| LoadError::Io { path: path.display().to_string(), source };
    let file = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::new();
    file.take(MAX_FILE_BYTES + 1).read_to_end(&mut bytes).map_err(io)?;
    if bytes.len() as u64 > MAX_FILE_BYTES {
        return Err(LoadError::TooLarge { path: path.display().to_string(), limit: MAX_FILE_BYTES });
    }
    String::from_utf8(bytes).map_err(|e| {
        let good = e.utf8_error().valid_up_to();
        let prefix = String::from_utf8_lossy(&e.as_bytes()[..good]).into_owned();
        LoadError::Syntax {
            location: Location::at(&path.display().to_string(), &prefix, prefix.len()),
            message: "not valid UTF-8 (a fuzzy-system file is UTF-8 TOML)".into(),
        }
    })
}

fn load(text: &str, origin: &str, interface: Option<&Interface>) -> Result<FuzzySystem, LoadError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let parsed: FileSystem = toml::from_str(text).map_err(|e| LoadError::Syntax {
        location: match e.span() {
            Some(span) => Location::at(origin, text, span.start),
            None => Location { file: origin.to_owned(), line_column: None },
        },
        message: e.message().trim_end().to_owned(),
    })?;
    let invalid = |offset: Option<usize>, source: FuzzyError| LoadError::Invalid {
        location: match offset {
            Some(o) => Location::at(origin, text, o),
            None => Location { file: origin.to_owned(), line_column: None },
        },
        source,
    };

    if parsed.rules.len() > crate::MAX_RULES {
        let first_beyond = parsed.rules.get(crate::MAX_RULES).map(|r| r.span().start);
        return Err(invalid(
            first_beyond,
            FuzzyError::TooManyRules { count: parsed.rules.len(), limit: crate::MAX_RULES },
        ));
    }
    let input_starts: Vec<usize> = parsed.inputs.iter().map(|i| i.span().start).collect();
    let mut inputs = Vec::with_capacity(parsed.inputs.len());
    for input in parsed.inputs {
        let start = input.span().start;
        let input = input.into_inner();
        let var = InputVariable { name: input.name, range: input.range, sets: convert_sets(origin, text, input.sets)? };
        var.validate().map_err(|e| invalid(Some(start), e))?;
        inputs.push(var);
    }
    let output_start = parsed.output.span().start;
    let output = parsed.output.into_inner();
    let output = OutputVariable {
        name: output.name,
        universe: output.universe,
        scale: match output.scale {
            FileScale::Linear => OutputScale::Linear,
            FileScale::Log10 => OutputScale::Log10,
        },
        sets: convert_sets(origin, text, output.sets)?,
    };
    output.validate().map_err(|e| invalid(Some(output_start), e))?;
    let rule_starts: Vec<usize> = parsed.rules.iter().map(|r| r.span().start).collect();
    let rules = parsed
        .rules
        .into_iter()
        .map(|r| {
            let r = r.into_inner();
            Rule {
                antecedents: r.antecedents.into_iter().map(|(variable, set)| Antecedent { variable, set }).collect(),
                consequent: r.then,
            }
        })
        .collect();
    let default_start = parsed.default_output.span().start;
    let located = |e: &FuzzyError| match *e {
        FuzzyError::EmptyRule { rule }
        | FuzzyError::UnknownVariable { rule, .. }
        | FuzzyError::UnknownSet { rule, .. }
        | FuzzyError::DuplicateAntecedent { rule, .. } => rule_starts.get(rule).copied(),
        FuzzyError::InvalidDefault { .. } | FuzzyError::DefaultOutsideUniverse { .. } => Some(default_start),
        FuzzyError::DuplicateName { .. } | FuzzyError::TooManySets { .. } | FuzzyError::NoInputs => {
            input_starts.first().copied()
        }
        _ => None,
    };
    let system = FuzzySystem::new(inputs, output, rules, *parsed.default_output.get_ref()).map_err(|e| {
        let at = located(&e);
        invalid(at, e)
    })?;
    let (defuzzifier, defuzzifier_start) = match parsed.defuzzifier {
        None => (Defuzzifier::Exact, None),
        Some(d) => {
            let start = d.span().start;
            let d = match d.into_inner() {
                FileDefuzzifier::Exact => Defuzzifier::Exact,
                FileDefuzzifier::Sampled(points) => Defuzzifier::Sampled { points },
                FileDefuzzifier::Grid(points_per_axis) => Defuzzifier::Grid { points_per_axis },
            };
            (d, Some(start))
        }
    };
    let system = system.with_defuzzifier(defuzzifier).map_err(|e| invalid(defuzzifier_start, e))?;
    match interface {
        None => Ok(system),
        Some(interface) => system.bind_located(interface).map_err(|e| {
            let at = match (&e.error, e.input) {
                (_, Some(i)) => input_starts.get(i).copied(),
                (FuzzyError::OutputRange { .. }, None) => Some(output_start),
                _ => input_starts.first().copied(),
            };
            invalid(at, e.error)
        }),
    }
}
