//! The system as data, its validation, and Mamdani evaluation.

use crate::defuzz::{self, CentroidGrid, MAX_OUTPUT_SETS};
use crate::{FuzzyError, MembershipFunction};

/// The most fuzzy sets of all input variables together (stack scratch of the allocation-free
/// evaluation).
pub const MAX_INPUT_SETS: usize = 256;

/// The most rules a system may have: an evaluation visits every rule, so this bounds its time
/// (about 10 µs for 10 000 rules of three antecedents).
pub const MAX_RULES: usize = 10_000;

/// The most points of the [`Defuzzifier::Sampled`] centroid: an evaluation visits every point
/// for every output set (about 1 ms at the limit with three sets).
pub const MAX_SAMPLED_POINTS: usize = 100_000;

/// An input variable: its name, its range, its named fuzzy sets.
///
/// Inputs outside `range` are clamped to it before fuzzification (reported by
/// [`Evaluation::clamped`]): a sensor value beyond the range means the same as the range's end, so sets
/// meant to cover "everything above" should keep full membership up to the end of the range (an
/// infinite shoulder does).
#[derive(Debug, Clone, PartialEq)]
pub struct InputVariable {
    /// Name used by the rules.
    pub name: String,
    /// `(lo, hi)`, finite, `lo < hi`.
    pub range: (f64, f64),
    /// Named sets, in order.
    pub sets: Vec<(String, MembershipFunction)>,
}

/// How the defuzzified value (in universe units) maps to the system's output.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum OutputScale {
    /// The output is the centroid.
    #[default]
    Linear,
    /// The universe is `log10` of the output: the output is `10^centroid` (the BDS/INS system's
    /// `u = log10 t`, so a wide "big" set does not pull the centroid).
    Log10,
}

/// The output variable: its universe, its named sets (finite trapezoids/triangles within the
/// universe, of positive width) and the scale of the crisp output.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputVariable {
    /// Name (documentation only; rules name the output's sets).
    pub name: String,
    /// `(lo, hi)`, finite, `lo < hi`: where the centroid is taken.
    pub universe: (f64, f64),
    /// Named sets, in order.
    pub sets: Vec<(String, MembershipFunction)>,
    /// Scale of the crisp output.
    pub scale: OutputScale,
}

/// One test of a rule's premise: `variable IS set`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Antecedent {
    /// Input variable name.
    pub variable: String,
    /// One of its set names.
    pub set: String,
}

/// `IF a_1 AND a_2 … THEN output IS consequent` (AND = min, implication = min). A rule need not test
/// every input.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Rule {
    /// The premises, each on a different input.
    pub antecedents: Vec<Antecedent>,
    /// An output set name.
    pub consequent: String,
}

impl Rule {
    /// A rule from `(variable, set)` pairs and the consequent set.
    pub fn new(antecedents: &[(&str, &str)], consequent: &str) -> Self {
        Self {
            antecedents: antecedents
                .iter()
                .map(|&(v, s)| Antecedent { variable: v.to_owned(), set: s.to_owned() })
                .collect(),
            consequent: consequent.to_owned(),
        }
    }
}

/// How the aggregated output is turned into a number (all three compute a centroid).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Defuzzifier {
    /// `Σ x μ(x) / Σ μ(x)` on `points` equally spaced points of the universe (ends included); the
    /// reference, with 1000 points in the benches. `points >= 2`.
    Sampled {
        /// Number of points.
        points: usize,
    },
    /// The exact centroid of the piecewise-linear aggregated membership (the default).
    Exact,
    /// Area and moment tabulated once on a regular grid of the per-output-set clip levels
    /// (`points_per_axis^K` nodes, `K` output sets, at most `2^22` nodes and 8 sets) and interpolated
    /// multilinearly.
    Grid {
        /// Grid points per clip-level axis, `>= 2`.
        points_per_axis: usize,
    },
}

impl Defuzzifier {
    /// The reference sampled centroid on 1000 points.
    pub const SAMPLED_1000: Self = Self::Sampled { points: 1000 };
}

