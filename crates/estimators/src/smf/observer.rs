//! The interval observer beside the linear set-membership filter (docs/carrier-smf.md §4.8,
//! (O1)–(O4)).
//!
//! One ellipsoid with a trace-minimising update is a poor box: a state measured to `±√R_ii` at
//! every step can stay several times wider in the ellipsoid's projection, because the trace is
//! dominated by the weakly observed states. A box `O` run beside the ellipsoid, in interval
//! arithmetic with outward rounding, holds the true state as well:
//!
//! ```text
//! (O1)  O⁺_i = Σ_j A_ij O_j + Σ_j B_ij U_j + [−√Q_ii, √Q_ii]      (U_j = u_j, or the input's box)
//! (O2)  O⁺_i ∩ [x_lower_i, x_upper_i]                              (declared state bounds)
//! (O3)  x_j ∈ (y_i − [−√R_ii, √R_ii] − Σ_{k≠j} C_ik O⁺_k) / C_ij   (every measured row i, C_ij ≠ 0; two sweeps)
//! (O4)  published interval = (x̂_i ± √P_ii) ∩ bounds ∩ O⁺,   O ← published interval
//! ```
//!
//! (`|w_i| ≤ √Q_ii` for every `w ∈ 𝓔(0, Q)`: the projection of the ellipsoid.) The ellipsoid itself
//! is not cut: the filter's set and centre are the paper's, only the published interval is
//! narrowed — so `x̂_i` may lie outside it. An empty range in (O3) proves the data inconsistent
//! with the box and the noise bounds (under the default policy an error, the filter unchanged:
//! for a full step the filter's own [`EstimatorError::InconsistentData`] when its proof finds it
//! too, else [`EstimatorError::SetMissed`]; under another policy the step is published marked inconsistent, cut by the
//! bounds only). A predicted box wholly outside the bounds is
//! [`EstimatorError::OutsideStateBounds`]. Angle outputs are put on their branch over `C_i O⁺`
//! widened by `V`'s box; a row whose enclosure spans 2π is left out of (O3) (the filter decides
//! about its guarantee). Allocation-free after construction.

use intervals::Interval;
use nalgebra::DVector;

use models::{Dims, LinearModel};

use super::consistency::InconsistencyPolicy;
use super::filter::{SetEstimate, SetMembershipFilter};
use super::input::InputModel;
use super::two_multiplier::TwoMultiplierSolver;
use super::update::UpdateSolver;
use crate::angle_branch::{measured, shift_error};
use crate::checks::DataChecks;
use crate::error::EstimatorError;
use crate::partial::{Measured, classify};
use crate::traits::forward_estimator;
use crate::validate::{check_model, check_vec};

/// The linear set-membership filter with an interval observer beside it (module
/// [`observer`](self)): the same ellipsoid, a published interval never wider than its projection,
/// the declared state bounds or the observer's box.
#[derive(Debug, Clone)]
pub struct ObservedSetMembershipFilter<S: UpdateSolver = TwoMultiplierSolver> {
    inner: SetMembershipFilter<S>,
    /// Declared bounds of the state (`ENTIRE` where none).
    bounds: Vec<Interval>,
    /// The observer's box: the last published interval.
    observer: Vec<Interval>,
    /// `√Q_ii`, `√R_ii` rounded up.
    w_half: Vec<f64>,
    v_half: Vec<f64>,
    ws: Work,
}

#[derive(Debug, Clone)]
struct Work {
    /// The box of this step: (O1)–(O2), then (O3).
    next: Vec<Interval>,
    /// (O3)'s box, contracted from `next`; copied back unless the data contradict it.
    contracted: Vec<Interval>,
    /// The measured rows of a partial step.
    rows: Vec<usize>,
    /// The measurement on its branch, the rounding of the shift, and whether the row is used.
    y_used: Vec<f64>,
    y_err: Vec<f64>,
    usable: Vec<bool>,
}

/// Why a step whose measurement misses the observer's box was refused.
const OBSERVER_MISSED: &str = "a measurement's strip misses the interval observer's box (a certified contradiction of \
                               the data, the noise bounds and the state bounds)";

