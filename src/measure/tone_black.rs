//! The black level a camera's tone curve leaves unseen, found from the paper
//! around the strip where the light changes along it.
//!
//! [`super::sine_tone`] makes a strip's values affine in light,
//! `v' = α + β·ℓ`: an offset α leaves every period a sine, so the strip's
//! shape cannot tell it. The modulation read is then `m·L/(L + α/(βM))`
//! (L the light, M the strip's mean reflectance): under even light only the
//! chart modulation is scaled (divided out), but where the light changes
//! along the strip the MTF's shape bends (independent camera, picture style
//! with light 1.5–2.1:1: MTF50 off by up to ±5 %).
//!
//! The paper around the strip sees the same light through the same curve:
//! beside stretch k, `s_k = α + β·W·L_k`, while the strip's local mean (a
//! mean, a sine and a cosine at the law's phase and their trends, fitted
//! over the stretch: whatever the MTF) is `m_k = α + β·M·L_k`. So `m = c0 + c1·s`
//! with `c1 = M/W` and `c0 = α(1 − c1)`: where the light changes, a line
//! through the stretches gives α. A light that is a product of a profile
//! along the strip and one across it (a gradient, most of a vignette) only
//! scales `s` and leaves α. Two bands are read, [`GAP_PX`] beyond each long
//! edge and [`DEPTH_PX`] deep, and their mean is used (a light falling
//! across the strip cancels in it); each gives α alone too, and they must
//! agree within [`MAX_BAND_GAP`] (another strip, a label or the card's edge
//! in a band shows as a disagreement or a poor line). Paper brighter than
//! the codes the strip's shape was read over is left out (the correction is
//! not known there): where the light is strongest away from the strip's
//! low-frequency end, too little paper is left and α is not found. Used
//! only where the light changes enough ([`MIN_LIGHT_SPREAD`]), the line
//! holds ([`MAX_RESIDUAL`]) through at least [`MIN_STRETCHES`] stretches, α
//! is large enough to matter ([`MIN_EFFECT`]) and either significant
//! ([`MIN_SIGNIFICANCE`]) or known better than an unseen black level would
//! be claimed; then α is taken from the strip's values, and the claims rest
//! on its error (the line's bend carried to zero light) only where it is
//! significant ([`BlackLevel::claims`]).

use super::PhaseLaw;
use super::profile::{Profile, Strip};
use super::sine_tone::{CODE_HIGH, NX, ToneFix, code_of, window_row};
use crate::geometry::Homography;

/// Distance of each band of paper read from the strip's long edge, px.
pub const GAP_PX: f64 = 8.0;
/// Depth of each band of paper read, px.
pub const DEPTH_PX: f64 = 16.0;
/// The strip is cut into stretches of 1/STRETCHES of its length along it
/// (or one whole cycle, where that is longer).
pub const STRETCHES: usize = 32;
/// Fewest stretches a line needs.
/// (Independent camera, picture styles under light 1.5–2.3:1, seeds 52–53,
/// 40 shots: at 5, eight read 4 stretches of paper within the codes the
/// strip's shape was read over and were left with MTF50 2.0–6.7 % off; at 3,
/// a line through three read one shot's α at +3 % of the mean, its MTF50
/// then 5.7 % off against 3.8 % with α left unseen.)
pub const MIN_STRETCHES: usize = 4;
/// The paper's light must change at least this much (brightest over
/// darkest stretch) for α to be found.
pub const MIN_LIGHT_SPREAD: f64 = 1.08;
/// Largest RMS departure of the stretches from the line, as a fraction of
/// the strip's mean value.
pub const MAX_RESIDUAL: f64 = 0.004;
/// Largest difference of the two bands' α alone, as a fraction of the
/// strip's mean value (beyond their errors): a vignette near the frame's
/// edge parts them by up to 10 % (the pair's mean cancels it).
pub const MAX_BAND_GAP: f64 = 0.15;
/// α is used, and the modulations' claims rest on its error, beyond this
/// many times what the stretches' scatter (least squares) and the two bands'
/// disagreement would move it by. Nearer, it is used only where its error
/// on the modulations is smaller than the claim an unseen black level gives
/// them ([`super::tone_unseen::full_scale`]; a black level left unseen is not 0,
/// it is unknown), and the claims stay those ([`BlackLevel::claims`]).
pub const MIN_SIGNIFICANCE: f64 = 3.0;
/// α is used only where it is at least this fraction of the strip's mean value.
pub const MIN_EFFECT: f64 = 0.002;
/// A stretch's paper is read only where its mean code (0–1) lies at least
/// this far below the top of the code range the strip's shape was read over
/// (the correction is known only within it, and least well at its ends).
/// (Independent camera, picture styles under light 1.5–2.3:1, seeds 52–57,
/// 120 shots, with the mean code in place of every bin's, session 42: at
/// 0.01 mean RMS |MTF − truth| 0.0108, MTF50 beyond 3 % in 12; at 0.005
/// 0.0098 and 9; at 0 0.0090 and 6, but one shot's paper then lay at the
/// range's top, where the correction leans: a straight line through five
/// stretches put α 6 σ off and the chart modulation claimed ±2.3 % where it
/// read +11.7 %.)
pub const CODE_MARGIN: f64 = 0.005;