/// The result of one inference.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub struct Evaluation {
    /// The crisp output: the centroid mapped through the output scale, or the system's default output
    /// when no rule fires.
    pub output: f64,
    /// The centroid in universe units; `None` when no rule fired.
    pub centroid: Option<f64>,
    /// The largest rule strength (0 when no rule fired).
    pub firing: f64,
    /// Number of rules with a positive strength.
    pub fired_rules: usize,
    /// Whether some input was outside its range and clamped.
    pub clamped: bool,
}

/// Rules compiled to indices.
#[derive(Debug, Clone)]
struct Compiled {
    /// Corners of every input set, all inputs concatenated.
    input_sets: Vec<[f64; 4]>,
    /// `input_offsets[i]..input_offsets[i + 1]` are input `i`'s sets.
    input_offsets: Vec<usize>,
    /// Flat input-set indices of every rule's antecedents.
    antecedents: Vec<usize>,
    /// Per rule: `(first antecedent, end, consequent)`.
    rules: Vec<(usize, usize, usize)>,
    /// Corners of the output sets.
    output_sets: Vec<[f64; 4]>,
    grid: Option<CentroidGrid>,
}

/// A validated Mamdani fuzzy system: AND = min, implication = min, aggregation = max, centroid
/// defuzzification (by the [`Defuzzifier`] chosen).
///
/// Built by [`FuzzySystem::new`] from plain data, or loaded from TOML
/// ([`FuzzySystem::from_toml_str`]); evaluation ([`FuzzySystem::evaluate`]) allocates nothing.
/// Equality compares the description (rules in canonical form) and the defuzzifier.
#[derive(Debug, Clone)]
pub struct FuzzySystem {
    inputs: Vec<InputVariable>,
    output: OutputVariable,
    rules: Vec<Rule>,
    default_output: f64,
    defuzzifier: Defuzzifier,
    compiled: Compiled,
}

impl PartialEq for FuzzySystem {
    fn eq(&self, other: &Self) -> bool {
        self.inputs == other.inputs
            && self.output == other.output
            && self.rules == other.rules
            && self.default_output == other.default_output
            && self.defuzzifier == other.defuzzifier
    }
}

fn check_range(context: &dyn Fn() -> String, (lo, hi): (f64, f64)) -> Result<(), FuzzyError> {
    if lo.is_finite() && hi.is_finite() && lo < hi {
        Ok(())
    } else {
        Err(FuzzyError::EmptyRange { context: context(), lo, hi })
    }
}

fn check_set_names(context: &str, sets: &[(String, MembershipFunction)]) -> Result<(), FuzzyError> {
    if sets.is_empty() {
        return Err(FuzzyError::NoSets { context: context.to_owned() });
    }
    for (i, (name, _)) in sets.iter().enumerate() {
        if sets[..i].iter().any(|(n, _)| n == name) {
            return Err(FuzzyError::DuplicateName { context: context.to_owned(), name: name.clone() });
        }
    }
    Ok(())
}

impl InputVariable {
    /// Checks this variable alone: a finite non-empty range, at least one set, unique set names, valid
    /// shapes.
    pub fn validate(&self) -> Result<(), FuzzyError> {
        let context = format!("input `{}`", self.name);
        check_range(&|| context.clone(), self.range)?;
        check_set_names(&context, &self.sets)?;
        for (name, mf) in &self.sets {
            mf.validate(&|| format!("{context}, set `{name}`"))?;
        }
        Ok(())
    }
}

impl OutputVariable {
    /// The crisp outputs the variable can give: the universe `(lo, hi)` mapped through the
    /// scale (`(10^lo, 10^hi)` for [`OutputScale::Log10`]).
    #[must_use]
    pub fn output_range(&self) -> (f64, f64) {
        let (lo, hi) = self.universe;
        match self.scale {
            OutputScale::Linear => (lo, hi),
            OutputScale::Log10 => (10_f64.powf(lo), 10_f64.powf(hi)),
        }
    }

