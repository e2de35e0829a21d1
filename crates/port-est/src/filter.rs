//! `port-est filter`: run a registered estimator over logged data, one output row per step.
//!
//! `OUT.csv` has the header `k,xhat1,…,xhatn`, then columns named after what the numbers are
//! ([`EstimateColumns`]: `sd1…,trace_cov` for Gaussian estimates, `lo1…,hi1…,trace_shape` for
//! guaranteed sets, none for point estimates), the estimator's own numbers (its registry row's
//! `details`: `tau1,tau2,tau3,iterations`, `scale,distance`, `iterations`) and `status`; the row of step `k` is labelled `k + 1` (it
//! estimates `x_{k+1}`). Numbers are written in Rust's `{:e}` notation, exact to the last bit.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use estimators::registry::{self, EstimatorEntry, EstimatorSettings, SmfSolver};
use estimators::{AnyEstimator, DataChecks, EstimatorError};
use nalgebra::DVector;

use crate::blame::{self, LargestCell};
use crate::data::{DataReader, DataRow, RowSource};
use crate::error::{Error, echo};
use crate::limits::Limits;
use crate::model::{Model, read_model_with};
use crate::output::OutputFile;
use crate::run::{EstimateColumns, OnError, StatusPolicy, StatusTally, enforce, step_error};

/// What `port-est filter` is asked to do.
#[derive(Debug, Clone, PartialEq)]
pub struct FilterOptions {
    /// `MODEL.toml`.
    pub model: PathBuf,
    /// `DATA.csv`.
    pub input: PathBuf,
    /// `OUT.csv`.
    pub output: PathBuf,
    /// A name of [`registry::ESTIMATORS`].
    pub estimator: String,
    /// How a set-membership filter solves (29) (`None`: the two-multiplier method); only for the
    /// estimators whose settings have a solver.
    pub solver: Option<String>,
    /// What a gap in `k` does: an error naming the row (default), or prediction-only steps.
    pub gaps: GapPolicy,
    /// Refuse a data column the model does not read (`--exact-columns`); by default such columns
    /// are ignored and listed in [`FilterSummary::ignored_columns`].
    pub exact_columns: bool,
    /// What a step that does not end cleanly does: a warning (default) or an error (`--strict`).
    pub status: StatusPolicy,
    /// How the estimator checks its data (`None`: its defaults, an error at the first step whose
    /// data contradict the noise description).
    pub checks: Option<estimators::DataChecks>,
    /// What an error does with the steps before it (`--on-error`).
    pub on_error: OnError,
    /// The resource limits (`--max-file-size`, `--mhe-memory-limit`, `--max-gap`).
    pub limits: Limits,
    /// Which topics of the input bag are copied into a bag output beside the estimates
    /// (`--copy-topics`).
    pub copy_topics: CopyTopics,
}

impl FilterOptions {
    /// `port-est filter --model MODEL --input INPUT --output OUTPUT` with the command line's
    /// defaults: the improved set-membership filter (`smf`) with its exact solver, a gap in `k`
    /// an error, extra columns ignored, unclean steps a warning, the estimator's own data checks,
    /// nothing kept on error, the default limits, no topics copied. Change a field with struct
    /// update syntax: `FilterOptions { estimator: "czf".into(), ..FilterOptions::new(m, i, o) }`.
    #[must_use]
    pub fn new(model: impl Into<PathBuf>, input: impl Into<PathBuf>, output: impl Into<PathBuf>) -> Self {
        Self {
            model: model.into(),
            input: input.into(),
            output: output.into(),
            estimator: registry::names::SMF.to_owned(),
            solver: None,
            gaps: GapPolicy::Error,
            exact_columns: false,
            status: StatusPolicy::Warn,
            checks: None,
            on_error: OnError::Discard,
            limits: Limits::default(),
            copy_topics: CopyTopics::None,
        }
    }
}

/// Which topics of the input bag `port-est filter` copies into its bag output (`--output
/// est.mcap --copy-topics`), so that one file holds the data and the estimates.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum CopyTopics {
    /// None: the output holds the estimates only.
    #[default]
    None,
    /// Every topic of the input bag (but `/estimate`, the estimates' own).
    All,
    /// These topics.
    Only(Vec<String>),
}

