//! [`RawError`], why a raw file could not be decoded, and rawler's errors turned into it.

use crate::photo::exif::{ExifFacts, clean_text};
use rawler::RawlerError;
use std::path::Path;
use thiserror::Error;

/// Why a raw file could not be decoded.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum RawError {
    /// The file could not be opened or read.
    #[error("{path}: cannot read: {cause}")]
    Io {
        /// The file.
        path: String,
        /// The operating system's reason.
        cause: String,
    },
    /// The camera or raw format is not supported by the decoder.
    #[error("{path}: unsupported camera or raw format (make '{make}', model '{model}'): {what}")]
    Unsupported {
        /// The file.
        path: String,
        /// Camera make as written in the file ("" if unknown).
        make: String,
        /// Camera model as written in the file ("" if unknown).
        model: String,
        /// What is not supported.
        what: String,
    },
    /// The file is not a camera raw the decoder recognises (no make or model found).
    #[error("{path}: not a camera raw format the decoder recognises ({what})")]
    Unrecognised {
        /// The file.
        path: String,
        /// What the decoder reported.
        what: String,
    },
    /// The file is damaged or not what its name says.
    #[error("{path}: corrupt or unreadable raw data: {cause}")]
    Corrupt {
        /// The file.
        path: String,
        /// What the decoder reported.
        cause: String,
    },
    /// The decoder crashed on the file (contained; the file is probably corrupt).
    #[error(
        "{path}: the raw decoder failed on this file ({cause}); it is probably corrupt or unsupported"
    )]
    DecoderPanic {
        /// The file.
        path: String,
        /// The decoder's panic message.
        cause: String,
    },
}

/// Turns a rawler error into ours, naming make and model (from `facts` when rawler has none).
pub(super) fn map_error(path: &Path, e: RawlerError, facts: &ExifFacts) -> RawError {
    let path = path.display().to_string();
    match e {
        RawlerError::Unsupported {
            what, make, model, ..
        } => {
            let make = clean_text(&make)
                .or_else(|| facts.make.clone())
                .unwrap_or_default();
            let model = clean_text(&model)
                .or_else(|| facts.model.clone())
                .unwrap_or_default();
            if make.is_empty() && model.is_empty() {
                RawError::Unrecognised { path, what }
            } else {
                RawError::Unsupported {
                    path,
                    make,
                    model,
                    what,
                }
            }
        }
        RawlerError::DecoderFailed(cause) => RawError::Corrupt {
            path,
            cause: if cause.contains("EOF") {
                format!("the file is truncated ({cause})")
            } else {
                cause
            },
        },
    }
}
