//! `port-est bds-ins`: the fuzzy-adaptive Kalman filter of the BDS/INS paper
//! (`docs/bds-ins-fuzzy-kf.md`) over a log of INS and BDS solutions with the receiver's working
//! state, loosely coupled, output correction (the INS is never reset).
//!
//! `DATA.csv` has the general layout of `port-est filter` with `p = 3` and `m = 5` — header
//! `k,u1,u2,u3,y1,y2,y3,y4,y5`; row `k` holds the INS solution and the BDS fix of the epoch that
//! ends the `k`-th period:
//!
//! | column | quantity | unit |
//! |---|---|---|
//! | `u1`, `u2` | INS position east `x`, north `y` (any local level frame) | m |
//! | `u3` | INS heading, azimuth clockwise from north | rad |
//! | `y1`, `y2` | BDS position east, north (same frame) | m |
//! | `y3` | BDS (dual-antenna) heading, azimuth | rad |
//! | `y4` | satellites used `N` (≥ 0) | – |
//! | `y5` | RTK status: 1 single, 2 differential, 3 fixed, 4 float; **0 = no fix** (the epoch is a prediction only and `y1`…`y4` are ignored, but must be numbers). With `--gga`, the NMEA GGA quality instead: 0 no fix, 1 → 1, 2 → 2, 4 → 3, 5 → 4 | – |
//!
//! `OUT.csv`: `k,x,y,psi,dx,dy,dpsi,sd_dx,sd_dy,sd_dpsi,t,d`, one row per epoch labelled `k+1`:
//! the corrected position and heading (`x = x_INS − δx̂`, `ψ = wrap(ψ_INS − δψ̂)`), the estimated
//! INS errors with one standard deviation each, and the scale `t_k` with the distance `d_k` it was
//! chosen from (both empty on epochs without a fix).
//!
//! `--config FILE.toml` (optional) overrides the digest's settings: `ts` (s), `latitude_deg`,
//! `flat` (no Earth rate), `sigma0` (nominal BDS horizontal σ, m; also scales the default fuzzy
//! system's `d` sets), `heading_sigma_deg`, `accel_white` (m/s²/√Hz), `gyro_white` (rad/s/√Hz),
//! `p0_sigma` (13 initial standard deviations, paper order). `--fis FILE.toml` replaces the fuzzy
//! system (three inputs `[N, RTK, d]`, e.g. an edited copy of
//! `crates/fuzzy-inference/systems/bds_ins.toml`); `--scaling none` runs the plain Kalman filter.

use std::cell::Cell;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::rc::Rc;

use bds_ins_dynamics::{
    BdsInsError, DiscreteInsModel, Earth, InsErrorModel, InsNoise, InsParams, RtkStatus, STATES, correct, idx,
    measurement, scenario,
};
use estimators::{
    AdaptiveError, AdaptiveKalmanFilter, ConstantScaling, Estimate, Estimator, EstimatorError, FuzzyScaling,
    NoiseScaling, Setup,
};
use fuzzy_inference::{BDS_INS_INTERFACE, FuzzySystem};
use nalgebra::{DMatrix, DVector};
use serde::Deserialize;
use toml::Spanned;

use crate::data::{DataReader, DataRow};
use crate::error::Error;
use crate::limits::Limits;
use crate::output::OutputFile;
use crate::plausibility::{Limit, check_satellites, defaults};
use crate::run::{OnError, StatusPolicy, StatusTally, enforce};
use crate::settings::{self, SettingsFile};

/// How the RTK column is coded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RtkCoding {
    /// The paper's codes 1–4, 0 for no fix.
    Paper,
    /// NMEA GGA quality indicators (0 no fix, 1, 2, 4, 5).
    Gga,
}

/// What `port-est bds-ins` needs.
#[derive(Debug, Clone)]
pub struct BdsInsOptions {
    /// The logged data.
    pub input: PathBuf,
    /// Where to write the estimates.
    pub output: PathBuf,
    /// Optional settings file.
    pub config: Option<PathBuf>,
    /// Optional fuzzy system (TOML).
    pub fis: Option<PathBuf>,
    /// `false`: the plain Kalman filter (`t ≡ 1`).
    pub fuzzy: bool,
    /// Coding of the RTK column.
    pub rtk_coding: RtkCoding,
    /// What a step that does not end cleanly does.
    pub status: StatusPolicy,
    /// How the estimator checks its data (`None`: its defaults, an error at the first step whose
    /// data contradict the noise description).
    pub checks: Option<estimators::DataChecks>,
    /// What an error does with the steps before it.
    pub on_error: OnError,
    /// Size limit of the settings and rule files.
    pub limits: Limits,
}

impl BdsInsOptions {
    /// `port-est bds-ins --input INPUT --output OUTPUT` with every other setting at the command
    /// line's default: the shipped settings and rule file, fuzzy scaling, the paper's RTK coding,
    /// a warning for a step that does not end cleanly, the estimator's data checks, nothing
    /// written on an error, the default limits.
    #[must_use]
    pub fn new(input: impl Into<PathBuf>, output: impl Into<PathBuf>) -> Self {
        Self {
            input: input.into(),
            output: output.into(),
            config: None,
            fis: None,
            fuzzy: true,
            rtk_coding: RtkCoding::Paper,
            status: StatusPolicy::Warn,
            checks: None,
            on_error: OnError::Discard,
            limits: Limits::default(),
        }
    }
}

