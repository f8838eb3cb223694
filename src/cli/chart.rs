//! `sweepmtf chart`: arguments and dispatch.

use super::{CliError, Code};

/// Arguments of `sweepmtf chart`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `sweepmtf chart`.
pub fn run(_args: &Args) -> Result<(), CliError> {
    Err(CliError::new(
        Code::Internal,
        "'chart' is not implemented yet",
    ))
}
