//! The command line, declared with `clap`'s derive API. Paths are `PathBuf`s, so arguments that
//! are not UTF-8 are accepted (paths) or refused by `clap` with a message (names), never a
//! panic.

use std::path::PathBuf;

use clap::builder::{PossibleValue, PossibleValuesParser};
use clap::{Args, Parser, Subcommand};
use estimators::registry;

/// Guaranteed (set-membership) and Kalman state estimation over logged data of port vehicles.
#[derive(Debug, Parser)]
#[command(name = "port-est", version, arg_required_else_help = true, propagate_version = true)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
    /// The largest model, settings or rule file read (each is read whole): bytes, or with K, M,
    /// G (KiB, MiB, GiB)
    #[arg(long, value_name = "SIZE", global = true, default_value = "16MiB", value_parser = size)]
    pub max_file_size: u64,
}

/// A size argument (`4096`, `64MiB`, `2G`).
fn size(text: &str) -> Result<u64, String> {
    crate::limits::parse_size(text)
}

/// What an error does with the steps before it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum OnErrorArg {
    /// Write nothing (the output is published only when every step succeeded)
    Discard,
    /// Keep the steps before the error in OUT.partial.csv beside the output
    KeepPartial,
}

impl From<OnErrorArg> for crate::OnError {
    fn from(a: OnErrorArg) -> Self {
        match a {
            OnErrorArg::Discard => crate::OnError::Discard,
            OnErrorArg::KeepPartial => crate::OnError::KeepPartial,
        }
    }
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run an estimator over logged inputs and measurements, one estimate per step
    Filter(FilterArgs),
    /// Run the truck paper's extended Kalman filter over logged data of a 3-axle port truck
    Truck(TruckArgs),
    /// Run the BDS/INS paper's fuzzy-adaptive Kalman filter over logged INS and BDS solutions with the receiver status
    BdsIns(BdsInsArgs),
    /// List the estimators (--estimator) and the solvers of the set-membership filters (--solver);
    /// with --model, which estimators run on that model and why the others do not
    Estimators(EstimatorsArgs),
    /// List a ROS 2 bag's (MCAP) topics: type, encoding, messages, rate and the numeric field
    /// paths a model file's `[log]` table can map
    Inspect(InspectArgs),
}

/// The arguments of `port-est inspect`.
#[derive(Debug, Args)]
pub struct InspectArgs {
    /// The bag (MCAP)
    #[arg(value_name = "BAG.mcap")]
    pub bag: PathBuf,
}

const TRUCK_FORMATS: &str = "\
Files:
  DATA.csv    header `k,u1,…,u7,y1,y2,y3`: u1 = front road-wheel steering angle δ [rad];
              u2…u7 = wheel speeds ω [rad/s] of front-left, front-right, middle-left, middle-right,
              rear-left, rear-right; y1, y2, y3 = measured Vx [m/s], a_y [m/s²], γ [rad/s] after the step.
  OUT.csv     header `k,vx,vy,gamma,beta,sd_vx,sd_vy,sd_gamma` (β = atan(Vy/Vx) [rad], one standard
              deviation per state), one row per step labelled k+1; written atomically.
  CONFIG.toml optional: `ts` (s), `x0` (3), `p0`, `q`, `r` (3×3 covariances, arrays of rows). Defaults:
              the digest's vehicle and settings (T = 1 ms, Q = T·diag(1e-4, 1e-4, 1e-6),
              R = diag(0.05², 0.05², 0.002²), P0 = diag(0.1², 0.1², 0.01²)); x0 from the first row.
              Every error is reported at the key's file:line:column.

--on-error keep-partial keeps the steps before an error in OUT.partial.csv (a log that turns bad
after many good steps). Limits: see crates/port-est/README.md (--max-file-size).";

