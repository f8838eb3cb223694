//! The adapter over `rawler` (=0.8.0; the crate is named only here and in
//! the lossless-JPEG tile encoder `ljpeg.rs`):
//! decode a raw file into a [`RawFrame`] and read a raw's EXIF facts. Every
//! call into rawler runs inside [`guard::contain`], so a decoder panic on a
//! corrupt file becomes a [`RawError::DecoderPanic`] for that file.
//!
//! [`guard::contain`]: super::guard::contain

mod deltas;
mod error;
mod facts;
mod whole;

use super::dng;
use super::frame::RawFrame;
use rawler::rawsource::RawSource;
use std::path::Path;

pub(super) use deltas::Deltas;
pub use error::RawError;
pub use facts::read_raw_facts;
pub(super) use facts::{facts_of, tiff_exif_of_file};
pub use whole::decode_raw_with_rawler;

/// File name extensions (lower case) of the camera raw formats rawler reads.
pub const RAW_EXTENSIONS: &[&str] = &[
    "dng", "cr2", "cr3", "crw", "nef", "nrw", "arw", "srf", "sr2", "raf", "rw2", "rwl", "orf",
    "pef", "srw", "x3f", "3fr", "fff", "iiq", "erf", "kdc", "dcr", "dcs", "mef", "mos", "mrw",
    "ari", "qtk", "tfr",
];

/// Whether `path` has a camera raw extension (see [`RAW_EXTENSIONS`]).
pub fn is_raw_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| RAW_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str()))
}

fn open(path: &Path) -> Result<RawSource, RawError> {
    let meta = std::fs::metadata(path).map_err(|e| RawError::Io {
        path: path.display().to_string(),
        cause: e.to_string(),
    })?;
    if meta.len() == 0 {
        return Err(RawError::Corrupt {
            path: path.display().to_string(),
            cause: "the file is empty".to_string(),
        });
    }
    let src = RawSource::new(path).map_err(|e| RawError::Io {
        path: path.display().to_string(),
        cause: e.to_string(),
    })?;
    let buf = src.buf();
    match super::tiff_bounds::tiff_damage(&mut std::io::Cursor::new(buf), buf.len() as u64) {
        Some(cause) => Err(RawError::Corrupt {
            path: path.display().to_string(),
            cause,
        }),
        None => Ok(src),
    }
}

/// Decodes a camera raw into linear sensor data cropped to its active area,
/// with its EXIF facts. No demosaicing and no colour processing.
pub fn decode_raw(path: &Path) -> Result<RawFrame, RawError> {
    decode_raw_within(path, None)
}

/// Like [`decode_raw`], but only the frame rectangle `want` = (x0, y0, x1,
/// y1) (frame pixels, end exclusive; `None` = all) needs to be decoded. The
/// common DNGs (uncompressed or lossless JPEG, strips or tiles) are read by
/// our windowed reader, which reads and decodes only the strips or tiles
/// meeting `want` (the rest of the frame reads as 0 DN, see
/// [`RawFrame::decoded_rect`]); other files are decoded whole by rawler.
pub fn decode_raw_within(
    path: &Path,
    want: Option<(usize, usize, usize, usize)>,
) -> Result<RawFrame, RawError> {
    if !is_dng_path(path) {
        return decode_raw_with_rawler(path);
    }
    // The windowed reader is a fast path: whatever it does not take or
    // refuses (other than an unreadable file) gets rawler's own verdict.
    let why = match super::dng::read_dng(path, want) {
        Ok(super::dng::Dng::Frame(mut f)) => {
            f.decoder = "sweepmtf windowed DNG reader".to_string();
            return Ok(*f);
        }
        Ok(super::dng::Dng::Rawler(why)) => why,
        Err(e @ RawError::Io { .. }) => return Err(e),
        Err(e) => format!("the windowed reader refused it: {e}"),
    };
    let mut f = decode_raw_with_rawler(path)?;
    f.decoder = format!("{RAWLER} (not read windowed: {why})");
    Ok(f)
}

fn is_dng_path(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("dng"))
}

/// The raw decoder crate and its pinned version.
const RAWLER: &str = "rawler 0.8.0";