/// What a run did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BdsInsSummary {
    /// Epochs written.
    pub epochs: u64,
    /// Epochs without a fix (prediction only).
    pub outages: u64,
    /// How the steps ended.
    pub tally: StatusTally,
}

/// The settings file, as written.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ConfigFile {
    ts: Option<Spanned<f64>>,
    latitude_deg: Option<Spanned<f64>>,
    flat: Option<Spanned<bool>>,
    sigma0: Option<Spanned<f64>>,
    heading_sigma_deg: Option<Spanned<f64>>,
    accel_white: Option<Spanned<f64>>,
    gyro_white: Option<Spanned<f64>>,
    p0_sigma: Option<Spanned<Vec<f64>>>,
    max_heading: Option<Spanned<f64>>,
    max_satellites: Option<Spanned<f64>>,
}

/// The validated settings.
#[derive(Debug, Clone)]
pub(crate) struct Settings {
    model: DiscreteInsModel,
    sigma0: f64,
    r: DMatrix<f64>,
    p0: DMatrix<f64>,
    /// The plausible headings `|u3|`, `|y3|`.
    heading: Limit,
    /// The plausible satellite count `y4`.
    satellites: Limit,
}

fn read_config(path: Option<&Path>, limits: &Limits) -> Result<Settings, Error> {
    let (file, source): (ConfigFile, SettingsFile) = SettingsFile::read(path, limits.file_bytes)?;
    settings_of(&file, &source)
}

/// Checks every setting at its key, then the matrices derived from them (named by the settings
/// they come from).
pub(crate) fn settings_of(file: &ConfigFile, source: &SettingsFile) -> Result<Settings, Error> {
    let span = |v: &Option<Spanned<f64>>| v.as_ref().map(Spanned::span);
    let positive = |key: &str, v: &Option<Spanned<f64>>, default: f64| settings::positive_or(source, key, v, default);
    let non_negative = |key: &str, v: &Option<Spanned<f64>>, default: f64| match v {
        Some(v) => settings::non_negative(source, key, v),
        None => Ok(default),
    };
    let ts = positive("ts", &file.ts, scenario::PAPER_PERIOD)?;
    let sigma0 = positive("sigma0", &file.sigma0, scenario::SIGMA0)?;
    let heading =
        positive("heading_sigma_deg", &file.heading_sigma_deg, scenario::HEADING_SIGMA0.to_degrees())?.to_radians();
    let flat = file.flat.as_ref().is_some_and(|f| *f.get_ref());
    let earth = if flat {
        Earth::Flat
    } else {
        let latitude = match &file.latitude_deg {
            Some(v) => {
                let deg = *v.get_ref();
                if !deg.is_finite() {
                    return Err(source.error("latitude_deg", v, format!("must be finite, got {deg}")));
                }
                deg.to_radians()
            }
            None => bds_ins_dynamics::DIGEST_LATITUDE,
        };
        Earth::Rotating { latitude }
    };
    let digest = InsNoise::digest_filter();
    let noise = InsNoise {
        accel_white: non_negative("accel_white", &file.accel_white, digest.accel_white)?,
        gyro_white: non_negative("gyro_white", &file.gyro_white, digest.gyro_white)?,
        ..digest
    };
    // Φ and Q come from the period, the Earth model and the noise intensities together: a
    // failure is put on the first given setting whose default makes it go away.
    let process_keys = [
        ("accel_white", span(&file.accel_white)),
        ("gyro_white", span(&file.gyro_white)),
        ("ts", span(&file.ts)),
        ("latitude_deg", span(&file.latitude_deg)),
    ];
    let params = InsParams { earth, ..InsParams::digest() };
    if let (Err(BdsInsError::OutOfRange { lo, hi, .. }), Some(v)) = (params.validate(), &file.latitude_deg) {
        let (lo, hi) = (lo.to_degrees(), hi.to_degrees());
        return Err(source.error(
            "latitude_deg",
            v,
            format!("must lie in [{lo:.0}, {hi:.0}] degrees, got {}", v.get_ref()),
        ));
    }
    let model = match process_model(params, noise, ts) {
        Ok(model) => model,
        Err(e) => {
            let defaults = InsParams::digest();
            let culprits = [
                (
                    "accel_white",
                    span(&file.accel_white),
                    process_model(params, InsNoise { accel_white: digest.accel_white, ..noise }, ts),
                ),
                (
                    "gyro_white",
                    span(&file.gyro_white),
                    process_model(params, InsNoise { gyro_white: digest.gyro_white, ..noise }, ts),
                ),
                ("ts", span(&file.ts), process_model(params, noise, scenario::PAPER_PERIOD)),
                (
                    "latitude_deg",
                    span(&file.latitude_deg),
                    process_model(InsParams { earth: defaults.earth, ..params }, noise, ts),
                ),
            ];
            let given: Vec<(&str, Option<std::ops::Range<usize>>)> = culprits
                .iter()
                .filter(|(_, span, fixed)| span.is_some() && fixed.is_ok())
                .chain(culprits.iter().filter(|(_, span, _)| span.is_some()))
                .map(|(k, span, _)| (*k, span.clone()))
                .collect();
            let message =
                format!("the INS error model derived from `accel_white`, `gyro_white`, `ts` and `latitude_deg`: {e}");
            return Err(source.derived_error(&given, message));
        }
    };
    let p0_sigma = match &file.p0_sigma {
        None => scenario::initial_sigma().to_vec(),
        Some(v) => {
            let x = settings::vector(source, "p0_sigma", v, STATES)?;
            if let Some(i) = x.iter().position(|s| *s <= 0.0) {
                let message =
                    format!("entry {} = {} must be positive (13 standard deviations, paper state order)", i + 1, x[i]);
                return Err(source.error("p0_sigma", v, message));
            }
            x
        }
    };
    // Squares that overflow or underflow: named by the setting squared.
    let variance = |key: &str, span: Option<std::ops::Range<usize>>, sigma: f64, what: &str| {
        let v = sigma * sigma;
        if v.is_finite() && v >= f64::MIN_POSITIVE {
            return Ok(v);
        }
        let message = format!("its square {v:e}, a variance of the {what}, is not a usable positive number");
        Err(source.derived_error(&[(key, span)], message))
    };
    let s2 = variance("sigma0", span(&file.sigma0), sigma0, "measurement covariance R")?;
    let h2 = variance("heading_sigma_deg", span(&file.heading_sigma_deg), heading, "measurement covariance R")?;
    let r = DMatrix::from_diagonal(&DVector::from_vec(vec![s2, s2, h2]));
    let p0_span = file.p0_sigma.as_ref().map(Spanned::span);
    let mut p0 = DMatrix::zeros(STATES, STATES);
    for (i, s) in p0_sigma.iter().enumerate() {
        p0[(i, i)] = variance("p0_sigma", p0_span.clone(), *s, "initial covariance P0").map_err(|e| match e {
            Error::At { at, message } => Error::At { at, message: format!("{message} (entry {})", i + 1) },
            e => e,
        })?;
    }
    settings::check_covariance(&r).map_err(|why| {
        let keys = [("sigma0", span(&file.sigma0)), ("heading_sigma_deg", span(&file.heading_sigma_deg))];
        source.derived_error(&keys, format!("the measurement covariance R = diag(sigma0², sigma0², heading²) {why}"))
    })?;
    settings::check_covariance(&p0).map_err(|why| {
        source.derived_error(&[("p0_sigma", p0_span.clone())], format!("the initial covariance P0 {why}"))
    })?;
    let heading = Limit {
        key: "max_heading",
        bound: positive("max_heading", &file.max_heading, defaults::MAX_HEADING)?,
        unit: "rad",
        hint: "logged in degrees?",
    };
    let satellites = Limit {
        key: "max_satellites",
        bound: positive("max_satellites", &file.max_satellites, defaults::MAX_SATELLITES)?,
        unit: "",
        hint: "another column's quantity?",
    };
    let settings = Settings { model, sigma0, r, p0, heading, satellites };
    // What the filter itself checks, in the file's terms.
    AdaptiveKalmanFilter::new(setup(&settings), ConstantScaling(1.0)).map_err(|e| {
        let keys: &[(&str, Option<std::ops::Range<usize>>)] = match &e {
            AdaptiveError::Filter(
                EstimatorError::NotPositiveDefinite { what: "R" } | EstimatorError::NotSymmetric { what: "R" },
            ) => &[("sigma0", span(&file.sigma0)), ("heading_sigma_deg", span(&file.heading_sigma_deg))],
            AdaptiveError::Filter(EstimatorError::NotPositiveDefinite { what: "P0" }) => {
                &[("p0_sigma", file.p0_sigma.as_ref().map(Spanned::span))]
            }
            _ => &process_keys,
        };
        source.derived_error(keys, format!("the filter refuses the matrices derived from it: {e}"))
    })?;
    Ok(settings)
}

