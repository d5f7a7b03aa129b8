//! The `coif` command line: parse, call the library, report. Exit codes: 0 success, 2 bad input
//! or usage, 1 anything else.
use std::process::ExitCode;

use clap::Parser;

mod cli;

fn main() -> ExitCode {
    let parsed = cli::Cli::parse();
    if let Err(error) = coif::io::cleanup::install_signal_handlers() {
        eprintln!("coif: warning: cannot catch interrupts to clean up temporary files: {error}");
    }
    match cli::run(parsed) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("coif: error: {}", cli::error_chain(&error));
            ExitCode::from(error.exit_code() as u8)
        }
    }
}
