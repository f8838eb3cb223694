//! The tone left in a strip: a camera's own tone curve (its picture style's
//! S-curve) on top of the curve the file declares, found from the shape of
//! the strip's low-frequency periods and taken out.
//!
//! The chart's sine is printed in reflectance and a lens is linear, so in
//! linear light every period is a pure sine, whatever the MTF. A tone curve
//! that the decoding does not undo bends it: harmonics appear, and the
//! modulation read depends on the amplitude (a sine about a third of
//! clipping through a tanh S-curve of strength 2 on the sRGB code reads an
//! MTF of 0.5 as 0.53). Camera JPEGs carry such curves (simulated sRGB + a
//! tanh S-curve of strength 1–2.5 in code: MTF50 up to +6 %).
//!
//! The correction is linear in light: `v' = v + Σ βⱼ ψⱼ(c)`, with `c` the
//! code the file's tone gives the decoded value `v`, and ψⱼ the first-order
//! effects of a quintic correction of the code (`D'(c)·uᵏ`, k < [`TERMS`],
//! `u` the code scaled to the range read) made orthogonal to `1` and `v`
//! over the data; up to [`MAX_PASSES`] passes, each fitting what the ones
//! before left. An affine change of the linear values (an offset, a gain)
//! leaves every period a sine, so the shape cannot tell it: it is left out,
//! and the chart modulation stays as the file's tone reads it; where the
//! light changes along the strip that unseen offset also bends the MTF;
//! there the paper beside the strip gives it ([`super::tone_black`]), and
//! where it cannot, a light above [`MAX_EVEN_LIGHT`] is warned. Over windows of
//! [`WINDOW_CYCLES`] cycles at the strip's low end the values must be a
//! local mean, a sine and a cosine at the law's phase, each with a linear
//! trend (light); β is their weighted least-squares fit with the windows'
//! parameters profiled out, residuals weighted in code units (where the
//! file's noise and rounding are). It is used only where it is significant
//! (Wald distance from none > [`MIN_USE_SIGNIFICANCE`] σ), changes the MTF at 0.5
//! by more than [`MIN_EFFECT`], and keeps the values in order.
//!
//! A camera's JPEG engine also sharpens the code (an unsharp mask after its
//! tone curve), and that bends a period's shape too: each harmonic of the
//! code gains more than the fundamental. But a mask's gain departs from 1 as
//! f² near 0, so its bend grows with the window's frequency while a tone
//! curve's does not. Beside the tone, each direction is fitted again times
//! q and q² (q = (f/[`MAX_FREQ_CY_PX`])², f each row's local frequency), as a
//! nuisance that is set aside, not taken out (the sharpening is the
//! camera's MTF); the tone is then its f → 0 limit. The nuisance is used
//! only where it explains significantly more than the tone alone
//! ([`MIN_SHARPENING_SIGNIFICANCE`], nested fits), so a strip without it is
//! fitted exactly as before; where it is, the tone's significance is its
//! Wald distance with the nuisance profiled out. Independent camera, sRGB
//! with its code sharpened (amount 0.3–1, radius 0.6–1.5 px; seeds 4 and 6,
//! 20 shots): read as a tone alone, a correction was taken out of 18 and
//! the chart modulation read up to +0.55 % (4 beyond 0.5 %); now none,
//! and +0.06…+0.46 %.

use super::PhaseLaw;
use super::profile::Profile;
use crate::photo::linearise::Tone;
use rayon::prelude::*;

mod system;
pub(super) use system::window_row;
use system::{Row, fit_pass, windows};