/// The discrete error model, with a finite `Φ` and `Q` (else why not, in words).
fn process_model(params: InsParams, noise: InsNoise, ts: f64) -> Result<DiscreteInsModel, String> {
    let model = InsErrorModel::new(params, noise).and_then(|m| m.discretize(ts)).map_err(|e| e.to_string())?;
    let finite = |m: &DMatrix<f64>| m.iter().all(|v| v.is_finite());
    if !finite(&model.phi) {
        return Err("the transition matrix Φ = e^(F ts) is not finite".into());
    }
    if !finite(&model.q) {
        return Err("the process noise Q is not finite".into());
    }
    Ok(model)
}

fn setup(s: &Settings) -> Setup {
    Setup {
        x0: DVector::zeros(STATES),
        p0: s.p0.clone(),
        process_noise: s.model.q.clone(),
        measurement_noise: s.r.clone(),
        inputs: 0,
    }
}

/// What the runner sees of the fuzzy scaling inside the filter: the last `t` it gave, and a
/// scale that replaces it (to tell whether a failed step is the rule file's doing).
#[derive(Debug, Default)]
struct Probe {
    last: Cell<Option<f64>>,
    forced: Cell<Option<f64>>,
}

/// The scaling chosen on the command line.
enum Scaling {
    Fuzzy(Box<FuzzyScaling>, Rc<Probe>),
    Unit(ConstantScaling),
}

