//! Every estimator checks its data against what it was told, with one policy vocabulary.
//!
//! * The set-membership filters prove a measurement incompatible with the predicted set and the
//!   noise bounds (a separating direction, [`smf::consistency`](crate::smf::consistency)).
//! * The Gaussian filters (Kalman, extended, unscented, adaptive) gate the innovation: the
//!   normalised innovation squared `NIS = νᵀ S⁻¹ ν` (`S` the innovation covariance of the step)
//!   is compared with the quantile of the χ² distribution with `m` degrees of freedom at
//!   [`DataChecks::gate_probability`] ([`InnovationGate`]). A statistical test, not a proof: with
//!   the default probability `1 − 10⁻¹²` a correct model raises a false alarm once in a trillion
//!   steps (a terminal's fleet logs hundreds of billions of steps; the gate stands at about 7σ
//!   for one output, `χ²₃ ≈ 59` for three).
//! * The moving-horizon estimators of linear models prove a window inconsistent when no
//!   disturbance sequence in `W` fits its measurements into `V` (a linear programme, after the
//!   published solution failed to witness consistency; `mhe::consistency`, docs/robust-mhe.md).
//!   The nonlinear MHE does not check (policy `Off` only).
//!
//! What happens to data that fail the check is the [`InconsistencyPolicy`]: an error naming the
//! step (the default), flag and continue, restart (the set-membership filter inflates its
//! prediction until the data meet it; a Gaussian filter or a moving-horizon estimator drops the
//! measurement and publishes its prediction), or no check at all. Every step says what the check found
//! ([`DataCheck`](crate::DataCheck) in its status).

use statrs::distribution::{ChiSquared, ContinuousCDF};

use nalgebra::{DMatrix, DVector};

use crate::error::{EstimatorError, WorstOutput};

/// What an estimator does when a step's data fail its check.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum InconsistencyPolicy {
    /// Refuse the step with an error naming it
    /// ([`EstimatorError::InconsistentData`] or
    /// [`EstimatorError::InconsistentWindow`] for a proof,
    /// [`EstimatorError::Outlier`] for a failed gate); the estimator
    /// is unchanged (the default).
    #[default]
    Error,
    /// Use the data anyway, mark the step inconsistent (and a guaranteed set, from this step on, no
    /// longer guaranteed).
    FlagAndContinue,
    /// Move on without trusting the data, marked inconsistent: the set-membership filter inflates
    /// the prediction (`A P_k Aᵀ`, `Q` and `P_k` alike, by `(1 + excess)²` and then powers of four)
    /// until the measurement strip meets it and updates from there, so the set moves to where the
    /// data are (every later set no longer guaranteed: the inflation is a choice, not a bound); a
    /// Gaussian filter and a moving-horizon estimator drop the measurement and publish the
    /// prediction.
    Restart,
    /// No check: the data are used as they come and the status says `NotChecked`.
    Off,
}

/// The data checks of an estimator: the policy, and for the Gaussian filters the gate's
/// probability.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DataChecks {
    /// What a step whose data fail the check does.
    pub policy: InconsistencyPolicy,
    /// The probability, under the filter's own noise model, that a measurement passes the
    /// Gaussian filters' innovation gate (in `(0, 1)`; default `1 − 10⁻¹²`).
    pub gate_probability: f64,
}

impl DataChecks {
    /// The default gate probability, `1 − 10⁻¹²`.
    pub const DEFAULT_GATE_PROBABILITY: f64 = 1.0 - 1e-12;

    /// No check (the papers' filters, for reproducing them).
    pub const OFF: Self = Self { policy: InconsistencyPolicy::Off, gate_probability: Self::DEFAULT_GATE_PROBABILITY };

    /// The given policy with the default gate probability.
    #[must_use]
    pub fn with_policy(policy: InconsistencyPolicy) -> Self {
        Self { policy, ..Self::default() }
    }
}