/// Code polynomial degrees of the correction (0 … TERMS − 1).
pub const TERMS: usize = 6;
/// Cycles per window of the shape fit.
pub const WINDOW_CYCLES: f64 = 2.0;
/// Highest local frequency (cy/px) read for the shape: its harmonics stay
/// clear of Nyquist and of a camera's sharpening.
pub const MAX_FREQ_CY_PX: f64 = 0.06;
/// Where fewer than [`MIN_WINDOWS`] windows lie below [`MAX_FREQ_CY_PX`],
/// the fit reads up to this frequency (cy/px).
pub const MAX_FREQ_STRETCH_CY_PX: f64 = 0.12;
/// Fewest windows the fit needs.
pub const MIN_WINDOWS: usize = 3;
/// A further pass is fitted only beyond this distance from none (σ, Wald).
pub const MIN_SIGNIFICANCE: f64 = 5.0;
/// A correction is used only beyond this distance from none (σ, Wald; its
/// first pass). The Wald distance takes the windows' residuals as
/// independent; JPEG's blocks, uneven light and the lens make them share:
/// on 20 shots of the independent camera with no tone beyond sRGB
/// (everything at once: q75, 2:1 light, sharpening, distortion) it reached
/// 6.1 σ, and at 5 σ three were "corrected" (one chart modulation +2.9 %,
/// RMS 0.018); the weakest picture style drawn there (tanh strength 1) read
/// 20–162 σ (session 27).
pub const MIN_USE_SIGNIFICANCE: f64 = 10.0;
/// A sharpening of the code is fitted beside the tone only where it explains
/// the windows' shapes beyond this distance from none (σ, Wald; nested fits).
/// As for [`MIN_USE_SIGNIFICANCE`], the windows' residuals are not
/// independent (JPEG's blocks, uneven light, the lens), and this test adds
/// 2 × [`TERMS`] parameters: on shots of the independent camera whose code
/// is not sharpened (`camera`, `tone`: sharpening in linear light, if any,
/// which is the lens's MTF and keeps a sine a sine) its first pass read
/// 2.6–6.9 σ (32 shots; a later pass up to 39), and at 5 σ the nuisance was
/// fitted on half of them; it then took most of the tone with it (`camera`
/// seed 71 #6: the tone at 16 σ instead of 46, the black level's line through
/// the paper lost, MTF −0.17 at 0.15 cy/px against a claim of ±0.025).
/// Shots whose code is sharpened read 4.1–16.3 σ; at 10 those below lose
/// nothing measurable (session 44, independent camera, 5 σ → 10 σ: `camera`
/// seeds 71 and 76, 40 shots, mean RMS |MTF − truth| 0.0165 → 0.0102 and
/// 0.0109 → 0.0086; `jpegcam` seeds 73 and 77, 0.0057 → 0.0053 and
/// 0.0081 → 0.0080; `codesharp` seed 74 and `tone` seed 75 unchanged).
pub const MIN_SHARPENING_SIGNIFICANCE: f64 = 10.0;
/// A correction is used only where it changes the MTF at 0.5 by more than
/// this fraction.
pub const MIN_EFFECT: f64 = 0.001;
/// Above this ratio of the light along a strip a used correction is warned
/// about ([`ToneFix::uneven_light`]).
/// (Independent camera, picture styles: light 1.03–1.11 RMS ≤ 0.0055, MTF50
/// within ±1.1 %; 1.5–2.1 up to 0.076 and ±6.8 %.)
pub const MAX_EVEN_LIGHT: f64 = 1.2;
/// Codes (0–1) at or above this are taken as clipped: their window is left out.
pub(super) const CODE_HIGH: f64 = 0.985;
/// Codes (0–1) at or below this are taken as clipped black.
const CODE_LOW: f64 = 0.01;
/// Window parameters: mean, its slope, sine, cosine and their slopes.
pub(super) const NX: usize = 6;
/// Functions the correction is made of: 1, v and D'(c)·uᵏ.
const NF: usize = TERMS + 2;
/// Parameters of a pass's fit: the correction's directions and, as a
/// nuisance, each times (f / [`MAX_FREQ_CY_PX`])² (a sharpening of the code).
const NP: usize = (1 + NS) * TERMS;
/// Families of the sharpening nuisance: each direction times q and q², with
/// q = (f / [`MAX_FREQ_CY_PX`])² (the mask's gain 1 + a·(1 − e^(−2π²r²f²))
/// is quadratic in f only well below 1/r; its saturation needs the second).
const NS: usize = 2;

