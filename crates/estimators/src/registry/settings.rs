//! The settings an estimator takes beyond its [`Setup`](crate::Setup): one typed variant of
//! [`EstimatorSettings`] per [`SettingsKind`], their defaults, and the keywords (with their
//! meanings) every surface spells them with.

use nalgebra::DVector;

use fuzzy_inference::FuzzySystem;
use lmi::SolverSettings;

use crate::czf::ConstrainedZonotopeSettings;
use crate::error::EstimatorError;
use crate::mhe::{MheSettings, NonlinearMheSettings};
use crate::smf::InconsistencyPolicy;
use crate::ukf::UkfParams;

/// How a set-membership filter solves (29), parsed from a name in one place
/// ([`SmfSolver::by_name`]).
#[derive(Debug, Clone, PartialEq, Default)]
#[non_exhaustive]
pub enum SmfSolver {
    /// The exact two-multiplier method (the default; microseconds per step).
    #[default]
    TwoMultiplier,
    /// An SDP backend of `lmi` on LMI (28).
    Sdp {
        /// The backend's name ([`lmi::backend_names`]).
        backend: &'static str,
        /// Its settings.
        settings: SolverSettings,
    },
}

impl SmfSolver {
    /// The name of the two-multiplier method.
    pub const TWO_MULTIPLIER: &'static str = "two-multiplier";

    /// The names this build accepts: the two-multiplier method, then the SDP backends.
    #[must_use]
    pub fn names() -> Vec<&'static str> {
        let mut v = vec![Self::TWO_MULTIPLIER];
        v.extend(lmi::backend_names());
        v
    }

    /// The solver called `name`. An SDP backend gets [`SmfSolver::sdp_settings`]: it
    /// warm-starts from the previous step (a filter's SDPs at consecutive steps are nearby
    /// problems; the filter certifies its set whatever the solver returns).
    ///
    /// # Errors
    /// [`EstimatorError::UnknownSolver`] naming the known ones.
    pub fn by_name(name: &str) -> Result<Self, EstimatorError> {
        if name == Self::TWO_MULTIPLIER {
            return Ok(SmfSolver::TwoMultiplier);
        }
        match lmi::backend_names().into_iter().find(|b| *b == name) {
            Some(backend) => Ok(SmfSolver::Sdp { backend, settings: Self::sdp_settings() }),
            None => Err(EstimatorError::UnknownSolver { name: name.to_owned(), known: Self::names().join(", ") }),
        }
    }

    /// The settings of an SDP-backed filter ([`SmfSolver::by_name`]): warm start from the previous
    /// step, and duality-gap tolerances of `1e-9`, ten times tighter than `lmi`'s default.
    ///
    /// The filter keeps only the SDP's `τ`, and the trace of the set it publishes is not flat in
    /// `τ` when the optimum of (29) lies on the boundary of the simplex. With `n = m` it often
    /// does: `τ = (0, 0, 1)`, the measurement's own ellipsoid. There an interior-point iterate
    /// stopped at a gap of `10⁻⁸` still has `τ₁, τ₂ ≈ 10⁻⁶`, and the published trace moves
    /// linearly with them: on 768 steps of random systems (`tests/sdp_objective.rs`) three first
    /// steps of `faer-ipm` were `1.1–3.0·10⁻⁶` relative above the exact solver's. With gap
    /// tolerances of `10⁻⁹` the worst is `1.9·10⁻⁷`, for 7 % more iterations (7.09 → 7.60 per
    /// step on that test). Tightening the feasibility tolerance too costs more for less; `10⁻¹⁰`
    /// doubles the iterations.
    #[must_use]
    pub fn sdp_settings() -> SolverSettings {
        SolverSettings { warm_start: true, tol_gap_rel: 1e-9, tol_gap_abs: 1e-9, ..SolverSettings::default() }
    }

    /// The solver's name.
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self {
            SmfSolver::TwoMultiplier => Self::TWO_MULTIPLIER,
            SmfSolver::Sdp { backend, .. } => backend,
        }
    }

    /// One line for `--help`.
    #[must_use]
    pub fn summary(name: &str) -> &'static str {
        if name == Self::TWO_MULTIPLIER { "exact two-multiplier method (fastest)" } else { "SDP backend on LMI (28)" }
    }
}

