//! Constrained-zonotope set-membership filters (docs/constrained-zonotopes.md): the set
//! `X_k = ⟨c, G, A, b⟩` propagated through the model and intersected with every measurement, on
//! any [`SecondOrderModel`] — exactly (up to enclosed rounding) on a linear model, Scott et al.
//! (2016), and by the mean-value extension (C1) on a nonlinear one, as Rego et al. (2020).
//!
//! * Prediction (C2): `X̄ = M X ⊕ E ⊕ W` with `f(x) ∈ M x + E` over the set's box.
//! * Update (C3): `X = X̄ ∩_M (y − E_h ⊕ (−V))`, the generalised intersection with the
//!   measurement's strip, `h(x) ∈ M x + E_h` over the predicted box (`M = C`, `E_h = 0` on a
//!   linear model).
//! * Published interval (C4): the certified interval hull (verified LP bounds) intersected with
//!   an interval observer run beside the set (C5) and with the declared state bounds; that box
//!   is also where the next extension is taken.
//! * Reduction (Z4)–(Z6) to the [`ConstrainedZonotopeSettings`] limits after every operation;
//!   at order 1 with no constraints kept the set between steps is the published box itself (C6).
//!
//! The [`Setup`] matrices are generator matrices: `X₀ = ⟨x₀, P₀⟩`, `W = ⟨0, Q⟩`, `V = ⟨0, R⟩` (a
//! diagonal matrix is the box of those half-widths; no ellipsoid is needed). A measurement whose
//! strip misses the predicted set (certified: a verified Farkas certificate, or interval bounds
//! that cross) is inconsistent data, handled by the [`DataChecks`] policy.

mod extension;

use std::borrow::Cow;

use intervals::Interval;
use nalgebra::{DMatrix, DVector};

use constrained_zonotope::{ConstrainedZonotope, ReductionLimits, SetError};
use models::{Dims, SecondOrderModel, TaylorEnclosure};

use crate::angle_branch::{self, Branch};
use crate::checks::{DataChecks, InconsistencyPolicy};
use crate::error::EstimatorError;
use crate::partial::{self, Measured, check_measured, classify};
use crate::traits::{
    DataCheck, DetailField, Estimate, EstimateKind, Guarantee, Setup, SolveOutcome, StepDetails, StepStatus,
};
use extension::{Function, boxed, contract_box, mean_value, predict_box};

/// Settings of the constrained-zonotope filters.
#[derive(Debug, Clone, PartialEq)]
pub struct ConstrainedZonotopeSettings {
    /// Generators kept per state after each reduction (the zonotope order; `order · n` factors).
    /// Order 1 with `max_constraints = 0` keeps a box between steps: the published interval
    /// itself, the tightest certified one (docs/constrained-zonotopes.md (C6)).
    pub order: usize,
    /// Equality constraints kept after each reduction.
    pub max_constraints: usize,
    /// What a step does with a measurement that contradicts the set and the noise bounds.
    pub inconsistency: InconsistencyPolicy,
    /// `(lower, upper)`: bounds the true state always respects (±∞ where none).
    pub state_bounds: Option<(DVector<f64>, DVector<f64>)>,
    /// A state's published width above this many times its initial width marks the step
    /// diverging ([`Guarantee::Diverging`]); a state with finite declared bounds is diverging
    /// when its published interval spans their whole range instead.
    pub divergence_factor: f64,
}

impl Default for ConstrainedZonotopeSettings {
    /// Order 20, 8 constraints, an error on inconsistent data, no state bounds, divergence at 2×
    /// the initial width.
    fn default() -> Self {
        Self {
            order: 20,
            max_constraints: 8,
            inconsistency: InconsistencyPolicy::Error,
            state_bounds: None,
            divergence_factor: 2.0,
        }
    }
}

const MISSED_OBSERVER: &str = "the set's certified hull and the interval observer's box do not meet";
const MISSED_STRIP: &str = "the measurement's strip misses the predicted set (a verified certificate, or certified \
                            bounds that cross)";

