//! Keyword settings → the registry's typed [`EstimatorSettings`], chosen by the row's
//! [`SettingsKind`] (never by the estimator's name): what a Python caller writes as
//! `Estimator(name, model, solver="faer-ipm")` or `horizon=10`. Unknown keywords are refused
//! with the list of those the estimator takes.

use estimators::mhe::{
    ArrivalRecursion, BlockWeighting, BlockingPreset, MheCost, MheSettings, NonlinearArrival, NonlinearPrior,
    PriorMean, WindowSolver,
};
use estimators::registry::{
    EstimatorEntry, EstimatorSettings, FuzzyAdaptiveSettings, InputBox, SetMembershipSettings, SettingsKind, SmfSolver,
};
use estimators::{ConstrainedZonotopeSettings, Dims, InconsistencyPolicy, UkfParams};
use fuzzy_inference::FuzzySystem;
use nalgebra::DVector;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::convert::bound_vector;
use crate::errors::value_error;

/// What a model file of `port-est` contributes to an estimator's settings (its input range and
/// its `[mhe]` table); keywords override it.
#[derive(Debug, Clone, Copy, Default)]
pub struct FileSettings<'a> {
    /// `u_lower`, `u_upper`.
    pub input_range: Option<&'a (DVector<f64>, DVector<f64>)>,
    /// `x_lower`, `x_upper` (used by the set-membership filters).
    pub state_bounds: Option<&'a (DVector<f64>, DVector<f64>)>,
    /// The `[mhe]` table.
    pub mhe: Option<&'a MheSettings>,
    /// The `[ukf]` table (keywords override its entries).
    pub ukf: Option<UkfParams>,
    /// The file, to report an estimator's complaint at the key it is about.
    pub source: Option<&'a port_est::Model>,
}

/// The keywords each kind of settings takes (for error messages and `estimators()`): the
/// registry's ([`SettingsKind::keywords`]).
pub fn setting_names(kind: SettingsKind) -> Vec<&'static str> {
    kind.keywords().iter().map(|k| k.name).collect()
}

/// The keyword arguments, consumed one by one; what is left over is an error.
struct Kwargs<'py> {
    dict: Bound<'py, PyDict>,
}

impl<'py> Kwargs<'py> {
    fn new(py: Python<'py>, given: Option<&Bound<'py, PyDict>>) -> PyResult<Self> {
        Ok(Self { dict: given.map_or_else(|| Ok(PyDict::new(py)), |d| d.copy())? })
    }

    /// The value of `key` (None when absent or given as None).
    fn take(&self, key: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
        let value = self.dict.get_item(key)?;
        if value.is_some() {
            self.dict.del_item(key)?;
        }
        Ok(value.filter(|v| !v.is_none()))
    }

    fn extract<T: for<'a> FromPyObject<'a, 'py>>(&self, key: &str, what: &str) -> PyResult<Option<T>> {
        self.take(key)?
            .map(|v| v.extract::<T>().map_err(|_| value_error(format!("setting {key} must be {what}, got {v}"))))
            .transpose()
    }

    fn float(&self, key: &str) -> PyResult<Option<f64>> {
        self.extract(key, "a number")
    }

    fn count(&self, key: &str) -> PyResult<Option<usize>> {
        self.extract(key, "a non-negative integer")
    }

    /// One of `options`, by name.
    fn choice<T: Copy>(&self, key: &str, options: &[(&str, T)]) -> PyResult<Option<T>> {
        let Some(name) = self.extract::<String>(key, "a string")? else {
            return Ok(None);
        };
        match options.iter().find(|(n, _)| *n == name) {
            Some((_, t)) => Ok(Some(*t)),
            None => {
                let known: Vec<&str> = options.iter().map(|(n, _)| *n).collect();
                Err(value_error(format!("setting {key}: unknown value {name:?} (one of: {})", known.join(", "))))
            }
        }
    }

    /// A pair of bound vectors `(lower, upper)` of length `len`: both or neither.
    fn bounds(&self, lower: &str, upper: &str, len: usize) -> PyResult<Option<(DVector<f64>, DVector<f64>)>> {
        match (self.take(lower)?, self.take(upper)?) {
            (Some(l), Some(u)) => Ok(Some((bound_vector(&l, lower, len)?, bound_vector(&u, upper, len)?))),
            (None, None) => Ok(None),
            _ => Err(value_error(format!("give both {lower} and {upper}, or neither"))),
        }
    }

    /// Refuses what is left, naming what `entry` takes.
    fn finish(self, entry: &EstimatorEntry) -> PyResult<()> {
        if self.dict.is_empty() {
            return Ok(());
        }
        let left: Vec<String> = self.dict.keys().iter().map(|k| k.to_string()).collect();
        let takes = setting_names(entry.settings);
        let takes = if takes.is_empty() { "no settings".to_owned() } else { takes.join(", ") };
        Err(value_error(format!(
            "unknown setting(s) {} for estimator {} (it takes: {takes})",
            left.join(", "),
            entry.name
        )))
    }
}