/// The black level found from the paper around a strip.
#[derive(Debug, Clone, PartialEq)]
pub struct BlackLevel {
    /// The offset α of the corrected values (linear units; taken from them when used).
    pub offset: f64,
    /// Its standard error (linear units).
    pub sigma: f64,
    /// Half the two bands' α alone apart (linear units; 0 where one band is
    /// read): the standard error of their mean as two readings of α, which
    /// carries what the light does across the strip beyond first order.
    pub band_spread: f64,
    /// α over the strip's mean corrected value (dimensionless).
    pub relative: f64,
    /// Stretches in the line.
    pub stretches: usize,
    /// Bands of paper read (0–2).
    pub bands: usize,
    /// The paper's light, brightest stretch over darkest.
    pub light_spread: f64,
    /// RMS departure from the line over the strip's mean value.
    pub residual: f64,
    /// Whether it is taken from the values.
    pub used: bool,
    /// Whether α lies beyond [`MIN_SIGNIFICANCE`] times what the stretches'
    /// scatter and the bands' disagreement would move it by: only then do
    /// the claims rest on its error ([`Self::claims`]).
    pub significant: bool,
    /// Why it is not used ("" when used).
    pub why_not: &'static str,
    /// The strip's mean corrected value before α is taken out (linear units).
    pub mean: f64,
}

impl BlackLevel {
    /// Whether it is taken out and the modulations' uncertainties rest on
    /// its own error. A used α nearer zero than [`MIN_SIGNIFICANCE`] times
    /// what the stretches' scatter and the bands' disagreement move it by is
    /// taken out (an estimate beats none: below) but leaves each modulation
    /// the claim of an unseen black level: it cannot be told from a
    /// correction that is wrong at the paper's codes. (Independent camera,
    /// `camera` seed 45 #5, whose tone fit lost a pass: α +0.36 ± 1.5 % of
    /// the mean from a straight line through four stretches, the chart
    /// modulation 18 % off; on α's error it claimed ±1.6 %.)
    pub fn claims(&self) -> bool {
        self.used && self.significant
    }

    /// The relative standard error it gives every modulation,
    /// √(σ² + band_spread²)/(mean − α).
    pub fn modulation_rel_err(&self) -> f64 {
        let d = self.mean - self.offset;
        let e = self.sigma.hypot(self.band_spread);
        if e.is_finite() && d > 0.0 { e / d } else { 0.0 }
    }