impl Default for DataChecks {
    fn default() -> Self {
        Self { policy: InconsistencyPolicy::Error, gate_probability: Self::DEFAULT_GATE_PROBABILITY }
    }
}

/// The innovation gate of a Gaussian filter with `m` outputs: the χ² quantile and the policy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InnovationGate {
    checks: DataChecks,
    threshold: f64,
}

/// What the gate found for one measurement.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum GateVerdict {
    /// No check (policy off).
    Unchecked,
    /// Inside the gate.
    Pass,
    /// Outside, and the policy uses the measurement anyway.
    FlagAndUse,
    /// Outside, and the policy drops the measurement (publish the prediction).
    Drop,
}

impl InnovationGate {
    /// The gate for `m` outputs.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidSetting`] for a probability outside `(0, 1)` or a quantile that
    /// cannot be computed.
    pub fn new(checks: DataChecks, m: usize) -> Result<Self, EstimatorError> {
        let p = checks.gate_probability;
        let bad = |value| EstimatorError::InvalidSetting { what: "gate_probability", value, requirement: "in (0, 1)" };
        if !(p > 0.0 && p < 1.0) {
            return Err(bad(p));
        }
        let threshold = ChiSquared::new(m.max(1) as f64).map_err(|_| bad(p))?.inverse_cdf(p);
        if !(threshold.is_finite() && threshold > 0.0) {
            return Err(bad(p));
        }
        Ok(Self { checks, threshold })
    }

    /// The checks it applies.
    #[must_use]
    pub fn checks(&self) -> DataChecks {
        self.checks
    }

    /// The χ² quantile a measurement's `NIS` is compared with.
    #[must_use]
    pub fn threshold(&self) -> f64 {
        self.threshold
    }

    /// Whether the gate computes anything (the policy is not off).
    pub(crate) fn is_on(&self) -> bool {
        self.checks.policy != InconsistencyPolicy::Off
    }

    /// Judges a measurement of normalised innovation squared `nis` at `step`.
    ///
    /// # Errors
    /// [`EstimatorError::Outlier`] outside the gate with the policy [`InconsistencyPolicy::Error`].
    pub(crate) fn judge(&self, nis: f64, step: u64) -> Result<GateVerdict, EstimatorError> {
        if !self.is_on() {
            return Ok(GateVerdict::Unchecked);
        }
        // NaN is outside: a non-finite innovation is not consistent with anything.
        if nis <= self.threshold {
            return Ok(GateVerdict::Pass);
        }
        match self.checks.policy {
            InconsistencyPolicy::FlagAndContinue => Ok(GateVerdict::FlagAndUse),
            InconsistencyPolicy::Restart => Ok(GateVerdict::Drop),
            _ => Err(EstimatorError::Outlier {
                step,
                nis,
                threshold: self.threshold,
                probability: self.checks.gate_probability,
                worst: None,
            }),
        }
    }
}

/// An outlier error with the output of the largest normalised innovation `|ν_i| / √S_ii` added,
/// from `ν` and the lower Cholesky factor of `S` (`S_ii` the squared norm of the factor's row
/// `i`). Other errors pass through.
pub(crate) fn name_worst_output(e: EstimatorError, innov: &DVector<f64>, s_chol: &DMatrix<f64>) -> EstimatorError {
    let EstimatorError::Outlier { step, nis, threshold, probability, worst: None } = e else { return e };
    let mut worst: Option<WorstOutput> = None;
    for (i, &r) in innov.iter().enumerate() {
        let var: f64 = (0..=i).map(|j| s_chol[(i, j)] * s_chol[(i, j)]).sum();
        let sigmas = r.abs() / var.sqrt();
        if worst.is_none_or(|w| sigmas > w.sigmas) {
            worst = Some(WorstOutput { index: i, residual: r, sigmas });
        }
    }
    EstimatorError::Outlier { step, nis, threshold, probability, worst }
}

