//! `MODEL.toml`: either the linear discrete-time model `x_{k+1} = a x_k + b u_k + w_k`,
//! `y_{k+1} = c x_{k+1} + v_{k+1}` given by its matrices, or a model written as equations (a
//! `[model]` table, read by `equation-models`), and in both cases its noise descriptions and
//! initial estimate, read with `serde` and checked against the model's dimensions, every complaint
//! at the `file:line:column` of the key's value.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use equation_models::EquationModel;
use estimators::registry::{self, KeywordContext};
use estimators::{EstimateKind, EstimatorError, Setup, UkfParams};
use models::{AnyModel, Capability, ConstantModel, DiscreteModel, LinearModel};
use nalgebra::{DMatrix, DVector};
use serde::Deserialize;
use serde::de::IgnoredAny;
use toml::Spanned;

use crate::builtin::Builtin;
use crate::error::{Error, Location, line_col};
use crate::keyword_table::{KeywordTable, SpannedTable};
use crate::limits::Limits;

/// A `(lower, upper)` pair of bounds.
type Bounds = (DVector<f64>, DVector<f64>);

/// The top-level keys of a model file that `port-est` reads itself; the rest of a model written
/// as equations (`[model]`, `[parameters]`, `[definitions]`, `[f]` or `[dxdt]`, `[h]`) is read by
/// `equation-models`.
pub const NOISE_KEYS: [&str; 18] = [
    "x0",
    "p0",
    "q",
    "r",
    "u_lower",
    "u_upper",
    "x_lower",
    "x_upper",
    "mhe",
    "ukf",
    "estimator",
    "x0_radius",
    "w_radius",
    "v_radius",
    "x0_generators",
    "w_generators",
    "v_generators",
    "log",
];

impl std::fmt::Debug for Dynamics {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Dynamics::Matrices(m) => f.debug_tuple("Matrices").field(m).finish(),
            Dynamics::Equations(m) => f.debug_tuple("Equations").field(m).finish(),
            Dynamics::Builtin { vehicle, .. } => f.debug_tuple("Builtin").field(&vehicle.name).finish(),
        }
    }
}

/// The names of a model file's `[model]` table (a built-in vehicle's file is read for its names
/// and noise only: its model is the compiled one).
#[derive(Debug, Deserialize)]
struct Names {
    #[serde(default)]
    inputs: Vec<String>,
    #[serde(default)]
    outputs: Vec<String>,
}

/// The model file, as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelFile {
    a: Option<Spanned<Vec<Vec<f64>>>>,
    b: Option<Spanned<Vec<Vec<f64>>>>,
    c: Option<Spanned<Vec<Vec<f64>>>>,
    q: Spanned<SquareSpec>,
    r: Spanned<SquareSpec>,
    p0: Spanned<SquareSpec>,
    x0: Spanned<Vec<f64>>,
    u_lower: Option<Spanned<Vec<f64>>>,
    u_upper: Option<Spanned<Vec<f64>>>,
    x_lower: Option<Spanned<Vec<f64>>>,
    x_upper: Option<Spanned<Vec<f64>>>,
    x0_radius: Option<Spanned<Vec<f64>>>,
    w_radius: Option<Spanned<Vec<f64>>>,
    v_radius: Option<Spanned<Vec<f64>>>,
    x0_generators: Option<Spanned<Vec<Vec<f64>>>>,
    w_generators: Option<Spanned<Vec<Vec<f64>>>>,
    v_generators: Option<Spanned<Vec<Vec<f64>>>>,
    mhe: Option<Spanned<SpannedTable>>,
    ukf: Option<Spanned<SpannedTable>>,
    estimator: Option<Spanned<BTreeMap<String, Spanned<SpannedTable>>>>,
    log: Option<Spanned<crate::log_table::LogTable>>,
    // The equation tables, read by `equation-models`.
    model: Option<Spanned<toml::Value>>,
    parameters: Option<IgnoredAny>,
    definitions: Option<IgnoredAny>,
    f: Option<IgnoredAny>,
    dxdt: Option<IgnoredAny>,
    h: Option<IgnoredAny>,
}

/// A covariance or shape as written: the full matrix (a list of rows), its diagonal (a list of
/// numbers) or one number (a multiple of the identity).
#[derive(Debug, Deserialize)]
#[serde(untagged, expecting = "a matrix (a list of rows), a diagonal (a list of numbers) or a number")]
enum SquareSpec {
    Number(f64),
    Diagonal(Vec<f64>),
    Full(Vec<Vec<f64>>),
}

/// What moves the state: the matrices of a linear model, or equations.
#[derive(Clone)]
#[non_exhaustive]
pub enum Dynamics {
    /// `a`, `b`, `c` given as matrices.
    Matrices(ConstantModel),
    /// A `[model]` table of equations (linear or not), compiled by `equation-models`.
    Equations(Arc<EquationModel>),
    /// A built-in vehicle (`builtin:NAME`): the compiled Rust model, and the names of its
    /// inputs and outputs from its model file.
    Builtin {
        /// The vehicle.
        vehicle: &'static crate::builtin::Builtin,
        /// Its compiled model.
        model: crate::builtin::SharedModel,
        /// The names of its inputs and outputs.
        names: (Vec<String>, Vec<String>),
    },
}

