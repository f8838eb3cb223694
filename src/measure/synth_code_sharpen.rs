//! A camera's sharpening of the code for the reference renderer
//! ([`super::synth`]): the simulator's unsharp mask ([`Sharpen`]) on the code (after the
//! sRGB curve and any picture style), as a camera's JPEG engine sharpens,
//! and the truth such a camera gives a sine chart.
//!
//! Sharpening the code makes the camera non-linear: it has no MTF of its
//! own. The truth is the one a sine of the chart's contrast defines, as
//! every modulation-based method reads it: a pure sine of the linear
//! transfer at `f`, encoded, each harmonic k of its code scaled by the
//! mask's discrete transfer at k·f (in the strip's direction), decoded; its
//! fundamental over its own mean, over the chart's contrast. (Over the
//! input's mean it would read higher: sharpening the code raises the linear
//! mean where the code swings wider.)

use super::synth::picture_style;
use crate::photo::linearise::{linear_to_srgb, srgb_to_linear};
use crate::simulate::nuisance::Sharpen;
use std::f64::consts::PI;

/// The modulation transfer a sine of contrast `contrast` about linear mean
/// `mean` reads at `f` cycles/pixel in direction `angle` (radians), its
/// linear transfer up to the code being `t_lin`, through sRGB, a picture
/// style of strength `style` and the unsharp mask `mask` on the code (see
/// the module text; the mask's gain at each harmonic is [`Sharpen::gain`]).
pub fn truth(
    mask: &Sharpen,
    f: f64,
    angle: f64,
    t_lin: f64,
    mean: f64,
    contrast: f64,
    style: f64,
) -> f64 {
    const N: usize = 256;
    let (fx, fy) = (f * angle.cos(), f * angle.sin());
    let code: Vec<f64> = (0..N)
        .map(|i| {
            let v = mean * (1.0 + contrast * t_lin * (2.0 * PI * i as f64 / N as f64).cos());
            picture_style(linear_to_srgb(v.clamp(0.0, 1.0)), style)
        })
        .collect();
    // Each harmonic of the code scaled by the mask's transfer at k·f.
    let mut sharp = vec![0.0; N];
    for h in 0..N / 2 {
        let (mut a, mut b) = (0.0, 0.0);
        for (i, c) in code.iter().enumerate() {
            let ph = 2.0 * PI * (h * i) as f64 / N as f64;
            a += c * ph.cos();
            b += c * ph.sin();
        }
        let w = if h == 0 { 1.0 } else { 2.0 } / N as f64;
        let gain = mask.gain(h as f64 * fx, h as f64 * fy);
        for (i, s) in sharp.iter_mut().enumerate() {
            let ph = 2.0 * PI * (h * i) as f64 / N as f64;
            *s += gain * w * (a * ph.cos() + b * ph.sin());
        }
    }
    // Decoded: its fundamental over its mean.
    let (mut m, mut a, mut b) = (0.0, 0.0, 0.0);
    for (i, c) in sharp.iter().enumerate() {
        let v = srgb_to_linear(unstyle(c.clamp(0.0, 1.0), style));
        let ph = 2.0 * PI * i as f64 / N as f64;
        m += v;
        a += v * ph.cos();
        b += v * ph.sin();
    }
    2.0 * a.hypot(b) / m / contrast
}

/// Sharpens a row-major plane of code values (0–1) in place with `mask`
/// ([`Sharpen::apply`], edges held).
pub fn apply(mask: &Sharpen, plane: &mut [f64], width: usize) {
    let mut p32: Vec<f32> = plane.iter().map(|&v| v as f32).collect();
    mask.apply(&mut p32, width);
    for (o, v) in plane.iter_mut().zip(p32) {
        *o = v as f64;
    }
}

/// The inverse of [`picture_style`] of strength `k` on a code (0–1).
fn unstyle(c: f64, k: f64) -> f64 {
    if k == 0.0 {
        c
    } else {
        let t = ((2.0 * c - 1.0) * (0.5 * k).tanh()).clamp(-1.0 + 1e-15, 1.0 - 1e-15);
        0.5 + t.atanh() / k
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The truth against a sharpened sine rendered on the pixel grid: a
    /// plane of a pure sine in linear light (whole cycles across it, so the
    /// mask's edges do not matter in the middle), encoded, sharpened by
    /// [`apply`], decoded, its fundamental over its mean read
    /// by least squares in the middle rows.
    #[test]
    fn the_truth_matches_a_sharpened_plane() {
        let s = Sharpen {
            amount: 0.8,
            radius_px: 1.2,
        };
        // Frequencies whose harmonics alias onto the fundamental only from
        // order 7 (f = 1/8) or 15 (3/16) on: the grid's reading is then the
        // fundamental's.
        for (f, style) in [(0.125, 0.0), (0.1875, 2.0), (0.0625, 2.0)] {
            let (w, h, mean, contrast, t) = (256, 32, 0.35, 0.8, 0.7);
            let mut plane: Vec<f64> = (0..w * h)
                .map(|i| {
                    let x = (i % w) as f64 + 0.5;
                    let v = mean * (1.0 + contrast * t * (2.0 * PI * f * x).cos());
                    picture_style(linear_to_srgb(v), style)
                })
                .collect();
            apply(&s, &mut plane, w);
            let row = &plane[16 * w..17 * w];
            let (mut m, mut a, mut b) = (0.0, 0.0, 0.0);
            for (x, c) in row.iter().enumerate().skip(32).take(w - 64) {
                let v = srgb_to_linear(unstyle(c.clamp(0.0, 1.0), style));
                let ph = 2.0 * PI * f * (x as f64 + 0.5);
                m += v;
                a += v * ph.cos();
                b += v * ph.sin();
            }
            let read = 2.0 * a.hypot(b) / m / contrast;
            let truth = truth(&s, f, 0.0, t, mean, contrast, style);
            assert!(
                (read - truth).abs() < 1e-4,
                "f {f} style {style}: read {read} truth {truth}"
            );
            // And it is not the linear guess t·gain at the fundamental.
            assert!(truth > t, "f {f}: {truth} ≤ {t}");
        }
    }
}
