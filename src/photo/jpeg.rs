//! JPEG decoding that reads only what a measurement needs (issue 16), through
//! zune-jpeg directly (the decoder the image crate wraps, so no new code
//! path for the pixels themselves).
//!
//! Two savings, both exact for what is kept:
//! - **Rows.** A sequential JPEG whose one scan holds every component is
//!   decoded only down to the MCU row below the last needed row (plus one
//!   MCU row, so chroma upsampling at the cut sees the same neighbours as a
//!   whole decode): the frame header's height is lowered in a copy of the
//!   headers, so the decoder stops there. Entropy decoding of the rows above
//!   cannot be skipped (each block's DC is coded against the one before).
//!   Progressive and multi-scan files are decoded whole.
//! - **Chroma.** For a luminance measurement the decoder can return the Y
//!   plane alone (no chroma IDCT, upsampling or colour conversion): a
//!   one-channel image of Y′ codes. On a neutral chart Y′ equals R′ = G′ = B′
//!   up to JPEG's chroma rounding (see the README's "Speed and memory").
//! - **Both cores.** For such a luma decode of a sequential one-scan file,
//!   zune-jpeg (vendored with one change, `vendor/zune-jpeg/SWEEPMTF.md`)
//!   entropy-decodes on this thread and runs the IDCT on a second one, when
//!   the calling rayon pool has a second thread to give (a batch worker's
//!   pool of one does not); the pixels are the same either way.
//!
//! Rows below the cut are left zero in a full-size buffer whose pages are
//! never touched (so they cost no memory); [`Decoded::rows`] says how many
//! rows hold the picture.
//!
//! Corrupt scan data: the file is first decoded strictly; if the decoder
//! complains and a lenient decode still succeeds, the picture is kept with a
//! warning that says so ([`Decoded::warnings`]).

use super::decode::{DecodeError, Decoded, Samples};
use zune_core::bytestream::ZCursor;
use zune_core::colorspace::ColorSpace;
use zune_core::options::DecoderOptions;
use zune_jpeg::JpegDecoder;
use zune_jpeg::errors::DecodeErrors;

/// What of a JPEG the caller will read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct JpegWant {
    /// Rows from the top (pixels) that must hold the picture; `None`: all.
    pub rows: Option<usize>,
    /// Only the luma plane Y′ (one channel) is needed.
    pub luma_only: bool,
}

/// The frame facts read from the headers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Frame {
    /// Byte offset of the frame header's 16-bit height field.
    height_at: usize,
    /// Height in pixels.
    height: usize,
    /// Components in the frame.
    components: usize,
    /// Largest vertical sampling factor (MCU height = 8 × this).
    v_max: usize,
    /// Sequential Huffman (SOF0/SOF1), the only kind whose rows can be cut.
    sequential: bool,
    /// Components in the first scan.
    first_scan: usize,
}

/// Whether marker `m` starts a frame header (SOF0–SOF15; not DHT, DAC or JPG).
pub(crate) fn is_frame_header(m: u8) -> bool {
    (0xC0..=0xCF).contains(&m) && m != 0xC4 && m != 0xC8 && m != 0xCC
}

/// The marker segments of a JPEG's headers, up to and including the first
/// scan header: (marker, offset of the marker's 0xFF, segment body). It ends
/// early, without an error, where the bytes are not a well-formed segment.
pub(crate) fn header_segments(b: &[u8]) -> impl Iterator<Item = (u8, usize, &[u8])> {
    let mut i = if b.get(..2) == Some(&[0xFF, 0xD8][..]) {
        2
    } else {
        usize::MAX
    };
    std::iter::from_fn(move || {
        // Fill bytes (FF FF …) may precede a marker.
        while *b.get(i)? == 0xFF && *b.get(i + 1)? == 0xFF {
            i += 1;
        }
        if *b.get(i)? != 0xFF {
            return None;
        }
        let m = *b.get(i + 1)?;
        let len = u16::from_be_bytes([*b.get(i + 2)?, *b.get(i + 3)?]) as usize;
        let seg = b.get(i + 4..i + 2 + len)?;
        let at = i;
        // After the scan header the entropy-coded data follows: stop there.
        i = if m == 0xDA { usize::MAX } else { i + 2 + len };
        Some((m, at, seg))
    })
}

