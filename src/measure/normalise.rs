//! Normalisation: the chart modulation a strip's modulation is divided by —
//! the target's printed contrast, or without a target extrapolated to 0 cy/px
//! from the lowest measured points ([`super::curve::extrapolate_chart_modulation`])
//! — and the division of each point's modulation and uncertainty by it.

use super::{Failure, MtfPoint, curve};

/// The chart modulation (unitless), its one-sigma uncertainty (0 when printed),
/// the line saying where it came from, and the curve's relative slope at 0
/// (per cy/px; 0 when printed or the start is even): the printed `contrast`
/// when the target gives one, else extrapolated from the `points` at `s ≥ s_min`
/// (read by windows of `window_cycles` cycles: its uncertainty is widened for
/// the data neighbouring points share, [`shared_data_factor`]).
pub(super) fn chart_modulation(
    points: &[MtfPoint],
    s_min: f64,
    window_cycles: f64,
    contrast: Option<f64>,
    channel: &str,
    id: &str,
) -> Result<(f64, f64, String, f64), Failure> {
    match contrast {
        Some(c) => Ok((c, 0.0, format!("target: printed contrast {c}"), 0.0)),
        None => {
            let mut cm = curve::extrapolate_chart_modulation(points, s_min)
                .map_err(|e| Failure::ModulationUnknown(format!("{channel}/{id}: {e}")))?;
            cm.err *= shared_data_factor(points, cm.f_lo, cm.f_hi, window_cycles);
            Ok((
                cm.value,
                cm.err,
                format!(
                    "extrapolated to 0 cy/px from {:.4}–{:.4} cy/px (± {:.4}{})",
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