/// `solver`, `inconsistency`, `interval_observer` (default true) and `x_lower`, `x_upper`
/// (keywords over the model file's).
fn set_membership(
    kw: &Kwargs<'_>,
    states: usize,
    file: Option<&(DVector<f64>, DVector<f64>)>,
) -> PyResult<SetMembershipSettings> {
    let interval_observer = kw.extract::<bool>("interval_observer", "True or False")?.unwrap_or(true);
    // The file's bounds are the vehicle's, used where they can be: not by a linear filter without
    // its observer (bounds given as keywords then are refused by the registry).
    let state_bounds = match kw.bounds("x_lower", "x_upper", states)? {
        Some(b) => Some(b),
        None if interval_observer => file.cloned(),
        None => None,
    };
    let solver = match kw.extract::<String>("solver", "a string")? {
        Some(name) => SmfSolver::by_name(&name).map_err(|e| value_error(e.to_string()))?,
        None => SmfSolver::default(),
    };
    let inconsistency = inconsistency(kw)?;
    Ok(SetMembershipSettings { solver, inconsistency, state_bounds, interval_observer })
}

fn moving_horizon(kw: &Kwargs<'_>, dims: Dims, file: Option<&MheSettings>) -> PyResult<MheSettings> {
    let w = kw.bounds("w_lower", "w_upper", dims.states)?;
    let v = kw.bounds("v_lower", "v_upper", dims.outputs)?;
    let mut s = match (file, w, v) {
        (Some(f), w, v) => {
            let mut s = f.clone();
            if let Some(w) = w {
                s.w_box = w;
            }
            if let Some(v) = v {
                s.v_box = v;
            }
            s
        }
        (None, Some(w), Some(v)) => MheSettings::new(w, v),
        (None, ..) => {
            return Err(value_error(
                "the moving-horizon estimators need the noise boxes: w_lower, w_upper (length n) and v_lower, v_upper \
                 (length m)",
            ));
        }
    };
    let limit = memory_limit(kw)?;
    let horizon = kw.count("horizon")?;
    let presets = [BlockingPreset::Rmhe, BlockingPreset::RmheOp, BlockingPreset::RmheOf];
    let preset_names: Vec<(String, BlockingPreset)> = presets.iter().map(|p| (p.name().to_lowercase(), *p)).collect();
    let preset_options: Vec<(&str, BlockingPreset)> = preset_names.iter().map(|(n, p)| (n.as_str(), *p)).collect();
    let (preset, blocks) =
        (kw.choice("preset", &preset_options)?, kw.extract::<Vec<usize>>("blocks", "a list of block lengths")?);
    // The window's size is checked before any buffer of the horizon's length is made.
    let h = horizon.unwrap_or(s.horizon);
    let block_count = match (&blocks, horizon) {
        (Some(b), _) => b.len(),
        (None, Some(h)) => h,
        (None, None) => s.blocks.len(),
    };
    let clarabel = s.output_constraint
        || matches!(s.solver, WindowSolver::CoordinateRotation { inner: estimators::mhe::InnerSolver::Clarabel, .. });
    let need = port_est::mhe_table::memory_estimate(dims.states, dims.outputs, dims.inputs, h, block_count, clarabel);
    check_memory(need, limit, "horizon", h)?;
    if let Some(h) = horizon {
        s.horizon = h;
        s.blocks = vec![1; h];
    }
    match (preset, blocks) {
        (Some(p), None) => s.blocks = p.lengths(s.horizon).map_err(|e| value_error(e.to_string()))?,
        (None, Some(b)) => s.blocks = b,
        (None, None) => {}
        (Some(_), Some(_)) => return Err(value_error("give preset or blocks, not both")),
    }
    if let Some(bw) =
        kw.choice("block_weighting", &[("length", BlockWeighting::Length), ("unit", BlockWeighting::Unit)])?
    {
        s.block_weighting = bw;
    }
    if let Some(l) = kw.float("lambda_v")? {
        s.cost = MheCost::MinMax { lambda_v: l };
    }
    let theta = kw.float("theta")?;
    match kw.choice("arrival", &[("kalman", false), ("h-infinity", true)])? {
        Some(true) => s.arrival = ArrivalRecursion::HInfinity { theta: theta.unwrap_or(0.9) },
        Some(false) => s.arrival = ArrivalRecursion::Kalman,
        None if theta.is_some() => return Err(value_error("theta applies to arrival=\"h-infinity\"")),
        None => {}
    }
    if let Some(p) = kw.choice("prior_mean", &[("smoothed", PriorMean::Smoothed), ("filtered", PriorMean::Filtered)])? {
        s.prior_mean = p;
    }
    let (sweeps, tolerance) = (iteration_count(kw, "max_sweeps")?, kw.float("tolerance")?);
    let exact = kw.choice("window_solver", &[("coordinate-rotation", false), ("exact-saddle", true)])?;
    let exact = exact.unwrap_or(matches!(s.solver, WindowSolver::ExactSaddle { .. }));
    let base = match (exact, s.solver) {
        (false, current @ WindowSolver::CoordinateRotation { .. })
        | (true, current @ WindowSolver::ExactSaddle { .. }) => current,
        (false, _) => WindowSolver::coordinate_rotation(),
        (true, _) => WindowSolver::exact_saddle(),
    };
    s.solver = match base {
        WindowSolver::CoordinateRotation { max_sweeps, tolerance: t, inner } => WindowSolver::CoordinateRotation {
            max_sweeps: sweeps.unwrap_or(max_sweeps),
            tolerance: tolerance.unwrap_or(t),
            inner,
        },
        WindowSolver::ExactSaddle { max_iterations, tolerance: t } => WindowSolver::ExactSaddle {
            max_iterations: sweeps.unwrap_or(max_iterations),
            tolerance: tolerance.unwrap_or(t),
        },
        other => other,
    };
    Ok(s)
}

