//! A minimal DNG writer for simulated Bayer shots: one little-endian TIFF
//! file, the 16-bit CFA mosaic in IFD 0 (one uncompressed strip, or
//! lossless-JPEG strips of 16 rows as most cameras compress), with the
//! DNG tags a raw decoder needs (CFA pattern, per-site black levels, white
//! level, active area with masked borders, optional BlackLevelDeltaH/V and
//! orientation) and an EXIF IFD carrying the pixel pitch as
//! FocalPlaneX/YResolution (in pixels per centimetre).
//!
//! The generic part ([`tiff_bytes`], [`TagValue`]) writes any IFD 0 tags and
//! one EXIF sub-IFD, so tests can build odd DNGs with the same code.

use super::{BayerOrder, Camera, SimError};
use rayon::prelude::*;

/// The value of one TIFF tag.
#[derive(Debug, Clone, PartialEq)]
pub enum TagValue {
    /// BYTE (type 1).
    Byte(Vec<u8>),
    /// ASCII (type 2); the NUL terminator is added.
    Ascii(String),
    /// SHORT (type 3).
    Short(Vec<u16>),
    /// LONG (type 4).
    Long(Vec<u32>),
    /// RATIONAL (type 5): numerator, denominator.
    Rational(Vec<(u32, u32)>),
    /// SRATIONAL (type 10): numerator, denominator.
    SRational(Vec<(i32, i32)>),
}

impl TagValue {
    fn type_and_count(&self) -> (u16, usize) {
        match self {
            TagValue::Byte(v) => (1, v.len()),
            TagValue::Ascii(s) => (2, s.len() + 1),
            TagValue::Short(v) => (3, v.len()),
            TagValue::Long(v) => (4, v.len()),
            TagValue::Rational(v) => (5, v.len()),
            TagValue::SRational(v) => (10, v.len()),
        }
    }

