//! `cargo xtask`: the repository's automation entry point (see `cargo xtask help`).
//!
//! Always run through the alias in `.cargo/config.toml`, which builds it optimised, so that the
//! numbers and timings it prints never come from a debug build.

use xtask::{filter, reproduce, sdplib};

use std::process::ExitCode;

const HELP: &str = "\
cargo xtask <command> [options]

Commands:
  reproduce [--quick] [--out DIR] [--seed S] [--runs R]
                         Regenerate the straddle-carrier experiment and the extended scenarios:
                         figures, CSV, summary.json and report.md in DIR (default out/reproduce)
  sdplib [--dir D] [--backend NAME]
                         Solve the SDPLIB suite and print a table (default: every compiled backend)
  filter --model MODEL.toml --input DATA.csv --output OUT.csv [--estimator smf|kf|yang-li] [--solver NAME]
                         Run an estimator over logged data (formats: README); --solver is
                         two-multiplier (default) or an SDP backend (faer-ipm, clarabel)
  help                   This text
";

fn main() -> ExitCode {
    let mut argv = std::env::args().skip(1);
    let command = argv.next();
    let rest: Vec<String> = argv.collect();
    let result = match command.as_deref() {
        Some("reproduce") => reproduce::run(&rest),
        Some("sdplib") => sdplib::run(&rest),
        Some("filter") => filter::run(&rest),
        Some("help") | Some("--help") | Some("-h") | None => {
            print!("{HELP}");
            Ok(())
        }
        Some(other) => Err(format!("unknown command {other:?}\n\n{HELP}")),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}
