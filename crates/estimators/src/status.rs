//! What every estimate says about itself: the kind of set, one step status shared by every
//! estimator, and the estimator's own details (no downcasting).
//!
//! A [`StepStatus`] has three parts, each with a fixed vocabulary:
//!
//! * [`SolveOutcome`]: how the step's computation ended — the initial estimate, a prediction
//!   without a measurement, converged (closed-form filters always), not converged (an iterative
//!   solver stopped at its limit and its last iterate is published), a fallback (the solver's
//!   answer was not used; a set-membership filter publishes a certified set from a feasible
//!   multiplier, an unscented filter a covariance recomputed about the central sigma point), or
//!   relaxed (the problem as posed had no solution and a relaxed one was solved);
//! * [`DataCheck`]: whether the estimator checked the step's data against what it was told, and
//!   what it found;
//! * [`Guarantee`]: for guaranteed sets, whether the published set is still guaranteed.
//!
//! [`StepStatus::label`] writes them as one word list (`converged`, `fallback`,
//! `converged+inconsistent+not-guaranteed`), the `status` column of `port-est`.
//!
//! [`StepDetails`] carries an estimator's own numbers as an open structure: each estimator
//! declares its [`DetailField`]s (name and meaning) once, in its module; its registry row lists the
//! same, and the command line's columns, Python's `details` and the type stubs read them from
//! there. This module sits below every estimator and names none of them.

use std::fmt;

/// What kind of set an estimate describes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum EstimateKind {
    /// A Gaussian estimate: mean and covariance; the per-state bounds are ±1 standard deviation.
    Gaussian,
    /// A guaranteed ellipsoid `𝓔(c, P) = {x : (x − c)ᵀ P⁻¹ (x − c) ≤ 1}` that contains the true
    /// state whenever the noises respect their bounds; the per-state bounds are its projections.
    GuaranteedEllipsoid,
    /// A guaranteed constrained zonotope `{c + G ξ : ‖ξ‖∞ ≤ 1, A ξ = b}` that contains the true
    /// state whenever the noises respect their bounds; the per-state bounds are its certified
    /// interval hull (tightened by an interval observer and the declared state bounds), and the
    /// shape is the diagonal of their squared half-widths.
    GuaranteedConstrainedZonotope,
    /// A point estimate (moving-horizon estimators): no per-state bounds; the shape is a weight
    /// matrix of the method (documented by the estimator), neither a calibrated covariance nor a
    /// guaranteed set.
    Point,
}

impl EstimateKind {
    /// A short label for tables and file headers.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            EstimateKind::Gaussian => "gaussian",
            EstimateKind::GuaranteedEllipsoid => "guaranteed ellipsoid",
            EstimateKind::GuaranteedConstrainedZonotope => "guaranteed constrained zonotope",
            EstimateKind::Point => "point",
        }
    }

    /// What the shape matrix is.
    #[must_use]
    pub fn shape_meaning(self) -> &'static str {
        match self {
            EstimateKind::Gaussian => "covariance",
            EstimateKind::GuaranteedEllipsoid => "ellipsoid shape matrix (certified outer bound)",
            EstimateKind::GuaranteedConstrainedZonotope => {
                "diagonal of the squared half-widths of the certified interval (the set itself: the estimator's set)"
            }
            EstimateKind::Point => "weight matrix of the method (not a covariance, not a bound)",
        }
    }

    /// What the per-state bounds mean, `None` when the kind has none.
    #[must_use]
    pub fn bounds_meaning(self) -> Option<&'static str> {
        match self {
            EstimateKind::Gaussian => Some("mean ∓ one standard deviation"),
            EstimateKind::GuaranteedEllipsoid => Some("guaranteed interval (the ellipsoid's projection)"),
            EstimateKind::GuaranteedConstrainedZonotope => {
                Some("guaranteed interval (the set's verified hull, the interval observer, the state bounds)")
            }
            EstimateKind::Point => None,
        }
    }
}

