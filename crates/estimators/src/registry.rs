//! Every estimator by name, in one table: the command line, the reproduction and the Python
//! package choose estimators here and contain no estimator names of their own. Adding an
//! estimator touches its own module and one row of [`ESTIMATORS`].
//!
//! A row ([`EstimatorEntry`]) says what the estimator publishes ([`EstimateKind`]), which model
//! capability it needs ([`Capability`]), which settings it takes ([`SettingsKind`]: the typed
//! [`EstimatorSettings`] variant, with its default) and how to build it from a [`Setup`]. The
//! result is an [`AnyEstimator`]: the estimator behind the object-safe [`DynEstimator`] over
//! `dyn AnyModel`, taking from the model the capability it needs (or naming the one missing).
//!
//! ```
//! use estimators::registry;
//! use estimators::{DynEstimator, Setup};
//! use models::{AnyModel, ConstantModel};
//! use nalgebra::{DMatrix, DVector};
//!
//! let model = ConstantModel::new(DMatrix::identity(1, 1) * 0.9, DMatrix::identity(1, 1), DMatrix::identity(1, 1))?;
//! let setup = Setup {
//!     x0: DVector::zeros(1),
//!     p0: DMatrix::identity(1, 1),
//!     process_noise: DMatrix::identity(1, 1) * 0.01,
//!     measurement_noise: DMatrix::identity(1, 1) * 0.1,
//!     inputs: 1,
//! };
//! for name in ["kf", "smf", "ekf", "ukf"] {
//!     let mut est = registry::build(name, setup.clone(), None)?;
//!     let e = est.step_dyn(&model as &dyn AnyModel, &DVector::zeros(1), &DVector::from_element(1, 0.1))?;
//!     assert!(e.status().is_clean(), "{name}: {}", e.status());
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use nalgebra::DVector;

use models::{AnyModel, Capability, DifferentiableModel, Dims, DiscreteModel, LinearModel, SecondOrderModel};

use crate::adaptive::{AdaptiveKalmanFilter, FuzzyScaling};
use crate::checks::DataChecks;
use crate::czf::ConstrainedZonotopeFilter;
use crate::ekf::ExtendedKalmanFilter;
use crate::error::EstimatorError;
use crate::kalman::KalmanFilter;
use crate::mhe::{MheCost, MheSettings, MovingHorizonEstimator, NonlinearMhe};
use crate::smf::{
    InconsistencyPolicy, NonlinearSetMembershipFilter, ObservedSetMembershipFilter, SdpUpdateSolver,
    SetMembershipFilter, TwoMultiplierSolver,
};
use crate::traits::{DetailField, DynEstimator, Estimate, EstimateKind, Setup};
use crate::ukf::UnscentedKalmanFilter;
use crate::yang_li;

mod keywords;
mod settings;
pub use keywords::{
    DEFAULT_MEMORY_LIMIT, KeywordContext, KeywordSource, MAX_WINDOW_ITERATIONS, read_moving_horizon, read_settings,
    read_sigma_points, show_bytes,
};
pub use settings::{
    EstimatorSettings, FuzzyAdaptiveSettings, InputBox, Keyword, SetMembershipSettings, SettingsKind, SmfSolver,
};

/// A registered estimator.
#[derive(Debug)]
pub struct EstimatorEntry {
    /// Its name (`--estimator`).
    pub name: &'static str,
    /// What it publishes.
    pub kind: EstimateKind,
    /// One line for `--help` and reports.
    pub summary: &'static str,
    /// What it needs of the model.
    pub needs: Capability,
    /// The settings it takes.
    pub settings: SettingsKind,
    /// The length of its measurement vector beyond the model's outputs (the fuzzy-adaptive
    /// filter's receiver status `[N, RTK]`: 2).
    pub extra_measurements: usize,
    /// The numbers each step reports beyond its status, with their meanings (the estimator's
    /// module declares them; the command line's columns and Python's `details` are these).
    pub details: &'static [DetailField],
    build: fn(&'static EstimatorEntry, Setup, EstimatorSettings) -> Result<Inner, EstimatorError>,
}

impl EstimatorEntry {
    /// Builds the estimator from `setup` and `settings` (the row's default when `None`).
    ///
    /// # Errors
    /// [`EstimatorError::MissingSetting`] when the row has no default and none are given;
    /// [`EstimatorError::WrongSettings`] for another row's settings; the constructor's validation
    /// errors.
    pub fn build(
        &'static self,
        setup: Setup,
        settings: Option<EstimatorSettings>,
    ) -> Result<AnyEstimator, EstimatorError> {
        let settings = match settings {
            Some(s) => s,
            None => self
                .settings
                .default_settings()
                .ok_or(EstimatorError::MissingSetting { estimator: self.name, what: self.settings.describe() })?,
        };
        if settings.kind() != self.settings {
            return Err(EstimatorError::WrongSettings {
                estimator: self.name,
                expected: self.settings.describe(),
                given: settings.kind().describe(),
            });
        }
        Ok(AnyEstimator { entry: self, inner: (self.build)(self, setup, settings)? })
    }