/// Most generators per state ([`ConstrainedZonotopeSettings::order`]).
pub const MAX_ORDER: usize = 200;

/// A constrained-zonotope filter's account of its last step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ZonotopeReport {
    /// Generators of the set after reduction.
    pub generators: usize,
    /// Constraints of the set after reduction.
    pub constraints: usize,
    /// Linear programs of the hull that gave no usable answer (their bounds fell back to
    /// propagated ranges: certified, possibly wider).
    pub lp_failures: usize,
    /// States whose published interval the interval observer or the declared bounds tightened
    /// beyond the set's own hull.
    pub tightened: usize,
    /// States wider than the divergence rule allows.
    pub diverging: usize,
}

/// The numbers a constrained-zonotope step reports beyond its status (`port-est`'s columns,
/// Python's `details`).
pub const DETAILS: &[DetailField] = &[
    DetailField { name: "generators", meaning: "generators of the set after order reduction" },
    DetailField { name: "constraints", meaning: "equality constraints of the set after reduction" },
];

impl ZonotopeReport {
    /// The report as [`StepDetails`] ([`DETAILS`]).
    #[must_use]
    pub fn details(&self) -> StepDetails {
        StepDetails::new(DETAILS, &[Some(self.generators as f64), Some(self.constraints as f64)])
    }
}

/// A guaranteed constrained zonotope and its certified interval hull.
#[derive(Debug, Clone)]
pub struct ZonotopeEstimate {
    published: Published,
    set: ConstrainedZonotope,
}

impl ZonotopeEstimate {
    /// The set itself (after reduction), `⟨c, G, A, b⟩`.
    #[must_use]
    pub fn set(&self) -> &ConstrainedZonotope {
        &self.set
    }

    /// The certified lower bounds.
    #[must_use]
    pub fn lower(&self) -> &DVector<f64> {
        &self.published.lower
    }

    /// The certified upper bounds.
    #[must_use]
    pub fn upper(&self) -> &DVector<f64> {
        &self.published.upper
    }

    /// The filter's report.
    #[must_use]
    pub fn report(&self) -> ZonotopeReport {
        self.published.report
    }
}

impl Estimate for ZonotopeEstimate {
    fn kind(&self) -> EstimateKind {
        EstimateKind::GuaranteedConstrainedZonotope
    }
    fn center(&self) -> &DVector<f64> {
        &self.published.center
    }
    fn shape(&self) -> &DMatrix<f64> {
        &self.published.shape
    }
    fn bounds(&self, i: usize) -> Option<(f64, f64)> {
        let p = &self.published;
        (i < p.lower.len()).then(|| (p.lower[i], p.upper[i]))
    }
    fn status(&self) -> StepStatus {
        self.published.status
    }
    fn details(&self) -> StepDetails {
        self.published.report.details()
    }
    fn constrained_zonotope(&self) -> Option<&ConstrainedZonotope> {
        Some(&self.set)
    }
}

/// The constrained-zonotope filter (module documentation).
#[derive(Debug, Clone)]
pub struct ConstrainedZonotopeFilter {
    dims: Dims,
    observer: Vec<Interval>,
    w: ConstrainedZonotope,
    w_radius: Vec<f64>,
    v_generators: DMatrix<f64>,
    v_radius: Vec<f64>,
    limits: ReductionLimits,
    /// Order 1, no constraints: the set kept between steps is the published box (C6).
    box_between_steps: bool,
    checks: DataChecks,
    bounds: Option<(Vec<f64>, Vec<f64>)>,
    initial_width: Vec<f64>,
    divergence_factor: f64,
    step: u64,
    last_u: DVector<f64>,
    lost: bool,
    estimate: ZonotopeEstimate,
    f_enclosure: TaylorEnclosure,
    h_enclosure: TaylorEnclosure,
}

fn set_error(what: &'static str, e: SetError) -> EstimatorError {
    EstimatorError::InvalidConfiguration { estimator: "constrained-zonotope filter", message: format!("{what}: {e}") }
}

