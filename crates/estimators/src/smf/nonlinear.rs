//! The nonlinear set-membership filter (`smf-nl`): the improved filter (13)–(29) on the model
//! linearised about the current centre, its Lagrange remainder bounded rigorously over the set and
//! added to the noise sets (docs/nonlinear-smf.md, equations (N1)–(N9)).
//!
//! One step from `x_k ∈ 𝓔(x̂, P)` with `x_{k+1} = f(x_k, u) + w`, `y = h(x_{k+1}, u) + v`:
//!
//! 1. the box `B = x̂ ± s`, `s_j = √P_jj` (rounded up), holds the set (N1); with declared state
//!    bounds ([`NonlinearSetMembershipFilter::with_state_bounds`]) the box cut by them and
//!    widened to hold `x̂` (N1');
//! 2. the model's enclosures ([`SecondOrderModel`]) at the point `x̂` give `f̂ ≈ f(x̂)` and
//!    `Â ≈ ∂f/∂x(x̂)` with their errors, and over `B` the Hessians; for every `x` of the set
//!    `|f_i(x) − f̂_i − Â_i (x − x̂)| ≤ ρ_i = |f_i(x̂) − f̂_i| + Σ_j |J_ij − Â_ij| s_j +
//!    ½ Σ_jk |H_ijk| s_j s_k` (N2), all in outward-rounded interval arithmetic; where the
//!    Hessians do not hold on `B`, `Â` is the midpoint of the Jacobian's enclosure over `B` and
//!    `ρ_i = |f_i(x̂) − f̂_i| + Σ_j |[J]_ij(B) − Â_ij| s_j` (N2');
//! 3. so `x_{k+1} = Â x_k + b + e + w` with `b = f̂ − Â x̂` and `e` in the box `|e_i| ≤ ρ_i`
//!    (plus the rounding of `b`), which lies in `𝓔(0, D)`, `D = diag(ρ_i Σ_j ρ_j)`, and
//!    `e + w ∈ 𝓔(0, Q')`, `Q' = (1 + 1/β) Q + (1 + β) D` (N3);
//! 4. the same for `h` about the predicted centre `x̄ = Â x̂ + b` over the predicted box `x̄ ± t`,
//!    `t_i = √(Â P Âᵀ)_ii + ρ_i + √Q_ii` (N4): `y' = y − ĥ + Ĉ x̄ = Ĉ x_{k+1} + v'` with
//!    `v' ∈ 𝓔(0, R')` (N5);
//! 5. the linear filter's certified step on `(Â, b, Ĉ)` with `Q'`, `R'` and `y'` (N6).
//!
//! The published set is certified as the linear filter's: it contains `x_{k+1}` whenever
//! `x_k ∈ 𝓔(x̂, P)`, `w ∈ 𝓔(0, Q)` and `v ∈ 𝓔(0, R)`. When an enclosure is unbounded (a function
//! undefined somewhere on the set, an overflow) or a remainder exceeds the limit
//! ([`NonlinearSmfSettings::max_remainder`]), the step returns
//! [`EstimatorError::GuaranteeLost`] and the filter is unchanged. On a linear model every
//! remainder is zero and the filter is the linear one (to rounding).

use models::{Dims, Interval, SecondOrderModel, StepMatrices, TaylorEnclosure};
use nalgebra::{DMatrix, DVector};

use super::filter::{SetEstimate, SetMembershipFilter};
use super::two_multiplier::TwoMultiplierSolver;
use super::update::UpdateSolver;
use crate::angle_branch::{Branch, branch, measured};
use crate::checks::{DataChecks, InconsistencyPolicy, defined_at};
use crate::error::EstimatorError;
use crate::partial::{Measured, classify};
use crate::traits::Setup;
use crate::validate::check_vec;

/// Unit roundoff of `f64`.
const U: f64 = f64::EPSILON / 2.0;

/// The settings of the nonlinear set-membership filter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NonlinearSmfSettings {
    /// The largest remainder bound `ρ_i`, `σ_i` accepted (in the state's or the measurement's
    /// units); beyond it the linearisation no longer describes the model on the set, and the
    /// step reports [`EstimatorError::GuaranteeLost`] instead of publishing a set that has grown
    /// without limit. Default `1e6`.
    pub max_remainder: f64,
}

impl Default for NonlinearSmfSettings {
    fn default() -> Self {
        Self { max_remainder: 1e6 }
    }
}

/// The remainder bounds of the last step.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RemainderBounds {
    /// `ρ` (N2): the bound of the process model's linearisation remainder, per state.
    pub process: DVector<f64>,
    /// `σ` (N5): the bound of the measurement model's, per output.
    pub measurement: DVector<f64>,
}