    /// The measurement length the estimator consumes for a model with `outputs` outputs.
    #[must_use]
    pub fn measurement_len(&self, outputs: usize) -> usize {
        outputs + self.extra_measurements
    }
}

/// The registered names, for code that runs a particular estimator (the reproduction): every name
/// is written here once.
pub mod names {
    /// The improved set-membership filter.
    pub const SMF: &str = "smf";
    /// The Kalman filter.
    pub const KF: &str = "kf";
    /// The Yang–Li reconstruction (a), input unused.
    pub const YANG_LI: &str = "yang-li";
    /// The Yang–Li reconstruction (b), input in the predictor.
    pub const YANG_LI_WITH_INPUT: &str = "yang-li-with-input";
    /// The robust min–max moving-horizon estimator.
    pub const RMHE: &str = "rmhe";
    /// Plain least-squares moving-horizon estimation.
    pub const MHE: &str = "mhe";
    /// The fuzzy-adaptive Kalman filter.
    pub const FKF: &str = "fkf";
    /// The extended Kalman filter.
    pub const EKF: &str = "ekf";
    /// The unscented Kalman filter.
    pub const UKF: &str = "ukf";
    /// The nonlinear moving-horizon estimator with a UKF arrival cost.
    pub const MHE_UKF: &str = "mhe-ukf";
    /// The nonlinear set-membership filter (certified linearisation remainder).
    pub const SMF_NL: &str = "smf-nl";
    /// The constrained-zonotope filter on linear models.
    pub const CZF: &str = "czf";
    /// The constrained-zonotope filter on nonlinear models (mean-value extension).
    pub const CZF_NL: &str = "czf-nl";
}

/// The set-membership filter built by `$build` (an expression of the solver `$t`) with the
/// settings `$s` (solver, inconsistency policy, interval observer and state bounds), behind the
/// linear adapter.
macro_rules! set_membership {
    ($e:expr, $s:expr, |$t:ident| $build:expr) => {{
        let s: &SetMembershipSettings = $s;
        match solver(s.solver.clone())? {
            Solver::Two($t) => linear_set_membership($e, s, with_policy($build?, s.inconsistency)),
            Solver::Sdp($t) => linear_set_membership($e, s, with_policy($build?, s.inconsistency)),
        }
    }};
}

/// Every registered estimator, in display order.
pub static ESTIMATORS: &[EstimatorEntry] = &[
    EstimatorEntry {
        name: names::SMF,
        kind: EstimateKind::GuaranteedEllipsoid,
        summary: "improved set-membership filter (carrier paper (13)-(29)), certified containment; an interval \
                  observer beside it narrows the published interval (docs/carrier-smf.md §4.8)",
        needs: Capability::Linear,
        settings: SettingsKind::SetMembership,
        extra_measurements: 0,
        details: crate::smf::DETAILS,
        build: |e, setup, s| {
            let EstimatorSettings::SetMembership(s) = s else { return Err(wrong_settings(e)) };
            set_membership!(e, &s, |t| SetMembershipFilter::with_solver(setup, t))
        },
    },
    EstimatorEntry {
        name: names::KF,
        kind: EstimateKind::Gaussian,
        summary: "Kalman filter, Joseph form (Q, R, P0 as covariances)",
        needs: Capability::Linear,
        settings: SettingsKind::None,
        extra_measurements: 0,
        details: &[],
        build: |e, setup, _| Ok(on_linear(e, KalmanFilter::new(setup)?)),
    },
    EstimatorEntry {
        name: names::YANG_LI,
        kind: EstimateKind::GuaranteedEllipsoid,
        summary: "reconstruction (a) of the carrier paper's reference [17]: input unused, bounded by its box",
        needs: Capability::Linear,
        settings: SettingsKind::SetMembershipInputBox,
        extra_measurements: 0,
        details: crate::smf::DETAILS,
        build: |e, setup, s| {
            let EstimatorSettings::SetMembershipInputBox(s, b) = s else { return Err(wrong_settings(e)) };
            set_membership!(e, &s, |t| yang_li::without_input(setup, &b.lower, &b.upper, t))
        },
    },
    EstimatorEntry {
        name: names::YANG_LI_WITH_INPUT,
        kind: EstimateKind::GuaranteedEllipsoid,
        summary: "reconstruction (b) of [17]: the input in the predictor (equal to smf)",
        needs: Capability::Linear,
        settings: SettingsKind::SetMembership,
        extra_measurements: 0,
        details: crate::smf::DETAILS,
        build: |e, setup, s| {
            let EstimatorSettings::SetMembership(s) = s else { return Err(wrong_settings(e)) };
            set_membership!(e, &s, |t| yang_li::with_input(setup, t))
        },
    },
    EstimatorEntry {
        name: names::RMHE,
        kind: EstimateKind::Point,
        summary: "robust min-max moving-horizon estimator with disturbance blocking (car paper), box-bounded noise; \
                  Q, R, P0 as weights",
        needs: Capability::Linear,
        settings: SettingsKind::MovingHorizon,
        extra_measurements: 0,
        details: crate::mhe::DETAILS,
        build: |e, setup, s| {
            let EstimatorSettings::MovingHorizon(s) = s else { return Err(wrong_settings(e)) };
            Ok(on_linear(e, MovingHorizonEstimator::new(setup, *s)?))
        },
    },
    EstimatorEntry {
        name: names::MHE,
        kind: EstimateKind::Point,
        summary: "plain least-squares moving-horizon estimator: the rmhe settings with the least-squares cost \
                  (lambda_v -> infinity)",
        needs: Capability::Linear,
        settings: SettingsKind::MovingHorizon,
        extra_measurements: 0,
        details: crate::mhe::DETAILS,
        build: |e, setup, s| {
            let EstimatorSettings::MovingHorizon(s) = s else { return Err(wrong_settings(e)) };
            let settings = MheSettings { cost: MheCost::LeastSquares, ..*s };
            Ok(on_linear(e, MovingHorizonEstimator::new(setup, settings)?))
        },
    },
    EstimatorEntry {
        name: names::FKF,
        kind: EstimateKind::Gaussian,
        summary: "fuzzy-adaptive Kalman filter (BDS/INS paper): R scaled every epoch by a Mamdani system of the \
                  receiver status; measurement [y, satellites, RTK code], RTK 0 = no fix",
        needs: Capability::Linear,
        settings: SettingsKind::FuzzyAdaptive,
        extra_measurements: 2,
        details: crate::adaptive::DETAILS,
        build: |e, setup, s| {
            let EstimatorSettings::FuzzyAdaptive(s) = s else { return Err(wrong_settings(e)) };
            let FuzzyAdaptiveSettings { system, horizontal } = *s;
            let scaling = FuzzyScaling::new(system).map_err(adaptive)?;
            let f = AdaptiveKalmanFilter::new(setup, scaling).and_then(|f| f.with_horizontal(horizontal));
            Ok(on_linear(e, f.map_err(adaptive)?))
        },
    },
    EstimatorEntry {
        name: names::EKF,
        kind: EstimateKind::Gaussian,
        summary: "extended Kalman filter, Joseph form (truck paper (7)-(11)); Q, R, P0 as covariances",
        needs: Capability::Differentiable,
        settings: SettingsKind::None,
        extra_measurements: 0,
        details: &[],
        build: |e, setup, _| Ok(on_differentiable(e, ExtendedKalmanFilter::new(setup)?)),
    },
    EstimatorEntry {
        name: names::UKF,
        kind: EstimateKind::Gaussian,
        summary: "unscented Kalman filter, scaled sigma points with a positive-definiteness guard (dp-vessel note); \
                  Q, R, P0 as covariances",
        needs: Capability::Discrete,
        settings: SettingsKind::Unscented,
        extra_measurements: 0,
        details: &[],
        build: |e, setup, s| {
            let EstimatorSettings::Unscented(params) = s else { return Err(wrong_settings(e)) };
            Ok(on_discrete(e, UnscentedKalmanFilter::new(setup, params)?))
        },
    },
    EstimatorEntry {
        name: names::MHE_UKF,
        kind: EstimateKind::Point,
        summary: "nonlinear moving-horizon estimator, N = 10, Gauss-Newton on the banded window, UKF arrival cost \
                  (vessel paper (21)-(37)); Q, R, P0 as weights",
        needs: Capability::Differentiable,
        settings: SettingsKind::NonlinearMovingHorizon,
        extra_measurements: 0,
        details: crate::mhe::NONLINEAR_DETAILS,
        build: |e, setup, s| {
            let EstimatorSettings::NonlinearMovingHorizon(s) = s else { return Err(wrong_settings(e)) };
            Ok(on_differentiable(e, NonlinearMhe::new(setup, *s)?))
        },
    },
    EstimatorEntry {
        name: names::SMF_NL,
        kind: EstimateKind::GuaranteedEllipsoid,
        summary: "nonlinear set-membership filter: the improved update on the model linearised about the centre, \
                  its remainder bounded over the set by interval Hessians (docs/nonlinear-smf.md), certified containment",
        needs: Capability::SecondOrder,
        settings: SettingsKind::SetMembership,
        extra_measurements: 0,
        details: crate::smf::DETAILS,
        build: |e, setup, s| {
            let EstimatorSettings::SetMembership(s) = s else { return Err(wrong_settings(e)) };
            if !s.interval_observer {
                return Err(EstimatorError::InvalidConfiguration {
                    estimator: e.name,
                    message: "its interval observer (docs/nonlinear-smf.md (N7)-(N8)) cannot be turned off".into(),
                });
            }
            let checks = DataChecks::with_policy(s.inconsistency);
            let bounds = s.state_bounds.as_ref();
            Ok(match solver(s.solver)? {
                Solver::Two(t) => {
                    let mut f = NonlinearSetMembershipFilter::with_solver(setup, t)?;
                    f.set_data_checks(checks)?;
                    on_second_order(e, with_state_bounds(f, bounds)?)
                }
                Solver::Sdp(t) => {
                    let mut f = NonlinearSetMembershipFilter::with_solver(setup, t)?;
                    f.set_data_checks(checks)?;
                    on_second_order(e, with_state_bounds(f, bounds)?)
                }
            })
        },
    },
    EstimatorEntry {
        name: names::CZF,
        kind: EstimateKind::GuaranteedConstrainedZonotope,
        summary: "constrained-zonotope filter (Scott et al. 2016): the exact set of a linear model with boxed noise, \
                  reduced to its order; verified interval hull, interval observer, p0/q/r as box half-widths \
                  (docs/constrained-zonotopes.md)",
        needs: Capability::Linear,
        settings: SettingsKind::ConstrainedZonotope,
        extra_measurements: 0,
        details: crate::czf::DETAILS,
        build: |e, setup, s| {
            let EstimatorSettings::ConstrainedZonotope(s) = s else { return Err(wrong_settings(e)) };
            Ok(on_linear(e, ConstrainedZonotopeFilter::new(setup, s)?))
        },
    },
    EstimatorEntry {
        name: names::CZF_NL,
        kind: EstimateKind::GuaranteedConstrainedZonotope,
        summary: "nonlinear constrained-zonotope filter: the mean-value extension of f and h over the set's box \
                  (Rego et al. 2020), verified interval hull, interval observer (docs/constrained-zonotopes.md)",
        needs: Capability::SecondOrder,
        settings: SettingsKind::ConstrainedZonotope,
        extra_measurements: 0,
        details: crate::czf::DETAILS,
        build: |e, setup, s| {
            let EstimatorSettings::ConstrainedZonotope(s) = s else { return Err(wrong_settings(e)) };
            Ok(on_second_order(e, ConstrainedZonotopeFilter::new(setup, s)?))
        },
    },
];

/// The entry called `name`.
#[must_use]
pub fn entry(name: &str) -> Option<&'static EstimatorEntry> {
    ESTIMATORS.iter().find(|e| e.name == name)
}