/// How a step's computation ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum SolveOutcome {
    /// No step yet: the initial estimate.
    Initial,
    /// A prediction without a measurement.
    Predicted,
    /// The step finished as designed (closed form, or an iterative solve within its tolerance).
    Converged,
    /// An iterative solver stopped at its limit; its last iterate is published.
    NotConverged,
    /// The solver's answer was not used; a fallback was published (module documentation).
    FallbackUsed,
    /// The step's constraints could not all hold; the estimate of a relaxed problem is published.
    Relaxed,
    /// A real-time iteration scheme spent its configured budget of iterations, from the previous
    /// step's solution: the iterate is published, not converged by design (clean: the step did
    /// what its settings ask).
    RealTimeIteration,
}

impl SolveOutcome {
    /// A short label: `initial`, `predicted`, `converged`, `not-converged`, `fallback`, `relaxed`,
    /// `real-time`.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            SolveOutcome::Initial => "initial",
            SolveOutcome::Predicted => "predicted",
            SolveOutcome::Converged => "converged",
            SolveOutcome::NotConverged => "not-converged",
            SolveOutcome::FallbackUsed => "fallback",
            SolveOutcome::Relaxed => "relaxed",
            SolveOutcome::RealTimeIteration => "real-time",
        }
    }
}

/// Whether the step's data were checked against the estimator's assumptions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum DataCheck {
    /// The estimator does not check its data (or there were none: a prediction).
    NotChecked,
    /// Checked and consistent with the noise description.
    Consistent,
    /// Provably inconsistent with the noise description, and published anyway (a policy the
    /// caller chose).
    Inconsistent,
}

/// Whether a published set is guaranteed to contain the true state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Guarantee {
    /// The estimate is not a guaranteed set (Gaussian, point).
    NotApplicable,
    /// Guaranteed whenever the noises respect their bounds.
    Holds,
    /// No longer guaranteed: inconsistent data were accepted at this or an earlier step.
    Lost,
    /// Guaranteed, but some state's interval has grown past the estimator's divergence rule (wider
    /// than a set factor — 2 by default — times its initial width, or than its declared bounds): a
    /// bound too wide to act on.
    Diverging,
}

/// The status of one step, the same vocabulary for every estimator (module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct StepStatus {
    /// How the computation ended.
    pub outcome: SolveOutcome,
    /// What the data check found.
    pub data: DataCheck,
    /// Whether the set is guaranteed.
    pub guarantee: Guarantee,
}

impl StepStatus {
    /// The initial estimate of a non-guaranteed estimator.
    pub const INITIAL: Self =
        Self { outcome: SolveOutcome::Initial, data: DataCheck::NotChecked, guarantee: Guarantee::NotApplicable };

    /// A status with no data check and no guarantee (Gaussian and point estimators).
    #[must_use]
    pub fn unchecked(outcome: SolveOutcome) -> Self {
        Self { outcome, data: DataCheck::NotChecked, guarantee: Guarantee::NotApplicable }
    }

    /// Whether nothing is wrong: initial, predicted or converged, no inconsistent data, and the
    /// guarantee (if any) holds.
    #[must_use]
    pub fn is_clean(&self) -> bool {
        matches!(
            self.outcome,
            SolveOutcome::Initial | SolveOutcome::Predicted | SolveOutcome::Converged | SolveOutcome::RealTimeIteration
        ) && self.data != DataCheck::Inconsistent
            && !matches!(self.guarantee, Guarantee::Lost | Guarantee::Diverging)
    }

    /// The outcome, then `+inconsistent` and `+not-guaranteed` where they apply.
    #[must_use]
    pub fn label(&self) -> String {
        self.to_string()
    }
}

impl fmt::Display for StepStatus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.outcome.label())?;
        if self.data == DataCheck::Inconsistent {
            f.write_str("+inconsistent")?;
        }
        if self.guarantee == Guarantee::Lost {
            f.write_str("+not-guaranteed")?;
        }
        if self.guarantee == Guarantee::Diverging {
            f.write_str("+diverging")?;
        }
        Ok(())
    }
}

/// One number an estimator reports at every step beyond its [`StepStatus`]: the name of its column
/// (`port-est`'s output, Python's `details`) and what it means.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct DetailField {
    /// The column name (`tau1`, `scale`, `iterations`).
    pub name: &'static str,
    /// What the number is, in one line.
    pub meaning: &'static str,
}

