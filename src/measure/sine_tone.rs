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
//! (Wald distance from none > [`MIN_SIGNIFICANCE`] σ), changes the MTF at 0.5
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
/// A correction is used only beyond this distance from none (σ, Wald).
pub const MIN_SIGNIFICANCE: f64 = 5.0;
/// A sharpening of the code is fitted beside the tone only where it explains
/// the windows' shapes beyond this distance from none (σ, Wald; nested fits).
pub const MIN_SHARPENING_SIGNIFICANCE: f64 = 5.0;
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
        self.significance > MIN_SIGNIFICANCE && self.effect.abs() > MIN_EFFECT
    }

    /// Whether the light changes so much along the strip that the curve's
    /// unseen offset moves the MTF's shape, and the paper did not give it
    /// (a warning when used).
    pub fn uneven_light(&self) -> bool {
        self.used
            && self.light_ratio > MAX_EVEN_LIGHT
            && !self.black.as_ref().is_some_and(|b| b.used)
    }

    /// The warning for [`Self::uneven_light`].
    pub fn uneven_light_warning(&self) -> String {
        format!(
            "the light changes {:.2}:1 along the strip, and with a camera tone curve taken out \
             the MTF's shape then depends on the curve's black level, which a sine's shape does \
             not show and the paper beside the strip did not give (simulated picture styles: \
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

/// One bin read for the shape: code, linear value, samples, weight, window design row.
#[derive(Clone)]
struct Row {
    c: f64,
    v: f64,
    n: f64,
    w: f64,
    x: [f64; NX],
    /// (f / [`MAX_FREQ_CY_PX`])² at the row's local frequency f: the scale of
    /// a sharpening of the code, which bends a period's shape as a tone
    /// curve does but vanishes as f → 0.
    q: f64,
}

impl Row {
    /// The row with its value `v` (decoded with `base`) replaced.
    fn with_value(&self, base: &Tone, v: f64) -> Row {
        let c = code_of(base, v);
        Row {
            c,
            v,
            w: self.n / slope(base, c).powi(2).max(1e-300),
            ..self.clone()
        }
    }
}

/// The base tone's slope dD/dc at code `c`.
fn slope(base: &Tone, c: f64) -> f64 {
    let h = 1e-4;
    (base.apply(c + h) - base.apply(c - h)) / (2.0 * h)
}

/// The bins of each window at the strip's low end (from one cycle past its
/// start), up to [`MAX_FREQ_CY_PX`] (or [`MAX_FREQ_STRETCH_CY_PX`] when that
/// gives fewer than [`MIN_WINDOWS`]); windows with a clipped code are left
/// out. Weights: samples over D'(c)², so residuals count in code units.
fn windows(
    prof: &Profile,
    law: &PhaseLaw,
    s_per_px: &dyn Fn(f64) -> f64,
    base: &Tone,
) -> Vec<Vec<Row>> {
    let (Some(&s0), Some(&s1)) = (prof.s.first(), prof.s.last()) else {
        return Vec::new();
    };
    let p0 = law.phase(s0) + 1.0;
    let read = |f_max: f64| -> Vec<Vec<Row>> {
        let mut out = Vec::new();
        let mut k = 0.0;
        loop {
            let (a, b) = (p0 + k * WINDOW_CYCLES, p0 + (k + 1.0) * WINDOW_CYCLES);
            k += 1.0;
            if b > law.phase(s1) - 0.5 {
                break;
            }
            let (sa, sb) = (law.s_at_phase(a, s0, s1), law.s_at_phase(b, s0, s1));
            if law.freq(sb) * s_per_px(sb) > f_max {
                break;
            }
            let (mid, half) = (0.5 * (sa + sb), 0.5 * (sb - sa));
            let bins = prof.bins_within(sa, sb);
            let mut rows = Vec::with_capacity(bins.len());
            let mut clipped = false;
            for i in bins {
                let (v, c) = (prof.y[i], code_of(base, prof.y[i]));
                clipped |= !(CODE_LOW..CODE_HIGH).contains(&c);
                let f = law.freq(prof.s[i]) * s_per_px(prof.s[i]);
                rows.push(Row {
                    c,
                    v,
                    n: prof.count[i],
                    w: prof.count[i] / slope(base, c).powi(2).max(1e-300),
                    x: window_row(law, prof.s[i], mid, half),
                    q: (f / MAX_FREQ_CY_PX).powi(2),
                });
            }
            if !clipped && rows.len() >= 4 * NX {
                out.push(rows);
            }
        }
        out
    };
    let w = read(MAX_FREQ_CY_PX);
    if w.len() >= MIN_WINDOWS {
        w
    } else {
        read(MAX_FREQ_STRETCH_CY_PX)
    }
}

/// A window's design row at `s` (window middle `mid`, half-width `half`):
/// a mean, a sine and a cosine at the law's phase, and each times the
/// position d ∈ [−1, 1] (the light's trend).
pub(super) fn window_row(law: &PhaseLaw, s: f64, mid: f64, half: f64) -> [f64; NX] {
    let d = (s - mid) / half;
    let (sn, cs) = (std::f64::consts::TAU * law.phase(s)).sin_cos();
    [1.0, d, sn, cs, d * sn, d * cs]
}

/// The correction's directions: the functions D'(c)·uᵏ made orthonormal to
/// 1, v and each other over the rows (weighted Gram–Schmidt; `vals`: each
/// row's functions), as coefficient vectors over the functions; a function
/// (nearly) inside the span of those before it is dropped.
fn directions(rows: &[&Row], vals: &[[f64; NF]]) -> Vec<[f64; NF]> {
    let dot = |a: &[f64; NF], b: &[f64; NF]| -> f64 {
        rows.iter()
            .zip(vals)
            .map(|(r, f)| {
                let x: f64 = a.iter().zip(f).map(|(p, q)| p * q).sum();
                let y: f64 = b.iter().zip(f).map(|(p, q)| p * q).sum();
                r.w * x * y
            })
            .sum()
    };
    let mut basis: Vec<[f64; NF]> = Vec::new();
    let mut out = Vec::new();
    for j in 0..NF {
        let mut e = [0.0; NF];
        e[j] = 1.0;
        let norm0 = dot(&e, &e).sqrt();
        for q in &basis {
            let p = dot(&e, q);
            for m in 0..NF {
                e[m] -= p * q[m];
            }
        }
        let norm = dot(&e, &e).sqrt();
        if !(norm > 1e-5 * norm0) {
            continue;
        }
        e.iter_mut().for_each(|x| *x /= norm);
        basis.push(e);
        if j >= 2 {
            out.push(e);
        }
    }
    out
}

/// Per window, the Schur complement of the window parameters in the
/// weighted Gram matrix of [X | Ψ | v]: adds the profiled normal matrix to
/// `a` and the profiled right side to `b` (unused directions stay 0), and
/// returns the window's residual sum of squares with no correction
/// (`vals`: each row's functions).
fn profiled(
    rows: &[Row],
    vals: &[[f64; NF]],
    dirs: &[[f64; NF]],
    a: &mut [[f64; NP]; NP],
    b: &mut [f64; NP],
) -> Option<f64> {
    const M: usize = NX + NP + 1;
    let k = dirs.len();
    let mut g = [[0.0; M]; M];
    for (r, f) in rows.iter().zip(vals) {
        let mut z = [0.0; M];
        z[..NX].copy_from_slice(&r.x);
        for (j, d) in dirs.iter().enumerate() {
            let psi: f64 = d.iter().zip(f).map(|(p, q)| p * q).sum();
            z[NX + j] = psi;
            let mut qm = 1.0;
            for m in 1..=NS {
                qm *= r.q;
                z[NX + m * TERMS + j] = qm * psi;
            }
        }
        z[M - 1] = r.v;
        for i in 0..M {
            for j in i..M {
                g[i][j] += r.w * z[i] * z[j];
            }
        }
    }
    for i in 0..M {
        for j in 0..i {
            g[i][j] = g[j][i];
        }
    }
    let mut gxx = [[0.0; NX]; NX];
    for i in 0..NX {
        gxx[i].copy_from_slice(&g[i][..NX]);
    }
    let scale = (0..NX).map(|i| gxx[i][i]).fold(0.0, f64::max);
    // G_XX⁻¹ times each of the other columns (directions, their
    // sharpening twins, then v).
    let params: Vec<usize> = (0..=NS).flat_map(|m| m * TERMS..m * TERMS + k).collect();
    let cols: Vec<usize> = params.iter().map(|p| NX + p).chain([M - 1]).collect();
    let mut y = Vec::with_capacity(cols.len());
    for &col in &cols {
        let rhs: [f64; NX] = std::array::from_fn(|i| g[i][col]);
        y.push(crate::linalg::solve(gxx, rhs, 1e-12 * scale.max(1e-300))?);
    }
    let schur = |p: usize, q: usize, yq: &[f64; NX]| -> f64 {
        g[p][q] - (0..NX).map(|i| g[i][p] * yq[i]).sum::<f64>()
    };
    for &i in &params {
        for (yj, &j) in params.iter().enumerate() {
            a[i][j] += schur(NX + i, NX + j, &y[yj]);
        }
        b[i] += schur(NX + i, M - 1, &y[params.len()]);
    }
    Some(schur(M - 1, M - 1, &y[params.len()]).max(0.0))
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
    s_per_px: &dyn Fn(f64) -> f64,
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
            .iter()
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
        fix.passes.push(next.pass);
        fix.sharpening_seen |= next.sharpening_seen;
        last = next;
    }
    let (lo, hi) = fix.code_range;
    let steps = 64;
    let corrected: Vec<(f64, f64)> = (0..=steps)
        .map(|i| {
            let c = lo + (hi - lo) * i as f64 / steps as f64;
            (c, fix.linear(base.apply(c)))
        })
        .collect();
    fix.max_shift_255 = corrected
        .iter()
        .map(|&(c, v)| 255.0 * (code_of(base, v) - c).abs())
        .fold(0.0, f64::max);
    let in_order = corrected.windows(2).all(|p| p[1].1 > p[0].1);
    let (vlo, vhi) = (base.apply(lo), base.apply(hi));
    fix.effect = effect_at_half(&|v| fix.linear(v), 0.5 * (vlo + vhi), 0.5 * (vhi - vlo));
    fix.used =
        fix.needed() && in_order && fix.passes.iter().flat_map(|p| p.coef).all(f64::is_finite);
    // The light along the whole strip is read only for a correction that is used.
    if fix.used {
        fix.light_ratio = light_ratio(prof, law, &|v| fix.linear(v));
    }
    Some(fix)
}

/// One pass of the fit: the correction, its Wald distance from none (σ), the
/// change of the MTF at 0.5 it makes, the code range and windows read.
struct PassFit {
    pass: Pass,
    significance: f64,
    /// Whether a sharpening of the code was fitted beside the tone.
    sharpening_seen: bool,
    effect: f64,
    code_range: (f64, f64),
    windows: usize,
}

/// One pass: the first-order correction of the values in the windows' rows
/// (see the module text).
fn fit_pass(wins: &[Vec<Row>], base: &Tone) -> Option<PassFit> {
    let all: Vec<&Row> = wins.iter().flatten().collect();
    let (lo, hi) = all
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), r| {
            (l.min(r.c), h.max(r.c))
        });
    if !(hi > lo) {
        return None;
    }
    let mh = (0.5 * (lo + hi), 0.5 * (hi - lo));
    // Each row's functions, once per pass (the directions and the fit read them).
    let vals: Vec<[f64; NF]> = all.iter().map(|r| functions(base, r.c, r.v, mh)).collect();
    let dirs = directions(&all, &vals);
    if dirs.is_empty() {
        return None;
    }
    let (mut a, mut b) = ([[0.0; NP]; NP], [0.0; NP]);
    let mut rss0 = 0.0;
    let mut at = 0;
    for w in wins {
        rss0 += profiled(w, &vals[at..at + w.len()], &dirs, &mut a, &mut b)?;
        at += w.len();
    }
    // Unused directions: identity rows, so the padded system stays regular.
    for j in (0..=NS).flat_map(|m| m * TERMS + dirs.len()..(m + 1) * TERMS) {
        a[j][j] = 1.0;
    }
    let n = all.len();
    let k = dirs.len();
    // The tone alone: the least squares over its block, and the fall in the
    // residual it gives (βᵀAβ = −βᵀb).
    let (tone, explained_tone) = {
        let mut at = [[0.0; TERMS]; TERMS];
        for (row, full) in at.iter_mut().zip(&a) {
            row.copy_from_slice(&full[..TERMS]);
        }
        let bt: [f64; TERMS] = std::array::from_fn(|i| b[i]);
        let tiny = 1e-12 * (0..TERMS).map(|i| at[i][i]).fold(0.0, f64::max);
        let beta = crate::linalg::solve(at, bt.map(|x| -x), tiny.max(1e-300))?;
        let explained = -(0..TERMS).map(|j| beta[j] * bt[j]).sum::<f64>();
        (beta, explained)
    };
    let dof_tone = n.checked_sub(NX * wins.len() + k)?.max(1) as f64;
    let s2_tone = ((rss0 - explained_tone) / dof_tone).max(1e-300);
    // With a sharpening of the code beside it (each direction again times q
    // and q²): used where it explains significantly more. Where that larger
    // system cannot be solved, the tone alone stands.
    let with_sharpening = sharpened_fit(
        &a,
        &b,
        rss0,
        explained_tone,
        n,
        NX * wins.len() + k * (1 + NS),
    );
    let (beta, significance, sharpening_seen) = match with_sharpening {
        Some((beta, significance)) => (beta, significance, true),
        None => (tone, (explained_tone.max(0.0) / s2_tone).sqrt(), false),
    };
    let mut coef = [0.0; NF];
    for (j, d) in dirs.iter().enumerate() {
        for m in 0..NF {
            coef[m] += beta[j] * d[m];
        }
    }
    let pass = Pass {
        coef,
        code_mid_half: mh,
    };
    let (vlo, vhi) = (base.apply(lo), base.apply(hi));
    let one = |v: f64| pass.apply(base, v);
    Some(PassFit {
        pass,
        significance,
        sharpening_seen,
        effect: effect_at_half(&one, 0.5 * (vlo + vhi), 0.5 * (vhi - vlo)),
        code_range: (lo, hi),
        windows: wins.len(),
    })
}

