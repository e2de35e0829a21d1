//! Settings read by keyword, in one place for every surface: Python's keyword arguments, a model
//! file's tables and anything else that holds values by name implements [`KeywordSource`], and
//! [`read_settings`] turns it into the row's typed [`EstimatorSettings`] with the keywords of
//! [`SettingsKind::keywords`]. The source only converts a value to a number, a count, a flag, a
//! text or a list and says where a key is; every default, choice, length, both-or-neither rule and
//! resource check is here, so the surfaces cannot drift apart.
//!
//! Resources are checked before anything is allocated for them: a moving-horizon window's memory
//! ([`crate::mhe::memory_estimate`], [`NonlinearMheSettings::memory_estimate`]) against
//! [`KeywordContext::memory_limit`], iteration counts against [`MAX_WINDOW_ITERATIONS`].

use std::path::PathBuf;

use nalgebra::DVector;

use fuzzy_inference::FuzzySystem;
use models::Dims;

use crate::czf::ConstrainedZonotopeSettings;
use crate::mhe::{
    AlphaMap, ArrivalRecursion, BlockWeighting, BlockingPreset, InnerSolver, MheCost, MheSettings, NonlinearArrival,
    NonlinearMheSettings, NonlinearPrior, PriorMean, WindowSolver, memory_estimate,
};
use crate::smf::InconsistencyPolicy;
use crate::ukf::UkfParams;

use super::settings::{
    EstimatorSettings, FuzzyAdaptiveSettings, InputBox, SetMembershipSettings, SettingsKind, SmfSolver,
};

/// A pair of bound vectors `(lower, upper)`.
type Bounds = (DVector<f64>, DVector<f64>);

/// The most sweeps (or Newton, or Gauss–Newton iterations) a moving-horizon window may be given,
/// so that a step's time is bounded.
pub const MAX_WINDOW_ITERATIONS: usize = 10_000;

/// The bytes a moving-horizon estimator's buffers may take unless a surface says otherwise
/// (256 MiB; the `memory_limit` keyword raises it).
pub const DEFAULT_MEMORY_LIMIT: u64 = 256 << 20;

