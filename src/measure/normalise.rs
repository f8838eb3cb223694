//! Normalisation: the chart modulation a strip's modulation is divided by —
//! the target's printed contrast, or without a target extrapolated to 0 cy/px
//! from the lowest measured points ([`super::curve::extrapolate_chart_modulation`])
//! — and the division of each point's modulation and uncertainty by it.

use super::estimate::fit::{PhaseTable, local_fit};
use super::profile::Profile;
use super::{Failure, MtfPoint, PhaseLaw, curve};

/// The chart modulation (unitless), its one-sigma uncertainty (0 when printed),
/// the line saying where it came from, and the curve's relative slope at 0
/// (per cy/px; 0 when printed or the start is even): the printed `contrast`
/// when the target gives one, else extrapolated from the `points` at `s ≥ s_min`
/// together with the `low` end's points below them ([`low_end_points`]; read
/// by windows of `window_cycles` cycles: its uncertainty is widened for the
/// data neighbouring points share, [`shared_data_factor`]).
pub(super) fn chart_modulation(
    points: &[MtfPoint],
    s_min: f64,
    low: &[MtfPoint],
    window_cycles: f64,
    contrast: Option<f64>,
    channel: &str,
    id: &str,
) -> Result<(f64, f64, String, f64), Failure> {
    match contrast {
        Some(c) => Ok((c, 0.0, format!("target: printed contrast {c}"), 0.0)),
        None => {
            let below: Vec<MtfPoint> = low.iter().filter(|p| p.s < s_min).copied().collect();
            let below_f: Vec<f64> = below.iter().map(|p| p.freq_cy_px).collect();
            let joined: Vec<MtfPoint>;
            let (points, s_min) = if below.is_empty() {
                (points, s_min)
            } else {
                let s_low = below.iter().map(|p| p.s).fold(f64::INFINITY, f64::min);
                joined = below
                    .into_iter()
                    .chain(points.iter().filter(|p| p.s >= s_min).copied())
                    .collect();
                (&joined[..], s_low)
            };
            let mut cm = curve::extrapolate_chart_modulation(points, s_min)
                .map_err(|e| Failure::ModulationUnknown(format!("{channel}/{id}: {e}")))?;
            cm.err *= shared_data_factor(points, cm.f_lo, cm.f_hi, window_cycles);
            // The low end's points it read (not in the curve): said.
            let short = below_f
                .iter()
                .filter(|&&f| f >= cm.f_lo && f <= cm.f_hi)
                .count();
            let short = match short {
                0 => String::new(),
                1 => ", its first point from a two-cycle window".into(),
                n => format!(", its first {n} points from two-cycle windows"),
            };
            Ok((
                cm.value,
                cm.err,
                format!(
                    "extrapolated to 0 cy/px from {:.4}–{:.4} cy/px (± {:.4}{}{short})",
                    cm.f_lo,
                    cm.f_hi,
                    cm.err,
                    if cm.linear_start {
                        ", linear start"
                    } else {
                        ", even start"
                    }
                ),
                cm.slope_rel,
            ))
        }
    }
}

/// Half-width of the low end's windows (cycles): two cycles each.
const LOW_END_HALF_CYCLES: f64 = 1.0;

/// Phase kept clear of the strip's low end by the low end's windows (cycles):
/// the paper's light blurred across the end and a corner a few pixels off
/// stay outside them.
const LOW_END_MARGIN_CYCLES: f64 = 0.25;

/// Phase between the low end's windows (cycles).
const LOW_END_STEP_CYCLES: f64 = 0.5;