    /// The summary's line for it.
    pub fn describe(&self) -> String {
        if !self.offset.is_finite() {
            return format!(
                "the tone curve's black level is not found from the paper beside the strip: {}",
                self.why_not
            );
        }
        let what = if self.claims() {
            "taken out".to_string()
        } else if self.used {
            "taken out, but so near zero that each modulation keeps the uncertainty of an unseen \
             black level"
                .to_string()
        } else {
            format!("not taken out: {}", self.why_not)
        };
        format!(
            "the tone curve's black level from the paper beside the strip (light {:.2}:1 over {} \
             stretches, {} band{}): {:+.2} % of the strip's mean ({:.1} σ); {what}",
            self.light_spread,
            self.stretches,
            self.bands,
            if self.bands == 1 { "" } else { "s" },
            100.0 * self.relative,
            (self.offset / self.sigma.max(1e-300)).abs()
        )
    }
}

/// The two bands of paper beside a strip (above its t = 0 edge, below its
/// t = width edge), as strips with the same `s`.
pub fn bands(strip: &Strip) -> Vec<Strip> {
    let px_per_t = strip.px_per_t(0.5 * strip.length);
    if !(px_per_t.is_finite() && px_per_t > 0.0) {
        return Vec::new();
    }
    let (gap, depth) = (GAP_PX / px_per_t, DEPTH_PX / px_per_t);
    [-(gap + depth), strip.width + gap]
        .into_iter()
        .map(|t0| Strip {
            to_image: strip.to_image.compose(&Homography {
                m: [1.0, 0.0, 0.0, 0.0, 1.0, t0, 0.0, 0.0, 1.0],
            }),
            lens: strip.lens,
            length: strip.length,
            width: depth,
        })
        .collect()
}

/// A line `m = c0 + c1·s` through the stretches: α = c0/(1 − c1), its
/// error as scatter and as a bend, and the RMS residual.
struct Line {
    alpha: f64,
    /// α's least-squares standard error (times Student's t): what scatter
    /// about the line would move it by.
    scatter: f64,
    /// α's error where the departures are a bend (claimed).
    sigma: f64,
    c1: f64,
    rms: f64,
}

fn line(pts: &[(f64, f64)]) -> Option<Line> {
    let k = pts.len() as f64;
    if pts.len() < MIN_STRETCHES {
        return None;
    }
    let xm = pts.iter().map(|p| p.0).sum::<f64>() / k;
    let ym = pts.iter().map(|p| p.1).sum::<f64>() / k;
    let sxx: f64 = pts.iter().map(|p| (p.0 - xm).powi(2)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - xm) * (p.1 - ym)).sum();
    if !(sxx > 0.0) {
        return None;
    }
    let c1 = sxy / sxx;
    let c0 = ym - c1 * xm;
    let rss: f64 = pts.iter().map(|p| (p.1 - c0 - c1 * p.0).powi(2)).sum();
    let s2 = rss / (k - 2.0);
    let (v0, v1, v01) = (s2 * (1.0 / k + xm * xm / sxx), s2 / sxx, -xm * s2 / sxx);
    let d = 1.0 - c1;
    if !(d.abs() > 1e-6) {
        return None;
    }
    let (g0, g1) = (1.0 / d, c0 / (d * d));
    let var = g0 * g0 * v0 + g1 * g1 * v1 + 2.0 * g0 * g1 * v01;
    let scatter = var.max(0.0).sqrt() * t_one_sigma(pts.len() - 2);
    Some(Line {
        alpha: c0 / d,
        scatter,
        // The stretches depart from the line by a bend, not by independent
        // scatter: noise-free shots of the independent camera depart as much
        // (RMS 0.10–0.24 % of the mean against 0.06–0.27 % with noise; the
        // correction and the local means are not exactly affine in light),
        // and a bend does not average out over the stretches. So α's error
        // is the departure carried to zero light by the line's lever: the
        // least-squares error times √k, and times Student's t for the few
        // residuals that tell the bend's size. (`tonelight` seed 52 #0, #7, #9
        // noise-free: the chart modulation read 1.7, 4.6 and 8.5 % off against
        // claims of 0.8, 1.7 and 4.5 % with the least-squares error alone;
        // now 2.0 and 4.3 %, and #9's α is too near zero to claim on.)
        sigma: scatter * k.sqrt(),
        c1,
        rms: (rss / k).sqrt(),
    })
}