/// Validates declared state bounds (`n` each; `lower ≤ upper`, no NaN, `lower < +∞`, `upper > −∞`)
/// into intervals.
///
/// # Errors
/// [`EstimatorError::DimensionMismatch`], [`EstimatorError::InvalidSetting`].
pub(crate) fn state_bounds(n: usize, lower: &[f64], upper: &[f64]) -> Result<Vec<Interval>, EstimatorError> {
    for (what, found) in [("state lower bounds", lower.len()), ("state upper bounds", upper.len())] {
        if found != n {
            return Err(EstimatorError::DimensionMismatch { what, expected: n, found });
        }
    }
    for (&lo, &hi) in lower.iter().zip(upper) {
        for (what, value) in [("state lower bound", lo), ("state upper bound", hi)] {
            if value.is_nan() {
                return Err(EstimatorError::InvalidSetting { what, value, requirement: "a number" });
            }
        }
        if lo > hi || lo == f64::INFINITY || hi == f64::NEG_INFINITY {
            return Err(EstimatorError::InvalidSetting {
                what: "state lower bound",
                value: lo,
                requirement: "finite or -inf, and not above its upper bound",
            });
        }
    }
    Ok(lower.iter().zip(upper).map(|(&lo, &hi)| Interval::new(lo, hi)).collect())
}

/// `√M_ii` rounded up, per row of a validated noise shape: the half-widths of its ellipsoid's
/// bounding box.
pub(super) fn half_widths(m: &nalgebra::DMatrix<f64>) -> Vec<f64> {
    (0..m.nrows()).map(|i| Interval::point(m[(i, i)].max(0.0)).sqrt().hi()).collect()
}

impl<S: UpdateSolver> ObservedSetMembershipFilter<S> {
    /// The filter `inner` (its set, noise and settings) with an observer starting from its
    /// published interval, no state bounds.
    #[must_use]
    pub fn new(inner: SetMembershipFilter<S>) -> Self {
        let (n, m) = (inner.n, inner.m);
        let est = inner.estimate();
        let observer = (0..n).map(|i| Interval::new(est.lower[i], est.upper[i])).collect();
        let (w_half, v_half) = (half_widths(&inner.q), half_widths(&inner.r));
        Self {
            inner,
            bounds: vec![Interval::ENTIRE; n],
            observer,
            w_half,
            v_half,
            ws: Work {
                next: vec![Interval::ZERO; n],
                contracted: vec![Interval::ZERO; n],
                rows: Vec::with_capacity(m),
                y_used: vec![0.0; m],
                y_err: vec![0.0; m],
                usable: vec![false; m],
            },
        }
    }

    /// Declares bounds the true state always respects (length `n` each, `±inf` where none): they
    /// cut the published interval and the observer's box (O2), and a state with finite bounds is
    /// `diverging` when its interval spans them. The initial interval is cut at once.
    ///
    /// # Errors
    /// Wrong lengths, NaN, `lower > upper` ([`EstimatorError::InvalidSetting`]); bounds that miss
    /// the initial set ([`EstimatorError::OutsideStateBounds`], step 0).
    pub fn with_state_bounds(mut self, lower: &[f64], upper: &[f64]) -> Result<Self, EstimatorError> {
        let bounds = state_bounds(self.inner.n, lower, upper)?;
        for (j, (b, o)) in bounds.iter().zip(&self.observer).enumerate() {
            if o.meet(*b).is_none() {
                return Err(EstimatorError::OutsideStateBounds {
                    step: 0,
                    state: j,
                    set_lower: o.lo(),
                    set_upper: o.hi(),
                    bound_lower: b.lo(),
                    bound_upper: b.hi(),
                });
            }
        }
        self.bounds = bounds;
        let entire = vec![Interval::ENTIRE; self.inner.n];
        self.inner.estimate_mut().cut_by(&self.bounds, &entire);
        self.take_published();
        Ok(self)
    }

    /// The filter beside the observer (its ellipsoid is the published set's).
    #[must_use]
    pub fn inner(&self) -> &SetMembershipFilter<S> {
        &self.inner
    }

    /// The current set estimate: the ellipsoid, its interval cut by the bounds and the observer.
    #[must_use]
    pub fn estimate(&self) -> &SetEstimate {
        self.inner.estimate()
    }

    /// Number of states, inputs, outputs.
    #[must_use]
    pub fn dims(&self) -> Dims {
        self.inner.dims()
    }

    /// Steps taken so far.
    #[must_use]
    pub fn steps(&self) -> u64 {
        self.inner.steps()
    }

    /// The data checks ([`SetMembershipFilter::set_data_checks`]); the observer follows the same
    /// policy.
    pub fn set_data_checks(&mut self, checks: DataChecks) -> Result<(), EstimatorError> {
        self.inner.set_data_checks(checks)
    }

    /// What a step does with data that contradict the noise bounds, the ellipsoid's proof or the
    /// observer's alike.
    pub fn set_inconsistency_policy(&mut self, policy: InconsistencyPolicy) {
        self.inner.set_inconsistency_policy(policy);
    }

