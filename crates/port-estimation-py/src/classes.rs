//! The convenience classes: `KalmanFilter(model, ...)` is `Estimator(<the Kalman filter's
//! registry name>, model, ...)` with the settings that estimator takes as named keywords (written once,
//! by `convenience_class!`, for the classes whose keywords are all named). The
//! names come from `estimators::registry::names`; everything else is [`Estimator`]'s.

use estimators::registry::names;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::estimator::{Estimator, Initial};
use crate::model::Model;

/// `Estimator(name, …)` with `settings`, as the base of a convenience class.
fn base(
    py: Python<'_>,
    name: &str,
    model: &Bound<'_, Model>,
    initial: Initial<'_, '_>,
    settings: &[(&str, Option<Bound<'_, PyAny>>)],
    extra: Option<&Bound<'_, PyDict>>,
) -> PyResult<Estimator> {
    let given = match extra {
        Some(d) => d.copy()?,
        None => PyDict::new(py),
    };
    for (key, value) in settings {
        if let Some(v) = value {
            given.set_item(*key, v)?;
        }
    }
    Estimator::create(py, name, model, initial, Some(&given), None)
}

/// A convenience class `$class`: `Estimator($name, model, ...)` with the keywords `$kw` of its
/// registry row named in its signature (so `help()` and `inspect` show them), `x0`, `P0`, `Q`,
/// `R` first as everywhere.
macro_rules! convenience_class {
    ($(#[$doc:meta])* $class:ident = $name:expr $(, $kw:ident)* $(,)?) => {
        $(#[$doc])*
        #[pyclass(extends = Estimator, frozen, module = "port_estimation")]
        pub struct $class;

        #[pymethods]
        impl $class {
            #[new]
            #[pyo3(signature = (model, *, x0 = None, P0 = None, Q = None, R = None $(, $kw = None)*))]
            #[allow(non_snake_case, clippy::too_many_arguments)]
            fn new(
                py: Python<'_>,
                model: &Bound<'_, Model>,
                x0: Option<&Bound<'_, PyAny>>,
                P0: Option<&Bound<'_, PyAny>>,
                Q: Option<&Bound<'_, PyAny>>,
                R: Option<&Bound<'_, PyAny>>,
                $($kw: Option<Bound<'_, PyAny>>,)*
            ) -> PyResult<PyClassInitializer<Self>> {
                let e = base(py, $name, model, Initial { x0, P0, Q, R }, &[$((stringify!($kw), $kw)),*], None)?;
                Ok(PyClassInitializer::from(e).add_subclass(Self))
            }
        }
    };
}

convenience_class! {
    /// Kalman filter over a linear model, Joseph-form update (``Estimator("kf", model, ...)``).
    ///
    /// ``x[k+1] = A x[k] + B u[k] + w[k]``, ``y[k+1] = C x[k+1] + v[k+1]`` with ``w ~ N(0, Q)``,
    /// ``v ~ N(0, R)``: ``predict(u)`` computes ``x = A x + B u``, ``P = A P A' + Q``; ``update(y)`` the gain
    /// ``K = P C' (C P C' + R)^-1``, ``x = x + K (y - C x)`` and ``P = (I - K C) P (I - K C)' + K R K'``.
    ///
    /// Parameters
    /// ----------
    /// model : Model
    ///     A linear model, e.g. ``Model(A, B, C)``.
    /// x0 : array_like, shape (n,), optional
    ///     Initial mean (default zeros).
    /// P0 : array_like, shape (n, n), (n,) or scalar, optional
    ///     Initial covariance (default identity).
    /// Q : array_like, shape (n, n), (n,) or scalar, optional
    ///     Process noise covariance (default identity).
    /// R : array_like, shape (m, m), (m,) or scalar, optional
    ///     Measurement noise covariance (default identity).
    ///
    /// Attributes
    /// ----------
    /// x, P : ndarray
    ///     The current mean and covariance (read-only copies).
    /// dim_x, dim_u, dim_z : int
    ///     States, inputs, measurements.
    ///
    /// Examples
    /// --------
    /// >>> import numpy as np, port_estimation as pe
    /// >>> model = pe.Model([[1.0, 0.1], [0.0, 1.0]], [[0.0], [0.1]], [[1.0, 0.0]])
    /// >>> kf = pe.KalmanFilter(model, P0=10.0, Q=1e-4, R=1e-2)
    /// >>> _ = kf.predict([1.0])
    /// >>> e = kf.update([0.05])
    /// >>> e.status
    /// 'converged'
    ///
    /// See ``Estimator`` for ``step``, ``run`` and the exceptions.
    KalmanFilter = names::KF
}

convenience_class! {
    /// Extended Kalman filter over a differentiable model, Joseph form (``Estimator("ekf", model, ...)``).
    ///
    /// ``predict(u)``: ``x = f(x, u)``, ``P = F P F' + Q`` with ``F = df/dx`` at the previous estimate;
    /// ``update(y)``: ``H = dh/dx`` at the prediction (with the input of that prediction),
    /// ``K = P H' (H P H' + R)^-1``, ``x = x + K (y - h(x, u))``, ``P = (I - K H) P (I - K H)' + K R K'``.
    ///
    /// Parameters
    /// ----------
    /// model : Model
    ///     A model with Jacobians: ``Model.truck()``, ``Model.vessel()``, or any linear model.
    /// x0, P0, Q, R
    ///     As for ``KalmanFilter`` (covariances).
    ///
    /// Examples
    /// --------
    /// >>> import port_estimation as pe
    /// >>> ekf = pe.ExtendedKalmanFilter(pe.Model.vessel(), P0=1.0, Q=1e-4, R=1e-2)
    /// >>> ekf.dim_x, ekf.dim_u, ekf.dim_z
    /// (6, 3, 3)
    ExtendedKalmanFilter = names::EKF
}

convenience_class! {
    /// Unscented Kalman filter with scaled sigma points (``Estimator("ukf", model, ...)``).
    ///
    /// Van der Merwe's scaled sigma points (filterpy's ``MerweScaledSigmaPoints(n, alpha, beta, kappa)``):
    /// ``lambda = alpha^2 (n + kappa) - n``, points ``x`` and ``x +/- sqrt(n + lambda) L_i`` (``L`` the
    /// Cholesky factor of ``P``). ``predict(u)`` maps them through ``f`` and adds ``Q``; ``update(y)``
    /// draws them again from the prediction, maps them through ``h`` with the prediction's input, and
    /// updates with ``P = P - K S K'``. A covariance that loses positive definiteness (possible with
    /// negative weights) is recomputed about the central point and the step reports ``fallback``.
    ///
    /// Parameters
    /// ----------
    /// model : Model
    ///     Any model (only ``f`` and ``h`` are used).
    /// x0, P0, Q, R
    ///     As for ``KalmanFilter`` (covariances).
    /// alpha, beta, kappa : float, optional
    ///     Sigma-point parameters (default 1, 2, 0; ``alpha^2 (n + kappa)`` must be positive).
    UnscentedKalmanFilter = names::UKF, alpha, beta, kappa
}

convenience_class! {
    /// The improved set-membership filter with certified containment (``Estimator("smf", model, ...)``).
    ///
    /// Unknown-but-bounded noise: ``w`` in the ellipsoid ``{w : w' Q^-1 w <= 1}``, ``v`` in
    /// ``{v : v' R^-1 v <= 1}``, the initial state in ``{x : (x - x0)' P0^-1 (x - x0) <= 1}``. Each step
    /// publishes an ellipsoid ``{x : (x - c)' P^-1 (x - c) <= 1}`` that certainly contains the true
    /// state whenever the noises respect their bounds; its shape is certified against rounding, so
    /// containment never depends on the solver's accuracy. ``lower``/``upper`` are its projections:
    /// guaranteed intervals. ``predict(u)`` alone grows the set; ``update(y)`` needs the prediction
    /// before it (the update is joint with it), so ``step(u, y)`` is the usual call.
    ///
    /// Parameters
    /// ----------
    /// model : Model
    ///     A linear model.
    /// x0, P0 : array_like
    ///     Centre and shape of the initial set.
    /// Q, R : array_like
    ///     Shapes of the process and measurement noise bounds.
    /// solver : str, optional
    ///     How each step's semidefinite program is solved: ``"two-multiplier"`` (exact, the default and
    ///     fastest) or an SDP backend (``solvers()`` lists this build's).
    /// inconsistency : str, optional
    ///     What a measurement that contradicts the bounds does: ``"error"`` (default: raise
    ///     ``InconsistentDataError``, the filter unchanged), ``"flag"`` (publish it marked inconsistent,
    ///     every later set marked not guaranteed) or ``"restart"`` (move the set to the data, marked
    ///     likewise).
    /// x_lower, x_upper : array_like, optional
    ///     Bounds the true state always respects (length n, ``inf`` where none): they cut the
    ///     published interval.
    /// interval_observer : bool, optional
    ///     Run an interval observer beside the ellipsoid (default ``True``): the published interval
    ///     is the ellipsoid's projection cut by the observer's box and the bounds, never wider than
    ///     either. ``False`` publishes the paper's filter alone (no state bounds then).
    ///
    /// Attributes
    /// ----------
    /// x, P : ndarray
    ///     The centre and shape of the current set (``x`` may lie outside the published interval
    ///     when the observer cuts it).
    ///
    /// Examples
    /// --------
    /// >>> import port_estimation as pe
    /// >>> smf = pe.SetMembershipFilter(pe.Model.carrier(), P0=0.01, Q=1e-8, R=1e-6)
    /// >>> smf.dim_x, smf.dim_u, smf.dim_z
    /// (4, 8, 4)
    SetMembershipFilter = names::SMF, solver, inconsistency, x_lower, x_upper, interval_observer
}

/// The moving-horizon estimators of linear models with box-bounded noise: the robust min-max MHE
/// with disturbance blocking (``robust=True``, ``Estimator("rmhe", ...)``) or plain least-squares MHE
/// (``robust=False``, ``Estimator("mhe", ...)``). Point estimates (no bounds); ``P0``, ``Q``, ``R``
/// are the cost's weights and ``R`` must be diagonal. ``step(u, y)`` only (no separate update).
///
/// Parameters
/// ----------
/// model : Model
///     A linear model.
/// x0, P0, Q, R : array_like
///     Prior mean and weights.
/// robust : bool
///     The min-max estimator (default) or plain MHE.
/// **settings
///     ``w_lower``, ``w_upper`` (length n, may be infinite) and ``v_lower``, ``v_upper`` (length m):
///     the noise boxes (required); ``horizon`` (default 6), ``preset`` (``"rmhe"``, ``"rmhe-op"``,
///     ``"rmhe-of"``) or ``blocks``, ``lambda_v`` (default 10), ``block_weighting``, ``arrival``
///     (``"kalman"``, ``"h-infinity"`` with ``theta``), ``prior_mean``, ``solver``
///     (``"coordinate-rotation"``, ``"exact-saddle"``), ``max_sweeps`` (at most 10 000), ``tolerance``,
///     ``memory_limit`` (bytes the window may take, default 256 MiB; a larger horizon is refused
///     before anything is allocated).
#[pyclass(extends = Estimator, frozen, module = "port_estimation")]
pub struct MovingHorizonEstimator;

#[pymethods]
impl MovingHorizonEstimator {
    #[new]
    #[pyo3(signature = (model, *, x0 = None, P0 = None, Q = None, R = None, robust = true, **settings))]
    #[allow(non_snake_case)]
    fn new(
        py: Python<'_>,
        model: &Bound<'_, Model>,
        x0: Option<&Bound<'_, PyAny>>,
        P0: Option<&Bound<'_, PyAny>>,
        Q: Option<&Bound<'_, PyAny>>,
        R: Option<&Bound<'_, PyAny>>,
        robust: bool,
        settings: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<PyClassInitializer<Self>> {
        let name = if robust { names::RMHE } else { names::MHE };
        let e = base(py, name, model, Initial { x0, P0, Q, R }, &[], settings)?;
        Ok(PyClassInitializer::from(e).add_subclass(Self))
    }
}

/// The nonlinear moving-horizon estimator: Gauss-Newton on the window of any differentiable model,
/// with an unscented (default), extended or fixed arrival cost (``Estimator("mhe-ukf", ...)``). Point
/// estimates; ``P0``, ``Q``, ``R`` are weights. ``step(u, y)`` only.
///
/// Parameters
/// ----------
/// model : Model
///     A differentiable model (``Model.vessel()``...).
/// x0, P0, Q, R : array_like
///     Prior mean and weights.
/// **settings
///     ``horizon`` (default 10), ``max_iterations``, ``tolerance``, ``real_time_iterations``
///     (1 to 10 Gauss–Newton iterations per update from the previous window, status
///     ``real-time``; default: iterate to the tolerance), ``arrival`` (``"unscented"``,
///     ``"extended"``, ``"fixed"``) with ``alpha``, ``beta``, ``kappa``, ``prior`` (``"smoothed"``,
///     ``"arrival-filter"``), optional boxes ``w_lower``/``w_upper``, ``v_lower``/``v_upper``,
///     ``memory_limit`` (bytes, default 256 MiB; checked before anything is allocated).
#[pyclass(extends = Estimator, frozen, module = "port_estimation")]
pub struct NonlinearMHE;

#[pymethods]
impl NonlinearMHE {
    #[new]
    #[pyo3(signature = (model, *, x0 = None, P0 = None, Q = None, R = None, **settings))]
    #[allow(non_snake_case)]
    fn new(
        py: Python<'_>,
        model: &Bound<'_, Model>,
        x0: Option<&Bound<'_, PyAny>>,
        P0: Option<&Bound<'_, PyAny>>,
        Q: Option<&Bound<'_, PyAny>>,
        R: Option<&Bound<'_, PyAny>>,
        settings: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<PyClassInitializer<Self>> {
        let e = base(py, names::MHE_UKF, model, Initial { x0, P0, Q, R }, &[], settings)?;
        Ok(PyClassInitializer::from(e).add_subclass(Self))
    }
}

convenience_class! {
    /// The fuzzy-adaptive Kalman filter of the BDS/INS paper (``Estimator("fkf", model, ...)``): the
    /// Kalman step with ``R`` scaled every epoch by a Mamdani system of the receiver status. Each
    /// measurement is ``[y_1..y_m, satellites, rtk]`` (``dim_z = m + 2``); ``rtk = 0`` is an epoch without
    /// a fix (a prediction). ``details`` reports the scale and the innovation distance.
    ///
    /// Parameters
    /// ----------
    /// model : Model
    ///     A linear model.
    /// x0, P0, Q, R : array_like
    ///     As for ``KalmanFilter`` (covariances; ``R`` before scaling).
    /// fis : str or path, optional
    ///     A TOML rule file replacing the paper's 45-rule system.
    /// horizontal : tuple[int, int], optional
    ///     The two outputs whose innovation forms the distance (default (0, 1)).
    FuzzyKalmanFilter = names::FKF, fis, horizontal
}