fn nonlinear_moving_horizon(kw: &Kwargs<'_>, dims: Dims, entry: &EstimatorEntry) -> PyResult<EstimatorSettings> {
    let Some(EstimatorSettings::NonlinearMovingHorizon(mut s)) = entry.settings.default_settings() else {
        return Err(value_error(format!("estimator {} has no default nonlinear MHE settings", entry.name)));
    };
    let limit = memory_limit(kw)?;
    if let Some(h) = kw.count("horizon")? {
        s.horizon = h;
    }
    if let Some(i) = iteration_count(kw, "max_iterations")? {
        s.max_iterations = i;
    }
    // Checked (1 to MAX_REAL_TIME_ITERATIONS) with the other settings when the estimator is built.
    s.real_time_iterations = kw.count("real_time_iterations")?;
    if let Some(t) = kw.float("tolerance")? {
        s.tolerance = t;
    }
    let base = match s.arrival {
        NonlinearArrival::Ukf(p) => p,
        _ => UkfParams::default(),
    };
    let sigma = sigma_points(kw, base)?;
    match kw.choice("arrival", &[("unscented", 0u8), ("extended", 1), ("fixed", 2)])? {
        Some(1) => s.arrival = NonlinearArrival::Ekf,
        Some(2) => s.arrival = NonlinearArrival::Fixed,
        Some(_) => s.arrival = NonlinearArrival::Ukf(sigma),
        None => {
            if let NonlinearArrival::Ukf(_) = s.arrival {
                s.arrival = NonlinearArrival::Ukf(sigma);
            }
        }
    }
    if let Some(p) = kw
        .choice("prior", &[("smoothed", NonlinearPrior::Smoothed), ("arrival-filter", NonlinearPrior::ArrivalFilter)])?
    {
        s.prior = p;
    }
    if let Some(w) = kw.bounds("w_lower", "w_upper", dims.states)? {
        s.w_box = Some(w);
    }
    if let Some(v) = kw.bounds("v_lower", "v_upper", dims.outputs)? {
        s.v_box = Some(v);
    }
    check_memory(s.memory_estimate(dims.states, dims.outputs, dims.inputs), limit, "horizon", s.horizon)?;
    Ok(EstimatorSettings::NonlinearMovingHorizon(s))
}

