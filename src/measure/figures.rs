//! The summary figures of one MTF curve: MTFnn (where the curve first falls
//! to nn % of its low-frequency value, 1 after normalisation), MTFnnP (where
//! it first falls to nn % of its *peak*, searching upward from the peak),
//! the peak itself, and the MTF at Nyquist.
//!
//! Both kinds of crossing use the same convention: the non-aliased points,
//! lightly smoothed (3-point running mean, so one noisy point does not
//! decide), the first fall through the level, linear interpolation between
//! the two points around it; then a weighted quadratic over the points
//! within ±8 % of that frequency refines it (a ripple of the curve, such as
//! a coarse JPEG's, is averaged instead of followed). The peak is the largest smoothed value. Without
//! sharpening the curve's largest value is its low-frequency 1 (a peak that
//! does not rise above 1 by more than [`PEAK_SIGMAS`] times its uncertainty
//! and [`PEAK_FLOOR`] is noise): the peak is then taken as 1 at 0 cy/px and
//! MTFnnP equals MTFnn exactly.
//!
//! MTF50 carries its one-sigma uncertainty: the points' `mtf_err` at the
//! crossing (the smoothed uncertainty, interpolated) over the fitted
//! curve's slope there. It is not divided by the fit's √n: neighbouring
//! points share samples (each modulation is read over several periods),
//! and near Nyquist the error is a slow beat with the alias, not noise.

use super::curve::MtfPoint;
use serde::{Deserialize, Serialize};

/// Summary figures of one curve (frequencies in cycles/pixel; None where not reached).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Figures {
    /// Frequency where the MTF first falls to 0.5 (cy/px).
    pub mtf50_cy_px: Option<f64>,
    /// One-sigma uncertainty of MTF50 (cy/px): the points' MTF uncertainty
    /// at the crossing over the curve's slope there (module text).
    #[serde(default)]
    pub mtf50_err_cy_px: Option<f64>,
    /// Frequency where the MTF first falls to 0.3 (cy/px).
    pub mtf30_cy_px: Option<f64>,
    /// Frequency where the MTF first falls to 0.2 (cy/px).
    pub mtf20_cy_px: Option<f64>,
    /// Frequency where the MTF first falls to 0.1 (cy/px).
    pub mtf10_cy_px: Option<f64>,
    /// MTF at the Nyquist frequency, 0.5 cycles/pixel (None when not measured or aliased there).
    pub mtf_nyquist: Option<f64>,
    /// Peak MTF (dimensionless): the largest smoothed value, or 1 when the curve does not rise above 1 beyond its noise.
    pub peak_mtf: Option<f64>,
    /// Frequency of the peak (cy/px; 0 when the peak is the low-frequency 1).
    pub peak_cy_px: Option<f64>,
    /// True when the curve rises above its low-frequency value beyond its noise (sharpening).
    pub sharpening_peak: bool,
    /// Frequency above the peak where the MTF first falls to 50 % of the peak (cy/px).
    pub mtf50p_cy_px: Option<f64>,
    /// Frequency above the peak where the MTF first falls to 20 % of the peak (cy/px).
    pub mtf20p_cy_px: Option<f64>,
    /// Frequency above the peak where the MTF first falls to 10 % of the peak (cy/px).
    pub mtf10p_cy_px: Option<f64>,
}

/// A peak counts as sharpening only when it exceeds 1 by this many times its one-sigma uncertainty.
pub const PEAK_SIGMAS: f64 = 3.0;
/// … and by at least this much (dimensionless; estimator bias of noiseless curves).
pub const PEAK_FLOOR: f64 = 0.002;

/// The non-aliased points with their 3-point running means of MTF and of its uncertainty.
fn smoothed(points: &[MtfPoint]) -> (Vec<&MtfPoint>, Vec<f64>, Vec<f64>) {
    let pts: Vec<&MtfPoint> = points
        .iter()
        .filter(|p| !p.aliased && p.mtf.is_finite() && p.freq_cy_px.is_finite())
        .collect();
    let mean = |g: &dyn Fn(&MtfPoint) -> f64| -> Vec<f64> {
        (0..pts.len())
            .map(|i| {
                let a = i.saturating_sub(1);
                let b = (i + 2).min(pts.len());
                pts[a..b].iter().map(|p| g(p)).sum::<f64>() / (b - a) as f64
            })
            .collect()
    };
    let sm = mean(&|p| p.mtf);
    let err = mean(&|p| p.mtf_err.abs());
    (pts, sm, err)
}