/// The arguments of `port-est truck`.
#[derive(Debug, Args)]
#[command(after_long_help = TRUCK_FORMATS)]
pub struct TruckArgs {
    /// The logged data: header `k,u1,…,u7,y1,y2,y3` (δ, six wheel speeds; Vx, a_y, γ)
    #[arg(short, long, value_name = "DATA.csv")]
    pub input: PathBuf,
    /// Where to write the estimates (CSV; replaced only if the run succeeds)
    #[arg(short, long, value_name = "OUT.csv")]
    pub output: PathBuf,
    /// Settings overriding the digest's defaults: ts, x0, p0, q, r (TOML)
    #[arg(short, long, value_name = "CONFIG.toml")]
    pub config: Option<PathBuf>,
    /// Refuse any step that does not end cleanly (see `port-est filter --help`)
    #[arg(long)]
    pub strict: bool,
    /// How the estimator checks its data.
    #[command(flatten)]
    pub checks: CheckArgs,
    /// What an error does with the steps before it: `discard` (write nothing) or `keep-partial`
    /// (keep them in OUT.partial.csv; the error says where and why the run stopped)
    #[arg(long, value_name = "POLICY", value_enum, default_value = "discard")]
    pub on_error: OnErrorArg,
}

fn status_policy(strict: bool) -> crate::StatusPolicy {
    if strict { crate::StatusPolicy::Error } else { crate::StatusPolicy::Warn }
}

/// How the estimator checks its data (every subcommand).
#[derive(Debug, Args)]
pub struct CheckArgs {
    /// What a step whose data contradict the noise description does: `error` (the default) stops
    /// at its row; `flag` uses the data and marks the row inconsistent; `restart` does not trust
    /// them (a set-membership filter inflates its prediction to meet them, a Gaussian filter or a
    /// moving-horizon estimator drops the measurement) and marks the row; `off` checks nothing
    #[arg(long, value_name = "POLICY", value_parser = ["error", "flag", "restart", "off"])]
    pub on_inconsistent: Option<String>,
    /// The Gaussian filters' innovation gate: the probability that a measurement of a correct model
    /// passes it [default: 1 - 1e-12, about 7 sigma]
    #[arg(long, value_name = "P")]
    pub gate_probability: Option<f64>,
}

impl CheckArgs {
    /// The data checks asked for (`None`: the estimator's defaults).
    #[must_use]
    pub fn checks(&self) -> Option<estimators::DataChecks> {
        use estimators::InconsistencyPolicy as P;
        if self.on_inconsistent.is_none() && self.gate_probability.is_none() {
            return None;
        }
        let policy = match self.on_inconsistent.as_deref() {
            Some("flag") => P::FlagAndContinue,
            Some("restart") => P::Restart,
            Some("off") => P::Off,
            _ => P::Error,
        };
        let gate_probability = self.gate_probability.unwrap_or(estimators::DataChecks::DEFAULT_GATE_PROBABILITY);
        Some(estimators::DataChecks { policy, gate_probability })
    }
}

impl From<TruckArgs> for crate::truck::TruckOptions {
    fn from(a: TruckArgs) -> Self {
        Self {
            input: a.input,
            output: a.output,
            config: a.config,
            status: status_policy(a.strict),
            checks: a.checks.checks(),
            on_error: a.on_error.into(),
            limits: crate::Limits::default(),
        }
    }
}

const BDS_INS_FORMATS: &str = "\
Files:
  DATA.csv    header `k,u1,u2,u3,y1,y2,y3,y4,y5`, one row per epoch: u1, u2 = INS position east, north [m];
              u3 = INS heading (azimuth, clockwise from north) [rad]; y1, y2 = BDS position east, north [m];
              y3 = BDS dual-antenna heading [rad]; y4 = satellites used (>= 0); y5 = RTK status 1 single,
              2 differential, 3 fixed, 4 float, 0 = no fix (prediction only; y1..y4 ignored). With --gga,
              y5 is the NMEA GGA quality (0 no fix, 1, 2, 4 RTK fixed, 5 RTK float).
  OUT.csv     header `k,x,y,psi,dx,dy,dpsi,sd_dx,sd_dy,sd_dpsi,t,d`, one row per epoch labelled k+1: the
              corrected position and heading (INS minus the estimated error; the INS is never reset), the
              estimated errors and their standard deviations, the noise scale t_k and the distance d_k
              (empty without a fix); written atomically.
  CONFIG.toml optional: `ts` (s, default 1), `latitude_deg` (31), `flat` (false), `sigma0` (nominal BDS
              horizontal sigma, m, 0.2), `heading_sigma_deg` (0.2), `accel_white` (m/s^2/sqrt(Hz)),
              `gyro_white` (rad/s/sqrt(Hz)), `p0_sigma` (13 initial sigmas, paper state order).
  SYSTEM.toml optional fuzzy system whose inputs are named `N` (or `satellites`), `RTK` and `d` (or
              `distance`), in any order: each is matched by its name, an unknown or missing name is
              an error at its line (default: the 45-rule system of docs/bds-ins-fuzzy-kf.md with the
              d sets scaled by sigma0; an editable copy is crates/fuzzy-inference/systems/bds_ins.toml).

