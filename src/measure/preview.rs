//! Preview: the picture of the measured region (plus a margin, at most
//! ~1200 px on its long side) drawn beside the plots — from a decoded photo's
//! 8-bit samples, or from a raw frame's green lattice through the sRGB curve.

use super::Preview;
use super::region::bbox_crop;
use crate::geometry::Point;
use crate::photo::decode::{Decoded, Samples};
use crate::photo::linearise::Crop;

/// A decoded photo's preview of the region `roi` (image px), from its 8-bit samples.
pub(super) fn make_preview(dec: &Decoded, roi: &[Point; 4]) -> Preview {
    // A cut decode holds rows down to just below the region: the picture stops there.
    preview_from(roi, dec.width, dec.rows, |x, y| {
        let mut px = [0u8; 3];
        for (c, out) in px.iter_mut().enumerate() {
            let cc = if dec.channels == 1 { 0 } else { c };
            let k = (y * dec.width + x) * dec.channels + cc;
            *out = match &dec.samples {
                Samples::U8(v) => v[k],
                Samples::U16(v) => (v[k] >> 8) as u8,
                Samples::F32(v) => (v[k].clamp(0.0, 1.0) * 255.0).round() as u8,
            };
        }
        px
    })
}

/// The image rectangle a preview of the region shows (the region plus a
/// margin) and its step (image px per preview px, so that the long side is at
/// most ~1200 px).
fn preview_window(roi: &[Point; 4], width: usize, height: usize) -> (Crop, usize) {
    let xmin = roi.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min);
    let xmax = roi.iter().map(|p| p[0]).fold(f64::NEG_INFINITY, f64::max);
    let ymin = roi.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
    let ymax = roi.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max);
    let pad = 0.08 * (xmax - xmin).max(ymax - ymin) + 8.0;
    let crop = bbox_crop(roi, width, height, pad);
    let (cw, ch) = (crop.x1 - crop.x0, crop.y1 - crop.y0);
    let step = ((cw.max(ch) as f64 / 1200.0).ceil() as usize).max(1);
    (crop, step)
}

/// A raw frame's preview of the region: on a Bayer mosaic one green lattice
/// (an even step, so every preview pixel is a green site and the picture
/// shows no CFA checkerboard), otherwise the first sample of each pixel;
/// through the sRGB curve (a table) for display. Converted a row at a time
/// in parallel, straight from the decoded samples.
pub(super) fn raw_preview(frame: &crate::photo::raw::RawFrame, roi: &[Point; 4]) -> Preview {
    let (crop, step) = preview_window(roi, frame.width, frame.height);
    let (offset, step) = match frame.green_site() {
        Some(g) => {
            let step = step.next_multiple_of(2);
            // The first green site at or after the crop's corner.
            let first = |lo: usize, g: usize| lo + (g + 2 - lo % 2) % 2;
            ((first(crop.x0, g.0), first(crop.y0, g.1)), step)
        }
        None => ((crop.x0, crop.y0), step),
    };
    let sample = if frame.samples_per_pixel == 3 { 1 } else { 0 };
    let plane = frame.lattice_plane(
        offset,
        (step, step),
        sample,
        (crop.x0, crop.y0, crop.x1, crop.y1),
    );
    const LEVELS: usize = 4096;
    let srgb: Vec<u8> = (0..LEVELS)
        .map(|i| {
            let v = i as f64 / (LEVELS - 1) as f64;
            (255.0 * crate::photo::linearise::linear_to_srgb(v)).round() as u8
        })
        .collect();
    let rgb = plane
        .data
        .iter()
        .flat_map(|&v| {
            let c = srgb[(v.clamp(0.0, 1.0) * (LEVELS - 1) as f32 + 0.5) as usize];
            [c, c, c]
        })
        .collect();
    Preview {
        x0: plane.offset.0 as f64,
        y0: plane.offset.1 as f64,
        scale: step as f64,
        width: plane.width,
        height: plane.height,
        rgb,
    }
}

/// A preview of the region (plus a margin), at most ~1200 px on its long side.
fn preview_from(
    roi: &[Point; 4],
    width: usize,
    height: usize,
    pixel: impl Fn(usize, usize) -> [u8; 3],
) -> Preview {
    let (crop, step) = preview_window(roi, width, height);
    let (cw, ch) = (crop.x1 - crop.x0, crop.y1 - crop.y0);
    let (pw, ph) = (cw.div_ceil(step), ch.div_ceil(step));
    let mut rgb = Vec::with_capacity(pw * ph * 3);
    for j in 0..ph {
        for i in 0..pw {
            rgb.extend(pixel(crop.x0 + i * step, crop.y0 + j * step));
        }
    }
    Preview {
        x0: crop.x0 as f64,
        y0: crop.y0 as f64,
        scale: step as f64,
        width: pw,
        height: ph,
        rgb,
    }
}
