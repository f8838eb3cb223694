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

use super::decode::{Deltas, RawError, facts_of, tiff_exif_of_file};
use super::frame::{BlackLevels, CfaColour, CfaPattern, Ids, Layout, RawFrame, Samples};
use super::guard;
use crate::photo::exif::{ExifFacts, clean_text};
use rawler::decompressors::Decompressor;
use rawler::decompressors::ljpeg::LjpegDecompressor;
use rawler::decompressors::packed::PackedDecompressor;
use rawler::formats::tiff::reader::TiffReader;
use rawler::formats::tiff::{GenericTiffReader, IFD, Value};
use rawler::tags::{DngTag, TiffCommonTag};
use rayon::prelude::*;
use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;
use std::sync::Mutex;

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

fn count(ifd: &IFD, tag: impl rawler::tags::TiffTag) -> usize {
    ifd.get_entry(tag).map_or(0, |e| e.count() as usize)
}

fn usize_at(ifd: &IFD, tag: impl rawler::tags::TiffTag, i: usize) -> Option<usize> {
    ifd.get_entry(tag)
        .and_then(|e| e.value.get_usize(i).ok().flatten())
}

/// n / d, NaN for a zero denominator.
fn ratio(n: f64, d: f64) -> f64 {
    if d == 0.0 { f64::NAN } else { n / d }
}

fn f64s(ifd: &IFD, tag: impl rawler::tags::TiffTag) -> Option<Vec<f64>> {
    let e = ifd.get_entry(tag)?;
    let v: Option<Vec<f64>> = match &e.value {
        Value::Short(v) => Some(v.iter().map(|&x| x as f64).collect()),
        Value::Long(v) => Some(v.iter().map(|&x| x as f64).collect()),
        Value::Rational(v) => Some(v.iter().map(|r| ratio(r.n as f64, r.d as f64)).collect()),
        Value::SRational(v) => Some(v.iter().map(|r| ratio(r.n as f64, r.d as f64)).collect()),
        Value::Float(v) => Some(v.iter().map(|&x| x as f64).collect()),
        Value::Double(v) => Some(v.clone()),
        _ => None,
    };
    v
}