/// Student's t at the normal's one-sigma point (0.8413) for `dof` degrees of
/// freedom (dimensionless): a standard error estimated from `dof` residuals,
/// times this, covers as one sigma does (1.84 for 1, 1.32 for 2, 1.11 for 5; the
/// Cornish–Fisher series 1 + 1/(2ν) + 1/(4ν²) from 2 on, within 0.7 %).
pub fn t_one_sigma(dof: usize) -> f64 {
    match dof {
        0 => f64::INFINITY,
        1 => 1.8373,
        n => {
            let n = n as f64;
            1.0 + 0.5 / n + 0.25 / (n * n)
        }
    }
}

/// The black level of a strip whose values `prof` a used `fix` has
/// corrected, from its bands of paper `paper` as binned with the base tone
/// (not corrected); None where no band or too few stretches can be read.
pub fn find(
    prof: &Profile,
    paper: &[Profile],
    law: &PhaseLaw,
    fix: &ToneFix,
) -> Option<BlackLevel> {
    let (Some(&s0), Some(&s1)) = (prof.s.first(), prof.s.last()) else {
        return None;
    };
    // Per stretch: the strip's local mean, and each band's mean corrected
    // paper value (None where the band is missing, cut or too bright).
    let mut rows: Vec<(f64, [Option<f64>; 2])> = Vec::new();
    for (a, b) in stretches(law, s0, s1) {
        // The strip's local mean at the stretch's middle: a sine at the
        // law's phase, and the light's trend, fitted beside it (a mean over
        // whole periods moved with the law's small phase errors: ±2 % at
        // the low end).
        if !(law.phase(b) - law.phase(a) >= 1.0) {
            continue;
        }
        let Some(m) = local_mean(prof, law, a, b) else {
            continue;
        };
        let mut band = [None, None];
        for (slot, p) in band.iter_mut().zip(paper) {
            let bins = p.bins_within(a, b);
            // Paper brighter than the strip's range read (less a margin) is
            // left out: there the correction is not known (a camera curve's
            // shoulder; read 0.02 beyond, the line bent by 0.5–1 %). The
            // stretch's mean code is tested, not every bin's: a band's bins
            // are a few pixels each, and their noise put one of ~150 over
            // the line in stretches whose paper lay well within, which left
            // half the readable stretches out (3–5 of 8–9 on `tonelight`
            // seed 57; mean RMS 0.0114 → 0.0108 over 120 shots with the
            // margin unchanged).
            let mean_code = p.y[bins.clone()]
                .iter()
                .map(|&y| code_of(&fix.base, y))
                .sum::<f64>()
                / bins.len().max(1) as f64;
            let beyond = !(mean_code <= (fix.code_range.1 - CODE_MARGIN).min(CODE_HIGH));
            // A band must cover the stretch (not be cut by the frame).
            let covered = !bins.is_empty()
                && p.s[bins.start] - a < 0.1 * (b - a)
                && b - p.s[bins.end - 1] < 0.1 * (b - a);
            if !beyond && covered {
                *slot = p.mean_within(a, b, |y| fix.linear(y));
            }
        }
        rows.push((m, band));
    }
    let strip_mean = rows.iter().map(|r| r.0).sum::<f64>() / rows.len().max(1) as f64;
    // Each band alone, and both together where both are read.
    let pts = |pick: &dyn Fn(&[Option<f64>; 2]) -> Option<f64>| -> Vec<(f64, f64)> {
        rows.iter()
            .filter_map(|(m, b)| pick(b).map(|s| (s, *m)))
            .collect()
    };
    let each: Vec<Option<Line>> = (0..2).map(|i| line(&pts(&|b| b[i]))).collect();
    // Both bands' mean where both are read anywhere (a light falling across
    // the strip, as a vignette near the frame's edge does, cancels in it to
    // first order; one band alone carries it), else the one band read.
    let paired = rows.iter().any(|(_, b)| b[0].is_some() && b[1].is_some());
    let both = pts(&|b| match b {
        [Some(x), Some(y)] => Some(0.5 * (x + y)),
        [Some(x), None] | [None, Some(x)] if !paired => Some(*x),
        _ => None,
    });
    let Some(all) = line(&both) else {
        return Some(BlackLevel {
            offset: f64::NAN,
            sigma: f64::NAN,
            band_spread: 0.0,
            relative: f64::NAN,
            stretches: both.len(),
            bands: 0,
            light_spread: f64::NAN,
            residual: f64::NAN,
            used: false,
            significant: false,
            mean: strip_mean,
            why_not: "too little of the paper beside the strip can be read: outside the frame, or brighter than every code the strip's shape was read over (where the light is strongest away from the strip's low-frequency end)",
        });
    };
    let bands = each.iter().filter(|l| l.is_some()).count();
    let spread = {
        let hi = both.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
        let lo = both.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
        if lo > 0.0 { hi / lo } else { f64::INFINITY }
    };
    let relative = all.alpha / strip_mean;
    let residual = all.rms / strip_mean;
    let agree = match (&each[0], &each[1]) {
        (Some(a), Some(b)) => {
            (a.alpha - b.alpha).abs() <= 3.0 * a.sigma.hypot(b.sigma) + MAX_BAND_GAP * strip_mean
        }
        _ => true,
    };
    // The two bands' α disagree where the light across the strip is not one
    // profile times another (a vignette near the frame's edge under keystone
    // and distortion): the independent camera's `camera` shots read the two
    // bands 7–10 % of the strip's mean apart and their mean 1.6–3.6 % off,
    // claiming 0.2–1.0 %.
    let band_spread = match (&each[0], &each[1]) {
        (Some(a), Some(b)) if paired => 0.5 * (a.alpha - b.alpha).abs(),
        _ => 0.0,
    };
    // Significant: beyond what the stretches' scatter and the bands'
    // disagreement would move it by. Better than unseen: its whole error
    // (the bend) on every modulation, against what leaving it unseen claims.
    let significant = all.alpha.abs() > MIN_SIGNIFICANCE * all.scatter.hypot(band_spread);
    let err = all.sigma.hypot(band_spread);
    let better_than_unseen = err / (strip_mean - all.alpha) < super::tone_unseen::full_scale(fix);
    let why_not = if !(spread >= MIN_LIGHT_SPREAD) {
        "the light changes too little along the strip to tell it"
    } else if !(residual <= MAX_RESIDUAL) || !(0.05..0.95).contains(&all.c1) {
        "the paper beside the strip does not follow the strip's light (not plain paper?)"
    } else if !agree {
        "the paper above and below the strip disagree (not plain paper?)"
    } else if !(relative.abs() > MIN_EFFECT) {
        "too small to matter"
    } else if !(significant || better_than_unseen) {
        "known no better than an unseen one is claimed (the paper's stretches scatter, or \
         the bands above and below the strip disagree)"
    } else if !(relative.abs() < 0.5) {
        "too large to be a black level"
    } else {
        ""
    };
    Some(BlackLevel {
        offset: all.alpha,
        sigma: all.sigma,
        band_spread,
        relative,
        stretches: both.len(),
        bands,
        light_spread: spread,
        residual,
        used: why_not.is_empty(),
        significant,
        why_not,
        mean: strip_mean,
    })
}

