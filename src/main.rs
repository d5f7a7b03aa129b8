//! The `coif` command line: parse, call the library, report. Exit codes: 0 success, 2 bad input
//! or usage, 1 anything else.
use std::process::ExitCode;

use clap::Parser;

mod cli;

fn main() -> ExitCode {
    let parsed = cli::Cli::parse();
    match cli::run(parsed) {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("coif: error: {}", cli::error_chain(&error));
            ExitCode::from(error.exit_code() as u8)
        }
    }
}
