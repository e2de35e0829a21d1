//! The `port-est` binary: parses the command line with `clap` and hands it to the library.
//! Errors go to stderr as `error: …` with exit code 1 (usage errors: clap's message, code 2); on
//! SIGINT/SIGTERM the temporary output is removed and the exit code is 128 + the signal.

use std::io::Write;
use std::process::ExitCode;

use clap::Parser;

fn main() -> ExitCode {
    let cli = port_est::Cli::parse();
    // Ctrl-C or SIGTERM mid-run: no temporary output file is left behind.
    if let Err(e) = atomic_output::remove_temporaries_on_signals() {
        let _ = writeln!(std::io::stderr(), "warning: cannot watch for SIGINT/SIGTERM: {e}");
    }
    match port_est::execute(cli, &mut std::io::stdout().lock(), &mut std::io::stderr().lock()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let _ = writeln!(std::io::stderr(), "error: {e}");
            ExitCode::FAILURE
        }
    }
}