/// The `memory_limit` keyword of the moving-horizon estimators: the most bytes their buffers
/// may take (default the command line's `--mhe-memory-limit`, 256 MiB).
fn memory_limit(kw: &Kwargs<'_>) -> PyResult<u128> {
    Ok(kw
        .extract::<u64>("memory_limit", "a number of bytes (a non-negative integer)")?
        .map_or(u128::from(port_est::limits::DEFAULT_MHE_MEMORY_BYTES), u128::from))
}

/// Refuses a window whose buffers (`need` bytes, `None`: beyond `u128`) would exceed `limit`,
/// naming the keyword that sizes them, before anything is allocated.
fn check_memory(need: Option<u128>, limit: u128, key: &str, value: usize) -> PyResult<()> {
    if need.is_some_and(|n| n <= limit) {
        return Ok(());
    }
    let show = port_est::limits::show_bytes;
    let need = need.map_or_else(|| "more than 2^128 bytes".to_owned(), |n| format!("about {}", show(n)));
    Err(value_error(format!(
        "setting {key} = {value}: the estimator would need {need}, more than memory_limit = {} (raise it with \
         memory_limit=...; a step's time grows with the window too)",
        show(limit)
    )))
}

/// An iteration count bounded as in the command line's `[mhe]` table (at most
/// `port_est::limits::MAX_MHE_SWEEPS` per window), so a window's time is bounded.
fn iteration_count(kw: &Kwargs<'_>, key: &str) -> PyResult<Option<usize>> {
    let max = port_est::limits::MAX_MHE_SWEEPS;
    match kw.count(key)? {
        Some(v) if v > max => Err(value_error(format!("setting {key} = {v}: at most {max} per window"))),
        other => Ok(other),
    }
}

fn sigma_points(kw: &Kwargs<'_>, base: UkfParams) -> PyResult<UkfParams> {
    Ok(UkfParams {
        alpha: kw.float("alpha")?.unwrap_or(base.alpha),
        beta: kw.float("beta")?.unwrap_or(base.beta),
        kappa: kw.float("kappa")?.unwrap_or(base.kappa),
    })
}

fn fuzzy_adaptive(kw: &Kwargs<'_>) -> PyResult<FuzzyAdaptiveSettings> {
    let mut s = FuzzyAdaptiveSettings::default();
    match (kw.extract::<std::path::PathBuf>("fis", "a path")?, kw.extract::<String>("fis_toml", "a string")?) {
        (Some(path), None) => s.system = FuzzySystem::from_toml_file(&path).map_err(|e| value_error(e.to_string()))?,
        (None, Some(text)) => {
            s.system = FuzzySystem::from_toml_str(&text, "<fis_toml>").map_err(|e| value_error(e.to_string()))?;
        }
        (None, None) => {}
        (Some(_), Some(_)) => return Err(value_error("give fis (a file) or fis_toml (its text), not both")),
    }
    if let Some((i, j)) = kw.extract::<(usize, usize)>("horizontal", "a pair of output indices")? {
        s.horizontal = [i, j];
    }
    Ok(s)
}