    /// Checks this variable alone: a finite non-empty universe, at least one set (at most
    /// [`MAX_OUTPUT_SETS`]), unique names, finite shapes of positive width within the universe.
    pub fn validate(&self) -> Result<(), FuzzyError> {
        let context = format!("output `{}`", self.name);
        check_range(&|| context.clone(), self.universe)?;
        check_set_names(&context, &self.sets)?;
        if self.sets.len() > MAX_OUTPUT_SETS {
            return Err(FuzzyError::TooManySets { what: "output", count: self.sets.len(), limit: MAX_OUTPUT_SETS });
        }
        let (lo, hi) = self.universe;
        for (name, mf) in &self.sets {
            let set_context = || format!("{context}, set `{name}`");
            mf.validate(&set_context)?;
            let corners = mf.corners();
            if corners.iter().any(|c| c.is_infinite()) {
                return Err(FuzzyError::InfiniteCorner { context: set_context(), corners });
            }
            if corners[0] < lo || corners[3] > hi {
                return Err(FuzzyError::OutputSetOutsideUniverse { context: set_context(), corners, lo, hi });
            }
            if corners[0] >= corners[3] {
                return Err(FuzzyError::DegenerateOutputSet { context: set_context(), corners });
            }
        }
        Ok(())
    }
}

impl FuzzySystem {
    /// Validates and compiles a system (with the [`Defuzzifier::Exact`] centroid).
    ///
    /// Rules are kept in canonical form: antecedents ordered as the inputs. `default_output` is the
    /// crisp output (after the output scale) returned when no rule fires.
    ///
    /// # Errors
    /// A [`FuzzyError`] naming the first problem found: invalid variables (see
    /// [`InputVariable::validate`], [`OutputVariable::validate`]), duplicate input names, no inputs,
    /// no rules, a rule with no antecedent, an unknown variable or set, an input tested twice, a
    /// non-finite default or one outside the outputs the universe allows
    /// ([`OutputVariable::output_range`]), more than [`MAX_INPUT_SETS`] input sets or
    /// [`MAX_RULES`] rules.
    pub fn new(
        inputs: Vec<InputVariable>,
        output: OutputVariable,
        mut rules: Vec<Rule>,
        default_output: f64,
    ) -> Result<Self, FuzzyError> {
        if inputs.is_empty() {
            return Err(FuzzyError::NoInputs);
        }
        for (i, input) in inputs.iter().enumerate() {
            input.validate()?;
            if inputs[..i].iter().any(|p| p.name == input.name) {
                return Err(FuzzyError::DuplicateName { context: "inputs".to_owned(), name: input.name.clone() });
            }
        }
        let total: usize = inputs.iter().map(|i| i.sets.len()).sum();
        if total > MAX_INPUT_SETS {
            return Err(FuzzyError::TooManySets { what: "all inputs", count: total, limit: MAX_INPUT_SETS });
        }
        output.validate()?;
        if !default_output.is_finite() {
            return Err(FuzzyError::InvalidDefault { value: default_output });
        }
        let (lo, hi) = output.output_range();
        if !(lo <= default_output && default_output <= hi) {
            let scale = match output.scale {
                OutputScale::Log10 => " through 10^u",
                OutputScale::Linear => "",
            };
            return Err(FuzzyError::DefaultOutsideUniverse { value: default_output, lo, hi, scale });
        }
        if rules.is_empty() {
            return Err(FuzzyError::NoRules);
        }
        if rules.len() > MAX_RULES {
            return Err(FuzzyError::TooManyRules { count: rules.len(), limit: MAX_RULES });
        }

        let mut input_offsets = vec![0];
        let mut input_sets = Vec::with_capacity(total);
        for input in &inputs {
            input_sets.extend(input.sets.iter().map(|(_, mf)| mf.corners()));
            input_offsets.push(input_sets.len());
        }
        let mut antecedents = Vec::new();
        let mut compiled_rules = Vec::with_capacity(rules.len());
        for (r, rule) in rules.iter_mut().enumerate() {
            if rule.antecedents.is_empty() {
                return Err(FuzzyError::EmptyRule { rule: r });
            }
            let mut keyed = Vec::with_capacity(rule.antecedents.len());
            for a in &rule.antecedents {
                let Some(i) = inputs.iter().position(|v| v.name == a.variable) else {
                    return Err(FuzzyError::UnknownVariable { rule: r, variable: a.variable.clone() });
                };
                let Some(s) = inputs[i].sets.iter().position(|(n, _)| *n == a.set) else {
                    return Err(FuzzyError::UnknownSet { rule: r, variable: a.variable.clone(), set: a.set.clone() });
                };
                if keyed.iter().any(|&(j, _)| j == i) {
                    return Err(FuzzyError::DuplicateAntecedent { rule: r, variable: a.variable.clone() });
                }
                keyed.push((i, input_offsets[i] + s));
            }
            let Some(consequent) = output.sets.iter().position(|(n, _)| *n == rule.consequent) else {
                return Err(FuzzyError::UnknownSet {
                    rule: r,
                    variable: output.name.clone(),
                    set: rule.consequent.clone(),
                });
            };
            // Canonical order: as the inputs.
            let mut order: Vec<usize> = (0..keyed.len()).collect();
            order.sort_by_key(|&k| keyed[k].0);
            rule.antecedents = order.iter().map(|&k| rule.antecedents[k].clone()).collect();
            keyed.sort_by_key(|&(i, _)| i);
            let start = antecedents.len();
            antecedents.extend(keyed.iter().map(|&(_, s)| s));
            compiled_rules.push((start, antecedents.len(), consequent));
        }
        let output_sets = output.sets.iter().map(|(_, mf)| mf.corners()).collect();
        Ok(Self {
            inputs,
            output,
            rules,
            default_output,
            defuzzifier: Defuzzifier::Exact,
            compiled: Compiled {
                input_sets,
                input_offsets,
                antecedents,
                rules: compiled_rules,
                output_sets,
                grid: None,
            },
        })
    }

