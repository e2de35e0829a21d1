//! `port-est truck`: the extended Kalman filter of the truck paper (`docs/truck-ekf.md`) over
//! logged data of a 3-axle port truck, with the truck model of `truck-dynamics` (the digest's
//! vehicle, `TruckParams::digest_preset`, Euler at the sample period).
//!
//! `DATA.csv` has the general layout of `port-est filter` with `p = 7` inputs and `m = 3`
//! outputs — header `k,u1,…,u7,y1,y2,y3`:
//!
//! | column | quantity | unit |
//! |---|---|---|
//! | `u1` | road-wheel steering angle `δ` of the front axle | rad |
//! | `u2`…`u7` | wheel speeds `ω` of the positions front-left, front-right, middle-left, middle-right, rear-left, rear-right (the `truck_dynamics::WHEEL_NAMES` order) | rad/s |
//! | `y1`, `y2`, `y3` | measured `V_x`, lateral acceleration `a_y`, yaw rate `γ` after the step | m/s, m/s², rad/s |
//!
//! `OUT.csv`: `k,vx,vy,gamma,beta,sd_vx,sd_vy,sd_gamma`, one row per step labelled `k+1`, with
//! the sideslip angle `β = atan(V_y/V_x)` \[rad\] and one standard deviation of each state.
//!
//! `--config FILE.toml` (optional) overrides the digest's settings: `ts` (sample period, s),
//! `x0` (3), `p0`, `q`, `r` (3 × 3, arrays of rows; covariances). Without `x0` the filter starts
//! from the first row's measurement (`V_x = y1`, `V_y = 0`, `γ = y3`).

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use estimators::registry::{self, names};
use estimators::{AnyEstimator, EstimatorError, Setup};
use models::DiscreteModel;
use nalgebra::{DMatrix, DVector, Vector3};
use serde::Deserialize;
use toml::Spanned;
use truck_dynamics::{TruckEkfModel, TruckInput, TruckParams, TruthTrajectory};

use crate::data::{DataReader, DataRow};
use crate::error::Error;
use crate::limits::Limits;
use crate::output::OutputFile;
use crate::plausibility::{Limit, defaults};
use crate::run::{OnError, StatusPolicy, StatusTally, enforce};
use crate::settings::{self, SettingsFile};

/// What `port-est truck` needs.
#[derive(Debug, Clone)]
pub struct TruckOptions {
    /// The logged data.
    pub input: PathBuf,
    /// Where to write the estimates.
    pub output: PathBuf,
    /// Optional settings file.
    pub config: Option<PathBuf>,
    /// What a step that does not end cleanly does.
    pub status: StatusPolicy,
    /// How the estimator checks its data (`None`: its defaults, an error at the first step whose
    /// data contradict the noise description).
    pub checks: Option<estimators::DataChecks>,
    /// What an error does with the steps before it.
    pub on_error: OnError,
    /// Size limit of the settings file.
    pub limits: Limits,
}

impl TruckOptions {
    /// `port-est truck --input INPUT --output OUTPUT` with every other setting at the command
    /// line's default: the digest's settings, a warning for a step that does not end cleanly, the
    /// estimator's data checks, nothing written on an error, the default limits.
    #[must_use]
    pub fn new(input: impl Into<PathBuf>, output: impl Into<PathBuf>) -> Self {
        Self {
            input: input.into(),
            output: output.into(),
            config: None,
            status: StatusPolicy::Warn,
            checks: None,
            on_error: OnError::Discard,
            limits: Limits::default(),
        }
    }
}

/// The settings file, as written.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct ConfigFile {
    ts: Option<Spanned<f64>>,
    x0: Option<Spanned<Vec<f64>>>,
    p0: Option<Spanned<Vec<Vec<f64>>>>,
    q: Option<Spanned<Vec<Vec<f64>>>>,
    r: Option<Spanned<Vec<Vec<f64>>>>,
    max_steering: Option<Spanned<f64>>,
    max_wheel_speed: Option<Spanned<f64>>,
}

/// The wheel-speed columns of the log as errors name them (no formatting per row).
const WHEEL_SPEED_COLUMNS: [&str; 6] = [
    "u2 (wheel speed)",
    "u3 (wheel speed)",
    "u4 (wheel speed)",
    "u5 (wheel speed)",
    "u6 (wheel speed)",
    "u7 (wheel speed)",
];

