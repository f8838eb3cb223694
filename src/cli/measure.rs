//! `sweepmtf measure`: arguments and dispatch.

use super::{CliError, Code};

/// Arguments of `sweepmtf measure`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `sweepmtf measure`.
pub fn run(_args: &Args) -> Result<(), CliError> {
    Err(CliError::new(
        Code::Internal,
        "'measure' is not implemented yet",
    ))
}