/// The entry called `name`, or an error listing the known names.
///
/// # Errors
/// [`EstimatorError::UnknownEstimator`].
pub fn lookup(name: &str) -> Result<&'static EstimatorEntry, EstimatorError> {
    entry(name).ok_or_else(|| EstimatorError::UnknownEstimator {
        name: name.to_owned(),
        known: ESTIMATORS.iter().map(|e| e.name).collect::<Vec<_>>().join(", "),
    })
}

/// Builds the estimator `name` (see [`EstimatorEntry::build`]).
///
/// # Errors
/// [`EstimatorError::UnknownEstimator`] and the errors of [`EstimatorEntry::build`].
pub fn build(name: &str, setup: Setup, settings: Option<EstimatorSettings>) -> Result<AnyEstimator, EstimatorError> {
    lookup(name)?.build(setup, settings)
}

/// The estimators that run on `model` (its capability covers theirs).
pub fn runs_on(model: &dyn AnyModel) -> impl Iterator<Item = &'static EstimatorEntry> {
    let offered = Capability::of(model);
    ESTIMATORS.iter().filter(move |e| e.needs <= offered)
}

type Inner = Box<dyn for<'m> DynEstimator<dyn AnyModel + 'm> + Send>;

/// An estimator built from the registry: any estimator behind [`DynEstimator`] over
/// `dyn AnyModel`, with its registry entry. A step takes from the model the capability the
/// estimator needs and returns [`EstimatorError::ModelLacksCapability`] when it is missing. It is
/// `Send`: it may run on another thread (a worker, a Python call that releases the GIL).
pub struct AnyEstimator {
    entry: &'static EstimatorEntry,
    inner: Inner,
}