impl NoiseScaling for Scaling {
    fn scale(&mut self, c: &estimators::ScalingContext<'_>) -> Result<f64, AdaptiveError> {
        match self {
            Scaling::Fuzzy(f, probe) => {
                if let Some(t) = probe.forced.get() {
                    return Ok(t);
                }
                probe.last.set(None);
                let t = f.scale(c)?;
                probe.last.set(Some(t));
                Ok(t)
            }
            Scaling::Unit(u) => u.scale(c),
        }
    }
}

/// Reads the rule file (`--fis`), its inputs bound to the receiver's quantities by name.
fn rule_file(path: &Path, limits: &Limits) -> Result<FuzzySystem, Error> {
    parse_rule_file(path, &crate::limits::read_text(path, "rule file", limits.file_bytes)?)
}

/// A rule file's system from its text, its inputs bound to the receiver's quantities by name.
fn parse_rule_file(path: &Path, text: &str) -> Result<FuzzySystem, Error> {
    FuzzySystem::from_toml_str_for(text, &path.display().to_string(), &BDS_INS_INTERFACE)
        .map_err(|e| Error::Usage(format!("--fis: {e}")))
}

fn scaling(options: &BdsInsOptions, sigma0: f64) -> Result<(Scaling, Option<Rc<Probe>>), Error> {
    if !options.fuzzy {
        return Ok((Scaling::Unit(ConstantScaling(1.0)), None));
    }
    let system = match &options.fis {
        Some(path) => rule_file(path, &options.limits)?,
        None => FuzzySystem::bds_ins(sigma0).map_err(|e| Error::Usage(format!("fuzzy system: {e}")))?,
    };
    let f = FuzzyScaling::new(system).map_err(|e| {
        let shown = options.fis.as_deref().unwrap_or(Path::new("<default>")).display().to_string();
        Error::Usage(format!("--fis {shown}: {e}"))
    })?;
    let probe = Rc::new(Probe::default());
    Ok((Scaling::Fuzzy(Box::new(f), Rc::clone(&probe)), Some(probe)))
}

/// Runs the filter over `options.input` and writes `options.output` (atomically).
///
/// # Errors
/// Every [`Error`]: the output checks, a malformed settings, fuzzy-system or data file (at its
/// `file:line:column`), a receiver status or a step the filter rejects (at its data cell), a
/// step the rule file makes fail (naming the rule file); with [`OnError::KeepPartial`] the steps
/// before the error are kept in `OUT.partial.csv` and the error says so.
pub fn bds_ins(options: &BdsInsOptions) -> Result<BdsInsSummary, Error> {
    let mut inputs: Vec<(&'static str, &Path)> = vec![("input", &options.input)];
    if let Some(c) = &options.config {
        inputs.push(("config", c));
    }
    if let Some(f) = &options.fis {
        inputs.push(("fis", f));
    }
    let mut out = OutputFile::create(&options.output, &inputs)?;
    let settings = read_config(options.config.as_deref(), &options.limits)?;
    let (mut runner, scaling) = Runner::new(&settings, options)?;
    let mut data = DataReader::open(&options.input, 3, 5)?;
    let mut tally = StatusTally::default();
    match runner.run(scaling, &mut data, &mut out, &options.output, &mut tally) {
        Ok(()) => {
            out.commit()?;
            Ok(BdsInsSummary { epochs: tally.steps, outages: tally.predicted, tally })
        }
        Err(e) => Err(out.fail(e, tally.steps, options.on_error, &inputs)),
    }
}

/// Checks the text of a settings file (named `path` in errors) as `port-est bds-ins --config`
/// does: every complaint at its key's `file:line:column`, derived matrices named by the settings
/// they come from.
///
/// # Errors
/// As [`bds_ins`] for a settings file.
pub fn check_settings(path: &Path, text: &str) -> Result<(), Error> {
    let (file, source): (ConfigFile, SettingsFile) = SettingsFile::from_text(path, text)?;
    settings_of(&file, &source).map(drop)
}

/// The whole of `port-est bds-ins` but the files: the settings of `config` and the rule file of
/// `fis` (each a file's name and text; `None`: the defaults), the log `data`, the rows written to
/// `out` (tests and fuzzing drive it).
///
/// # Errors
/// As [`bds_ins`].
pub fn run_log<R: Read, W: Write>(
    config: Option<(&Path, &str)>,
    fis: Option<(&Path, &str)>,
    coding: RtkCoding,
    data: &mut DataReader<R>,
    out: &mut W,
) -> Result<BdsInsSummary, Error> {
    let settings = match config {
        Some((path, text)) => {
            let (file, source): (ConfigFile, SettingsFile) = SettingsFile::from_text(path, text)?;
            settings_of(&file, &source)?
        }
        None => read_config(None, &Limits::default())?,
    };
    let system = match fis {
        Some((path, text)) => parse_rule_file(path, text)?,
        None => FuzzySystem::bds_ins(settings.sigma0).map_err(|e| Error::Usage(format!("fuzzy system: {e}")))?,
    };
    let f = FuzzyScaling::new(system).map_err(|e| Error::Usage(format!("--fis: {e}")))?;
    let probe = Rc::new(Probe::default());
    let scaling = Scaling::Fuzzy(Box::new(f), Rc::clone(&probe));
    let rules = Rules { probe: Some(probe), path: fis.map(|(p, _)| p.to_owned()) };
    let mut runner = Runner { settings: &settings, coding, status: StatusPolicy::Warn, checks: None, rules };
    let mut tally = StatusTally::default();
    runner.run(scaling, data, out, Path::new("<output>"), &mut tally)?;
    Ok(BdsInsSummary { epochs: tally.steps, outages: tally.predicted, tally })
}

/// Column index (for `DataReader::locate`) of `y4` and `y5`.
const SATELLITES_COLUMN: usize = 7;
const RTK_COLUMN: usize = 8;

/// The paper's RTK code of a row (0: no fix), from the paper's coding or a GGA quality.
fn rtk_code<R: Read>(row: &DataRow, coding: RtkCoding, data: &DataReader<R>) -> Result<f64, Error> {
    let code = row.y[4];
    match coding {
        RtkCoding::Paper => Ok(code),
        RtkCoding::Gga => {
            let mapped = (code.fract() == 0.0 && (0.0..=255.0).contains(&code))
                .then(|| {
                    if code == 0.0 {
                        Some(0.0)
                    } else {
                        RtkStatus::from_gga_quality(code as u8).map(|s| f64::from(s.code()))
                    }
                })
                .flatten();
            mapped.ok_or_else(|| {
                Error::at(
                    data.locate(Some(RTK_COLUMN)),
                    format!("y5 = {code} is not an NMEA GGA quality this filter knows (0 no fix, 1, 2, 4, 5)"),
                )
            })
        }
    }
}

/// The fuzzy system in use and where it came from, to blame it for the failures it causes.
struct Rules {
    probe: Option<Rc<Probe>>,
    path: Option<PathBuf>,
}

impl Rules {
    fn shown(&self) -> PathBuf {
        self.path.clone().unwrap_or_else(|| PathBuf::from("<built-in fuzzy system>"))
    }
}

struct Runner<'a> {
    settings: &'a Settings,
    coding: RtkCoding,
    status: StatusPolicy,
    checks: Option<estimators::DataChecks>,
    rules: Rules,
}