fn guarantee_lost(step: u64, reason: String) -> EstimatorError {
    EstimatorError::GuaranteeLost { step, reason }
}

/// The box radii of the zonotope `⟨0, G⟩`.
fn radii(g: &DMatrix<f64>) -> Vec<f64> {
    let z = ConstrainedZonotope::zonotope(DVector::zeros(g.nrows()), g.clone());
    z.map(|z| z.zonotope_hull().1.iter().copied().collect()).unwrap_or_else(|_| vec![f64::INFINITY; g.nrows()])
}

/// What a step publishes besides its set: the centre and shape, the certified interval, the
/// status and the report ([`Published::with_set`] attaches the set).
#[derive(Debug, Clone)]
struct Published {
    center: DVector<f64>,
    shape: DMatrix<f64>,
    lower: DVector<f64>,
    upper: DVector<f64>,
    status: StepStatus,
    report: ZonotopeReport,
}

impl Published {
    /// The estimate of the (reduced) `set`, its size in the report.
    fn with_set(self, set: ConstrainedZonotope) -> ZonotopeEstimate {
        let mut published = self;
        published.report.generators = set.generators();
        published.report.constraints = set.constraints();
        ZonotopeEstimate { published, set }
    }
}

/// The outcome of an update, before it is committed (the set is the estimate's).
struct Updated {
    observer: Vec<Interval>,
    estimate: ZonotopeEstimate,
    lost: bool,
}