/// The stretches [a, b) of the strip [s0, s1] the black level is read over:
/// a [`STRETCHES`]th of it each, or one whole cycle where that is longer
/// (the local mean needs one). With equal stretches only, a log sweep's low
/// end (a cycle of ≈ 100 px at 0.008 cy/px, a 32nd of the strip ≈ 0.3
/// cycle) was left out, and with it the paper where the light is dimmest
/// when it rises along the strip: the only paper dark enough to lie within
/// the codes the strip's shape was read over.
fn stretches(law: &PhaseLaw, s0: f64, s1: f64) -> Vec<(f64, f64)> {
    let step = (s1 - s0) / STRETCHES as f64;
    let mut out = Vec::new();
    let mut a = s0;
    while a < s1 - 0.5 * step && out.len() < STRETCHES {
        // A hair past one cycle, so that the whole-cycle test in `find` holds
        // after the inversion's rounding.
        let one_cycle = law.s_at_phase(law.phase(a) + 1.0 + 1e-6, s0, s1);
        let b = (a + step).max(one_cycle).min(s1);
        if !(b > a) {
            break;
        }
        out.push((a, b));
        a = b;
    }
    out
}

/// A profile's local mean at the middle of [a, b): least squares of a
/// mean, a sine and a cosine at the law's phase, each with a linear trend,
/// weighted by the bins' samples; None when singular.
fn local_mean(p: &Profile, law: &PhaseLaw, a: f64, b: f64) -> Option<f64> {
    let bins = p.bins_within(a, b);
    if bins.len() < 24 {
        return None;
    }
    let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
    let (mut ata, mut atb) = ([[0.0; NX]; NX], [0.0; NX]);
    for i in bins {
        let x = window_row(law, p.s[i], mid, half);
        let w = p.count[i];
        for r in 0..NX {
            atb[r] += w * x[r] * p.y[i];
            for c in 0..NX {
                ata[r][c] += w * x[r] * x[c];
            }
        }
    }
    let tiny = 1e-12 * ata[0][0];
    crate::linalg::solve(ata, atb, tiny.max(1e-300)).map(|c| c[0])
}

