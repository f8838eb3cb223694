//! Tests of [`super`]: the strip-tone fit on profiles rendered through known
//! camera curves, lights and sharpened codes.

use super::*;
use crate::measure::LawKind;

/// A log sweep 0.008 → 0.3 cy/px over 1200 px, binned at 0.25 px, its
/// linear value `light(s)·(1 + m sin φ)/2` passed through `camera`
/// (linear → code 0–1), rounded to 8 bits and decoded with sRGB.
fn profile(camera: impl Fn(f64) -> f64, light: impl Fn(f64) -> f64) -> (Profile, PhaseLaw) {
    let len = 1200.0;
    let k = (0.3f64 / 0.008).ln() / len;
    let law = PhaseLaw {
        kind: LawKind::Log,
        c0: 0.0,
        c1: 0.008,
        c2: k,
        persp: 0.0,
    };
    let n = (len / 0.25) as usize;
    let s: Vec<f64> = (0..n).map(|i| (i as f64 + 0.5) * 0.25).collect();
    let y = s
        .iter()
        .map(|&s| {
            let lin = light(s) * 0.5 * (1.0 + 0.8 * (std::f64::consts::TAU * law.phase(s)).sin());
            let code = (camera(lin) * 255.0).round() / 255.0;
            Tone::Srgb.apply(code)
        })
        .collect();
    let prof = Profile {
        count: vec![60.0; n],
        var_s: vec![0.0; n],
        s,
        y,
        bin: 0.25,
        length: len,
        samples: 60 * n,
        clipped_high: 0,
        clipped_low: 0,
        clipped: Vec::new(),
        parity: Vec::new(),
    };
    (prof, law)
}

fn srgb(l: f64) -> f64 {
    crate::photo::linearise::linear_to_srgb(l)
}

/// As [`profile`] under even light 0.9, but with the code sharpened as a
/// camera's JPEG engine does after its tone curve: an unsharp mask of
/// Gaussian radius `radius` px and amount `amount` on the code, applied
/// to each harmonic of a period's code at the local frequency f
/// (gain 1 + amount·(1 − exp(−2π²r²(kf)²)) on harmonic k).
fn sharpened(camera: impl Fn(f64) -> f64, amount: f64, radius: f64) -> (Profile, PhaseLaw) {
    let (mut prof, law) = profile(&camera, |_| 0.9);
    // The code's harmonics over one period (64 points; 16 kept).
    let n = 64;
    let codes: Vec<f64> = (0..n)
        .map(|i| {
            let ph = std::f64::consts::TAU * i as f64 / n as f64;
            camera(0.9 * 0.5 * (1.0 + 0.8 * ph.sin()))
        })
        .collect();
    let harmonics: Vec<(f64, f64)> = (0..16)
        .map(|k| {
            let (mut a, mut b) = (0.0, 0.0);
            for (i, c) in codes.iter().enumerate() {
                let ph = std::f64::consts::TAU * (k * i) as f64 / n as f64;
                a += c * ph.cos();
                b += c * ph.sin();
            }
            let w = if k == 0 { 1.0 } else { 2.0 } / n as f64;
            (a * w, b * w)
        })
        .collect();
    for (y, &s) in prof.y.iter_mut().zip(&prof.s) {
        let (f, ph) = (law.freq(s), std::f64::consts::TAU * law.phase(s));
        let code: f64 = harmonics
            .iter()
            .enumerate()
            .map(|(k, &(a, b))| {
                let x = std::f64::consts::TAU * radius * k as f64 * f;
                let gain = 1.0 + amount * (1.0 - (-0.5 * x * x).exp());
                let kph = k as f64 * ph;
                gain * (a * kph.cos() + b * kph.sin())
            })
            .sum();
        *y = Tone::Srgb.apply((code.clamp(0.0, 1.0) * 255.0).round() / 255.0);
    }
    (prof, law)
}