impl ConstrainedZonotopeFilter {
    /// A filter from `setup` (generator matrices: module documentation) and `settings`.
    ///
    /// # Errors
    /// Wrong sizes, non-finite entries, settings out of range (order `1..=MAX_ORDER`, a
    /// divergence factor above 1), bounds that exclude the initial set.
    pub fn new(setup: Setup, settings: ConstrainedZonotopeSettings) -> Result<Self, EstimatorError> {
        let dims = setup.dims();
        let (n, m) = (dims.states, dims.outputs);
        crate::validate::check_finite("x0", setup.x0.as_slice())?;
        crate::validate::check_shape(("rows of P0", "columns of P0"), &setup.p0, n, n)?;
        crate::validate::check_shape(("rows of Q", "columns of Q"), &setup.process_noise, n, n)?;
        crate::validate::check_shape(("rows of R", "columns of R"), &setup.measurement_noise, m, m)?;
        crate::validate::check_finite("P0", setup.p0.as_slice())?;
        crate::validate::check_finite("Q", setup.process_noise.as_slice())?;
        crate::validate::check_finite("R", setup.measurement_noise.as_slice())?;
        if !(1..=MAX_ORDER).contains(&settings.order) {
            return Err(EstimatorError::InvalidSetting {
                what: "order",
                value: settings.order as f64,
                requirement: "an integer from 1 to 200",
            });
        }
        if settings.divergence_factor.is_nan() || settings.divergence_factor <= 1.0 {
            return Err(EstimatorError::InvalidSetting {
                what: "divergence_factor",
                value: settings.divergence_factor,
                requirement: "above 1 (a finite number, or infinity for no rule)",
            });
        }
        let max_generators = settings.order.saturating_mul(n.max(1));
        if max_generators < n + settings.max_constraints {
            return Err(EstimatorError::InvalidSetting {
                what: "max_constraints",
                value: settings.max_constraints as f64,
                requirement: "at most order·n − n (a generator reduction boxes n + constraints factors)",
            });
        }
        let limits = ReductionLimits::new(max_generators, settings.max_constraints)
            .map_err(|e| set_error("reduction limits", e))?;
        let set = ConstrainedZonotope::zonotope(setup.x0.clone(), setup.p0.clone()).map_err(|e| set_error("X0", e))?;
        let w = ConstrainedZonotope::zonotope(DVector::zeros(n), setup.process_noise.clone())
            .map_err(|e| set_error("W", e))?;
        let w_radius = radii(&setup.process_noise);
        let v_radius = radii(&setup.measurement_noise);
        let bounds = match settings.state_bounds {
            None => None,
            Some((lo, hi)) => {
                for (what, v) in [("x_lower", &lo), ("x_upper", &hi)] {
                    if v.len() != n {
                        return Err(EstimatorError::DimensionMismatch { what, expected: n, found: v.len() });
                    }
                }
                // ±∞ where a state has no bound; NaN, an empty range or a bound that excludes
                // every number are refused.
                let bad = |i: usize| {
                    lo[i].is_nan()
                        || hi[i].is_nan()
                        || lo[i] > hi[i]
                        || lo[i] == f64::INFINITY
                        || hi[i] == f64::NEG_INFINITY
                };
                if let Some(i) = (0..n).find(|&i| bad(i)) {
                    return Err(EstimatorError::InvalidSetting {
                        what: "x_lower/x_upper",
                        value: i as f64,
                        requirement: "lower ≤ upper at every state, each finite or ±∞ on its own side (the value is \
                                      the state's index)",
                    });
                }
                Some((lo.iter().copied().collect(), hi.iter().copied().collect()))
            }
        };
        let (lo, hi) = set.zonotope_hull();
        let initial_width: Vec<f64> = (0..n).map(|i| hi[i] - lo[i]).collect();
        let mut filter = Self {
            dims,
            observer: boxed(&lo, &hi),
            w,
            w_radius,
            v_generators: setup.measurement_noise.clone(),
            v_radius,
            limits,
            box_between_steps: settings.order == 1 && settings.max_constraints == 0,
            checks: DataChecks::with_policy(settings.inconsistency),
            bounds,
            initial_width,
            divergence_factor: settings.divergence_factor,
            step: 0,
            last_u: DVector::zeros(dims.inputs),
            lost: false,
            estimate: ZonotopeEstimate {
                published: Published {
                    center: DVector::zeros(n),
                    shape: DMatrix::zeros(n, n),
                    lower: lo,
                    upper: hi,
                    status: StepStatus {
                        outcome: SolveOutcome::Initial,
                        data: DataCheck::NotChecked,
                        guarantee: Guarantee::Holds,
                    },
                    report: ZonotopeReport::default(),
                },
                set: ConstrainedZonotope::zonotope(DVector::zeros(n), DMatrix::zeros(n, 0))
                    .map_err(|e| set_error("X0", e))?,
            },
            f_enclosure: TaylorEnclosure::new(n, n),
            h_enclosure: TaylorEnclosure::new(m, n),
        };
        let hull = set.interval_hull().map_err(|e| set_error("X0", e))?;
        let status = filter.estimate.published.status;
        let (published, _) = filter.publish(&hull, filter.observer.clone(), status, 0)?;
        filter.estimate = published.with_set(set);
        Ok(filter)
    }

    /// The current estimate.
    #[must_use]
    pub fn estimate(&self) -> &ZonotopeEstimate {
        &self.estimate
    }

    /// `(n, p, m)`.
    #[must_use]
    pub fn dims(&self) -> Dims {
        self.dims
    }

    /// The data checks (every policy is supported).
    ///
    /// # Errors
    /// None.
    pub fn set_data_checks(&mut self, checks: DataChecks) -> Result<(), EstimatorError> {
        self.checks = checks;
        Ok(())
    }

    fn check_model<M: SecondOrderModel + ?Sized>(&self, model: &M) -> Result<(), EstimatorError> {
        crate::validate::check_discrete(model, self.dims.states, self.dims.inputs, self.dims.outputs)
    }

    /// The box the next extension is taken over: the published interval.
    fn current_box(&self) -> Vec<Interval> {
        boxed(&self.estimate.published.lower, &self.estimate.published.upper)
    }

