//! Opening a DNG through a reader: its TIFF structure, its EXIF facts, make
//! and model, and the check for image sizes no camera makes.

use super::tags::usize_at;
use crate::photo::exif::{ExifFacts, clean_text};
use crate::photo::raw::decode::{RawError, facts_of, tiff_exif_of_file};
use crate::photo::raw::guard;
use rawler::formats::tiff::GenericTiffReader;
use rawler::formats::tiff::reader::TiffReader;
use rawler::tags::{DngTag, TiffCommonTag};
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

/// Opens the file and parses its TIFF structure through a reader: the file,
/// its length and the IFDs, or `None` when it is not a TIFF-based DNG (or
/// its structure does not parse; rawler then gives its verdict).
pub(super) fn open_dng(path: &Path) -> Result<Option<(File, u64, GenericTiffReader)>, RawError> {
    let io = |e: std::io::Error| RawError::Io {
        path: path.display().to_string(),
        cause: e.to_string(),
    };
    let file = File::open(path).map_err(io)?;
    let len = file.metadata().map_err(io)?.len();
    let mut head = [0u8; 4];
    {
        let mut f = &file;
        if len < 8 || f.read_exact(&mut head).is_err() {
            return Ok(None);
        }
        f.seek(SeekFrom::Start(0)).map_err(io)?;
    }
    if head != *b"II*\0" && head != *b"MM\0*" {
        return Ok(None);
    }
    // A structure rawler's parser cannot take safely is left to the whole-file
    // path, whose opening refuses it as corrupt (see `decode::open`).
    let damaged = super::tiff_bounds::tiff_damage(&mut &file, len).is_some();
    (&file).seek(SeekFrom::Start(0)).map_err(io)?;
    if damaged {
        return Ok(None);
    }
    let tiff = {
        let mut reader = BufReader::with_capacity(64 << 10, &file);
        match guard::contain(|| GenericTiffReader::new(&mut reader, 0, 0, None, &[])) {
            Ok(Ok(t)) => t,
            Ok(Err(_)) | Err(_) => return Ok(None),
        }
    };
    if !tiff.root_ifd().has_entry(DngTag::DNGVersion) {
        return Ok(None);
    }
    Ok(Some((file, len, tiff)))
}

/// The EXIF facts of a DNG (TIFF EXIF from the file's head, make and model
/// from IFD 0) and its make and model, without rawler.
pub(super) fn facts_and_names(
    path: &Path,
    tiff: &GenericTiffReader,
) -> (ExifFacts, String, String) {
    let mut facts = facts_of(None, tiff_exif_of_file(path), "", "");
    let root = tiff.root_ifd();
    let text = |tag| {
        root.get_entry(tag)
            .and_then(|e| e.value.as_string().cloned())
            .and_then(|s| clean_text(&s))
            .unwrap_or_default()
    };
    let (make, model) = (text(TiffCommonTag::Make), text(TiffCommonTag::Model));
    if facts.make.is_none() && !make.is_empty() {
        facts.make = Some(make.clone());
    }
    if facts.model.is_none() && !model.is_empty() {
        facts.model = Some(model.clone());
    }
    (facts, make, model)
}

/// Samples one image of a raw may plausibly hold: no camera makes a
/// gigasample frame, so a header saying so is damaged.
pub(super) const MAX_SAMPLES: usize = 1 << 30;

/// The first image size in the TIFF structure of the file at `path` that no
/// camera makes (width × height × samples per pixel over [`MAX_SAMPLES`]),
/// as a cause for [`RawError::Corrupt`]; `None` when every size is plausible
/// or the file is not TIFF-based. Checked before rawler decodes, which
/// allocates whatever a damaged header asks for (an allocation failure
/// aborts the process; it cannot be caught).
pub(crate) fn implausible_tiff_size(path: &Path) -> Option<String> {
    let mut file = File::open(path).ok()?;
    let mut head = [0u8; 4];
    file.read_exact(&mut head).ok()?;
    if head != *b"II*\0" && head != *b"MM\0*" {
        return None;
    }
    file.seek(SeekFrom::Start(0)).ok()?;
    let mut reader = BufReader::with_capacity(64 << 10, file);
    let tiff = match guard::contain(|| GenericTiffReader::new(&mut reader, 0, 0, None, &[])) {
        Ok(Ok(t)) => t,
        _ => return None,
    };
    tiff.file()
        .chain
        .iter()
        .flat_map(|ifd| ifd.find_ifds_with_tag(TiffCommonTag::ImageWidth))
        .find_map(|ifd| {
            let width = usize_at(ifd, TiffCommonTag::ImageWidth, 0).unwrap_or(0);
            let height = usize_at(ifd, TiffCommonTag::ImageLength, 0).unwrap_or(0);
            let spp = usize_at(ifd, TiffCommonTag::SamplesPerPixel, 0).unwrap_or(1);
            let n = width
                .checked_mul(height)
                .and_then(|n| n.checked_mul(spp.max(1)));
            n.is_none_or(|n| n > MAX_SAMPLES)
                .then(|| format!("an implausible image size ({width}×{height}×{spp} samples)"))
        })
}