/// The frame facts a cut needs, from the headers up to the first scan;
/// `None` when they are not what a cut needs (the whole file is then decoded).
fn frame_facts(b: &[u8]) -> Option<Frame> {
    let mut frame: Option<Frame> = None;
    for (m, i, seg) in header_segments(b) {
        if is_frame_header(m) {
            let n = *seg.get(5)? as usize;
            let v_max = (0..n)
                .map(|c| seg.get(7 + 3 * c).map(|s| (s & 0x0F) as usize))
                .collect::<Option<Vec<_>>>()?
                .into_iter()
                .max()?;
            frame = Some(Frame {
                height_at: i + 5,
                height: u16::from_be_bytes([*seg.get(1)?, *seg.get(2)?]) as usize,
                components: n,
                v_max: v_max.max(1),
                sequential: m == 0xC0 || m == 0xC1,
                first_scan: 0,
            });
        } else if m == 0xDA {
            let mut f = frame?;
            f.first_scan = *seg.first()? as usize;
            return Some(f);
        }
    }
    None
}

/// The height to decode to for `rows` needed rows, when that is less than the frame.
fn cut_height(f: &Frame, rows: usize) -> Option<usize> {
    if !f.sequential || f.first_scan != f.components || f.height == 0 {
        return None;
    }
    let mcu = 8 * f.v_max;
    let h = (rows.div_ceil(mcu) + 1) * mcu;
    (h < f.height).then_some(h)
}

/// Makes, given a photo's width and height (px), the observer of its
/// decode's luma rows ([`zune_jpeg::RowObserver`]); `None`: none wanted.
pub type ObserverFor<'a> = &'a (dyn Fn(usize, usize) -> Option<zune_jpeg::RowObserver> + Sync);

/// Decodes a JPEG as `want` asks; `name` is used in messages.
pub fn decode_jpeg(bytes: &[u8], name: &str, want: JpegWant) -> Result<Decoded, DecodeError> {
    decode_jpeg_observed(bytes, name, want, None)
}