/// Settings of the set-membership filters.
#[derive(Debug, Clone, PartialEq)]
pub struct SetMembershipSettings {
    /// How (29) is solved.
    pub solver: SmfSolver,
    /// What a step does with data that contradict the noise bounds (default: an error).
    pub inconsistency: InconsistencyPolicy,
    /// `(lower, upper)`: bounds the true state always respects (length `n` each, ±∞ where none).
    /// They cut the published interval: `smf-nl`'s (N1')
    /// ([`with_state_bounds`](crate::smf::NonlinearSetMembershipFilter::with_state_bounds),
    /// docs/nonlinear-smf.md), the linear filters' through their interval observer (which they
    /// then need).
    pub state_bounds: Option<(DVector<f64>, DVector<f64>)>,
    /// The linear filters (`smf`, `yang-li*`): run the interval observer beside the ellipsoid
    /// ([`ObservedSetMembershipFilter`](crate::smf::ObservedSetMembershipFilter),
    /// docs/carrier-smf.md §4.8), so that the published interval is never wider than an interval
    /// observer's. Default `true`; `false` publishes the paper's
    /// filter alone (the reproduction does). `smf-nl` always runs its own.
    pub interval_observer: bool,
}

impl Default for SetMembershipSettings {
    fn default() -> Self {
        Self {
            solver: SmfSolver::default(),
            inconsistency: InconsistencyPolicy::default(),
            state_bounds: None,
            interval_observer: true,
        }
    }
}

/// The known range of the input, `lower ≤ u ≤ upper` componentwise.
#[derive(Debug, Clone, PartialEq)]
pub struct InputBox {
    /// Lower bounds (length `p`).
    pub lower: DVector<f64>,
    /// Upper bounds (length `p`).
    pub upper: DVector<f64>,
}

/// Settings of the fuzzy-adaptive Kalman filter.
#[derive(Debug, Clone)]
pub struct FuzzyAdaptiveSettings {
    /// The Mamdani system with inputs `[N, RTK, d]`.
    pub system: FuzzySystem,
    /// The two outputs whose innovation forms `d_k`.
    pub horizontal: [usize; 2],
}

impl Default for FuzzyAdaptiveSettings {
    /// The digest's 45-rule system ([`FuzzySystem::bds_ins_default`]), `d` from outputs 0 and 1.
    fn default() -> Self {
        Self { system: FuzzySystem::bds_ins_default(), horizontal: [0, 1] }
    }
}

/// The settings an estimator takes beyond its [`Setup`](crate::Setup); the variant is the row's
/// [`SettingsKind`].
#[derive(Debug, Clone)]
#[non_exhaustive]
pub enum EstimatorSettings {
    /// None (Kalman and extended Kalman filters).
    None,
    /// A set-membership filter's solver and inconsistency policy.
    SetMembership(SetMembershipSettings),
    /// The same, and the known input box (the Yang–Li reconstruction (a)).
    SetMembershipInputBox(SetMembershipSettings, InputBox),
    /// The (robust) moving-horizon estimators.
    MovingHorizon(Box<MheSettings>),
    /// The unscented filter's sigma points.
    Unscented(UkfParams),
    /// The nonlinear moving-horizon estimator.
    NonlinearMovingHorizon(Box<NonlinearMheSettings>),
    /// The fuzzy-adaptive filter's system.
    FuzzyAdaptive(Box<FuzzyAdaptiveSettings>),
    /// The constrained-zonotope filters' reduction limits, policy, bounds and divergence rule.
    ConstrainedZonotope(ConstrainedZonotopeSettings),
}