impl<'a> Runner<'a> {
    /// The runner of `options` on `settings`, and the noise scaling of its steps (the rule file's,
    /// or none).
    fn new(settings: &'a Settings, options: &BdsInsOptions) -> Result<(Self, Scaling), Error> {
        let (scaling, probe) = scaling(options, settings.sigma0)?;
        let rules = Rules { probe, path: options.fis.clone() };
        let runner =
            Self { settings, coding: options.rtk_coding, status: options.status, checks: options.checks, rules };
        Ok((runner, scaling))
    }

    /// A step's error at its data row: the receiver status at its cell (with a hint for RTK
    /// codes), a noise scale the rule file gave naming the rule file.
    fn step_error<R: Read>(
        &self,
        e: EstimatorError,
        data: &DataReader<R>,
        k: u64,
        retry: impl FnOnce(f64) -> bool,
    ) -> Error {
        let rule_file =
            |message: String| Error::RuleFile { path: self.rules.shown(), message, at: data.locate(Some(0)), k };
        match e {
            EstimatorError::Adaptive { index: Some(i), source } => {
                let column = if i == 3 { SATELLITES_COLUMN } else { RTK_COLUMN };
                let hint = if self.coding == RtkCoding::Paper && matches!(*source, AdaptiveError::RtkOutOfRange(_)) {
                    " (0 marks an epoch without a fix; --gga reads NMEA GGA qualities)"
                } else {
                    ""
                };
                Error::at(data.locate(Some(column)), format!("{source}{hint}"))
            }
            EstimatorError::Adaptive { index: None, source }
                if matches!(*source, AdaptiveError::InvalidScale(_) | AdaptiveError::Fuzzy(_)) =>
            {
                rule_file(source.to_string())
            }
            EstimatorError::NumericalFailure(what) if self.rules.probe.is_some() => {
                // The same step with t = 1: if it succeeds, the rule file's t made it fail.
                let t = self.rules.probe.as_ref().and_then(|p| p.last.get());
                match t {
                    Some(t) if t != 1.0 && retry(1.0) => rule_file(format!(
                        "numerical failure: {what} with the noise scale t = {t:e} the rule file gave"
                    )),
                    _ => crate::run::step_error(EstimatorError::NumericalFailure(what), data, k),
                }
            }
            e => crate::run::step_error(e, data, k),
        }
    }