/// The first fall of the smoothed curve `sm` through `level` at or after
/// index `from`: found on the smoothed points, then refined by a weighted
/// local fit ([`refine_fall`]). Returns the crossing (cy/px) and the curve's
/// slope there (per cy/px: the fit's, else the smoothed points').
fn fall_from(pts: &[&MtfPoint], sm: &[f64], from: usize, level: f64) -> Option<(f64, f64)> {
    for i in (from + 1).max(1)..pts.len() {
        if sm[i - 1] >= level && sm[i] < level {
            let t = (sm[i - 1] - level) / (sm[i - 1] - sm[i]);
            let df = pts[i].freq_cy_px - pts[i - 1].freq_cy_px;
            let f0 = pts[i - 1].freq_cy_px + t * df;
            let lo = pts[from].freq_cy_px;
            return Some(refine_fall(pts, f0, level, lo).unwrap_or((f0, (sm[i] - sm[i - 1]) / df)));
        }
    }
    None
}

/// One-sigma uncertainty of a crossing at `f` (cy/px) where the curve falls
/// with `slope` (per cy/px): the smoothed uncertainty `err` interpolated at
/// `f`, over |slope|; at most `f` itself (a flat stretch tells nothing),
/// None when not finite (an infinite slope, from repeated frequencies, would
/// claim none).
fn crossing_sigma(pts: &[&MtfPoint], err: &[f64], f: f64, slope: f64) -> Option<f64> {
    if !slope.is_finite() {
        return None;
    }
    let k = pts.partition_point(|p| p.freq_cy_px < f);
    let e = match (k.checked_sub(1), pts.get(k)) {
        (Some(a), Some(b)) if pts[k].freq_cy_px > pts[a].freq_cy_px => {
            let t = (f - pts[a].freq_cy_px) / (b.freq_cy_px - pts[a].freq_cy_px);
            err[a] + t.clamp(0.0, 1.0) * (err[k] - err[a])
        }
        (Some(a), _) => err[a],
        (None, Some(_)) => err[k],
        (None, None) => return None,
    };
    let s = (e / slope.abs()).min(f);
    (s.is_finite() && s >= 0.0).then_some(s)
}

/// Half-width of the crossing fit, as a fraction of the crossing's frequency.
pub const CROSSING_FIT_HALF_WIDTH: f64 = 0.08;
/// Least points on each side of a crossing for its fit.
const CROSSING_FIT_SIDE_POINTS: usize = 3;