--on-error keep-partial keeps the steps before an error in OUT.partial.csv. Limits: see
crates/port-est/README.md (--max-file-size).

Example:
  port-est bds-ins --input examples/bds-ins/data.csv --output out.csv";

/// The arguments of `port-est bds-ins`.
#[derive(Debug, Args)]
#[command(after_long_help = BDS_INS_FORMATS)]
pub struct BdsInsArgs {
    /// The logged data: header `k,u1,u2,u3,y1,y2,y3,y4,y5` (INS x, y, heading; BDS x, y, heading, satellites, RTK)
    #[arg(short, long, value_name = "DATA.csv")]
    pub input: PathBuf,
    /// Where to write the estimates (CSV; replaced only if the run succeeds)
    #[arg(short, long, value_name = "OUT.csv")]
    pub output: PathBuf,
    /// Settings overriding the digest's defaults (TOML)
    #[arg(short, long, value_name = "CONFIG.toml")]
    pub config: Option<PathBuf>,
    /// A fuzzy system replacing the built-in one (TOML), its inputs named N, RTK and d (any order)
    #[arg(long, value_name = "SYSTEM.toml")]
    pub fis: Option<PathBuf>,
    /// `fuzzy`: R scaled by the fuzzy system every epoch; `none`: the plain Kalman filter
    #[arg(long, value_name = "SCALING", default_value = "fuzzy", value_parser = ["fuzzy", "none"])]
    pub scaling: String,
    /// Read y5 as an NMEA GGA quality indicator instead of the paper's RTK code
    #[arg(long)]
    pub gga: bool,
    /// Refuse any step that does not end cleanly (see `port-est filter --help`)
    #[arg(long)]
    pub strict: bool,
    /// How the estimator checks its data.
    #[command(flatten)]
    pub checks: CheckArgs,
    /// What an error does with the steps before it: `discard` (write nothing) or `keep-partial`
    /// (keep them in OUT.partial.csv; the error says where and why the run stopped)
    #[arg(long, value_name = "POLICY", value_enum, default_value = "discard")]
    pub on_error: OnErrorArg,
}

impl From<BdsInsArgs> for crate::bds_ins::BdsInsOptions {
    fn from(a: BdsInsArgs) -> Self {
        Self {
            input: a.input,
            output: a.output,
            config: a.config,
            fis: a.fis,
            fuzzy: a.scaling == "fuzzy",
            rtk_coding: if a.gga { crate::bds_ins::RtkCoding::Gga } else { crate::bds_ins::RtkCoding::Paper },
            status: status_policy(a.strict),
            checks: a.checks.checks(),
            on_error: a.on_error.into(),
            limits: crate::Limits::default(),
        }
    }
}