#[derive(Debug, Clone)]
struct Work {
    point_f: TaylorEnclosure,
    box_f: TaylorEnclosure,
    point_h: TaylorEnclosure,
    box_h: TaylorEnclosure,
    boxed: Vec<Interval>,
    /// The point about which an enclosure is taken (`enclose_about`).
    centre: Vec<Interval>,
    /// The box over which `box_h` holds `h`'s enclosure after (N4)–(N5), and whether `point_h`
    /// then holds `h`'s values alone at the predicted centre: (N8) reuses them when its box and
    /// its point are the same bits (the same call, so the same enclosure).
    h_box: Vec<Interval>,
    h_values_at_centre: bool,
    radius: DVector<f64>,
    lin: StepMatrices,
    one: DVector<f64>,
    xbar: DVector<f64>,
    y_lin: DVector<f64>,
    q_eff: DMatrix<f64>,
    r_eff: DMatrix<f64>,
    remainders: RemainderBounds,
    /// The interval observer's box of the step (N7)–(N8), before it is published.
    obs: Vec<Interval>,
    /// The point about which `h` is expanded in (N8).
    obs_point: Vec<Interval>,
    /// `J_ik (x_k − p_k)` of one output row (N8).
    terms: Vec<Interval>,
    /// The measurement with its angle outputs on their branch, and the rounding bound of each.
    y_used: DVector<f64>,
    y_err: Vec<f64>,
    /// The plain values of `f` at the centre and `h` at the predicted centre (defined there?).
    f_plain: DVector<f64>,
    h_plain: DVector<f64>,
    /// A partial step: the measured outputs, the measured angle outputs, and `y` with the
    /// others' entries 0 (never read as data).
    rows: Vec<usize>,
    angle_rows: Vec<usize>,
    y_partial: DVector<f64>,
}

/// The nonlinear set-membership filter over any [`SecondOrderModel`], generic over the solver of
/// (29).
#[derive(Debug, Clone)]
pub struct NonlinearSetMembershipFilter<S: UpdateSolver = TwoMultiplierSolver> {
    inner: SetMembershipFilter<S>,
    dims: Dims,
    q: DMatrix<f64>,
    r: DMatrix<f64>,
    settings: NonlinearSmfSettings,
    /// Declared bounds on the state (N1'); `ENTIRE` where none.
    bounds: Vec<Interval>,
    ws: Work,
    /// The input of the pending prediction (for `h(x, u)` at the update).
    u_last: DVector<f64>,
    /// The interval observer's box (N7)–(N8): the published interval of the last step.
    observer: Vec<Interval>,
    /// Half-widths of the boxes around `Q` and `R` (`√Q_ii`, `√R_ii`, rounded up).
    w_half: Vec<f64>,
    v_half: Vec<f64>,
}

impl NonlinearSetMembershipFilter<TwoMultiplierSolver> {
    /// The filter with the exact two-multiplier solver of (29).
    ///
    /// # Errors
    /// As [`SetMembershipFilter::new`].
    pub fn new(setup: Setup) -> Result<Self, EstimatorError> {
        Self::with_solver(setup, TwoMultiplierSolver::new())
    }
}

/// Why (N8) refused a step.
const OBSERVER_MISSED: &str = "the interval observer's box and the measurement's strip do not meet (a certified \
                               contradiction of the data and the noise bounds)";

/// Why an angle measurement refused a step.
const ANGLE_MISSED: &str = "an angle output has no branch within h over the predicted box plus the noise bound (a \
                            certified contradiction of the data and the noise bounds)";

fn guarantee_lost(step: u64, reason: impl Into<String>) -> EstimatorError {
    EstimatorError::GuaranteeLost { step, reason: reason.into() }
}

/// The largest entry, NaN if any is.
fn largest(v: &DVector<f64>) -> f64 {
    v.iter().copied().fold(0.0, |a, b| if b.is_nan() || b > a { b } else { a })
}

/// Whether two boxes are the same bits (so that a model's enclosure over one is its enclosure
/// over the other).
fn same_bits(a: &[Interval], b: &[Interval]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| x.lo().to_bits() == y.lo().to_bits() && x.hi().to_bits() == y.hi().to_bits())
}

/// The midpoint of a bounded interval.
fn mid(v: Interval) -> f64 {
    0.5 * v.lo() + 0.5 * v.hi()
}

/// The bound (N2) of row `i`'s linearisation remainder `|g_i(x) − ĝ_i − ℓ·(x − x̂)|` over the box
/// `x̂ ± radius` (`ĝ_i` the value used, `ℓ` the row of the linearisation): the smaller of the
/// second-order (Lagrange) bound, when the Hessians hold on the box, and the mean-value bound
/// `|g_i(x̂) − ĝ_i| + Σ_j |[J]_ij(box) − ℓ_j| s_j` (N2'), valid for every Lipschitz function —
/// both are bounds, so their minimum is one. Without Hessians only `point`'s values are read.
fn remainder(
    point: &TaylorEnclosure,
    boxed: &TaylorEnclosure,
    i: usize,
    row: impl Iterator<Item = f64>,
    radius: &DVector<f64>,
    value_used: f64,
) -> Interval {
    let at_centre = Interval::point((point.value(i) - value_used).mag());
    let second_order = boxed.hessian_valid();
    let (mut second, mut mean_value) = (at_centre, at_centre);
    let n = radius.len();
    for (j, l) in row.enumerate() {
        mean_value = mean_value + Interval::point((boxed.jacobian(i, j) - l).mag()) * radius[j];
        if second_order {
            second = second + Interval::point((point.jacobian(i, j) - l).mag()) * radius[j];
            for k in 0..n {
                let h = boxed.hessian(i, j, k).mag();
                if h != 0.0 {
                    second = second + Interval::point(0.5 * h) * radius[j] * radius[k];
                }
            }
        }
    }
    if second_order && second.hi() < mean_value.hi() { second } else { mean_value }
}