/// The crossing near `f0` from a quadratic fitted (weights 1/σ²) to the
/// points within ±[`CROSSING_FIT_HALF_WIDTH`]·f0 (at least
/// [`CROSSING_FIT_SIDE_POINTS`] on each side), not below `lo`. Three
/// smoothed points follow a ripple of the curve (a coarse JPEG's block
/// quantisation ripples it by ±0.015 with a period of ≈ 0.02 cy/px, which
/// moved MTF50 by up to 1.3 %); the fit averages over it. None when the fit
/// does not fall through `level` inside its window; else the crossing and
/// the fit's slope there (per cy/px).
fn refine_fall(pts: &[&MtfPoint], f0: f64, level: f64, lo: f64) -> Option<(f64, f64)> {
    let hw = CROSSING_FIT_HALF_WIDTH * f0;
    let k = pts.partition_point(|p| p.freq_cy_px < f0);
    let first = pts.partition_point(|p| p.freq_cy_px < (f0 - hw).max(lo));
    let end = pts.partition_point(|p| p.freq_cy_px <= f0 + hw);
    let first = first.min(k.saturating_sub(CROSSING_FIT_SIDE_POINTS));
    let end = end.max(k + CROSSING_FIT_SIDE_POINTS).min(pts.len());
    // (Unsorted frequencies, never produced here, give no fit rather than a bad slice.)
    if first >= end {
        return None;
    }
    let near = &pts[first..end];
    if near.len() < 2 * CROSSING_FIT_SIDE_POINTS || pts[first].freq_cy_px < lo {
        return None;
    }
    let span = near[near.len() - 1].freq_cy_px - near[0].freq_cy_px;
    if !(span > 0.0) {
        return None;
    }
    // Normalised abscissa d = (f − f0)/span keeps the normal equations well scaled.
    // Weights 1/σ², scaled so the largest is 1 (σ floored at 10⁻³ of the largest).
    let top = near.iter().map(|p| p.mtf_err.abs()).fold(0.0, f64::max);
    let floor = (top * 1e-3).max(1e-12);
    let mut a = [[0.0; 3]; 3];
    let mut b = [0.0; 3];
    for p in near {
        let d = (p.freq_cy_px - f0) / span;
        let w = (floor / p.mtf_err.abs().max(floor)).powi(2);
        let basis = [1.0, d, d * d];
        for r in 0..3 {
            b[r] += w * basis[r] * p.mtf;
            for c in 0..3 {
                a[r][c] += w * basis[r] * basis[c];
            }
        }
    }
    let [c0, c1, c2] = crate::linalg::solve(a, b, 1e-18)?;
    // Root of c0 − level + c1·d + c2·d² nearest d = 0, where the fit falls.
    let (p0, p1, p2) = (c0 - level, c1, c2);
    let roots: Vec<f64> = if p2.abs() < 1e-12 * p1.abs().max(1e-300) {
        vec![-p0 / p1]
    } else {
        let disc = p1 * p1 - 4.0 * p2 * p0;
        if disc < 0.0 {
            return None;
        }
        let q = -0.5 * (p1 + p1.signum() * disc.sqrt());
        vec![q / p2, p0 / q]
    };
    let (d_lo, d_hi) = (
        (near[0].freq_cy_px - f0) / span,
        (near[near.len() - 1].freq_cy_px - f0) / span,
    );
    roots
        .into_iter()
        .filter(|d| d.is_finite() && *d >= d_lo && *d <= d_hi && p1 + 2.0 * p2 * d < 0.0)
        .min_by(|x, y| x.abs().total_cmp(&y.abs()))
        .map(|d| (f0 + d * span, (p1 + 2.0 * p2 * d) / span))
}

/// The frequency where the (non-aliased) curve first falls through `level`, by linear interpolation.
pub fn crossing(points: &[MtfPoint], level: f64) -> Option<f64> {
    let (pts, sm, _) = smoothed(points);
    fall_from(&pts, &sm, 0, level).map(|c| c.0)
}

/// MTF50's one-sigma uncertainty (cy/px) from the points' current `mtf_err`
/// (as [`figures`] gives it): for uncertainties widened after the figures
/// were taken, such as a tone curve's unseen black level.
pub fn mtf50_sigma(points: &[MtfPoint]) -> Option<f64> {
    let (pts, sm, err) = smoothed(points);
    let (f, slope) = fall_from(&pts, &sm, 0, 0.5)?;
    crossing_sigma(&pts, &err, f, slope)
}

/// The (non-aliased) MTF at frequency `f`, by linear interpolation; None outside the measured range.
pub fn mtf_at(points: &[MtfPoint], f: f64) -> Option<f64> {
    let pts: Vec<&MtfPoint> = points.iter().filter(|p| !p.aliased).collect();
    pts.windows(2).find_map(|w| {
        let (a, b) = (w[0], w[1]);
        (a.freq_cy_px <= f && f <= b.freq_cy_px && b.freq_cy_px > a.freq_cy_px)
            .then(|| a.mtf + (b.mtf - a.mtf) * (f - a.freq_cy_px) / (b.freq_cy_px - a.freq_cy_px))
    })
}

/// The peak of a curve: (value, frequency cy/px, index into the smoothed points
/// to search from, whether it is a sharpening peak); None without points.
fn peak(pts: &[&MtfPoint], sm: &[f64], err: &[f64]) -> Option<(f64, f64, usize, bool)> {
    let i = (0..sm.len()).max_by(|&a, &b| sm[a].total_cmp(&sm[b]))?;
    // The smoothed point's uncertainty (neighbours share data: not divided by √3).
    let sig = err[i];
    if sm[i] > 1.0 + (PEAK_SIGMAS * sig).max(PEAK_FLOOR) {
        Some((sm[i], pts[i].freq_cy_px, i, true))
    } else {
        Some((1.0, 0.0, 0, false))
    }
}

