//! `sweepmtf model`: arguments and dispatch.

use super::{CliError, Code};

/// Arguments of `sweepmtf model`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `sweepmtf model`.
pub fn run(_args: &Args) -> Result<(), CliError> {
    Err(CliError::new(
        Code::Internal,
        "'model' is not implemented yet",
    ))
}