/// Encloses a function over the box `centre ± radius` (`enclose` into `boxed`) and at the centre
/// (into `point`, through `boxes`): the whole enclosure at the centre when the Hessians hold on
/// the box, for the second-order bound, the value alone (`enclose_value`) otherwise — the
/// mean-value bound (N2') needs no Jacobian at the centre, and the linearisation is then the
/// midpoint of the box's Jacobian, which makes that bound least. Returns whether the
/// linearisation comes from the centre's Jacobian; `what` names the function and `centre_name`
/// the point in a [`EstimatorError::GuaranteeLost`].
#[allow(clippy::too_many_arguments)]
fn enclose_about<E, V>(
    step: u64,
    what: &str,
    centre_name: &str,
    (centre, radius, bounds): (&DVector<f64>, &mut DVector<f64>, &[Interval]),
    (boxes, centre_box): (&mut [Interval], &mut [Interval]),
    (point, boxed): (&mut TaylorEnclosure, &mut TaylorEnclosure),
    enclose: E,
    enclose_value: V,
) -> Result<bool, EstimatorError>
where
    E: Fn(&[Interval], &mut TaylorEnclosure) -> Result<(), models::ModelError>,
    V: Fn(&[Interval], &mut TaylorEnclosure) -> Result<(), models::ModelError>,
{
    for (j, (b, (&c, r))) in boxes.iter_mut().zip(centre.iter().zip(radius.iter_mut())).enumerate() {
        *b = Interval::centered(c, *r);
        let bound = bounds[j];
        if bound != Interval::ENTIRE {
            // (N1'): the box ∩ the bounds, with the centre (the segments from it must stay inside).
            let (lo, hi) = (b.lo().max(bound.lo()), b.hi().min(bound.hi()));
            if lo > hi {
                return Err(EstimatorError::OutsideStateBounds {
                    step,
                    state: j,
                    set_lower: b.lo(),
                    set_upper: b.hi(),
                    bound_lower: bound.lo(),
                    bound_upper: bound.hi(),
                });
            }
            *b = Interval::new(lo.min(c), hi.max(c));
            let point = Interval::point(c);
            *r = (point - Interval::point(b.lo())).hi().max((Interval::point(b.hi()) - point).hi()).min(*r);
        }
    }
    enclose(boxes, boxed)?;
    if !boxed.is_bounded() {
        return Err(guarantee_lost(
            step,
            format!(
                "the Jacobian or Hessian of {what} is unbounded on the bounding box about {centre_name} (a function \
                 undefined there, or an overflow)"
            ),
        ));
    }
    for (b, c) in centre_box.iter_mut().zip(centre.iter()) {
        *b = Interval::point(*c);
    }
    let at_centre = boxed.hessian_valid();
    let bounded = if at_centre {
        enclose(centre_box, point)?;
        point.is_bounded()
    } else {
        enclose_value(centre_box, point)?;
        point.values_bounded()
    };
    if !bounded {
        return Err(guarantee_lost(step, format!("{what} or its Jacobian is undefined or overflows at {centre_name}")));
    }
    Ok(at_centre)
}

/// `Q' ⪰ Q ⊕ box(ρ)` (N3): `(1 + 1/β) Q + (1 + β) D`, `D = diag(ρ_i Σ_j ρ_j)` the least-trace
/// diagonal ellipsoid holding the box, rounding covered. `Q'` is `Q` itself when `ρ = 0`.
pub(super) fn inflate(q: &DMatrix<f64>, rho: &DVector<f64>, out: &mut DMatrix<f64>) {
    out.copy_from(q);
    let mut sum = Interval::ZERO;
    for r in rho.iter() {
        sum = sum + Interval::point(*r);
    }
    let sum = sum.hi();
    if sum <= 0.0 {
        return;
    }
    // A corner e of the box: Σ e_i²/(ρ_i S) = Σ ρ_i/S = 1 (S = Σ ρ_j, rounded up).
    let trace_d = Interval::point(sum).sqr();
    // The trace-optimal weight: tr((1 + 1/β) Q + (1 + β) D) is least at β = √(tr Q / tr D). Any
    // β > 0 gives an outer bound, so its rounding does not matter; the factors are rounded up.
    let trace_q = q.trace().max(f64::MIN_POSITIVE);
    let beta = (trace_q / trace_d.hi().max(f64::MIN_POSITIVE)).sqrt().clamp(1e-150, 1e150);
    let f1 = (Interval::point(1.0) + Interval::point(1.0) / Interval::point(beta)).hi();
    let f2 = (Interval::point(1.0) + Interval::point(beta)).hi();
    let n = q.nrows() as f64;
    let mut biggest = 0.0f64;
    for (o, qv) in out.iter_mut().zip(q.iter()) {
        *o = f1 * qv;
        biggest = biggest.max(o.abs());
    }
    for (i, r) in rho.iter().enumerate() {
        let box_part = (Interval::point(*r) * sum * f2).hi();
        out[(i, i)] += box_part;
        biggest = biggest.max(out[(i, i)].abs());
    }
    // The elementwise roundings form a symmetric error matrix of spectral norm at most
    // n · 2u · max|entry| (Gershgorin); a diagonal of twice that covers it.
    let pad = 4.0 * n * U * biggest;
    for i in 0..q.nrows() {
        out[(i, i)] += pad;
    }
}

