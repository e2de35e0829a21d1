//! The `port-est` binary: parses the command line with `clap` and hands it to the library.
//! Errors go to stderr as `error: …` with exit code 1 (usage errors: clap's message, code 2).

use std::io::Write;
use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = port_est::Cli::parse();
    match port_est::execute(cli, &mut std::io::stdout().lock(), &mut std::io::stderr().lock()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let _ = writeln!(std::io::stderr(), "error: {e}");
            ExitCode::FAILURE
        }
    }
}