/// One pass of a correction: `v' = v + coef · (1, v, D'(c)·uᵏ)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pass {
    /// Coefficients over 1, v and D'(c)·uᵏ (linear units).
    pub coef: [f64; NF],
    /// Code (0–1) at u = 0 and the half-range u is scaled by.
    pub code_mid_half: (f64, f64),
}

impl Pass {
    /// The value `v` (linear, decoded with `base`) after this pass.
    fn apply(&self, base: &Tone, v: f64) -> f64 {
        let c = code_of(base, v);
        let f = functions(base, c, v, self.code_mid_half);
        v + self.coef.iter().zip(f).map(|(a, b)| a * b).sum::<f64>()
    }
}

/// A tone correction found in a strip.
#[derive(Debug, Clone, PartialEq)]
pub struct ToneFix {
    /// The tone the planes were decoded with.
    pub base: Tone,
    /// The passes, in order: each fits what the ones before left (the first
    /// is a first-order correction; a strong curve needs a second or third).
    pub passes: Vec<Pass>,
    /// Wald distance of the first pass from none (σ).
    pub significance: f64,
    /// Relative change of the MTF at 0.5 it makes (e.g. −0.03).
    pub effect: f64,
    /// Largest move of a code in the range read, in 8-bit steps (code × 255).
    pub max_shift_255: f64,
    /// The code range (0–1) the shape was read over.
    pub code_range: (f64, f64),
    /// Windows read.
    pub windows: usize,
    /// The light's largest ratio along the strip (the brightest of eight
    /// equal stretches' mean over the darkest; 1 where the correction is not used).
    pub light_ratio: f64,
    /// Whether it is applied (significant, large enough, values kept in order).
    pub used: bool,
    /// Whether a camera's sharpening of the code was seen in the periods'
    /// shapes and set aside (fitted beside the tone, not taken out).
    pub sharpening_seen: bool,
    /// The black level the curve leaves unseen, from the paper beside the
    /// strip (read only when used; see [`super::tone_black`]).
    pub black: Option<super::tone_black::BlackLevel>,
}

impl ToneFix {
    /// The corrected linear value for a value `v` decoded with the base tone.
    pub fn linear(&self, v: f64) -> f64 {
        self.passes.iter().fold(v, |v, p| p.apply(&self.base, v))
    }

    /// Whether it is significant and large enough to use (then unused only
    /// because it would put the values out of order: a warning).
    pub fn needed(&self) -> bool {
        self.significance > MIN_USE_SIGNIFICANCE && self.effect.abs() > MIN_EFFECT
    }

    /// Whether the light changes so much along the strip that the curve's
    /// unseen offset moves the MTF's shape, and the paper did not give it
    /// (a warning when used).
    pub fn uneven_light(&self) -> bool {
        self.used
            && self.light_ratio > MAX_EVEN_LIGHT
            && !self.black.as_ref().is_some_and(|b| b.claims())
    }

    /// The warning for [`Self::uneven_light`].
    pub fn uneven_light_warning(&self) -> String {
        format!(
            "the light changes {:.2}:1 along the strip, and with a camera tone curve taken out \
             the MTF's shape then depends on the curve's black level, which a sine's shape does \
             not show and the paper beside the strip did not give clearly (simulated picture styles: \
             light 1.5–2.1:1, MTF50 off by up to ±7 %; 1.03–1.11:1, ±1.1 %; each point's \
             uncertainty carries it, see the chart modulation's); light the chart \
             evenly (or brightest at the strip's low-frequency end, on plain paper), or give \
             --tone chart with grey patches",
            self.light_ratio
        )
    }

    /// The summary's line for it.
    pub fn describe(&self) -> String {
        let (lo, hi) = self.code_range;
        let black = self.black.as_ref().is_some_and(|b| b.used);
        let what = if self.used && black {
            "taken out, its black level from the paper beside the strip"
        } else if self.used {
            "taken out (the chart modulation stays as the file's tone reads it: an offset or gain of the light does not change a sine's shape)"
        } else {
            "not taken out (it would put the values out of order)"
        };
        let sharpening = if self.sharpening_seen {
            "; a sharpening of the code (its effect on the periods' shapes grows with frequency, \
             a tone curve's does not) was fitted beside it and left in the MTF"
        } else {
            ""
        };
        format!(
            "the strip's low-frequency periods are not sine-shaped through the file's tone \
             (a camera's own tone curve): codes {:.0}–{:.0} off by up to {:.1}/255 ({:.0} σ); \
             read through it, an MTF of 0.5 comes out {:+.1} % off; {what}{sharpening}",
            255.0 * lo,
            255.0 * hi,
            self.max_shift_255,
            self.significance,
            -100.0 * self.effect
        )
    }
}

