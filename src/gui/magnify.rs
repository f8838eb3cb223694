//! The magnifier's full-resolution view: `GET /api/crop?id=N&x=X&y=Y` answers
//! a small window of the photo's own pixels around image point (X, Y), drawn
//! as the display rendition draws them (code values as they are; linear data
//! tone-mapped with the rendition's white), so a corner can be placed on the
//! real pixels rather than on the downscaled rendition.
//!
//! The photo is decoded at full resolution on the first request and kept
//! (a 24 MP JPEG: ≈ 72 MB of 8-bit RGB) for the moves that follow; a raw
//! gives its location plane (the first green lattice: one sample every
//! `step` pixels, drawn as `step`-pixel squares).

use super::display::tone_byte;
use super::server::{Reply, Server};
use super::session::{Photo, Source};
use crate::cli::Code;
use serde_json::json;
use std::sync::Arc;
use sweepmtf::photo::Plane;
use sweepmtf::photo::decode::{Decoded, Samples, decode_bytes};

/// Side of the window sent (image pixels).
pub const CROP_PX: usize = 64;

/// A photo's full-resolution data, decoded once for the magnifier.
pub enum Full {
    /// A JPEG, PNG or TIFF, decoded.
    Decoded(Decoded),
    /// A raw frame's location plane (linear).
    Plane(Plane),
}

/// Decodes a photo's full-resolution data (what [`Full`] holds).
pub fn decode_full(p: &Photo) -> Result<Full, String> {
    match &p.source {
        Source::File(bytes) => decode_bytes(bytes, &p.name)
            .map(Full::Decoded)
            .map_err(|e| e.to_string()),
        Source::Raw(path) => sweepmtf::photo::raw::decode_raw(path)
            .map(|f| Full::Plane(f.location_plane()))
            .map_err(|e| e.to_string()),
        Source::Frame(f) => Ok(Full::Plane(f.location_plane())),
    }
}

/// The photo's full-resolution data, decoded on first use and kept.
pub fn full_of(p: &Photo) -> Result<Arc<Full>, String> {
    p.full.get_or_init(|| decode_full(p).map(Arc::new)).clone()
}

/// A window of `n` samples along one axis of `len` samples of step `step`
/// image pixels starting at image pixel `offset`, centred as near as the
/// edges allow on image coordinate `c`: (first sample, samples).
fn window(c: f64, len: usize, step: usize, offset: usize) -> (usize, usize) {
    let n = (CROP_PX / step).max(1).min(len);
    let centre = ((c - offset as f64 - 0.5) / step as f64).round();
    let first = (centre - (n / 2) as f64).clamp(0.0, (len - n) as f64) as usize;
    (first, n)
}

/// The window around image point (x, y): RGB bytes, its size in samples,
/// and its extent in image pixels (left, top, width, height).
pub fn crop(full: &Full, white: f32, x: f64, y: f64) -> (Vec<u8>, [usize; 2], [f64; 4]) {
    let (w, h, step, offset) = match full {
        Full::Decoded(d) => (d.width, d.height, (1, 1), (0, 0)),
        Full::Plane(p) => (p.width, p.height, p.step, p.offset),
    };
    let (i0, nw) = window(x, w, step.0, offset.0);
    let (j0, nh) = window(y, h, step.1, offset.1);
    let mut rgb = Vec::with_capacity(nw * nh * 3);
    for j in j0..j0 + nh {
        for i in i0..i0 + nw {
            let px: [u8; 3] = match full {
                Full::Decoded(d) => {
                    let at = (j * d.width + i) * d.channels;
                    let c = |k: usize| at + k.min(d.channels - 1);
                    match &d.samples {
                        Samples::U8(v) => [v[c(0)], v[c(1)], v[c(2)]],
                        Samples::U16(v) => {
                            [0, 1, 2].map(|k| tone_byte(v[c(k)] as f32 / 65535.0, white))
                        }
                        Samples::F32(v) => {
                            [0, 1, 2].map(|k| (v[c(k)] * 255.0).round().clamp(0.0, 255.0) as u8)
                        }
                    }
                }
                Full::Plane(p) => [tone_byte(p.data[j * p.width + i], white); 3],
            };
            rgb.extend_from_slice(&px);
        }
    }
    // Sample i's centre is at offset + i·step + 0.5; it is drawn as a step-wide square.
    let edge =
        |first: usize, s: usize, o: usize| o as f64 + (first * s) as f64 + 0.5 - s as f64 / 2.0;
    let extent = [
        edge(i0, step.0, offset.0),
        edge(j0, step.1, offset.1),
        (nw * step.0) as f64,
        (nh * step.1) as f64,
    ];
    (rgb, [nw, nh], extent)
}

