//! `port_estimation.Estimate`: one estimate as Python sees it — a snapshot taken when the step
//! returned, so that it stays valid while the estimator moves on.

use estimators::{EstimateKind, StepStatus};
use nalgebra::{DMatrix, DVector};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::{mat_out, vec_out};

/// The estimate of one step: its kind, centre, shape, per-state bounds, status and details.
///
/// Attributes
/// ----------
/// kind : str
///     ``"gaussian"`` (mean and covariance), ``"guaranteed ellipsoid"`` or ``"guaranteed constrained
///     zonotope"`` (sets certainly holding the state while the noises respect their bounds) or
///     ``"point"`` (moving-horizon estimators).
/// center : ndarray, shape (n,)
///     The centre (the mean of a Gaussian estimate).
/// shape : ndarray, shape (n, n)
///     The covariance, the ellipsoid's shape matrix ``{x : (x - c)' P^-1 (x - c) <= 1}``, or the
///     method's weight matrix of a point estimate.
/// lower, upper : ndarray, shape (n,), or None
///     ``center -/+ sqrt(diag(shape))``: one standard deviation of a Gaussian estimate, the guaranteed
///     interval of a set; None for point estimates.
/// status : str
///     How the step ended: ``initial``, ``predicted``, ``converged``, ``not-converged``, ``fallback``,
///     ``relaxed``, ``real-time`` (a real-time iteration's budget spent, as configured), followed
///     by ``+inconsistent`` and ``+not-guaranteed`` where they apply.
/// clean : bool
///     Whether nothing is wrong (initial, predicted, converged or real-time, consistent, guarantee
///     intact).
/// guaranteed : bool
///     Whether this is a guaranteed set whose guarantee holds.
/// set : tuple of ndarray, or None
///     The guaranteed constrained zonotope ``{c + G xi : |xi|_inf <= 1, A xi = b}`` of a
///     ``"guaranteed constrained zonotope"`` estimate, as ``(c, G, A, b)``; None for other kinds.
/// details : dict[str, float | None]
///     The estimator's own numbers (``tau1``, ``tau2``, ``tau3``, ``iterations`` of a set-membership
///     step; ``scale``, ``distance`` of the fuzzy-adaptive filter; ``iterations`` of a moving-horizon
///     window); ``estimators()`` gives each estimator's with their meanings.
///
/// All arrays are read-only copies.
#[pyclass(frozen, module = "port_estimation")]
pub struct Estimate {
    kind: EstimateKind,
    center: DVector<f64>,
    shape: DMatrix<f64>,
    bounds: Option<(Vec<f64>, Vec<f64>)>,
    status: StepStatus,
    details: Vec<(&'static str, Option<f64>)>,
    set: Option<constrained_zonotope::ConstrainedZonotope>,
}

impl Estimate {
    /// A snapshot of `e`.
    pub fn of(e: &dyn estimators::Estimate) -> Self {
        let n = e.center().len();
        let bounds = (e.kind() != EstimateKind::Point).then(|| {
            let (mut lo, mut hi) = (vec![f64::NAN; n], vec![f64::NAN; n]);
            for i in 0..n {
                if let Some((l, h)) = e.bounds(i) {
                    lo[i] = l;
                    hi[i] = h;
                }
            }
            (lo, hi)
        });
        let mut details = Vec::new();
        e.details().for_each_field(&mut |name, value| details.push((name, value)));
        Self {
            kind: e.kind(),
            center: e.center().clone(),
            shape: e.shape().clone(),
            bounds,
            status: e.status(),
            details,
            set: e.constrained_zonotope().cloned(),
        }
    }

    /// The centre.
    pub fn center_vector(&self) -> &DVector<f64> {
        &self.center
    }

    /// The shape matrix.
    pub fn shape_matrix(&self) -> &DMatrix<f64> {
        &self.shape
    }

    /// The status.
    pub fn step_status(&self) -> StepStatus {
        self.status
    }
}

#[pymethods]
impl Estimate {
    /// ``"gaussian"``, ``"guaranteed ellipsoid"``, ``"guaranteed constrained zonotope"`` or ``"point"``.
    #[getter]
    fn kind(&self) -> &'static str {
        self.kind.label()
    }

    /// The centre (mean), shape (n,).
    #[getter]
    fn center<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f64>>> {
        vec_out(py, self.center.as_slice())
    }

    /// The shape matrix (covariance, ellipsoid shape or weight), shape (n, n).
    #[getter]
    fn shape<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        mat_out(py, &self.shape)
    }

    /// Per-state lower bounds ``center - sqrt(diag(shape))``; None for point estimates.
    #[getter]
    fn lower<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray1<f64>>>> {
        self.bounds.as_ref().map(|(lo, _)| vec_out(py, lo)).transpose()
    }

    /// Per-state upper bounds ``center + sqrt(diag(shape))``; None for point estimates.
    #[getter]
    fn upper<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray1<f64>>>> {
        self.bounds.as_ref().map(|(_, hi)| vec_out(py, hi)).transpose()
    }

    /// How the step ended (``converged``, ``predicted``, ``fallback``, ...; see the class).
    #[getter]
    fn status(&self) -> String {
        self.status.label()
    }

    /// Whether the step ended cleanly.
    #[getter]
    fn clean(&self) -> bool {
        self.status.is_clean()
    }

    /// Whether this is a guaranteed set whose guarantee holds.
    #[getter]
    fn guaranteed(&self) -> bool {
        matches!(self.kind, EstimateKind::GuaranteedEllipsoid | EstimateKind::GuaranteedConstrainedZonotope)
            && matches!(self.status.guarantee, estimators::Guarantee::Holds | estimators::Guarantee::Diverging)
    }

    /// The constrained zonotope ``(c, G, A, b)``; None for other kinds of estimate.
    #[getter]
    #[allow(clippy::type_complexity)]
    fn set<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<
        Option<(
            Bound<'py, PyArray1<f64>>,
            Bound<'py, PyArray2<f64>>,
            Bound<'py, PyArray2<f64>>,
            Bound<'py, PyArray1<f64>>,
        )>,
    > {
        let Some(z) = &self.set else { return Ok(None) };
        Ok(Some((
            vec_out(py, z.center().as_slice())?,
            mat_out(py, z.generator_matrix())?,
            mat_out(py, z.constraint_matrix())?,
            vec_out(py, z.constraint_rhs().as_slice())?,
        )))
    }

    /// The estimator's own numbers by name (None where the step has none).
    #[getter]
    fn details<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (name, value) in &self.details {
            d.set_item(*name, *value)?;
        }
        Ok(d)
    }

    fn __repr__(&self) -> String {
        let c: Vec<String> = self.center.iter().map(|v| format!("{v:.6}")).collect();
        format!("Estimate(kind={:?}, status={:?}, center=[{}])", self.kind.label(), self.status.label(), c.join(", "))
    }
}
