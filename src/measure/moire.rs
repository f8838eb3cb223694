//! Colour moiré along a sweep: how far the red and blue channels' MTFs part.
//!
//! Definition (per sweep, at each point of the red curve, the blue curve
//! interpolated linearly in frequency): the **R−B spread**
//! `Δ(f) = |MTF_R(f) − MTF_B(f)|`, each channel's MTF being its measured
//! modulation divided by its own low-frequency (chart) modulation. So the
//! light's colour and the white balance cancel, and Δ is the difference of
//! the two channels' modulation in units of the chart's own modulation: the
//! chroma contrast of the false colour, as a fraction of the contrast of the
//! detail that was photographed. On a neutral chart through a camera without
//! a colour mosaic Δ is 0 up to noise; where red and blue are sampled on
//! separate, sparser lattices (a Bayer mosaic: each on every second row and
//! column, shifted by one pixel against each other) and interpolated, their
//! aliases carry opposite signs and Δ rises. It is not divided by the luma's
//! MTF: that ratio would grow without bound (and with the noise) where the
//! luma's modulation vanishes, while the false colour's own contrast stays
//! finite.
//!
//! Summary: the largest smoothed Δ and where it is, and the **onset**, the
//! lowest frequency where the smoothed Δ rises above [`ONSET_SPREAD`] and
//! [`ONSET_SIGMAS`] times its own uncertainty at [`ONSET_RUN`] successive
//! points (interpolated linearly to the threshold crossing), or none.
//! Smoothing is the 3-point running mean the MTF figures use. Aliased points
//! are kept: colour moiré is what aliasing shows, whatever the MTF flags say.

use super::Curve;
use serde::Serialize;

/// Spread (fraction of the chart's modulation) above which colour moiré counts as begun.
pub const ONSET_SPREAD: f64 = 0.05;
/// … and it must exceed its own one-sigma uncertainty this many times (the
/// MTFs' σ is conservative: it holds the sine fit's residual, which the
/// alias itself raises; on neutral noisy shots the spread stays below 0.6 σ).
pub const ONSET_SIGMAS: f64 = 2.0;
/// … at this many successive points (one noisy point does not decide).
pub const ONSET_RUN: usize = 3;

/// The one-sentence definition carried in the JSON summary.
pub const DEFINITION: &str = "spread = |MTF_R - MTF_B| at each red point (blue interpolated in frequency), each channel normalised by its own low-frequency modulation: the false colour's R-B contrast as a fraction of the chart's modulation; 3-point running mean; onset = lowest frequency where it exceeds 0.05 and 2 sigma at 3 successive points";

/// One point of the R−B spread along a sweep.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SpreadPoint {
    /// Image frequency (cycles/pixel), the red curve's point.
    pub freq_cy_px: f64,
    /// |MTF_R − MTF_B| (dimensionless, fraction of the chart's modulation).
    pub spread: f64,
    /// One-sigma uncertainty of the spread (the two MTFs' σ in quadrature).
    pub spread_err: f64,
}

/// Colour moiré of one sweep.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ColourMoire {
    /// The sweep.
    pub sweep_id: String,
    /// The spread at each red point inside the blue curve's frequency range.
    pub points: Vec<SpreadPoint>,
    /// Largest smoothed spread (dimensionless); None without points.
    pub max_spread: Option<f64>,
    /// Its one-sigma uncertainty (smoothed like the spread).
    pub max_spread_err: Option<f64>,
    /// Where the largest smoothed spread is (cycles/pixel).
    pub max_at_cy_px: Option<f64>,
    /// Onset of colour moiré (cycles/pixel): see the module's definition; None when not reached.
    pub onset_cy_px: Option<f64>,
    /// Highest frequency the spread was measured at (cycles/pixel).
    pub measured_to_cy_px: Option<f64>,
}

/// Linear interpolation of (frequency, value, σ) pairs sorted by frequency; None outside.
fn interp(xs: &[(f64, f64, f64)], f: f64) -> Option<(f64, f64)> {
    let first = xs.first()?;
    let last = xs.last()?;
    if !(f >= first.0 && f <= last.0) {
        return None;
    }
    let i = xs.partition_point(|p| p.0 < f);
    if i == 0 {
        return Some((first.1, first.2));
    }
    let (a, b) = (xs[i - 1], xs[i]);
    let t = if b.0 > a.0 {
        (f - a.0) / (b.0 - a.0)
    } else {
        0.0
    };
    Some((a.1 + t * (b.1 - a.1), a.2 + t * (b.2 - a.2)))
}