/// A validated model: `n` states, `p` inputs, `m` outputs, its noise descriptions and settings.
#[derive(Debug, Clone)]
pub struct Model {
    /// What moves the state.
    pub dynamics: Dynamics,
    /// `Q` (n×n): process-noise shape (set-membership) or covariance (Kalman).
    pub q: DMatrix<f64>,
    /// `R` (m×m): measurement-noise shape or covariance.
    pub r: DMatrix<f64>,
    /// `P₀` (n×n): initial shape or covariance.
    pub p0: DMatrix<f64>,
    /// `x₀` (n): initial centre.
    pub x0: DVector<f64>,
    /// The known input range `(u_lower, u_upper)`, if given.
    pub input_range: Option<(DVector<f64>, DVector<f64>)>,
    /// Bounds `(x_lower, x_upper)` the true state always respects (±inf where none), if given:
    /// used by `smf-nl` (docs/nonlinear-smf.md (N1')).
    pub state_bounds: Option<(DVector<f64>, DVector<f64>)>,
    /// The zonotopes `X₀`, `W`, `V` of the constrained-zonotope filters, if given (each as a box,
    /// `*_radius`, or a generator matrix, `*_generators`).
    pub boxes: Option<Boxes>,
    /// The moving-horizon settings of the `[mhe]` table, if given (checked structurally; the
    /// estimator validates them when built, see [`Model::estimator_error`]).
    pub mhe: Option<estimators::MheSettings>,
    /// The unscented filter's `[ukf]` table, if given (missing entries: the defaults).
    pub ukf: Option<UkfParams>,
    /// How a ROS 2 bag is read as this model's log (the `[log]` table, read as module [`crate::bag`] describes).
    pub log: Option<ros_bag::LogSpec>,
    /// The `[estimator.NAME]` tables: each estimator's settings by the registry's keywords.
    estimator_tables: Vec<(&'static str, KeywordTable)>,
    /// The file it was read from and where each key's value starts, to report later complaints
    /// (an estimator rejecting `q`, say) at the right place.
    source: Source,
}

/// The generator matrices of the initial set `X₀ = {x₀ + G ξ : ‖ξ‖∞ ≤ 1}`, of `W` and of `V`
/// (centred at 0): `*_generators` as given, or `diag(*_radius)` for a box.
#[derive(Debug, Clone, PartialEq)]
pub struct Boxes {
    /// `X₀`'s generators (`n` rows).
    pub x0: DMatrix<f64>,
    /// `W`'s generators (`n` rows).
    pub w: DMatrix<f64>,
    /// `V`'s generators (`m` rows).
    pub v: DMatrix<f64>,
}

/// The most columns a generator matrix of a model file may have.
pub const MAX_GENERATOR_COLUMNS: usize = 1000;

/// Where the keys of a model file are.
#[derive(Debug, Clone, Default)]
struct Source {
    path: PathBuf,
    keys: Vec<(String, u64, u64)>,
    /// The limit of a moving-horizon window's memory (`--mhe-memory-limit`).
    memory_limit: u64,
}

impl Model {
    /// The model as the estimators see it: every capability it offers.
    #[must_use]
    pub fn any(&self) -> &dyn AnyModel {
        match &self.dynamics {
            Dynamics::Matrices(m) => m,
            Dynamics::Equations(m) => m.as_ref(),
            Dynamics::Builtin { model, .. } => model.as_ref(),
        }
    }

    /// The matrices `A`, `B`, `C` when the model is linear (given as matrices, or equations
    /// recognised as linear).
    #[must_use]
    pub fn linear(&self) -> Option<&dyn LinearModel> {
        self.any().linear()
    }

    /// Number of states `n`.
    #[must_use]
    pub fn states(&self) -> usize {
        self.any().discrete().dims().states
    }

    /// Number of inputs `p`.
    #[must_use]
    pub fn inputs(&self) -> usize {
        self.any().discrete().dims().inputs
    }

    /// Number of outputs `m`.
    #[must_use]
    pub fn outputs(&self) -> usize {
        self.any().discrete().dims().outputs
    }

    /// The names of the inputs and outputs, when the model file declares them (equations): the
    /// data file's header may use them instead of `u1…`, `y1…`.
    #[must_use]
    pub fn column_names(&self) -> Option<(&[String], &[String])> {
        match &self.dynamics {
            Dynamics::Matrices(_) => None,
            Dynamics::Equations(m) => Some((m.input_names(), m.output_names())),
            Dynamics::Builtin { names, .. } => Some((&names.0, &names.1)),
        }
    }

    /// Why `needs` is not offered by this model, in words (`None` when it is).
    #[must_use]
    pub fn lacks(&self, needs: Capability) -> Option<String> {
        if needs.is_offered_by(self.any()) {
            return None;
        }
        let file = self.path().display();
        Some(match (&self.dynamics, needs) {
            (Dynamics::Builtin { vehicle, .. }, Capability::SecondOrder) => {
                format!("needs {}; the compiled {} model does not offer them yet", needs.requirement(), vehicle.name)
            }
            (Dynamics::Equations(_), _) => format!(
                "needs {}; the equations of {file} are not linear (or have a constant term, or an output \
                 depends on an input)",
                needs.requirement()
            ),
            (Dynamics::Matrices(_) | Dynamics::Builtin { .. }, _) => format!("needs {}", needs.requirement()),
        })
    }

    /// The file the model was read from.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.source.path
    }

