//! Frequency law along a strip: the starting law refined from local sine
//! fits over the well-resolved part, the output grid of positions it is
//! sampled at, and the local-frequency check (the image's own frequency
//! against the law) that flags aliasing.

use super::Curve;
use super::estimate::fit::{LocalFit, PhaseTable, local_fit};
use super::law::{self, PhaseLaw};
use super::profile::Profile;
use rayon::prelude::*;

/// Refines a phase law from local sine fits over the well-resolved part of the
/// strip (contiguous from the low-frequency end, signal-to-noise ≥ 8, below
/// 0.85 of the band limit), with the foreshortening along the strip that the
/// phase shows ([`PhaseLaw::persp`]). Returns the law, its RMS phase residual
/// (cycles) and the number of fits that support it.
pub(super) fn refine_law(
    prof: &Profile,
    start: PhaseLaw,
    s_per_px: &impl Fn(f64) -> f64,
    band_limit: &impl Fn(f64) -> f64,
) -> Option<(PhaseLaw, f64, usize)> {
    let mut law = start;
    let (s_first, s_hi) = (prof.s[0], prof.s[prof.s.len() - 1]);
    let mut result = None;
    for _ in 0..3 {
        // A linear sweep's law over a surround clicked before the print's
        // low end falls to 0 cy and below there: fitted from where it rises.
        let Some(s_lo) = positive_from(&law, s_first, s_hi) else {
            return result;
        };
        let table = PhaseTable::new(prof, &law);
        // One fit per cycle up to 0.85 of the band limit, computed in parallel,
        // then accepted in order while the phase shift stays continuous.
        let (p_lo, p_hi) = (law.phase(s_lo), law.phase(s_hi));
        let mut at = Vec::new();
        let mut p = p_lo + 1.5;
        while p < p_hi - 1.5 {
            let s = law.s_at_phase(p, s_lo, s_hi);
            if law.freq(s) * s_per_px(s) > 0.85 * band_limit(s) {
                break;
            }
            at.push((p, s));
            p += 1.0;
        }
        let fits: Vec<_> = at
            .par_iter()
            .map(|&(p, s)| (p, s, local_fit(prof, &table, &law, s, 2.0)))
            .collect();
        let mut pts = Vec::new();
        let mut prev_shift: Option<f64> = None;
        for (p, s, fit) in fits {
            let Some(fit) = fit else {
                continue;
            };
            let snr = fit.amp / fit.amp_var.sqrt().max(1e-12);
            if snr < 8.0 {
                if pts.len() >= 8 {
                    break;
                }
                continue;
            }
            let mut shift = fit.phase_shift;
            if let Some(prev) = prev_shift {
                shift -= (shift - prev).round();
                if (shift - prev).abs() > 0.2 {
                    break;
                }
            }
            prev_shift = Some(shift);
            pts.push((s, p + shift, snr.min(1e3).powi(2)));
        }
        if pts.len() < 6 {
            return result;
        }
        // The law with the foreshortening its phase shows (a keystone the
        // corners miss, [`PhaseLaw::persp`]); the plain law where that fit fails.
        let (l, rms) = law::fit_perspective(&pts, law.kind, s_lo.abs().max(s_hi.abs()))
            .or_else(|| law::fit_law(&pts, law.kind))?;
        // Converged when the new law moves no fitted point's phase by 1/1000 cycle.
        let moved = pts
            .iter()
            .map(|&(s, _, _)| (l.phase(s) - law.phase(s)).abs())
            .fold(0.0, f64::max);
        law = l;
        result = Some((law, rms, pts.len()));
        if moved < 1e-3 {
            break;
        }
    }
    result
}

/// Farthest into a strip (fraction of its length) a law's frequency may
/// rise from 0 for the stretch before to be taken as surround clicked
/// beyond the print's low end: a law that is not positive over more is no
/// sweep's (an aliased channel's crossings, where that channel is measured
/// along luma's law instead).
const MAX_RISE_FRACTION: f64 = 0.1;

/// Where a law's frequency is positive in `s_lo..s_hi` (strip units): `s_lo`
/// where it already is there; else where it rises through a thousandth of
/// its value at `s_hi` (a linear law extrapolated over a surround before the
/// print's low end, where no print can be), if within
/// [`MAX_RISE_FRACTION`] of the span. None where it is not positive at
/// `s_hi` or rises only farther in.
pub(super) fn positive_from(law: &PhaseLaw, s_lo: f64, s_hi: f64) -> Option<f64> {
    let f_hi = law.freq(s_hi);
    if !(f_hi > 0.0 && f_hi.is_finite() && s_lo <= s_hi) {
        return None;
    }
    let f_lo = law.freq(s_lo);
    if f_lo > 0.0 && f_lo.is_finite() {
        return Some(s_lo);
    }
    let floor = 1e-3 * f_hi;
    let (mut a, mut b) = (s_lo, s_hi);
    for _ in 0..60 {
        let m = 0.5 * (a + b);
        if law.freq(m) > floor {
            b = m;
        } else {
            a = m;
        }
    }
    (b - s_lo <= MAX_RISE_FRACTION * (s_hi - s_lo)).then_some(b)
}

