//! Exit codes (documented in the README) and the CLI's one-line error.

/// A documented exit code.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Code {
    /// 1: an internal error (a bug; please report it).
    Internal = 1,
    /// 2: bad arguments or parameter values.
    Usage = 2,
    /// 3: an input file is missing, unreadable, corrupt or of an unsupported format.
    Input = 3,
    /// 4: the chart or region was not found, or the given region is unusable.
    Locate = 4,
    /// 5: the measurement is impossible (clipped, no oscillation, modulation unknown).
    Measure = 5,
    /// 6: an output file could not be written.
    Output = 6,
    /// 7: a batch finished but some shots failed.
    Partial = 7,
    /// 8: the output folder is in use by another `batch` or `merge` run.
    Busy = 8,
}

impl From<Code> for std::process::ExitCode {
    fn from(c: Code) -> Self {
        std::process::ExitCode::from(c as u8)
    }
}

/// An error ready to print: one line and its exit code.
#[derive(Debug)]
pub struct CliError {
    /// Exit code.
    pub code: Code,
    /// The line printed on stderr (after "sweepmtf: ").
    pub message: String,
}

impl CliError {
    /// An error with a code and a message.
    pub fn new(code: Code, message: impl Into<String>) -> Self {
        CliError {
            code,
            message: message.into(),
        }
    }
    /// A usage error (exit code 2).
    #[allow(dead_code)]
    pub fn usage(message: impl Into<String>) -> Self {
        Self::new(Code::Usage, message)
    }
}