    /// Where the value of `key` (`"q"`, `"x0"`, …) starts in the model file, if it was given.
    #[must_use]
    pub fn key_location(&self, key: &str) -> Option<Location> {
        let &(_, line, column) = self.source.keys.iter().find(|(k, ..)| *k == key)?;
        Some(Location::new(&self.source.path, line, column))
    }

    /// An estimator's complaint about the model (`Q` not positive definite, say), in the model
    /// file's terms: at the `file:line:column` of the key it is about when that can be told.
    #[must_use]
    pub fn estimator_error(&self, e: EstimatorError) -> Error {
        self.estimator_error_at(None, e)
    }

    /// As [`Model::estimator_error`] for the complaint of the estimator `name` while it was built:
    /// a setting it refuses is reported at its key in `[estimator.NAME]` when the table gives it
    /// (else in `[mhe]`).
    #[must_use]
    pub fn estimator_error_for(&self, name: &str, e: EstimatorError) -> Error {
        self.estimator_error_at(Some(name), e)
    }

    /// The initial data an estimator of `kind` reads from the file. A constrained-zonotope
    /// filter reads generator matrices: the file's zonotopes (`*_radius` or `*_generators`) when it
    /// gives them, else the boxes around the ellipsoids `p0`, `q`, `r` (half-widths `√Pᵢᵢ`:
    /// every ellipsoid lies in its box, so the filter's guarantee covers the ellipsoidal bounds);
    /// every other kind reads `p0`, `q`, `r` as they are.
    #[must_use]
    pub fn setup(&self, kind: EstimateKind) -> Setup {
        let (p0, q, r) = if kind == EstimateKind::GuaranteedConstrainedZonotope {
            let around =
                |m: &DMatrix<f64>| DVector::from_iterator(m.nrows(), (0..m.nrows()).map(|i| m[(i, i)].max(0.0).sqrt()));
            match &self.boxes {
                Some(b) => (b.x0.clone(), b.w.clone(), b.v.clone()),
                None => (
                    DMatrix::from_diagonal(&around(&self.p0)),
                    DMatrix::from_diagonal(&around(&self.q)),
                    DMatrix::from_diagonal(&around(&self.r)),
                ),
            }
        } else {
            (self.p0.clone(), self.q.clone(), self.r.clone())
        };
        Setup { x0: self.x0.clone(), p0, process_noise: q, measurement_noise: r, inputs: self.inputs() }
    }

    /// The `[estimator.NAME]` table of the estimator `name` (an empty one when the file has
    /// none): its settings by the registry's keywords, read with [`KeywordTable::reader`].
    #[must_use]
    pub fn settings_table(&self, name: &str) -> std::borrow::Cow<'_, KeywordTable> {
        match self.estimator_tables.iter().find(|(n, _)| *n == name) {
            Some((_, t)) => std::borrow::Cow::Borrowed(t),
            None => std::borrow::Cow::Owned(KeywordTable::absent(&format!("estimator.{name}"), &self.source.path)),
        }
    }

    /// What the file gives every estimator's settings: its sizes, state and input bounds, `[mhe]`
    /// and `[ukf]` tables, and the limit of a moving-horizon window's memory it was read with.
    #[must_use]
    pub fn keyword_context(&self) -> KeywordContext<'_> {
        KeywordContext {
            dims: models::Dims { states: self.states(), inputs: self.inputs(), outputs: self.outputs() },
            state_bounds: self.state_bounds.as_ref(),
            input_range: self.input_range.as_ref(),
            mhe: self.mhe.as_ref(),
            ukf: self.ukf,
            memory_limit: self.source.memory_limit,
            raise_memory: "--mhe-memory-limit",
            memory_ceiling: self.source.memory_limit,
        }
    }

    fn estimator_error_at(&self, estimator: Option<&str>, e: EstimatorError) -> Error {
        let key = match &e {
            EstimatorError::NotSymmetric { what }
            | EstimatorError::NotPositiveDefinite { what }
            | EstimatorError::NotPositiveSemidefinite { what }
            | EstimatorError::NonFinite { what, .. }
            | EstimatorError::DimensionMismatch { what, .. } => key_of(what).map(str::to_owned),
            EstimatorError::InvalidInputBounds { .. } => Some("u_lower".to_owned()),
            _ => None,
        };
        // A setting in the estimator's own table before the same setting in `[mhe]`.
        let own = |key: &str| {
            let setting = key.strip_prefix("mhe.").unwrap_or(key);
            estimator.map(|name| format!("estimator.{name}.{setting}")).into_iter().chain([key.to_owned()])
        };
        let key = match (&e, key) {
            (EstimatorError::InvalidSetting { .. }, None) => {
                e.setting_keyword().and_then(|setting| own(setting).find(|k| self.key_location(k).is_some()))
            }
            (EstimatorError::InvalidConfiguration { message, .. }, None) => crate::mhe_table::key_of_message(message)
                .iter()
                .flat_map(|k| own(k))
                .chain(["mhe".to_owned()])
                .find(|k| self.key_location(k).is_some()),
            (_, key) => key,
        };
        match key.and_then(|k| self.key_location(&k).map(|at| (k, at))) {
            Some((k, at)) => Error::At { at, message: format!("`{k}`: {e}") },
            None => Error::File {
                path: self.source.path.clone(),
                message: format!("{e} (Q, R, P0, x0 are the model file's `q`, `r`, `p0`, `x0`)"),
            },
        }
    }
}