impl std::fmt::Debug for AnyEstimator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AnyEstimator").field("name", &self.entry.name).finish_non_exhaustive()
    }
}

impl AnyEstimator {
    /// Its registry entry.
    #[must_use]
    pub fn entry(&self) -> &'static EstimatorEntry {
        self.entry
    }

    /// One step (see [`Estimator::step`](crate::Estimator::step)).
    ///
    /// # Errors
    /// The estimator's errors; [`EstimatorError::ModelLacksCapability`].
    pub fn step(
        &mut self,
        model: &dyn AnyModel,
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) -> Result<&dyn Estimate, EstimatorError> {
        self.inner.step_dyn(model, u, y)
    }

    /// A prediction (see [`Estimator::predict`](crate::Estimator::predict)).
    ///
    /// # Errors
    /// As [`AnyEstimator::step`].
    pub fn predict(&mut self, model: &dyn AnyModel, u: &DVector<f64>) -> Result<&dyn Estimate, EstimatorError> {
        self.inner.predict_dyn(model, u)
    }

    /// A measurement update (see [`Estimator::update`](crate::Estimator::update)).
    ///
    /// # Errors
    /// As [`AnyEstimator::step`].
    pub fn update(&mut self, model: &dyn AnyModel, y: &DVector<f64>) -> Result<&dyn Estimate, EstimatorError> {
        self.inner.update_dyn(model, y)
    }

    /// A step in which only the outputs with `measured[i]` were taken (see
    /// [`Estimator::step_partial`](crate::Estimator::step_partial)); an estimator that updates
    /// with every output at once refuses a proper subset by its registry name.
    ///
    /// # Errors
    /// As [`AnyEstimator::step`].
    pub fn step_partial(
        &mut self,
        model: &dyn AnyModel,
        u: &DVector<f64>,
        y: &DVector<f64>,
        measured: &[bool],
    ) -> Result<&dyn Estimate, EstimatorError> {
        let name = self.entry.name;
        self.inner.step_partial_dyn(model, u, y, measured).map_err(|e| match e {
            EstimatorError::Unsupported { estimator: "this estimator", operation, reason } => {
                EstimatorError::Unsupported { estimator: name, operation, reason }
            }
            e => e,
        })
    }

    /// The current estimate.
    #[must_use]
    pub fn estimate(&self) -> &dyn Estimate {
        self.inner.estimate_dyn()
    }

    /// The lengths of the state, the input and the measurement it consumes.
    #[must_use]
    pub fn dims(&self) -> Dims {
        self.inner.dims_dyn()
    }

    /// The data checks (see [`Estimator::set_data_checks`](crate::Estimator::set_data_checks)).
    ///
    /// # Errors
    /// As [`Estimator::set_data_checks`](crate::Estimator::set_data_checks).
    pub fn set_data_checks(&mut self, checks: DataChecks) -> Result<(), EstimatorError> {
        self.inner.set_data_checks_dyn(checks)
    }
}