    /// The published interval from a set's hull, the interval observer's box and the bounds
    /// (C4), and the observer's box cut to it; an error when they do not meet.
    fn publish(
        &self,
        hull: &constrained_zonotope::Hull,
        observer: Vec<Interval>,
        mut status: StepStatus,
        step: u64,
    ) -> Result<(Published, Vec<Interval>), EstimatorError> {
        let n = self.dims.states;
        let mut lower = DVector::zeros(n);
        let mut upper = DVector::zeros(n);
        let mut tightened = 0;
        let mut diverging = 0;
        let mut observer = observer;
        for i in 0..n {
            let mut x = Interval::new(hull.lower[i], hull.upper[i]);
            let own = x;
            if let Some((lo, hi)) = &self.bounds {
                x = x.meet(Interval::new(lo[i], hi[i])).ok_or(EstimatorError::OutsideStateBounds {
                    step,
                    state: i,
                    set_lower: own.lo(),
                    set_upper: own.hi(),
                    bound_lower: lo[i],
                    bound_upper: hi[i],
                })?;
            }
            x = x.meet(observer[i]).ok_or(EstimatorError::SetMissed { step, reason: MISSED_OBSERVER })?;
            observer[i] = x;
            if x != own {
                tightened += 1;
            }
            // A state with finite declared bounds is diverging when its interval spans them (it
            // says nothing they did not); the others when wider than `divergence_factor` times
            // their initial width.
            let spans = |lo: f64, hi: f64| lo.is_finite() && hi.is_finite() && x.lo() <= lo && x.hi() >= hi;
            match &self.bounds {
                Some((lo, hi)) if lo[i].is_finite() && hi[i].is_finite() => {
                    diverging += usize::from(spans(lo[i], hi[i]))
                }
                _ => diverging += usize::from(x.width() > self.divergence_factor * self.initial_width[i]),
            }
            lower[i] = x.lo();
            upper[i] = x.hi();
        }
        if diverging > 0 && status.guarantee == Guarantee::Holds {
            status.guarantee = Guarantee::Diverging;
        }
        let mut center = DVector::zeros(n);
        let mut shape = DMatrix::zeros(n, n);
        for i in 0..n {
            let (c, r) = Interval::new(lower[i], upper[i]).mid_rad();
            center[i] = c;
            shape[(i, i)] = r * r;
        }
        let report =
            ZonotopeReport { generators: 0, constraints: 0, lp_failures: hull.lp_failures, tightened, diverging };
        Ok((Published { center, shape, lower, upper, status, report }, observer))
    }

    /// The set kept for the next step: `set` reduced to the limits (Z4)–(Z6), or, when they hold
    /// only a box, the published box (C6) — a reduction with anything to do would end in a box
    /// containing `set`, and the published interval is the tightest box the step certified (the
    /// set's hull met with the interval observer's box and the declared bounds, each of which
    /// holds the true state).
    fn kept(&self, set: &ConstrainedZonotope, published: &Published) -> Result<ConstrainedZonotope, SetError> {
        if self.box_between_steps {
            ConstrainedZonotope::from_bounds(&published.lower, &published.upper)
        } else {
            set.reduce(&self.limits)
        }
    }