/// The model-file key an estimator's name for a matrix refers to (`"Q"` → `q`, `"rows of A"` →
/// `a`).
fn key_of(what: &str) -> Option<&'static str> {
    let last = what.rsplit(' ').next().unwrap_or(what);
    Some(match last {
        "A" => "a",
        "B" => "b",
        "C" => "c",
        "Q" => "q",
        "R" => "r",
        "P0" | "P₀" => "p0",
        "x0" | "x₀" => "x0",
        _ => return None,
    })
}

/// Reading context: the file's text and name.
struct Ctx<'t> {
    text: &'t str,
    path: &'t Path,
}

impl Ctx<'_> {
    fn at(&self, span: Range<usize>) -> Location {
        let (line, column) = line_col(self.text, span.start);
        Location::new(self.path, line, column)
    }

    fn matrix(
        &self,
        name: &str,
        v: &Spanned<Vec<Vec<f64>>>,
        rows: Option<usize>,
        cols: Option<usize>,
    ) -> Result<DMatrix<f64>, Error> {
        let at = |msg: String| Error::at(self.at(v.span()), format!("`{name}`: {msg}"));
        let m = v.get_ref();
        let Some(first) = m.first() else {
            return Err(at("empty matrix".into()));
        };
        if let Some(r) = rows {
            if m.len() != r {
                return Err(at(format!("expected {r} rows, found {}", m.len())));
            }
        }
        let width = cols.unwrap_or(first.len());
        for (i, row) in m.iter().enumerate() {
            if row.len() != width {
                return Err(at(format!("row {} has {} entries, expected {width}", i + 1, row.len())));
            }
            if let Some(j) = row.iter().position(|x| !x.is_finite()) {
                return Err(at(format!("entry ({}, {}) is not finite", i + 1, j + 1)));
            }
        }
        if width == 0 && name != "b" {
            return Err(at("rows are empty".into()));
        }
        Ok(DMatrix::from_fn(m.len(), width, |i, j| m[i][j]))
    }

    /// A square `n × n` matrix given as a matrix, a diagonal or a number (a multiple of `I`).
    fn square(&self, name: &str, v: &Spanned<SquareSpec>, n: usize) -> Result<DMatrix<f64>, Error> {
        let at = |msg: String| Error::at(self.at(v.span()), format!("`{name}`: {msg}"));
        match v.get_ref() {
            SquareSpec::Number(x) if x.is_finite() => Ok(DMatrix::identity(n, n) * *x),
            SquareSpec::Number(_) => Err(at("is not finite".into())),
            SquareSpec::Diagonal(d) => {
                if d.len() != n {
                    return Err(at(format!("a diagonal of {} entries, expected {n} (or an {n}×{n} matrix)", d.len())));
                }
                if let Some(j) = d.iter().position(|x| !x.is_finite()) {
                    return Err(at(format!("diagonal entry {} is not finite", j + 1)));
                }
                Ok(DMatrix::from_diagonal(&DVector::from_column_slice(d)))
            }
            SquareSpec::Full(rows) => {
                let full = Spanned::new(v.span(), rows.clone());
                self.matrix(name, &full, Some(n), Some(n))
            }
        }
    }

    fn vector(&self, name: &str, v: &Spanned<Vec<f64>>, len: usize) -> Result<DVector<f64>, Error> {
        self.vector_with(name, v, len, false)
    }

    /// As `vector`; `infinite`: ±inf allowed (a bound that is not there), NaN never.
    fn vector_with(
        &self,
        name: &str,
        v: &Spanned<Vec<f64>>,
        len: usize,
        infinite: bool,
    ) -> Result<DVector<f64>, Error> {
        let x = v.get_ref();
        if x.len() != len {
            return Err(Error::at(self.at(v.span()), format!("`{name}`: expected {len} entries, found {}", x.len())));
        }
        let bad = |x: &f64| if infinite { x.is_nan() } else { !x.is_finite() };
        if let Some(j) = x.iter().position(bad) {
            let what = if infinite { "not a number" } else { "not finite" };
            return Err(Error::at(self.at(v.span()), format!("`{name}`: entry {} is {what}", j + 1)));
        }
        Ok(DVector::from_column_slice(x))
    }

    /// A pair of bound keys (`u_lower`, `u_upper`, say): both or neither, `len` entries each, not
    /// empty — checked for every estimator, not only those that use it: an empty range is a
    /// mistake in the file whatever runs on it.
    fn range(
        &self,
        (lo_name, lo): (&str, &Option<Spanned<Vec<f64>>>),
        (hi_name, hi): (&str, &Option<Spanned<Vec<f64>>>),
        len: usize,
        what: &str,
        infinite: bool,
    ) -> Result<Option<Bounds>, Error> {
        match (lo, hi) {
            (Some(lo), Some(hi)) => {
                let (l, u) =
                    (self.vector_with(lo_name, lo, len, infinite)?, self.vector_with(hi_name, hi, len, infinite)?);
                if let Some(i) = (0..len).find(|&i| l[i] > u[i] || l[i] == f64::INFINITY || u[i] == f64::NEG_INFINITY) {
                    let rel = if l[i] > u[i] { ">" } else { "and" };
                    let message = format!("{lo_name}[{i}] = {} {rel} {hi_name}[{i}] = {}: {what} is empty", l[i], u[i]);
                    return Err(Error::at(self.at(lo.span()), message));
                }
                Ok(Some((l, u)))
            }
            (None, None) => Ok(None),
            (Some(v), None) | (None, Some(v)) => {
                Err(Error::at(self.at(v.span()), format!("give both `{lo_name}` and `{hi_name}`, or neither")))
            }
        }
    }
}

