//! `sweepmtf simulate`: arguments and dispatch.

use super::{CliError, Code};

/// Arguments of `sweepmtf simulate`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `sweepmtf simulate`.
pub fn run(_args: &Args) -> Result<(), CliError> {
    Err(CliError::new(
        Code::Internal,
        "'simulate' is not implemented yet",
    ))
}
