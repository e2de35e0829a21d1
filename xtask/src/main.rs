//! `cargo xtask`: the repository's automation entry point (see `cargo xtask help`).
//!
//! Always run through the alias in `.cargo/config.toml`, which builds it optimised, so that the
//! numbers and timings it prints never come from a debug build.

use xtask::{reproduce, sdplib, test_suite};

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
                         (a virtual environment in target/python-venv with the pinned requirements
                         of crates/port-estimation-py, the package built by maturin, pytest)
  help                   This text
";

fn main() -> ExitCode {
    let mut argv = std::env::args().skip(1);
    let command = argv.next();
    let rest: Vec<String> = argv.collect();
    let result = match command.as_deref() {
        Some("reproduce") => reproduce::run(&rest),
        Some("sdplib") => sdplib::run(&rest),
        Some("test") => test_suite::run_tests(&rest),
        Some("filter") => {
            Err("`cargo xtask filter` moved to the installable CLI: `cargo run -p port-est -- filter …` \
                               (or `cargo install --path crates/port-est`, then `port-est filter …`)"
                .to_owned())
        }
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