/// Output positions: at least one cycle apart and at most ~1/300 of the frequency range apart.
pub(super) fn output_grid(law: &PhaseLaw, s_lo: f64, s_hi: f64) -> Vec<f64> {
    let (f_lo, f_hi) = (law.freq(s_lo), law.freq(s_hi));
    let df = (f_hi - f_lo) / 300.0;
    let mut out = Vec::new();
    let mut s = law.s_at_phase(law.phase(s_lo) + 0.5, s_lo, s_hi);
    let p_end = law.phase(s_hi) - 0.5;
    while law.phase(s) <= p_end && out.len() < 5000 {
        out.push(s);
        let by_cycle = law.s_at_phase(law.phase(s) + 1.0, s_lo, s_hi);
        let target_f = law.freq(s) + df;
        // s where the frequency reaches target_f (bisection; frequency rises).
        let (mut a, mut b) = (s, s_hi);
        for _ in 0..60 {
            let m = 0.5 * (a + b);
            if law.freq(m) < target_f {
                a = m;
            } else {
                b = m;
            }
        }
        let next = by_cycle.max(0.5 * (a + b));
        if next <= s + 1e-12 {
            break;
        }
        s = next;
    }
    out
}

/// Half-width (cycles) of the local fits of the local-frequency check.
pub(super) const DEV_HALF_CYCLES: f64 = 2.0;

/// Relative deviation of the image's local frequency from the law, (s, deviation) at grid points with a clear signal.
pub(super) fn local_freq_deviation(
    prof: &Profile,
    table: &PhaseTable,
    law: &PhaseLaw,
    grid: &[f64],
) -> Vec<(f64, f64)> {
    let fits: Vec<Option<LocalFit>> = grid
        .par_iter()
        .map(|&s| local_fit(prof, table, law, s, DEV_HALF_CYCLES))
        .collect();
    deviation_from_fits(law, grid, &fits)
}

/// [`local_freq_deviation`] from its local fits (±[`DEV_HALF_CYCLES`]) at the grid points, made already.
pub(super) fn deviation_from_fits(
    law: &PhaseLaw,
    grid: &[f64],
    fits: &[Option<LocalFit>],
) -> Vec<(f64, f64)> {
    let fits: Vec<(f64, f64, f64)> = grid
        .iter()
        .zip(fits)
        .filter_map(|(&s, f)| {
            let f = f.as_ref()?;
            let snr = f.amp / f.amp_var.sqrt().max(1e-12);
            (snr > 15.0).then_some((s, law.phase(s), f.phase_shift))
        })
        .collect();
    // Pair each fit with the next one at least 4 cycles on (phase noise ~1/(2π·SNR) per fit).
    let mut out = Vec::new();
    for i in 0..fits.len() {
        let j = fits[i..].partition_point(|f| f.1 < fits[i].1 + 4.0) + i;
        if let Some(fj) = fits.get(j)
            && fj.1 - fits[i].1 < 12.0
        {
            let mut d = fj.2 - fits[i].2;
            d -= d.round();
            out.push((0.5 * (fits[i].0 + fj.0), d / (fj.1 - fits[i].1)));
        }
    }
    out
}

/// The local-frequency deviation at the fit nearest to `s` (strip units), if any.
pub(super) fn dev_at(dev: &[(f64, f64)], s: f64) -> Option<f64> {
    let i = dev.partition_point(|d| d.0 < s);
    let cand = [i.checked_sub(1), Some(i)];
    cand.iter()
        .flatten()
        .filter_map(|&k| dev.get(k))
        .min_by(|a, b| (a.0 - s).abs().total_cmp(&(b.0 - s).abs()))
        .map(|d| d.1)
}

/// Foreshortening from end to end (|persp|·length) from which a note names it.
const NOTED_FORESHORTENING: f64 = 0.002;

/// A note where the sweep's phase shows the strip foreshortened beyond what
/// its corners say (a keystone they miss), with how far off that puts the
/// far end's height (px; `margin` is the fraction of the strip's height left
/// out along each long edge); None below 0.2 % from end to end.
pub(super) fn foreshortening_note(c: &Curve, margin: f64) -> Option<String> {
    let span = c.law.persp * c.strip_length;
    if !(span.abs() >= NOTED_FORESHORTENING) {
        return None;
    }
    let r = &c.region_px;
    let far = (r[2][0] - r[1][0]).hypot(r[2][1] - r[1][1]) / (1.0 - 2.0 * margin).max(0.1);
    Some(format!(
        "the sweep's phase shows the strip {:.2} % {} from end to end than its corners say \
         (its far end's height off by ≈ {:.2} px); the frequencies follow the phase",
        100.0 * span.abs(),
        if span > 0.0 {
            "less foreshortened"
        } else {
            "more foreshortened"
        },
        span.abs() * far
    ))
}