/// The worst departure (fraction of the range) of `fix` applied to the
/// camera's codes from an affine map of the true light, over `lo..hi`.
fn affine_departure(fix: &ToneFix, camera: impl Fn(f64) -> f64, lo: f64, hi: f64) -> f64 {
    let ls: Vec<f64> = (0..=50).map(|i| lo + (hi - lo) * i as f64 / 50.0).collect();
    let vs: Vec<f64> = ls
        .iter()
        .map(|&l| fix.linear(Tone::Srgb.apply(camera(l))))
        .collect();
    let n = ls.len() as f64;
    let (ml, mv) = (ls.iter().sum::<f64>() / n, vs.iter().sum::<f64>() / n);
    let sxy: f64 = ls.iter().zip(&vs).map(|(l, v)| (l - ml) * (v - mv)).sum();
    let sxx: f64 = ls.iter().map(|l| (l - ml).powi(2)).sum();
    let (b, a) = (sxy / sxx, mv - sxy / sxx * ml);
    ls.iter()
        .zip(&vs)
        .map(|(l, v)| ((v - a) / b - l).abs() / (hi - lo))
        .fold(0.0, f64::max)
}

#[test]
fn a_picture_style_is_found_and_the_values_made_linear() {
    // Paper white at 0.9: the sine spans 0.09–0.81 of clipping.
    for k in [1.0, 2.0, 3.0] {
        let camera = move |l: f64| crate::measure::synth::picture_style(srgb(l), k);
        let (prof, law) = profile(camera, |_| 0.9);
        let f = fit(&prof, &law, &|_| 1.0, &Tone::Srgb).unwrap();
        assert!(f.used && f.significance > 50.0, "k {k}: {f:?}");
        // Read through sRGB alone, MTF 0.5 reads high (the modulation ratio of
        // two sines through the curve, computed apart: +1.5 / +5.9 / +12.0 %
        // at a mean of 0.3 for k = 1 / 2 / 3, here at 0.45 less).
        assert!(f.effect < -0.005, "k {k}: {}", f.effect);
        let dev = affine_departure(&f, camera, 0.095, 0.805);
        assert!(
            dev < 0.003,
            "k {k}: the corrected light departs by {dev:.5} of its range"
        );
        // Without the correction the departure is tens of times larger.
        let none = ToneFix {
            passes: Vec::new(),
            ..f.clone()
        };
        let raw = affine_departure(&none, camera, 0.095, 0.805);
        assert!(
            raw > 5.0 * dev.max(0.001),
            "k {k}: {raw:.5} against {dev:.5}"
        );
    }
}

#[test]
fn uneven_light_under_a_used_correction_is_warned() {
    let camera = |l: f64| crate::measure::synth::picture_style(srgb(l), 2.0);
    // Light falling 2:1 along the strip: the curve's unseen offset moves the MTF.
    let (prof, law) = profile(camera, |s| 0.9 - 0.45 * s / 1200.0);
    let f = fit(&prof, &law, &|_| 1.0, &Tone::Srgb).unwrap();
    // Stretch means of the light: 0.872 first, 0.478 last (1.82:1); read
    // through the curve's unseen offset, more (2.3).
    assert!(
        f.light_ratio > 1.6 && f.light_ratio < 2.6,
        "{}",
        f.light_ratio
    );
    assert!(f.used && f.uneven_light(), "{f:?}");
    assert!(f.uneven_light_warning().contains(":1 along the strip"));
    // Even light: no warning.
    let (prof, law) = profile(camera, |_| 0.9);
    let f = fit(&prof, &law, &|_| 1.0, &Tone::Srgb).unwrap();
    assert!(f.used && !f.uneven_light() && f.light_ratio < 1.05, "{f:?}");
}

#[test]
fn a_sharpened_code_is_not_taken_for_a_tone_curve() {
    // sRGB alone, the code sharpened: the periods' shapes bend (the
    // harmonics gain more than the fundamental), more at each higher
    // frequency, which a tone curve cannot do. Fitted as a tone alone
    // (before session 26) they read 16 σ and 11 σ, and the second was
    // taken out (the MTF at 0.5 moved by +0.4 %). A mask of radius 1.5
    // px at amount 1 reads 6.8 σ (+0.4 %, noiseless): its gain saturates
    // within the windows read, beyond what q and q² follow; it was taken
    // out until session 27 raised the use threshold to 10 σ.
    for (amount, radius) in [(0.5, 0.8), (0.8, 1.2), (1.0, 1.5)] {
        let (prof, law) = sharpened(srgb, amount, radius);
        let f = fit(&prof, &law, &|_| 1.0, &Tone::Srgb).unwrap();
        assert!(f.sharpening_seen && !f.used, "{amount} {radius}: {f:?}");
        let bar = if radius < 1.5 {
            MIN_SIGNIFICANCE
        } else {
            MIN_USE_SIGNIFICANCE
        };
        assert!(f.significance < bar, "{amount} {radius}: {f:?}");
    }
}

