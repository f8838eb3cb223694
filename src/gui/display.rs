//! The display rendition of a photo: box-averaged down to at most
//! [`MAX_SIDE`] pixels on the long side, tone-mapped to sRGB, as a JPEG. Only
//! for the eye; every measurement reads the full-resolution data.

use rayon::prelude::*;
use sweepmtf::photo::Plane;
use sweepmtf::photo::decode::{Decoded, Samples};
use sweepmtf::photo::linearise::linear_to_srgb;

/// Longest side of the display rendition (pixels).
pub const MAX_SIDE: usize = 1600;

/// A display rendition: JPEG bytes, size, and image pixels per display pixel.
pub struct Rendition {
    /// JPEG file bytes.
    pub jpeg: Vec<u8>,
    /// Width (display pixels).
    pub width: usize,
    /// Height (display pixels).
    pub height: usize,
    /// Image pixels per display pixel.
    pub scale: f64,
    /// Linear value drawn as white when the data is linear (tone-mapped); 1 for code values.
    pub white: f32,
}

/// Box-averages `n_ch` interleaved channels by `k` (values as given).
fn boxed(w: usize, h: usize, n_ch: usize, k: usize, at: impl Fn(usize) -> f32 + Sync) -> Vec<f32> {
    let (dw, dh) = (w.div_ceil(k), h.div_ceil(k));
    let mut out = vec![0f32; dw * dh * 3];
    out.par_chunks_mut(dw * 3)
        .enumerate()
        .for_each(|(dy, row)| {
            let y0 = dy * k;
            let y1 = (y0 + k).min(h);
            for dx in 0..dw {
                let x0 = dx * k;
                let x1 = (x0 + k).min(w);
                let mut acc = [0f32; 3];
                for y in y0..y1 {
                    for x in x0..x1 {
                        let i = (y * w + x) * n_ch;
                        for (c, a) in acc.iter_mut().enumerate() {
                            *a += at(i + c.min(n_ch - 1));
                        }
                    }
                }
                let n = ((y1 - y0) * (x1 - x0)) as f32;
                for c in 0..3 {
                    row[dx * 3 + c] = acc[c] / n;
                }
            }
        });
    out
}

fn factor(w: usize, h: usize) -> usize {
    w.max(h).div_ceil(MAX_SIDE).max(1)
}

/// The linear value drawn as white: the 99.5th percentile of `lin` (1 when it is not positive).
fn white_of(lin: &[f32]) -> f32 {
    let mut sorted: Vec<f32> = lin.iter().copied().filter(|v| v.is_finite()).collect();
    if sorted.is_empty() {
        return 1.0;
    }
    let i = ((sorted.len() - 1) as f64 * 0.995) as usize;
    let (_, v, _) = sorted.select_nth_unstable_by(i, f32::total_cmp);
    if *v > 0.0 { *v } else { 1.0 }
}

/// A linear value to an sRGB byte, `white` drawn as 255.
pub fn tone_byte(v: f32, white: f32) -> u8 {
    (linear_to_srgb((v / white).clamp(0.0, 1.0) as f64) * 255.0).round() as u8
}

/// Linear values to sRGB bytes with `white` drawn as 255.
fn tone_map(lin: &[f32], white: f32) -> Vec<u8> {
    lin.iter().map(|&v| tone_byte(v, white)).collect()
}

fn jpeg(rgb: &[u8], w: usize, h: usize) -> Vec<u8> {
    let mut buf = Vec::new();
    let enc = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut buf, 88);
    // Encoding an in-memory buffer of the right size cannot fail.
    let _ = image::ImageEncoder::write_image(
        enc,
        rgb,
        w as u32,
        h as u32,
        image::ExtendedColorType::Rgb8,
    );
    buf
}

/// The rendition of a decoded JPEG/PNG/TIFF: 8-bit code values are averaged as
/// they are (already for display); 16-bit data is taken as linear and tone-mapped.
pub fn of_decoded(d: &Decoded) -> Rendition {
    let k = factor(d.width, d.height);
    let (w, h) = (d.width.div_ceil(k), d.height.div_ceil(k));
    let mut white = 1.0;
    let rgb = match &d.samples {
        Samples::U8(v) => boxed(d.width, d.height, d.channels, k, |i| v[i] as f32)
            .iter()
            .map(|&x| x.round().clamp(0.0, 255.0) as u8)
            .collect(),
        Samples::U16(v) => {
            let lin = boxed(d.width, d.height, d.channels, k, |i| v[i] as f32 / 65535.0);
            white = white_of(&lin);
            tone_map(&lin, white)
        }
        // Float code values (0 = black, 1 = white), as for display.
        Samples::F32(v) => boxed(d.width, d.height, d.channels, k, |i| v[i] * 255.0)
            .iter()
            .map(|&x| x.round().clamp(0.0, 255.0) as u8)
            .collect(),
    };
    Rendition {
        jpeg: jpeg(&rgb, w, h),
        width: w,
        height: h,
        scale: k as f64,
        white,
    }
}

/// The rendition of a raw frame's linear location plane (one lattice of
/// `step` image pixels per plane pixel), tone-mapped.
pub fn of_plane(p: &Plane) -> Rendition {
    let k = factor(p.width, p.height);
    let (w, h) = (p.width.div_ceil(k), p.height.div_ceil(k));
    let lin = boxed(p.width, p.height, 1, k, |i| p.data[i]);
    let white = white_of(&lin);
    let rgb = tone_map(&lin, white);
    Rendition {
        jpeg: jpeg(&rgb, w, h),
        width: w,
        height: h,
        scale: (k * p.step.0) as f64,
        white,
    }
}