    /// The same system with another defuzzifier (a [`Defuzzifier::Grid`] is tabulated here, once).
    ///
    /// # Errors
    /// [`FuzzyError::InvalidDefuzzifier`] for fewer than 2 or more than [`MAX_SAMPLED_POINTS`]
    /// sampled points, fewer than 2 grid points per axis, or a grid beyond the node or dimension
    /// limit.
    pub fn with_defuzzifier(mut self, defuzzifier: Defuzzifier) -> Result<Self, FuzzyError> {
        self.compiled.grid = None;
        match defuzzifier {
            Defuzzifier::Sampled { points } if !(2..=MAX_SAMPLED_POINTS).contains(&points) => {
                return Err(FuzzyError::InvalidDefuzzifier {
                    reason: format!(
                        "the sampled centroid needs 2 to {MAX_SAMPLED_POINTS} points \
                         (fuzzy_inference::MAX_SAMPLED_POINTS; every evaluation visits each), got {points}"
                    ),
                });
            }
            Defuzzifier::Grid { points_per_axis } => {
                self.compiled.grid =
                    Some(CentroidGrid::new(&self.compiled.output_sets, self.output.universe, points_per_axis)?);
            }
            _ => {}
        }
        self.defuzzifier = defuzzifier;
        Ok(self)
    }

    /// The input variables.
    pub fn inputs(&self) -> &[InputVariable] {
        &self.inputs
    }

    /// The output variable.
    pub fn output(&self) -> &OutputVariable {
        &self.output
    }

    /// The rules, antecedents in input order.
    pub fn rules(&self) -> &[Rule] {
        &self.rules
    }

    /// The crisp output returned when no rule fires.
    pub fn default_output(&self) -> f64 {
        self.default_output
    }

    /// The defuzzifier in use.
    pub fn defuzzifier(&self) -> Defuzzifier {
        self.defuzzifier
    }

