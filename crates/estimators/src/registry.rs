//! Estimators by name, so that the CLI, the reproduction and user interfaces choose one at run
//! time and adding a filter touches one place (this table and its constructor).
//!
//! Estimators are grouped by the model capability they need: [`LINEAR_ESTIMATORS`] run on linear
//! (time-varying) models ([`linear`], `Box<dyn DynEstimator<dyn LinearModel>>`),
//! [`DIFFERENTIABLE_ESTIMATORS`] on models with Jacobians ([`differentiable`]),
//! [`NONLINEAR_ESTIMATORS`] on models that give only `f` and `h` ([`nonlinear`]).

use nalgebra::{DMatrix, DVector};

use lmi::SolverSettings;
use models::{DifferentiableModel, DiscreteModel, LinearModel};

use crate::ekf::ExtendedKalmanFilter;
use crate::error::EstimatorError;
use crate::kalman::KalmanFilter;
use crate::mhe::{MheCost, MheSettings, MovingHorizonEstimator, NonlinearMhe, NonlinearMheSettings};
use crate::smf::{SdpUpdateSolver, SetMembershipFilter, TwoMultiplierSolver};
use crate::traits::{DynEstimator, EstimateKind, NoiseSettings};
use crate::ukf::{UkfParams, UnscentedKalmanFilter};
use crate::yang_li;

/// The solver name of the exact two-multiplier method (the default of the set-membership
/// filters); any `lmi` backend name (`faer-ipm`, `clarabel` with that feature) selects an SDP
/// solver instead.
pub const TWO_MULTIPLIER: &str = "two-multiplier";

/// A registered estimator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EstimatorInfo {
    /// Its name in the registry (CLI `--estimator`).
    pub name: &'static str,
    /// What kind of set it publishes.
    pub kind: EstimateKind,
    /// One line for `--help` and reports.
    pub summary: &'static str,
    /// Whether it uses [`LinearSetup::solver`].
    pub uses_solver: bool,
    /// Whether it needs [`LinearSetup::input_bounds`].
    pub needs_input_bounds: bool,
}

/// The estimators for linear models, in display order.
pub const LINEAR_ESTIMATORS: &[EstimatorInfo] = &[
    EstimatorInfo {
        name: "smf",
        kind: EstimateKind::GuaranteedEllipsoid,
        summary: "improved set-membership filter (carrier paper (13)-(29)), certified containment",
        uses_solver: true,
        needs_input_bounds: false,
    },
    EstimatorInfo {
        name: "kf",
        kind: EstimateKind::Gaussian,
        summary: "Kalman filter, Joseph form (Q, R, P0 as covariances)",
        uses_solver: false,
        needs_input_bounds: false,
    },
    EstimatorInfo {
        name: "yang-li",
        kind: EstimateKind::GuaranteedEllipsoid,
        summary: "reconstruction (a) of the carrier paper's reference [17]: input unused, bounded by its box",
        uses_solver: true,
        needs_input_bounds: true,
    },
    EstimatorInfo {
        name: "yang-li-with-input",
        kind: EstimateKind::GuaranteedEllipsoid,
        summary: "reconstruction (b) of [17]: the input in the predictor",
        uses_solver: true,
        needs_input_bounds: false,
    },
    EstimatorInfo {
        name: "rmhe",
        kind: EstimateKind::Point,
        summary: "robust min-max moving-horizon estimator with disturbance blocking (car paper), box-bounded noise",
        uses_solver: false,
        needs_input_bounds: false,
    },
    EstimatorInfo {
        name: "mhe",
        kind: EstimateKind::Point,
        summary: "plain least-squares moving-horizon estimator (the rmhe settings with lambda_v -> infinity)",
        uses_solver: false,
        needs_input_bounds: false,
    },
];

/// Everything a linear-model estimator is built from.
#[derive(Debug, Clone)]
pub struct LinearSetup {
    /// Initial centre (mean) `x̂₀`.
    pub x0: DVector<f64>,
    /// Initial shape (covariance) `P₀`.
    pub p0: DMatrix<f64>,
    /// `Q`, `R`: ellipsoid shapes for set-membership filters, covariances for the Kalman filter.
    pub noise: NoiseSettings,
    /// Number of inputs `p`.
    pub inputs: usize,
    /// The known input box `[lower, upper]` (needed by `yang-li`).
    pub input_bounds: Option<(DVector<f64>, DVector<f64>)>,
    /// How a set-membership filter solves (29): [`TWO_MULTIPLIER`] (default) or an `lmi`
    /// backend name.
    pub solver: String,
    /// Settings of an SDP backend. [`LinearSetup::new`] turns
    /// [`SolverSettings::warm_start`] on: a filter's SDPs at consecutive steps are nearby
    /// problems, and `faer-ipm` solves them in a third to a half of the iterations from the previous
    /// step's solution (the filter certifies its `P_{k+1}` whatever the solver returns).
    pub sdp_settings: SolverSettings,
    /// Settings of the moving-horizon estimators (`rmhe`, `mhe`); their `x0`, `p0`, `q`, `r`
    /// are replaced by this setup's.
    pub mhe: Option<MheSettings>,
}

