//! `sweepmtf batch` and `sweepmtf merge`: arguments and dispatch.

use super::{CliError, Code};

/// Arguments of `sweepmtf batch`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Arguments of `sweepmtf merge`.
#[derive(Debug, clap::Args)]
pub struct MergeArgs {}

/// Runs `sweepmtf batch`.
pub fn run(_args: &Args) -> Result<(), CliError> {
    Err(CliError::new(
        Code::Internal,
        "'batch' is not implemented yet",
    ))
}

/// Runs `sweepmtf merge`.
pub fn run_merge(_args: &MergeArgs) -> Result<(), CliError> {
    Err(CliError::new(
        Code::Internal,
        "'merge' is not implemented yet",
    ))
}
