//! A raw's EXIF facts: rawler's metadata filled in from the TIFF EXIF of the
//! file's head, read without decoding the image data.

use super::{RawError, is_dng_path, open};
use crate::photo::exif::{ExifFacts, clean_text, try_facts_from_bytes};
use crate::photo::raw::guard;
use rawler::decoders::{RawDecodeParams, RawMetadata};
use std::path::Path;

/// Facts from rawler's metadata, filled in from the TIFF EXIF where kamadak-exif can read it.
pub(in crate::photo::raw) fn facts_of(
    meta: Option<&RawMetadata>,
    tiff: Option<ExifFacts>,
    make: &str,
    model: &str,
) -> ExifFacts {
    let mut f = ExifFacts {
        from_raw: true,
        make: clean_text(make),
        model: clean_text(model),
        ..ExifFacts::default()
    };
    if let Some(m) = meta {
        let e = &m.exif;
        let ratio = |r: &rawler::formats::tiff::Rational| {
            if r.d == 0 {
                f64::NAN
            } else {
                r.n as f64 / r.d as f64
            }
        };
        f.lens_model = e.lens_model.as_deref().and_then(clean_text);
        f.orientation = e.orientation;
        f.set_f_number(e.fnumber.as_ref().map(ratio));
        f.set_focal_length_mm(e.focal_length.as_ref().map(ratio));
        f.set_exposure_time_s(e.exposure_time.as_ref().map(ratio));
        f.set_iso(
            e.iso_speed_ratings
                .map(u32::from)
                .or(e.iso_speed)
                .or(e.recommended_exposure_index),
        );
    }
    if let Some(tiff) = tiff {
        f.fill_from(tiff);
    }
    // rawler's cleaned-up names only where the file itself names nothing.
    if let Some(m) = meta {
        if f.make.is_none() {
            f.make = clean_text(&m.make);
        }
        if f.model.is_none() {
            f.model = clean_text(&m.model);
        }
    }
    f
}

/// Bytes of the file's head tried first for its TIFF EXIF: TIFF-based raws keep
/// their IFDs ahead of the image data.
const EXIF_HEAD_BYTES: usize = 4 << 20;

/// The TIFF EXIF facts of a raw file's bytes, read from its first
/// [`EXIF_HEAD_BYTES`] when they suffice (the EXIF reader copies what it is
/// given, and a raw's image data is tens of MB), else from the whole file.
pub(super) fn tiff_exif(buf: &[u8]) -> Option<ExifFacts> {
    let read = |b: &[u8]| guard::contain(|| try_facts_from_bytes(b)).ok().flatten();
    if buf.len() > EXIF_HEAD_BYTES
        && let Some(f) = read(&buf[..EXIF_HEAD_BYTES])
    {
        return Some(f);
    }
    read(buf)
}

/// The TIFF EXIF facts from the first [`EXIF_HEAD_BYTES`] of the file at
/// `path` (read, not mapped), or `None` when they are not there.
pub(in crate::photo::raw) fn tiff_exif_of_file(path: &Path) -> Option<ExifFacts> {
    use std::io::Read;
    let mut head = Vec::new();
    std::fs::File::open(path)
        .ok()?
        .take(EXIF_HEAD_BYTES as u64)
        .read_to_end(&mut head)
        .ok()?;
    guard::contain(|| try_facts_from_bytes(&head))
        .ok()
        .flatten()
}

/// Reads the EXIF facts of a raw file without decoding its image data.
pub fn read_raw_facts(path: &Path) -> Result<ExifFacts, RawError> {
    if is_dng_path(path)
        && let Some(facts) = super::dng::read_dng_facts(path)?
    {
        return Ok(facts);
    }
    let src = match open(path) {
        Ok(src) => src,
        Err(RawError::Corrupt { cause, .. }) => {
            return Ok(ExifFacts {
                from_raw: true,
                warnings: vec![format!("no EXIF: {cause}")],
                ..ExifFacts::default()
            });
        }
        Err(e) => return Err(e),
    };
    let outcome = guard::contain(|| {
        let decoder = rawler::get_decoder(&src)?;
        decoder.raw_metadata(&src, &RawDecodeParams::default())
    });
    let tiff = tiff_exif(src.buf());
    match outcome {
        Ok(Ok(meta)) => Ok(facts_of(Some(&meta), tiff, "", "")),
        // No rawler metadata: fall back on the TIFF EXIF alone.
        Ok(Err(_)) | Err(_) => {
            let mut f = facts_of(None, tiff, "", "");
            f.warnings
                .push("the raw decoder could not read this file's metadata".to_string());
            Ok(f)
        }
    }
}