/// Reads and validates a model from its text (dimensions are checked against `a`; every error
/// gives `path:line:column`). A leading UTF-8 byte-order mark is ignored.
///
/// # Errors
/// [`Error::At`] for a TOML syntax error, an unknown, missing (at `1:1`) or ill-typed key, or a
/// matrix or vector of the wrong size or with a non-finite entry.
pub fn parse_model(path: &Path, text: &str) -> Result<Model, Error> {
    parse_model_with(path, text, &Limits::default())
}

/// As [`parse_model`], with the resource limits of `limits` (the `[mhe]` table's memory).
///
/// # Errors
/// As [`parse_model`], and a horizon or blocks beyond the limits at their key.
pub fn parse_model_with(path: &Path, text: &str, limits: &Limits) -> Result<Model, Error> {
    parse(path, text, limits, None)
}

/// [`parse_model_with`], the dynamics being the compiled `builtin` when given (its file then
/// gives the noise, the settings and the names only).
fn parse(path: &Path, text: &str, limits: &Limits, builtin: Option<&'static Builtin>) -> Result<Model, Error> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let cx = Ctx { text, path };
    let f: ModelFile = toml::from_str(text).map_err(|e| {
        let message = e.message().trim_end().to_owned();
        // A key missing because it was written after an equation table (and so read into it).
        if message.starts_with("missing field")
            && let Err(Error::At { at, message }) = equations(&cx)
            && message.contains("belongs at the top of the file")
        {
            return Error::At { at, message };
        }
        match e.span() {
            // (A missing key is reported over the whole document, at 1:1.)
            Some(s) => Error::at(cx.at(s), message),
            None => Error::File { path: path.to_owned(), message },
        }
    })?;
    let dynamics = match builtin {
        Some(vehicle) => {
            let names: Names = match &f.model {
                Some(table) => table.get_ref().clone().try_into().map_err(|e: toml::de::Error| {
                    Error::at(cx.at(table.span()), format!("[model]: {}", e.message().trim_end()))
                })?,
                None => Names { inputs: Vec::new(), outputs: Vec::new() },
            };
            let model = vehicle.compile().map_err(Error::Usage)?;
            Dynamics::Builtin { vehicle, model, names: (names.inputs, names.outputs) }
        }
        None => dynamics(&cx, &f)?,
    };
    let dims = match &dynamics {
        Dynamics::Matrices(m) => DiscreteModel::dims(m),
        Dynamics::Equations(m) => m.dims(),
        Dynamics::Builtin { model, .. } => model.discrete().dims(),
    };
    let (n, p, m) = (dims.states, dims.inputs, dims.outputs);
    let q = cx.square("q", &f.q, n)?;
    let r = cx.square("r", &f.r, m)?;
    let p0 = cx.square("p0", &f.p0, n)?;
    let x0 = cx.vector("x0", &f.x0, n)?;
    let input_range = cx.range(("u_lower", &f.u_lower), ("u_upper", &f.u_upper), p, "the input range", false)?;
    let state_bounds = cx.range(("x_lower", &f.x_lower), ("x_upper", &f.x_upper), n, "the state's range", true)?;
    let boxes = boxes(&cx, &f, n, m)?;
    let mut keys = Vec::with_capacity(16);
    for (k, span) in [("q", f.q.span()), ("r", f.r.span()), ("p0", f.p0.span()), ("x0", f.x0.span())]
        .into_iter()
        .chain(f.u_lower.as_ref().map(|v| ("u_lower", v.span())))
        .chain(f.u_upper.as_ref().map(|v| ("u_upper", v.span())))
        .chain(f.x_lower.as_ref().map(|v| ("x_lower", v.span())))
        .chain(f.x_upper.as_ref().map(|v| ("x_upper", v.span())))
        .chain(f.x0_radius.as_ref().map(|v| ("x0_radius", v.span())))
        .chain(f.w_radius.as_ref().map(|v| ("w_radius", v.span())))
        .chain(f.v_radius.as_ref().map(|v| ("v_radius", v.span())))
        .chain(f.x0_generators.as_ref().map(|v| ("x0_generators", v.span())))
        .chain(f.w_generators.as_ref().map(|v| ("w_generators", v.span())))
        .chain(f.v_generators.as_ref().map(|v| ("v_generators", v.span())))
        .chain(f.a.as_ref().map(|v| ("a", v.span())))
        .chain(f.b.as_ref().map(|v| ("b", v.span())))
        .chain(f.c.as_ref().map(|v| ("c", v.span())))
        .chain(f.model.as_ref().map(|v| ("model", v.span())))
        .chain(f.ukf.as_ref().map(|v| ("ukf", v.span())))
    {
        let (line, column) = line_col(text, span.start);
        keys.push((k.to_owned(), line, column));
    }
    let table = |name: &str, t: &Spanned<SpannedTable>| KeywordTable::new(name, path, text, t.span(), t.get_ref());
    let mut tables = Vec::new();
    let mut keyword_cx = KeywordContext {
        dims,
        state_bounds: state_bounds.as_ref(),
        input_range: input_range.as_ref(),
        mhe: None,
        ukf: None,
        memory_limit: limits.mhe_memory_bytes,
        raise_memory: "--mhe-memory-limit",
        memory_ceiling: limits.mhe_memory_bytes,
    };
    let mhe = match &f.mhe {
        Some(t) => {
            let t = table("mhe", t);
            let settings =
                registry::read_moving_horizon("the moving-horizon estimators", &keyword_cx, &mut t.reader(&[]))?;
            tables.push(t);
            Some(settings)
        }
        None => None,
    };
    let ukf = match &f.ukf {
        Some(t) => {
            let t = table("ukf", t);
            let params = registry::read_sigma_points("the unscented filters", &mut t.reader(&[]))?;
            params.weights(n).map_err(|e| t.error("", &e.to_string()))?;
            tables.push(t);
            Some(params)
        }
        None => None,
    };
    (keyword_cx.mhe, keyword_cx.ukf) = (mhe.as_ref(), ukf);
    let mut estimator_tables = Vec::new();
    for (name, t) in f.estimator.iter().flat_map(|e| e.get_ref()) {
        let t = table(&format!("estimator.{name}"), t);
        let Some(entry) = registry::entry(name) else {
            let known: Vec<&str> = registry::ESTIMATORS.iter().map(|e| e.name).collect();
            return Err(t.error("", &format!("no estimator is called {name:?} (one of: {})", known.join(", "))));
        };
        // Read once here so that a mistake is found when the file is read, whatever runs.
        registry::read_settings(entry.settings, &format!("estimator {name}"), &keyword_cx, &mut t.reader(&[]))?;
        estimator_tables.push((entry.name, t));
    }
    for t in tables.iter().chain(estimator_tables.iter().map(|(_, t)| t)) {
        if let Some(at) = t.at() {
            keys.push((t.name().to_owned(), at.line, at.column));
        }
        for (k, at) in t.locations() {
            keys.push((k, at.line, at.column));
        }
    }
    let source = Source { path: path.to_owned(), keys, memory_limit: limits.mhe_memory_bytes };
    let mut model = Model {
        dynamics,
        q,
        r,
        p0,
        x0,
        input_range,
        state_bounds,
        boxes,
        mhe,
        ukf,
        log: None,
        estimator_tables,
        source,
    };
    if let Some(t) = &f.log {
        let named = |given: Option<&[String]>, prefix: &str, len: usize| -> Vec<String> {
            match given {
                Some(names) if names.len() == len => names.to_vec(),
                _ => (1..=len).map(|i| format!("{prefix}{i}")).collect(),
            }
        };
        let names = model.column_names();
        let (inputs, outputs) = (named(names.map(|n| n.0), "u", p), named(names.map(|n| n.1), "y", m));
        let spec = t.get_ref().spec(t.span(), &inputs, &outputs);
        model.log = Some(spec.map_err(|(span, message)| Error::at(cx.at(span), message))?);
    }
    Ok(model)
}