/// The correction's functions at code `c` (linear value `v`): 1, v, D'(c)·uᵏ.
fn functions(base: &Tone, c: f64, v: f64, (mid, half): (f64, f64)) -> [f64; NF] {
    let slope = slope(base, c);
    // Beyond the range read the polynomial is held at its ends' level.
    let u = ((c - mid) / half).clamp(-1.0, 1.0);
    let mut f = [0.0; NF];
    f[0] = 1.0;
    f[1] = v;
    let mut p = 1.0;
    for k in 0..TERMS {
        f[2 + k] = slope * p;
        p *= u;
    }
    f
}

/// The code (0–1) a tone gives a linear value: closed forms for sRGB and a
/// power law, bisection on a tabulated curve.
pub fn code_of(tone: &Tone, y: f64) -> f64 {
    match tone {
        Tone::Srgb => crate::photo::linearise::linear_to_srgb(y.max(0.0)),
        Tone::Gamma(g) if *g > 0.0 => y.max(0.0).powf(1.0 / g),
        _ => {
            let (mut lo, mut hi) = (0.0, 1.0);
            for _ in 0..48 {
                let mid = 0.5 * (lo + hi);
                if tone.apply(mid) < y {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            0.5 * (lo + hi)
        }
    }
}
/// The base tone's slope dD/dc at code `c`.
fn slope(base: &Tone, c: f64) -> f64 {
    let h = 1e-4;
    (base.apply(c + h) - base.apply(c - h)) / (2.0 * h)
}

/// The change a correction `g` makes to the ratio of the modulations
/// (fundamental over mean) of two sines of linear mean `mean` and amplitudes
/// `amp` and `amp`/2: the relative change of an MTF of 0.5 it makes.
fn effect_at_half(g: &dyn Fn(f64) -> f64, mean: f64, amp: f64) -> f64 {
    let fundamental = |a: f64| -> f64 {
        let n = 64;
        let (mut s, mut c, mut m) = (0.0, 0.0, 0.0);
        for i in 0..n {
            let ph = std::f64::consts::TAU * i as f64 / n as f64;
            let v = g(mean + a * ph.sin());
            s += v * ph.sin();
            c += v * ph.cos();
            m += v;
        }
        s.hypot(c) / m
    };
    2.0 * fundamental(0.5 * amp) / fundamental(amp) - 1.0
}

/// Most passes of a correction.
pub const MAX_PASSES: usize = 3;

/// The tone correction of a strip binned with the base tone `base`, from its
/// low-frequency periods along `law`: passes while the last is significant
/// and changes the MTF at 0.5 by more than [`MIN_EFFECT`]; None where too few
/// clean windows lie at the low end or the fit is singular.
pub fn fit(
    prof: &Profile,
    law: &PhaseLaw,
    s_per_px: &(dyn Fn(f64) -> f64 + Sync),
    base: &Tone,
) -> Option<ToneFix> {
    let wins = windows(prof, law, s_per_px, base);
    if wins.len() < MIN_WINDOWS {
        return None;
    }
    let first = fit_pass(&wins, base)?;
    let mut fix = ToneFix {
        base: base.clone(),
        passes: vec![first.pass],
        significance: first.significance,
        effect: 0.0,
        max_shift_255: 0.0,
        code_range: first.code_range,
        windows: first.windows,
        light_ratio: 1.0,
        used: false,
        sharpening_seen: first.sharpening_seen,
        black: None,
    };
    let mut last = first;
    while fix.passes.len() < MAX_PASSES
        && last.significance > MIN_SIGNIFICANCE
        && last.effect.abs() > MIN_EFFECT
    {
        // The rows as the passes so far leave them (read where the original codes were clean).
        let work: Vec<Vec<Row>> = wins
            .par_iter()
            .map(|w| {
                w.iter()
                    .map(|r| r.with_value(base, fix.linear(r.v)))
                    .collect()
            })
            .collect();
        let Some(next) = fit_pass(&work, base) else {
            break;
        };
        if !(next.significance > MIN_SIGNIFICANCE) {
            break;
        }
        // A pass that would put the values out of order is a degenerate fit,
        // not a stronger curve: it is left out and the passes before it kept
        // (the independent camera's `camera` seed 45 #5: two passes in order,
        // moving codes by up to 34/255; a third moved them by 382/255 and, as
        // the whole correction was then refused, MTF50 read −4.9 % off).
        let mut more = fix.clone();
        more.passes.push(next.pass);
        if !in_order(&corrected_codes(&more)) {
            break;
        }
        fix.passes.push(next.pass);
        fix.sharpening_seen |= next.sharpening_seen;
        last = next;
    }
    let corrected = corrected_codes(&fix);
    fix.max_shift_255 = corrected
        .iter()
        .map(|&(c, v)| 255.0 * (code_of(base, v) - c).abs())
        .fold(0.0, f64::max);
    let (lo, hi) = fix.code_range;
    let (vlo, vhi) = (base.apply(lo), base.apply(hi));
    fix.effect = effect_at_half(&|v| fix.linear(v), 0.5 * (vlo + vhi), 0.5 * (vhi - vlo));
    fix.used = fix.needed()
        && in_order(&corrected)
        && fix.passes.iter().flat_map(|p| p.coef).all(f64::is_finite);
    // The light along the whole strip is read only for a correction that is used.
    if fix.used {
        fix.light_ratio = light_ratio(prof, law, &|v| fix.linear(v));
    }
    Some(fix)
}

/// A correction's values at 65 codes evenly over the range it was read over
/// (code 0–1, corrected linear value).
fn corrected_codes(fix: &ToneFix) -> Vec<(f64, f64)> {
    let (lo, hi) = fix.code_range;
    let steps = 64;
    (0..=steps)
        .map(|i| {
            let c = lo + (hi - lo) * i as f64 / steps as f64;
            (c, fix.linear(fix.base.apply(c)))
        })
        .collect()
}

/// Whether corrected values rise with the code (a correction keeps them in order).
fn in_order(corrected: &[(f64, f64)]) -> bool {
    corrected.windows(2).all(|p| p[1].1 > p[0].1)
}

/// The light's largest ratio along a profile whose values `g` corrects: the
/// mean corrected value over the whole periods of each of eight equal
/// stretches, brightest over darkest.
fn light_ratio(prof: &Profile, law: &PhaseLaw, g: &dyn Fn(f64) -> f64) -> f64 {
    let (Some(&s0), Some(&s1)) = (prof.s.first(), prof.s.last()) else {
        return 1.0;
    };
    let n = 8;
    let means: Vec<f64> = (0..n)
        .filter_map(|k| {
            let (a, b) = (
                s0 + (s1 - s0) * k as f64 / n as f64,
                s0 + (s1 - s0) * (k + 1) as f64 / n as f64,
            );
            let (pa, pb) = (law.phase(a).ceil(), law.phase(b).floor());
            if !(pb > pa) {
                return None;
            }
            let (sa, sb) = (law.s_at_phase(pa, s0, s1), law.s_at_phase(pb, s0, s1));
            prof.mean_within(sa, sb, g)
        })
        .collect();
    let hi = means.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let lo = means.iter().cloned().fold(f64::INFINITY, f64::min);
    if lo > 0.0 && hi.is_finite() {
        hi / lo
    } else {
        1.0
    }
}

/// Applies a used correction to a profile's values (linear light).
pub fn apply(fix: &ToneFix, prof: &mut Profile) {
    if fix.used {
        for y in prof.y.iter_mut() {
            *y = fix.linear(*y);
        }
    }
}

#[cfg(test)]
mod tests;
