//! `port-est`: state estimation over logged data of port vehicles, from the command line.
//!
//! ```text
//! port-est filter --model MODEL.toml --input DATA.csv --output OUT.csv [--estimator NAME] [--solver NAME]
//! port-est estimators [--model MODEL.toml]
//! port-est truck --input DATA.csv --output OUT.csv [--config CONFIG.toml]
//! port-est bds-ins --input DATA.csv --output OUT.csv [--config CONFIG.toml] [--fis SYSTEM.toml] [--scaling none] [--gga]
//! ```
//!
//! `filter` runs any estimator of [`estimators::registry`] (the set-membership filter `smf` by
//! default, the Kalman filter `kf`, the Yang–Li reconstructions, the EKF, UKF and MHEs) over a
//! model file ([`model`]: matrices, or equations compiled by `equation-models`)
//! and a CSV log ([`data`]) and writes one estimate per step ([`filter()`]) to an output that is
//! published only when every step succeeded ([`output`]). Malformed files are reported at their
//! `file:line:column` ([`Error`]). The binary is a thin layer over [`execute`], so that tests
//! drive the same code.
//!
//! Every file read whole and every setting that sizes memory or time is bounded ([`limits`]);
//! `--on-error keep-partial` keeps the steps before an error in `OUT.partial.csv`; temporary
//! files are removed on SIGINT/SIGTERM, and those of a killed run are named by the next.

pub mod bag;
pub mod bds_ins;
mod blame;
pub mod builtin;
pub mod cli;
pub mod data;
pub mod error;
pub mod filter;
pub mod keyword_table;
pub mod limits;
mod log_table;
pub mod mhe_table;
pub mod model;
pub mod output;
mod plausibility;
pub mod run;
mod settings;
pub mod truck;

use std::io::{self, Write};

pub use cli::{Cli, Command, FilterArgs};
pub use error::{Error, Location};
pub use filter::{CopyTopics, FilterOptions, FilterSummary, GapPolicy, filter};
pub use limits::Limits;
pub use model::{Model, parse_model, parse_model_with, read_model, read_model_with};
pub use run::{OnError, StatusPolicy, StatusTally};

use estimators::registry;

/// Runs a parsed command line: `filter`, `truck` and `bds-ins` report what they wrote on
/// `stderr`, with one warning per kind of step that did not end cleanly (not converged, fallback,
/// relaxed, inconsistent data, no longer guaranteed; `--strict` makes them errors); `estimators`
/// lists the registry on `stdout` (a closed pipe is not an error).
///
/// # Errors
/// The command's [`Error`].
pub fn execute(cli: Cli, stdout: &mut dyn Write, stderr: &mut dyn Write) -> Result<(), Error> {
    // A closed stderr is no reason to fail a run whose output is written.
    let report = |stderr: &mut dyn Write, what: String, tally: &StatusTally| {
        let _ = writeln!(stderr, "{what}");
        for w in tally.warnings() {
            let _ = writeln!(stderr, "{w}");
        }
    };
    let file_bytes = cli.max_file_size;
    match cli.command {
        Command::Filter(args) => {
            let mut options = FilterOptions::from(args);
            options.limits.file_bytes = file_bytes;
            warn_stale(&options.output, stderr);
            let s = filter(&options)?;
            if !s.ignored_columns.is_empty() {
                let _ = writeln!(
                    stderr,
                    "note: ignored the data columns the model does not read: {} (--exact-columns refuses them)",
                    s.ignored_columns.join(", ")
                );
            }
            let target = if options.output.as_os_str() == "-" {
                "standard output".to_owned()
            } else {
                options.output.display().to_string()
            };
            let what = format!("{} steps of {} written to {target}", s.tally.steps, s.estimator);
            report(stderr, what, &s.tally);
            remove_stale_partial(&options.output, options.on_error, stderr);
            Ok(())
        }
        Command::Truck(args) => {
            let mut options = truck::TruckOptions::from(args);
            options.limits.file_bytes = file_bytes;
            warn_stale(&options.output, stderr);
            let tally = truck::truck(&options)?;
            let what = format!("{} steps of the EKF written to {}", tally.steps, options.output.display());
            report(stderr, what, &tally);
            remove_stale_partial(&options.output, options.on_error, stderr);
            Ok(())
        }
        Command::BdsIns(args) => {
            let mut options = bds_ins::BdsInsOptions::from(args);
            options.limits.file_bytes = file_bytes;
            warn_stale(&options.output, stderr);
            let s = bds_ins::bds_ins(&options)?;
            let filter = if options.fuzzy { "the fuzzy-adaptive Kalman filter" } else { "the Kalman filter" };
            let what = format!(
                "{} epochs ({} without a fix) of {filter} written to {}",
                s.epochs,
                s.outages,
                options.output.display()
            );
            report(stderr, what, &s.tally);
            remove_stale_partial(&options.output, options.on_error, stderr);
            Ok(())
        }
        Command::Inspect(args) => bag::inspect(&args.bag, stdout),
        Command::Estimators(args) => {
            let written = match args.model {
                None => write_estimators(stdout),
                Some(path) => {
                    let limits = Limits { file_bytes, ..Limits::default() };
                    let model = read_model_with(&path, &limits)?;
                    write_estimators_for(&model, stdout)
                }
            };
            match written {
                Err(e) if e.kind() != io::ErrorKind::BrokenPipe => Err(Error::io("<stdout>".as_ref(), e)),
                _ => Ok(()),
            }
        }
    }
}