/// The validated settings.
#[derive(Debug, Clone)]
pub(crate) struct Settings {
    ts: f64,
    x0: Option<DVector<f64>>,
    p0: DMatrix<f64>,
    q: DMatrix<f64>,
    r: DMatrix<f64>,
    /// The plausible road-wheel steering angle `|u1|`.
    steering: Limit,
    /// The plausible wheel speeds `|u2…u7|`.
    wheel_speed: Limit,
}

/// Reads the settings file (`None`: the digest's defaults).
fn read_config(path: Option<&Path>, limits: &Limits) -> Result<Settings, Error> {
    let (file, source): (ConfigFile, SettingsFile) = SettingsFile::read(path, limits.file_bytes)?;
    settings_of(&file, &source)
}

/// Checks every setting at its key, then the matrices the filter is given (those derived from
/// `ts` named by it).
pub(crate) fn settings_of(file: &ConfigFile, source: &SettingsFile) -> Result<Settings, Error> {
    let ts = match &file.ts {
        Some(v) => settings::positive(source, "ts", v)?,
        None => truck_dynamics::PAPER_SAMPLE_PERIOD,
    };
    // The digest's §4 settings (assumed there, not the paper's): Q = T diag(qc), R = diag(σ²).
    let q = match &file.q {
        Some(v) => settings::covariance(source, "q", v, 3)?,
        None => {
            let q = DMatrix::from_diagonal(&DVector::from_vec(vec![1e-4 * ts, 1e-4 * ts, 1e-6 * ts]));
            settings::check_covariance(&q).map_err(|why| {
                let span = file.ts.as_ref().map(Spanned::span);
                source.derived_error(
                    &[("ts", span)],
                    format!("the default process noise Q = ts·diag(1e-4, 1e-4, 1e-6) it sets {why}; give `q`"),
                )
            })?;
            q
        }
    };
    let r = match &file.r {
        Some(v) => settings::covariance(source, "r", v, 3)?,
        None => DMatrix::from_diagonal(&DVector::from_vec(vec![0.05f64.powi(2), 0.05f64.powi(2), 0.002f64.powi(2)])),
    };
    let p0 = match &file.p0 {
        Some(v) => settings::covariance(source, "p0", v, 3)?,
        None => DMatrix::from_diagonal(&DVector::from_vec(vec![0.01, 0.01, 1e-4])),
    };
    let x0 = match &file.x0 {
        Some(v) => {
            let x = settings::vector(source, "x0", v, 3)?;
            if x[0] <= 0.0 {
                let message = format!("V_x = {} must be positive (the model drives forward: β divides by V_x)", x[0]);
                return Err(source.error("x0", v, message));
            }
            Some(DVector::from_vec(x))
        }
        None => None,
    };
    let model = TruckEkfModel::new(TruckParams::digest_preset(), ts).map_err(|e| {
        let span = file.ts.as_ref().map(Spanned::span);
        source.derived_error(&[("ts", span)], format!("truck model: {e}"))
    })?;
    let limit = |key, v: &Option<Spanned<f64>>, default| settings::positive_or(source, key, v, default);
    let steering = Limit {
        key: "max_steering",
        bound: limit("max_steering", &file.max_steering, defaults::MAX_STEERING)?,
        unit: "rad",
        hint: "logged in degrees, or the steering-wheel angle instead of the road wheels'?",
    };
    let wheel_speed = Limit {
        key: "max_wheel_speed",
        bound: limit("max_wheel_speed", &file.max_wheel_speed, defaults::MAX_WHEEL_SPEED)?,
        unit: "rad/s",
        hint: "logged in rpm or degrees per second?",
    };
    let settings = Settings { ts, x0, p0, q, r, steering, wheel_speed };
    // What the filter itself checks, in the file's terms.
    let probe = setup(&settings, &model, DVector::from_vec(vec![10.0, 0.0, 0.0]));
    registry::build(names::EKF, probe, None).map_err(|e| {
        let key = match &e {
            EstimatorError::NotSymmetric { what }
            | EstimatorError::NotPositiveDefinite { what }
            | EstimatorError::NotPositiveSemidefinite { what }
            | EstimatorError::NonFinite { what, .. } => match *what {
                "Q" => Some(("q", file.q.as_ref().map(Spanned::span))),
                "R" => Some(("r", file.r.as_ref().map(Spanned::span))),
                "P0" => Some(("p0", file.p0.as_ref().map(Spanned::span))),
                _ => None,
            },
            _ => None,
        };
        match key {
            Some((k, span)) => {
                source.derived_error(&[(k, span), ("ts", file.ts.as_ref().map(Spanned::span))], e.to_string())
            }
            None => Error::Estimator(e),
        }
    })?;
    Ok(settings)
}