/// `GET /api/crop?id=N&x=X&y=Y`: JSON {x, y, width, height (image pixels), png (a data URL)}.
pub fn endpoint(s: &Server, id: Option<&str>, x: Option<&str>, y: Option<&str>) -> Reply {
    let num = |v: Option<&str>| {
        v.and_then(|t| t.parse::<f64>().ok())
            .filter(|v| v.is_finite())
    };
    let (Some(id), Some(x), Some(y)) = (id.and_then(|t| t.parse::<usize>().ok()), num(x), num(y))
    else {
        return Reply::error(
            400,
            Code::Usage as u8,
            "crop: give id=<photo>, x=<px> and y=<px>",
        );
    };
    let photo: Arc<Photo> = match super::measure_api::photo(s, id) {
        Ok(p) => p,
        Err(r) => return r,
    };
    let full = match full_of(&photo) {
        Ok(f) => f,
        Err(e) => return Reply::error(422, Code::Input as u8, e),
    };
    let (rgb, [nw, nh], ext) = crop(&full, photo.display.white, x, y);
    match sweepmtf::report::roi_plot::encode_png(rgb, nw as u32, nh as u32) {
        Ok(png) => Reply::json(&json!({
            "x": ext[0], "y": ext[1], "width": ext[2], "height": ext[3],
            "png": format!("data:image/png;base64,{}", sweepmtf::batch::base64::encode(&png)),
        })),
        Err(e) => Reply::error(500, Code::Output as u8, e.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grey(w: usize, h: usize) -> Full {
        Full::Decoded(Decoded {
            width: w,
            height: h,
            channels: 1,
            samples: Samples::U8((0..w * h).map(|i| (i % 251) as u8).collect()),
            format: "png",
            rows: h,
            warnings: vec![],
            declared_tone: None,
            jpeg_luma_quant: None,
        })
    }

    #[test]
    fn window_is_centred_and_stays_inside() {
        let f = grey(300, 200);
        let (rgb, n, e) = crop(&f, 1.0, 150.2, 100.7);
        assert_eq!(n, [64, 64]);
        assert_eq!(rgb.len(), 64 * 64 * 3);
        // Pixel (150, 100) (covering [150, 151) × [100, 101)) sits at the centre: edges 32 px before.
        assert_eq!(e, [118.0, 68.0, 64.0, 64.0]);
        // The first byte is pixel (118, 68) as stored.
        assert_eq!(rgb[0], ((68 * 300 + 118) % 251) as u8);
        // At a corner of the photo the window is pushed inside.
        assert_eq!(crop(&f, 1.0, -50.0, 1e9).2, [0.0, 136.0, 64.0, 64.0]);
        // A photo smaller than the window is sent whole.
        let (rgb, n, e) = crop(&grey(10, 7), 1.0, 5.0, 3.0);
        assert_eq!((n, e, rgb.len()), ([10, 7], [0.0, 0.0, 10.0, 7.0], 210));
    }

    #[test]
    fn plane_samples_are_drawn_at_their_image_positions() {
        // A green lattice: sample (i, j) at image pixel (1 + 2i, 2j), value i / 100.
        let (pw, ph) = (100, 80);
        let p = Plane {
            width: pw,
            height: ph,
            step: (2, 2),
            offset: (1, 0),
            data: (0..pw * ph).map(|k| (k % pw) as f32 / 100.0).collect(),
        };
        let (rgb, n, e) = crop(&Full::Plane(p), 1.0, 81.5, 40.5);
        assert_eq!(n, [32, 32]);
        // Image x 81.5 is sample 40 (centre 1 + 80 + 0.5), y 40.5 sample 20; the window
        // starts 16 samples before each, its squares 2 px wide about the centres.
        assert_eq!(e, [48.5, 7.5, 64.0, 64.0]);
        assert_eq!(rgb[0], tone_byte(0.24, 1.0));
    }
}