/// The zonotopes `X₀`, `W`, `V`: for each, a box `NAME_radius` (finite, non-negative half-widths)
/// or a generator matrix `NAME_generators` (finite, one row per state or output, at most
/// [`MAX_GENERATOR_COLUMNS`] columns), not both; all three sets or none.
fn boxes(cx: &Ctx<'_>, f: &ModelFile, n: usize, m: usize) -> Result<Option<Boxes>, Error> {
    let sets = [
        ("x0", &f.x0_radius, &f.x0_generators, n),
        ("w", &f.w_radius, &f.w_generators, n),
        ("v", &f.v_radius, &f.v_generators, m),
    ];
    let given = sets.iter().filter(|(_, r, g, _)| r.is_some() || g.is_some()).count();
    if given == 0 {
        return Ok(None);
    }
    // Where a missing set is reported: the first one given.
    let first_given = sets
        .iter()
        .find_map(|(_, r, g, _)| r.as_ref().map(Spanned::span).or_else(|| g.as_ref().map(Spanned::span)))
        .unwrap_or(0..0);
    let mut out = Vec::with_capacity(3);
    for (name, radius, generators, len) in sets {
        match (radius, generators) {
            (Some(_), Some(g)) => {
                return Err(Error::at(
                    cx.at(g.span()),
                    format!("give `{name}_radius` (a box) or `{name}_generators` (a zonotope), not both"),
                ));
            }
            (Some(v), None) => {
                let r = cx.vector(&format!("{name}_radius"), v, len)?;
                if let Some(i) = r.iter().position(|x| *x < 0.0) {
                    return Err(Error::at(
                        cx.at(v.span()),
                        format!("`{name}_radius`: entry {} is {} (a half-width must be ≥ 0)", i + 1, r[i]),
                    ));
                }
                out.push(DMatrix::from_diagonal(&r));
            }
            (None, Some(g)) => {
                let key = format!("{name}_generators");
                let columns = g.get_ref().first().map_or(0, Vec::len);
                if columns > MAX_GENERATOR_COLUMNS {
                    return Err(Error::at(
                        cx.at(g.span()),
                        format!("`{key}`: {columns} columns, more than the {MAX_GENERATOR_COLUMNS} allowed"),
                    ));
                }
                out.push(cx.matrix(&key, g, Some(len), None)?);
            }
            (None, None) => {
                return Err(Error::at(
                    cx.at(first_given.clone()),
                    format!(
                        "`{name}` has no set: give all three sets (`x0_`, `w_`, `v_` with `_radius` or \
                         `_generators`), or none"
                    ),
                ));
            }
        }
    }
    let [x0, w, v]: [DMatrix<f64>; 3] = match out.try_into() {
        Ok(sets) => sets,
        Err(_) => return Ok(None),
    };
    Ok(Some(Boxes { x0, w, v }))
}