impl LinearSetup {
    /// A setup with the default solver and no input box.
    #[must_use]
    pub fn new(x0: DVector<f64>, p0: DMatrix<f64>, noise: NoiseSettings, inputs: usize) -> Self {
        Self {
            x0,
            p0,
            noise,
            inputs,
            input_bounds: None,
            solver: TWO_MULTIPLIER.to_owned(),
            sdp_settings: SolverSettings { warm_start: true, ..SolverSettings::default() },
            mhe: None,
        }
    }
}

/// The names of the solvers a set-membership filter accepts.
#[must_use]
pub fn solver_names() -> Vec<&'static str> {
    let mut v = vec![TWO_MULTIPLIER];
    v.extend(lmi::backend_names());
    v
}

/// A linear-model estimator.
pub type BoxedLinearEstimator = Box<dyn for<'m> DynEstimator<dyn LinearModel + 'm>>;

/// Builds the registered estimator `name` from `setup`.
///
/// # Errors
/// [`EstimatorError::UnknownEstimator`]; [`EstimatorError::MissingSetting`] (the input box of
/// `yang-li`); an unknown solver ([`EstimatorError::Lmi`]); the constructors' validation
/// errors.
pub fn linear(name: &str, setup: &LinearSetup) -> Result<BoxedLinearEstimator, EstimatorError> {
    let LinearSetup { x0, p0, noise, inputs, .. } = setup;
    let (x0, p0, q, r) = (x0.clone(), p0.clone(), noise.q.clone(), noise.r.clone());
    let two = setup.solver == TWO_MULTIPLIER;
    let sdp = || SdpUpdateSolver::by_name(&setup.solver, setup.sdp_settings.clone());
    Ok(match name {
        "kf" => Box::new(KalmanFilter::new(x0, p0, q, r, *inputs)?),
        "smf" if two => Box::new(SetMembershipFilter::two_multiplier(x0, p0, q, r, *inputs)?),
        "smf" => Box::new(SetMembershipFilter::new(x0, p0, q, r, *inputs, sdp()?)?),
        "yang-li" => {
            let Some((lo, hi)) = &setup.input_bounds else {
                return Err(EstimatorError::MissingSetting { estimator: "yang-li", what: "the input box" });
            };
            if two {
                Box::new(yang_li::without_input(x0, p0, q, r, lo, hi, TwoMultiplierSolver::new())?)
            } else {
                Box::new(yang_li::without_input(x0, p0, q, r, lo, hi, sdp()?)?)
            }
        }
        "yang-li-with-input" if two => {
            Box::new(yang_li::with_input(x0, p0, q, r, *inputs, TwoMultiplierSolver::new())?)
        }
        "yang-li-with-input" => Box::new(yang_li::with_input(x0, p0, q, r, *inputs, sdp()?)?),
        "rmhe" | "mhe" => {
            let Some(settings) = &setup.mhe else {
                return Err(EstimatorError::MissingSetting {
                    estimator: if name == "rmhe" { "rmhe" } else { "mhe" },
                    what: "the moving-horizon settings (horizon, blocks, noise boxes W and V, lambda_v)",
                });
            };
            let mut settings = MheSettings { x0, p0, q, r, ..settings.clone() };
            if name == "mhe" {
                settings.cost = MheCost::LeastSquares;
            }
            Box::new(MovingHorizonEstimator::new(settings, *inputs)?)
        }
        _ => {
            return Err(EstimatorError::UnknownEstimator {
                name: name.to_owned(),
                known: LINEAR_ESTIMATORS.iter().map(|e| e.name).collect::<Vec<_>>().join(", "),
            });
        }
    })
}

/// The registry entry called `name`.
#[must_use]
pub fn info(name: &str) -> Option<&'static EstimatorInfo> {
    LINEAR_ESTIMATORS.iter().find(|e| e.name == name)
}