/// The largest number of states for which `port-est filter` runs a set-membership filter with an
/// SDP solver (LMI (28) has order `3n + 1 + m`): beyond it a step takes seconds (n = 50: 8 s per
/// step with faer-ipm), so the exact two-multiplier solver is the only sensible choice.
pub const MAX_SDP_STATES: usize = 16;

/// What `port-est filter` does when `k` skips values (rows missing from the log).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum GapPolicy {
    /// Refuse the file at the row after the gap.
    #[default]
    Error,
    /// Bridge the missing steps by prediction-only steps with the last logged input held (no
    /// measurement: a guaranteed set grows to cover every state the model and the noise bound
    /// allow, and stays guaranteed if that was the input applied); one output row per missing
    /// step.
    Bridge,
}

/// What a run did.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FilterSummary {
    /// The estimator's registry name.
    pub estimator: &'static str,
    /// How the steps ended (rows written, not converged, fallbacks…).
    pub tally: StatusTally,
    /// The data's columns the model does not read, ignored: `name (column j)`.
    pub ignored_columns: Vec<String>,
}

/// The registry entry of `estimator` and the solver to use, checked against each other.
///
/// # Errors
/// [`Error::Usage`] for an unknown estimator or solver, or a solver given to an estimator
/// that has none.
pub fn select(estimator: &str, solver: Option<&str>) -> Result<(&'static EstimatorEntry, Option<SmfSolver>), Error> {
    let known = |names: &mut dyn Iterator<Item = &str>| names.collect::<Vec<_>>().join(", ");
    let Some(entry) = registry::entry(estimator) else {
        return Err(Error::Usage(format!(
            "unknown estimator {} (known: {})",
            echo(estimator),
            known(&mut registry::ESTIMATORS.iter().map(|e| e.name))
        )));
    };
    let Some(solver) = solver else {
        return Ok((entry, None));
    };
    if !entry.settings.uses_smf_solver() {
        return Err(Error::Usage(format!(
            "--solver applies to the estimators that solve the SDP (29) ({}), not {}",
            known(&mut registry::ESTIMATORS.iter().filter(|e| e.settings.uses_smf_solver()).map(|e| e.name)),
            entry.name
        )));
    }
    match SmfSolver::by_name(solver) {
        Ok(s) => Ok((entry, Some(s))),
        Err(_) => Err(Error::Usage(format!(
            "unknown solver {} (known: {})",
            echo(solver),
            known(&mut SmfSolver::names().into_iter())
        ))),
    }
}