#[test]
fn a_picture_style_under_a_sharpened_code_is_still_found() {
    // A picture style with the code sharpened after it: the curve is
    // still found, as straight as without the sharpening (the bar of
    // `a_picture_style_is_found_and_the_values_made_linear`). Fitted as
    // a tone alone (before session 26), k = 1 departed by 0.0039.
    for k in [1.0, 2.0] {
        let camera = move |l: f64| crate::measure::synth::picture_style(srgb(l), k);
        let (prof, law) = sharpened(camera, 0.8, 1.2);
        let f = fit(&prof, &law, &|_| 1.0, &Tone::Srgb).unwrap();
        let dev = affine_departure(&f, camera, 0.095, 0.805);
        assert!(f.used && f.sharpening_seen, "k {k}: {f:?}");
        assert!(
            dev < 0.003,
            "k {k}: the corrected light departs by {dev:.5} of its range"
        );
    }
}

#[test]
fn curved_light_on_an_exact_sine_is_not_a_tone() {
    // Vignetting across the low end: the windows' linear trends leave a
    // little curvature, which the fit sees (≈ 10 σ on noiseless data)
    // but which changes the MTF by less than MIN_EFFECT: not used. With
    // a sharpening of the code fitted beside the tone (it takes some of
    // the curvature for one, noiseless) the effect is −0.09 %, against
    // −0.05 % with the tone alone: the margin left is small.
    let light = |s: f64| 0.8 * (1.0 - 0.5 * ((s - 600.0) / 700.0).powi(2));
    let (mut prof, law) = profile(srgb, light);
    for (y, &s) in prof.y.iter_mut().zip(&prof.s) {
        *y = light(s) * 0.5 * (1.0 + 0.8 * (std::f64::consts::TAU * law.phase(s)).sin());
    }
    let f = fit(&prof, &law, &|_| 1.0, &Tone::Srgb).unwrap();
    assert!(!f.used && f.effect.abs() < MIN_EFFECT, "{f:?}");
}

#[test]
fn clipped_periods_are_not_read_and_too_few_give_none() {
    // Paper white beyond clipping: every low-end window holds a clipped code.
    let (prof, law) = profile(|l| srgb(l).min(1.0), |_| 1.4);
    assert!(fit(&prof, &law, &|_| 1.0, &Tone::Srgb).is_none());
}

#[test]
fn a_power_law_file_with_a_picture_style_on_top() {
    // The file says gamma 2.2; the camera put its style on that code.
    let camera = |l: f64| crate::measure::synth::picture_style(l.powf(1.0 / 2.2), 2.0);
    let (mut prof, law) = profile(camera, |_| 0.9);
    // `profile` decodes with sRGB: decode with the file's power law instead.
    for y in prof.y.iter_mut() {
        *y = Tone::Gamma(2.2).apply(srgb(*y));
    }
    let f = fit(&prof, &law, &|_| 1.0, &Tone::Gamma(2.2)).unwrap();
    assert!(f.used, "{f:?}");
    let v = |l: f64| f.linear(Tone::Gamma(2.2).apply(camera(l)));
    // Equal steps of light give equal steps of corrected value (within 1 %).
    let steps: Vec<f64> = (0..8)
        .map(|i| v(0.15 + 0.08 * (i + 1) as f64) - v(0.15 + 0.08 * i as f64))
        .collect();
    let mean = steps.iter().sum::<f64>() / 8.0;
    assert!(
        steps.iter().all(|s| (s / mean - 1.0).abs() < 0.01),
        "{steps:?}"
    );
}

#[test]
fn a_pure_sine_through_srgb_needs_no_correction() {
    let (prof, law) = profile(srgb, |s| 0.8 - 0.2 * s / 1200.0);
    let f = fit(&prof, &law, &|_| 1.0, &Tone::Srgb).unwrap();
    assert!(!f.used, "{f:?}");
    assert!(f.max_shift_255 < 0.5, "{f:?}");
}