    fn bytes(&self) -> Vec<u8> {
        match self {
            TagValue::Byte(v) => v.clone(),
            TagValue::Ascii(s) => {
                let mut b = s.as_bytes().to_vec();
                b.push(0);
                b
            }
            TagValue::Short(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            TagValue::Long(v) => v.iter().flat_map(|x| x.to_le_bytes()).collect(),
            TagValue::Rational(v) => v
                .iter()
                .flat_map(|(n, d)| n.to_le_bytes().into_iter().chain(d.to_le_bytes()))
                .collect(),
            TagValue::SRational(v) => v
                .iter()
                .flat_map(|(n, d)| n.to_le_bytes().into_iter().chain(d.to_le_bytes()))
                .collect(),
        }
    }
}

/// One IFD laid out at file offset `at`: the entry table, then its out-of-line
/// values (each padded to even length).
fn layout_ifd(tags: &[(u16, TagValue)], at: usize) -> Vec<u8> {
    let n = tags.len();
    let mut extra_at = at + 2 + 12 * n + 4;
    let mut table = Vec::with_capacity(2 + 12 * n + 4);
    let mut extra = Vec::new();
    table.extend((n as u16).to_le_bytes());
    for (tag, v) in tags {
        let (typ, count) = v.type_and_count();
        let b = v.bytes();
        table.extend(tag.to_le_bytes());
        table.extend(typ.to_le_bytes());
        table.extend((count as u32).to_le_bytes());
        if b.len() <= 4 {
            let mut w = b;
            w.resize(4, 0);
            table.extend(w);
        } else {
            table.extend((extra_at as u32).to_le_bytes());
            let padded = b.len() + (b.len() & 1);
            extra.extend(&b);
            extra.resize(extra.len() + (b.len() & 1), 0);
            extra_at += padded;
        }
    }
    table.extend(0u32.to_le_bytes()); // no next IFD
    table.extend(extra);
    table
}

/// A little-endian TIFF file: IFD 0 with `tags` (any order; StripOffsets 273,
/// StripByteCounts 279 and, when `exif` is not empty, the EXIF IFD pointer
/// 34665 are added here), the EXIF IFD with `exif`, then `strip` as IFD 0's
/// only strip.
pub fn tiff_bytes(tags: &[(u16, TagValue)], exif: &[(u16, TagValue)], strip: &[u8]) -> Vec<u8> {
    tiff_with_chunks(tags, exif, &[strip], (273, 279))
}

/// Like [`tiff_bytes`] with several data chunks (strips or tiles) whose
/// offsets and byte counts go into the tags `(offsets, counts)`: (273, 279)
/// for strips, (324, 325) for tiles.
pub fn tiff_with_chunks(
    tags: &[(u16, TagValue)],
    exif: &[(u16, TagValue)],
    chunks: &[&[u8]],
    (offsets_tag, counts_tag): (u16, u16),
) -> Vec<u8> {
    let mut ifd0: Vec<(u16, TagValue)> = tags
        .iter()
        .filter(|(t, _)| !matches!(*t, 273 | 279 | 324 | 325 | 34665))
        .cloned()
        .collect();
    ifd0.push((offsets_tag, TagValue::Long(vec![0; chunks.len()])));
    ifd0.push((
        counts_tag,
        TagValue::Long(chunks.iter().map(|c| c.len() as u32).collect()),
    ));
    if !exif.is_empty() {
        ifd0.push((34665, TagValue::Long(vec![0])));
    }
    ifd0.sort_by_key(|t| t.0);
    let mut exif: Vec<(u16, TagValue)> = exif.to_vec();
    exif.sort_by_key(|t| t.0);
    // The sizes do not depend on the offsets' values: lay out once to measure, then for real.
    let ifd0_at = 8;
    let ifd0_len = layout_ifd(&ifd0, ifd0_at).len();
    let exif_at = ifd0_at + ifd0_len;
    let exif_len = if exif.is_empty() {
        0
    } else {
        layout_ifd(&exif, exif_at).len()
    };
    let data_at = exif_at + exif_len;
    let mut offsets = Vec::with_capacity(chunks.len());
    let mut at = data_at;
    for c in chunks {
        offsets.push(at as u32);
        at += c.len() + (c.len() & 1);
    }
    for (tag, v) in ifd0.iter_mut() {
        if *tag == offsets_tag {
            *v = TagValue::Long(offsets.clone());
        } else if *tag == 34665 {
            *v = TagValue::Long(vec![exif_at as u32]);
        }
    }
    let mut file = Vec::with_capacity(at);
    file.extend(b"II*\0");
    file.extend((ifd0_at as u32).to_le_bytes());
    file.extend(layout_ifd(&ifd0, ifd0_at));
    if !exif.is_empty() {
        file.extend(layout_ifd(&exif, exif_at));
    }
    debug_assert_eq!(file.len(), data_at);
    for c in chunks {
        file.extend_from_slice(c);
        if c.len() & 1 == 1 {
            file.push(0);
        }
    }
    file
}

/// How a simulated mosaic is stored in a DNG (levels in DN of the 16-bit samples).
#[derive(Debug, Clone, PartialEq)]
pub struct DngSettings {
    /// Black level of each site of the 2×2 repeat from the active area's corner, row-major (DN).
    pub black: [u16; 4],
    /// White (clipping) level (DN).
    pub white: u16,
    /// Masked border around the image on every side (pixels): the active area starts here.
    pub margin_px: usize,
    /// EXIF/TIFF orientation code 1–8 (1 = as stored).
    pub orientation: u16,
    /// BlackLevelDeltaH: per active-area column, added to the black level (DN); empty = none.
    pub black_delta_h: Vec<f64>,
    /// BlackLevelDeltaV: per active-area row, added to the black level (DN); empty = none.
    pub black_delta_v: Vec<f64>,
    /// Store the mosaic as lossless-JPEG strips of 16 rows (DNG compression 7)
    /// instead of one uncompressed strip; needs an even sensor width.
    pub lossless_jpeg: bool,
    /// With `lossless_jpeg`: square tiles of this many pixels (a multiple of
    /// 16, as DNG asks; edge tiles padded by repeating the last column and
    /// row) instead of strips of 16 rows; 0 = strips.
    pub tile_px: usize,
    /// Make (TIFF tag 271).
    pub make: String,
    /// Model (TIFF tag 272); UniqueCameraModel is "make model".
    pub model: String,
}

impl Default for DngSettings {
    fn default() -> Self {
        DngSettings {
            black: [1024, 1028, 1020, 1024],
            white: 64000,
            margin_px: 8,
            orientation: 1,
            black_delta_h: Vec::new(),
            black_delta_v: Vec::new(),
            lossless_jpeg: false,
            tile_px: 0,
            make: "sweepmtf".to_string(),
            model: "simulated".to_string(),
        }
    }
}

/// A DN value as an SRATIONAL with denominator 1000.
fn srational(v: f64) -> (i32, i32) {
    ((v * 1000.0).round() as i32, 1000)
}

/// Encodes a linear mosaic (`width × height`, 1.0 = clipping, colours in `order`
/// from the top-left pixel) as a DNG with `settings`; the pixel pitch (µm) goes
/// into the EXIF FocalPlaneX/YResolution.
pub fn encode_mosaic(
    linear: &[f32],
    width: usize,
    height: usize,
    order: BayerOrder,
    pixel_pitch_um: f64,
    s: &DngSettings,
) -> Result<Vec<u8>, SimError> {
    let bad = |m: String| Err(SimError::Parameter(m));
    if linear.len() != width * height || width == 0 || height == 0 {
        return bad(format!(
            "DNG: {} samples for a {width}×{height} mosaic",
            linear.len()
        ));
    }
    if s.black.iter().any(|&b| b >= s.white) {
        return bad(format!(
            "DNG: black levels {:?} must lie below the white level {}",
            s.black, s.white
        ));
    }
    if !(1..=8).contains(&s.orientation) {
        return bad(format!("DNG: orientation {} is not 1–8", s.orientation));
    }
    if !(s.black_delta_h.is_empty() || s.black_delta_h.len() == width)
        || !(s.black_delta_v.is_empty() || s.black_delta_v.len() == height)
    {
        return bad("DNG: BlackLevelDeltaH/V need one value per column / row".into());
    }
    let m = s.margin_px;
    let (fw, fh) = (width + 2 * m, height + 2 * m);
    if fw > u32::MAX as usize / 2 || (fw * fh * 2) > u32::MAX as usize {
        return bad(format!("DNG: {fw}×{fh} px is too large for one TIFF strip"));
    }
    let delta = |x: usize, y: usize| {
        s.black_delta_h.get(x).copied().unwrap_or(0.0)
            + s.black_delta_v.get(y).copied().unwrap_or(0.0)
    };
    // Active-area pixel (x, y): black of its site plus the deltas; masked pixels
    // hold the black pattern continued (anchored at the active area's corner).
    let mut dns = vec![0u16; fw * fh];
    for (fy, row) in dns.chunks_exact_mut(fw).enumerate() {
        for (fx, out) in row.iter_mut().enumerate() {
            let (ax, ay) = (fx.wrapping_sub(m), fy.wrapping_sub(m));
            let inside = ax < width && ay < height;
            let site = ((fy + 2 - m % 2) % 2) * 2 + (fx + 2 - m % 2) % 2;
            let black = s.black[site] as f64;
            let dn = if inside {
                let b = black + delta(ax, ay);
                let v = linear[ay * width + ax].clamp(0.0, 1.0) as f64;
                b + v * (s.white as f64 - b)
            } else {
                black
            };
            *out = dn.round().clamp(0.0, 65535.0) as u16;
        }
    }
    let pattern: Vec<u8> = [(0, 0), (1, 0), (0, 1), (1, 1)]
        .iter()
        .map(|&(x, y)| order.colour_at(x, y) as u8)
        .collect();
    let unique = format!("{} {}", s.make, s.model);
    let mut tags: Vec<(u16, TagValue)> = vec![
        (254, TagValue::Long(vec![0])),
        (256, TagValue::Long(vec![fw as u32])),
        (257, TagValue::Long(vec![fh as u32])),
        (258, TagValue::Short(vec![16])),
        (259, TagValue::Short(vec![1])),
        (262, TagValue::Short(vec![32803])),
        (271, TagValue::Ascii(s.make.clone())),
        (272, TagValue::Ascii(s.model.clone())),
        (274, TagValue::Short(vec![s.orientation])),
        (277, TagValue::Short(vec![1])),
        (284, TagValue::Short(vec![1])),
        (305, TagValue::Ascii("sweepmtf simulate".into())),
        (33421, TagValue::Short(vec![2, 2])),
        (33422, TagValue::Byte(pattern)),
        (50706, TagValue::Byte(vec![1, 4, 0, 0])),
        (50707, TagValue::Byte(vec![1, 1, 0, 0])),
        (50708, TagValue::Ascii(unique)),
        (50713, TagValue::Short(vec![2, 2])),
        (
            50714,
            TagValue::Long(s.black.iter().map(|&b| b as u32).collect()),
        ),
        (50717, TagValue::Long(vec![s.white as u32])),
        (
            50829,
            TagValue::Long(vec![
                m as u32,
                m as u32,
                (m + height) as u32,
                (m + width) as u32,
            ]),
        ),
    ];
    if !s.black_delta_h.is_empty() {
        tags.push((
            50715,
            TagValue::SRational(s.black_delta_h.iter().map(|&v| srational(v)).collect()),
        ));
    }
    if !s.black_delta_v.is_empty() {
        tags.push((
            50716,
            TagValue::SRational(s.black_delta_v.iter().map(|&v| srational(v)).collect()),
        ));
    }
    let mut exif = Vec::new();
    if pixel_pitch_um > 0.0 && pixel_pitch_um.is_finite() {
        // pixels per centimetre = 10 mm / pitch, as 10⁷ / pitch in nm
        let nm = (pixel_pitch_um * 1000.0).round().max(1.0) as u32;
        exif.push((41486, TagValue::Rational(vec![(10_000_000, nm)])));
        exif.push((41487, TagValue::Rational(vec![(10_000_000, nm)])));
        exif.push((41488, TagValue::Short(vec![3])));
    }
    if !s.lossless_jpeg {
        tags.push((278, TagValue::Long(vec![fh as u32])));
        let strip: Vec<u8> = dns.iter().flat_map(|d| d.to_le_bytes()).collect();
        return Ok(tiff_bytes(&tags, &exif, &strip));
    }
    // Strips of ROWS rows, each one lossless JPEG (two interleaved components
    // of half the width, as DNG writers do). Strips, not padded tiles: rawler
    // crops a padded image by copying it, which would double its peak memory.
    const ROWS: usize = 16;
    tags.retain(|(t, _)| *t != 259);
    tags.push((259, TagValue::Short(vec![7])));
    if s.tile_px > 0 {
        let t = s.tile_px;
        if !t.is_multiple_of(16) {
            return bad(format!("DNG: tiles of {t} px are not a multiple of 16"));
        }
        tags.push((322, TagValue::Long(vec![t as u32])));
        tags.push((323, TagValue::Long(vec![t as u32])));
        let (across, down) = (fw.div_ceil(t), fh.div_ceil(t));
        let tiles: Result<Vec<Vec<u8>>, String> = (0..across * down)
            .into_par_iter()
            .map(|i| {
                let (x0, y0) = ((i % across) * t, (i / across) * t);
                let tile: Vec<u16> = (0..t * t)
                    .map(|k| {
                        let x = (x0 + k % t).min(fw - 1);
                        let y = (y0 + k / t).min(fh - 1);
                        dns[y * fw + x]
                    })
                    .collect();
                crate::photo::raw::lossless_jpeg_cfa_tile(&tile, t, t)
            })
            .collect();
        let tiles = tiles.map_err(|e| SimError::Encode(format!("DNG lossless JPEG: {e}")))?;
        let chunks: Vec<&[u8]> = tiles.iter().map(Vec::as_slice).collect();
        return Ok(tiff_with_chunks(&tags, &exif, &chunks, (324, 325)));
    }
    tags.push((278, TagValue::Long(vec![ROWS as u32])));
    let strips: Result<Vec<Vec<u8>>, String> = dns
        .par_chunks(ROWS * fw)
        .map(|rows| crate::photo::raw::lossless_jpeg_cfa_tile(rows, fw, rows.len() / fw))
        .collect();
    let strips = strips.map_err(|e| SimError::Encode(format!("DNG lossless JPEG: {e}")))?;
    let chunks: Vec<&[u8]> = strips.iter().map(Vec::as_slice).collect();
    Ok(tiff_with_chunks(&tags, &exif, &chunks, (273, 279)))
}

/// Encodes the camera's recorded mosaic as a DNG with the default [`DngSettings`].
pub fn encode(camera: &Camera, linear: &[f32]) -> Result<Vec<u8>, SimError> {
    let order = camera.bayer.ok_or_else(|| {
        SimError::Parameter(
            "a DNG holds a Bayer mosaic: give --bayer RGGB (or another order)".into(),
        )
    })?;
    encode_mosaic(
        linear,
        camera.width_px,
        camera.height_px,
        order,
        camera.pixel_pitch_um,
        &DngSettings::default(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn u16_at(b: &[u8], at: usize) -> u16 {
        u16::from_le_bytes([b[at], b[at + 1]])
    }
    fn u32_at(b: &[u8], at: usize) -> u32 {
        u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
    }

    /// Walks the file as a TIFF reader would: IFD 0's tags are sorted, the
    /// strip offset points at the strip, the EXIF pointer at a valid IFD.
    #[test]
    fn the_tiff_structure_reads_back_by_hand() {
        let tags = [
            (256, TagValue::Long(vec![3])),
            (271, TagValue::Ascii("Make".into())),
            (50714, TagValue::Long(vec![1, 2, 3, 4])),
        ];
        let exif = [(41488, TagValue::Short(vec![3]))];
        let strip = [9u8, 8, 7, 6, 5, 4];
        let b = tiff_bytes(&tags, &exif, &strip);
        assert_eq!(&b[..4], b"II*\0");
        let ifd = u32_at(&b, 4) as usize;
        let n = u16_at(&b, ifd) as usize;
        let entries: Vec<(u16, u16, u32, u32)> = (0..n)
            .map(|i| {
                let e = ifd + 2 + 12 * i;
                (
                    u16_at(&b, e),
                    u16_at(&b, e + 2),
                    u32_at(&b, e + 4),
                    u32_at(&b, e + 8),
                )
            })
            .collect();
        let ids: Vec<u16> = entries.iter().map(|e| e.0).collect();
        assert_eq!(ids, [256, 271, 273, 279, 34665, 50714]);
        let strip_at = entries[2].3 as usize;
        assert_eq!(&b[strip_at..], &strip);
        assert_eq!(entries[3].3, 6);
        // out-of-line values
        let make_at = entries[1].3 as usize;
        assert_eq!(&b[make_at..make_at + 5], b"Make\0");
        let bl_at = entries[5].3 as usize;
        assert_eq!(u32_at(&b, bl_at + 12), 4);
        let exif_at = entries[4].3 as usize;
        assert_eq!(u16_at(&b, exif_at), 1);
        assert_eq!(u16_at(&b, exif_at + 2), 41488);
        assert_eq!(u16_at(&b, exif_at + 10), 3);
    }

    #[test]
    fn bad_settings_are_refused() {
        let lin = vec![0.5f32; 16];
        let s = DngSettings {
            black: [64000, 0, 0, 0],
            ..DngSettings::default()
        };
        assert!(encode_mosaic(&lin, 4, 4, BayerOrder::Rggb, 4.3, &s).is_err());
        assert!(encode_mosaic(&lin, 4, 3, BayerOrder::Rggb, 4.3, &DngSettings::default()).is_err());
        let s = DngSettings {
            orientation: 9,
            ..DngSettings::default()
        };
        assert!(encode_mosaic(&lin, 4, 4, BayerOrder::Rggb, 4.3, &s).is_err());
    }
}