/// The R−B spread of one pair of curves (red and blue of the same sweep).
pub fn spread_points(red: &Curve, blue: &Curve) -> Vec<SpreadPoint> {
    let finite = |c: &Curve| -> Vec<(f64, f64, f64)> {
        let mut v: Vec<_> = c
            .points
            .iter()
            .filter(|p| p.freq_cy_px.is_finite() && p.mtf.is_finite() && p.mtf_err.is_finite())
            .map(|p| (p.freq_cy_px, p.mtf, p.mtf_err.abs()))
            .collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        v
    };
    let b = finite(blue);
    finite(red)
        .into_iter()
        .filter_map(|(f, mr, er)| {
            let (mb, eb) = interp(&b, f)?;
            Some(SpreadPoint {
                freq_cy_px: f,
                spread: (mr - mb).abs(),
                spread_err: er.hypot(eb),
            })
        })
        .collect()
}

/// 3-point running mean of `v`.
fn running_mean(v: &[f64]) -> Vec<f64> {
    (0..v.len())
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 2).min(v.len()));
            v[a..b].iter().sum::<f64>() / (b - a) as f64
        })
        .collect()
}

/// The summary of a spread curve: (max, its σ, where, onset).
pub fn summarise(points: &[SpreadPoint]) -> (Option<f64>, Option<f64>, Option<f64>, Option<f64>) {
    if points.is_empty() {
        return (None, None, None, None);
    }
    let sm = running_mean(&points.iter().map(|p| p.spread).collect::<Vec<_>>());
    let se = running_mean(&points.iter().map(|p| p.spread_err).collect::<Vec<_>>());
    let k = (0..sm.len())
        .max_by(|&a, &b| sm[a].total_cmp(&sm[b]))
        .unwrap_or(0);
    let above = |i: usize| sm[i] > ONSET_SPREAD && sm[i] > ONSET_SIGMAS * se[i];
    let onset = (0..sm.len())
        .find(|&i| i + ONSET_RUN <= sm.len() && (i..i + ONSET_RUN).all(above))
        .map(|i| {
            if i == 0 {
                return points[0].freq_cy_px;
            }
            // Where the smoothed spread crosses the threshold that applies at i.
            let level = ONSET_SPREAD.max(ONSET_SIGMAS * se[i]);
            let (f0, f1) = (points[i - 1].freq_cy_px, points[i].freq_cy_px);
            if sm[i - 1] >= level || sm[i] <= sm[i - 1] {
                return f1;
            }
            f0 + (level - sm[i - 1]) / (sm[i] - sm[i - 1]) * (f1 - f0)
        });
    (Some(sm[k]), Some(se[k]), Some(points[k].freq_cy_px), onset)
}

/// Colour moiré of every sweep measured in both red and blue (none otherwise).
pub fn colour_moire(curves: &[Curve]) -> Vec<ColourMoire> {
    let mut out = Vec::new();
    for red in curves.iter().filter(|c| c.channel == "r") {
        let Some(blue) = curves
            .iter()
            .find(|c| c.channel == "b" && c.sweep_id == red.sweep_id)
        else {
            continue;
        };
        let points = spread_points(red, blue);
        let (max_spread, max_spread_err, max_at_cy_px, onset_cy_px) = summarise(&points);
        out.push(ColourMoire {
            sweep_id: red.sweep_id.clone(),
            measured_to_cy_px: points.last().map(|p| p.freq_cy_px),
            points,
            max_spread,
            max_spread_err,
            max_at_cy_px,
            onset_cy_px,
        });
    }
    out
}