const FILE_FORMATS: &str = "\
Files:
  MODEL.toml  the discrete-time model x_{k+1} = a x_k + b u_k + w_k, y_{k+1} = c x_{k+1} + v_{k+1}:
              `a` (n×n), `b` (n×p), `c` (m×n), `q` (n×n), `r` (m×m), `p0` (n×n) as arrays of rows and
              `x0` (length n); optional `u_lower`, `u_upper` (length p), the input range (yang-li),
              and `x_lower`, `x_upper` (length n, inf where none), bounds the true state always
              respects, such as speed limits (the set-membership filters cut their published
              intervals by them: docs/carrier-smf.md §4.8, docs/nonlinear-smf.md (N1')).
              Set-membership filters read q, r, p0 as ellipsoid shapes, the Kalman filter as
              covariances. The moving-horizon estimators (rmhe, mhe) read them as weights (r
              diagonal) and need a table `[mhe]` with the noise boxes `w_lower`, `w_upper` (length
              n) and `v_lower`, `v_upper` (length m); optional `horizon`, `preset` (rmhe, rmhe-op,
              rmhe-of) or `blocks`, `lambda_v` or `alpha`, `solver` (coordinate-rotation,
              exact-saddle), `inner`, `max_sweeps`, `tolerance`, `arrival`, `theta`, `prior_mean`,
              `block_weighting`, `output_constraint` (see crates/port-est/README.md).
              Or the model as equations instead of a, b, c: a [model] table (states, inputs,
              outputs, ts, discretization), [parameters], [definitions], [f] or [dxdt], [h]
              (crates/equation-models/README.md), with x0, p0, q, r… and an optional [ukf] table
              (alpha, beta, kappa) as top-level keys before the first table. Estimators the model
              cannot serve are refused with the reason (`port-est estimators --model MODEL.toml`).
  BAG.mcap    a ROS 2 bag, read as the model file's `[log]` table says: `ts` (a step, s) or
              `driving` (a topic: one step per message), optional `stamps` (`log` or `header`),
              `reorder_window` (s), and a table `[log.fields]` mapping every input and output name
              (`u1…`, `y1…` for matrices) to `{ topic = '/name', field = 'a.b[0]' }`; an output with no
              message in a step is not measured. `port-est inspect BAG.mcap` lists the fields. An
              error's position is BAG:ROW:COLUMN of the rows the mapping makes.
  DATA.csv    header `k,u1,…,up,y1,…,ym` (or the model's input and output names, in its order);
              row k holds the input u_k and the measurement y_{k+1}
              (fkf: two more columns, the satellite count and the RTK code, 0 = no fix).
  OUT.csv     one row per step, labelled k+1: `k,xhat1,…,xhatn`, then by kind of estimate
              `sd1,…,sdn,trace_cov` (Gaussian: one standard deviation per state),
              `lo1,…,lon,hi1,…,hin,trace_shape` (guaranteed intervals), or nothing (point
              estimates of the moving-horizon estimators: no bounds), then the estimator's own
              numbers (`tau1,tau2,tau3,iterations`; `scale,distance`; `iterations`) and `status`: converged,
              predicted, not-converged, fallback, relaxed or real-time, with `+inconsistent` and
              `+not-guaranteed` where they apply. Steps that do not end cleanly are counted in a
              warning on stderr; --strict makes the first one an error. The file is written to a
              temporary file beside it and renamed on success (removed on Ctrl-C or SIGTERM; one
              left by a killed run is named by the next), and may not be the model or the input.
              --on-error keep-partial keeps the steps before an error in OUT.partial.csv.

Limits (each refused with a message naming it): --max-file-size (model file, 16 MiB),
--mhe-memory-limit (the [mhe] horizon and blocks, 256 MiB), --max-gap (steps bridged at one gap,
10000), [mhe] max_sweeps <= 10000, data lines <= 1 MiB.

Malformed files are reported at their file:line:column.

Examples:
  port-est filter --model examples/filter/model.toml --input examples/filter/data.csv --output out.csv
  port-est filter --model examples/models/vessel.toml --input examples/vessel/data.csv --output out.csv -e ukf";

/// The arguments of `port-est filter`.
#[derive(Debug, Args)]
#[command(after_long_help = FILE_FORMATS)]
pub struct FilterArgs {
    /// The model: a, b, c (or equations: `[model]`, `[f]` or `[dxdt]`, `[h]`), q, r, p0, x0 and optionally
    /// u_lower, u_upper, an `[mhe]` and a `[ukf]` table (TOML); or a built-in vehicle, `builtin:carrier`,
    /// `builtin:car`, `builtin:truck`, `builtin:vessel`, `builtin:bds-ins` (the compiled model with
    /// the noise of its file in examples/models/)
    #[arg(short, long, value_name = "MODEL.toml")]
    pub model: PathBuf,
    /// The logged data: header `k,u1,…,up,y1,…,ym` or the model's names, in any order (CSV); an
    /// empty output cell is a sensor that did not report; `-` reads standard input. Or a ROS 2
    /// bag (`.mcap`), read through the model file's `[log]` table
    #[arg(short, long, value_name = "DATA.csv")]
    pub input: PathBuf,
    /// Where to write the estimates (CSV; replaced only if the run succeeds); `-` writes standard
    /// output, row by row as they are computed; `.mcap` writes them as a bag (from a bag input)
    #[arg(short, long, value_name = "OUT.csv")]
    pub output: PathBuf,
    /// With a bag input and `--output OUT.mcap`: copy the input's topics into the output beside
    /// `/estimate` (schemas, channels and messages unchanged), so one file holds data and
    /// estimates; alone every topic (but an old `/estimate`), or the topics listed
    #[arg(long, value_name = "TOPIC,...", num_args = 0.., value_delimiter = ',')]
    pub copy_topics: Option<Vec<String>>,
    /// The estimator
    #[arg(short, long, value_name = "NAME", default_value = registry::names::SMF, value_parser = estimator_names())]
    pub estimator: String,
    /// How the set-membership filters solve their SDP (29) [default: two-multiplier]
    #[arg(short, long, value_name = "NAME", value_parser = solver_names())]
    pub solver: Option<String>,
    /// What a gap in `k` (rows missing from the log) does: `error` names the row; `bridge` runs
    /// prediction-only steps with the last input held (a guaranteed set grows honestly) and writes
    /// a row for each missing step
    #[arg(long, value_name = "POLICY", default_value = "error", value_parser = ["error", "bridge"])]
    pub gaps: String,
    /// Refuse a data column the model does not read (by default such columns are ignored, with a
    /// note on stderr; columns are matched by name, in any order)
    #[arg(long)]
    pub exact_columns: bool,
    /// Refuse any step that does not end cleanly (a solver that did not converge, a fallback, a
    /// relaxed problem, inconsistent data, a set no longer guaranteed) instead of writing it with
    /// its status and warning
    #[arg(long)]
    pub strict: bool,
    /// How the estimator checks its data.
    #[command(flatten)]
    pub checks: CheckArgs,
    /// What an error does with the steps before it: `discard` (write nothing) or `keep-partial`
    /// (keep them in OUT.partial.csv; the error says where and why the run stopped)
    #[arg(long, value_name = "POLICY", value_enum, default_value = "discard")]
    pub on_error: OnErrorArg,
    /// With `--gaps bridge`: the most missing steps bridged at one gap (a larger gap is an error
    /// at its row)
    #[arg(long, value_name = "N", default_value_t = crate::limits::DEFAULT_MAX_GAP)]
    pub max_gap: u64,
    /// The most memory a moving-horizon estimator (rmhe, mhe) may take for its `[mhe]` horizon and
    /// blocks: bytes, or with K, M, G
    #[arg(long, value_name = "SIZE", default_value = "256MiB", value_parser = size)]
    pub mhe_memory_limit: u64,
}

/// The arguments of `port-est estimators`.
#[derive(Debug, Args)]
pub struct EstimatorsArgs {
    /// A model file or `builtin:NAME`: list which estimators run on it and why the others do not
    #[arg(short, long, value_name = "MODEL.toml")]
    pub model: Option<PathBuf>,
}

/// The registry's estimators that run on the linear model of a model file, with their summaries
/// for `--help`.
fn estimator_names() -> PossibleValuesParser {
    PossibleValuesParser::new(registry::ESTIMATORS.iter().map(|e| PossibleValue::new(e.name).help(e.summary)))
}

/// The solvers this build has.
fn solver_names() -> PossibleValuesParser {
    PossibleValuesParser::new(
        registry::SmfSolver::names().into_iter().map(|s| PossibleValue::new(s).help(registry::SmfSolver::summary(s))),
    )
}

impl From<FilterArgs> for crate::FilterOptions {
    fn from(a: FilterArgs) -> Self {
        let gaps = if a.gaps == "bridge" { crate::filter::GapPolicy::Bridge } else { crate::filter::GapPolicy::Error };
        Self {
            model: a.model,
            input: a.input,
            output: a.output,
            estimator: a.estimator,
            solver: a.solver,
            gaps,
            exact_columns: a.exact_columns,
            status: status_policy(a.strict),
            checks: a.checks.checks(),
            on_error: a.on_error.into(),
            limits: crate::Limits {
                mhe_memory_bytes: a.mhe_memory_limit,
                max_gap: a.max_gap,
                ..crate::Limits::default()
            },
            copy_topics: match a.copy_topics {
                None => crate::CopyTopics::None,
                Some(t) if t.is_empty() => crate::CopyTopics::All,
                Some(t) => crate::CopyTopics::Only(t),
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn the_command_line_is_well_formed() {
        Cli::command().debug_assert();
    }

    #[test]
    fn filter_arguments_parse_with_defaults() {
        let cli =
            Cli::try_parse_from(["port-est", "filter", "-m", "m.toml", "--input", "d.csv", "-o", "o.csv"]).unwrap();
        let Command::Filter(a) = cli.command else { panic!("not filter") };
        assert_eq!((a.estimator.as_str(), a.solver.as_deref()), ("smf", None));
        // The library's constructor has the command line's defaults.
        assert_eq!(crate::FilterOptions::from(a), crate::FilterOptions::new("m.toml", "d.csv", "o.csv"));
        let e = Cli::try_parse_from(["port-est", "filter", "-m", "m", "-i", "d", "-o", "o", "-e", "nope"]).unwrap_err();
        assert_eq!(e.kind(), clap::error::ErrorKind::InvalidValue);
        let e = Cli::try_parse_from(["port-est", "filter", "-m", "m", "-i", "d"]).unwrap_err();
        assert_eq!(e.kind(), clap::error::ErrorKind::MissingRequiredArgument);
        // --copy-topics: absent, alone (every topic), or a list.
        let copy = |extra: &[&str]| {
            let base = ["port-est", "filter", "-m", "m", "-i", "d.mcap", "-o", "o.mcap"];
            let cli = Cli::try_parse_from(base.iter().chain(extra)).unwrap();
            let Command::Filter(a) = cli.command else { panic!("not filter") };
            crate::FilterOptions::from(a).copy_topics
        };
        assert_eq!(copy(&[]), crate::CopyTopics::None);
        assert_eq!(copy(&["--copy-topics"]), crate::CopyTopics::All);
        assert_eq!(copy(&["--copy-topics", "-e", "ekf"]), crate::CopyTopics::All);
        let two = crate::CopyTopics::Only(vec!["/imu".into(), "/gnss/fix".into()]);
        assert_eq!(copy(&["--copy-topics", "/imu,/gnss/fix"]), two);
        assert_eq!(copy(&["--copy-topics", "/imu", "/gnss/fix"]), two);
    }

    #[cfg(unix)]
    #[test]
    fn non_utf8_arguments_do_not_panic() {
        use std::ffi::OsString;
        use std::os::unix::ffi::OsStringExt;
        let bad = OsString::from_vec(b"d\xff.csv".to_vec());
        let args = [OsString::from("port-est"), "filter".into(), "-m".into(), "m".into(), "-i".into(), bad.clone()];
        let cli = Cli::try_parse_from(args.iter().cloned().chain(["-o".into(), "o".into()])).unwrap();
        let Command::Filter(a) = cli.command else { panic!("not filter") };
        assert_eq!(a.input.as_os_str(), bad);
        let e = Cli::try_parse_from(args.iter().cloned().chain(["-o".into(), "o".into(), "-e".into(), bad.clone()]));
        assert!(e.is_err());
    }
}