/// The estimators for differentiable (nonlinear) models, in display order.
pub const DIFFERENTIABLE_ESTIMATORS: &[EstimatorInfo] = &[
    EstimatorInfo {
        name: "ekf",
        kind: EstimateKind::Gaussian,
        summary: "extended Kalman filter, Joseph form (truck paper (7)-(11)); Q, R, P0 as covariances",
        uses_solver: false,
        needs_input_bounds: false,
    },
    EstimatorInfo {
        name: "mhe-ukf",
        kind: EstimateKind::Point,
        summary: "nonlinear moving-horizon estimator, N = 10, Gauss-Newton on the banded window, UKF arrival cost \
                  (vessel paper (21)-(37)); Q, R, P0 as weights",
        uses_solver: false,
        needs_input_bounds: false,
    },
];

/// Everything a Gaussian estimator of a nonlinear model is built from.
#[derive(Debug, Clone)]
pub struct GaussianSetup {
    /// Initial mean `x̂₀`.
    pub x0: DVector<f64>,
    /// Initial covariance `P₀`.
    pub p0: DMatrix<f64>,
    /// Process and measurement covariances.
    pub noise: NoiseSettings,
    /// Number of inputs `p`.
    pub inputs: usize,
}

/// An estimator of differentiable models.
pub type BoxedDifferentiableEstimator = Box<dyn for<'m> DynEstimator<dyn DifferentiableModel + 'm>>;

/// Builds the registered estimator `name` for differentiable models from `setup`.
///
/// # Errors
/// [`EstimatorError::UnknownEstimator`]; the constructors' validation errors.
pub fn differentiable(name: &str, setup: &GaussianSetup) -> Result<BoxedDifferentiableEstimator, EstimatorError> {
    let GaussianSetup { x0, p0, noise, inputs } = setup;
    match name {
        "ekf" => {
            Ok(Box::new(ExtendedKalmanFilter::new(x0.clone(), p0.clone(), noise.q.clone(), noise.r.clone(), *inputs)?))
        }
        "mhe-ukf" => Ok(Box::new(NonlinearMhe::new(
            NonlinearMheSettings::new(x0.clone(), p0.clone(), noise.q.clone(), noise.r.clone()),
            *inputs,
        )?)),
        _ => Err(EstimatorError::UnknownEstimator {
            name: name.to_owned(),
            known: DIFFERENTIABLE_ESTIMATORS.iter().map(|e| e.name).collect::<Vec<_>>().join(", "),
        }),
    }
}

/// The estimators that need only `f` and `h` ([`models::DiscreteModel`]), in display order.
pub const NONLINEAR_ESTIMATORS: &[EstimatorInfo] = &[EstimatorInfo {
    name: "ukf",
    kind: EstimateKind::Gaussian,
    summary: "unscented Kalman filter, scaled sigma points with a positive-definiteness guard (dp-vessel note); \
              Q, R, P0 as covariances",
    uses_solver: false,
    needs_input_bounds: false,
}];

/// Everything an estimator of [`NONLINEAR_ESTIMATORS`] is built from: the Gaussian setup and
/// the sigma-point parameters.
#[derive(Debug, Clone)]
pub struct NonlinearSetup {
    /// Initial mean and covariance, noise covariances, number of inputs.
    pub gaussian: GaussianSetup,
    /// Sigma-point parameters of `ukf`.
    pub ukf: UkfParams,
}

impl NonlinearSetup {
    /// A setup with the default sigma-point parameters ([`UkfParams::default`]).
    #[must_use]
    pub fn new(gaussian: GaussianSetup) -> Self {
        Self { gaussian, ukf: UkfParams::default() }
    }
}

/// An estimator of discrete (nonlinear) models.
pub type BoxedNonlinearEstimator = Box<dyn for<'m> DynEstimator<dyn DiscreteModel + 'm>>;

/// Builds the registered estimator `name` for discrete models from `setup`. (Every estimator
/// here also implements `Estimator<dyn DifferentiableModel>`, so the same filter can be boxed
/// beside the EKF.)
///
/// # Errors
/// [`EstimatorError::UnknownEstimator`]; the constructors' validation errors.
pub fn nonlinear(name: &str, setup: &NonlinearSetup) -> Result<BoxedNonlinearEstimator, EstimatorError> {
    let GaussianSetup { x0, p0, noise, inputs } = &setup.gaussian;
    match name {
        "ukf" => Ok(Box::new(UnscentedKalmanFilter::new(
            x0.clone(),
            p0.clone(),
            noise.q.clone(),
            noise.r.clone(),
            *inputs,
            setup.ukf,
        )?)),
        _ => Err(EstimatorError::UnknownEstimator {
            name: name.to_owned(),
            known: NONLINEAR_ESTIMATORS.iter().map(|e| e.name).collect::<Vec<_>>().join(", "),
        }),
    }
}