/// The spread at frequency `f` (cycles/pixel), interpolated; None outside the measured range.
pub fn spread_at(cm: &ColourMoire, f: f64) -> Option<f64> {
    let xs: Vec<(f64, f64, f64)> = cm
        .points
        .iter()
        .map(|p| (p.freq_cy_px, p.spread, p.spread_err))
        .collect();
    interp(&xs, f).map(|v| v.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::{LawKind, MtfPoint, PhaseLaw};

    fn curve(channel: &str, pts: &[(f64, f64)], err: f64) -> Curve {
        Curve {
            channel: channel.into(),
            sweep_id: "main".into(),
            law: PhaseLaw {
                kind: LawKind::Linear,
                c0: 0.0,
                c1: 0.1,
                c2: 0.0,
                persp: 0.0,
            },
            strip_unit: "px",
            strip_length: 1.0,
            points: pts
                .iter()
                .map(|&(f, m)| MtfPoint {
                    s: f,
                    freq_cy_px: f,
                    freq_chart: f,
                    modulation: m,
                    mtf: m,
                    mtf_err: err,
                    aliased: false,
                    jpeg_limited: false,
                })
                .collect(),
            chart_modulation: 1.0,
            chart_modulation_err: 0.0,
            chart_modulation_source: "test".into(),
            figures: Default::default(),
            aliasing_from_cy_px: None,
            rounded_away_from_cy_px: None,
            clipped_fraction: 0.0,
            region_px: [[0.0; 2]; 4],
            outline_px: Vec::new(),
            alias_line_px: None,
            measured_lines_px: [[[0.0; 2]; 2]; 2],
            paper_bands_px: Vec::new(),
            print_ends_inside_px: [None; 2],
            tone_fix: None,
        }
    }

    #[test]
    fn identical_channels_have_no_spread_and_no_onset() {
        let pts: Vec<(f64, f64)> = (1..50)
            .map(|i| (i as f64 * 0.01, 1.0 - i as f64 * 0.01))
            .collect();
        let cs = [curve("r", &pts, 0.01), curve("b", &pts, 0.01)];
        let cm = colour_moire(&cs);
        assert_eq!(cm.len(), 1);
        assert_eq!(cm[0].max_spread, Some(0.0));
        assert_eq!(cm[0].onset_cy_px, None);
        assert_eq!(cm[0].points.len(), 49);
        assert!((cm[0].points[0].spread_err - 0.01 * 2f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn a_ramp_crosses_the_threshold_where_worked_out_by_hand() {
        // Red = blue + a ramp 0 below 0.2025, rising 1 per cy/px above: the
        // smoothed spread of a linear ramp is the ramp (away from its knee
        // and ends), so it reaches 0.05 at 0.2525 cy/px, between two points;
        // σ tiny, so 0.05 decides. At the last point the mean of two: 0.295.
        let fs: Vec<f64> = (0..=100).map(|i| i as f64 * 0.005).collect();
        let b: Vec<(f64, f64)> = fs.iter().map(|&f| (f, 0.5)).collect();
        let r: Vec<(f64, f64)> = fs
            .iter()
            .map(|&f| (f, 0.5 + (f - 0.2025).max(0.0)))
            .collect();
        let cm = colour_moire(&[curve("r", &r, 1e-4), curve("b", &b, 1e-4)]);
        let on = cm[0].onset_cy_px.unwrap();
        assert!((on - 0.2525).abs() < 1e-9, "{on}");
        assert!((cm[0].max_spread.unwrap() - 0.295).abs() < 1e-9);
        assert_eq!(cm[0].max_at_cy_px, Some(0.5));
    }

    #[test]
    fn noise_alone_gives_no_onset_and_one_spike_does_not_decide() {
        // A spread of 0.2 at a single point: smoothing spreads it to three
        // points at 0.067, above 0.05, but with σ 0.04 (2σ = 0.08) it is
        // not clear of the noise.
        let fs: Vec<f64> = (0..60).map(|i| i as f64 * 0.005).collect();
        let b: Vec<(f64, f64)> = fs.iter().map(|&f| (f, 0.8)).collect();
        let r: Vec<(f64, f64)> = fs
            .iter()
            .enumerate()
            .map(|(i, &f)| (f, if i == 30 { 1.0 } else { 0.8 }))
            .collect();
        let cm = colour_moire(&[
            curve("r", &r, 0.04 / 2f64.sqrt()),
            curve("b", &b, 0.04 / 2f64.sqrt()),
        ]);
        assert_eq!(cm[0].onset_cy_px, None);
        assert!((cm[0].max_spread.unwrap() - 0.2 / 3.0).abs() < 1e-9);
    }

    #[test]
    fn stiff_cases() {
        // No blue, a blue of another sweep, empty and NaN curves.
        assert!(colour_moire(&[curve("r", &[(0.1, 1.0)], 0.01)]).is_empty());
        let mut b = curve("b", &[(0.1, 1.0), (0.2, 1.0)], 0.01);
        b.sweep_id = "other".into();
        assert!(colour_moire(&[curve("r", &[(0.1, 1.0)], 0.01), b]).is_empty());
        let cm = colour_moire(&[curve("r", &[], 0.01), curve("b", &[], 0.01)]);
        assert_eq!(cm[0].max_spread, None);
        assert_eq!(cm[0].onset_cy_px, None);
        let cm = colour_moire(&[
            curve("r", &[(0.1, f64::NAN), (0.2, 1.0)], 0.01),
            curve("b", &[(0.1, 1.0), (0.3, f64::NAN)], 0.01),
        ]);
        // Blue's only finite point is at 0.1: red's 0.2 lies outside it.
        assert!(cm[0].points.is_empty());
        // Red beyond blue's range is left out, not extrapolated.
        let cm = colour_moire(&[
            curve("r", &[(0.05, 1.0), (0.15, 0.9), (0.4, 0.3)], 0.01),
            curve("b", &[(0.1, 1.0), (0.2, 0.8)], 0.01),
        ]);
        assert_eq!(cm[0].points.len(), 1);
        assert!((cm[0].points[0].spread - 0.0).abs() < 1e-12);
        assert_eq!(spread_at(&cm[0], 0.15), Some(0.0));
        assert_eq!(spread_at(&cm[0], 0.3), None);
    }
}
