//! `sweepmtf model`: arguments and dispatch.

use super::factors::FactorArgs;
use super::{CliError, Code};

/// Arguments of `sweepmtf model`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The model factors.
    #[command(flatten)]
    pub factors: FactorArgs,
}

/// Runs `sweepmtf model`.
pub fn run(args: &Args) -> Result<(), CliError> {
    let _system = args.factors.build()?;
    Err(CliError::new(
        Code::Internal,
        "'model' outputs are not implemented yet",
    ))
}
