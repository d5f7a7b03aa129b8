//! The binary's half of coif: argument grammar (`args`) and the commands that drive the library
//! (`commands`). Nothing here is needed by a host that calls the library directly.
mod args;
mod checks;
mod commands;

pub(crate) use args::Cli;
pub(crate) use commands::{error_chain, run};