    fn run<R: Read, W: Write>(
        &mut self,
        scaling: Scaling,
        data: &mut DataReader<R>,
        out: &mut W,
        out_path: &Path,
        tally: &mut StatusTally,
    ) -> Result<(), Error> {
        let s = self.settings;
        let wio = |e| Error::io(out_path, e);
        writeln!(out, "k,x,y,psi,dx,dy,dpsi,sd_dx,sd_dy,sd_dpsi,t,d,status").map_err(wio)?;
        let mut filter =
            AdaptiveKalmanFilter::new(setup(s), scaling).map_err(|e| Error::Usage(format!("filter: {e}")))?;
        if let Some(checks) = self.checks {
            filter.set_data_checks(checks).map_err(Error::Estimator)?;
        }
        let mut row = DataRow::zeros(3, 5);
        let u = DVector::zeros(0);
        // The measurement the filter consumes: the INS-minus-BDS difference (13) and the receiver
        // status [N, RTK] of the epoch (RTK 0: no fix, a prediction only).
        let mut y = DVector::zeros(5);
        while data.read_row(&mut row)? {
            s.heading.check(data, 3, "u3 (INS heading)", row.u[2])?;
            s.heading.check(data, 6, "y3 (BDS heading)", row.y[2])?;
            check_satellites(data, SATELLITES_COLUMN, row.y[3], &s.satellites)?;
            let ins = [row.u[0], row.u[1], row.u[2]];
            let code = rtk_code(&row, self.coding, data)?;
            let z = measurement(ins, [row.y[0], row.y[1], row.y[2]]);
            y.rows_mut(0, 3).copy_from_slice(&z);
            y[3] = row.y[3];
            y[4] = code;
            let e = match Estimator::step(&mut filter, &s.model, &u, &y) {
                Ok(e) => e,
                Err(err) => {
                    let probe = self.rules.probe.clone();
                    let retry = |t: f64| {
                        // The filter is unchanged by the failed step: try it again with `t`.
                        let Some(p) = probe else { return false };
                        p.forced.set(Some(t));
                        let ok = Estimator::step(&mut filter, &s.model, &u, &y).is_ok();
                        p.forced.set(None);
                        ok
                    };
                    return Err(self.step_error(err, data, row.k, retry));
                }
            };
            enforce(self.status, e.status(), || data.locate(Some(0)), row.k)?;
            let Some(label) = row.k.checked_add(1) else {
                return Err(Error::at(data.locate(Some(0)), format!("k = {} is too large", row.k)));
            };
            let c = correct(ins, &e.center).map_err(|e| Error::Usage(e.to_string()))?;
            let (dx, dy, dpsi) = (e.center[idx::DX], e.center[idx::DY], e.center[idx::DPSI]);
            let sd = |i: usize| e.std_dev[i];
            let (t, d) = match (e.details.get("scale"), e.details.get("distance")) {
                (Some(Some(t)), Some(Some(d))) => (format!("{t:e}"), format!("{d:e}")),
                _ => (String::new(), String::new()),
            };
            writeln!(
                out,
                "{label},{:e},{:e},{:e},{dx:e},{dy:e},{dpsi:e},{:e},{:e},{:e},{t},{d},{}",
                c[0],
                c[1],
                c[2],
                sd(idx::DX),
                sd(idx::DY),
                sd(idx::DPSI),
                e.status
            )
            .map_err(wio)?;
            tally.record(e.status());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A log in the documented layout from the reproduction's field route: the truth drives due
    /// east at 10 m/s from (0, 0), heading 90°; INS = truth + error state, BDS = truth + BDS error.
    fn log(seconds: usize, outage_every: usize) -> (String, Vec<[f64; 2]>) {
        let s = read_config(None, &Limits::default()).unwrap();
        let truth_model = InsErrorModel::new(InsParams::digest(), InsNoise::digest()).unwrap().discretize(1.0).unwrap();
        let mut rng = models::Xoshiro256StarStar::seed_from_u64(5);
        let xs = bds_ins_dynamics::simulate_error_states(&truth_model, &scenario::initial_error(), seconds, &mut rng)
            .unwrap();
        let bds = bds_ins_dynamics::BdsSimulator::new(
            scenario::paper_zones(scenario::NoiseIncrease::Variance, RtkStatus::Float),
            1.0,
            6,
        )
        .unwrap();
        let _ = s;
        let mut text = String::from("k,u1,u2,u3,y1,y2,y3,y4,y5\n");
        let mut truth = Vec::new();
        for (k, epoch) in bds.take(seconds).enumerate() {
            let t = (k + 1) as f64;
            let (px, py, psi) = (10.0 * t, 0.0, std::f64::consts::FRAC_PI_2);
            let x = &xs[k + 1];
            let ins = [px + x[idx::DX], py + x[idx::DY], psi + x[idx::DPSI]];
            let fix = epoch.fix.unwrap();
            let bdsp = [px + fix.error[0], py + fix.error[1], psi + fix.error[2]];
            let code = if outage_every > 0 && k % outage_every == outage_every - 1 { 0 } else { fix.rtk.code() };
            text.push_str(&format!(
                "{k},{},{},{},{},{},{},{},{code}\n",
                ins[0], ins[1], ins[2], bdsp[0], bdsp[1], bdsp[2], fix.satellites
            ));
            truth.push([px, py]);
        }
        (text, truth)
    }

    fn options(fis: Option<&Path>, fuzzy: bool, coding: RtkCoding) -> BdsInsOptions {
        BdsInsOptions {
            fis: fis.map(Path::to_owned),
            fuzzy,
            rtk_coding: coding,
            ..BdsInsOptions::new("d.csv", "o.csv")
        }
    }

    pub(super) fn run_with(text: &str, options: &BdsInsOptions) -> Result<(String, BdsInsSummary), Error> {
        let settings = read_config(None, &Limits::default())?;
        let (mut runner, scaling) = Runner::new(&settings, options)?;
        let mut data = DataReader::from_text(Path::new("d.csv"), text, 3, 5)?;
        let mut out = Vec::new();
        let mut tally = StatusTally::default();
        runner.run(scaling, &mut data, &mut out, Path::new("o.csv"), &mut tally)?;
        let summary = BdsInsSummary { epochs: tally.steps, outages: tally.predicted, tally };
        Ok((String::from_utf8(out).unwrap(), summary))
    }

    fn run_text(text: &str, fuzzy: bool, coding: RtkCoding) -> Result<(String, BdsInsSummary), Error> {
        run_with(text, &options(None, fuzzy, coding))
    }

    fn run_checked(
        text: &str,
        fuzzy: bool,
        coding: RtkCoding,
        checks: Option<estimators::DataChecks>,
    ) -> Result<(String, BdsInsSummary), Error> {
        run_with(text, &BdsInsOptions { checks, ..options(None, fuzzy, coding) })
    }

    #[test]
    fn the_filter_corrects_the_ins_on_a_logged_route() {
        let (text, truth) = log(900, 10);
        let (out, summary) = run_text(&text, true, RtkCoding::Paper).unwrap();
        assert_eq!((summary.epochs, summary.outages, summary.tally.unclean()), (900, 90, 0));
        let lines: Vec<&str> = out.lines().collect();
        assert_eq!(lines[0], "k,x,y,psi,dx,dy,dpsi,sd_dx,sd_dy,sd_dpsi,t,d,status");
        let mut sq = 0.0;
        let mut ins_sq = 0.0;
        let (mut scaled_before, mut scaled_after) = (0.0, 0.0);
        for (k, line) in lines[1..].iter().enumerate().skip(100) {
            let cells: Vec<&str> = line.split(',').collect();
            let v: Vec<f64> = cells[..10].iter().map(|x| x.parse().unwrap()).collect();
            assert_eq!(v[0], (k + 1) as f64);
            sq += (v[1] - truth[k][0]).powi(2) + (v[2] - truth[k][1]).powi(2);
            ins_sq += (v[1] + v[4] - truth[k][0]).powi(2) + (v[2] + v[5] - truth[k][1]).powi(2);
            if k % 10 == 9 {
                assert_eq!((cells[10], cells[11], cells[12]), ("", "", "predicted"), "outage row {k}");
            } else if k < 600 {
                scaled_before += cells[10].parse::<f64>().unwrap();
            } else {
                scaled_after += cells[10].parse::<f64>().unwrap();
            }
        }
        let rms = (sq / 800.0).sqrt();
        let ins_rms = (ins_sq / 800.0).sqrt();
        assert!(rms < 0.3, "corrected RMS {rms} m");
        assert!(ins_rms > 10.0 * rms, "the INS alone {ins_rms} m");
        // Float after 600 s: the FIS scales R up (t ≈ 5) where the fixed phase had t ≈ 1.
        assert!(scaled_after / 270.0 > 2.0 * scaled_before / 450.0, "{scaled_before} {scaled_after}");
        // The plain KF on the same file: its innovation gate finds the float fixes after 600 s (noise
        // five times the nominal) outliers; without the check, t = 1 throughout.
        let e = run_text(&text, false, RtkCoding::Paper).unwrap_err().to_string();
        assert!(e.contains("is an outlier: normalised innovation squared"), "{e}");
        let line: u64 = e.split(':').nth(1).unwrap().parse().unwrap();
        assert!(line > 600, "the first outlier after the noise grows: {e}");
        let (plain, _) = run_checked(&text, false, RtkCoding::Paper, Some(estimators::DataChecks::OFF)).unwrap();
        assert!(
            plain.lines().skip(1).filter(|l| !l.ends_with(",,predicted")).all(|l| l.split(',').nth(10) == Some("1e0"))
        );
    }

    #[test]
    fn bad_status_cells_are_located() {
        let head = "k,u1,u2,u3,y1,y2,y3,y4,y5\n0,0,0,0,0,0,0,20,3\n";
        let e = run_text(&format!("{head}1,0,0,0,0,0,0,-2,3\n"), true, RtkCoding::Paper).unwrap_err().to_string();
        assert!(e.starts_with("d.csv:3:15: y4 = -2 satellites is not a count"), "{e}");
        let e = run_text(&format!("{head}1,0,0,0,0,0,0,7.5,3\n"), true, RtkCoding::Paper).unwrap_err().to_string();
        assert!(e.starts_with("d.csv:3:15: y4 = 7.5 satellites is not a count"), "{e}");
        // Headings in degrees: beyond ±2π rad, at the INS's and the BDS's cells.
        let e = run_text(&format!("{head}1,0,0,45,0,0,0,20,3\n"), true, RtkCoding::Paper).unwrap_err().to_string();
        assert!(e.starts_with("d.csv:3:7: u3 (INS heading) = 45 rad is beyond the plausible"), "{e}");
        assert!(e.contains("`max_heading`"), "{e}");
        let e = run_text(&format!("{head}1,0,0,0,0,0,-90,20,3\n"), true, RtkCoding::Paper).unwrap_err().to_string();
        assert!(e.starts_with("d.csv:3:13: y3 (BDS heading) = -90 rad"), "{e}");
        let e = run_text(&format!("{head}1,0,0,0,0,0,0,20,7\n"), true, RtkCoding::Paper).unwrap_err().to_string();
        assert!(e.starts_with("d.csv:3:18: RTK status code 7 is not one of"), "{e}");
        assert!(e.contains("--gga"), "{e}");
        // GGA: 4 is RTK fixed, 5 float, 0 no fix; 3 (PPS) is refused.
        let (out, s) = run_text(
            "k,u1,u2,u3,y1,y2,y3,y4,y5\n0,0,0,0,0,0,0,20,4\n1,0,0,0,0,0,0,20,0\n2,0,0,0,0,0,0,20,5\n",
            true,
            RtkCoding::Gga,
        )
        .unwrap();
        assert_eq!(s.outages, 1);
        assert_eq!(out.lines().count(), 4);
        let gga_head = "k,u1,u2,u3,y1,y2,y3,y4,y5\n0,0,0,0,0,0,0,20,4\n";
        let e = run_text(&format!("{gga_head}1,0,0,0,0,0,0,20,3\n"), true, RtkCoding::Gga).unwrap_err().to_string();
        assert!(e.starts_with("d.csv:3:18: y5 = 3 is not an NMEA GGA quality"), "{e}");
        // A wrong header names the expected column.
        let e = DataReader::from_text(Path::new("d.csv"), "k,x,y\n", 3, 5).unwrap_err().to_string();
        assert!(e.starts_with("d.csv:1:3: the header has no column \"u1\""), "{e}");
    }

    #[test]
    fn settings_and_fuzzy_systems_are_checked() {
        let dir = std::env::temp_dir().join(format!("port-est-bds-ins-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let cfg = dir.join("c.toml");
        let read = |cfg: &Path| read_config(Some(cfg), &Limits::default());
        for (text, expected) in [
            (
                "ts = 0.5\nlatitude_deg = 45.0\nsigma0 = 0.05\np0_sigma = [1.0]\n",
                "c.toml:4:12: `p0_sigma`: expected 13 entries, found 1",
            ),
            ("ts = 0.5\nflat = true\nsigma0 = -1\n", "c.toml:3:10: `sigma0`: must be positive"),
            ("ts = 0.5\nlatitude = 3\n", "c.toml:2:1"),
            ("ts = 0.5\nlatitude_deg = 95.0\n", "c.toml:2:16: `latitude_deg`: must lie in [-89, 89] degrees"),
        ] {
            std::fs::write(&cfg, text).unwrap();
            let e = read(&cfg).unwrap_err().to_string();
            assert!(e.contains(expected), "{text}: {e}");
        }
        std::fs::write(&cfg, "ts = 0.5\nlatitude_deg = 45.0\nsigma0 = 0.05\n").unwrap();
        let s = read(&cfg).unwrap();
        assert_eq!((s.model.ts, s.sigma0), (0.5, 0.05));
        // The shipped system loads; a malformed one is refused, naming the file.
        let fis = dir.join("fis.toml");
        let system =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../fuzzy-inference/systems/bds_ins.toml"))
                .unwrap();
        std::fs::write(&fis, &system).unwrap();
        let options = |fis: &Path| options(Some(fis), true, RtkCoding::Paper);
        assert!(scaling(&options(&fis), 0.2).is_ok());
        std::fs::write(&fis, "default_output = 1\n").unwrap();
        let e = scaling(&options(&fis), 0.2).err().unwrap().to_string();
        assert!(e.starts_with("--fis: ") && e.contains("fis.toml"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_step_the_rule_file_makes_fail_names_the_rule_file() {
        use fuzzy_inference::{InputVariable, MembershipFunction, OutputScale, OutputVariable, Rule};
        // A system whose outputs are negative: refused at load as a rule file (at `[output]`)…
        let any = |name: &str| InputVariable {
            name: name.into(),
            range: (0.0, 100.0),
            sets: vec![("any".into(), MembershipFunction::trapezoid(0.0, 0.0, f64::INFINITY, f64::INFINITY))],
        };
        let output = OutputVariable {
            name: "t".into(),
            universe: (-1.0, 1.0),
            sets: vec![("neg".into(), MembershipFunction::triangle(-1.0, -0.5, 0.0))],
            scale: OutputScale::Linear,
        };
        let rules = vec![Rule::new(&[("N", "any")], "neg")];
        let system = FuzzySystem::new(vec![any("N"), any("RTK"), any("d")], output, rules, 0.5).unwrap();
        let e = system.clone().bind(&BDS_INS_INTERFACE).unwrap_err().to_string();
        assert!(e.contains("must be positive and finite"), "{e}");
        // …and if such a system reaches the filter anyway, the failure names it, not the row.
        let settings = read_config(None, &Limits::default()).unwrap();
        let probe = Rc::new(Probe::default());
        let scaling = Scaling::Fuzzy(Box::new(FuzzyScaling::new(system).unwrap()), Rc::clone(&probe));
        let rules = Rules { probe: Some(probe), path: Some("rules.toml".into()) };
        let mut runner =
            Runner { settings: &settings, coding: RtkCoding::Paper, status: StatusPolicy::Warn, checks: None, rules };
        let text = "k,u1,u2,u3,y1,y2,y3,y4,y5\n0,0,0,0,0,0,0,20,3\n";
        let mut data = DataReader::from_text(Path::new("d.csv"), text, 3, 5).unwrap();
        let mut tally = StatusTally::default();
        let e = runner.run(scaling, &mut data, &mut Vec::new(), Path::new("o.csv"), &mut tally).unwrap_err();
        assert!(matches!(e, Error::RuleFile { .. }), "{e}");
        let e = e.to_string();
        assert!(e.starts_with("rules.toml: the noise scale t_k must be positive and finite, got -0.5"), "{e}");
        assert!(e.contains("(at d.csv:2:1, step k = 0: the rule file's output, not the row, is the cause)"), "{e}");
    }
}