    /// Infers the output for crisp `inputs` (one per input variable, in order). Allocation-free.
    ///
    /// Inputs outside their range are clamped to it ([`Evaluation::clamped`]); ±∞ is clamped too. If
    /// no rule fires (every strength is 0), or the aggregated output has no area, the output is the
    /// default output and [`Evaluation::centroid`] is `None`.
    ///
    /// # Errors
    /// [`FuzzyError::InputCount`] for a slice of the wrong length, [`FuzzyError::NanInput`] for a NaN
    /// input.
    pub fn evaluate(&self, inputs: &[f64]) -> Result<Evaluation, FuzzyError> {
        let mut beta = [0.0_f64; MAX_OUTPUT_SETS];
        let k = self.compiled.output_sets.len();
        let (firing, fired_rules, clamped) = self.clip_levels(inputs, &mut beta[..k])?;
        let beta = &beta[..k];
        let mut centroid = None;
        if fired_rules > 0 {
            let sets = &self.compiled.output_sets;
            let universe = self.output.universe;
            let (area, moment) = match (self.defuzzifier, &self.compiled.grid) {
                (Defuzzifier::Sampled { points }, _) => defuzz::sampled(sets, beta, universe, points),
                (Defuzzifier::Grid { .. }, Some(grid)) => grid.lookup(beta),
                _ => defuzz::exact(sets, beta, universe),
            };
            if area > 0.0 {
                let (lo, hi) = universe;
                centroid = Some((moment / area).clamp(lo, hi));
            }
        }
        let output = match (centroid, self.output.scale) {
            (None, _) => self.default_output,
            (Some(c), OutputScale::Linear) => c,
            (Some(c), OutputScale::Log10) => 10_f64.powf(c),
        };
        Ok(Evaluation { output, centroid, firing, fired_rules, clamped })
    }

