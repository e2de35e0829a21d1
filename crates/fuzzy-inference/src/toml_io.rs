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
//! offending `[[inputs]]` entry, `[output]` table or `[[rules]]` entry for invalid content.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Deserialize;
use toml::Spanned;

use crate::{
    Antecedent, Defuzzifier, FuzzyError, FuzzySystem, InputVariable, LoadError, Location, MembershipFunction,
    OutputScale, OutputVariable, Rule,
};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileSystem {
    default_output: f64,
    #[serde(default)]
    defuzzifier: Option<FileDefuzzifier>,
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

impl FuzzySystem {
    /// Loads a system from TOML text (layout in the crate's `systems/bds_ins.toml`); `origin` names the
    /// source in error locations.
    ///
    /// # Errors
    /// [`LoadError::Syntax`] for invalid TOML or layout, [`LoadError::Invalid`] for an invalid system
    /// (the [`FuzzyError`] of [`FuzzySystem::new`]), both with `file:line:column`.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<FuzzySystem, LoadError> {
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

        let mut inputs = Vec::with_capacity(parsed.inputs.len());
        for input in parsed.inputs {
            let start = input.span().start;
            let input = input.into_inner();
            let var =
                InputVariable { name: input.name, range: input.range, sets: convert_sets(origin, text, input.sets)? };
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
                    antecedents: r
                        .antecedents
                        .into_iter()
                        .map(|(variable, set)| Antecedent { variable, set })
                        .collect(),
                    consequent: r.then,
                }
            })
            .collect();
        let rule_location = |e: &FuzzyError| match *e {
            FuzzyError::EmptyRule { rule }
            | FuzzyError::UnknownVariable { rule, .. }
            | FuzzyError::UnknownSet { rule, .. }
            | FuzzyError::DuplicateAntecedent { rule, .. } => rule_starts.get(rule).copied(),
            _ => None,
        };
        let system = FuzzySystem::new(inputs, output, rules, parsed.default_output).map_err(|e| {
            let at = rule_location(&e);
            invalid(at, e)
        })?;
        let defuzzifier = match parsed.defuzzifier {
            None | Some(FileDefuzzifier::Exact) => Defuzzifier::Exact,
            Some(FileDefuzzifier::Sampled(points)) => Defuzzifier::Sampled { points },
            Some(FileDefuzzifier::Grid(points_per_axis)) => Defuzzifier::Grid { points_per_axis },
        };
        system.with_defuzzifier(defuzzifier).map_err(|e| invalid(None, e))
    }

    /// Loads a system from a TOML file (see [`FuzzySystem::from_toml_str`]).
    ///
    /// # Errors
    /// [`LoadError::Io`] if the file cannot be read, otherwise as [`FuzzySystem::from_toml_str`].
    pub fn from_toml_file(path: impl AsRef<Path>) -> Result<FuzzySystem, LoadError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path)
            .map_err(|source| LoadError::Io { path: path.display().to_string(), source })?;
        Self::from_toml_str(&text, &path.display().to_string())
    }
}