    /// (C2): the predicted set, unreduced, and the interval observer's predicted box.
    fn predicted<M: SecondOrderModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        step: u64,
    ) -> Result<(ConstrainedZonotope, Vec<Interval>), EstimatorError> {
        let x = self.current_box();
        let mv = mean_value(model, Function::Dynamics, &x, u, &mut self.f_enclosure)?
            .map_err(|reason| guarantee_lost(step, reason))?;
        let (e_mid, e_rad): (Vec<f64>, Vec<f64>) = mv.e.iter().map(|e| e.mid_rad()).unzip();
        let lost = |e: SetError| guarantee_lost(step, format!("the predicted set: {e}"));
        let set = self
            .estimate
            .set
            .affine_map(&mv.m, Some(&DVector::from_vec(e_mid)))
            .and_then(|s| s.add_box(&DVector::from_vec(e_rad)))
            .and_then(|s| s.minkowski_sum(&self.w))
            .map_err(lost)?;
        let observer = predict_box(model, &x, u, &mv, &self.w_radius, &mut self.f_enclosure)?
            .ok_or_else(|| guarantee_lost(step, "f is unbounded over the interval observer's box".into()))?;
        Ok((set, observer))
    }

    /// (C3): the update of `set` (the predicted set, whose published box is `x`) with `y`.
    fn updated<M: SecondOrderModel + ?Sized>(
        &mut self,
        model: &M,
        set: ConstrainedZonotope,
        x: Vec<Interval>,
        observer: Vec<Interval>,
        y: &DVector<f64>,
        step: u64,
        rows: Option<&[usize]>,
    ) -> Result<Updated, EstimatorError> {
        match rows {
            None => {
                crate::validate::check_vec("y", y, self.dims.outputs)?;
                crate::validate::check_finite("y", y.as_slice())?;
            }
            Some(rows) => check_measured(y, self.dims.outputs, rows)?,
        }
        let u = self.last_u.clone();
        let mv = mean_value(model, Function::Measurement, &x, &u, &mut self.h_enclosure)?
            .map_err(|reason| guarantee_lost(step, reason))?;
        // A partial measurement: the measured rows of h's extension, of y and of V's generators
        // (the projection of the zonotope V onto the measured outputs).
        let (mv, y, v_generators, v_radius_full, angle_outputs) = match rows {
            None => (
                mv,
                Cow::Borrowed(y),
                Cow::Borrowed(&self.v_generators),
                Cow::Borrowed(self.v_radius.as_slice()),
                Cow::Borrowed(model.angles().outputs),
            ),
            Some(rows) => {
                let mut angles = Vec::new();
                partial::angle_positions(rows, model.angles().outputs, &mut angles);
                let mut g = DMatrix::zeros(rows.len(), self.v_generators.ncols());
                partial::gather_rows(&self.v_generators, rows, &mut g);
                (
                    mv.select(rows),
                    Cow::Owned(DVector::from_iterator(rows.len(), rows.iter().map(|&i| y[i]))),
                    Cow::Owned(g),
                    Cow::Owned(rows.iter().map(|&i| self.v_radius[i]).collect()),
                    Cow::Owned(angles),
                )
            }
        };
        let m = y.len();
        // Angle outputs on the branch of h's enclosure over the box (module `angle_branch`).
        let n = self.dims.states;
        let mut y_err = vec![0.0; m];
        let mut y_used = DVector::zeros(m);
        let h_over_box =
            |i: usize| (0..n).fold(mv.value[i], |h, k| h + mv.jacobian[i * n + k] * (x[k] - Interval::point(mv.p[k])));
        let branch =
            angle_branch::branch(&angle_outputs, &y, h_over_box, &v_radius_full, &mut y_used, &mut y_err, step)?;
        let y = &y_used;
        // Y = (y − mid E_h) ⊕ □(rad E_h + rounding) ⊕ (−V).
        let mut yc = DVector::zeros(m);
        let mut rad = DVector::zeros(m);
        for i in 0..m {
            let (em, er) = mv.e[i].mid_rad();
            yc[i] = y[i] - em;
            rad[i] = intervals::up(er + intervals::up(f64::EPSILON * yc[i].abs()));
            if y_err[i] > 0.0 {
                rad[i] = intervals::up(rad[i] + y_err[i]);
            }
        }
        let v_radius: Vec<f64> =
            v_radius_full.iter().zip(&y_err).map(|(&v, &e)| if e > 0.0 { intervals::up(v + e) } else { v }).collect();
        let lost = |e: SetError| guarantee_lost(step, format!("the measurement update: {e}"));
        let strip =
            ConstrainedZonotope::zonotope(yc, -v_generators.as_ref()).and_then(|s| s.add_box(&rad)).map_err(lost)?;
        let checked = self.checks.policy != InconsistencyPolicy::Off;
        let candidate = set.intersect(&mv.m, &strip).map_err(lost)?;
        let hull = candidate.interval_hull().map_err(lost)?;
        let mut contracted: Vec<Interval> = observer.iter().zip(&x).filter_map(|(o, b)| o.meet(*b)).collect();
        let observer_ok = contracted.len() == x.len() && contract_box(&mut contracted, &mv, y, &v_radius).is_some();
        let consistent = !hull.certified_empty && observer_ok && branch == Branch::Chosen;
        let status = |data, lost: bool| StepStatus {
            outcome: SolveOutcome::Converged,
            data,
            guarantee: if lost { Guarantee::Lost } else { Guarantee::Holds },
        };
        if consistent {
            let data = if checked { DataCheck::Consistent } else { DataCheck::NotChecked };
            match self.publish(&hull, contracted, status(data, self.lost), step) {
                Ok((published, observer)) => {
                    let kept = self.kept(&candidate, &published).map_err(lost)?;
                    let estimate = published.with_set(kept);
                    return Ok(Updated { observer, estimate, lost: self.lost });
                }
                // The hull, the observer and the declared bounds do not meet: inconsistent too.
                Err(e) if self.checks.policy == InconsistencyPolicy::Error => return Err(e),
                Err(_) => {}
            }
        }
        if self.checks.policy == InconsistencyPolicy::Error {
            return Err(EstimatorError::SetMissed { step, reason: MISSED_STRIP });
        }
        // Flag, restart or off: the measurement cannot be used (the intersection is empty); the
        // prediction is published, and no later set is guaranteed.
        let data = if checked { DataCheck::Inconsistent } else { DataCheck::NotChecked };
        let hull = set.interval_hull().map_err(lost)?;
        let (published, observer) = self.publish(&hull, x, status(data, true), step)?;
        let kept = self.kept(&set, &published).map_err(lost)?;
        let estimate = published.with_set(kept);
        Ok(Updated { observer, estimate, lost: true })
    }

    fn commit(&mut self, up: Updated, step: u64) {
        self.observer = up.observer;
        self.estimate = up.estimate;
        self.lost = up.lost;
        self.step = step;
    }

    /// The prediction with `u_k` (C2); the filter is unchanged on error.
    ///
    /// # Errors
    /// Wrong sizes, non-finite input; [`EstimatorError::GuaranteeLost`] when `f` cannot be
    /// enclosed over the set's box.
    pub fn predict<M: SecondOrderModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
    ) -> Result<&ZonotopeEstimate, EstimatorError> {
        self.check_model(model)?;
        crate::validate::check_vec("u", u, self.dims.inputs)?;
        crate::validate::check_finite("u", u.as_slice())?;
        let step = self.step + 1;
        let (set, observer) = self.predicted(model, u, step)?;
        let hull = set.interval_hull().map_err(|e| guarantee_lost(step, e.to_string()))?;
        let status = StepStatus {
            outcome: SolveOutcome::Predicted,
            data: DataCheck::NotChecked,
            guarantee: if self.lost { Guarantee::Lost } else { Guarantee::Holds },
        };
        let (published, observer) = self.publish(&hull, observer, status, step)?;
        let kept = self.kept(&set, &published).map_err(|e| guarantee_lost(step, e.to_string()))?;
        let estimate = published.with_set(kept);
        self.last_u.copy_from(u);
        self.commit(Updated { observer, estimate, lost: self.lost }, step);
        Ok(&self.estimate)
    }

    /// The measurement update with `y_{k+1}` (C3) of the current set (the initial set before
    /// any prediction); the filter is unchanged on error.
    ///
    /// # Errors
    /// As [`ConstrainedZonotopeFilter::step`].
    pub fn update<M: SecondOrderModel + ?Sized>(
        &mut self,
        model: &M,
        y: &DVector<f64>,
    ) -> Result<&ZonotopeEstimate, EstimatorError> {
        self.check_model(model)?;
        let step = self.step;
        let x = self.current_box();
        let observer = self.observer.clone();
        let up = self.updated(model, self.estimate.set.clone(), x, observer, y, step, None)?;
        self.commit(up, step);
        Ok(&self.estimate)
    }

    /// One step: the prediction with `u_k`, then the update with `y_{k+1}`; the filter is
    /// unchanged on error.
    ///
    /// # Errors
    /// Wrong sizes, non-finite data; [`EstimatorError::GuaranteeLost`] when `f` or `h` cannot be
    /// enclosed; [`EstimatorError::InconsistentData`] (policy `Error`) when the measurement
    /// contradicts the set and the noise bounds; [`EstimatorError::OutsideStateBounds`].
    pub fn step<M: SecondOrderModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) -> Result<&ZonotopeEstimate, EstimatorError> {
        self.check_model(model)?;
        crate::validate::check_vec("u", u, self.dims.inputs)?;
        crate::validate::check_finite("u", u.as_slice())?;
        crate::validate::check_vec("y", y, self.dims.outputs)?;
        crate::validate::check_finite("y", y.as_slice())?;
        self.step_rows(model, u, y, None)
    }

    /// One step with the outputs `measured[i]` only (module `partial`): the predicted set met
    /// with the strip of the measured rows of `h` and of `V`'s generators (`V` projected onto
    /// them); none measured is [`ConstrainedZonotopeFilter::predict`], all is
    /// [`ConstrainedZonotopeFilter::step`]. Unmeasured entries of `y` are ignored.
    ///
    /// # Errors
    /// As [`ConstrainedZonotopeFilter::step`]; a mask of another length.
    pub fn step_partial<M: SecondOrderModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        measured: &[bool],
    ) -> Result<&ZonotopeEstimate, EstimatorError> {
        self.check_model(model)?;
        let mut rows = Vec::with_capacity(self.dims.outputs);
        match classify(measured, u, y, (self.dims.outputs, self.dims.inputs), &mut rows)? {
            Measured::All => self.step(model, u, y),
            Measured::Nothing => self.predict(model, u),
            Measured::Some(_) => self.step_rows(model, u, y, Some(&rows)),
        }
    }

    /// The step with the measured `rows` (`None`: all), its data checked.
    fn step_rows<M: SecondOrderModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        rows: Option<&[usize]>,
    ) -> Result<&ZonotopeEstimate, EstimatorError> {
        let step = self.step + 1;
        let (set, observer) = self.predicted(model, u, step)?;
        // The predicted box: the hull of the predicted set with the observer and the bounds. It
        // only linearises h and starts the observer's contraction: where h is affine over the
        // cheap propagated box (its Jacobian enclosure a point) no LP is needed for it.
        let quick = set.propagated_hull();
        let affine = h_is_affine(model, &boxed(&quick.lower, &quick.upper), u, &mut self.h_enclosure)?;
        let hull = if affine { quick } else { set.interval_hull().map_err(|e| guarantee_lost(step, e.to_string()))? };
        let status = StepStatus::unchecked(SolveOutcome::Predicted);
        let (_, x) = self.publish(&hull, observer, status, step)?;
        let saved_u = std::mem::replace(&mut self.last_u, u.clone());
        let result = self.updated(model, set, x.clone(), x, y, step, rows);
        match result {
            Ok(up) => {
                self.commit(up, step);
                Ok(&self.estimate)
            }
            Err(e) => {
                self.last_u = saved_u;
                Err(e)
            }
        }
    }
}

/// Whether every entry of `h`'s Jacobian enclosure over the box is a single number (`h` affine
/// there).
fn h_is_affine<M: SecondOrderModel + ?Sized>(
    model: &M,
    x: &[Interval],
    u: &DVector<f64>,
    enclosure: &mut TaylorEnclosure,
) -> Result<bool, EstimatorError> {
    model.h_enclosure(x, u, enclosure)?;
    let (rows, n) = enclosure.dims();
    Ok((0..rows).all(|i| {
        (0..n).all(|j| {
            let d = enclosure.jacobian(i, j);
            d.lo() == d.hi()
        })
    }))
}

crate::traits::forward_estimator!(impl<> for ConstrainedZonotopeFilter, SecondOrderModel, ZonotopeEstimate, partial);
