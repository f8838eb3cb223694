//! The whole-file decode through rawler (every format it reads): its image
//! turned into a [`RawFrame`], cropped, with the CFA pattern, black and white
//! levels re-anchored at the frame.

use super::deltas::{Deltas, dng_black_deltas};
use super::error::map_error;
use super::facts::{facts_of, tiff_exif};
use super::{RAWLER, RawError, open};
use crate::photo::exif::{ExifFacts, clean_text};
use crate::photo::raw::frame::{
    BlackLevels, CfaColour, CfaPattern, Ids, Layout, RawFrame, Samples,
};
use crate::photo::raw::guard;
use rawler::RawlerError;
use rawler::decoders::RawDecodeParams;
use rawler::rawimage::{RawImage, RawImageData, RawPhotometricInterpretation};
use std::path::Path;

/// Decodes a camera raw whole through rawler (every format rawler reads);
/// [`decode_raw`](super::decode_raw) uses it for the files the windowed DNG reader does not handle.
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