impl<'m> DynEstimator<dyn AnyModel + 'm> for AnyEstimator {
    fn step_dyn(
        &mut self,
        model: &(dyn AnyModel + 'm),
        u: &DVector<f64>,
        y: &DVector<f64>,
    ) -> Result<&dyn Estimate, EstimatorError> {
        self.inner.step_dyn(model, u, y)
    }
    fn predict_dyn(&mut self, model: &(dyn AnyModel + 'm), u: &DVector<f64>) -> Result<&dyn Estimate, EstimatorError> {
        self.inner.predict_dyn(model, u)
    }
    fn update_dyn(&mut self, model: &(dyn AnyModel + 'm), y: &DVector<f64>) -> Result<&dyn Estimate, EstimatorError> {
        self.inner.update_dyn(model, y)
    }
    fn step_partial_dyn(
        &mut self,
        model: &(dyn AnyModel + 'm),
        u: &DVector<f64>,
        y: &DVector<f64>,
        measured: &[bool],
    ) -> Result<&dyn Estimate, EstimatorError> {
        self.step_partial(model, u, y, measured)
    }
    fn estimate_dyn(&self) -> &dyn Estimate {
        self.inner.estimate_dyn()
    }
    fn dims_dyn(&self) -> Dims {
        self.inner.dims_dyn()
    }
    fn set_data_checks_dyn(&mut self, checks: DataChecks) -> Result<(), EstimatorError> {
        self.inner.set_data_checks_dyn(checks)
    }
}

/// The set-membership filter's solver, built.
enum Solver {
    Two(TwoMultiplierSolver),
    Sdp(SdpUpdateSolver),
}

/// Builds the solver of (29).
fn solver(solver: SmfSolver) -> Result<Solver, EstimatorError> {
    Ok(match solver {
        SmfSolver::TwoMultiplier => Solver::Two(TwoMultiplierSolver::new()),
        SmfSolver::Sdp { backend, settings } => Solver::Sdp(SdpUpdateSolver::by_name(backend, settings)?),
    })
}

fn with_policy<S: crate::smf::UpdateSolver>(
    mut filter: SetMembershipFilter<S>,
    policy: InconsistencyPolicy,
) -> SetMembershipFilter<S> {
    filter.set_inconsistency_policy(policy);
    filter
}

/// A linear set-membership filter as the settings ask: with its interval observer and the state
/// bounds (which only the observer can use: without it they are refused rather than ignored), or
/// alone.
fn linear_set_membership<S: crate::smf::UpdateSolver + Send + 'static>(
    e: &'static EstimatorEntry,
    s: &SetMembershipSettings,
    filter: SetMembershipFilter<S>,
) -> Result<Inner, EstimatorError> {
    if !s.interval_observer {
        if s.state_bounds.is_some() {
            return Err(EstimatorError::InvalidConfiguration {
                estimator: e.name,
                message: "state bounds cut the published interval through the interval observer, which is off".into(),
            });
        }
        return Ok(on_linear(e, filter));
    }
    let observed = ObservedSetMembershipFilter::new(filter);
    Ok(on_linear(
        e,
        match &s.state_bounds {
            Some((lower, upper)) => observed.with_state_bounds(lower.as_slice(), upper.as_slice())?,
            None => observed,
        },
    ))
}

/// `f` with the settings' state bounds, if any.
fn with_state_bounds<S: crate::smf::UpdateSolver>(
    f: NonlinearSetMembershipFilter<S>,
    bounds: Option<&(DVector<f64>, DVector<f64>)>,
) -> Result<NonlinearSetMembershipFilter<S>, EstimatorError> {
    match bounds {
        Some((lower, upper)) => f.with_state_bounds(lower.as_slice(), upper.as_slice()),
        None => Ok(f),
    }
}

/// A row's build function given another row's settings (never: [`EstimatorEntry::build`] checks
/// the kind first).
fn wrong_settings(e: &'static EstimatorEntry) -> EstimatorError {
    EstimatorError::WrongSettings { estimator: e.name, expected: e.settings.describe(), given: "other settings" }
}

fn adaptive(e: crate::adaptive::AdaptiveError) -> EstimatorError {
    EstimatorError::Adaptive { index: None, source: Box::new(e) }
}

fn missing(name: &'static str, needs: Capability, model: &dyn AnyModel) -> EstimatorError {
    EstimatorError::ModelLacksCapability { estimator: name, needs, offered: Capability::of(model) }
}

fn on_linear<E: for<'x> DynEstimator<dyn LinearModel + 'x> + Send + 'static>(
    e: &'static EstimatorEntry,
    inner: E,
) -> Inner {
    Box::new(OnLinear { name: e.name, inner })
}

fn on_differentiable<E: for<'x> DynEstimator<dyn DifferentiableModel + 'x> + Send + 'static>(
    e: &'static EstimatorEntry,
    inner: E,
) -> Inner {
    Box::new(OnDifferentiable { name: e.name, inner })
}

fn on_second_order<E: for<'x> DynEstimator<dyn SecondOrderModel + 'x> + Send + 'static>(
    e: &'static EstimatorEntry,
    inner: E,
) -> Inner {
    Box::new(OnSecondOrder { name: e.name, inner })
}