/// The constrained-zonotope filters' settings: `order`, `max_constraints`, `inconsistency`,
/// `x_lower`/`x_upper` (over the file's), `divergence_factor`.
fn constrained_zonotope(
    kw: &Kwargs<'_>,
    states: usize,
    file: Option<&(DVector<f64>, DVector<f64>)>,
) -> PyResult<ConstrainedZonotopeSettings> {
    let mut s = ConstrainedZonotopeSettings::default();
    if let Some(order) = kw.extract::<usize>("order", "a positive integer")? {
        s.order = order;
    }
    if let Some(nc) = kw.extract::<usize>("max_constraints", "a non-negative integer")? {
        s.max_constraints = nc;
    }
    if let Some(f) = kw.extract::<f64>("divergence_factor", "a number above 1")? {
        s.divergence_factor = f;
    }
    s.inconsistency = inconsistency(kw)?;
    s.state_bounds = kw.bounds("x_lower", "x_upper", states)?.or_else(|| file.cloned());
    Ok(s)
}

/// The `inconsistency` keyword: `"error"` (the default), `"flag"` or `"restart"`.
fn inconsistency(kw: &Kwargs<'_>) -> PyResult<InconsistencyPolicy> {
    Ok(kw
        .choice(
            "inconsistency",
            &[
                ("error", InconsistencyPolicy::Error),
                ("flag", InconsistencyPolicy::FlagAndContinue),
                ("restart", InconsistencyPolicy::Restart),
            ],
        )?
        .unwrap_or_default())
}

/// The settings of `entry` from keywords over the model file's (`None`: the row's defaults).
///
/// # Errors
/// `ValueError` for an unknown keyword, a value of the wrong type or out of its choices, or a
/// setting the row needs and nobody gave.
pub fn settings(
    py: Python<'_>,
    entry: &'static EstimatorEntry,
    dims: Dims,
    given: Option<&Bound<'_, PyDict>>,
    file: FileSettings<'_>,
) -> PyResult<Option<EstimatorSettings>> {
    let kw = Kwargs::new(py, given)?;
    let settings = match entry.settings {
        SettingsKind::None => None,
        SettingsKind::SetMembership => {
            Some(EstimatorSettings::SetMembership(set_membership(&kw, dims.states, file.state_bounds)?))
        }
        SettingsKind::SetMembershipInputBox => {
            let smf = set_membership(&kw, dims.states, file.state_bounds)?;
            let (lower, upper) = match (kw.bounds("u_lower", "u_upper", dims.inputs)?, file.input_range) {
                (Some(b), _) => b,
                (None, Some(b)) => b.clone(),
                (None, None) => {
                    return Err(value_error(format!(
                        "estimator {} needs the input range: u_lower, u_upper (length p = {})",
                        entry.name, dims.inputs
                    )));
                }
            };
            Some(EstimatorSettings::SetMembershipInputBox(smf, InputBox { lower, upper }))
        }
        SettingsKind::MovingHorizon => {
            Some(EstimatorSettings::MovingHorizon(Box::new(moving_horizon(&kw, dims, file.mhe)?)))
        }
        SettingsKind::Unscented => Some(EstimatorSettings::Unscented(sigma_points(&kw, file.ukf.unwrap_or_default())?)),
        SettingsKind::NonlinearMovingHorizon => Some(nonlinear_moving_horizon(&kw, dims, entry)?),
        SettingsKind::FuzzyAdaptive => Some(EstimatorSettings::FuzzyAdaptive(Box::new(fuzzy_adaptive(&kw)?))),
        SettingsKind::ConstrainedZonotope => {
            Some(EstimatorSettings::ConstrainedZonotope(constrained_zonotope(&kw, dims.states, file.state_bounds)?))
        }
        other => {
            return Err(value_error(format!(
                "estimator {} takes {}, which this version of the package cannot set",
                entry.name,
                other.describe()
            )));
        }
    };
    kw.finish(entry)?;
    Ok(settings)
}