/// The modulation at the strip's low end, where the estimator's own windows
/// (`window_cycles` long) would run past the strip's end and are left out of
/// the chart modulation: local sine fits over windows of two cycles
/// ([`LOW_END_HALF_CYCLES`]), from [`LOW_END_MARGIN_CYCLES`] past the end, every
/// half cycle, up to where the estimator's first whole window is centred.
/// Points of the chart modulation's extrapolation only (the curve keeps its
/// own windows), for the fit estimator (`fit`), whose model these are.
///
/// A linear sweep rises fast from its start (√(f₀² + 2kφ) after φ cycles):
/// its estimator's first whole window is centred near 0.05 cy/px, and the
/// extrapolation to 0 multiplied the points' shared error there 4–6 times.
/// These windows reach down to ≈ 0.03 cy/px on the same strips. On the
/// independent camera (issue 15, session 31; 417 shots of 14 kinds) the
/// chart modulation's RMS error went from 0.225 % to 0.166 % (keystoned
/// linear sweeps 0.30 → 0.17 %, worst −1.05 → −0.56 %), shots beyond
/// 0.5 % from 14 to 6.
pub(super) fn low_end_points(
    prof: &Profile,
    table: &PhaseTable,
    law: &PhaseLaw,
    s_per_px: &dyn Fn(f64) -> f64,
    window_cycles: f64,
) -> Vec<MtfPoint> {
    let (Some(&s0), Some(&s1)) = (prof.s.first(), prof.s.last()) else {
        return Vec::new();
    };
    let start = law.phase(s0);
    let last = start + 0.5 * window_cycles;
    let first = start + LOW_END_HALF_CYCLES + LOW_END_MARGIN_CYCLES;
    let steps = ((last - first) / LOW_END_STEP_CYCLES).floor();
    if !(0.0..1e3).contains(&steps) {
        return Vec::new();
    }
    (0..=steps as usize)
        .filter_map(|k| {
            let s = law.s_at_phase(first + k as f64 * LOW_END_STEP_CYCLES, s0, s1);
            let fit = local_fit(prof, table, law, s, LOW_END_HALF_CYCLES)?;
            // Whole windows only (the end is outside them by construction).
            let whole = fit.cycles >= 0.95 * 2.0 * LOW_END_HALF_CYCLES;
            let f_chart = law.freq(fit.s_amp);
            let p = MtfPoint {
                s: fit.s_amp,
                freq_cy_px: f_chart * s_per_px(fit.s_amp),
                freq_chart: f_chart,
                modulation: fit.modulation(),
                mtf: fit.modulation(),
                mtf_err: fit.modulation_err(),
                aliased: false,
                jpeg_limited: false,
            };
            (whole
                && fit.mean > 0.0
                && p.modulation.is_finite()
                && p.mtf_err.is_finite()
                && p.freq_cy_px > 0.0)
                .then_some(p)
        })
        .collect()
}

/// How much a fit through the points between `f_lo` and `f_hi` cy/px
/// understates its uncertainty because neighbouring points share data:
/// √(span / spacing), at least 1, where the spacing is the points' mean
/// distance in cycles of the sweep and the span the estimator window's
/// equivalent width, 0.7 × `window_cycles` for its biweight taper
/// ((∫w)²/∫w² = 1.4 half-widths). Points a cycle apart under a 4-cycle window
/// hold 2.8 × fewer independent values than their count: the fit's scatter
/// (its dispersion) sees the noise's size but not that its slow ripple is
/// shared. On the simulator's f/16 diffraction shot the chart modulation
/// read 0.39 % low and claimed ± 0.13 %; on the independent camera's linear
/// sweeps up to 0.7 % against ± 0.4 %.
fn shared_data_factor(points: &[MtfPoint], f_lo: f64, f_hi: f64, window_cycles: f64) -> f64 {
    let mut used: Vec<&MtfPoint> = points
        .iter()
        .filter(|p| !p.aliased && p.freq_cy_px >= f_lo && p.freq_cy_px <= f_hi)
        .collect();
    used.sort_by(|a, b| a.s.total_cmp(&b.s));
    if used.len() < 2 {
        return 1.0;
    }
    let cycles: f64 = used
        .windows(2)
        .map(|w| (w[1].s - w[0].s).abs() * 0.5 * (w[0].freq_chart + w[1].freq_chart).abs())
        .sum();
    let spacing = cycles / (used.len() - 1) as f64;
    let span = 0.7 * window_cycles;
    if spacing > 0.0 && spacing.is_finite() {
        (span / spacing).max(1.0).sqrt()
    } else {
        1.0
    }
}