/// Takes a used black level out of a strip's corrected values.
pub fn apply(black: &BlackLevel, prof: &mut Profile) {
    if black.used {
        for y in prof.y.iter_mut() {
            *y -= black.offset;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::LawKind;
    use crate::measure::sine_tone;
    use crate::photo::linearise::Tone;

    const LEN: f64 = 1200.0;

    /// A camera: sRGB, then a picture style (tanh S-curve of strength 2 on the code).
    fn camera(lin: f64) -> f64 {
        let c = crate::photo::linearise::linear_to_srgb(lin.clamp(0.0, 1.0));
        0.5 + 0.5 * (2.0 * (c - 0.5)).tanh() / 1f64.tanh()
    }

    /// Binned values (decoded with sRGB, 8-bit codes) of `reflectance(s)·light(s)`.
    fn binned(refl: impl Fn(f64) -> f64, light: &dyn Fn(f64) -> f64) -> Profile {
        let n = (LEN / 0.25) as usize;
        let s: Vec<f64> = (0..n).map(|i| (i as f64 + 0.5) * 0.25).collect();
        let y = s
            .iter()
            .map(|&s| Tone::Srgb.apply((camera(refl(s) * light(s)) * 255.0).round() / 255.0))
            .collect();
        Profile {
            count: vec![60.0; n],
            var_s: vec![0.0; n],
            s,
            y,
            bin: 0.25,
            length: LEN,
            samples: 60 * n,
            clipped_high: 0,
            clipped_low: 0,
            clipped: Vec::new(),
            parity: Vec::new(),
        }
    }

    /// A log sweep 0.008 → 0.3 cy/px over 1200 px (0.1–0.9 of the paper),
    /// its tone taken out, and its black level from two bands of paper
    /// (`paper(s)`: the bands' reflectance).
    fn run(light: &dyn Fn(f64) -> f64, paper: &dyn Fn(f64) -> f64) -> (Profile, ToneFix) {
        let law = PhaseLaw {
            kind: LawKind::Log,
            c0: 0.0,
            c1: 0.008,
            c2: (0.3f64 / 0.008).ln() / LEN,
            persp: 0.0,
        };
        let sine = |s: f64| 0.5 * (1.0 + 0.8 * (std::f64::consts::TAU * law.phase(s)).sin());
        let mut prof = binned(sine, light);
        let mut fix = sine_tone::fit(&prof, &law, &|_| 1.0, &Tone::Srgb).expect("a tone fit");
        assert!(fix.used, "{fix:?}");
        sine_tone::apply(&fix, &mut prof);
        let bands = [binned(paper, light), binned(paper, light)];
        fix.black = find(&prof, &bands, &law, &fix);
        if let Some(b) = &fix.black {
            apply(b, &mut prof);
        }
        (prof, fix)
    }

    /// The offset left in a fix's values, over the mean value: the
    /// intercept of the corrected (and black-corrected) value against the
    /// true light over the strip's range, computed from the camera's curve.
    fn offset_left(fix: &ToneFix, light_max: f64) -> f64 {
        let black = fix
            .black
            .as_ref()
            .filter(|b| b.used)
            .map_or(0.0, |b| b.offset);
        let ls: Vec<f64> = (0..=40)
            .map(|i| light_max * (0.1 + 0.8 * i as f64 / 40.0))
            .filter(|&l| camera(l) < fix.code_range.1)
            .collect();
        let vs: Vec<f64> = ls
            .iter()
            .map(|&l| fix.linear(Tone::Srgb.apply(camera(l))) - black)
            .collect();
        let n = ls.len() as f64;
        let (ml, mv) = (ls.iter().sum::<f64>() / n, vs.iter().sum::<f64>() / n);
        let sxy: f64 = ls.iter().zip(&vs).map(|(l, v)| (l - ml) * (v - mv)).sum();
        let sxx: f64 = ls.iter().map(|l| (l - ml).powi(2)).sum();
        (mv - sxy / sxx * ml) / mv
    }

    /// Under `light` (brightest `light_max`) on white paper: the black level
    /// is found and used, and takes the offset the shape alone leaves
    /// (several per cent of the mean) to within 0.5 %, with no warning.
    fn found_and_taken_out(light: &dyn Fn(f64) -> f64, light_max: f64) -> BlackLevel {
        let (_, fix) = run(light, &|_| 1.0);
        let b = fix.black.clone().expect("a black level");
        assert!(b.used, "{b:?}");
        let without = ToneFix {
            black: None,
            ..fix.clone()
        };
        let (before, after) = (
            offset_left(&without, light_max),
            offset_left(&fix, light_max),
        );
        assert!(before.abs() > 0.03, "{before}");
        assert!(after.abs() < 0.005, "{before} → {after}; {b:?}");
        assert!(!fix.uneven_light(), "found: no warning");
        b
    }

    #[test]
    fn the_black_level_is_found_where_the_light_falls_along_the_strip() {
        // Light 1.8:1, brightest at the low-frequency end; paper at 0.75 there.
        let b = found_and_taken_out(&|s: f64| 0.75 * (1.0 - 0.45 * s / LEN), 0.75);
        // Its error on the modulations: the offset's σ over the mean less α
        // (the line's bend carried to zero light: 1.1 % here, where what is
        // left is under 0.5 %).
        let e = b.modulation_rel_err();
        assert!(
            e > 0.0
                && e < 0.02
                && (e - b.sigma.hypot(b.band_spread) / (b.mean - b.offset)).abs() < 1e-15,
            "{b:?}"
        );
    }

    #[test]
    fn students_t_at_one_sigma_matches_its_table() {
        // scipy.stats.t.ppf(norm.cdf(1), dof) for dof 1–12 and 30.
        let table = [
            (1, 1.8373),
            (2, 1.3213),
            (3, 1.1969),
            (4, 1.1416),
            (5, 1.1105),
            (6, 1.0906),
            (8, 1.0665),
            (12, 1.0434),
            (30, 1.0171),
        ];
        for (dof, t) in table {
            let got = t_one_sigma(dof);
            assert!((got - t).abs() < 0.007 * t, "{dof}: {got} against {t}");
        }
        assert!(t_one_sigma(0).is_infinite());
    }

    #[test]
    fn a_line_through_stretches_that_bend_claims_the_bend_carried_to_zero_light() {
        // m = α + 0.5·(s − α) with α = −0.04 over light 1–1.3, exact, and
        // then with a shoulder of 0.2 % of the mean at the bright end.
        let alpha = -0.04;
        let pts = |bend: f64| -> Vec<(f64, f64)> {
            (0..8)
                .map(|i| {
                    let t = i as f64 / 7.0;
                    let s = 0.5 * (1.0 + 0.3 * t);
                    (s, alpha + 0.5 * (s - alpha) + bend * t * t)
                })
                .collect()
        };
        let exact = line(&pts(0.0)).expect("a line");
        assert!((exact.alpha - alpha).abs() < 1e-12 && exact.sigma < 1e-9);
        let bent = pts(0.002);
        let l = line(&bent).expect("a line");
        // The departures (RMS) carried to zero light by the line's lever
        // (mean light over its spread) are claimed: the least-squares error,
        // which takes them as independent scatter, would be √8 smaller.
        let n = bent.len() as f64;
        let xm = bent.iter().map(|p| p.0).sum::<f64>() / n;
        let sd = (bent.iter().map(|p| (p.0 - xm).powi(2)).sum::<f64>() / n).sqrt();
        assert!(
            l.sigma >= l.rms * xm / sd,
            "{} against {}",
            l.sigma,
            l.rms * xm / sd
        );
        // A shoulder moves α by more than that (2.5 times here): the claim
        // is calibrated on the independent camera's bends, not a bound.
        assert!(
            (l.alpha - alpha).abs() < 3.0 * l.sigma,
            "{} ± {}",
            l.alpha,
            l.sigma
        );
        // Three stretches are too few for a line.
        assert!(line(&bent[..3]).is_none());
    }

    #[test]
    fn even_light_tells_no_black_level() {
        let (_, fix) = run(&|_| 0.75, &|_| 1.0);
        let b = fix.black.expect("read");
        assert!(!b.used && b.why_not.contains("too little"), "{b:?}");
    }

    #[test]
    fn paper_beside_a_dim_low_end_is_read_where_the_light_rises_along_the_strip() {
        // Light rising 1.8:1 towards the high-frequency end: only the paper
        // beside the low end, where a 32nd of the strip holds under a cycle,
        // lies within the codes the shape was read over (until session 39
        // those stretches were left out and α was not found).
        found_and_taken_out(&|s: f64| 0.42 * (1.0 + 0.8 * s / LEN), 0.756);
    }

    #[test]
    fn paper_brighter_than_the_strip_everywhere_is_not_read() {
        // Even light over the low end's periods (the shape's codes), rising
        // 1.8:1 beyond them: the paper is above every code read.
        let light = |s: f64| 0.42 * (1.0 + 0.8 * ((s / LEN - 0.6) / 0.4).max(0.0));
        let (_, fix) = run(&light, &|_| 1.0);
        let b = fix.black.clone().expect("read");
        assert!(!b.used && !b.offset.is_finite(), "{b:?}");
        assert!(b.describe().contains("not found"), "{}", b.describe());
        assert!(fix.uneven_light(), "not found under uneven light: warned");
    }

    #[test]
    fn no_paper_or_no_strip_ends_cleanly() {
        let light = |s: f64| 0.75 * (1.0 - 0.45 * s / LEN);
        let (prof, fix) = run(&light, &|_| 1.0);
        let law = PhaseLaw {
            kind: LawKind::Log,
            c0: 0.0,
            c1: 0.008,
            c2: (0.3f64 / 0.008).ln() / LEN,
            persp: 0.0,
        };
        // Bands outside the frame bin nothing.
        let empty = [Profile::default(), Profile::default()];
        let b = find(&prof, &empty, &law, &fix).expect("read");
        assert!(
            !b.used && !b.offset.is_finite() && b.modulation_rel_err() == 0.0,
            "{b:?}"
        );
        assert!(find(&Profile::default(), &empty, &law, &fix).is_none());
        // A degenerate strip has no bands.
        let flat = Strip {
            to_image: Homography { m: [0.0; 9] },
            lens: None,
            length: 1.0,
            width: 1.0,
        };
        assert!(bands(&flat).is_empty());
    }

    #[test]
    fn a_surround_that_is_not_plain_paper_is_refused() {
        let light = |s: f64| 0.75 * (1.0 - 0.45 * s / LEN);
        // Grey labels every 150 px in the bands.
        let (_, fix) = run(&light, &|s: f64| {
            if (s / 150.0).fract() < 0.3 { 0.7 } else { 1.0 }
        });
        let b = fix.black.expect("read");
        assert!(!b.used && b.why_not.contains("not plain paper"), "{b:?}");
    }
}