impl<S: UpdateSolver> NonlinearSetMembershipFilter<S> {
    /// The filter with `solver`; `setup.process_noise`, `setup.measurement_noise` are the shapes
    /// of the noise ellipsoids, `setup.p0` the initial set's.
    ///
    /// # Errors
    /// As [`SetMembershipFilter::with_solver`].
    pub fn with_solver(setup: Setup, solver: S) -> Result<Self, EstimatorError> {
        let (n, p, m) = (setup.x0.len(), setup.inputs, setup.measurement_noise.nrows());
        let (q, r) = (setup.process_noise.clone(), setup.measurement_noise.clone());
        let inner = SetMembershipFilter::with_solver(Setup { inputs: 1, ..setup }, solver)?;
        let ws = Work {
            point_f: TaylorEnclosure::new(n, n),
            box_f: TaylorEnclosure::new(n, n),
            point_h: TaylorEnclosure::new(m, n),
            box_h: TaylorEnclosure::new(m, n),
            boxed: vec![Interval::ZERO; n],
            centre: vec![Interval::ZERO; n],
            h_box: vec![Interval::ZERO; n],
            h_values_at_centre: false,
            radius: DVector::zeros(n),
            lin: StepMatrices { a: DMatrix::zeros(n, n), b: DMatrix::zeros(n, 1), c: DMatrix::zeros(m, n) },
            one: DVector::from_element(1, 1.0),
            xbar: DVector::zeros(n),
            y_lin: DVector::zeros(m),
            q_eff: q.clone(),
            r_eff: r.clone(),
            remainders: RemainderBounds { process: DVector::zeros(n), measurement: DVector::zeros(m) },
            obs: vec![Interval::ZERO; n],
            obs_point: vec![Interval::ZERO; n],
            terms: vec![Interval::ZERO; n],
            y_used: DVector::zeros(m),
            y_err: vec![0.0; m],
            f_plain: DVector::zeros(n),
            h_plain: DVector::zeros(m),
            rows: Vec::with_capacity(m),
            angle_rows: Vec::with_capacity(m),
            y_partial: DVector::zeros(m),
        };
        let (w_half, v_half) = (super::observer::half_widths(&q), super::observer::half_widths(&r));
        let est = inner.estimate();
        let observer = (0..n).map(|i| Interval::new(est.lower[i], est.upper[i])).collect();
        Ok(Self {
            inner,
            dims: Dims::new(n, p, m),
            q,
            r,
            settings: NonlinearSmfSettings::default(),
            bounds: vec![Interval::ENTIRE; n],
            ws,
            u_last: DVector::zeros(p),
            observer,
            w_half,
            v_half,
        })
    }

    /// Replaces the settings.
    ///
    /// # Errors
    /// [`EstimatorError::InvalidSetting`] for a `max_remainder` that is not positive.
    pub fn with_settings(mut self, settings: NonlinearSmfSettings) -> Result<Self, EstimatorError> {
        if settings.max_remainder.is_nan() || settings.max_remainder <= 0.0 {
            return Err(EstimatorError::InvalidSetting {
                what: "max_remainder",
                value: settings.max_remainder,
                requirement: "positive",
            });
        }
        self.settings = settings;
        Ok(self)
    }

    /// Declares bounds `lower ≤ x ≤ upper` that the true state always respects — physical limits
    /// such as a vessel's largest speed (±∞ where there is none). The remainders (N2), (N5) are
    /// then bounded over the set's box intersected with these bounds (N1'), which keeps a set from
    /// feeding its own growth through a state it does not measure; the published set is
    /// guaranteed under this assumption too. A set that lies wholly outside the bounds is an
    /// [`EstimatorError::OutsideStateBounds`].
    ///
    /// # Errors
    /// [`EstimatorError::DimensionMismatch`] unless both have one entry per state;
    /// [`EstimatorError::InvalidSetting`] for a NaN or a lower bound above its upper bound.
    pub fn with_state_bounds(mut self, lower: &[f64], upper: &[f64]) -> Result<Self, EstimatorError> {
        self.bounds = super::observer::state_bounds(self.dims.states, lower, upper)?;
        Ok(self)
    }

    /// The current set.
    #[must_use]
    pub fn estimate(&self) -> &SetEstimate {
        self.inner.estimate()
    }

    /// `(n, p, m)`.
    #[must_use]
    pub fn dims(&self) -> Dims {
        self.dims
    }

    /// The remainder bounds `ρ`, `σ` of the last step.
    #[must_use]
    pub fn remainders(&self) -> &RemainderBounds {
        &self.ws.remainders
    }