/// MTF50/30/20/10, the peak and MTF50P/20P/10P, and the MTF at Nyquist of a curve.
pub fn figures(points: &[MtfPoint]) -> Figures {
    let (pts, sm, err) = smoothed(points);
    let at = |level: f64| fall_from(&pts, &sm, 0, level).map(|c| c.0);
    let pk = peak(&pts, &sm, &err);
    let at_p =
        |frac: f64| pk.and_then(|(v, _, i, _)| fall_from(&pts, &sm, i, frac * v).map(|c| c.0));
    let f50 = fall_from(&pts, &sm, 0, 0.5);
    Figures {
        mtf50_cy_px: f50.map(|c| c.0),
        mtf50_err_cy_px: f50.and_then(|(f, slope)| crossing_sigma(&pts, &err, f, slope)),
        mtf30_cy_px: at(0.3),
        mtf20_cy_px: at(0.2),
        mtf10_cy_px: at(0.1),
        mtf_nyquist: mtf_at(points, 0.5),
        peak_mtf: pk.map(|p| p.0),
        peak_cy_px: pk.map(|p| p.1),
        sharpening_peak: pk.is_some_and(|p| p.3),
        mtf50p_cy_px: at_p(0.5),
        mtf20p_cy_px: at_p(0.2),
        mtf10p_cy_px: at_p(0.1),
    }
}

