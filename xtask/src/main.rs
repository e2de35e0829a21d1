//! `cargo xtask`: the repository's automation entry point (see `cargo xtask help`).
//!
//! Always run through the alias in `.cargo/config.toml`, which builds it optimised, so that the
//! numbers and timings it prints never come from a debug build. Arguments are taken as the
//! operating system gives them (paths need not be UTF-8); each command answers `--help`.

use xtask::{reproduce, sdplib, test_suite};

use std::ffi::OsString;
use std::process::ExitCode;

const HELP: &str = "\
cargo xtask <command> [options]

Commands:
  reproduce [--paper NAME] [--quick] [--out DIR] [--seed S] [--runs R]
                         Regenerate every paper's experiment (or one: --paper carrier) into
                         DIR/NAME/ (report.md, summary.json, figures/, csv/) and DIR/index.md
                         (default DIR: out/reproduce)
  sdplib [--dir D] [--backend NAME]
                         Solve the SDPLIB suite and print a table (default: every compiled backend)
  test [--rust-only | --python-only] [CARGO TEST ARGS...]
                         Every test: `cargo test --workspace ARGS`, then the Python package's tests
                         (a virtual environment in target/python-venv, the package built by maturin,
                         pytest)
  help [COMMAND]         This text, or a command's (as COMMAND --help)
";

fn main() -> ExitCode {
    // Ctrl-C or SIGTERM: no temporary file or half-built paper directory is left behind.
    if let Err(e) = atomic_output::remove_temporaries_on_signals() {
        eprintln!("warning: cannot watch for SIGINT/SIGTERM: {e}");
    }
    let mut argv = std::env::args_os().skip(1);
    let command = argv.next();
    let rest: Vec<OsString> = argv.collect();
    let help = [OsString::from("--help")];
    let result = match command.as_ref().map(|c| c.to_str()) {
        Some(Some("reproduce")) => reproduce::run(&rest),
        Some(Some("sdplib")) => sdplib::run(&rest),
        Some(Some("test")) => test_suite::run_tests(&rest),
        Some(Some("filter")) => Err("`cargo xtask filter` moved to the installable CLI: `cargo run -p port-est -- \
                                     filter …` (or `cargo install --path crates/port-est`, then `port-est filter …`)"
            .to_owned()),
        Some(Some("help")) => match rest.first().and_then(|c| c.to_str()) {
            Some("reproduce") => reproduce::run(&help),
            Some("sdplib") => sdplib::run(&help),
            Some("test") => test_suite::run_tests(&help),
            _ => {
                print!("{HELP}");
                Ok(())
            }
        },
        Some(Some("--help" | "-h")) | None => {
            print!("{HELP}");
            Ok(())
        }
        Some(_) => {
            let shown = command.as_ref().map(|c| c.to_string_lossy().into_owned()).unwrap_or_default();
            Err(format!("unknown command {shown:?}\n\n{HELP}"))
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}