/// [`decode_jpeg`], showing the rows to an observer made by `observe` as
/// they are written, when the IDCT runs on a second thread (a luma decode
/// of a sequential one-scan file): the observer's work then runs beside the
/// entropy decoding. Only the strict decode is shown (not a lenient retry).
pub fn decode_jpeg_observed(
    bytes: &[u8],
    name: &str,
    want: JpegWant,
    observe: Option<ObserverFor<'_>>,
) -> Result<Decoded, DecodeError> {
    let corrupt = |cause: String| DecodeError::Corrupt {
        path: name.to_string(),
        cause,
    };
    let unsupported = |what: String| DecodeError::Unsupported {
        path: name.to_string(),
        what,
    };
    let facts = frame_facts(bytes);
    let cut = facts.and_then(|f| want.rows.and_then(|r| cut_height(&f, r)).map(|h| (f, h)));
    // The copy with the lowered height (headers and scan data: zune-jpeg reads one slice).
    let patched;
    let input: &[u8] = match cut {
        Some((f, h)) => {
            let mut v = bytes.to_vec();
            v[f.height_at..f.height_at + 2].copy_from_slice(&(h as u16).to_be_bytes());
            patched = v;
            &patched
        }
        None => bytes,
    };
    let options = |strict: bool| {
        DecoderOptions::default()
            .set_strict_mode(strict)
            .set_max_width(usize::MAX)
            .set_max_height(usize::MAX)
    };
    let mut d = JpegDecoder::new_with_options(ZCursor::new(input), options(true));
    d.decode_headers().map_err(|e| corrupt(e.to_string()))?;
    let (w, h) = d
        .dimensions()
        .ok_or_else(|| corrupt("no frame header".into()))?;
    let (width, decoded) = (w, h);
    let height = cut.map_or(decoded, |(f, _)| f.height);
    // A cut frame's last MCU row is upsampled as an image edge (its chroma has
    // no row below), so it differs from the whole decode: only the rows above
    // it are the picture. `cut_height` decodes one MCU row more for this.
    let rows = cut.map_or(decoded, |(f, _)| decoded - 8 * f.v_max);
    if width == 0 || height == 0 {
        return Err(corrupt("the image has no pixels".into()));
    }
    let space = d.input_colorspace().expect("headers were decoded");
    let out_space = match space {
        ColorSpace::Luma | ColorSpace::LumaA => ColorSpace::Luma,
        ColorSpace::YCbCr if want.luma_only => ColorSpace::Luma,
        ColorSpace::YCbCr | ColorSpace::RGB | ColorSpace::RGBA => ColorSpace::RGB,
        other => {
            return Err(unsupported(format!(
                "{other:?} JPEG colour is not read; use grey or YCbCr/RGB"
            )));
        }
    };
    let channels = out_space.num_components();
    let n = width * height * channels;
    // The image crate's default allocation limit (512 MiB), as before.
    image::Limits::default()
        .reserve(n as u64)
        .map_err(|e| corrupt(e.to_string()))?;
    let mut buf = super::hugebuf::zeroed::<u8>(n);
    let opts = options(true).jpeg_set_out_colorspace(out_space);
    d.set_options(opts);
    let mut warnings = Vec::new();
    let span = super::hugebuf::span_of(&buf[..width * decoded * channels]);
    // Only where this thread's pool has a second thread to give (a batch
    // worker measuring its shot on one thread keeps to one).
    let pipelined =
        pipelined_idct(facts, out_space, width * decoded) && rayon::current_num_threads() >= 2;
    d.set_pipelined_idct(Some(pipelined));
    if pipelined && let Some(make) = observe {
        d.set_row_observer(make(width, decoded));
    }
    let strict = if pipelined {
        d.decode_into(&mut buf[..width * decoded * channels])
    } else {
        rayon::join(
            || d.decode_into(&mut buf[..width * decoded * channels]),
            || super::hugebuf::populate(span),
        )
        .0
    };
    if let Err(strict) = strict {
        if is_unsupported(&strict) {
            return Err(unsupported(strict.to_string()));
        }
        // Decodable but damaged? A lenient pass keeps what can be read.
        let mut d = JpegDecoder::new_with_options(
            ZCursor::new(input),
            options(false).jpeg_set_out_colorspace(out_space),
        );
        d.set_pipelined_idct(Some(pipelined));
        d.decode_into(&mut buf[..width * decoded * channels])
            .map_err(|e| corrupt(e.to_string()))?;
        warnings.push(format!(
            "JPEG scan data is corrupt ({strict}); measured from a lenient decode, damaged blocks may be grey or wrong"
        ));
    }
    Ok(Decoded {
        width,
        height,
        channels,
        samples: Samples::U8(buf),
        format: "jpeg",
        rows,
        warnings,
        declared_tone: None,
        jpeg_luma_quant: super::jpeg_quant::luma_table(bytes).map(Box::new),
    })
}

/// Whether zune-jpeg (vendor/zune-jpeg/SWEEPMTF.md) runs the IDCT of this
/// decode on a second thread; that thread then also takes the page faults of
/// the output, which `hugebuf::populate` would take on it otherwise.
fn pipelined_idct(f: Option<Frame>, out: ColorSpace, pixels: usize) -> bool {
    out == ColorSpace::Luma
        && f.is_some_and(|f| f.sequential && f.first_scan == f.components)
        && pixels >= 512 * 512
}

fn is_unsupported(e: &DecodeErrors) -> bool {
    matches!(e, DecodeErrors::Unsupported(_))
}