impl Figures {
    /// The crossing figures, each with its label ("MTF50", "MTF50P", …), for output tables.
    pub fn crossings(&self) -> [(&'static str, Option<f64>); 7] {
        [
            ("MTF50", self.mtf50_cy_px),
            ("MTF30", self.mtf30_cy_px),
            ("MTF20", self.mtf20_cy_px),
            ("MTF10", self.mtf10_cy_px),
            ("MTF50P", self.mtf50p_cy_px),
            ("MTF20P", self.mtf20p_cy_px),
            ("MTF10P", self.mtf10p_cy_px),
        ]
    }

    /// Mutable references to every crossing figure (for leaving out noisy ones).
    pub fn crossings_mut(&mut self) -> [&mut Option<f64>; 7] {
        [
            &mut self.mtf50_cy_px,
            &mut self.mtf30_cy_px,
            &mut self.mtf20_cy_px,
            &mut self.mtf10_cy_px,
            &mut self.mtf50p_cy_px,
            &mut self.mtf20p_cy_px,
            &mut self.mtf10p_cy_px,
        ]
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// 200 points of `f` from 0.005 cy/px in steps of 0.0025, each ± `err`, aliased above 0.5.
    pub(in crate::measure) fn curve(f: impl Fn(f64) -> f64, err: f64) -> Vec<MtfPoint> {
        (0..200)
            .map(|i| {
                let fr = 0.005 + i as f64 * 0.0025;
                MtfPoint {
                    s: i as f64,
                    freq_cy_px: fr,
                    freq_chart: fr,
                    modulation: f(fr),
                    mtf: f(fr),
                    mtf_err: err,
                    aliased: fr > 0.5,
                    jpeg_limited: false,
                }
            })
            .collect()
    }

    /// A Gaussian MTF exp(−(f/0.3)²·ln 2) (MTF50 exactly 0.3 cy/px) with a
    /// ripple of ±0.015 and period 0.02 cy/px, as a coarse JPEG's blocks
    /// leave it (the ripple alone moves a point's crossing by ±2.2 %): the
    /// fitted crossing stays within 0.5 % of 0.3 at every phase of the ripple.
    #[test]
    fn a_rippled_curve_crosses_where_its_smooth_part_does() {
        let mut worst: f64 = 0.0;
        for k in 0..16 {
            let ph = k as f64 / 16.0 * std::f64::consts::TAU;
            let f = move |f: f64| {
                (-(f / 0.3).powi(2) * std::f64::consts::LN_2).exp()
                    + 0.015 * (std::f64::consts::TAU * f / 0.02 + ph).sin()
            };
            let g = figures(&curve(f, 0.01));
            worst = worst.max((g.mtf50_cy_px.unwrap() / 0.3 - 1.0).abs());
        }
        assert!(worst < 0.005, "{worst}");
    }

    /// Zero, NaN and infinite uncertainties, repeated and unsorted
    /// frequencies: figures without a panic, crossings inside the data.
    #[test]
    fn odd_uncertainties_and_frequencies_do_not_break_the_fit() {
        let gauss = |f: f64| (-(f / 0.3).powi(2) * std::f64::consts::LN_2).exp();
        for err in [0.0, f64::NAN, f64::INFINITY, 1e-300] {
            let g = figures(&curve(gauss, err));
            let f50 = g.mtf50_cy_px.unwrap();
            assert!((f50 / 0.3 - 1.0).abs() < 0.01, "{err}: {f50}");
        }
        let mut pts = curve(gauss, 0.003);
        pts.reverse();
        pts.swap(3, 90);
        let dup = pts[50];
        pts.insert(50, dup);
        let g = figures(&pts);
        assert!(
            g.mtf50_cy_px.is_none_or(|f| (0.0..=0.5).contains(&f)),
            "{g:?}"
        );
        // MTF50's uncertainty is never claimed as nothing on such input.
        assert!(g.mtf50_err_cy_px.is_none_or(|e| e > 0.0), "{g:?}");
    }

    /// A smooth curve's crossings are unchanged by the fit (to 10⁻⁴ relative).
    #[test]
    fn a_smooth_curve_crosses_exactly() {
        let g = figures(&curve(
            |f| (-(f / 0.3).powi(2) * std::f64::consts::LN_2).exp(),
            0.002,
        ));
        assert!((g.mtf50_cy_px.unwrap() / 0.3 - 1.0).abs() < 1e-4, "{g:?}");
        // MTF20 of the same Gaussian: 0.3 · √(ln 5 / ln 2).
        let f20 = 0.3 * (5f64.ln() / 2f64.ln()).sqrt();
        assert!((g.mtf20_cy_px.unwrap() / f20 - 1.0).abs() < 1e-4, "{g:?}");
    }

    /// MTF50's uncertainty is the points' uncertainty over the slope there:
    /// on a Gaussian exp(−(f/0.3)²·ln 2) the slope at 0.3 is −ln 2/0.3 per
    /// cy/px (differentiated by hand), so ±0.002 gives 0.002·0.3/ln 2; a
    /// curve falling slowly through 0.5 is capped at MTF50 itself; a flat
    /// curve has neither.
    #[test]
    fn mtf50_uncertainty_is_the_points_over_the_slope() {
        let g = figures(&curve(
            |f| (-(f / 0.3).powi(2) * std::f64::consts::LN_2).exp(),
            0.002,
        ));
        let want = 0.002 * 0.3 / std::f64::consts::LN_2;
        let got = g.mtf50_err_cy_px.unwrap();
        // (The quadratic over ±8 % gives the slope to 0.14 %: the third derivative.)
        assert!((got / want - 1.0).abs() < 5e-3, "{got} vs {want}");
        // Linear fall with slope −0.01 per cy/px from 0.503: ±0.05 would be
        // 5 cy/px; capped at the crossing (0.3 cy/px).
        let g = figures(&curve(|f| 0.503 - 0.01 * f, 0.05));
        assert_eq!(g.mtf50_err_cy_px, g.mtf50_cy_px);
        assert!(g.mtf50_cy_px.is_some());
        let g = figures(&curve(|_| 1.0, 0.002));
        assert_eq!((g.mtf50_cy_px, g.mtf50_err_cy_px), (None, None));
        // A vertical step (repeated frequencies): no claim rather than zero.
        let pts = curve(|f| 1.0 - f, 0.01);
        let refs: Vec<&MtfPoint> = pts.iter().collect();
        let err = vec![0.01; refs.len()];
        assert_eq!(crossing_sigma(&refs, &err, 0.3, f64::NEG_INFINITY), None);
        assert_eq!(crossing_sigma(&refs, &err, 0.3, 0.0), Some(0.3));
    }

    /// A tent peaking at 1.2 at 0.1 cy/px, then falling linearly to 0 at 0.45:
    /// crossings by hand on the straight parts (the 3-point mean is exact there).
    #[test]
    fn peak_and_crossings_by_hand() {
        let tent = |f: f64| {
            if f <= 0.1 {
                1.0 + 2.0 * f
            } else {
                (1.2 * (0.45 - f) / 0.35).max(0.0)
            }
        };
        let g = figures(&curve(tent, 0.001));
        assert!(g.sharpening_peak);
        // The peak's 3-point mean sits just under the tent's corner.
        assert!((g.peak_mtf.unwrap() - 1.2).abs() < 0.005, "{g:?}");
        assert!((g.peak_cy_px.unwrap() - 0.1).abs() < 0.003, "{g:?}");
        // Falling part: 1.2 (0.45 − f)/0.35 = L → f = 0.45 − 0.35 L / 1.2.
        let fall = |l: f64| 0.45 - 0.35 * l / 1.2;
        assert!((g.mtf50_cy_px.unwrap() - fall(0.5)).abs() < 1e-9);
        assert!((g.mtf20_cy_px.unwrap() - fall(0.2)).abs() < 1e-9);
        let p = g.peak_mtf.unwrap();
        assert!((g.mtf50p_cy_px.unwrap() - fall(0.5 * p)).abs() < 1e-9);
        assert!((g.mtf20p_cy_px.unwrap() - fall(0.2 * p)).abs() < 1e-9);
        assert!((g.mtf10p_cy_px.unwrap() - fall(0.1 * p)).abs() < 1e-9);
        // Half a peak above 1 is reached earlier than 0.5.
        assert!(g.mtf50p_cy_px.unwrap() < g.mtf50_cy_px.unwrap());
    }

    /// No sharpening: the peak is the low-frequency 1 and MTFnnP is MTFnn, bit for bit.
    #[test]
    fn unsharpened_curve_gives_mtf50p_equal_to_mtf50() {
        let g = figures(&curve(|f| (-12.0 * f * f).exp(), 0.002));
        assert!(!g.sharpening_peak);
        assert_eq!((g.peak_mtf, g.peak_cy_px), (Some(1.0), Some(0.0)));
        assert_eq!(g.mtf50p_cy_px, g.mtf50_cy_px);
        assert_eq!(g.mtf20p_cy_px, g.mtf20_cy_px);
        assert_eq!(g.mtf10p_cy_px, g.mtf10_cy_px);
        assert!(g.mtf50_cy_px.is_some());
    }

    /// The peak at the first point: a sweep starting above the sharpening peak.
    #[test]
    fn peak_at_the_first_point() {
        let g = figures(&curve(|f| 1.3 - 2.0 * f, 0.001));
        assert!(g.sharpening_peak);
        // First smoothed value: mean of the first two points.
        let want = 1.3 - 2.0 * (0.005 + 0.00125);
        assert!((g.peak_mtf.unwrap() - want).abs() < 1e-12, "{g:?}");
        assert!((g.peak_cy_px.unwrap() - 0.005).abs() < 1e-12);
        let f50p = (1.3 - 0.5 * want) / 2.0;
        assert!((g.mtf50p_cy_px.unwrap() - f50p).abs() < 1e-9, "{g:?}");
        assert!((g.mtf50_cy_px.unwrap() - 0.4).abs() < 1e-9);
    }

    /// A curve that stays above 10 % of its peak: MTF10P (and MTF10) absent, not a wrong number.
    #[test]
    fn never_falling_to_10_percent_of_the_peak_gives_none() {
        let g = figures(&curve(|f| 1.15 * (-2.0 * f * f).exp(), 0.001));
        assert!(g.sharpening_peak);
        assert!(g.mtf10p_cy_px.is_none() && g.mtf10_cy_px.is_none());
        assert!(g.mtf20p_cy_px.is_none() && g.mtf50p_cy_px.is_none());
        // And an empty curve has no figures at all.
        let e = figures(&[]);
        assert_eq!(e, Figures::default());
    }

    /// A flat curve at 1 with ±0.02 noise (honest error bars): no peak, no crossings.
    #[test]
    fn flat_noisy_curve_has_no_peak_and_no_crossings() {
        let mut st = 12345u64;
        let mut noise = || {
            st = st
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            // Uniform on ±√3·0.02: standard deviation 0.02.
            ((st >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0) * 0.02 * 3f64.sqrt()
        };
        let pts: Vec<MtfPoint> = curve(|_| 1.0, 0.02)
            .into_iter()
            .map(|mut p| {
                p.mtf += noise();
                p
            })
            .collect();
        let g = figures(&pts);
        assert!(!g.sharpening_peak, "{g:?}");
        assert_eq!(g.peak_mtf, Some(1.0));
        assert!(g.crossings().iter().all(|(_, f)| f.is_none()), "{g:?}");
    }
}
