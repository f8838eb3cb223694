//! Normalisation: the chart modulation a strip's modulation is divided by —
//! the target's printed contrast, or without a target extrapolated to 0 cy/px
//! from the lowest measured points ([`super::curve::extrapolate_chart_modulation`])
//! — and the division of each point's modulation and uncertainty by it.

use super::{Failure, MtfPoint, curve};

/// The chart modulation (unitless) and the line saying where it came from: the
/// printed `contrast` when the target gives one, else extrapolated from `points`.
pub(super) fn chart_modulation(
    points: &[MtfPoint],
    contrast: Option<f64>,
    channel: &str,
    id: &str,
) -> Result<(f64, String), Failure> {
    match contrast {
        Some(c) => Ok((c, format!("target: printed contrast {c}"))),
        None => {
            let (a, lo, hi) = curve::extrapolate_chart_modulation(points)
                .map_err(|e| Failure::ModulationUnknown(format!("{channel}/{id}: {e}")))?;
            Ok((
                a,
                format!("extrapolated to 0 cy/px from {lo:.4}–{hi:.4} cy/px"),
            ))
        }
    }
}

/// Divides each point's modulation and uncertainty by the chart modulation `m_chart`.
pub(super) fn normalise(points: &mut [MtfPoint], m_chart: f64) {
    for p in points.iter_mut() {
        p.mtf = p.modulation / m_chart;
        p.mtf_err /= m_chart;
    }
}