fn on_discrete<E: for<'x> DynEstimator<dyn DiscreteModel + 'x> + Send + 'static>(
    e: &'static EstimatorEntry,
    inner: E,
) -> Inner {
    Box::new(OnDiscrete { name: e.name, inner })
}

/// The model as linear, if it is.
fn linear_of<'a>(m: &'a (dyn AnyModel + '_)) -> Option<&'a dyn LinearModel> {
    m.linear()
}

/// The model with Jacobians, if it has them.
fn differentiable_of<'a>(m: &'a (dyn AnyModel + '_)) -> Option<&'a dyn DifferentiableModel> {
    m.differentiable()
}

/// The model with enclosures of its derivatives, if it has them.
fn second_order_of<'a>(m: &'a (dyn AnyModel + '_)) -> Option<&'a dyn SecondOrderModel> {
    m.second_order()
}

/// The model as `f` and `h`: every model offers them.
fn discrete_of<'a>(m: &'a (dyn AnyModel + '_)) -> Option<&'a dyn DiscreteModel> {
    Some(m.discrete())
}

/// Implements `DynEstimator<dyn AnyModel>` for an adapter that takes one capability from the
/// model (`$get`) and hands it to the estimator inside.
macro_rules! capability_adapter {
    ($adapter:ident, $model:ident, $capability:expr, $get:ident) => {
        struct $adapter<E: ?Sized> {
            name: &'static str,
            inner: E,
        }

        impl<'m, E> DynEstimator<dyn AnyModel + 'm> for $adapter<E>
        where
            E: for<'x> DynEstimator<dyn $model + 'x> + ?Sized,
        {
            fn step_dyn(
                &mut self,
                model: &(dyn AnyModel + 'm),
                u: &DVector<f64>,
                y: &DVector<f64>,
            ) -> Result<&dyn Estimate, EstimatorError> {
                let m = $get(model).ok_or_else(|| missing(self.name, $capability, model))?;
                self.inner.step_dyn(m, u, y)
            }
            fn predict_dyn(
                &mut self,
                model: &(dyn AnyModel + 'm),
                u: &DVector<f64>,
            ) -> Result<&dyn Estimate, EstimatorError> {
                let m = $get(model).ok_or_else(|| missing(self.name, $capability, model))?;
                self.inner.predict_dyn(m, u)
            }
            fn update_dyn(
                &mut self,
                model: &(dyn AnyModel + 'm),
                y: &DVector<f64>,
            ) -> Result<&dyn Estimate, EstimatorError> {
                let m = $get(model).ok_or_else(|| missing(self.name, $capability, model))?;
                self.inner.update_dyn(m, y)
            }
            fn step_partial_dyn(
                &mut self,
                model: &(dyn AnyModel + 'm),
                u: &DVector<f64>,
                y: &DVector<f64>,
                measured: &[bool],
            ) -> Result<&dyn Estimate, EstimatorError> {
                let m = $get(model).ok_or_else(|| missing(self.name, $capability, model))?;
                self.inner.step_partial_dyn(m, u, y, measured)
            }
            fn estimate_dyn(&self) -> &dyn Estimate {
                self.inner.estimate_dyn()
            }
            fn dims_dyn(&self) -> Dims {
                self.inner.dims_dyn()
            }
            fn set_data_checks_dyn(&mut self, checks: DataChecks) -> Result<(), EstimatorError> {
                self.inner.set_data_checks_dyn(checks)
            }
        }
    };
}

capability_adapter!(OnLinear, LinearModel, Capability::Linear, linear_of);
capability_adapter!(OnDifferentiable, DifferentiableModel, Capability::Differentiable, differentiable_of);
capability_adapter!(OnSecondOrder, SecondOrderModel, Capability::SecondOrder, second_order_of);
capability_adapter!(OnDiscrete, DiscreteModel, Capability::Discrete, discrete_of);

#[cfg(test)]
mod tests;
