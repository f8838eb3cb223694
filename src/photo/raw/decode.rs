//! The adapter over `rawler` (=0.8.0; the crate is named only here and in
//! the lossless-JPEG tile encoder `ljpeg.rs`):
//! decode a raw file into a [`RawFrame`] and read a raw's EXIF facts. Every
//! call into rawler runs inside [`guard::contain`], so a decoder panic on a
//! corrupt file becomes a [`RawError::DecoderPanic`] for that file.

use super::frame::{BlackLevels, CfaColour, CfaPattern, Ids, Layout, RawFrame, Samples};
use super::guard;
use crate::photo::exif::{ExifFacts, clean_text, try_facts_from_bytes};
use rawler::RawlerError;
use rawler::decoders::{RawDecodeParams, RawMetadata};
use rawler::rawimage::{RawImage, RawImageData, RawPhotometricInterpretation};
use rawler::rawsource::RawSource;
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

/// Turns a rawler error into ours, naming make and model (from `facts` when rawler has none).
fn map_error(path: &Path, e: RawlerError, facts: &ExifFacts) -> RawError {
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

/// Facts from rawler's metadata, filled in from the TIFF EXIF where kamadak-exif can read it.
pub(super) fn facts_of(
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
fn tiff_exif(buf: &[u8]) -> Option<ExifFacts> {
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
pub(super) fn tiff_exif_of_file(path: &Path) -> Option<ExifFacts> {
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

/// Decodes a camera raw whole through rawler (every format rawler reads);
/// [`decode_raw`] uses it for the files the windowed DNG reader does not handle.
pub fn decode_raw_with_rawler(path: &Path) -> Result<RawFrame, RawError> {
    let src = open(path)?;
    if let Some(cause) = super::dng::implausible_tiff_size(path) {
        return Err(RawError::Corrupt {
            path: path.display().to_string(),
            cause,
        });
    }
    // The TIFF EXIF copy is read and freed before the image buffer exists,
    // so the two never add up in the peak memory.
    let tiff = tiff_exif(src.buf());
    let outcome = guard::contain(|| {
        let decoder = rawler::get_decoder(&src)?;
        let params = RawDecodeParams::default();
        let meta = decoder.raw_metadata(&src, &params).ok();
        let format = format!("{:?}", decoder.format_hint());
        let image = decoder.raw_image(&src, &params, false)?;
        let deltas = if format == "DNG" {
            dng_black_deltas(&src)
        } else {
            Deltas::default()
        };
        Ok::<_, RawlerError>((image, meta, format, deltas))
    });
    let (image, meta, format, deltas) = match outcome {
        Ok(Ok(parts)) => parts,
        Ok(Err(e)) => {
            return Err(map_error(path, e, &tiff.unwrap_or_default()));
        }
        Err(message) => {
            return Err(RawError::DecoderPanic {
                path: path.display().to_string(),
                cause: message,
            });
        }
    };
    let facts = facts_of(meta.as_ref(), tiff, &image.make, &image.model);
    drop(src);
    let path_text = path.display().to_string();
    let frame = frame_from_image(image, format, facts, deltas).map(|mut f| {
        f.decoder = RAWLER.to_string();
        f
    });
    frame.map_err(|e| match e {
        Refusal::Unsupported { make, model, what } => RawError::Unsupported {
            path: path_text,
            make,
            model,
            what,
        },
        Refusal::Corrupt(cause) => RawError::Corrupt {
            path: path_text,
            cause,
        },
    })
}

enum Refusal {
    Unsupported {
        make: String,
        model: String,
        what: String,
    },
    Corrupt(String),
}

/// The frame rectangle (x, y, w, h): the default crop inside the active area, else the active area.
fn frame_rect(image: &RawImage) -> (usize, usize, usize, usize) {
    let full = (0, 0, image.width, image.height);
    let rect = |r: &rawler::imgop::Rect| (r.p.x, r.p.y, r.d.w, r.d.h);
    let inside = |(x, y, w, h): (usize, usize, usize, usize), (ox, oy, ow, oh)| {
        w > 0 && h > 0 && x >= ox && y >= oy && x + w <= ox + ow && y + h <= oy + oh
    };
    let active = image
        .active_area
        .as_ref()
        .map(rect)
        .filter(|&r| inside(r, full))
        .unwrap_or(full);
    image
        .crop_area
        .as_ref()
        .map(rect)
        .filter(|&r| inside(r, active))
        .unwrap_or(active)
}

/// DNG BlackLevelDeltaH (per active-area column) and BlackLevelDeltaV (per
/// active-area row), in DN; rawler 0.8.0 does not apply them.
#[derive(Debug, Default)]
pub(super) struct Deltas {
    /// Per active-area column (DN).
    pub h: Vec<f64>,
    /// Per active-area row (DN).
    pub v: Vec<f64>,
}

impl Deltas {
    /// Puts the deltas of the frame `(x0, y0, w, h)` (decoded-buffer pixels)
    /// into `black`; `active` = (x, y, w, h) is the active area the deltas
    /// run over. Deltas of the wrong length are ignored with a warning.
    pub(super) fn apply(
        &self,
        black: &mut BlackLevels,
        (x0, y0, w, h): (usize, usize, usize, usize),
        (ax, ay, aw, ah): (usize, usize, usize, usize),
        warnings: &mut Vec<String>,
    ) {
        for (name, d, start, len, full, out) in [
            (
                "BlackLevelDeltaH",
                &self.h,
                x0 - ax.min(x0),
                w,
                aw,
                &mut black.delta_h,
            ),
            (
                "BlackLevelDeltaV",
                &self.v,
                y0 - ay.min(y0),
                h,
                ah,
                &mut black.delta_v,
            ),
        ] {
            if d.is_empty() {
                continue;
            }
            if d.len() == full && start + len <= full && d.iter().all(|v| v.is_finite()) {
                *out = d[start..start + len].to_vec();
            } else {
                warnings.push(format!(
                    "{name} has {} values for an active area {full} px across (or unreadable values): ignored",
                    d.len()
                ));
            }
        }
    }
}

/// Reads BlackLevelDeltaH/V (tags 50715/50716) of the raw IFD rawler decodes
/// (the first full-resolution IFD with a supported compression); none if absent.
fn dng_black_deltas(src: &RawSource) -> Deltas {
    use rawler::formats::tiff::GenericTiffReader;
    use rawler::formats::tiff::reader::TiffReader;
    use rawler::tags::{DngTag, TiffCommonTag};
    let Ok(tiff) = GenericTiffReader::new(&mut src.reader(), 0, 0, None, &[]) else {
        return Deltas::default();
    };
    let raw = tiff
        .find_ifds_with_tag(TiffCommonTag::Compression)
        .into_iter()
        .find(|ifd| {
            let compression = ifd
                .get_entry(TiffCommonTag::Compression)
                .and_then(|e| e.value.get_u32(0).ok().flatten())
                .unwrap_or(0);
            let subsampled = ifd
                .get_entry(TiffCommonTag::NewSubFileType)
                .and_then(|e| e.value.get_u32(0).ok().flatten())
                .is_some_and(|t| t & 1 != 0);
            !subsampled && [1, 7, 8, 0x884c, 52546].contains(&compression)
        });
    let Some(raw) = raw else {
        return Deltas::default();
    };
    let read = |tag: DngTag| -> Vec<f64> {
        raw.get_entry(tag)
            .map(|e| {
                (0..e.count() as usize)
                    .map(|i| {
                        e.value
                            .get_f32(i)
                            .ok()
                            .flatten()
                            .map_or(f64::NAN, f64::from)
                    })
                    .collect()
            })
            .unwrap_or_default()
    };
    Deltas {
        h: read(DngTag::BlackLevelDeltaH),
        v: read(DngTag::BlackLevelDeltaV),
    }
}

fn frame_from_image(
    image: RawImage,
    format: String,
    mut facts: ExifFacts,
    deltas: Deltas,
) -> Result<RawFrame, Refusal> {
    let make = clean_text(&image.make).unwrap_or_default();
    let model = clean_text(&image.model).unwrap_or_default();
    let unsupported = |what: String| Refusal::Unsupported {
        make: make.clone(),
        model: model.clone(),
        what,
    };
    let spp = image.cpp;
    let (x0, y0, w, h) = frame_rect(&image);
    let cfa = match &image.photometric {
        RawPhotometricInterpretation::Cfa(config) => {
            let c = &config.cfa;
            if c.width == 0 || c.height == 0 {
                return Err(unsupported("a CFA raw without a CFA pattern".to_string()));
            }
            // rawler anchors the CFA at the decoded buffer's (0, 0); ours starts at the frame.
            let mut colours = Vec::with_capacity(c.width * c.height);
            for y in 0..c.height {
                for x in 0..c.width {
                    let colour = match c.color_at(y0 + y, x0 + x) {
                        0 => CfaColour::Red,
                        1 => CfaColour::Green,
                        2 => CfaColour::Blue,
                        _ => {
                            return Err(unsupported(format!(
                                "CFA pattern {} has colours other than R, G, B",
                                c.name
                            )));
                        }
                    };
                    colours.push(colour);
                }
            }
            Some(CfaPattern::from_colours(c.width, c.height, colours))
        }
        RawPhotometricInterpretation::LinearRaw | RawPhotometricInterpretation::BlackIsZero => {
            if spp != 1 && spp != 3 {
                return Err(unsupported(format!("{spp} samples per pixel")));
            }
            None
        }
    };
    let mut black = black_levels(&image, (x0, y0), spp);
    // The deltas run over the active area; the frame may start inside it (default crop).
    let (ax, ay, aw, ah) = image
        .active_area
        .as_ref()
        .map(|r| (r.p.x, r.p.y, r.d.w, r.d.h))
        .unwrap_or((0, 0, image.width, image.height));
    deltas.apply(
        &mut black,
        (x0, y0, w, h),
        (ax, ay, aw, ah),
        &mut facts.warnings,
    );
    let white: Vec<f64> = match image.whitelevel.0.len() {
        n if n == spp => image.whitelevel.0.iter().map(|&v| v as f64).collect(),
        0 => vec![((1u64 << image.bps.clamp(1, 16)) - 1) as f64; spp],
        _ => vec![image.whitelevel.0[0] as f64; spp],
    };
    let samples = match image.data {
        RawImageData::Integer(v) => Samples::U16(v),
        RawImageData::Float(v) => Samples::F32(v),
    };
    let layout = Layout {
        full_width: image.width,
        full_height: image.height,
        origin: (x0, y0),
        size: (w, h),
        samples: spp,
    };
    let ids = Ids {
        make: make.clone(),
        model: model.clone(),
        format,
        bits_per_sample: image.bps,
        facts,
    };
    RawFrame::assemble(layout, cfa, black, white, samples, ids).map_err(Refusal::Corrupt)
}

/// Black levels re-anchored at the frame's top-left pixel. DNG anchors its
/// BlackLevel repeat at the active area's corner; other formats at (0, 0).
fn black_levels(image: &RawImage, origin: (usize, usize), spp: usize) -> BlackLevels {
    let bl = &image.blacklevel;
    let levels: Vec<f64> = bl
        .levels
        .iter()
        .map(|r| {
            if r.d == 0 {
                0.0
            } else {
                r.n as f64 / r.d as f64
            }
        })
        .collect();
    let anchor = if image.camera.mode == "dng" {
        image
            .active_area
            .as_ref()
            .map(|r| (r.p.x, r.p.y))
            .unwrap_or((0, 0))
    } else {
        (0, 0)
    };
    BlackLevels::reanchored(levels, bl.width, bl.height, spp, anchor, origin)
}