/// The most numbers one estimator reports per step ([`StepDetails`] holds them inline, so a step
/// publishes its details without allocating).
pub const MAX_DETAIL_FIELDS: usize = 4;

/// An estimator's own numbers for its last step, beyond the shared [`StepStatus`]: the fields the
/// estimator declares (the same at every step of one estimator, and the same as its registry row's)
/// and this step's value of each (`None` when the step has none, e.g. the noise scale of an epoch
/// without a fix). Typed reports stay with their estimators (`SetEstimate::report`,
/// `UnscentedKalmanFilter::report`, `AdaptiveKalmanFilter::last_step`, …).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepDetails {
    fields: &'static [DetailField],
    values: [Option<f64>; MAX_DETAIL_FIELDS],
}

impl StepDetails {
    /// No numbers beyond the status (the Kalman filters).
    pub const NONE: Self = Self { fields: &[], values: [None; MAX_DETAIL_FIELDS] };

    /// The values `values` of `fields`, in order. Fields beyond `MAX_DETAIL_FIELDS` (4) are not
    /// representable: an estimator declaring more is a programming error caught by its tests
    /// (debug assertion; release builds keep the first ones).
    #[must_use]
    pub fn new(fields: &'static [DetailField], values: &[Option<f64>]) -> Self {
        debug_assert!(fields.len() <= MAX_DETAIL_FIELDS && values.len() == fields.len());
        let mut v = [None; MAX_DETAIL_FIELDS];
        for (slot, value) in v.iter_mut().zip(values) {
            *slot = *value;
        }
        Self { fields: &fields[..fields.len().min(MAX_DETAIL_FIELDS)], values: v }
    }

    /// The fields every step of this estimator reports (for file headers and column lists).
    #[must_use]
    pub fn fields(&self) -> &'static [DetailField] {
        self.fields
    }

    /// The value of the field called `name`: `None` when the estimator has no such field,
    /// `Some(None)` when it has but this step gave no value.
    #[must_use]
    pub fn get(&self, name: &str) -> Option<Option<f64>> {
        self.fields.iter().position(|f| f.name == name).map(|i| self.values[i])
    }

    /// Calls `f` with each field's name and value, in order. Allocation-free.
    pub fn for_each_field(&self, f: &mut dyn FnMut(&'static str, Option<f64>)) {
        for (field, value) in self.fields.iter().zip(self.values) {
            f(field.name, value);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_list_every_flag() {
        let s =
            StepStatus { outcome: SolveOutcome::Converged, data: DataCheck::Consistent, guarantee: Guarantee::Holds };
        assert_eq!(s.label(), "converged");
        assert!(s.is_clean());
        let s = StepStatus { data: DataCheck::Inconsistent, guarantee: Guarantee::Lost, ..s };
        assert_eq!(s.label(), "converged+inconsistent+not-guaranteed");
        assert!(!s.is_clean());
        let s = StepStatus { outcome: SolveOutcome::FallbackUsed, data: DataCheck::Consistent, ..s };
        assert_eq!(s.label(), "fallback+not-guaranteed");
        assert_eq!(StepStatus::unchecked(SolveOutcome::NotConverged).label(), "not-converged");
        assert!(!StepStatus::unchecked(SolveOutcome::NotConverged).is_clean());
        assert!(StepStatus::INITIAL.is_clean());
    }

    #[test]
    fn details_report_their_fields_in_order() {
        const FIELDS: &[DetailField] =
            &[DetailField { name: "a", meaning: "first" }, DetailField { name: "b", meaning: "second" }];
        let d = StepDetails::new(FIELDS, &[Some(1.5), None]);
        let mut seen = Vec::new();
        d.for_each_field(&mut |n, v| seen.push((n, v)));
        assert_eq!(seen, [("a", Some(1.5)), ("b", None)]);
        assert_eq!((d.get("a"), d.get("b"), d.get("c")), (Some(Some(1.5)), Some(None), None));
        assert_eq!(d.fields(), FIELDS);
        assert!(StepDetails::NONE.fields().is_empty());
        assert_eq!(EstimateKind::Point.bounds_meaning(), None);
        assert!(EstimateKind::Gaussian.bounds_meaning().is_some());
    }
}