    /// The data checks (as the linear filter's).
    ///
    /// # Errors
    /// As [`SetMembershipFilter::set_data_checks`].
    pub fn set_data_checks(&mut self, checks: DataChecks) -> Result<(), EstimatorError> {
        self.inner.set_data_checks(checks)
    }

    fn check<M: SecondOrderModel + ?Sized>(&self, model: &M) -> Result<(), EstimatorError> {
        let d = model.dims();
        for (what, expected, found) in [
            ("model states", self.dims.states, d.states),
            ("model inputs", self.dims.inputs, d.inputs),
            ("model outputs", self.dims.outputs, d.outputs),
        ] {
            if expected != found {
                return Err(EstimatorError::DimensionMismatch { what, expected, found });
            }
        }
        Ok(model.angles().validate(d)?)
    }

    /// (N1)–(N3): linearises `f` about the centre of the current set: `ws.lin.a`, `ws.lin.b`,
    /// `ws.remainders.process`, `ws.q_eff`, and the predicted centre `ws.xbar` with the predicted
    /// box's half-widths in `ws.radius`.
    fn linearise_f<M: SecondOrderModel + ?Sized>(&mut self, model: &M, u: &DVector<f64>) -> Result<(), EstimatorError> {
        let step = self.inner.steps() + 1;
        let n = self.dims.states;
        let est = self.inner.estimate();
        let ws = &mut self.ws;
        for j in 0..n {
            ws.radius[j] = Interval::point(est.shape[(j, j)].max(0.0)).sqrt().hi();
        }
        let plain = model.f(&est.center, u, &mut ws.f_plain);
        defined_at("f", "the set's centre", plain, &ws.f_plain).map_err(|reason| guarantee_lost(step, reason))?;
        let at_centre = enclose_about(
            step,
            "f",
            "the set's centre",
            (&est.center, &mut ws.radius, &self.bounds),
            (&mut ws.boxed, &mut ws.centre),
            (&mut ws.point_f, &mut ws.box_f),
            |x, out| model.f_enclosure(x, u, out),
            |x, out| model.f_value_enclosure(x, u, out),
        )?;
        let jacobian = if at_centre { &ws.point_f } else { &ws.box_f };
        for i in 0..n {
            let value = ws.point_f.value(i);
            let f_hat = mid(value);
            let mut b = Interval::point(f_hat);
            for j in 0..n {
                let a = mid(jacobian.jacobian(i, j));
                ws.lin.a[(i, j)] = a;
                b = b - Interval::point(a) * est.center[j];
            }
            let b_mid = mid(b);
            ws.lin.b[(i, 0)] = b_mid;
            let rho = remainder(&ws.point_f, &ws.box_f, i, ws.lin.a.row(i).iter().copied(), &ws.radius, f_hat);
            ws.remainders.process[i] = (rho + (b - b_mid).mag()).hi();
        }
        let worst = largest(&ws.remainders.process);
        if worst.is_nan() || worst > self.settings.max_remainder {
            return Err(guarantee_lost(
                step,
                format!(
                    "the linearisation remainder of f reaches {worst:e}, beyond max_remainder = {:e}: the set has \
                     outgrown the model's linearisation",
                    self.settings.max_remainder
                ),
            ));
        }
        inflate(&self.q, &ws.remainders.process, &mut ws.q_eff);
        // (N4): the predicted centre and the predicted box.
        for i in 0..n {
            let mut xbar = Interval::point(ws.lin.b[(i, 0)]);
            let mut apa = Interval::ZERO;
            for j in 0..n {
                let a_ij = ws.lin.a[(i, j)];
                xbar = xbar + Interval::point(est.center[j]) * a_ij;
                // (P Aᵀ)_ji, then its product with a_ij: n² + n products per row, not 2n².
                let mut pa = Interval::ZERO;
                for k in 0..n {
                    pa = pa + Interval::point(est.shape[(j, k)]) * ws.lin.a[(i, k)];
                }
                apa = apa + pa * a_ij;
            }
            let centre = mid(xbar);
            ws.xbar[i] = centre;
            let half = Interval::point(apa.hi().max(0.0)).sqrt()
                + ws.remainders.process[i]
                + Interval::point(self.q[(i, i)].max(0.0)).sqrt()
                + (xbar - centre).mag();
            ws.radius[i] = half.hi();
        }
        Ok(())
    }

