//! What every subcommand shares when it runs an estimator over a log: the columns an estimate
//! is written as (named after what the numbers mean), the `status` column, the tally of steps
//! that did not end cleanly with its warning, `--strict`, and the location of a step's error.

use std::io::{self, Write};

use estimators::{
    DataCheck, DetailField, Estimate, EstimateKind, EstimatorError, Guarantee, SolveOutcome, StepDetails, StepStatus,
};

use crate::data::RowSource;
use crate::error::{Error, Location};

/// What a run does with a step whose status is not clean (not converged, a fallback, a relaxed
/// problem, inconsistent data, a set no longer guaranteed).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum StatusPolicy {
    /// Write it with its status and warn on stderr with the counts (the default).
    #[default]
    Warn,
    /// Stop at its row with an error; the output is not written (`--strict`).
    Error,
}

/// What a run does with the steps it wrote before an error (`--on-error`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum OnError {
    /// Write nothing: the output is published only when every step succeeded (the default).
    #[default]
    Discard,
    /// Keep the steps before the error in `OUT.partial.csv` beside the output (the output itself
    /// is not written); the error names the file and how many steps it holds.
    KeepPartial,
}

/// How many steps of a run ended how.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StatusTally {
    /// Steps run (rows written).
    pub steps: u64,
    /// Prediction-only steps (gaps bridged, epochs without a fix).
    pub predicted: u64,
    /// Steps whose iterative solver stopped at its limit.
    pub not_converged: u64,
    /// Steps that published a fallback.
    pub fallbacks: u64,
    /// Steps that solved a relaxed problem.
    pub relaxed: u64,
    /// Steps with data inconsistent with the noise bounds (published by the chosen policy).
    pub inconsistent: u64,
    /// Steps whose set is no longer guaranteed.
    pub not_guaranteed: u64,
    /// Steps whose guaranteed set is wider than the estimator's divergence rule allows.
    pub diverging: u64,
}

impl StatusTally {
    /// Counts one step.
    pub fn record(&mut self, s: StepStatus) {
        self.steps += 1;
        match s.outcome {
            SolveOutcome::Predicted => self.predicted += 1,
            SolveOutcome::NotConverged => self.not_converged += 1,
            SolveOutcome::FallbackUsed => self.fallbacks += 1,
            SolveOutcome::Relaxed => self.relaxed += 1,
            _ => {}
        }
        self.inconsistent += u64::from(s.data == DataCheck::Inconsistent);
        self.not_guaranteed += u64::from(s.guarantee == Guarantee::Lost);
        self.diverging += u64::from(s.guarantee == Guarantee::Diverging);
    }

    /// Steps that did not end cleanly.
    #[must_use]
    pub fn unclean(&self) -> u64 {
        self.not_converged + self.fallbacks + self.relaxed + self.inconsistent.max(self.not_guaranteed) + self.diverging
    }

    /// One warning line per kind of unclean step, empty when every step ended cleanly.
    #[must_use]
    pub fn warnings(&self) -> Vec<String> {
        let n = self.steps;
        let mut w = Vec::new();
        let mut add = |count: u64, what: &str| {
            if count > 0 {
                w.push(format!("warning: {count} of {n} steps {what} (see the status column; --strict refuses them)"));
            }
        };
        add(self.not_converged, "did not converge: the solver's last iterate is published");
        add(self.fallbacks, "fell back to a feasible solution after a solver failure");
        add(self.relaxed, "could not meet their constraints: a relaxed problem's estimate is published");
        add(self.inconsistent, "had data inconsistent with the noise bounds");
        add(self.not_guaranteed, "published sets that are no longer guaranteed");
        add(self.diverging, "published guaranteed sets wider than the divergence rule allows (too wide to act on)");
        w
    }
}

/// Applies `policy` to a step's status (an error at `at` for an unclean step under
/// [`StatusPolicy::Error`]).
///
/// # Errors
/// [`Error::At`] naming the step and its status.
pub fn enforce(policy: StatusPolicy, status: StepStatus, at: impl FnOnce() -> Location, k: u64) -> Result<(), Error> {
    if policy == StatusPolicy::Error && !status.is_clean() {
        let message = format!("step k = {k} ended {status} and --strict refuses steps that do not end cleanly");
        return Err(Error::At { at: at(), message });
    }
    Ok(())
}

/// A step's error at its data row: at the cell the estimator names (an input outside its box),
/// else at `k`.
pub fn step_error(source: EstimatorError, data: &dyn RowSource, k: u64) -> Error {
    let cell = match &source {
        EstimatorError::InputOutsideBounds { index, .. } => 1 + index,
        // An outlier: at the cell of the output with the largest normalised innovation.
        EstimatorError::Outlier { worst: Some(w), .. } => 1 + data.inputs() + w.index,
        _ => 0,
    };
    Error::Step { at: data.locate(Some(cell)), k, source }
}

