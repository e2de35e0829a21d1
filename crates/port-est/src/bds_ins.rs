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

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use bds_ins_dynamics::{
    DiscreteInsModel, Earth, InsErrorModel, InsNoise, InsParams, RtkStatus, STATES, correct, idx, measurement, scenario,
};
use estimators::{
    AdaptiveError, AdaptiveKalmanFilter, ConstantScaling, Estimate, Estimator, EstimatorError, FuzzyScaling,
    NoiseScaling, Setup, StepDetails,
};
use fuzzy_inference::FuzzySystem;
use nalgebra::{DMatrix, DVector};
use serde::Deserialize;

use crate::data::{DataReader, DataRow};
use crate::error::Error;
use crate::output::OutputFile;
use crate::run::{StatusPolicy, StatusTally, enforce};

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
struct ConfigFile {
    ts: Option<f64>,
    latitude_deg: Option<f64>,
    flat: Option<bool>,
    sigma0: Option<f64>,
    heading_sigma_deg: Option<f64>,
    accel_white: Option<f64>,
    gyro_white: Option<f64>,
    p0_sigma: Option<Vec<f64>>,
}

/// The validated settings.
#[derive(Debug, Clone)]
struct Settings {
    model: DiscreteInsModel,
    sigma0: f64,
    r: DMatrix<f64>,
    p0: DMatrix<f64>,
}

fn read_config(path: Option<&Path>) -> Result<Settings, Error> {
    let file: ConfigFile = crate::model::read_settings_toml(path)?;
    let p = path.unwrap_or(Path::new("<defaults>"));
    let bad = |message: String| Error::File { path: p.to_owned(), message };
    let positive = |key: &str, v: f64| {
        if v.is_finite() && v > 0.0 { Ok(v) } else { Err(bad(format!("`{key}` must be positive and finite, got {v}"))) }
    };
    let ts = positive("ts", file.ts.unwrap_or(scenario::PAPER_PERIOD))?;
    let sigma0 = positive("sigma0", file.sigma0.unwrap_or(scenario::SIGMA0))?;
    let heading =
        positive("heading_sigma_deg", file.heading_sigma_deg.unwrap_or(scenario::HEADING_SIGMA0.to_degrees()))?
            .to_radians();
    let earth = if file.flat.unwrap_or(false) {
        Earth::Flat
    } else {
        Earth::Rotating { latitude: file.latitude_deg.map_or(bds_ins_dynamics::DIGEST_LATITUDE, f64::to_radians) }
    };
    let digest = InsNoise::digest_filter();
    let noise = InsNoise {
        accel_white: file.accel_white.unwrap_or(digest.accel_white),
        gyro_white: file.gyro_white.unwrap_or(digest.gyro_white),
        ..digest
    };
    let model = InsErrorModel::new(InsParams { earth, ..InsParams::digest() }, noise)
        .and_then(|m| m.discretize(ts))
        .map_err(|e| bad(format!("INS error model: {e}")))?;
    let p0_sigma = match file.p0_sigma {
        None => scenario::initial_sigma().to_vec(),
        Some(v) if v.len() == STATES && v.iter().all(|s| s.is_finite() && *s > 0.0) => v,
        Some(_) => return Err(bad(format!("`p0_sigma` must be {STATES} positive numbers (paper state order)"))),
    };
    let r = DMatrix::from_diagonal(&DVector::from_vec(vec![sigma0 * sigma0, sigma0 * sigma0, heading * heading]));
    let p0 = DMatrix::from_diagonal(&DVector::from_iterator(STATES, p0_sigma.iter().map(|s| s * s)));
    Ok(Settings { model, sigma0, r, p0 })
}

/// The scaling chosen on the command line.
enum Scaling {
    Fuzzy(Box<FuzzyScaling>),
    Unit(ConstantScaling),
}

impl NoiseScaling for Scaling {
    fn scale(&mut self, c: &estimators::ScalingContext<'_>) -> Result<f64, AdaptiveError> {
        match self {
            Scaling::Fuzzy(f) => f.scale(c),
            Scaling::Unit(u) => u.scale(c),
        }
    }
}

