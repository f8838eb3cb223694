//! Windowed reading of the common DNG raws, without rawler's whole-file
//! decode: the IFDs are parsed from the file through a reader (no memory
//! map of the file, no camera table), and only the strips or tiles that
//! hold a wanted frame rectangle are read and decoded, straight into a
//! frame-sized buffer whose other pages are never touched. A measurement
//! whose region is known therefore reads only its rows.
//!
//! Handled here: CFA or linear DNGs, unsigned samples, uncompressed (any
//! bit depth rawler's packed unpacker reads) or lossless JPEG (compression
//! 7), in strips or tiles, with no linearisation table and no row/column
//! interleave. Anything else is handed back to the rawler path
//! ([`Dng::Rawler`]), which reads every format and gives its own verdict.
//! The metadata rules (raw IFD choice, active area, default crop, CFA
//! anchored at the active area, black repeat and deltas, white level)
//! follow rawler 0.8.0's DNG decoder; tests check that both paths give the
//! same frame.

mod metadata;
mod open;
mod tags;
mod window;

use super::decode::RawError;
use super::frame::RawFrame;
use super::guard;
use super::tiff_bounds;
use crate::photo::exif::ExifFacts;
use metadata::frame_of;
use open::{facts_and_names, open_dng};
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;
use std::sync::Mutex;

pub(crate) use open::implausible_tiff_size;

/// A frame rectangle (x0, y0, x1, y1) in frame pixels, end exclusive.
pub type FrameRect = (usize, usize, usize, usize);

/// What the windowed reader made of a file.
pub(crate) enum Dng {
    /// The frame, with the wanted rectangle decoded.
    Frame(Box<RawFrame>),
    /// Not a DNG this reader handles (the reason); decode it with rawler.
    Rawler(String),
}

/// How the raw IFD's samples are stored.
#[derive(Clone, Copy, PartialEq)]
enum Codec {
    /// Uncompressed, packed at `bits` per sample.
    Packed,
    /// Lossless JPEG (DNG compression 7).
    Ljpeg,
}

/// The strips or tiles of the raw IFD: unit `i` of a `down × across` grid
/// covers image columns `[c·w, c·w + w)` and rows `[r·h, r·h + h)`.
struct Units {
    w: usize,
    h: usize,
    across: usize,
    offsets: Vec<u64>,
    counts: Vec<u64>,
}

/// The file's raw-data reader: positioned reads under a lock.
struct Source {
    file: Mutex<File>,
    len: u64,
}

impl Source {
    /// Reads `len` bytes at `offset` into `buf` (resized to `len`).
    fn read_into(&self, offset: u64, len: u64, buf: &mut Vec<u8>) -> Result<(), String> {
        if offset.checked_add(len).is_none_or(|end| end > self.len) {
            return Err(format!(
                "image data at {offset}+{len} runs past the end of the {}-byte file (truncated?)",
                self.len
            ));
        }
        buf.resize(len as usize, 0);
        let mut f = self
            .file
            .lock()
            .map_err(|_| "file lock poisoned".to_string())?;
        f.seek(SeekFrom::Start(offset))
            .and_then(|_| f.read_exact(buf))
            .map_err(|e| e.to_string())
    }
}

/// One windowed decode: which units to read and where their pixels go.
struct Job<'a> {
    codec: Codec,
    bits: u32,
    endian: rawler::bits::Endian,
    spp: usize,
    /// Image width (pixels).
    width: usize,
    units: &'a Units,
    /// Frame origin (x, y) in the image and frame width.
    frame: (usize, usize, usize),
    /// Wanted rectangle (x0, y0, x1, y1) in image pixels.
    want: (usize, usize, usize, usize),
}

/// Reads the DNG at `path`, decoding only the frame rectangle `want` (all of
/// it when `None`; clamped to the frame). Other pixels of the frame hold 0
/// and are never read (see [`RawFrame::decoded_rect`]).
pub(crate) fn read_dng(path: &Path, want: Option<FrameRect>) -> Result<Dng, RawError> {
    let Some((file, len, tiff)) = open_dng(path)? else {
        return Ok(Dng::Rawler("not a DNG this reader parses".into()));
    };
    let source = Source {
        file: Mutex::new(file),
        len,
    };
    let outcome = guard::contain(|| frame_of(path, &tiff, &source, want));
    match outcome {
        Ok(r) => r,
        Err(p) => Ok(Dng::Rawler(format!("windowed reader failed: {p}"))),
    }
}

/// The EXIF facts of a DNG read without rawler (see [`facts_and_names`]), or
/// `None` when the file is not a DNG this reader parses.
pub(crate) fn read_dng_facts(path: &Path) -> Result<Option<ExifFacts>, RawError> {
    Ok(open_dng(path)?.map(|(_, _, tiff)| facts_and_names(path, &tiff).0))
}