/// The columns of one estimate: `xhat1..n`, then by kind `sd1..n,trace_cov` (Gaussian: one
/// standard deviation each and the covariance's trace), `lo1..n,hi1..n,trace_shape` (guaranteed
/// intervals and the set's trace) or nothing (point estimates: their shape is a weight, not a
/// bound), then the estimator's own numbers (`tau1..3`, `scale,distance`, `iterations`), then
/// `status`.
#[derive(Debug, Clone, Copy)]
pub struct EstimateColumns {
    kind: EstimateKind,
    states: usize,
    details: &'static [DetailField],
}

impl EstimateColumns {
    /// The columns of the estimates `initial` stands for (same kind, states and details).
    #[must_use]
    pub fn of(initial: &dyn Estimate) -> Self {
        Self { kind: initial.kind(), states: initial.center().len(), details: initial.details().fields() }
    }

    /// The header after `k`, comma-separated with a leading comma.
    #[must_use]
    pub fn header(&self) -> String {
        let n = self.states;
        let mut h = String::new();
        let mut push = |prefix: &str| (1..=n).for_each(|i| h.push_str(&format!(",{prefix}{i}")));
        push("xhat");
        match self.kind {
            EstimateKind::Gaussian => {
                push("sd");
                h.push_str(",trace_cov");
            }
            EstimateKind::GuaranteedEllipsoid => {
                push("lo");
                push("hi");
                h.push_str(",trace_shape");
            }
            EstimateKind::GuaranteedConstrainedZonotope => {
                push("lo");
                push("hi");
            }
            _ => {}
        }
        for d in self.details {
            h.push(',');
            h.push_str(d.name);
        }
        h.push_str(",status");
        h
    }

    /// Writes `e`'s cells (after `k`, each with a leading comma), numbers in `{:e}` notation (exact
    /// to the last bit), an empty cell where a number does not exist.
    ///
    /// # Errors
    /// When `out` fails.
    pub fn write(&self, out: &mut dyn Write, e: &dyn Estimate) -> io::Result<()> {
        let c = e.center();
        for i in 0..self.states {
            write!(out, ",{:e}", c[i])?;
        }
        match self.kind {
            EstimateKind::Gaussian => {
                for i in 0..self.states {
                    write!(out, ",{:e}", e.shape()[(i, i)].max(0.0).sqrt())?;
                }
                write!(out, ",{:e}", e.shape().trace())?;
            }
            EstimateKind::GuaranteedEllipsoid | EstimateKind::GuaranteedConstrainedZonotope => {
                for side in [0, 1] {
                    for i in 0..self.states {
                        match e.bounds(i) {
                            Some(b) => write!(out, ",{:e}", if side == 0 { b.0 } else { b.1 })?,
                            None => write!(out, ",")?,
                        }
                    }
                }
                if self.kind == EstimateKind::GuaranteedEllipsoid {
                    write!(out, ",{:e}", e.shape().trace())?;
                }
            }
            _ => {}
        }
        let mut result = Ok(());
        let details: StepDetails = e.details();
        details.for_each_field(&mut |_, v| {
            if result.is_ok() {
                result = match v {
                    Some(v) => write!(out, ",{v:e}"),
                    None => write!(out, ","),
                };
            }
        });
        result?;
        write!(out, ",{}", e.status())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tally_counts_and_warns() {
        let mut t = StatusTally::default();
        t.record(StepStatus::unchecked(SolveOutcome::Converged));
        t.record(StepStatus::unchecked(SolveOutcome::NotConverged));
        t.record(StepStatus::unchecked(SolveOutcome::Predicted));
        assert_eq!((t.steps, t.not_converged, t.predicted, t.unclean()), (3, 1, 1, 1));
        let w = t.warnings();
        assert_eq!(w.len(), 1);
        assert!(w[0].starts_with("warning: 1 of 3 steps did not converge"), "{}", w[0]);
        let at = || Location::new(std::path::Path::new("d.csv"), 3, 1);
        assert!(enforce(StatusPolicy::Warn, StepStatus::unchecked(SolveOutcome::NotConverged), at, 1).is_ok());
        let e = enforce(StatusPolicy::Error, StepStatus::unchecked(SolveOutcome::NotConverged), at, 1).unwrap_err();
        assert!(e.to_string().starts_with("d.csv:3:1: step k = 1 ended not-converged"), "{e}");
    }
}
