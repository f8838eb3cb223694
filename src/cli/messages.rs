//! Message levels on stderr: errors (always), warnings (something may be
//! wrong with the result; hidden by `-q`) and notes (what was done or
//! assumed; shown only with `-v`). The JSON summaries keep all of them,
//! labelled `warnings` and `notes`, whatever the level.

use std::sync::atomic::{AtomicU8, Ordering};

/// How much goes to stderr besides errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Level {
    /// `-q`: errors only (no warnings, notes or progress).
    Quiet = 0,
    /// Default: errors and warnings.
    Normal = 1,
    /// `-v`: errors, warnings and notes.
    Verbose = 2,
}

static LEVEL: AtomicU8 = AtomicU8::new(Level::Normal as u8);

/// Sets the level for the rest of the run (from `-q` / `-v`).
pub fn set_level(quiet: bool, verbose: bool) {
    let l = if quiet {
        Level::Quiet
    } else if verbose {
        Level::Verbose
    } else {
        Level::Normal
    };
    LEVEL.store(l as u8, Ordering::Relaxed);
}

/// The level set by [`set_level`].
pub fn level() -> Level {
    match LEVEL.load(Ordering::Relaxed) {
        0 => Level::Quiet,
        2 => Level::Verbose,
        _ => Level::Normal,
    }
}

/// Prints `sweepmtf: warning: {text}` unless quiet.
pub fn warning(text: &str) {
    if level() >= Level::Normal {
        eprintln!("sweepmtf: warning: {text}");
    }
}

/// Prints `sweepmtf: note: {text}` only when verbose.
pub fn note(text: &str) {
    if level() >= Level::Verbose {
        eprintln!("sweepmtf: note: {text}");
    }
}
