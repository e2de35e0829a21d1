//! `port-est`: state estimation over logged data of port vehicles, from the command line.
//!
//! ```text
//! port-est filter --model MODEL.toml --input DATA.csv --output OUT.csv [--estimator NAME] [--solver NAME]
//! port-est estimators
//! port-est truck --input DATA.csv --output OUT.csv [--config CONFIG.toml]
//! port-est bds-ins --input DATA.csv --output OUT.csv [--config CONFIG.toml] [--fis SYSTEM.toml] [--scaling none] [--gga]
//! ```
//!
//! `filter` runs any estimator of [`estimators::registry`] (the set-membership filter `smf` by
//! default, the Kalman filter `kf`, the Yang–Li reconstructions) over a model file ([`model`])
//! and a CSV log ([`data`]) and writes one estimate per step ([`filter`]) to an output that is
//! published only when every step succeeded ([`output`]). Malformed files are reported at their
//! `file:line:column` ([`Error`]). The binary is a thin layer over [`execute`], so that tests
//! drive the same code.

pub mod bds_ins;
pub mod cli;
pub mod data;
pub mod error;
pub mod filter;
mod mhe_table;
pub mod model;
pub mod output;
pub mod truck;

use std::io::{self, Write};

pub use cli::{Cli, Command, FilterArgs};
pub use error::{Error, Location};
pub use filter::{FilterOptions, FilterSummary, GapPolicy, filter};
pub use model::{Model, parse_model, read_model};

use estimators::registry;

/// Runs a parsed command line: `filter` reports what it wrote on `stderr`, `estimators` lists
/// the registry on `stdout` (a closed pipe is not an error).
///
/// # Errors
/// The command's [`Error`].
pub fn execute(cli: Cli, stdout: &mut dyn Write, stderr: &mut dyn Write) -> Result<(), Error> {
    match cli.command {
        Command::Filter(args) => {
            let options = FilterOptions::from(args);
            let s = filter(&options)?;
            let fallbacks = match s.fallbacks {
                0 => String::new(),
                f => format!(" ({f} steps fell back to a feasible τ after a solver failure)"),
            };
            // A closed stderr is no reason to fail a run whose output is written.
            let _ = writeln!(
                stderr,
                "{} steps of {} written to {}{fallbacks}",
                s.steps,
                s.estimator,
                options.output.display()
            );
            Ok(())
        }
        Command::Truck(args) => {
            let options = truck::TruckOptions::from(args);
            let steps = truck::truck(&options)?;
            let _ = writeln!(stderr, "{steps} steps of ekf written to {}", options.output.display());
            Ok(())
        }
        Command::BdsIns(args) => {
            let options = bds_ins::BdsInsOptions::from(args);
            let s = bds_ins::bds_ins(&options)?;
            let filter = if options.fuzzy { "the fuzzy-adaptive Kalman filter" } else { "the Kalman filter" };
            let _ = writeln!(
                stderr,
                "{} epochs ({} without a fix) of {filter} written to {}",
                s.epochs,
                s.outages,
                options.output.display()
            );
            Ok(())
        }
        Command::Estimators => match write_estimators(stdout) {
            Err(e) if e.kind() != io::ErrorKind::BrokenPipe => Err(Error::io("<stdout>".as_ref(), e)),
            _ => Ok(()),
        },
    }
}

/// Writes the registry: every estimator with its kind and summary, then the solvers.
///
/// # Errors
/// When `w` fails.
pub fn write_estimators(w: &mut dyn Write) -> io::Result<()> {
    let width = registry::LINEAR_ESTIMATORS.iter().map(|e| e.name.len()).max().unwrap_or(0);
    writeln!(w, "Estimators (--estimator NAME, default smf):")?;
    for e in registry::LINEAR_ESTIMATORS {
        let mut notes = vec![e.kind.label()];
        if e.uses_solver {
            notes.push("uses --solver");
        }
        if e.needs_input_bounds {
            notes.push("needs u_lower, u_upper");
        }
        writeln!(w, "  {:width$}  {} [{}]", e.name, e.summary, notes.join("; "))?;
    }
    writeln!(w)?;
    writeln!(w, "Estimators of nonlinear models in the library's registry (port-est truck runs ekf):")?;
    for e in registry::DIFFERENTIABLE_ESTIMATORS.iter().chain(registry::NONLINEAR_ESTIMATORS) {
        writeln!(w, "  {:width$}  {} [{}]", e.name, e.summary, e.kind.label())?;
    }
    writeln!(w)?;
    writeln!(w, "Solvers (--solver NAME, default {}):", registry::TWO_MULTIPLIER)?;
    for s in registry::solver_names() {
        let what = if s == registry::TWO_MULTIPLIER { "exact two-multiplier method (fastest)" } else { "SDP backend" };
        writeln!(w, "  {s:width$}  {what}")?;
    }
    Ok(())
}