fn bytes(ifd: &IFD, tag: impl rawler::tags::TiffTag) -> Option<Vec<u8>> {
    match &ifd.get_entry(tag)?.value {
        Value::Byte(v) | Value::Undefined(v) => Some(v.clone()),
        Value::Short(v) => v.iter().map(|&x| u8::try_from(x).ok()).collect(),
        _ => None,
    }
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

/// Opens the file and parses its TIFF structure through a reader: the file,
/// its length and the IFDs, or `None` when it is not a TIFF-based DNG (or
/// its structure does not parse; rawler then gives its verdict).
fn open_dng(path: &Path) -> Result<Option<(File, u64, GenericTiffReader)>, RawError> {
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
fn facts_and_names(path: &Path, tiff: &GenericTiffReader) -> (ExifFacts, String, String) {
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

/// The EXIF facts of a DNG read without rawler (see [`facts_and_names`]), or
/// `None` when the file is not a DNG this reader parses.
pub(crate) fn read_dng_facts(path: &Path) -> Result<Option<ExifFacts>, RawError> {
    Ok(open_dng(path)?.map(|(_, _, tiff)| facts_and_names(path, &tiff).0))
}

/// Samples one image of a raw may plausibly hold: no camera makes a
/// gigasample frame, so a header saying so is damaged.
const MAX_SAMPLES: usize = 1 << 30;

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

/// The raw IFD rawler decodes: the first full-resolution IFD with a supported compression.
fn raw_ifd(tiff: &GenericTiffReader) -> Option<&IFD> {
    tiff.find_ifds_with_tag(TiffCommonTag::Compression)
        .into_iter()
        .find(|ifd| {
            let compression = usize_at(ifd, TiffCommonTag::Compression, 0).unwrap_or(0);
            let subsampled =
                usize_at(ifd, TiffCommonTag::NewSubFileType, 0).is_some_and(|t| t & 1 != 0);
            !subsampled && [1, 7, 8, 0x884c, 52546].contains(&compression)
        })
}

fn frame_of(
    path: &Path,
    tiff: &GenericTiffReader,
    source: &Source,
    want: Option<FrameRect>,
) -> Result<Dng, RawError> {
    let rawler = |why: &str| Ok(Dng::Rawler(why.to_string()));
    let corrupt = |cause: String| RawError::Corrupt {
        path: path.display().to_string(),
        cause,
    };
    let Some(raw) = raw_ifd(tiff) else {
        return rawler("no raw IFD with a supported compression");
    };
    let width = usize_at(raw, TiffCommonTag::ImageWidth, 0).unwrap_or(0);
    let height = usize_at(raw, TiffCommonTag::ImageLength, 0).unwrap_or(0);
    let spp = usize_at(raw, TiffCommonTag::SamplesPerPixel, 0).unwrap_or(1);
    let bits = usize_at(raw, TiffCommonTag::BitsPerSample, 0).unwrap_or(0);
    let compression = usize_at(raw, TiffCommonTag::Compression, 0).unwrap_or(0);
    let photometric = usize_at(raw, TiffCommonTag::PhotometricInt, 0).unwrap_or(0);
    let sample_format = usize_at(raw, TiffCommonTag::SampleFormat, 0).unwrap_or(1);
    if width == 0 || height == 0 || !(1..=16).contains(&bits) || sample_format != 1 {
        return rawler("not 1–16-bit unsigned samples");
    }
    // No camera makes a gigasample frame: a header saying so is damaged.
    if width
        .checked_mul(height)
        .and_then(|n| n.checked_mul(spp))
        .is_none_or(|n| n > MAX_SAMPLES)
    {
        return Err(corrupt(format!(
            "an implausible image size ({width}×{height}×{spp} samples)"
        )));
    }
    if raw.has_entry(TiffCommonTag::Linearization)
        || usize_at(raw, DngTag::RowInterleaveFactor, 0).unwrap_or(1) != 1
        || usize_at(raw, DngTag::ColumnInterleaveFactor, 0).unwrap_or(1) != 1
    {
        return rawler("linearisation table or interleaved rows/columns");
    }
    let codec = match compression {
        1 => Codec::Packed,
        7 if bits > 8 => Codec::Ljpeg,
        _ => return rawler("compression other than none or lossless JPEG"),
    };
    let cfa_image = match (photometric, spp) {
        (32803, 1) => true,
        (34892, 1 | 3) => false,
        _ => return rawler("neither a one-sample CFA nor linear raw"),
    };
    // Active area [top, left, bottom, right], then the default crop inside it.
    let full = (0, 0, width, height);
    let inside = |(x, y, w, h): (usize, usize, usize, usize),
                  (ox, oy, ow, oh): (usize, usize, usize, usize)| {
        w > 0 && h > 0 && x >= ox && y >= oy && x + w <= ox + ow && y + h <= oy + oh
    };
    let active = (count(raw, DngTag::ActiveArea) == 4)
        .then(|| {
            let a = (0..4).map(|i| usize_at(raw, DngTag::ActiveArea, i));
            let a: Option<Vec<usize>> = a.collect();
            a.and_then(|a| {
                (a[2] > a[0] && a[3] > a[1]).then_some((a[1], a[0], a[3] - a[1], a[2] - a[0]))
            })
        })
        .flatten()
        .filter(|&r| inside(r, full));
    let (ax, ay, aw, ah) = active.unwrap_or(full);
    let crop = match (
        f64s(raw, DngTag::DefaultCropOrigin),
        f64s(raw, DngTag::DefaultCropSize),
    ) {
        (Some(o), Some(s)) if o.len() >= 2 && s.len() >= 2 => {
            let u = |v: f64| (v.is_finite() && v >= 0.0).then_some(v as usize);
            match (u(o[0]), u(o[1]), u(s[0]), u(s[1])) {
                (Some(x), Some(y), Some(w), Some(h)) => Some((ax + x, ay + y, w, h)),
                _ => None,
            }
        }
        _ => None,
    };
    let (fx, fy, fw, fh) = crop
        .filter(|&r| inside(r, (ax, ay, aw, ah)))
        .unwrap_or((ax, ay, aw, ah));

    // CFA pattern from the frame's top-left pixel (DNG anchors it at the active area).
    let cfa = if cfa_image {
        let dims = (
            usize_at(raw, TiffCommonTag::CFARepeatPatternDim, 0).unwrap_or(2),
            usize_at(raw, TiffCommonTag::CFARepeatPatternDim, 1).unwrap_or(2),
        );
        let (ph, pw) = dims;
        let Some(pattern) = bytes(raw, TiffCommonTag::CFAPattern) else {
            return rawler("no readable CFAPattern");
        };
        if pw == 0 || ph == 0 || pattern.len() != pw * ph || pw * ph != 4 {
            return rawler("a CFA repeat other than 2×2");
        }
        let planes = bytes(raw, DngTag::CFAPlaneColor).unwrap_or(vec![0, 1, 2]);
        let mut colours = Vec::with_capacity(4);
        for y in 0..ph {
            for x in 0..pw {
                let v = pattern[((y + fy - ay) % ph) * pw + (x + fx - ax) % pw];
                let colour = match planes.get(v as usize) {
                    Some(0) => CfaColour::Red,
                    Some(1) => CfaColour::Green,
                    Some(2) => CfaColour::Blue,
                    _ => return rawler("CFA colours other than R, G, B"),
                };
                colours.push(colour);
            }
        }
        Some(CfaPattern::from_colours(pw, ph, colours))
    } else {
        None
    };

    // Black levels (repeat anchored at the active area's corner) and deltas.
    let levels: Vec<f64> = f64s(raw, TiffCommonTag::BlackLevels)
        .unwrap_or_default()
        .into_iter()
        .map(|v| if v.is_finite() { v } else { 0.0 })
        .collect();
    let (brows, bcols) = match f64s(raw, DngTag::BlackLevelRepeatDim) {
        Some(d) if d.len() == 2 => (d[0] as usize, d[1] as usize),
        _ => (1, 1),
    };
    let mut black = if levels.is_empty() {
        BlackLevels::uniform(0.0, spp)
    } else {
        BlackLevels::reanchored(levels, bcols, brows, spp, (ax, ay), (fx, fy))
    };
    let (mut facts, make, model) = facts_and_names(path, tiff);
    let deltas = Deltas {
        h: f64s(raw, DngTag::BlackLevelDeltaH).unwrap_or_default(),
        v: f64s(raw, DngTag::BlackLevelDeltaV).unwrap_or_default(),
    };
    deltas.apply(
        &mut black,
        (fx, fy, fw, fh),
        (ax, ay, aw, ah),
        &mut facts.warnings,
    );
    let white: Vec<f64> = match f64s(raw, TiffCommonTag::WhiteLevel) {
        Some(w) if w.len() == spp => w,
        Some(w) if !w.is_empty() => vec![w[0]; spp],
        _ => vec![((1u64 << bits) - 1) as f64; spp],
    };
    // The units (tiles or strips) and the wanted rectangle in image pixels.
    let tiled = raw.has_entry(TiffCommonTag::TileOffsets);
    let units = if tiled {
        let (tw, th) = (
            usize_at(raw, TiffCommonTag::TileWidth, 0).unwrap_or(0),
            usize_at(raw, TiffCommonTag::TileLength, 0).unwrap_or(0),
        );
        if tw == 0 || th == 0 {
            return Err(corrupt("tiles of zero size".into()));
        }
        unit_table(
            raw,
            TiffCommonTag::TileOffsets,
            TiffCommonTag::TileByteCounts,
            tw,
            th,
            width,
        )
    } else {
        let rps = usize_at(raw, TiffCommonTag::RowsPerStrip, 0)
            .unwrap_or(height)
            .clamp(1, height);
        unit_table(
            raw,
            TiffCommonTag::StripOffsets,
            TiffCommonTag::StripByteCounts,
            width,
            rps,
            width,
        )
    };
    let down = height.div_ceil(units.h);
    if units.offsets.len() != units.across * down || units.counts.len() != units.offsets.len() {
        return Err(corrupt(format!(
            "{} data offsets and {} byte counts where {}×{} {} are needed",
            units.offsets.len(),
            units.counts.len(),
            down,
            units.across,
            if tiled { "tiles" } else { "strips" }
        )));
    }
    let (wx0, wy0, wx1, wy1) = want.unwrap_or((0, 0, fw, fh));
    let (wx0, wy0, wx1, wy1) = (wx0.min(fw), wy0.min(fh), wx1.min(fw), wy1.min(fh));
    let decoded = if wx0 < wx1 && wy0 < wy1 {
        (wx0, wy0, wx1, wy1)
    } else {
        (0, 0, 0, 0)
    };
    // Lazily zeroed: pages outside the decoded rectangle are never touched.
    let mut out = crate::photo::hugebuf::zeroed::<u16>(fw * fh * spp);
    if decoded.2 > decoded.0 {
        let job = Job {
            codec,
            bits: bits as u32,
            endian: raw.endian,
            spp,
            width,
            units: &units,
            frame: (fx, fy, fw),
            want: (
                fx + decoded.0,
                fy + decoded.1,
                fx + decoded.2,
                fy + decoded.3,
            ),
        };
        job.run(source, &mut out).map_err(corrupt)?;
    }
    let layout = Layout {
        full_width: fw,
        full_height: fh,
        origin: (0, 0),
        size: (fw, fh),
        samples: spp,
    };
    let ids = Ids {
        make,
        model,
        format: "DNG".to_string(),
        bits_per_sample: bits,
        facts,
    };
    let mut frame =
        RawFrame::assemble(layout, cfa, black, white, Samples::U16(out), ids).map_err(corrupt)?;
    frame.decoded = decoded;
    Ok(Dng::Frame(Box::new(frame)))
}

fn unit_table(
    raw: &IFD,
    offsets: TiffCommonTag,
    counts: TiffCommonTag,
    w: usize,
    h: usize,
    width: usize,
) -> Units {
    let list = |tag| -> Vec<u64> {
        raw.get_entry(tag)
            .map(|e| {
                (0..e.count() as usize)
                    .map(|i| e.value.get_u32(i).ok().flatten().unwrap_or(0) as u64)
                    .collect()
            })
            .unwrap_or_default()
    };
    Units {
        w,
        h,
        across: width.div_ceil(w),
        offsets: list(offsets),
        counts: list(counts),
    }
}

thread_local! {
    /// Per-thread buffers reused from unit to unit: the unit's bytes and its decoded samples.
    static SCRATCH: std::cell::RefCell<(Vec<u8>, Vec<u16>)> = const {
        std::cell::RefCell::new((Vec::new(), Vec::new()))
    };
}

/// Scratch capacity (elements) kept per thread between decodes: enough for
/// common strips and tiles (a 16-row strip of 6000 px is 96 k samples).
const SCRATCH_KEEP: usize = 1 << 20;

/// Rows of an uncompressed unit decoded per task.
const PACKED_ROWS: usize = 64;

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

impl Job<'_> {
    /// Decodes every unit meeting the wanted rectangle into `out` (the frame
    /// buffer), one band of unit rows per parallel task.
    fn run(&self, source: &Source, out: &mut [u16]) -> Result<(), String> {
        let u = self.units;
        let (_, fy, fw) = self.frame;
        let (x0, y0, x1, y1) = self.want;
        let row_len = fw * self.spp;
        // Frame rows y0..y1 split at unit-row boundaries, each band with its
        // slice; uncompressed units (which can start at any row) also every
        // PACKED_ROWS rows, so that one big strip still decodes in parallel
        // through a small buffer.
        let step = match self.codec {
            Codec::Packed => PACKED_ROWS,
            Codec::Ljpeg => u.h,
        };
        let mut bands = Vec::new();
        let mut rest = &mut out[(y0 - fy) * row_len..(y1 - fy) * row_len];
        let mut y = y0;
        while y < y1 {
            let band = y / u.h;
            let end = ((band + 1) * u.h).min((y / step + 1) * step).min(y1);
            let (head, tail) = rest.split_at_mut((end - y) * row_len);
            bands.push((band, y, end, head));
            rest = tail;
            y = end;
        }
        let (c0, c1) = (x0 / u.w, (x1 - 1) / u.w + 1);
        bands.into_par_iter().try_for_each(|(band, ya, yb, dst)| {
            for col in c0..c1.min(u.across) {
                self.unit(source, band, col, (ya, yb), dst)?;
            }
            Ok::<(), String>(())
        })
    }

    /// Decodes image rows `rows` of unit (`band`, `col`) and copies the wanted
    /// columns into `dst` (the frame rows `rows`).
    fn unit(
        &self,
        source: &Source,
        band: usize,
        col: usize,
        rows: (usize, usize),
        dst: &mut [u16],
    ) -> Result<(), String> {
        let u = self.units;
        let i = band * u.across + col;
        let (ux, uy) = (col * u.w, band * u.h);
        let line = u.w * self.spp;
        let (r0, r1) = (rows.0 - uy, rows.1 - uy);
        let (offset, count) = (u.offsets[i], u.counts[i]);
        SCRATCH.with(|scratch| {
            let (bytes, samples) = &mut *scratch.borrow_mut();
            // `samples` from `first` on: the unit's rows r0..r1, `line` samples each.
            let first = match self.codec {
                Codec::Packed => {
                    let row_bits = line as u64 * self.bits as u64;
                    let need = (r1 as u64 * row_bits).div_ceil(8);
                    if need > count {
                        return Err(format!(
                            "unit {i} holds {count} bytes where {need} are needed"
                        ));
                    }
                    // Whole bytes up to the first wanted row are skipped when rows are byte aligned.
                    let (start, skip) = if row_bits.is_multiple_of(8) {
                        (r0 as u64 * row_bits / 8, 0)
                    } else {
                        (0, r0)
                    };
                    source.read_into(offset + start, need - start, bytes)?;
                    samples.resize((r1 - r0) * line, 0);
                    PackedDecompressor::new(self.bits, self.endian).decompress(
                        bytes,
                        skip,
                        samples.chunks_exact_mut(line),
                        line,
                    )?;
                    0
                }
                Codec::Ljpeg => {
                    source.read_into(offset, count, bytes)?;
                    // The whole unit is decoded (into the reused buffer); rows r0.. are kept.
                    let d = LjpegDecompressor::new(bytes)?;
                    let (w, h) = (d.width(), d.height());
                    if w != line || h < r1 {
                        return Err(format!(
                            "unit {i} decodes to {w}×{h} samples where {line}×{} are expected",
                            r1
                        ));
                    }
                    samples.resize(w * h, 0);
                    d.decode(samples, 0, w, w, h, false)?;
                    r0 * line
                }
            };
            self.place(&samples[first..first + (r1 - r0) * line], ux, dst);
            // Big units (one strip for the whole image) are not kept alive per thread.
            if samples.capacity() > SCRATCH_KEEP {
                *samples = Vec::new();
            }
            if bytes.capacity() > SCRATCH_KEEP {
                *bytes = Vec::new();
            }
            Ok(())
        })
    }

    /// Copies the unit rows in `rows` (unit width, starting at image column
    /// `ux`) into the frame rows `dst`, the columns inside the image, the
    /// frame and the wanted range only.
    fn place(&self, rows: &[u16], ux: usize, dst: &mut [u16]) {
        let u = self.units;
        let line = u.w * self.spp;
        // Columns of this unit inside the image, the frame and the wanted range.
        let (fx, _, fw) = self.frame;
        let xa = ux.max(self.want.0).max(fx);
        let xb = (ux + u.w).min(self.width).min(self.want.2).min(fx + fw);
        if xa >= xb {
            return;
        }
        let row_len = fw * self.spp;
        let n = (xb - xa) * self.spp;
        for (k, src_row) in rows.chunks_exact(line).enumerate() {
            let s = (xa - ux) * self.spp;
            let d = k * row_len + (xa - fx) * self.spp;
            dst[d..d + n].copy_from_slice(&src_row[s..s + n]);
        }
    }
}