impl EstimatorSettings {
    /// How (29) is solved, for the settings of a set-membership filter; `None` for the others.
    #[must_use]
    pub fn smf_solver(&self) -> Option<&SmfSolver> {
        match self {
            EstimatorSettings::SetMembership(s) | EstimatorSettings::SetMembershipInputBox(s, _) => Some(&s.solver),
            _ => None,
        }
    }

    /// Which kind of settings this is.
    #[must_use]
    pub fn kind(&self) -> SettingsKind {
        match self {
            EstimatorSettings::None => SettingsKind::None,
            EstimatorSettings::SetMembership(_) => SettingsKind::SetMembership,
            EstimatorSettings::SetMembershipInputBox(..) => SettingsKind::SetMembershipInputBox,
            EstimatorSettings::MovingHorizon(_) => SettingsKind::MovingHorizon,
            EstimatorSettings::Unscented(_) => SettingsKind::Unscented,
            EstimatorSettings::NonlinearMovingHorizon(_) => SettingsKind::NonlinearMovingHorizon,
            EstimatorSettings::FuzzyAdaptive(_) => SettingsKind::FuzzyAdaptive,
            EstimatorSettings::ConstrainedZonotope(_) => SettingsKind::ConstrainedZonotope,
        }
    }
}

/// The nonlinear moving-horizon estimator's default: the paper's settings with sigma points valid
/// for every `n` (the paper's `κ = −2` needs `n > 2`).
pub(super) fn nonlinear_mhe_default() -> NonlinearMheSettings {
    NonlinearMheSettings {
        arrival: crate::mhe::NonlinearArrival::Ukf(UkfParams::default()),
        ..NonlinearMheSettings::paper()
    }
}

/// One keyword of an estimator's settings ([`SettingsKind::keywords`]): its name and meaning.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Keyword {
    /// The keyword (`solver`, `horizon`).
    pub name: &'static str,
    /// What it sets, in one line, with its default.
    pub meaning: &'static str,
}

/// Which [`EstimatorSettings`] variant a row takes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum SettingsKind {
    /// [`EstimatorSettings::None`].
    None,
    /// [`EstimatorSettings::SetMembership`].
    SetMembership,
    /// [`EstimatorSettings::SetMembershipInputBox`].
    SetMembershipInputBox,
    /// [`EstimatorSettings::MovingHorizon`].
    MovingHorizon,
    /// [`EstimatorSettings::Unscented`].
    Unscented,
    /// [`EstimatorSettings::NonlinearMovingHorizon`].
    NonlinearMovingHorizon,
    /// [`EstimatorSettings::FuzzyAdaptive`].
    FuzzyAdaptive,
    /// [`EstimatorSettings::ConstrainedZonotope`].
    ConstrainedZonotope,
}