fn scaling(options: &BdsInsOptions, sigma0: f64) -> Result<Scaling, Error> {
    if !options.fuzzy {
        return Ok(Scaling::Unit(ConstantScaling(1.0)));
    }
    let system = match &options.fis {
        Some(path) => FuzzySystem::from_toml_file(path).map_err(|e| Error::Usage(format!("--fis: {e}")))?,
        None => FuzzySystem::bds_ins(sigma0).map_err(|e| Error::Usage(format!("fuzzy system: {e}")))?,
    };
    let f = FuzzyScaling::new(system).map_err(|e| {
        let shown = options.fis.as_deref().unwrap_or(Path::new("<default>")).display().to_string();
        Error::Usage(format!("--fis {shown}: {e}"))
    })?;
    Ok(Scaling::Fuzzy(Box::new(f)))
}

/// Runs the filter over `options.input` and writes `options.output` (atomically).
///
/// # Errors
/// Every [`Error`]: the output checks, a malformed settings, fuzzy-system or data file (at its
/// `file:line:column`), a receiver status or a step the filter rejects (at its data cell).
pub fn bds_ins(options: &BdsInsOptions) -> Result<BdsInsSummary, Error> {
    let mut inputs: Vec<(&'static str, &Path)> = vec![("input", &options.input)];
    if let Some(c) = &options.config {
        inputs.push(("config", c));
    }
    if let Some(f) = &options.fis {
        inputs.push(("fis", f));
    }
    let mut out = OutputFile::create(&options.output, &inputs)?;
    let settings = read_config(options.config.as_deref())?;
    let scaling = scaling(options, settings.sigma0)?;
    let mut data = DataReader::open(&options.input, 3, 5)?;
    let policy = (options.status, options.checks);
    let summary = run(&settings, scaling, options.rtk_coding, policy, &mut data, &mut out, &options.output)?;
    out.commit()?;
    Ok(summary)
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

/// A step's error at its data row: the receiver status at its cell, with a hint for RTK codes.
fn step_error<R: Read>(e: EstimatorError, data: &DataReader<R>, k: u64, coding: RtkCoding) -> Error {
    match e {
        EstimatorError::Adaptive { index: Some(i), source } => {
            let column = if i == 3 { SATELLITES_COLUMN } else { RTK_COLUMN };
            let hint = if coding == RtkCoding::Paper && matches!(*source, AdaptiveError::RtkOutOfRange(_)) {
                " (0 marks an epoch without a fix; --gga reads NMEA GGA qualities)"
            } else {
                ""
            };
            Error::at(data.locate(Some(column)), format!("{source}{hint}"))
        }
        e => crate::run::step_error(e, data, k),
    }
}

fn run<R: Read, W: Write>(
    s: &Settings,
    scaling: Scaling,
    coding: RtkCoding,
    (status, checks): (StatusPolicy, Option<estimators::DataChecks>),
    data: &mut DataReader<R>,
    out: &mut W,
    out_path: &Path,
) -> Result<BdsInsSummary, Error> {
    let wio = |e| Error::io(out_path, e);
    writeln!(out, "k,x,y,psi,dx,dy,dpsi,sd_dx,sd_dy,sd_dpsi,t,d,status").map_err(wio)?;
    let setup = Setup {
        x0: DVector::zeros(STATES),
        p0: s.p0.clone(),
        process_noise: s.model.q.clone(),
        measurement_noise: s.r.clone(),
        inputs: 0,
    };
    let mut filter = AdaptiveKalmanFilter::new(setup, scaling).map_err(|e| Error::Usage(format!("filter: {e}")))?;
    if let Some(checks) = checks {
        filter.set_data_checks(checks).map_err(Error::Estimator)?;
    }
    let mut row = DataRow::zeros(3, 5);
    let u = DVector::zeros(0);
    // The measurement the filter consumes: the INS-minus-BDS difference (13) and the receiver
    // status [N, RTK] of the epoch (RTK 0: no fix, a prediction only).
    let mut y = DVector::zeros(5);
    let mut tally = StatusTally::default();
    while data.read_row(&mut row)? {
        let ins = [row.u[0], row.u[1], row.u[2]];
        let code = rtk_code(&row, coding, data)?;
        let z = measurement(ins, [row.y[0], row.y[1], row.y[2]]);
        y.rows_mut(0, 3).copy_from_slice(&z);
        y[3] = row.y[3];
        y[4] = code;
        let e = Estimator::step(&mut filter, &s.model, &u, &y).map_err(|e| step_error(e, data, row.k, coding))?;
        enforce(status, e.status(), || data.locate(Some(0)), row.k)?;
        tally.record(e.status());
        let Some(label) = row.k.checked_add(1) else {
            return Err(Error::at(data.locate(Some(0)), format!("k = {} is too large", row.k)));
        };
        let c = correct(ins, &e.center).map_err(|e| Error::Usage(e.to_string()))?;
        let (dx, dy, dpsi) = (e.center[idx::DX], e.center[idx::DY], e.center[idx::DPSI]);
        let sd = |i: usize| e.std_dev[i];
        let (t, d) = match e.details {
            StepDetails::Adaptive(Some(r)) => (format!("{:e}", r.scale), format!("{:e}", r.distance)),
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
    }
    Ok(BdsInsSummary { epochs: tally.steps, outages: tally.predicted, tally })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A log in the documented layout from the reproduction's field route: the truth drives due
    /// east at 10 m/s from (0, 0), heading 90°; INS = truth + error state, BDS = truth + BDS error.
    fn log(seconds: usize, outage_every: usize) -> (String, Vec<[f64; 2]>) {
        let s = read_config(None).unwrap();
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

    fn run_text(text: &str, fuzzy: bool, coding: RtkCoding) -> Result<(String, BdsInsSummary), Error> {
        run_checked(text, fuzzy, coding, None)
    }

    fn run_checked(
        text: &str,
        fuzzy: bool,
        coding: RtkCoding,
        checks: Option<estimators::DataChecks>,
    ) -> Result<(String, BdsInsSummary), Error> {
        let settings = read_config(None)?;
        let options = BdsInsOptions {
            input: "d.csv".into(),
            output: "o.csv".into(),
            config: None,
            fis: None,
            fuzzy,
            rtk_coding: coding,
            status: StatusPolicy::Warn,
            checks: None,
        };
        let scaling = scaling(&options, settings.sigma0)?;
        let mut data = DataReader::from_text(Path::new("d.csv"), text, 3, 5)?;
        let mut out = Vec::new();
        let policy = (StatusPolicy::Warn, checks);
        let summary = run(&settings, scaling, coding, policy, &mut data, &mut out, Path::new("o.csv"))?;
        Ok((String::from_utf8(out).unwrap(), summary))
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
        assert_eq!(e, "d.csv:3:15: the satellite count must be non-negative, got -2");
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
        assert!(e.starts_with("d.csv:1:3: header column 2"), "{e}");
    }

    #[test]
    fn settings_and_fuzzy_systems_are_checked() {
        let dir = std::env::temp_dir().join(format!("port-est-bds-ins-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let cfg = dir.join("c.toml");
        std::fs::write(&cfg, "ts = 0.5\nlatitude_deg = 45.0\nsigma0 = 0.05\np0_sigma = [1.0]\n").unwrap();
        let e = read_config(Some(&cfg)).unwrap_err().to_string();
        assert!(e.contains("`p0_sigma` must be 13 positive numbers"), "{e}");
        std::fs::write(&cfg, "ts = 0.5\nflat = true\nsigma0 = -1\n").unwrap();
        assert!(read_config(Some(&cfg)).unwrap_err().to_string().contains("`sigma0` must be positive"));
        std::fs::write(&cfg, "ts = 0.5\nlatitude = 3\n").unwrap();
        let e = read_config(Some(&cfg)).unwrap_err().to_string();
        assert!(e.contains("c.toml:2:1"), "{e}");
        std::fs::write(&cfg, "ts = 0.5\nlatitude_deg = 95.0\n").unwrap();
        assert!(read_config(Some(&cfg)).unwrap_err().to_string().contains("latitude"));
        std::fs::write(&cfg, "ts = 0.5\nlatitude_deg = 45.0\nsigma0 = 0.05\n").unwrap();
        let s = read_config(Some(&cfg)).unwrap();
        assert_eq!((s.model.ts, s.sigma0), (0.5, 0.05));
        // The shipped system loads; a malformed one is refused, naming the file.
        let fis = dir.join("fis.toml");
        let system =
            std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../fuzzy-inference/systems/bds_ins.toml"))
                .unwrap();
        std::fs::write(&fis, &system).unwrap();
        let options = |fis: &Path| BdsInsOptions {
            input: "d.csv".into(),
            output: "o.csv".into(),
            config: None,
            fis: Some(fis.to_owned()),
            fuzzy: true,
            rtk_coding: RtkCoding::Paper,
            status: StatusPolicy::Warn,
            checks: None,
        };
        assert!(scaling(&options(&fis), 0.2).is_ok());
        std::fs::write(&fis, "default_output = 1\n").unwrap();
        let e = scaling(&options(&fis), 0.2).err().unwrap().to_string();
        assert!(e.starts_with("--fis: ") && e.contains("fis.toml"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