/// Runs `options`: checks the options and the output, reads the model, streams the data
/// through the estimator into the output, and publishes the output only if every step
/// succeeded.
///
/// # Errors
/// Every [`Error`]: bad options, an output that would overwrite an input or cannot be written,
/// malformed files (at their `file:line:column`), a step the estimator rejects, and with
/// [`StatusPolicy::Error`] a step that does not end cleanly.
pub fn filter(options: &FilterOptions) -> Result<FilterSummary, Error> {
    let (entry, solver) = select(&options.estimator, options.solver.as_deref())?;
    if crate::bag::writes_bag(&options.output) {
        return filter_to_bag(options, entry, solver);
    }
    if options.copy_topics != CopyTopics::None {
        return Err(Error::Usage(
            "--copy-topics copies the input bag's topics into a bag output: give --output OUT.mcap".into(),
        ));
    }
    let stdin = options.input.as_os_str() == "-";
    let stdout = options.output.as_os_str() == "-";
    let inputs: [(&'static str, &Path); 2] = [("input", &options.input), ("model", &options.model)];
    // A file output is written beside its target and published only if the run succeeds; standard
    // output is a stream (rows go out as they are computed; an error ends it).
    let mut file = if stdout { None } else { Some(OutputFile::create(&options.output, &inputs)?) };
    let model = read_model_with(&options.model, &options.limits)?;
    let (p, m) = (model.inputs(), entry.measurement_len(model.outputs()));
    let names = model.column_names();
    let go = |out: &mut dyn Write, tally: &mut StatusTally| -> Result<Vec<String>, Error> {
        if !stdin && crate::bag::is_bag(&options.input) {
            let policy = (options.status, options.checks);
            let mut out = out;
            crate::bag::run_on_bag(&model, &options.input, |data| {
                run_filter_into(&model, data, entry, solver, policy, &mut out, &options.output, tally, None)
            })?;
            return Ok(Vec::new());
        }
        if stdin {
            let lock = std::io::stdin().lock();
            let mut data = DataReader::from_reader_named(Path::new("<stdin>"), lock, p, m, names)?;
            run_on(options, &model, &mut data, entry, solver, out, tally)
        } else {
            let mut data = DataReader::open_named(&options.input, p, m, names)?;
            run_on(options, &model, &mut data, entry, solver, out, tally)
        }
    };
    let mut tally = StatusTally::default();
    match file.take() {
        Some(mut out) => match go(&mut out, &mut tally) {
            Ok(ignored_columns) => {
                out.commit()?;
                Ok(FilterSummary { estimator: entry.name, tally, ignored_columns })
            }
            Err(e) => Err(out.fail(e, tally.steps, options.on_error, &inputs)),
        },
        None => {
            let mut out = std::io::BufWriter::new(std::io::stdout().lock());
            let ignored_columns = go(&mut out, &mut tally)?;
            out.flush().map_err(|e| Error::io(Path::new("<stdout>"), e))?;
            Ok(FilterSummary { estimator: entry.name, tally, ignored_columns })
        }
    }
}

/// `port-est filter --input run.mcap --output est.mcap`: the run of [`crate::filter()`], its
/// estimates written as a bag ([`BagOutput`](crate::bag::BagOutput)) with the input's topics copied beside them as
/// `--copy-topics` asks, published only if every step succeeded.
///
/// # Errors
/// As [`crate::filter()`]; an input that is not a bag, an output that is the input or the
/// model, `--on-error keep-partial` (a bag output keeps nothing), a topic to copy that the input
/// does not have.
fn filter_to_bag(
    options: &crate::FilterOptions,
    entry: &'static estimators::registry::EstimatorEntry,
    solver: Option<estimators::registry::SmfSolver>,
) -> Result<crate::FilterSummary, Error> {
    let refuse = |message: String| Error::Output { path: options.output.clone(), message };
    if !crate::bag::is_bag(&options.input) {
        return Err(refuse("estimates are written as a bag (.mcap) only from a bag input (their time stamps)".into()));
    }
    if options.on_error == crate::OnError::KeepPartial {
        return Err(refuse(
            "--on-error keep-partial keeps CSV rows; a bag output is written whole or not at all".into(),
        ));
    }
    for (role, input) in [("input", &options.input), ("model", &options.model)] {
        if crate::output::same_file(&options.output, input) {
            return Err(refuse(format!("is the {role}")));
        }
    }
    let model = crate::model::read_model_with(&options.model, &options.limits)?;
    let spec = crate::bag::log_spec(&model, &options.input)?;
    let bag = crate::bag::open(&options.input)?;
    let mut out = crate::bag::BagOutput::create(&options.output, &model, entry.kind, &bag, &options.copy_topics)?;
    let mut tally = crate::StatusTally::default();
    let policy = (options.status, options.checks);
    let mut rows = crate::bag::bag_rows(&bag, spec, &options.input)?;
    let mut csv = std::io::sink();
    run_filter_into(&model, &mut rows, entry, solver, policy, &mut csv, &options.output, &mut tally, Some(&mut out))?;
    out.finish()?;
    Ok(crate::FilterSummary { estimator: entry.name, tally, ignored_columns: Vec::new() })
}

/// The filter over one opened data stream: the column and gap options applied, then the run;
/// the data's ignored columns.
fn run_on<R: Read>(
    options: &FilterOptions,
    model: &Model,
    data: &mut DataReader<R>,
    entry: &'static EstimatorEntry,
    solver: Option<SmfSolver>,
    mut out: &mut dyn Write,
    tally: &mut StatusTally,
) -> Result<Vec<String>, Error> {
    if options.exact_columns {
        data.require_exact_columns()?;
    }
    let ignored = data.ignored_columns().into_iter().map(|(j, name)| format!("{name} (column {j})")).collect();
    data.set_allow_gaps(options.gaps == GapPolicy::Bridge);
    data.set_max_gap(options.limits.max_gap);
    data.set_allow_empty_outputs(true);
    let policy = (options.status, options.checks);
    run_filter_into(model, data, entry, solver, policy, &mut out, &options.output, tally, None)?;
    Ok(ignored)
}

/// Why `entry` cannot run on `model` (`None` when it can): a capability the model lacks, or
/// settings the model file does not give ([`SettingsKind::needs`](registry::SettingsKind::needs)).
#[must_use]
pub fn why_not(model: &Model, entry: &EstimatorEntry) -> Option<String> {
    if let Some(why) = model.lacks(entry.needs) {
        return Some(why);
    }
    read_settings(model, entry, None).err().and_then(|_| missing(entry))
}

/// What `entry`'s settings need that the model file must give, in its terms (`None`: nothing).
fn missing(entry: &EstimatorEntry) -> Option<String> {
    let need = entry.settings.needs()?;
    Some(format!("needs {need} in the model file (or in its `[estimator.{}]` table)", entry.name))
}

/// The settings of `entry`: the model file's (its `[estimator.NAME]` table over its `[mhe]`,
/// `[ukf]` and bounds) with the command line's `--solver` over them, read by the registry's one
/// settings reader; in the model file's terms when something is missing.
fn settings(
    model: &Model,
    entry: &EstimatorEntry,
    solver: Option<&SmfSolver>,
) -> Result<Option<EstimatorSettings>, Error> {
    // The file's tables were read when the file was: what can fail here is what it lacks.
    read_settings(model, entry, solver).map_err(|e| match missing(entry) {
        Some(why) => {
            Error::File { path: model.path().to_owned(), message: format!("--estimator {} {why}", entry.name) }
        }
        None => e,
    })
}

/// The settings the model file gives the estimator `name` (its `[estimator.NAME]` table over its
/// `[mhe]`, `[ukf]` and bounds), as `port-est filter --estimator NAME` runs it; `None` for an
/// estimator without settings.
///
/// # Errors
/// An unknown estimator, or settings the file lacks (in the file's terms).
pub fn estimator_settings(model: &Model, name: &str) -> Result<Option<EstimatorSettings>, Error> {
    let entry = registry::entry(name)
        .ok_or_else(|| Error::Usage(format!("unknown estimator {name:?} (`port-est estimators` lists them)")))?;
    settings(model, entry, None)
}

/// The settings of `entry` as the registry's reader gives them.
fn read_settings(
    model: &Model,
    entry: &EstimatorEntry,
    solver: Option<&SmfSolver>,
) -> Result<Option<EstimatorSettings>, Error> {
    let overrides: Vec<(&'static str, String)> = solver.map(|s| ("solver", s.name().to_owned())).into_iter().collect();
    let table = model.settings_table(entry.name);
    let name = format!("estimator {}", entry.name);
    registry::read_settings(entry.settings, &name, &model.keyword_context(), &mut table.reader(&overrides))
}

/// Builds the estimator `entry` for `model` (the errors in the model file's terms).
fn build(model: &Model, entry: &'static EstimatorEntry, solver: Option<SmfSolver>) -> Result<AnyEstimator, Error> {
    if let Some(why) = model.lacks(entry.needs) {
        return Err(Error::Usage(format!(
            "--estimator {} {why} (`port-est estimators --model {}` lists what runs on it)",
            entry.name,
            model.path().display()
        )));
    }
    let settings = settings(model, entry, solver.as_ref())?;
    let sdp = settings.as_ref().and_then(|s| s.smf_solver());
    if let Some(SmfSolver::Sdp { backend, .. }) = sdp
        && model.states() > MAX_SDP_STATES
    {
        let (n, m) = (model.states(), model.outputs());
        return Err(Error::Usage(format!(
            "--solver {backend} solves LMI (28) at every step: for n = {n} states it has order {} and {} unknowns, \
             seconds to minutes per step; the SDP solvers are offered up to n = {MAX_SDP_STATES}. Use --solver {} \
             (exact, the same update at a few microseconds per step)",
            3 * n + 1 + m,
            n * (n + 1) / 2 + n * m + n + 3,
            SmfSolver::TWO_MULTIPLIER
        )));
    }
    entry.build(model.setup(entry.kind), settings).map_err(|e| match e {
        EstimatorError::Lmi(_)
        | EstimatorError::UnknownEstimator { .. }
        | EstimatorError::MissingSetting { .. }
        | EstimatorError::WrongSettings { .. } => Error::Estimator(e),
        e => model.estimator_error_for(entry.name, e),
    })
}

/// Runs the estimator `entry` (with `solver`) over every row of `data`, writing the output CSV
/// to `out` row by row (`out_path` names it in errors).
///
/// # Errors
/// As [`filter`], except for the checks of the output path.
pub fn run_filter<R: Read, W: Write>(
    model: &Model,
    data: &mut DataReader<R>,
    entry: &'static EstimatorEntry,
    solver: Option<SmfSolver>,
    status: StatusPolicy,
    checks: Option<DataChecks>,
    out: &mut W,
    out_path: &Path,
) -> Result<FilterSummary, Error> {
    let mut tally = StatusTally::default();
    // An empty output cell: that output was not measured at that row (a partial step).
    data.set_allow_empty_outputs(true);
    run_filter_into(model, data, entry, solver, (status, checks), out, out_path, &mut tally, None)?;
    let ignored_columns = data.ignored_columns().into_iter().map(|(j, name)| format!("{name} (column {j})")).collect();
    Ok(FilterSummary { estimator: entry.name, tally, ignored_columns })
}

/// [`run_filter`] over any [`RowSource`], counting the steps written in `tally` (also when it
/// fails). A CSV source must allow empty output cells (a partial step).
pub(crate) fn run_filter_into<W: Write>(
    model: &Model,
    data: &mut dyn RowSource,
    entry: &'static EstimatorEntry,
    solver: Option<SmfSolver>,
    (status, checks): (StatusPolicy, Option<DataChecks>),
    out: &mut W,
    out_path: &Path,
    tally: &mut StatusTally,
    mut bag_out: Option<&mut crate::bag::BagOutput<'_>>,
) -> Result<(), Error> {
    let mut est = build(model, entry, solver)?;
    if let Some(checks) = checks {
        est.set_data_checks(checks).map_err(|e| Error::Usage(format!("--on-inconsistent, --gate-probability: {e}")))?;
    }
    let wio = |e| Error::io(out_path, e);
    let columns = EstimateColumns::of(est.estimate());
    writeln!(out, "k{}", columns.header()).map_err(wio)?;

    let sm = model.any();
    let mut row = DataRow::zeros(model.inputs(), entry.measurement_len(model.outputs()));
    let mut last: Option<(u64, DVector<f64>)> = None;
    let mut largest = LargestCell::default();
    while data.read_row(&mut row)? {
        // A gap (only with `--gaps bridge`): prediction-only steps with the last input held.
        if let Some((last_k, last_u)) = &last {
            for missing in last_k + 1..row.k {
                let e = est.predict(sm, last_u).map_err(|source| step_error(source, data, missing))?;
                enforce(status, e.status(), || data.locate(Some(0)), missing)?;
                write!(out, "{}", missing + 1).map_err(wio)?;
                columns.write(out, e).map_err(wio)?;
                writeln!(out).map_err(wio)?;
                tally.record(e.status());
            }
        }
        let Some(label) = row.k.checked_add(1) else {
            let message = format!("k = {} is too large (the output row is labelled k + 1)", row.k);
            return Err(Error::at(data.locate(Some(0)), message));
        };
        let complete = row.complete();
        let stepped =
            if complete { est.step(sm, &row.u, &row.y) } else { est.step_partial(sm, &row.u, &row.y, &row.measured) };
        let e = match stepped {
            Ok(e) => e,
            Err(EstimatorError::NumericalFailure(what)) => {
                let last_u = last.as_ref().map(|(_, u)| u);
                return Err(blame::numerical_failure(what, &mut est, model, sm, &row, last_u, &largest, data));
            }
            Err(EstimatorError::Adaptive { index: Some(i), source }) => {
                // The receiver status columns follow the model's inputs and outputs.
                let at = data.locate(Some(1 + model.inputs() + i));
                return Err(Error::At { at, message: format!("step k = {}: {source}", row.k) });
            }
            Err(source) => return Err(step_error(source, data, row.k)),
        };
        enforce(status, e.status(), || data.locate(Some(0)), row.k)?;
        write!(out, "{label}").map_err(wio)?;
        columns.write(out, e).map_err(wio)?;
        // A partial measurement: the status says which outputs the step used.
        let measured = if !complete && row.measured.iter().any(|&b| b) {
            let names = data.columns();
            let used: Vec<&str> = row
                .measured
                .iter()
                .enumerate()
                .filter(|&(_, &b)| b)
                .map(|(i, _)| names.get(1 + model.inputs() + i).map_or("?", String::as_str))
                .collect();
            let suffix = format!("+measured:{}", used.join(";"));
            write!(out, "{suffix}").map_err(wio)?;
            Some(suffix)
        } else {
            None
        };
        writeln!(out).map_err(wio)?;
        if let Some(bag) = bag_out.as_deref_mut() {
            let Some(t) = data.estimate_time_ns() else {
                return Err(Error::Usage("estimates are written as a bag only from a bag input".into()));
            };
            bag.write(row.k, t, e, measured.as_deref())?;
        }
        tally.record(e.status());
        largest.observe(&row, model.outputs(), data);
        match &mut last {
            Some((k, u)) => {
                *k = row.k;
                u.copy_from(&row.u);
            }
            None => last = Some((row.k, row.u.clone())),
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::parse_model;

    const MODEL: &str = "a = [[1.0, 0.01], [0.0, 0.99]]\nb = [[0.0], [0.01]]\nc = [[1.0, 0.0]]\nq = [[1e-4, 0.0], [0.0, 1e-4]]\nr = [[1e-2]]\np0 = [[1.0, 0.0], [0.0, 1.0]]\nx0 = [0.0, 0.0]\n";

    fn run(model: &str, data: &str, estimator: &str, solver: Option<&str>) -> Result<String, Error> {
        run_with(model, data, estimator, solver, StatusPolicy::Warn).map(|(text, _)| text)
    }

    fn run_with(
        model: &str,
        data: &str,
        estimator: &str,
        solver: Option<&str>,
        status: StatusPolicy,
    ) -> Result<(String, FilterSummary), Error> {
        let model = parse_model(Path::new("m.toml"), model)?;
        let (entry, solver) = select(estimator, solver)?;
        let m = entry.measurement_len(model.outputs());
        let mut data = DataReader::from_text(Path::new("d.csv"), data, model.inputs(), m)?;
        let mut out = Vec::new();
        let s = run_filter(&model, &mut data, entry, solver, status, None, &mut out, Path::new("o.csv"))?;
        Ok((String::from_utf8(out).unwrap(), s))
    }

    fn ramp(rows: u64) -> String {
        let mut s = String::from("k,u1,y1\n");
        for k in 0..rows {
            s.push_str(&format!("{k},1.0,{}\n", 0.01 * k as f64));
        }
        s
    }

    #[test]
    fn every_estimator_runs_and_the_set_contains_what_the_centre_implies() {
        for (est, solver) in [("smf", None), ("smf", Some("faer-ipm")), ("kf", None), ("yang-li-with-input", None)] {
            let csv = run(MODEL, &ramp(30), est, solver).unwrap();
            let lines: Vec<&str> = csv.lines().collect();
            assert_eq!(lines.len(), 31, "{est}");
            if est == "kf" {
                assert_eq!(lines[0], "k,xhat1,xhat2,sd1,sd2,trace_cov,status");
                assert!(lines[30].ends_with(",converged"), "{}", lines[30]);
                continue;
            }
            assert_eq!(lines[0], "k,xhat1,xhat2,lo1,lo2,hi1,hi2,trace_shape,tau1,tau2,tau3,iterations,status");
            assert!(lines[1].starts_with("1,"));
            let last: Vec<&str> = lines[30].split(',').collect();
            assert_eq!(last[12], "converged", "{est}");
            let last: Vec<f64> = last[..12].iter().map(|v| v.parse().unwrap()).collect();
            assert!(last[3] <= last[1] && last[1] <= last[5], "{est}: lo ≤ xhat ≤ hi");
        }
    }

    #[test]
    fn option_and_model_errors_say_what_to_change() {
        let e = run(MODEL, &ramp(3), "yang-li", None).unwrap_err().to_string();
        assert!(
            e.starts_with("m.toml: --estimator yang-li needs the input range u_lower, u_upper in the model"),
            "{e}"
        );
        let e = run(MODEL, &ramp(3), "nope", None).unwrap_err().to_string();
        assert!(e.starts_with("unknown estimator \"nope\" (known: smf, kf"), "{e}");
        let e = run(MODEL, &ramp(3), "kf", Some("faer-ipm")).unwrap_err().to_string();
        assert!(e.starts_with("--solver applies to the estimators that solve the SDP (29) (smf, yang-li"), "{e}");
        let e = run(MODEL, &ramp(3), "smf", Some("mosek")).unwrap_err().to_string();
        assert!(e.starts_with("unknown solver \"mosek\" (known: two-multiplier, faer-ipm"), "{e}");
        let bad = MODEL.replace("q = [[1e-4, 0.0], [0.0, 1e-4]]", "q = [[-1.0, 0.0], [0.0, 1e-4]]");
        let e = run(&bad, &ramp(3), "smf", None).unwrap_err().to_string();
        assert!(e.starts_with("m.toml:4:5: `q`: "), "{e}");
    }

    #[test]
    fn step_errors_name_the_row() {
        let e = run(MODEL, "k,u1,y1\n18446744073709551615,1,0\n", "kf", None).unwrap_err().to_string();
        assert!(e.starts_with("d.csv:2:1: k = 18446744073709551615 is too large"), "{e}");
        let model = format!("{MODEL}u_lower = [-1.0]\nu_upper = [1.0]\n");
        let e = run(&model, "k,u1,y1\n0,0.5,0\n1, 2.5,0\n", "yang-li", None).unwrap_err().to_string();
        assert!(e.starts_with("d.csv:3:4: step k = 1: input u[0] = 2.5 is outside"), "{e}");
    }

    #[test]
    fn data_that_contradict_the_bounds_stop_the_set_membership_filter_at_their_row() {
        let mut data = ramp(10);
        data = data.replace("\n5,1.0,0.05\n", "\n5,1.0,1000\n");
        let e = run(MODEL, &data, "smf", None).unwrap_err().to_string();
        assert!(e.starts_with("d.csv:7:1: step k = 5: data inconsistent with the noise bounds at step 6"), "{e}");
        // The Kalman filter's innovation gate finds the same row an outlier; without the check it
        // runs through.
        let e = run(MODEL, &data, "kf", None).unwrap_err().to_string();
        assert!(e.starts_with("d.csv:7:"), "{e}");
        assert!(e.contains("step k = 5: measurement at step 6 is an outlier"), "{e}");
        assert!(e.contains("the largest innovation is y[0]: residual 9.99"), "{e}");
        let model = parse_model(Path::new("m.toml"), MODEL).unwrap();
        let mut rows = DataReader::from_text(Path::new("d.csv"), &data, 1, 1).unwrap();
        let (entry, _) = select("kf", None).unwrap();
        let off = Some(DataChecks::OFF);
        let mut out = Vec::new();
        run_filter(&model, &mut rows, entry, None, StatusPolicy::Warn, off, &mut out, Path::new("o.csv")).unwrap();
        // Flagged: the row is used, written and marked (and the filter, pulled by the outlier, finds
        // the next rows inconsistent too); restarted: the row's measurement is dropped, the
        // prediction written and marked, and the filter goes on.
        for (policy, last_row) in [
            (estimators::InconsistencyPolicy::FlagAndContinue, "converged+inconsistent"),
            (estimators::InconsistencyPolicy::Restart, "predicted+inconsistent"),
        ] {
            let mut rows = DataReader::from_text(Path::new("d.csv"), &data, 1, 1).unwrap();
            let mut out = Vec::new();
            let checks = Some(DataChecks::with_policy(policy));
            let s =
                run_filter(&model, &mut rows, entry, None, StatusPolicy::Warn, checks, &mut out, Path::new("o.csv"))
                    .unwrap();
            let text = String::from_utf8(out).unwrap();
            assert!(text.lines().nth(6).unwrap().ends_with(last_row), "{policy:?}: {text}");
            assert!(s.tally.inconsistent >= 1, "{policy:?}");
            if policy == estimators::InconsistencyPolicy::Restart {
                assert_eq!(s.tally.inconsistent, 1, "only the outlier is dropped");
            }
        }
    }

    #[test]
    fn a_model_that_overflows_is_named_as_the_cause() {
        let model = MODEL.replace("a = [[1.0, 0.01], [0.0, 0.99]]", "a = [[1e100, 0.0], [0.0, 1e100]]");
        let e = run(&model, &ramp(10), "kf", None).unwrap_err().to_string();
        assert!(e.contains("numerical failure") && e.contains("the cause is the model in m.toml"), "{e}");
    }

    #[test]
    fn gaps_are_refused_or_bridged_as_chosen() {
        let gap = "k,u1,y1\n0,1.0,0.0\n1,1.0,0.01\n4,1.0,0.04\n5,1.0,0.05\n";
        let e = run(MODEL, gap, "smf", None).unwrap_err().to_string();
        assert!(e.starts_with("d.csv:4:1: k jumps from 1 to 4"), "{e}");
        // Bridged: rows k + 1 = 1..=6, the missing steps predicted (the set grows while blind).
        let model = parse_model(Path::new("m.toml"), MODEL).unwrap();
        let full = "k,u1,y1\n0,1.0,0.0\n1,1.0,0.01\n2,1.0,0.02\n3,1.0,0.03\n4,1.0,0.04\n5,1.0,0.05\n";
        for est in ["smf", "kf"] {
            let with_all = run(MODEL, full, est, None).unwrap();
            let all: Vec<Vec<f64>> = with_all
                .lines()
                .skip(1)
                .map(|l| l.split(',').map(|v| v.parse().unwrap_or(f64::NAN)).collect())
                .collect();
            let mut data = DataReader::from_text(Path::new("d.csv"), gap, 1, 1).unwrap();
            data.set_allow_gaps(true);
            let (entry, solver) = select(est, None).unwrap();
            let mut out = Vec::new();
            let s =
                run_filter(&model, &mut data, entry, solver, StatusPolicy::Warn, None, &mut out, Path::new("o.csv"))
                    .unwrap();
            assert_eq!((s.tally.steps, s.tally.predicted), (6, 2), "{est}");
            let text = String::from_utf8(out).unwrap();
            let rows: Vec<Vec<f64>> =
                text.lines().skip(1).map(|l| l.split(',').map(|v| v.parse().unwrap_or(f64::NAN)).collect()).collect();
            let labels: Vec<f64> = rows.iter().map(|r| r[0]).collect();
            assert_eq!(labels, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0], "{est}");
            // Without their measurements the bridged steps 3 and 4 publish larger sets (trace:
            // column 7 for the set, 5 for the covariance) than the same steps with them.
            let t = if est == "kf" { 5 } else { 7 };
            assert!(rows[2][t] > all[2][t] && rows[3][t] > all[3][t], "{est}: {text}");
            assert!(text.lines().nth(3).unwrap().ends_with(",predicted"), "{text}");
        }
    }

    #[test]
    fn sdp_solvers_are_refused_for_large_models() {
        let n = MAX_SDP_STATES + 1;
        let mat = |r: usize, c: usize, diag: f64| {
            let rows: Vec<String> = (0..r)
                .map(|i| {
                    let cells: Vec<String> =
                        (0..c).map(|j| if i == j { format!("{diag:?}") } else { "0.0".into() }).collect();
                    format!("[{}]", cells.join(", "))
                })
                .collect();
            format!("[{}]", rows.join(", "))
        };
        let model = format!(
            "a = {}\nb = {}\nc = {}\nq = {}\nr = {}\np0 = {}\nx0 = [{}]\n",
            mat(n, n, 0.9),
            mat(n, 1, 1.0),
            mat(1, n, 1.0),
            mat(n, n, 0.01),
            mat(1, 1, 0.1),
            mat(n, n, 1.0),
            vec!["0.0"; n].join(", ")
        );
        let e = run(&model, &ramp(3), "smf", Some("faer-ipm")).unwrap_err().to_string();
        assert!(e.starts_with("--solver faer-ipm solves LMI (28) at every step: for n = 17 states"), "{e}");
        // The two-multiplier solver is not refused (these synthetic data may contradict the bounds,
        // which is reported at its row, not as a size limit).
        let other = run(&model, &ramp(3), "smf", None);
        assert!(!matches!(other, Err(Error::Usage(_))), "{other:?}");
    }
}