impl SettingsKind {
    /// What the settings are, in words.
    #[must_use]
    pub fn describe(self) -> &'static str {
        match self {
            SettingsKind::None => "no settings",
            SettingsKind::SetMembership => "set-membership settings (solver, inconsistency policy)",
            SettingsKind::SetMembershipInputBox => "set-membership settings and the input box",
            SettingsKind::MovingHorizon => {
                "moving-horizon settings (horizon, blocks, noise boxes W and V, lambda_v, solver)"
            }
            SettingsKind::Unscented => "sigma-point parameters (alpha, beta, kappa)",
            SettingsKind::NonlinearMovingHorizon => "nonlinear moving-horizon settings",
            SettingsKind::FuzzyAdaptive => "a fuzzy system with inputs [N, RTK, d]",
            SettingsKind::ConstrainedZonotope => {
                "constrained-zonotope settings (order, max_constraints, inconsistency policy, state bounds, \
                 divergence factor)"
            }
        }
    }

    /// The default settings, `None` when they depend on data only the user has (the input box,
    /// the noise boxes).
    #[must_use]
    pub fn default_settings(self) -> Option<EstimatorSettings> {
        match self {
            SettingsKind::None => Some(EstimatorSettings::None),
            SettingsKind::SetMembership => Some(EstimatorSettings::SetMembership(SetMembershipSettings::default())),
            SettingsKind::SetMembershipInputBox | SettingsKind::MovingHorizon => None,
            SettingsKind::Unscented => Some(EstimatorSettings::Unscented(UkfParams::default())),
            SettingsKind::NonlinearMovingHorizon => {
                Some(EstimatorSettings::NonlinearMovingHorizon(Box::new(nonlinear_mhe_default())))
            }
            SettingsKind::FuzzyAdaptive => Some(EstimatorSettings::FuzzyAdaptive(Box::default())),
            SettingsKind::ConstrainedZonotope => {
                Some(EstimatorSettings::ConstrainedZonotope(ConstrainedZonotopeSettings::default()))
            }
        }
    }

    /// The keywords of these settings, each with its meaning: what Python takes as keyword
    /// arguments and `port-est estimators` lists (the model file spells its sections with the same
    /// names). One list for every surface; the Python package's tests hold its parser to it.
    #[must_use]
    pub fn keywords(self) -> &'static [Keyword] {
        const fn k(name: &'static str, meaning: &'static str) -> Keyword {
            Keyword { name, meaning }
        }
        const SOLVER: Keyword =
            k("solver", "how (29) is solved: two-multiplier (exact, the default) or an SDP backend (solvers())");
        const INCONSISTENCY: Keyword = k(
            "inconsistency",
            "what a step does with data that contradict the bounds: error (the default), flag or restart",
        );
        const X_LOWER: Keyword =
            k("x_lower", "lower bounds the true state always respects (length n, -inf where none)");
        const X_UPPER: Keyword = k("x_upper", "upper bounds the true state always respects (length n, inf where none)");
        const OBSERVER: Keyword =
            k("interval_observer", "run the interval observer beside the ellipsoid (default true; false: the paper's)");
        const W_LOWER: Keyword = k("w_lower", "lower corner of the process-noise box (length n)");
        const W_UPPER: Keyword = k("w_upper", "upper corner of the process-noise box (length n)");
        const V_LOWER: Keyword = k("v_lower", "lower corner of the measurement-noise box (length m)");
        const V_UPPER: Keyword = k("v_upper", "upper corner of the measurement-noise box (length m)");
        const MEMORY: Keyword =
            k("memory_limit", "bytes the window may take (default 256 MiB), checked before anything is allocated");
        const TOLERANCE: Keyword = k("tolerance", "the window's iteration stops when its step is below this");
        const ALPHA: Keyword = k("alpha", "sigma-point spread (default 1)");
        const BETA: Keyword = k("beta", "sigma-point weight of the prior's shape (default 2)");
        const KAPPA: Keyword = k("kappa", "secondary sigma-point scaling (default 0)");
        const SET_MEMBERSHIP_KEYWORDS: &[Keyword] = &[SOLVER, INCONSISTENCY, X_LOWER, X_UPPER, OBSERVER];
        const SET_MEMBERSHIP_INPUT_BOX_KEYWORDS: &[Keyword] = &[
            SOLVER,
            INCONSISTENCY,
            k("u_lower", "lower bounds of the input (length p)"),
            k("u_upper", "upper bounds of the input (length p)"),
            X_LOWER,
            X_UPPER,
            OBSERVER,
        ];
        const MOVING_HORIZON_KEYWORDS: &[Keyword] = &[
            W_LOWER,
            W_UPPER,
            V_LOWER,
            V_UPPER,
            k("horizon", "window length N (default 6)"),
            k("preset", "disturbance blocking: rmhe, rmhe-op or rmhe-of"),
            k("blocks", "disturbance block lengths, instead of a preset"),
            k("block_weighting", "a block's weight: length (default) or unit"),
            k("lambda_v", "weight of the measurement-noise term (default 10)"),
            k("alpha", "the weight as alpha in (0, 1), instead of lambda_v (lambda_v = 1/(1 - alpha))"),
            k("alpha_map", "how alpha gives lambda_v: one-over-one-minus-alpha (default) or one-over-alpha"),
            k("output_constraint", "also constrain each window's output residuals to V (default false)"),
            k("arrival", "the arrival cost's recursion: kalman (default) or h-infinity"),
            k("theta", "the h-infinity arrival cost's level (default 0.9)"),
            k("prior_mean", "the arrival cost's mean: smoothed (default) or filtered"),
            k("solver", "how the window is solved: coordinate-rotation (default) or exact-saddle"),
            k("inner", "the coordinate rotation's inner QP solver: active-set (default) or clarabel"),
            k("max_sweeps", "most min/max sweeps of the coordinate rotation (default 10)"),
            TOLERANCE,
            MEMORY,
        ];
        const UNSCENTED_KEYWORDS: &[Keyword] = &[ALPHA, BETA, KAPPA];
        const NONLINEAR_MOVING_HORIZON_KEYWORDS: &[Keyword] = &[
            k("horizon", "window length N (default 10)"),
            k("max_iterations", "most Gauss-Newton iterations per update (default 20)"),
            k(
                "real_time_iterations",
                "1 to 10 Gauss-Newton iterations per update from the previous window (status real-time)",
            ),
            TOLERANCE,
            k("arrival", "the arrival cost: unscented (default), extended or fixed"),
            ALPHA,
            BETA,
            KAPPA,
            k("prior", "the arrival cost's prior: smoothed (default) or arrival-filter"),
            W_LOWER,
            W_UPPER,
            V_LOWER,
            V_UPPER,
            MEMORY,
        ];
        const FUZZY_ADAPTIVE_KEYWORDS: &[Keyword] = &[
            k("fis", "a TOML rule file replacing the paper's 45-rule system"),
            k("fis_toml", "the same rules as text"),
            k("horizontal", "the two outputs whose innovation forms the distance d_k (default (0, 1))"),
        ];
        const CONSTRAINED_ZONOTOPE_KEYWORDS: &[Keyword] = &[
            k("order", "most generators per state after each reduction (default 20)"),
            k("max_constraints", "most equality constraints kept after each reduction (default 8)"),
            INCONSISTENCY,
            X_LOWER,
            X_UPPER,
            k("divergence_factor", "an interval wider than this times its initial width is diverging (default 2)"),
        ];
        match self {
            SettingsKind::None => &[],
            SettingsKind::SetMembership => SET_MEMBERSHIP_KEYWORDS,
            SettingsKind::SetMembershipInputBox => SET_MEMBERSHIP_INPUT_BOX_KEYWORDS,
            SettingsKind::MovingHorizon => MOVING_HORIZON_KEYWORDS,
            SettingsKind::Unscented => UNSCENTED_KEYWORDS,
            SettingsKind::NonlinearMovingHorizon => NONLINEAR_MOVING_HORIZON_KEYWORDS,
            SettingsKind::FuzzyAdaptive => FUZZY_ADAPTIVE_KEYWORDS,
            SettingsKind::ConstrainedZonotope => CONSTRAINED_ZONOTOPE_KEYWORDS,
        }
    }

    /// What these settings need that has no default (only the user knows it), in words with the
    /// keywords that give it; `None` when every setting has a default.
    #[must_use]
    pub fn needs(self) -> Option<&'static str> {
        match self {
            SettingsKind::SetMembershipInputBox => Some("the input range u_lower, u_upper"),
            SettingsKind::MovingHorizon => Some("the noise boxes w_lower, w_upper, v_lower, v_upper"),
            _ => None,
        }
    }

    /// Whether the settings include a solver of (29) (`--solver`).
    #[must_use]
    pub fn uses_smf_solver(self) -> bool {
        matches!(self, SettingsKind::SetMembership | SettingsKind::SetMembershipInputBox)
    }
}