/// Names the temporary files beside `output` that a killed run left (its writer no longer
/// runs), with how to remove them; they are not removed, as they may hold the only copy of a long
/// run's rows.
fn warn_stale(output: &std::path::Path, stderr: &mut dyn Write) {
    let Ok(stale) = atomic_output::stale_temporaries(output) else { return };
    for t in stale {
        let by = t.pid.map_or_else(|| "an earlier run".to_owned(), |pid| format!("process {pid}, no longer running"));
        let _ = writeln!(
            stderr,
            "warning: {} is a temporary file of {} left by an interrupted run ({by}); remove it: rm {}",
            t.path.display(),
            output.display(),
            t.path.display()
        );
    }
}

/// After a successful run with `--on-error keep-partial`: the partial file of an earlier failed
/// run is superseded by the complete output, so it is removed (and said so).
fn remove_stale_partial(output: &std::path::Path, on_error: OnError, stderr: &mut dyn Write) {
    if on_error != OnError::KeepPartial {
        return;
    }
    let partial = output::partial_path(output);
    if partial.is_file() && std::fs::remove_file(&partial).is_ok() {
        let _ = writeln!(stderr, "removed {}, the partial output of an earlier run", partial.display());
    }
}

/// Writes which estimators of the registry run on `model` and why the others do not.
///
/// # Errors
/// When `w` fails.
pub fn write_estimators_for(model: &Model, w: &mut dyn Write) -> io::Result<()> {
    let (n, p, m) = (model.states(), model.inputs(), model.outputs());
    let kind = match &model.dynamics {
        model::Dynamics::Matrices(_) => "linear (matrices)".to_owned(),
        model::Dynamics::Equations(_) => {
            format!("equations, {}", models::Capability::of(model.any()).label())
        }
        model::Dynamics::Builtin { vehicle, .. } => {
            format!("{}, {}", vehicle.description, models::Capability::of(model.any()).label())
        }
    };
    writeln!(w, "{}: {kind}; n = {n} states, p = {p} inputs, m = {m} outputs", model.path().display())?;
    let width = registry::ESTIMATORS.iter().map(|e| e.name.len()).max().unwrap_or(0);
    let (runs, not): (Vec<_>, Vec<_>) =
        registry::ESTIMATORS.iter().map(|e| (e, filter::why_not(model, e))).partition(|(_, why)| why.is_none());
    writeln!(w, "Runs (--estimator NAME):")?;
    for (e, _) in &runs {
        let extra = if e.extra_measurements > 0 {
            format!(" [{} extra measurement columns after the outputs]", e.extra_measurements)
        } else {
            String::new()
        };
        writeln!(w, "  {:width$}  {}{extra}", e.name, e.summary)?;
    }
    if !not.is_empty() {
        writeln!(w, "Does not run:")?;
        for (e, why) in &not {
            writeln!(w, "  {:width$}  {}", e.name, why.as_deref().unwrap_or_default())?;
        }
    }
    Ok(())
}

/// Writes the registry: every estimator with its kind, the model it needs, its settings and the
/// columns of its own numbers with their meanings, then the solvers.
///
/// # Errors
/// When `w` fails.
pub fn write_estimators(w: &mut dyn Write) -> io::Result<()> {
    let width = registry::ESTIMATORS.iter().map(|e| e.name.len()).max().unwrap_or(0);
    writeln!(w, "Estimators (--estimator NAME, default smf):")?;
    for e in registry::ESTIMATORS {
        let mut notes = vec![e.kind.label().to_owned(), format!("needs a {} model", e.needs.label())];
        if e.settings.uses_smf_solver() {
            notes.push("uses --solver".into());
        }
        if let Some(need) = e.settings.needs() {
            notes.push(format!("needs {need}"));
        }
        if e.extra_measurements > 0 {
            notes.push(format!("{} extra measurement columns", e.extra_measurements));
        }
        writeln!(w, "  {:width$}  {} [{}]", e.name, e.summary, notes.join("; "))?;
        for k in e.settings.keywords() {
            writeln!(w, "  {:width$}    setting {}: {}", "", k.name, k.meaning)?;
        }
        for d in e.details {
            writeln!(w, "  {:width$}    column {}: {}", "", d.name, d.meaning)?;
        }
    }
    writeln!(w)?;
    writeln!(w, "Solvers (--solver NAME, default {}):", registry::SmfSolver::TWO_MULTIPLIER)?;
    for s in registry::SmfSolver::names() {
        writeln!(w, "  {s:width$}  {}", registry::SmfSolver::summary(s))?;
    }
    Ok(())
}