/// Values by keyword. Each getter consumes its key (so that [`KeywordSource::unread`] lists what
/// nobody read) and returns `None` when the key is absent; a value of the wrong type is the
/// source's error, naming the key where the source can tell it.
pub trait KeywordSource {
    /// The source's error (a Python exception, an error at a file's `line:column`).
    type Error;
    /// A number.
    ///
    /// # Errors
    /// A value that is not a number.
    fn number(&mut self, key: &'static str) -> Result<Option<f64>, Self::Error>;
    /// A non-negative integer.
    ///
    /// # Errors
    /// A value that is not one.
    fn count(&mut self, key: &'static str) -> Result<Option<usize>, Self::Error>;
    /// True or false.
    ///
    /// # Errors
    /// A value that is not a boolean.
    fn flag(&mut self, key: &'static str) -> Result<Option<bool>, Self::Error>;
    /// A text (a name among choices).
    ///
    /// # Errors
    /// A value that is not a string.
    fn text(&mut self, key: &'static str) -> Result<Option<String>, Self::Error>;
    /// A file's path (a model file resolves it against its own folder).
    ///
    /// # Errors
    /// A value that is not a path.
    fn path(&mut self, key: &'static str) -> Result<Option<PathBuf>, Self::Error>;
    /// A list of numbers (`±inf` allowed; [`read_settings`] checks lengths and NaN).
    ///
    /// # Errors
    /// A value that is not a list of numbers.
    fn numbers(&mut self, key: &'static str) -> Result<Option<Vec<f64>>, Self::Error>;
    /// A list of non-negative integers.
    ///
    /// # Errors
    /// A value that is not one.
    fn counts(&mut self, key: &'static str) -> Result<Option<Vec<usize>>, Self::Error>;
    /// The error for `key` (given or not): `message` at the key when it was given.
    fn refuse(&self, key: &str, message: String) -> Self::Error;
    /// The keys given and not read.
    fn unread(&self) -> Vec<String>;
}

/// What the settings are read for, and what a model file gives every estimator (keywords
/// override it).
#[derive(Debug, Clone, Copy)]
pub struct KeywordContext<'a> {
    /// The model's sizes.
    pub dims: Dims,
    /// `x_lower`, `x_upper`: bounds the true state always respects.
    pub state_bounds: Option<&'a Bounds>,
    /// `u_lower`, `u_upper`: the known input range.
    pub input_range: Option<&'a Bounds>,
    /// A model file's `[mhe]` table, the base of the moving-horizon estimators' settings.
    pub mhe: Option<&'a MheSettings>,
    /// A model file's `[ukf]` table, the base of the sigma points.
    pub ukf: Option<UkfParams>,
    /// The bytes a moving-horizon window may take when no `memory_limit` is given.
    pub memory_limit: u64,
    /// How the user raises the memory limit, for the refusal's message (`memory_limit=...`,
    /// `--mhe-memory-limit`).
    pub raise_memory: &'static str,
    /// The most a `memory_limit` keyword may ask for: `u64::MAX` where the caller sets it
    /// (Python's keyword arguments), the command line's limit for a file's tables, so that a
    /// file cannot lift the limit its reader runs it under.
    pub memory_ceiling: u64,
}

impl KeywordContext<'_> {
    /// Nothing but the sizes: no file, [`DEFAULT_MEMORY_LIMIT`], raised by `memory_limit`.
    #[must_use]
    pub fn new(dims: Dims) -> Self {
        Self {
            dims,
            state_bounds: None,
            input_range: None,
            mhe: None,
            ukf: None,
            memory_limit: DEFAULT_MEMORY_LIMIT,
            raise_memory: "the keyword memory_limit",
            memory_ceiling: u64::MAX,
        }
    }
}

/// The settings of a row of kind `kind` (`name`, such as `estimator czf`, in messages) from `source` over `cx`:
/// `None` for a kind without settings. Every key of `source` must be one of `kind`'s keywords.
///
/// # Errors
/// The source's error for a value of the wrong type, out of its choices or of the wrong length, a
/// pair given half, a setting the kind needs and nobody gave, a window beyond its memory or
/// iteration limit, and a key the kind does not take (naming those it takes).
pub fn read_settings<S: KeywordSource>(
    kind: SettingsKind,
    name: &str,
    cx: &KeywordContext<'_>,
    source: &mut S,
) -> Result<Option<EstimatorSettings>, S::Error> {
    let dims = cx.dims;
    let settings = match kind {
        SettingsKind::None => None,
        SettingsKind::SetMembership => Some(EstimatorSettings::SetMembership(set_membership(source, cx)?)),
        SettingsKind::SetMembershipInputBox => {
            let smf = set_membership(source, cx)?;
            let (lower, upper) = match (bounds(source, "u_lower", "u_upper", dims.inputs, false)?, cx.input_range) {
                (Some(b), _) => b,
                (None, Some(b)) => b.clone(),
                (None, None) => {
                    return Err(source.refuse(
                        "u_lower",
                        format!("{name} needs the input range: u_lower, u_upper (length p = {})", dims.inputs),
                    ));
                }
            };
            Some(EstimatorSettings::SetMembershipInputBox(smf, InputBox { lower, upper }))
        }
        SettingsKind::MovingHorizon => Some(EstimatorSettings::MovingHorizon(Box::new(moving_horizon(source, cx)?))),
        SettingsKind::Unscented => {
            Some(EstimatorSettings::Unscented(sigma_points(source, cx.ukf.unwrap_or_default())?))
        }
        SettingsKind::NonlinearMovingHorizon => {
            Some(EstimatorSettings::NonlinearMovingHorizon(Box::new(nonlinear_moving_horizon(source, cx)?)))
        }
        SettingsKind::FuzzyAdaptive => Some(EstimatorSettings::FuzzyAdaptive(Box::new(fuzzy_adaptive(source)?))),
        SettingsKind::ConstrainedZonotope => {
            Some(EstimatorSettings::ConstrainedZonotope(constrained_zonotope(source, cx)?))
        }
    };
    finish(kind, name, source)?;
    Ok(settings)
}

/// A model file's `[mhe]` table: the moving-horizon settings every such estimator starts from
/// (`name` in messages); the keywords of [`SettingsKind::MovingHorizon`].
///
/// # Errors
/// As [`read_settings`].
pub fn read_moving_horizon<S: KeywordSource>(
    name: &str,
    cx: &KeywordContext<'_>,
    source: &mut S,
) -> Result<MheSettings, S::Error> {
    let s = moving_horizon(source, cx)?;
    finish(SettingsKind::MovingHorizon, name, source)?;
    Ok(s)
}

/// A model file's `[ukf]` table: `alpha`, `beta`, `kappa` over the defaults.
///
/// # Errors
/// As [`read_settings`].
pub fn read_sigma_points<S: KeywordSource>(name: &str, source: &mut S) -> Result<UkfParams, S::Error> {
    let s = sigma_points(source, UkfParams::default())?;
    finish(SettingsKind::Unscented, name, source)?;
    Ok(s)
}

/// Refuses the keys nobody read, naming those `kind` takes.
fn finish<S: KeywordSource>(kind: SettingsKind, name: &str, source: &S) -> Result<(), S::Error> {
    let unread = source.unread();
    let Some(first) = unread.first() else {
        return Ok(());
    };
    let takes: Vec<&str> = kind.keywords().iter().map(|k| k.name).collect();
    let takes = if takes.is_empty() { "no settings".to_owned() } else { takes.join(", ") };
    Err(source.refuse(first, format!("unknown setting(s) {} for {name} (it takes: {takes})", unread.join(", "))))
}

/// One of `options` by name.
fn choice<S: KeywordSource, T: Copy>(
    source: &mut S,
    key: &'static str,
    options: &[(&str, T)],
) -> Result<Option<T>, S::Error> {
    let Some(given) = source.text(key)? else {
        return Ok(None);
    };
    match options.iter().find(|(n, _)| *n == given) {
        Some((_, t)) => Ok(Some(*t)),
        None => {
            let known: Vec<&str> = options.iter().map(|(n, _)| *n).collect();
            Err(source.refuse(key, format!("unknown value {given:?} (one of: {})", known.join(", "))))
        }
    }
}

/// A pair of bound vectors `(lower, upper)` of length `len`, both or neither; `±inf` allowed
/// where `infinite` (a bound that is not there), NaN never.
fn bounds<S: KeywordSource>(
    source: &mut S,
    lower: &'static str,
    upper: &'static str,
    len: usize,
    infinite: bool,
) -> Result<Option<Bounds>, S::Error> {
    let (lo, hi) = (source.numbers(lower)?, source.numbers(upper)?);
    let vector = |source: &S, key: &'static str, v: Vec<f64>| {
        if v.len() != len {
            return Err(source.refuse(key, format!("expected {len} entries, found {}", v.len())));
        }
        let bad = |x: &f64| if infinite { x.is_nan() } else { !x.is_finite() };
        if let Some(j) = v.iter().position(bad) {
            let what = if infinite { "not a number" } else { "not finite" };
            return Err(source.refuse(key, format!("entry {} is {what}", j + 1)));
        }
        Ok(DVector::from_vec(v))
    };
    match (lo, hi) {
        (Some(l), Some(u)) => Ok(Some((vector(source, lower, l)?, vector(source, upper, u)?))),
        (None, None) => Ok(None),
        (Some(_), None) => Err(source.refuse(lower, format!("give both {lower} and {upper}, or neither"))),
        (None, Some(_)) => Err(source.refuse(upper, format!("give both {lower} and {upper}, or neither"))),
    }
}

/// An iteration count of at most [`MAX_WINDOW_ITERATIONS`].
fn iteration_count<S: KeywordSource>(source: &mut S, key: &'static str) -> Result<Option<usize>, S::Error> {
    match source.count(key)? {
        Some(v) if v > MAX_WINDOW_ITERATIONS => Err(source
            .refuse(key, format!("at most {MAX_WINDOW_ITERATIONS} sweeps (or Newton iterations) per window, got {v}"))),
        other => Ok(other),
    }
}

/// Refuses a window whose buffers (`need` bytes, `None`: beyond `u128`) would exceed the limit,
/// at the key that sizes them, before anything is allocated.
fn check_memory<S: KeywordSource>(
    source: &S,
    need: Option<u128>,
    limit: u64,
    cx: &KeywordContext<'_>,
    (key, what): (&'static str, String),
) -> Result<(), S::Error> {
    if need.is_some_and(|n| n <= u128::from(limit)) {
        return Ok(());
    }
    let need = need.map_or_else(|| "more than 2^128 bytes".to_owned(), |n| format!("about {}", show_bytes(n)));
    Err(source.refuse(
        key,
        format!(
            "{what} needs {need} for n = {} states and m = {} outputs, more than the limit of {} (raise it with {}; \
             a step's time grows with the window too)",
            cx.dims.states,
            cx.dims.outputs,
            show_bytes(u128::from(limit)),
            cx.raise_memory
        ),
    ))
}

/// `bytes` for people: `512 B`, `16 MiB`, `1.5 GiB`, `3.2e9 EiB`.
#[must_use]
pub fn show_bytes(bytes: u128) -> String {
    const UNITS: [&str; 6] = ["KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    if bytes < 1024 {
        return format!("{bytes} B");
    }
    let mut value = bytes as f64 / 1024.0;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < UNITS.len() {
        value /= 1024.0;
        unit += 1;
    }
    if value >= 1e4 {
        format!("{value:.1e} {}", UNITS[unit])
    } else if value.fract() == 0.0 {
        format!("{value} {}", UNITS[unit])
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

/// The `memory_limit` keyword, or the context's.
fn memory_limit<S: KeywordSource>(source: &mut S, cx: &KeywordContext<'_>) -> Result<u64, S::Error> {
    match source.count("memory_limit")? {
        Some(v) => match u64::try_from(v) {
            Ok(v) if v <= cx.memory_ceiling => Ok(v),
            _ => Err(source.refuse(
                "memory_limit",
                format!(
                    "{v} bytes is above the limit of {} this file is read under (raise that with {})",
                    show_bytes(u128::from(cx.memory_ceiling)),
                    cx.raise_memory
                ),
            )),
        },
        None => Ok(cx.memory_limit),
    }
}

/// `inconsistency`: `error` (the default), `flag` or `restart`.
fn inconsistency<S: KeywordSource>(source: &mut S) -> Result<InconsistencyPolicy, S::Error> {
    Ok(choice(
        source,
        "inconsistency",
        &[
            ("error", InconsistencyPolicy::Error),
            ("flag", InconsistencyPolicy::FlagAndContinue),
            ("restart", InconsistencyPolicy::Restart),
        ],
    )?
    .unwrap_or_default())
}

/// `solver`, `inconsistency`, `interval_observer` (default true) and `x_lower`, `x_upper` over
/// the file's state bounds.
fn set_membership<S: KeywordSource>(
    source: &mut S,
    cx: &KeywordContext<'_>,
) -> Result<SetMembershipSettings, S::Error> {
    let interval_observer = source.flag("interval_observer")?.unwrap_or(true);
    // The file's bounds are the vehicle's, used where they can be: not by a linear filter without
    // its observer (bounds given as keywords then are refused when the filter is built).
    let state_bounds = match bounds(source, "x_lower", "x_upper", cx.dims.states, true)? {
        Some(b) => Some(b),
        None if interval_observer => cx.state_bounds.cloned(),
        None => None,
    };
    let solver = match source.text("solver")? {
        Some(name) => SmfSolver::by_name(&name).map_err(|e| source.refuse("solver", e.to_string()))?,
        None => SmfSolver::default(),
    };
    let inconsistency = inconsistency(source)?;
    Ok(SetMembershipSettings { solver, inconsistency, state_bounds, interval_observer })
}

/// The (robust) moving-horizon estimators: the file's `[mhe]` table (or the noise boxes given
/// here) with the keywords over it.
fn moving_horizon<S: KeywordSource>(source: &mut S, cx: &KeywordContext<'_>) -> Result<MheSettings, S::Error> {
    let dims = cx.dims;
    let w = bounds(source, "w_lower", "w_upper", dims.states, true)?;
    let v = bounds(source, "v_lower", "v_upper", dims.outputs, false)?;
    let mut s = match (cx.mhe, w, v) {
        (Some(base), w, v) => {
            let mut s = base.clone();
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
            return Err(source.refuse(
                "w_lower",
                "the moving-horizon estimators need the noise boxes: w_lower, w_upper (length n) and v_lower, \
                 v_upper (length m)"
                    .into(),
            ));
        }
    };
    let limit = memory_limit(source, cx)?;
    let horizon = source.count("horizon")?;
    let presets = [BlockingPreset::Rmhe, BlockingPreset::RmheOp, BlockingPreset::RmheOf];
    let preset_names: Vec<(String, BlockingPreset)> = presets.iter().map(|p| (p.name().to_lowercase(), *p)).collect();
    let preset_options: Vec<(&str, BlockingPreset)> = preset_names.iter().map(|(n, p)| (n.as_str(), *p)).collect();
    let preset = choice(source, "preset", &preset_options)?;
    let blocks = source.counts("blocks")?;
    let inner =
        choice(source, "inner", &[("active-set", InnerSolver::ActiveSet), ("clarabel", InnerSolver::Clarabel)])?;
    let output_constraint = source.flag("output_constraint")?;
    // The window's size is checked before any buffer of the horizon's length is made.
    let h = horizon.unwrap_or(s.horizon);
    let block_count = match (&blocks, horizon) {
        (Some(b), _) => b.len(),
        (None, Some(h)) => h,
        (None, None) => s.blocks.len(),
    };
    let clarabel = output_constraint.unwrap_or(s.output_constraint)
        || inner == Some(InnerSolver::Clarabel)
        || matches!(s.solver, WindowSolver::CoordinateRotation { inner: InnerSolver::Clarabel, .. });
    let need = memory_estimate(dims.states, dims.outputs, dims.inputs, h, block_count, clarabel);
    let sizing = match (&blocks, horizon, preset) {
        (Some(_), _, _) if block_count > h => "blocks",
        (_, Some(_), _) => "horizon",
        (Some(_), None, _) => "blocks",
        (None, None, Some(_)) => "preset",
        (None, None, None) => "w_lower",
    };
    let what = format!("a horizon of N = {h} in {block_count} blocks");
    check_memory(source, need, limit, cx, (sizing, what))?;
    if let Some(b) = &blocks
        && b.iter().try_fold(0_usize, |sum, &d| sum.checked_add(d)).is_none()
    {
        return Err(source.refuse("blocks", "the block lengths overflow when summed (they must sum to N)".into()));
    }
    if let Some(h) = horizon {
        s.horizon = h;
        s.blocks = vec![1; h];
    }
    match (preset, blocks) {
        (Some(p), None) => s.blocks = p.lengths(s.horizon).map_err(|e| source.refuse("preset", e.to_string()))?,
        (None, Some(b)) => s.blocks = b,
        (None, None) => {}
        (Some(_), Some(_)) => return Err(source.refuse("preset", "give preset or blocks, not both".into())),
    }
    if let Some(bw) =
        choice(source, "block_weighting", &[("length", BlockWeighting::Length), ("unit", BlockWeighting::Unit)])?
    {
        s.block_weighting = bw;
    }
    let (lambda_v, alpha) = (source.number("lambda_v")?, source.number("alpha")?);
    let alpha_map = choice(
        source,
        "alpha_map",
        &[("one-over-one-minus-alpha", AlphaMap::OneOverOneMinusAlpha), ("one-over-alpha", AlphaMap::OneOverAlpha)],
    )?;
    match (lambda_v, alpha) {
        (Some(l), None) => s.cost = MheCost::MinMax { lambda_v: l },
        (None, Some(a)) => {
            let map = alpha_map.unwrap_or(AlphaMap::OneOverOneMinusAlpha);
            let lambda_v = map.lambda_v(a).map_err(|e| source.refuse("alpha", e.to_string()))?;
            s.cost = MheCost::MinMax { lambda_v };
        }
        (None, None) if alpha_map.is_some() => {
            return Err(source.refuse("alpha_map", "alpha_map applies to alpha".into()));
        }
        (None, None) => {}
        (Some(_), Some(_)) => return Err(source.refuse("lambda_v", "give lambda_v or alpha, not both".into())),
    }
    let theta = source.number("theta")?;
    match choice(source, "arrival", &[("kalman", false), ("h-infinity", true)])? {
        Some(true) => s.arrival = ArrivalRecursion::HInfinity { theta: theta.unwrap_or(0.9) },
        Some(false) if theta.is_some() => {
            return Err(source.refuse("theta", "theta applies to arrival = \"h-infinity\"".into()));
        }
        Some(false) => s.arrival = ArrivalRecursion::Kalman,
        None => match (&mut s.arrival, theta) {
            (ArrivalRecursion::HInfinity { theta }, Some(t)) => *theta = t,
            (_, Some(_)) => return Err(source.refuse("theta", "theta applies to arrival = \"h-infinity\"".into())),
            (_, None) => {}
        },
    }
    if let Some(p) =
        choice(source, "prior_mean", &[("smoothed", PriorMean::Smoothed), ("filtered", PriorMean::Filtered)])?
    {
        s.prior_mean = p;
    }
    if let Some(o) = output_constraint {
        s.output_constraint = o;
    }
    let (sweeps, tolerance) = (iteration_count(source, "max_sweeps")?, source.number("tolerance")?);
    let exact = choice(source, "solver", &[("coordinate-rotation", false), ("exact-saddle", true)])?;
    let exact = exact.unwrap_or(matches!(s.solver, WindowSolver::ExactSaddle { .. }));
    let base = match (exact, s.solver) {
        (false, current @ WindowSolver::CoordinateRotation { .. })
        | (true, current @ WindowSolver::ExactSaddle { .. }) => current,
        (false, _) => WindowSolver::coordinate_rotation(),
        (true, _) => WindowSolver::exact_saddle(),
    };
    s.solver = match base {
        WindowSolver::CoordinateRotation { max_sweeps, tolerance: t, inner: i } => WindowSolver::CoordinateRotation {
            max_sweeps: sweeps.unwrap_or(max_sweeps),
            tolerance: tolerance.unwrap_or(t),
            inner: inner.unwrap_or(i),
        },
        WindowSolver::ExactSaddle { .. } if inner.is_some() => {
            return Err(source.refuse("inner", "inner applies to solver = \"coordinate-rotation\"".into()));
        }
        WindowSolver::ExactSaddle { max_iterations, tolerance: t } => WindowSolver::ExactSaddle {
            max_iterations: sweeps.unwrap_or(max_iterations),
            tolerance: tolerance.unwrap_or(t),
        },
    };
    Ok(s)
}

/// The nonlinear moving-horizon estimator: the row's defaults with the keywords over them.
fn nonlinear_moving_horizon<S: KeywordSource>(
    source: &mut S,
    cx: &KeywordContext<'_>,
) -> Result<NonlinearMheSettings, S::Error> {
    let dims = cx.dims;
    let mut s = super::settings::nonlinear_mhe_default();
    let limit = memory_limit(source, cx)?;
    if let Some(h) = source.count("horizon")? {
        s.horizon = h;
    }
    if let Some(i) = iteration_count(source, "max_iterations")? {
        s.max_iterations = i;
    }
    // Checked (1 to MAX_REAL_TIME_ITERATIONS) with the other settings when the estimator is built.
    s.real_time_iterations = source.count("real_time_iterations")?;
    if let Some(t) = source.number("tolerance")? {
        s.tolerance = t;
    }
    let base = match s.arrival {
        NonlinearArrival::Ukf(p) => p,
        _ => UkfParams::default(),
    };
    let given = [source.number("alpha")?, source.number("beta")?, source.number("kappa")?];
    let sigma = UkfParams {
        alpha: given[0].unwrap_or(base.alpha),
        beta: given[1].unwrap_or(base.beta),
        kappa: given[2].unwrap_or(base.kappa),
    };
    let arrival = choice(source, "arrival", &[("unscented", 0u8), ("extended", 1), ("fixed", 2)])?;
    if matches!(arrival, Some(1 | 2))
        && let Some(i) = given.iter().position(Option::is_some)
    {
        let key = ["alpha", "beta", "kappa"][i];
        return Err(source.refuse(key, format!("{key} sets the sigma points of arrival = \"unscented\" only")));
    }
    match arrival {
        Some(1) => s.arrival = NonlinearArrival::Ekf,
        Some(2) => s.arrival = NonlinearArrival::Fixed,
        _ => s.arrival = NonlinearArrival::Ukf(sigma),
    }
    if let Some(p) = choice(
        source,
        "prior",
        &[("smoothed", NonlinearPrior::Smoothed), ("arrival-filter", NonlinearPrior::ArrivalFilter)],
    )? {
        s.prior = p;
    }
    if let Some(w) = bounds(source, "w_lower", "w_upper", dims.states, true)? {
        s.w_box = Some(w);
    }
    if let Some(v) = bounds(source, "v_lower", "v_upper", dims.outputs, false)? {
        s.v_box = Some(v);
    }
    let need = s.memory_estimate(dims.states, dims.outputs, dims.inputs);
    check_memory(source, need, limit, cx, ("horizon", format!("a horizon of N = {}", s.horizon)))?;
    Ok(s)
}

/// `alpha`, `beta`, `kappa` over `base`.
fn sigma_points<S: KeywordSource>(source: &mut S, base: UkfParams) -> Result<UkfParams, S::Error> {
    Ok(UkfParams {
        alpha: source.number("alpha")?.unwrap_or(base.alpha),
        beta: source.number("beta")?.unwrap_or(base.beta),
        kappa: source.number("kappa")?.unwrap_or(base.kappa),
    })
}

/// `fis` (a rule file) or `fis_toml` (its text), and `horizontal`.
fn fuzzy_adaptive<S: KeywordSource>(source: &mut S) -> Result<FuzzyAdaptiveSettings, S::Error> {
    let mut s = FuzzyAdaptiveSettings::default();
    match (source.path("fis")?, source.text("fis_toml")?) {
        (Some(path), None) => {
            s.system = FuzzySystem::from_toml_file(&path).map_err(|e| source.refuse("fis", e.to_string()))?;
        }
        (None, Some(text)) => {
            s.system = FuzzySystem::from_toml_str(&text, "<fis_toml>")
                .map_err(|e| source.refuse("fis_toml", e.to_string()))?;
        }
        (None, None) => {}
        (Some(_), Some(_)) => {
            return Err(source.refuse("fis", "give fis (a file) or fis_toml (its text), not both".into()));
        }
    }
    if let Some(pair) = source.counts("horizontal")? {
        let [i, j] = pair[..] else {
            return Err(source.refuse("horizontal", format!("expected 2 output indices, found {}", pair.len())));
        };
        s.horizontal = [i, j];
    }
    Ok(s)
}

/// `order`, `max_constraints`, `inconsistency`, `x_lower`/`x_upper` (over the file's),
/// `divergence_factor`.
fn constrained_zonotope<S: KeywordSource>(
    source: &mut S,
    cx: &KeywordContext<'_>,
) -> Result<ConstrainedZonotopeSettings, S::Error> {
    let mut s = ConstrainedZonotopeSettings::default();
    if let Some(order) = source.count("order")? {
        s.order = order;
    }
    if let Some(nc) = source.count("max_constraints")? {
        s.max_constraints = nc;
    }
    if let Some(f) = source.number("divergence_factor")? {
        s.divergence_factor = f;
    }
    s.inconsistency = inconsistency(source)?;
    s.state_bounds = bounds(source, "x_lower", "x_upper", cx.dims.states, true)?.or_else(|| cx.state_bounds.cloned());
    Ok(s)
}