/// The dynamics of a model file: its matrices `a`, `b`, `c`, or its `[model]` of equations.
fn dynamics(cx: &Ctx<'_>, f: &ModelFile) -> Result<Dynamics, Error> {
    let matrix_keys = [("a", &f.a), ("b", &f.b), ("c", &f.c)];
    let tables = [&f.parameters, &f.definitions, &f.f, &f.dxdt, &f.h];
    if f.model.is_some() || tables.iter().any(|t| t.is_some()) {
        if let Some((k, v)) = matrix_keys.iter().find_map(|(k, v)| v.as_ref().map(|v| (k, v))) {
            let message = format!(
                "`{k}`: a model file gives either the matrices `a`, `b`, `c` of a linear model or equations ([model], \
                 [f] or [dxdt], [h]), not both"
            );
            return Err(Error::at(cx.at(v.span()), message));
        }
        return Ok(Dynamics::Equations(Arc::new(equations(cx)?)));
    }
    let [(_, Some(fa)), (_, Some(fb)), (_, Some(fc))] = matrix_keys else {
        let missing: Vec<&str> = matrix_keys.iter().filter(|(_, v)| v.is_none()).map(|(k, _)| *k).collect();
        let message = format!(
            "missing {} (a model file gives the matrices `a`, `b`, `c` of a linear model, or a [model] table of \
             equations)",
            missing.iter().map(|k| format!("`{k}`")).collect::<Vec<_>>().join(", ")
        );
        return Err(Error::at(Location::new(cx.path, 1, 1), message));
    };
    let a = cx.matrix("a", fa, None, None)?;
    let n = a.nrows();
    if a.ncols() != n {
        return Err(Error::at(cx.at(fa.span()), format!("`a` must be square, is {n}x{}", a.ncols())));
    }
    let b = cx.matrix("b", fb, Some(n), None)?;
    let c = cx.matrix("c", fc, None, Some(n))?;
    // The dimensions and entries are checked above, at their keys.
    let model = ConstantModel::new(a, b, c).map_err(|e| Error::at(cx.at(fa.span()), e.to_string()))?;
    Ok(Dynamics::Matrices(model))
}

/// The model written as equations in the file of `cx` (compiled by `equation-models`, whose own
/// limits apply: crates/equation-models/README.md).
fn equations(cx: &Ctx<'_>) -> Result<EquationModel, Error> {
    let file = cx.path.display().to_string();
    EquationModel::from_toml_str_with_foreign_keys(cx.text, &file, &NOISE_KEYS).map_err(|e| match e {
        // TOML puts every key after a table header into that table.
        equation_models::EquationError::UnknownTarget { location, name, section, .. }
            if NOISE_KEYS.contains(&name.as_str()) =>
        {
            let message = format!(
                "`{name}` is read as part of [{section}]: `{name}` belongs at the top of the file, before the first \
                 table"
            );
            Error::At { at: Location::new(cx.path, location.line, location.column), message }
        }
        e => Error::Equations(e),
    })
}

/// Reads and validates `MODEL.toml` (see [`parse_model`]) with the default [`Limits`].
///
/// # Errors
/// As [`read_model_with`].
pub fn read_model(path: &Path) -> Result<Model, Error> {
    read_model_with(path, &Limits::default())
}

/// Reads and validates `MODEL.toml` within `limits` (see [`parse_model_with`]).
///
/// # Errors
/// [`Error::Io`] if the file cannot be read; [`Error::TooLarge`] beyond `limits.file_bytes`;
/// [`Error::At`] at the first byte that is not UTF-8; the errors of [`parse_model_with`].
pub fn read_model_with(path: &Path, limits: &Limits) -> Result<Model, Error> {
    if let Some(vehicle) = path.to_str().and_then(crate::builtin::lookup) {
        let vehicle = vehicle.map_err(Error::Usage)?;
        return parse(path, vehicle.file, limits, Some(vehicle));
    }
    let text = crate::limits::read_text(path, "model file", limits.file_bytes)?;
    parse_model_with(path, &text, limits)
}

#[cfg(test)]
mod tests {
    use super::*;

    const MODEL: &str = "a = [[1.0, 0.01], [0.0, 0.99]]\nb = [[0.0], [0.01]]\nc = [[1.0, 0.0]]\nq = [[1e-4, 0.0], [0.0, 1e-4]]\nr = [[1e-2]]\np0 = [[1.0, 0.0], [0.0, 1.0]]\nx0 = [0.0, 0.0]\n";

    fn err(text: &str) -> String {
        parse_model(Path::new("m.toml"), text).map(|_| ()).unwrap_err().to_string()
    }