/// The index of a partial measurement's worst output in the whole measurement.
pub(crate) fn map_worst_output(e: EstimatorError, rows: &[usize]) -> EstimatorError {
    match e {
        EstimatorError::Outlier { step, nis, threshold, probability, worst: Some(w) } => EstimatorError::Outlier {
            step,
            nis,
            threshold,
            probability,
            worst: Some(WorstOutput { index: rows.get(w.index).copied().unwrap_or(w.index), ..w }),
        },
        e => e,
    }
}

/// Whether a model function is defined at a point: `value` is its plain evaluation there (into
/// `out`). A NaN or an evaluation error is `Err(reason)`, for a certified filter's
/// `GuaranteeLost`: an interval enclosure can look bounded where the function is not defined
/// (`0 · ln t` at `t < 0` encloses as 0), so the filters ask the plain value too, as the
/// Gaussian filters do.
pub(crate) fn defined_at(
    what: &str,
    at: &str,
    value: Result<(), models::ModelError>,
    out: &DVector<f64>,
) -> Result<(), String> {
    match value {
        Err(models::ModelError::Evaluation(message)) => Err(format!("{what} is undefined at {at}: {message}")),
        Err(e) => Err(format!("{what} cannot be evaluated at {at}: {e}")),
        Ok(()) => match out.iter().position(|v| v.is_nan()) {
            Some(i) => Err(format!("{what}[{i}] is NaN (undefined) at {at}")),
            None => Ok(()),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_are_those_of_the_chi_squared_distribution() {
        // Reference values (scipy.stats.chi2.ppf): 95 % for 1, 2, 3 degrees of freedom.
        for (m, q) in [(1, 3.841458820694124), (2, 5.991464547107979), (3, 7.814727903251179)] {
            let g = InnovationGate::new(DataChecks { gate_probability: 0.95, ..DataChecks::default() }, m).unwrap();
            assert!((g.threshold() - q).abs() < 1e-9 * q, "m = {m}: {}", g.threshold());
        }
        // 1 − 1e-9 for one degree of freedom is (6.109410204869…)² = 37.3249…
        let g = InnovationGate::new(DataChecks { gate_probability: 1.0 - 1e-9, ..DataChecks::default() }, 1).unwrap();
        assert!((g.threshold() - 37.32489).abs() < 1e-3, "{}", g.threshold());
        // The default, 1 − 1e-12: (7.1305…)² = 50.84… for one degree of freedom.
        let g = InnovationGate::new(DataChecks::default(), 1).unwrap();
        assert!((g.threshold() - 50.84).abs() < 0.05, "{}", g.threshold());
    }

    #[test]
    fn the_policy_decides() {
        let gate = |policy| InnovationGate::new(DataChecks::with_policy(policy), 2).unwrap();
        let t = gate(InconsistencyPolicy::Error).threshold();
        assert_eq!(gate(InconsistencyPolicy::Error).judge(0.5 * t, 3), Ok(GateVerdict::Pass));
        assert!(matches!(
            gate(InconsistencyPolicy::Error).judge(2.0 * t, 3),
            Err(EstimatorError::Outlier { step: 3, .. })
        ));
        assert!(gate(InconsistencyPolicy::Error).judge(f64::NAN, 3).is_err());
        assert_eq!(gate(InconsistencyPolicy::FlagAndContinue).judge(2.0 * t, 3), Ok(GateVerdict::FlagAndUse));
        assert_eq!(gate(InconsistencyPolicy::Restart).judge(2.0 * t, 3), Ok(GateVerdict::Drop));
        assert_eq!(gate(InconsistencyPolicy::Off).judge(f64::INFINITY, 3), Ok(GateVerdict::Unchecked));
        for p in [0.0, 1.0, f64::NAN, -0.5] {
            assert!(InnovationGate::new(DataChecks { gate_probability: p, ..DataChecks::default() }, 2).is_err());
        }
    }
}
