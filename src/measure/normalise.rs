//! Normalisation: the chart modulation a strip's modulation is divided by —
//! the target's printed contrast, or without a target extrapolated to 0 cy/px
//! from the lowest measured points ([`super::curve::extrapolate_chart_modulation`])
//! — and the division of each point's modulation and uncertainty by it.

use super::{Failure, MtfPoint, curve};

/// The chart modulation (unitless), its one-sigma uncertainty (0 when printed),
/// the line saying where it came from, and the curve's relative slope at 0
/// (per cy/px; 0 when printed or the start is even): the printed `contrast`
/// when the target gives one, else extrapolated from the `points` at `s ≥ s_min`.
pub(super) fn chart_modulation(
    points: &[MtfPoint],
    s_min: f64,
    contrast: Option<f64>,
    channel: &str,
    id: &str,
) -> Result<(f64, f64, String, f64), Failure> {
    match contrast {
        Some(c) => Ok((c, 0.0, format!("target: printed contrast {c}"), 0.0)),
        None => {
            let cm = curve::extrapolate_chart_modulation(points, s_min)
                .map_err(|e| Failure::ModulationUnknown(format!("{channel}/{id}: {e}")))?;
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

/// Divides each point's modulation and uncertainty by the chart modulation
/// `m_chart`, adding its uncertainty `m_err` (which scales every point alike).
pub(super) fn normalise(points: &mut [MtfPoint], m_chart: f64, m_err: f64) {
    for p in points.iter_mut() {
        p.mtf = p.modulation / m_chart;
        p.mtf_err = (p.mtf_err / m_chart).hypot(p.mtf * m_err / m_chart);
    }
}