    /// Fuzzifies `inputs` and fills `beta[k]`, the largest strength of the rules concluding output set
    /// `k` (`beta.len()` = number of output sets). Returns `(max strength, rules fired, clamped)`.
    fn clip_levels(&self, inputs: &[f64], beta: &mut [f64]) -> Result<(f64, usize, bool), FuzzyError> {
        if inputs.len() != self.inputs.len() {
            return Err(FuzzyError::InputCount { expected: self.inputs.len(), got: inputs.len() });
        }
        if let Some(index) = inputs.iter().position(|x| x.is_nan()) {
            return Err(FuzzyError::NanInput { index, name: self.inputs[index].name.clone() });
        }
        let c = &self.compiled;
        let mut membership = [0.0_f64; MAX_INPUT_SETS];
        let mut clamped = false;
        for (i, (&x, var)) in inputs.iter().zip(&self.inputs).enumerate() {
            let (lo, hi) = var.range;
            let xc = x.clamp(lo, hi);
            clamped |= xc != x;
            for s in c.input_offsets[i]..c.input_offsets[i + 1] {
                membership[s] = crate::membership::degree(&c.input_sets[s], xc);
            }
        }
        let (mut firing, mut fired) = (0.0_f64, 0);
        for &(start, end, consequent) in &c.rules {
            let strength = c.antecedents[start..end].iter().fold(1.0_f64, |m, &s| m.min(membership[s]));
            if strength > 0.0 {
                fired += 1;
                firing = firing.max(strength);
                beta[consequent] = beta[consequent].max(strength);
            }
        }
        Ok((firing, fired, clamped))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tiny() -> (Vec<InputVariable>, OutputVariable, Vec<Rule>) {
        let x = InputVariable {
            name: "x".into(),
            range: (0.0, 10.0),
            sets: vec![
                ("low".into(), MembershipFunction::trapezoid(0.0, 0.0, 2.0, 6.0)),
                ("high".into(), MembershipFunction::trapezoid(4.0, 8.0, f64::INFINITY, f64::INFINITY)),
            ],
        };
        let y = OutputVariable {
            name: "y".into(),
            universe: (0.0, 1.0),
            sets: vec![
                ("small".into(), MembershipFunction::triangle(0.0, 0.0, 0.5)),
                ("big".into(), MembershipFunction::triangle(0.5, 1.0, 1.0)),
            ],
            scale: OutputScale::Linear,
        };
        let rules = vec![Rule::new(&[("x", "low")], "small"), Rule::new(&[("x", "high")], "big")];
        (vec![x], y, rules)
    }

    #[test]
    fn construction_errors_are_typed() {
        let (i, o, r) = tiny();
        assert!(FuzzySystem::new(i.clone(), o.clone(), r.clone(), 0.5).is_ok());
        let mut bad = r.clone();
        bad[1].antecedents[0].set = "huge".into();
        assert_eq!(
            FuzzySystem::new(i.clone(), o.clone(), bad, 0.5).unwrap_err(),
            FuzzyError::UnknownSet { rule: 1, variable: "x".into(), set: "huge".into() }
        );
        let mut bad = r.clone();
        bad[0].antecedents[0].variable = "z".into();
        assert!(matches!(FuzzySystem::new(i.clone(), o.clone(), bad, 0.5), Err(FuzzyError::UnknownVariable { .. })));
        let mut bad = r.clone();
        bad[0].consequent = "medium".into();
        assert!(matches!(FuzzySystem::new(i.clone(), o.clone(), bad, 0.5), Err(FuzzyError::UnknownSet { .. })));
        let mut bad = r.clone();
        bad[0].antecedents.push(Antecedent { variable: "x".into(), set: "high".into() });
        assert!(matches!(
            FuzzySystem::new(i.clone(), o.clone(), bad, 0.5),
            Err(FuzzyError::DuplicateAntecedent { rule: 0, .. })
        ));
        let mut bad = i.clone();
        bad[0].sets[0].1 = MembershipFunction::triangle(3.0, 2.0, 4.0);
        let e = FuzzySystem::new(bad, o.clone(), r.clone(), 0.5).unwrap_err();
        assert!(matches!(e, FuzzyError::NonMonotoneCorners { .. }));
        assert!(e.to_string().contains("input `x`, set `low`"), "{e}");
        let mut bad = o.clone();
        bad.universe = (1.0, 1.0);
        assert!(matches!(FuzzySystem::new(i.clone(), bad, r.clone(), 0.5), Err(FuzzyError::EmptyRange { .. })));
        let mut bad = o.clone();
        bad.universe = (f64::NAN, 1.0);
        assert!(matches!(FuzzySystem::new(i.clone(), bad, r.clone(), 0.5), Err(FuzzyError::EmptyRange { .. })));
        let mut bad = o.clone();
        bad.sets[1].1 = MembershipFunction::triangle(0.5, 1.0, 1.5);
        assert!(matches!(
            FuzzySystem::new(i.clone(), bad, r.clone(), 0.5),
            Err(FuzzyError::OutputSetOutsideUniverse { .. })
        ));
        let mut bad = o.clone();
        bad.sets[1].1 = MembershipFunction::triangle(0.5, 0.5, 0.5);
        assert!(matches!(
            FuzzySystem::new(i.clone(), bad, r.clone(), 0.5),
            Err(FuzzyError::DegenerateOutputSet { .. })
        ));
        let mut bad = o.clone();
        bad.sets[1].0 = "small".into();
        assert!(matches!(FuzzySystem::new(i.clone(), bad, r.clone(), 0.5), Err(FuzzyError::DuplicateName { .. })));
        assert!(matches!(
            FuzzySystem::new(i.clone(), o.clone(), r.clone(), f64::NAN),
            Err(FuzzyError::InvalidDefault { .. })
        ));
        assert_eq!(FuzzySystem::new(i.clone(), o.clone(), vec![], 0.5).unwrap_err(), FuzzyError::NoRules);
        assert_eq!(FuzzySystem::new(vec![], o.clone(), r.clone(), 0.5).unwrap_err(), FuzzyError::NoInputs);
        let sys = FuzzySystem::new(i, o, r, 0.5).unwrap();
        assert!(sys.clone().with_defuzzifier(Defuzzifier::Sampled { points: 1 }).is_err());
        assert!(sys.with_defuzzifier(Defuzzifier::Grid { points_per_axis: 1 }).is_err());
    }

    #[test]
    fn evaluation_clamps_and_refuses_nan() {
        let (i, o, r) = tiny();
        let sys = FuzzySystem::new(i, o, r, 0.5).unwrap();
        assert_eq!(sys.evaluate(&[f64::NAN]).unwrap_err(), FuzzyError::NanInput { index: 0, name: "x".into() });
        assert_eq!(sys.evaluate(&[1.0, 2.0]).unwrap_err(), FuzzyError::InputCount { expected: 1, got: 2 });
        let e = sys.evaluate(&[1e9]).unwrap();
        assert!(e.clamped);
        assert_eq!(e, sys.evaluate(&[f64::INFINITY]).unwrap());
        assert!((e.output - 5.0 / 6.0).abs() < 1e-12, "{e:?}");
        let e = sys.evaluate(&[1.0]).unwrap();
        assert!(!e.clamped && e.fired_rules == 1 && e.firing == 1.0);
        assert!((e.output - 0.5 / 3.0).abs() < 1e-12);
    }
}