/// The filter's setup from the settings, starting at `x0`.
fn setup(s: &Settings, model: &TruckEkfModel, x0: DVector<f64>) -> Setup {
    Setup {
        x0,
        p0: s.p0.clone(),
        process_noise: s.q.clone(),
        measurement_noise: s.r.clone(),
        inputs: model.dims().inputs,
    }
}

/// Runs the EKF over `options.input` and writes `options.output` (atomically); returns the steps.
///
/// # Errors
/// Every [`Error`]: the output checks, a malformed settings or data file (at its
/// `file:line:column`), a step the filter or the model rejects (at its data row); with
/// [`OnError::KeepPartial`] the steps before it are kept in `OUT.partial.csv` and the error says so.
pub fn truck(options: &TruckOptions) -> Result<StatusTally, Error> {
    let mut inputs: Vec<(&'static str, &Path)> = vec![("input", &options.input)];
    if let Some(c) = &options.config {
        inputs.push(("config", c));
    }
    let mut out = OutputFile::create(&options.output, &inputs)?;
    let settings = read_config(options.config.as_deref(), &options.limits)?;
    let mut data = DataReader::open(&options.input, 7, 3)?;
    let model = settings_model(&settings)?;
    let mut tally = StatusTally::default();
    let policy = (options.status, options.checks);
    match run_truck(&model, &settings, policy, &mut data, &mut out, &options.output, &mut tally) {
        Ok(()) => {
            out.commit()?;
            Ok(tally)
        }
        Err(e) => Err(out.fail(e, tally.steps, options.on_error, &inputs)),
    }
}

/// Checks the text of a settings file (named `path` in errors) as `port-est truck --config`
/// does: every complaint at its key's `file:line:column`.
///
/// # Errors
/// As [`truck`] for a settings file.
pub fn check_settings(path: &Path, text: &str) -> Result<(), Error> {
    let (file, source): (ConfigFile, SettingsFile) = SettingsFile::from_text(path, text)?;
    settings_of(&file, &source).map(drop)
}

/// The whole of `port-est truck` but the files: the settings of `config` (a settings file's name
/// and text; `None`: the defaults) and the log `data`, the rows written to `out` (tests and
/// fuzzing drive it).
///
/// # Errors
/// As [`truck`].
pub fn run_log<R: Read, W: Write>(
    config: Option<(&Path, &str)>,
    data: &mut DataReader<R>,
    out: &mut W,
    status: StatusPolicy,
) -> Result<StatusTally, Error> {
    let settings = match config {
        Some((path, text)) => {
            let (file, source): (ConfigFile, SettingsFile) = SettingsFile::from_text(path, text)?;
            settings_of(&file, &source)?
        }
        None => read_config(None, &Limits::default())?,
    };
    let model = settings_model(&settings)?;
    let mut tally = StatusTally::default();
    run_truck(&model, &settings, (status, None), data, out, Path::new("<output>"), &mut tally)?;
    Ok(tally)
}

fn settings_model(s: &Settings) -> Result<TruckEkfModel, Error> {
    TruckEkfModel::new(TruckParams::digest_preset(), s.ts).map_err(|e| Error::Usage(format!("truck model: {e}")))
}

fn run_truck<R: Read, W: Write>(
    model: &TruckEkfModel,
    s: &Settings,
    (status, checks): (StatusPolicy, Option<estimators::DataChecks>),
    data: &mut DataReader<R>,
    out: &mut W,
    out_path: &Path,
    tally: &mut StatusTally,
) -> Result<(), Error> {
    let wio = |e| Error::io(out_path, e);
    writeln!(out, "k,vx,vy,gamma,beta,sd_vx,sd_vy,sd_gamma,status").map_err(wio)?;
    let mut row = DataRow::zeros(7, 3);
    let mut est: Option<AnyEstimator> = None;
    let mut from_row = false;
    while data.read_row(&mut row)? {
        s.steering.check(data, 1, "u1 (steering angle)", row.u[0])?;
        for (i, name) in WHEEL_SPEED_COLUMNS.iter().enumerate() {
            s.wheel_speed.check(data, 2 + i, name, row.u[1 + i])?;
        }
        if est.is_none() {
            from_row = s.x0.is_none();
            let x0 = s.x0.clone().unwrap_or_else(|| DVector::from_vec(vec![row.y[0], 0.0, row.y[2]]));
            let mut ekf = registry::build(names::EKF, setup(s, model, x0), None).map_err(Error::Estimator)?;
            if let Some(checks) = checks {
                ekf.set_data_checks(checks).map_err(Error::Estimator)?;
            }
            est = Some(ekf);
        }
        let Some(f) = est.as_mut() else { break };
        let e = match f.step(model, &row.u, &row.y) {
            Ok(e) => e,
            Err(source) if from_row && tally.steps == 0 => {
                // The initial state is this row's measurement: say so, and which setting replaces it.
                let message = format!(
                    "step k = {}: {source} (the filter starts from this row's measurement, V_x = y1 = {}, \
                     V_y = 0, γ = y3 = {}: give `x0` in the settings file, --config, to start elsewhere)",
                    row.k, row.y[0], row.y[2]
                );
                return Err(Error::at(data.locate(Some(8)), message));
            }
            Err(source) => return Err(Error::Step { at: data.locate(Some(0)), k: row.k, source }),
        };
        enforce(status, e.status(), || data.locate(Some(0)), row.k)?;
        let Some(label) = row.k.checked_add(1) else {
            return Err(Error::at(data.locate(Some(0)), format!("k = {} is too large", row.k)));
        };
        let c = e.center();
        let beta = (c[1] / c[0]).atan();
        let sd = |i: usize| e.shape()[(i, i)].max(0.0).sqrt();
        writeln!(
            out,
            "{label},{:e},{:e},{:e},{beta:e},{:e},{:e},{:e},{}",
            c[0],
            c[1],
            c[2],
            sd(0),
            sd(1),
            sd(2),
            e.status()
        )
        .map_err(wio)?;
        tally.record(e.status());
    }
    Ok(())
}

/// Writes `(u_k, y_{k+1})` rows in the `DATA.csv` layout of `port-est truck` (this module's
/// documentation), header first, `k` counting from 0 (see [`truth_rows`] for a simulated run's).
///
/// # Errors
/// What writing to `out` returns.
pub fn write_log<W: Write>(
    out: &mut W,
    rows: impl IntoIterator<Item = (TruckInput, Vector3<f64>)>,
) -> std::io::Result<()> {
    writeln!(out, "k,u1,u2,u3,u4,u5,u6,u7,y1,y2,y3")?;
    for (k, (u, y)) in rows.into_iter().enumerate() {
        write!(out, "{k},{}", u.delta)?;
        for w in u.omega {
            write!(out, ",{w}")?;
        }
        writeln!(out, ",{},{},{}", y[0], y[1], y[2])?;
    }
    Ok(())
}

/// The rows `(u_k, y_{k+1})` a logger would have recorded from a simulated run (noise-free).
pub fn truth_rows(truth: &TruthTrajectory) -> impl Iterator<Item = (TruckInput, Vector3<f64>)> + '_ {
    (0..truth.len().saturating_sub(1)).map_while(|k| Some((truth.estimator_input(k)?, truth.measurement(k + 1)?)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use truck_dynamics::{Slalom, TruthConfig, simulate_truth};

    /// A short slalom logged in the documented layout.
    fn log(seconds: f64) -> (String, Vec<f64>) {
        let params = TruckParams::digest_preset();
        let config = TruthConfig { duration: seconds, ..TruthConfig::digest() };
        let slalom = Slalom::digest();
        let truth = simulate_truth(&params, &config, |t| slalom.angle(t)).unwrap();
        let mut text = Vec::new();
        write_log(&mut text, truth_rows(&truth)).unwrap();
        let betas = (1..truth.len()).map(|k| truth.body_state(k).unwrap()).map(|x| (x[1] / x[0]).atan()).collect();
        (String::from_utf8(text).unwrap(), betas)
    }

    #[test]
    fn the_ekf_tracks_a_logged_slalom() {
        let (text, betas) = log(3.0);
        let settings = read_config(None, &Limits::default()).unwrap();
        let model = settings_model(&settings).unwrap();
        let mut data = DataReader::from_text(Path::new("truck.csv"), &text, 7, 3).unwrap();
        let mut out = Vec::new();
        let mut tally = StatusTally::default();
        run_truck(&model, &settings, (StatusPolicy::Warn, None), &mut data, &mut out, Path::new("o.csv"), &mut tally)
            .unwrap();
        assert_eq!((tally.steps as usize, tally.unclean()), (betas.len(), 0));
        let out = String::from_utf8(out).unwrap();
        let lines: Vec<&str> = out.lines().collect();
        assert_eq!(lines[0], "k,vx,vy,gamma,beta,sd_vx,sd_vy,sd_gamma,status");
        let mut sq = 0.0;
        for (line, beta) in lines[1..].iter().zip(&betas).skip(1000) {
            assert!(line.ends_with(",converged"), "{line}");
            let v: Vec<f64> = line.split(',').take(8).map(|x| x.parse().unwrap()).collect();
            sq += (v[4] - beta).powi(2);
        }
        let rmse = (sq / (betas.len() - 1000) as f64).sqrt().to_degrees();
        assert!(rmse < 0.1, "β RMSE {rmse}°");
    }

    #[test]
    fn implausible_steering_and_wheel_speeds_are_errors_at_their_cells_and_the_limits_are_settings() {
        let run = |config: Option<&str>, row: &str| {
            let text = format!("k,u1,u2,u3,u4,u5,u6,u7,y1,y2,y3\n{row}\n");
            let mut data = DataReader::from_text(Path::new("t.csv"), &text, 7, 3).unwrap();
            let config = config.map(|c| (Path::new("c.toml"), c));
            run_log(config, &mut data, &mut Vec::new(), StatusPolicy::Warn).map(|t| t.steps).map_err(|e| e.to_string())
        };
        let ok = "0,0.1,20,20,20,20,20,20,10,0,0";
        assert_eq!(run(None, ok), Ok(1));
        // Steering in degrees.
        let e = run(None, "0,5.7,20,20,20,20,20,20,10,0,0").unwrap_err();
        assert!(e.starts_with("t.csv:2:3: u1 (steering angle) = 5.7 rad is beyond the plausible ±1 rad"), "{e}");
        assert!(e.contains("`max_steering`"), "{e}");
        // A wheel speed in rpm (the fourth wheel).
        let e = run(None, "0,0.1,20,20,20,1900,20,20,10,0,0").unwrap_err();
        assert!(e.starts_with("t.csv:2:16: u5 (wheel speed) = 1900 rad/s"), "{e}");
        assert!(e.contains("`max_wheel_speed`"), "{e}");
        // Raised in the settings file, accepted; a bad limit is an error at its key.
        assert_eq!(
            run(Some("max_steering = 6.0\nmax_wheel_speed = 2000.0\n"), "0,5.7,20,20,20,1900,20,20,10,0,0"),
            Ok(1)
        );
        let e = run(Some("max_steering = -1.0\n"), ok).unwrap_err();
        assert!(e.starts_with("c.toml:1:16: `max_steering`: must be positive"), "{e}");
    }

    #[test]
    fn bad_rows_and_settings_are_located() {
        let settings = read_config(None, &Limits::default()).unwrap();
        let model = settings_model(&settings).unwrap();
        // V_x = 0 in the first measurement: the model divides by it, and the filter started there.
        let text = "k,u1,u2,u3,u4,u5,u6,u7,y1,y2,y3\n0,0,0,0,0,0,0,0,0,0,0\n";
        let mut data = DataReader::from_text(Path::new("t.csv"), text, 7, 3).unwrap();
        let mut tally = StatusTally::default();
        let e = run_truck(
            &model,
            &settings,
            (StatusPolicy::Warn, None),
            &mut data,
            &mut Vec::new(),
            Path::new("o.csv"),
            &mut tally,
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("t.csv:2:17: step k = 0: model: "), "{e}");
        assert!(e.contains("give `x0` in the settings file"), "{e}");
        // A wrong header names the expected column.
        let e = DataReader::from_text(Path::new("t.csv"), "k,delta\n", 7, 3).unwrap_err().to_string();
        assert!(e.starts_with("t.csv:1:"), "{e}");
        let dir = std::env::temp_dir().join(format!("port-est-truck-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let cfg = dir.join("c.toml");
        std::fs::write(&cfg, "ts = 0.001\nq = [[1.0, 0.0], [0.0, 1.0]]\n").unwrap();
        let e = read_config(Some(&cfg), &Limits::default()).unwrap_err().to_string();
        assert!(e.contains("c.toml:2:5: `q`: must be 3 rows of 3 numbers"), "{e}");
        std::fs::write(&cfg, "ts = \"fast\"\n").unwrap();
        let e = read_config(Some(&cfg), &Limits::default()).unwrap_err().to_string();
        assert!(e.contains("c.toml:1:6"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