    /// (N4)–(N5): linearises `h` about `ws.xbar` over `ws.xbar ± ws.radius`: `ws.lin.c`,
    /// `ws.y_lin`, `ws.remainders.measurement`, `ws.r_eff`.
    fn linearise_h<M: SecondOrderModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        partial: bool,
    ) -> Result<(), EstimatorError> {
        let step = self.inner.steps() + 1;
        let (n, m) = (self.dims.states, self.dims.outputs);
        let ws = &mut self.ws;
        let plain = model.h(&ws.xbar, u, &mut ws.h_plain);
        defined_at("h", "the predicted centre", plain, &ws.h_plain).map_err(|reason| guarantee_lost(step, reason))?;
        let at_centre = enclose_about(
            step,
            "h",
            "the predicted centre",
            (&ws.xbar, &mut ws.radius, &self.bounds),
            (&mut ws.boxed, &mut ws.centre),
            (&mut ws.point_h, &mut ws.box_h),
            |x, out| model.h_enclosure(x, u, out),
            |x, out| model.h_value_enclosure(x, u, out),
        )?;
        ws.h_box.copy_from_slice(&ws.boxed);
        ws.h_values_at_centre = !at_centre;
        let jacobian = if at_centre { &ws.point_h } else { &ws.box_h };
        for i in 0..m {
            let value = ws.point_h.value(i);
            let h_hat = mid(value);
            let mut y_lin = measured(ws.y_used[i], ws.y_err[i]) - h_hat;
            for j in 0..n {
                let c = mid(jacobian.jacobian(i, j));
                ws.lin.c[(i, j)] = c;
                y_lin = y_lin + Interval::point(c) * ws.xbar[j];
            }
            let y_mid = mid(y_lin);
            ws.y_lin[i] = y_mid;
            let sigma = remainder(&ws.point_h, &ws.box_h, i, ws.lin.c.row(i).iter().copied(), &ws.radius, h_hat);
            ws.remainders.measurement[i] = (sigma + (y_lin - y_mid).mag()).hi();
        }
        if partial {
            // The unmeasured rows are not used: no remainder of theirs inflates R (below).
            for i in 0..m {
                if ws.rows.binary_search(&i).is_err() {
                    ws.remainders.measurement[i] = 0.0;
                }
            }
        }
        // Over the measured outputs only in a partial step (the others' rows are not used).
        let worst = if partial {
            ws.rows.iter().fold(0.0_f64, |a, &i| {
                let v = ws.remainders.measurement[i];
                if v.is_nan() || v > a { v } else { a }
            })
        } else {
            largest(&ws.remainders.measurement)
        };
        if worst.is_nan() || worst > self.settings.max_remainder {
            return Err(guarantee_lost(
                step,
                format!(
                    "the linearisation remainder of h reaches {worst:e}, beyond max_remainder = {:e}",
                    self.settings.max_remainder
                ),
            ));
        }
        inflate(&self.r, &ws.remainders.measurement, &mut ws.r_eff);
        Ok(())
    }

    /// One step (N1)–(N6). On error the filter is unchanged. Allocation-free after the first
    /// step with the two-multiplier solver.
    ///
    /// # Errors
    /// Wrong dimensions, non-finite data; [`EstimatorError::GuaranteeLost`] when a remainder
    /// cannot be bounded; the linear filter's errors ([`EstimatorError::InconsistentData`] when
    /// `y` contradicts the predicted set and the inflated noise bounds).
    pub fn step<M: SecondOrderModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) -> Result<&SetEstimate, EstimatorError> {
        self.check(model)?;
        check_vec("u", u, self.dims.inputs)?;
        check_vec("y", y, self.dims.outputs)?;
        self.linearise_f(model, u)?;
        self.observer_predict(model, u)?;
        let off_branch = self.branch_angles(model, u, y, false)?;
        self.linearise_h(model, u, false)?;
        let contradicted = self.observer_update(model, u, false)? || off_branch;
        self.apply_noise()?;
        let Self { inner, ws, .. } = self;
        if let Err(e) = inner.step(&ws.lin, &ws.one, &ws.y_lin) {
            self.restore_noise();
            return Err(e);
        }
        self.u_last.copy_from(u);
        Ok(self.published(contradicted))
    }

    /// One step with the outputs where `measured` is true (the others' entries of `y` are not
    /// read and may be NaN): `h`'s measured rows linearised and their remainders bounded, the
    /// measured angle outputs put on their branch, the observer contracted by the measured rows,
    /// and the linear filter's partial step (the sub-block of `R'`: the projection of its
    /// ellipsoid). Every output measured: [`Self::step`]; none: [`Self::predict`]. On error the
    /// filter is unchanged.
    ///
    /// # Errors
    /// As [`Self::step`]; a mask or `y` of another length than `m`.
    pub fn step_partial<M: SecondOrderModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        measured: &[bool],
    ) -> Result<&SetEstimate, EstimatorError> {
        self.check(model)?;
        let (m, p) = (self.dims.outputs, self.dims.inputs);
        match classify(measured, u, y, (m, p), &mut self.ws.rows)? {
            Measured::All => return self.step(model, u, y),
            Measured::Nothing => return self.predict(model, u),
            Measured::Some(_) => {}
        }
        let ws = &mut self.ws;
        ws.y_partial.fill(0.0);
        for &i in &ws.rows {
            ws.y_partial[i] = y[i];
        }
        let y = std::mem::take(&mut self.ws.y_partial);
        let result = self.step_measured(model, u, &y, measured);
        self.ws.y_partial = y;
        let contradicted = result?;
        self.u_last.copy_from(u);
        Ok(self.published(contradicted))
    }

    /// [`Self::step_partial`] after the mask is read (`ws.rows`; `y`'s unmeasured entries 0);
    /// whether the observer or an angle's branch found the data contradicted.
    fn step_measured<M: SecondOrderModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        measured: &[bool],
    ) -> Result<bool, EstimatorError> {
        self.linearise_f(model, u)?;
        self.observer_predict(model, u)?;
        let off_branch = self.branch_angles(model, u, y, true)?;
        self.linearise_h(model, u, true)?;
        let contradicted = self.observer_update(model, u, true)? || off_branch;
        self.apply_noise()?;
        let Self { inner, ws, .. } = self;
        if let Err(e) = inner.step_partial(&ws.lin, &ws.one, &ws.y_lin, measured) {
            self.restore_noise();
            return Err(e);
        }
        Ok(contradicted)
    }

    /// The measurement into `ws.y_used`, its angle outputs moved to their branch in `h` over the
    /// predicted observer box `ws.obs` widened by `V`'s box (module `angle_branch`). Returns whether
    /// an angle output has no representative there (the data contradict the set; with the default
    /// policy the step is refused).
    fn branch_angles<M: SecondOrderModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        y: &DVector<f64>,
        partial: bool,
    ) -> Result<bool, EstimatorError> {
        let step = self.inner.steps() + 1;
        let ws = &mut self.ws;
        let mut outputs = model.angles().outputs;
        if partial {
            // The measured angle outputs only (`ws.rows` is sorted, as the angles are).
            ws.angle_rows.clear();
            ws.angle_rows.extend(outputs.iter().copied().filter(|i| ws.rows.binary_search(i).is_ok()));
            outputs = &ws.angle_rows;
        }
        if !outputs.is_empty() {
            model.h_value_enclosure(&ws.obs, u, &mut ws.box_h)?;
        }
        let box_h = &ws.box_h;
        let found = branch(outputs, y, |i| box_h.value(i), &self.v_half, &mut ws.y_used, &mut ws.y_err, step)?;
        if found == Branch::Contradicted && self.inner.inconsistency_policy() == InconsistencyPolicy::Error {
            return Err(EstimatorError::SetMissed { step, reason: ANGLE_MISSED });
        }
        Ok(found == Branch::Contradicted)
    }

    /// (N7): the interval observer's prediction over its last box `O`: `f`'s natural interval
    /// extension plus `W`'s box, met with the linearisation's predicted box (N4); the latter is
    /// then narrowed, about its centre, to what the meet leaves (a sound box for the remainder of
    /// `h`). Into `ws.obs`.
    fn observer_predict<M: SecondOrderModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
    ) -> Result<(), EstimatorError> {
        let ws = &mut self.ws;
        model.f_value_enclosure(&self.observer, u, &mut ws.box_f)?;
        for i in 0..self.dims.states {
            let linearised = Interval::centered(ws.xbar[i], ws.radius[i]);
            let natural = ws.box_f.value(i) + Interval::new(-self.w_half[i], self.w_half[i]);
            let met = if natural.is_bounded() { natural.meet(linearised) } else { None };
            ws.obs[i] = met.unwrap_or(linearised);
            if let Some(b) = met {
                let c = Interval::point(ws.xbar[i]);
                let reach = (c - Interval::point(b.lo())).hi().max((Interval::point(b.hi()) - c).hi());
                ws.radius[i] = ws.radius[i].min(reach);
            }
        }
        Ok(())
    }

    /// (N8): `ws.obs` contracted by the measurement: `yᵢ − vᵢ ∈ hᵢ(p) + Σ_k J_ik (x_k − p_k)` for
    /// every `x` in the box (`J` the Jacobian enclosure over it, `p` its midpoint), solved for each
    /// `x_j` whose `J_ij` excludes 0, two sweeps. Returns whether the data contradict the box and the
    /// noise bounds (a range became empty: certified); the box is then left uncontracted, and with
    /// the default policy the step is refused ([`EstimatorError::SetMissed`]).
    fn observer_update<M: SecondOrderModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
        partial: bool,
    ) -> Result<bool, EstimatorError> {
        let (n, m) = (self.dims.states, self.dims.outputs);
        let ws = &mut self.ws;
        // `box_h` and `point_h` still hold (N4)–(N5)'s enclosures: where the observer's box, or its
        // midpoint, is the same bits as theirs, the same call would return the same enclosure.
        if !same_bits(&ws.obs, &ws.h_box) {
            model.h_enclosure(&ws.obs, u, &mut ws.box_h)?;
        }
        for k in 0..n {
            ws.obs_point[k] = Interval::point(mid(ws.obs[k]));
        }
        let at_centre = ws.obs_point.iter().zip(ws.xbar.iter()).all(|(p, x)| p.lo().to_bits() == x.to_bits());
        if !(ws.h_values_at_centre && at_centre) {
            model.h_value_enclosure(&ws.obs_point, u, &mut ws.point_h)?;
        }
        if !ws.box_h.is_bounded() || !ws.point_h.values_bounded() {
            return Ok(false);
        }
        // Contract a copy (in `ws.boxed`), so a contradiction leaves `ws.obs` as predicted.
        ws.boxed.copy_from_slice(&ws.obs);
        for _ in 0..2 {
            for i in 0..m {
                if partial && ws.rows.binary_search(&i).is_err() {
                    continue;
                }
                let target = measured(ws.y_used[i], ws.y_err[i])
                    - Interval::new(-self.v_half[i], self.v_half[i])
                    - ws.point_h.value(i);
                for k in 0..n {
                    ws.terms[k] = ws.box_h.jacobian(i, k) * (ws.boxed[k] - ws.obs_point[k]);
                }
                for j in 0..n {
                    let jij = ws.box_h.jacobian(i, j);
                    if jij.lo() <= 0.0 && jij.hi() >= 0.0 {
                        continue;
                    }
                    let mut rest = Interval::ZERO;
                    for (k, t) in ws.terms.iter().enumerate() {
                        if k != j {
                            rest = rest + *t;
                        }
                    }
                    let implied = (target - rest) / jij + ws.obs_point[j];
                    if implied.is_bounded() {
                        let Some(narrowed) = ws.boxed[j].meet(implied) else {
                            if self.inner.inconsistency_policy() == InconsistencyPolicy::Error {
                                return Err(EstimatorError::SetMissed {
                                    step: self.inner.steps() + 1,
                                    reason: OBSERVER_MISSED,
                                });
                            }
                            return Ok(true);
                        };
                        ws.boxed[j] = narrowed;
                        ws.terms[j] = jij * (narrowed - ws.obs_point[j]);
                    }
                }
            }
        }
        ws.obs.copy_from_slice(&ws.boxed);
        Ok(false)
    }

    /// The inner filter's estimate, its interval cut by the declared bounds (N1') and by the
    /// interval observer's box (N7)–(N8): both hold the true state, so the cut interval does. The
    /// observer then continues from the published interval. `contradicted`: the observer proved the
    /// data inconsistent (a policy other than the default let the step through); the step is
    /// published marked inconsistent and no later set is guaranteed, as the linear filter does.
    fn published(&mut self, contradicted: bool) -> &SetEstimate {
        let Self { inner, bounds, ws, observer, .. } = self;
        let est = inner.estimate_mut();
        if !est.cut_by(bounds, &ws.obs) || contradicted {
            inner.mark_inconsistent();
        }
        let est = inner.estimate();
        for (o, (l, h)) in observer.iter_mut().zip(est.lower.iter().zip(est.upper.iter())) {
            *o = Interval::new(*l, *h);
        }
        est
    }

    /// The prediction alone: (N1)–(N3) and the linear filter's prediction with `Q'`.
    ///
    /// # Errors
    /// As [`NonlinearSetMembershipFilter::step`].
    pub fn predict<M: SecondOrderModel + ?Sized>(
        &mut self,
        model: &M,
        u: &DVector<f64>,
    ) -> Result<&SetEstimate, EstimatorError> {
        self.check(model)?;
        check_vec("u", u, self.dims.inputs)?;
        self.linearise_f(model, u)?;
        self.observer_predict(model, u)?;
        self.inner.set_process_noise(&self.ws.q_eff)?;
        let Self { inner, ws, .. } = self;
        if let Err(e) = inner.predict(&ws.lin, &ws.one) {
            let _ = self.inner.set_process_noise(&self.q);
            return Err(e);
        }
        self.u_last.copy_from(u);
        Ok(self.published(false))
    }

    /// The update after [`NonlinearSetMembershipFilter::predict`]: `h` linearised about the
    /// predicted centre over the predicted set's bounding box (N4)–(N5), then the linear filter's
    /// joint update.
    ///
    /// # Errors
    /// [`EstimatorError::UpdateWithoutPrediction`] without a pending prediction; as
    /// [`NonlinearSetMembershipFilter::step`].
    pub fn update<M: SecondOrderModel + ?Sized>(
        &mut self,
        model: &M,
        y: &DVector<f64>,
    ) -> Result<&SetEstimate, EstimatorError> {
        self.check(model)?;
        check_vec("y", y, self.dims.outputs)?;
        let est = self.inner.estimate();
        for i in 0..self.dims.states {
            self.ws.xbar[i] = est.center[i];
            self.ws.radius[i] = Interval::point(est.shape[(i, i)].max(0.0)).sqrt().hi();
        }
        self.ws.obs.copy_from_slice(&self.observer);
        let u = std::mem::take(&mut self.u_last);
        let contradicted = self.branch_angles(model, &u, y, false).and_then(|off_branch| {
            self.linearise_h(model, &u, false)?;
            Ok(self.observer_update(model, &u, false)? || off_branch)
        });
        self.u_last = u;
        let contradicted = contradicted?;
        self.inner.set_measurement_noise(&self.ws.r_eff)?;
        let Self { inner, ws, .. } = self;
        if let Err(e) = inner.update(&ws.lin, &ws.y_lin) {
            let _ = self.inner.set_measurement_noise(&self.r);
            return Err(e);
        }
        Ok(self.published(contradicted))
    }

    fn apply_noise(&mut self) -> Result<(), EstimatorError> {
        self.inner.set_noise(&self.ws.q_eff, &self.ws.r_eff)
    }

    fn restore_noise(&mut self) {
        // The declared shapes were accepted at construction: restoring them cannot fail.
        let _ = self.inner.set_noise(&self.q, &self.r);
    }
}

crate::traits::forward_estimator!(
    impl<S: UpdateSolver> for NonlinearSetMembershipFilter<S>,
    SecondOrderModel,
    SetEstimate,
    partial
);