    #[test]
    fn model_errors_name_line_and_column() {
        let m = parse_model(Path::new("m.toml"), MODEL).unwrap();
        assert_eq!((m.states(), m.inputs(), m.outputs()), (2, 1, 1));
        let e = err(&MODEL.replace("b = [[0.0], [0.01]]", "b = [[0.0]]"));
        assert!(e.starts_with("m.toml:2:5: `b`: expected 2 rows, found 1"), "{e}");
        assert!(err(&MODEL.replace("x0 = [0.0, 0.0]", "x0 = [0.0]")).contains("m.toml:7:6: `x0`: expected 2 entries"));
        assert!(
            err(&MODEL.replace("r = [[1e-2]]", "r = [[1e-2, 0.0]]")).contains("`r`: row 1 has 2 entries, expected 1")
        );
        let e = err(&MODEL.replace("q = ", "qq = "));
        assert!(e.starts_with("m.toml:4:"), "{e}");
        let e = err(&format!("{MODEL}u_lower = [0.0]\n"));
        assert!(e.starts_with("m.toml:8:11: give both `u_lower` and `u_upper`"), "{e}");
        let e = err(&MODEL.replace("a = [[1.0, 0.01], [0.0, 0.99]]", "a = [[1.0, 0.01]]"));
        assert!(e.starts_with("m.toml:1:5: `a` must be square, is 1x2"), "{e}");
        let e = err(&MODEL.replace("r = [[1e-2]]", "r = [[nan]]"));
        assert!(e.starts_with("m.toml:5:5: `r`: entry (1, 1) is not finite"), "{e}");
        let e = err(&MODEL.replace("r = [[1e-2]]", "r = [[\"x\"]]"));
        assert!(e.starts_with("m.toml:5:5: ") && e.contains("a diagonal (a list of numbers) or a number"), "{e}");
        // A diagonal or a multiple of the identity where a covariance or shape is given.
        let diag =
            parse_model(Path::new("m.toml"), &MODEL.replace("q = [[1e-4, 0.0], [0.0, 1e-4]]", "q = [1e-4, 2e-4]"));
        assert_eq!(diag.unwrap().q, DMatrix::from_diagonal(&DVector::from_vec(vec![1e-4, 2e-4])));
        let scalar = parse_model(Path::new("m.toml"), &MODEL.replace("p0 = [[1.0, 0.0], [0.0, 1.0]]", "p0 = 2.0"));
        assert_eq!(scalar.unwrap().p0, DMatrix::identity(2, 2) * 2.0);
        let e = err(&MODEL.replace("q = [[1e-4, 0.0], [0.0, 1e-4]]", "q = [1e-4]"));
        assert!(e.starts_with("m.toml:4:5: `q`: a diagonal of 1 entries, expected 2"), "{e}");
    }

    #[test]
    fn a_missing_key_names_the_file_and_the_key() {
        let e = err(&MODEL.replace("x0 = [0.0, 0.0]\n", ""));
        assert!(e.starts_with("m.toml:1:1: missing field `x0`"), "{e}");
    }

    #[test]
    fn a_byte_order_mark_does_not_shift_columns() {
        let e = err(&format!("\u{feff}{}", MODEL.replace("a = [[1.0, 0.01], [0.0, 0.99]]", "a = [[1.0, 0.01]]")));
        assert!(e.starts_with("m.toml:1:5: "), "{e}");
    }

    #[test]
    fn estimator_complaints_point_at_the_key() {
        let m = parse_model(Path::new("m.toml"), MODEL).unwrap();
        let e = m.estimator_error(EstimatorError::NotPositiveDefinite { what: "Q" }).to_string();
        assert_eq!(e, "m.toml:4:5: `q`: Q is not positive definite");
        let e = m.estimator_error(EstimatorError::EmptySystem("no outputs")).to_string();
        assert!(e.starts_with("m.toml: ") && e.contains("the model file's `q`"), "{e}");
    }

    #[test]
    fn an_empty_input_range_is_refused_for_every_estimator() {
        let e = err(&format!("{MODEL}u_lower = [1.0]\nu_upper = [0.0]\n"));
        assert!(e.starts_with("m.toml:8:11: u_lower[0] = 1 > u_upper[0] = 0: the input range is empty"), "{e}");
        // The state's bounds: ±inf allowed (no bound), NaN and empty ranges not, both or neither.
        let m = parse_model(Path::new("m.toml"), &format!("{MODEL}x_lower = [-inf, -1.0]\nx_upper = [inf, 2.0]\n"))
            .unwrap();
        let (lo, hi) = m.state_bounds.clone().unwrap();
        assert_eq!((lo.as_slice(), hi.as_slice()), (&[f64::NEG_INFINITY, -1.0][..], &[f64::INFINITY, 2.0][..]));
        let e = err(&format!("{MODEL}x_lower = [0.0, nan]\nx_upper = [1.0, 1.0]\n"));
        assert!(e.starts_with("m.toml:8:11: `x_lower`: entry 2 is not a number"), "{e}");
        let e = err(&format!("{MODEL}x_lower = [0.0, 2.0]\nx_upper = [1.0, 1.0]\n"));
        assert!(e.starts_with("m.toml:8:11: x_lower[1] = 2 > x_upper[1] = 1: the state's range is empty"), "{e}");
        let e = err(&format!("{MODEL}x_lower = [inf, 0.0]\nx_upper = [inf, 1.0]\n"));
        assert!(e.starts_with("m.toml:8:11: x_lower[0] = inf and x_upper[0] = inf: the state's range is empty"), "{e}");
        let e = err(&format!("{MODEL}x_upper = [1.0, 1.0]\n"));
        assert!(e.starts_with("m.toml:8:11: give both `x_lower` and `x_upper`, or neither"), "{e}");
        let e = err(&format!("{MODEL}x_lower = [0.0]\nx_upper = [1.0]\n"));
        assert!(e.starts_with("m.toml:8:11: `x_lower`: expected 2 entries, found 1"), "{e}");
    }
}
