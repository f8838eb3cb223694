//! The raw IFD's metadata read into a frame: size, codec, active area and
//! default crop, CFA pattern, black and white levels, and the strips or tiles
//! holding the wanted rectangle, which are then decoded.

use super::open::{MAX_SAMPLES, facts_and_names};
use super::tags::{bytes, count, f64s, usize_at};
use super::{Codec, Dng, FrameRect, Job, Source, Units};
use crate::photo::raw::decode::{Deltas, RawError};
use crate::photo::raw::frame::{
    BlackLevels, CfaColour, CfaPattern, Ids, Layout, RawFrame, Samples,
};
use rawler::formats::tiff::reader::TiffReader;
use rawler::formats::tiff::{GenericTiffReader, IFD};
use rawler::tags::{DngTag, TiffCommonTag};
use std::path::Path;

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

pub(super) fn frame_of(
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