/// Divides each point's modulation and uncertainty by the chart modulation
/// `m_chart`, adding its uncertainty `m_err` (which scales every point alike).
pub(super) fn normalise(points: &mut [MtfPoint], m_chart: f64, m_err: f64) {
    for p in points.iter_mut() {
        p.mtf = p.modulation / m_chart;
        p.mtf_err = (p.mtf_err / m_chart).hypot(p.mtf * m_err / m_chart);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::law::LawKind;

    /// A linear sweep from 0.006 cy/px rising 2.1e-4 cy/px per px (a
    /// sineMTF-style strip, 1300 px), binned every 0.25 px, whose modulation
    /// falls as 0.8·(1 − 1.2 f) with the local frequency f, on a mean of 0.5.
    fn sweep() -> (Profile, PhaseLaw) {
        let law = PhaseLaw {
            kind: LawKind::Linear,
            c0: 0.0,
            c1: 0.006,
            c2: 0.5 * 2.1e-4,
            persp: 0.0,
        };
        let s: Vec<f64> = (0..5200).map(|i| 0.125 + 0.25 * i as f64).collect();
        let y = s
            .iter()
            .map(|&s| {
                let m = 0.8 * (1.0 - 1.2 * law.freq(s));
                0.5 * (1.0 + m * (std::f64::consts::TAU * law.phase(s)).sin())
            })
            .collect();
        let n = s.len();
        let prof = Profile {
            count: vec![60.0; n],
            var_s: vec![0.0; n],
            length: 1300.0,
            s,
            y,
            bin: 0.25,
            samples: 60 * n,
            clipped_high: 0,
            clipped_low: 0,
            clipped: Vec::new(),
            parity: Vec::new(),
        };
        (prof, law)
    }

    /// [`sweep`], its table, its low end's points (4-cycle estimator windows)
    /// and where the estimator's first whole window is centred.
    fn low_end_of_sweep() -> (Profile, PhaseLaw, PhaseTable, Vec<MtfPoint>, f64) {
        let (prof, law) = sweep();
        let table = PhaseTable::new(&prof, &law);
        let low = low_end_points(&prof, &table, &law, &|_| 1.0, 4.0);
        let s_first_whole = law.s_at_phase(2.0, 0.0, 1300.0);
        (prof, law, table, low, s_first_whole)
    }

    #[test]
    fn the_low_end_is_read_below_the_first_whole_window_and_exact() {
        let (prof, law, table, pts, s_first_whole) = low_end_of_sweep();
        // Windows centred 1.25 and 1.75 cycles past the end: two points,
        // below where the estimator's first whole 4-cycle window is centred.
        assert_eq!(pts.len(), 2, "{pts:?}");
        for p in &pts {
            assert!(p.s < s_first_whole && p.s > 0.0, "{p:?}");
            // Truth: the closed form at the point's own frequency (a linear
            // modulation is read exactly where its amplitude is placed).
            let truth = 0.8 * (1.0 - 1.2 * p.freq_cy_px);
            assert!(
                (p.modulation / truth - 1.0).abs() < 3e-4,
                "{p:?} against {truth}"
            );
        }
        assert!(
            pts[0].freq_cy_px < 0.8 * law.freq(s_first_whole),
            "{:?}",
            pts[0]
        );
        // Shorter windows than two cycles, or none to read: nothing, no panic.
        assert!(low_end_points(&prof, &table, &law, &|_| 1.0, 2.0).is_empty());
        let empty = Profile {
            s: Vec::new(),
            y: Vec::new(),
            count: Vec::new(),
            var_s: Vec::new(),
            ..prof.clone()
        };
        assert!(low_end_points(&empty, &table, &law, &|_| 1.0, 4.0).is_empty());
        let flat = PhaseLaw {
            c1: 0.0,
            c2: 0.0,
            persp: 0.0,
            ..law
        };
        assert!(
            low_end_points(&prof, &PhaseTable::new(&prof, &flat), &flat, &|_| 1.0, 4.0).is_empty()
        );
        assert!(low_end_points(&prof, &table, &law, &|_| 1.0, f64::NAN).is_empty());
    }

    #[test]
    fn the_chart_modulation_reads_the_low_end_and_says_so() {
        let (_, law, _, low, s_min) = low_end_of_sweep();
        // The curve's points from the first whole 4-cycle window on (exact).
        let points: Vec<MtfPoint> = (0..80)
            .map(|k| {
                let s = law.s_at_phase(2.5 + 0.5 * k as f64, 0.0, 1300.0);
                let f = law.freq(s);
                let m = 0.8 * (1.0 - 1.2 * f);
                MtfPoint {
                    s,
                    freq_cy_px: f,
                    freq_chart: f,
                    modulation: m,
                    mtf: m,
                    mtf_err: 1e-3,
                    aliased: false,
                    jpeg_limited: false,
                }
            })
            .collect();
        let with = chart_modulation(&points, s_min, &low, 4.0, None, "grey", "strip").unwrap();
        let without = chart_modulation(&points, s_min, &[], 4.0, None, "grey", "strip").unwrap();
        assert!((with.0 / 0.8 - 1.0).abs() < 5e-4, "{with:?}");
        assert!(
            with.2.contains("its first 2 points from two-cycle windows"),
            "{}",
            with.2
        );
        assert!(!without.2.contains("two-cycle"), "{}", without.2);
        // They reach lower than the curve's own first point.
        let f_lo = |src: &str| -> f64 {
            src.split("from ")
                .nth(1)
                .unwrap()
                .split('–')
                .next()
                .unwrap()
                .parse()
                .unwrap()
        };
        assert!(
            f_lo(&with.2) < f_lo(&without.2),
            "{} / {}",
            with.2,
            without.2
        );
        // A printed contrast reads none of it.
        let printed =
            chart_modulation(&points, s_min, &low, 4.0, Some(0.8), "grey", "strip").unwrap();
        assert_eq!((printed.0, printed.1), (0.8, 0.0));
    }
}