/// The tone's coefficients and Wald distance (σ) fitted with a sharpening of
/// the code beside it (the normal system `a`, `b` over the tone's directions
/// and their q, q² twins; `rss0` the residual with none, `explained_tone` the
/// fall the tone alone gives, `n` rows and `used` parameters with the
/// windows'): None where the sharpening does not explain the shapes beyond
/// [`MIN_SHARPENING_SIGNIFICANCE`] more than the tone alone, or the system
/// is singular.
fn sharpened_fit(
    a: &[[f64; NP]; NP],
    b: &[f64; NP],
    rss0: f64,
    explained_tone: f64,
    n: usize,
    used: usize,
) -> Option<([f64; TERMS], f64)> {
    let tiny = 1e-12 * (0..NP).map(|i| a[i][i]).fold(0.0, f64::max);
    let both = crate::linalg::solve(*a, b.map(|x| -x), tiny.max(1e-300))?;
    let explained = -(0..NP).map(|j| both[j] * b[j]).sum::<f64>();
    let s2 = ((rss0 - explained) / n.checked_sub(used)?.max(1) as f64).max(1e-300);
    if !(((explained - explained_tone).max(0.0) / s2).sqrt() > MIN_SHARPENING_SIGNIFICANCE) {
        return None;
    }
    // The tone's Wald distance with the sharpening profiled out: the fall
    // beyond what the sharpening alone explains.
    let (mut a2, mut b2) = (*a, *b);
    for i in 0..NP {
        for j in 0..NP {
            if i < TERMS || j < TERMS {
                a2[i][j] = if i == j { 1.0 } else { 0.0 };
            }
        }
        if i < TERMS {
            b2[i] = 0.0;
        }
    }
    let g = crate::linalg::solve(a2, b2.map(|x| -x), tiny.max(1e-300))?;
    let sharp_only = -(0..NP).map(|j| g[j] * b2[j]).sum::<f64>();
    Some((
        std::array::from_fn(|i| both[i]),
        ((explained - sharp_only).max(0.0) / s2).sqrt(),
    ))
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
mod tests {
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
        };
        let n = (len / 0.25) as usize;
        let s: Vec<f64> = (0..n).map(|i| (i as f64 + 0.5) * 0.25).collect();
        let y = s
            .iter()
            .map(|&s| {
                let lin =
                    light(s) * 0.5 * (1.0 + 0.8 * (std::f64::consts::TAU * law.phase(s)).sin());
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
        // px at amount 1 still is (6.8 σ, +0.4 %, noiseless): its gain
        // saturates within the windows read, beyond what q and q² follow.
        for (amount, radius) in [(0.5, 0.8), (0.8, 1.2)] {
            let (prof, law) = sharpened(srgb, amount, radius);
            let f = fit(&prof, &law, &|_| 1.0, &Tone::Srgb).unwrap();
            assert!(f.sharpening_seen && !f.used, "{amount} {radius}: {f:?}");
            assert!(
                f.significance < MIN_SIGNIFICANCE,
                "{amount} {radius}: {f:?}"
            );
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
}