    /// One step ([`SetMembershipFilter::step`]) with the observer's (O1)–(O4). On error the filter
    /// is unchanged.
    ///
    /// # Errors
    /// As [`SetMembershipFilter::step`]; [`EstimatorError::SetMissed`] when the measurement misses
    /// the observer's box (default policy); [`EstimatorError::OutsideStateBounds`].
    pub fn step<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) -> Result<&SetEstimate, EstimatorError> {
        let Dims { states: n, inputs: p, outputs: m } = self.dims();
        check_model(model, n, p, m)?;
        check_vec("u", u, p)?;
        check_vec("y", y, m)?;
        self.predict_box(model, u)?;
        self.ws.rows.clear();
        self.ws.rows.extend(0..m);
        let contradicted = self.contract(model, y)?;
        if self.refuses(contradicted) {
            return Err(self.refuse(Some((model, u, y))));
        }
        // The model and data are checked above: the filter's step without checking them again.
        let angles = LinearModel::angles(model).outputs;
        self.inner.step_model(&models::StepModel::new(model.a(), model.b(), model.c()), angles, u, y)?;
        Ok(self.publish(contradicted))
    }

    /// The prediction alone ([`SetMembershipFilter::predict`]) with (O1), (O2), (O4).
    ///
    /// # Errors
    /// As [`SetMembershipFilter::predict`]; [`EstimatorError::OutsideStateBounds`].
    pub fn predict<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
    ) -> Result<&SetEstimate, EstimatorError> {
        let Dims { states: n, inputs: p, outputs: m } = self.dims();
        check_model(model, n, p, m)?;
        check_vec("u", u, p)?;
        self.predict_box(model, u)?;
        self.inner.predict(model, u)?;
        Ok(self.publish(false))
    }

    /// The update after [`Self::predict`] ([`SetMembershipFilter::update`]): the predicted box (the
    /// published interval) contracted by (O3), the joint step's set cut by it (O4).
    ///
    /// # Errors
    /// As [`SetMembershipFilter::update`]; [`EstimatorError::SetMissed`] as [`Self::step`].
    pub fn update<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        y: &DVector<f64>,
    ) -> Result<&SetEstimate, EstimatorError> {
        let Dims { states: n, inputs: p, outputs: m } = self.dims();
        check_model(model, n, p, m)?;
        check_vec("y", y, m)?;
        if !self.inner.pending.armed {
            return Err(EstimatorError::UpdateWithoutPrediction { estimator: "the set-membership filter" });
        }
        self.ws.next.copy_from_slice(&self.observer);
        self.ws.rows.clear();
        self.ws.rows.extend(0..m);
        let contradicted = self.contract(model, y)?;
        if self.refuses(contradicted) {
            return Err(self.refuse::<M>(None));
        }
        self.inner.update(model, y)?;
        Ok(self.publish(contradicted))
    }

    /// A step with the outputs where `measured` is true ([`SetMembershipFilter::step_partial`]):
    /// (O3) over the measured rows only.
    ///
    /// # Errors
    /// As [`SetMembershipFilter::step_partial`] and [`Self::step`].
    pub fn step_partial<M: LinearModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        measured: &[bool],
    ) -> Result<&SetEstimate, EstimatorError> {
        let Dims { states: n, inputs: p, outputs: m } = self.dims();
        check_model(model, n, p, m)?;
        match classify(measured, u, y, (m, p), &mut self.ws.rows)? {
            Measured::All => return self.step(model, u, y),
            Measured::Nothing => return self.predict(model, u),
            Measured::Some(_) => {}
        }
        self.predict_box(model, u)?;
        let contradicted = self.contract(model, y)?;
        if self.refuses(contradicted) {
            return Err(self.refuse::<M>(None));
        }
        self.inner.step_partial(model, u, y, measured)?;
        Ok(self.publish(contradicted))
    }

    /// (O1)–(O2) into `ws.next`: `A O + B U + □W` in interval arithmetic, met with the bounds.
    fn predict_box<M: LinearModel + ?Sized>(&mut self, model: &M, u: &DVector<f64>) -> Result<(), EstimatorError> {
        let (a, b) = (model.a(), model.b());
        let input_box = match self.inner.input_model() {
            InputModel::BoundedDisturbance { lower, upper, .. } => Some((lower, upper)),
            _ => None,
        };
        for i in 0..self.observer.len() {
            let mut acc = Interval::new(-self.w_half[i], self.w_half[i]);
            for (j, o) in self.observer.iter().enumerate() {
                acc = acc + o.times(a[(i, j)]);
            }
            for j in 0..u.len() {
                let uj = match input_box {
                    Some((lo, hi)) => Interval::new(lo[j], hi[j]),
                    None => Interval::point(u[j]),
                };
                acc = acc + uj.times(b[(i, j)]);
            }
            let bound = self.bounds[i];
            self.ws.next[i] = if !acc.is_bounded() {
                bound
            } else {
                acc.meet(bound).ok_or(EstimatorError::OutsideStateBounds {
                    step: self.inner.steps() + 1,
                    state: i,
                    set_lower: acc.lo(),
                    set_upper: acc.hi(),
                    bound_lower: bound.lo(),
                    bound_upper: bound.hi(),
                })?
            };
        }
        Ok(())
    }

    /// (O3): `ws.next` contracted by the rows `ws.rows` of `C` and `y`, two sweeps. Returns
    /// whether the data contradict the box (then `ws.next` is left as predicted).
    fn contract<M: LinearModel + ?Sized>(&mut self, model: &M, y: &DVector<f64>) -> Result<bool, EstimatorError> {
        let c = model.c();
        let angles = LinearModel::angles(model).outputs;
        let Work { next, contracted, rows, y_used, y_err, usable } = &mut self.ws;
        let v = |i: usize| Interval::new(-self.v_half[i], self.v_half[i]);
        for &i in rows.iter() {
            y_used[i] = y[i];
            y_err[i] = 0.0;
            usable[i] = true;
            if angles.binary_search(&i).is_ok() {
                let mut h = v(i);
                for (k, o) in next.iter().enumerate() {
                    h = h + o.times(c[(i, k)]);
                }
                match models::angle_branch(y[i], h.lo(), h.hi()) {
                    Ok(Some(shifted)) => {
                        y_err[i] = shift_error(y[i], shifted);
                        y_used[i] = shifted;
                    }
                    Ok(None) => return Ok(true),
                    // 2π wide: this row says nothing the box can use.
                    Err(_) => usable[i] = false,
                }
            }
        }
        contracted.copy_from_slice(next);
        for _ in 0..2 {
            for &i in rows.iter() {
                if !usable[i] {
                    continue;
                }
                let target = measured(y_used[i], y_err[i]) - v(i);
                for j in 0..contracted.len() {
                    let cij = c[(i, j)];
                    if cij == 0.0 {
                        continue;
                    }
                    let mut rest = Interval::ZERO;
                    for (k, o) in contracted.iter().enumerate() {
                        if k != j {
                            rest = rest + o.times(c[(i, k)]);
                        }
                    }
                    let implied = (target - rest) / Interval::point(cij);
                    if !implied.is_bounded() {
                        continue;
                    }
                    match contracted[j].meet(implied) {
                        Some(narrowed) => contracted[j] = narrowed,
                        None => return Ok(true),
                    }
                }
            }
        }
        next.copy_from_slice(contracted);
        Ok(false)
    }

    /// A contradiction found by (O3) under the default policy, as an error (the filter
    /// unchanged): for a full step on a model without angle outputs, the filter's own
    /// [`EstimatorError::InconsistentData`] with its excess when its proof finds the data
    /// inconsistent too; otherwise [`EstimatorError::SetMissed`].
    fn refuse<M: LinearModel + ?Sized>(&mut self, full: Option<(&M, &DVector<f64>, &DVector<f64>)>) -> EstimatorError {
        let step = self.inner.steps() + 1;
        if let Some((model, u, y)) = full
            && LinearModel::angles(model).outputs.is_empty()
            && let Some(excess) =
                self.inner.proves_inconsistent(&models::StepModel::new(model.a(), model.b(), model.c()), u, y)
        {
            return EstimatorError::InconsistentData { step, excess };
        }
        EstimatorError::SetMissed { step, reason: OBSERVER_MISSED }
    }

    /// Whether a contradiction must be refused (the default policy).
    fn refuses(&self, contradicted: bool) -> bool {
        contradicted && self.inner.inconsistency_policy() == InconsistencyPolicy::Error
    }

    /// (O4) after the filter's step: its interval cut by the bounds and (unless the data
    /// contradicted it) the observer's box; the observer continues from the result. A box that
    /// misses the ellipsoid's interval, or contradicted data, mark the step inconsistent (a policy
    /// other than the default let it through): no set from now on is guaranteed.
    fn publish(&mut self, contradicted: bool) -> &SetEstimate {
        if contradicted {
            self.ws.next.fill(Interval::ENTIRE);
        }
        let met = self.inner.estimate_mut().cut_by(&self.bounds, &self.ws.next);
        if !met || contradicted {
            self.inner.mark_inconsistent();
        }
        self.take_published();
        self.inner.estimate()
    }

    /// The observer's box := the published interval.
    fn take_published(&mut self) {
        let est = self.inner.estimate();
        for (o, (l, h)) in self.observer.iter_mut().zip(est.lower.iter().zip(est.upper.iter())) {
            *o = Interval::new(*l, *h);
        }
    }
}

forward_estimator!(impl<S: UpdateSolver> for ObservedSetMembershipFilter<S>, LinearModel, SetEstimate, partial);
