//! A coarse JPEG's block ripple on a measured curve: how far a strip's bars
//! drift off the pixel axes (whether the 8×8 blocks average the quantiser's
//! error along the bars), and the smoothing in frequency that averages it
//! where they do not.

use super::{Curve, MtfPoint, curve};

/// Largest σ (cy/px) of the smoothing of a coarse JPEG's curve.
pub const RIPPLE_SIGMA_CY_PX: f64 = 0.06;
/// Largest σ of that smoothing as a fraction of the frequency (dimensionless).
pub const RIPPLE_SIGMA_REL: f64 = 0.25;
/// The RMS of a coarse JPEG's block ripple (MTF units): ±0.015 peak at
/// 0.25–0.45 cy/px (simulated q75), the error the smoothing averages out.
pub const RIPPLE_RMS_MTF: f64 = 0.015 / std::f64::consts::SQRT_2;

/// Below this drift (px) across the measured width, a curve's bars lie square
/// to the pixel grid. 0.1 px until session 30; the independent camera's
/// q75 shots with sharpening, uneven light, keystone and distortion (kind
/// `all`, seeds 4 and 6, 10 shots each) turned 0.2° read MTF50 beyond 1 %
/// on 4 of 20 and the chart modulation beyond 0.5 % on 6 of 20, and 17 of
/// the 20 drift less than 0.5 px at an end (keystone and distortion turn
/// the end lines); turned 1°, 0 and 1 of 20; turned 1.5°, 1 and 2 of 20.
pub const SQUARE_DRIFT_PX: f64 = 0.5;

/// How far (px) the bars drift off the nearer pixel axis across the
/// measured width: the smaller of the two measured end lines' offsets (a
/// keystoned or distorted strip turns its bars along its length, and the
/// error stays unaveraged where they lie square; the larger until session 30).
///
/// A coarse JPEG's quantisation error is averaged along the bars only when
/// its 8×8 blocks see the sine at different sample phases. Bars that drift by
/// less than [`SQUARE_DRIFT_PX`] give every block row the same samples, so
/// the error stays as one draw per block column (simulated q75 at 0°: MTF50
/// off by up to ±2.5 %, 11 of 24 shots beyond 1 %, the chart modulation by
/// up to +1.1 %; turned 0.1–5°: within ±1.1 %, 2 of 176 beyond 1 %).
pub fn bar_drift_px(c: &Curve) -> f64 {
    c.measured_lines_px
        .iter()
        .map(|[a, b]| (b[0] - a[0]).abs().min((b[1] - a[1]).abs()))
        .fold(f64::INFINITY, f64::min)
}

/// Smooths the non-aliased points of a coarse JPEG's curve in frequency by
/// local quadratic regression, twiced: at each point a weighted quadratic in
/// f (Gaussian kernel of σ = min([`RIPPLE_SIGMA_CY_PX`],
/// [`RIPPLE_SIGMA_REL`]·f, a third of the distance to the nearer end of
/// the non-aliased points), weights kernel/σ², is read at that point; the
/// same smoothing of what it left out (the residuals) is added back where
/// the kernel is whole (not narrowed by the ends).
///
/// The quantiser's error ripples the curve by up to ±0.015 with a period of
/// ≈ 0.02 cy/px, and at turns of 1–5° the ripple's slow part alone moved
/// MTF50 by up to ±1.9 % (simulated q75: 11 of 144 shots beyond 1 %). A
/// local *quadratic* has no bias from the curve's curvature (a kernel mean
/// or local line of this width raised MTF50 by ≈ 0.2–0.3 % on Gaussian and
/// sharpened curves), only from its fourth derivative: on a Gaussian lens ×
/// pixel aperture it raised the curve by up to +0.25 / +0.57 % (lens σ 0.55 /
/// 0.7 px) and MTF50 by +0.13 / +0.42 %. Twicing (Tukey: S(m) + S(m − S(m)),
/// an effective kernel 2K − K∗K) takes that to −0.02 / +0.07 % and still
/// removes the ripple, whose period is far inside the kernel. A point's
/// uncertainty becomes the kernel-weighted mean of its neighbours' (their
/// errors are correlated, so not divided by √n). Where the fit is singular
/// the kernel mean is kept.
///
/// Each point weighs 1/(σ² + `ripple`²), `ripple` the ripple's RMS in the
/// points' units: the ripple is every point's error here, and the noise
/// alone let the points the quantiser had left flat pin the fit. Where the
/// q75 file held nothing beyond ≈ 0.34 cy/px (a lens of σ 1.2 px), those
/// points read 0 ± 10⁻⁸ and, weighted by 1/σ², dragged the curve to 0 from
/// 0.205 cy/px, where it is 0.25 (RMS 0.072, MTF10 0.207 for 0.26 cy/px).
pub(super) fn smooth(points: &mut [MtfPoint], ripple: f64) {
    let src: Vec<(f64, f64, f64)> = points
        .iter()
        .filter(|p| !p.aliased && p.mtf_err.is_finite() && p.mtf_err > 0.0)
        .map(|p| (p.freq_cy_px, p.modulation, p.mtf_err))
        .collect();
    let (Some(first), Some(last)) = (src.first().map(|q| q.0), src.last().map(|q| q.0)) else {
        return;
    };
    // What the first pass leaves out at each point, smoothed again and added back.
    let residual: Vec<(f64, f64, f64)> = src
        .iter()
        .map(|&(f, m, e)| {
            let s = local_quadratic(&src, f, first, last, ripple).map_or(m, |v| v.0);
            (f, m - s, e)
        })
        .collect();
    for p in points.iter_mut().filter(|p| !p.aliased) {
        let Some((value, err)) = local_quadratic(&src, p.freq_cy_px, first, last, ripple) else {
            continue;
        };
        // Not where the ends narrow the kernel: a second pass there gives
        // back part of the ripple (simulated q75 square to the blocks: MTF50
        // up to 3.1 % off instead of 2.5 % when only kernels narrowed to less
        // than half were left out).
        let edge_limited = (p.freq_cy_px - first).min(last - p.freq_cy_px) / 3.0
            < RIPPLE_SIGMA_CY_PX.min(RIPPLE_SIGMA_REL * p.freq_cy_px);
        let back = if edge_limited {
            0.0
        } else {
            local_quadratic(&residual, p.freq_cy_px, first, last, ripple).map_or(0.0, |v| v.0)
        };
        p.modulation = value + back;
        p.mtf = p.modulation;
        p.mtf_err = err;
    }
}

/// The local quadratic of [`smooth`] through `src` (f cy/px,
/// value, σ; sorted by f, spanning `first`–`last`) read at `f0` (cy/px),
/// each point weighed by 1/(σ² + `ripple`²): the value and the
/// kernel-weighted mean σ; `None` where the kernel is empty.
fn local_quadratic(
    src: &[(f64, f64, f64)],
    f0: f64,
    first: f64,
    last: f64,
    ripple: f64,
) -> Option<(f64, f64)> {
    // Narrower towards the ends, so the window stays whole (a one-sided window is biased by the slope).
    let edge = (f0 - first).min(last - f0) / 3.0;
    let sigma = RIPPLE_SIGMA_CY_PX.min(RIPPLE_SIGMA_REL * f0).min(edge);
    if !(sigma > 0.0) {
        return None;
    }
    let lo = src.partition_point(|q| q.0 < f0 - 3.0 * sigma);
    let (mut sw, mut sm, mut se, mut n) = (0.0, 0.0, 0.0, 0usize);
    // Normal equations of the weighted quadratic in d = (f − f0)/σ.
    let (mut a, mut b) = ([[0.0; 3]; 3], [0.0; 3]);
    for &(f, m, e) in src[lo..].iter().take_while(|q| q.0 <= f0 + 3.0 * sigma) {
        let d = (f - f0) / sigma;
        let k = (-0.5 * d * d).exp();
        sw += k;
        sm += k * m;
        se += k * e;
        n += 1;
        let w = k / (e * e + ripple * ripple);
        let basis = [1.0, d, d * d];
        for r in 0..3 {
            b[r] += w * basis[r] * m;
            for c in 0..3 {
                a[r][c] += w * basis[r] * basis[c];
            }
        }
    }
    if !(sw > 0.0 && sw.is_finite()) {
        return None;
    }
    // Fewer than 5 points (the very ends) keep the kernel mean.
    let value = (n >= 5)
        .then(|| curve::solve3(a, b))
        .flatten()
        .map(|c| c[0])
        .filter(|m| m.is_finite())
        .unwrap_or(sm / sw);
    Some((value, se / sw))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::measure::figures::tests::curve;

    fn gauss(f: f64) -> f64 {
        (-(f / 0.3).powi(2) * std::f64::consts::LN_2).exp()
    }

    /// A parabola is reproduced exactly (the local fit is quadratic); a
    /// closed-form Gaussian MTF with a ±0.015 ripple of period 0.02 cy/px
    /// above 0.2 cy/px: smoothed, within 0.004 of the Gaussian there; the
    /// Gaussian alone moves by less than 5·10⁻⁴ anywhere (its fourth
    /// derivative's bias), aliased points untouched.
    #[test]
    fn the_block_ripple_is_smoothed_and_a_smooth_curve_kept() {
        // A sharpened curve's peak (a parabola, 1.2 at 0.2 cy/px) is kept exactly: the fit is quadratic.
        let parabola = |f: f64| 1.2 - 3.0 * (f - 0.2).powi(2);
        let mut pts = curve(parabola, 0.003);
        smooth(&mut pts, RIPPLE_RMS_MTF);
        // (The outermost two points on each side, with fewer than 5 in their
        // window, keep a kernel mean; the twicing pass carries their residual
        // a little way in: ≤ 2.5·10⁻⁶ below 0.05 cy/px.)
        for p in pts.iter().filter(|p| !p.aliased) {
            let tol = if (0.05..0.49).contains(&p.freq_cy_px) {
                1e-8
            } else if (0.01..0.49).contains(&p.freq_cy_px) {
                1e-5
            } else {
                1e-4
            };
            let moved = (p.mtf - parabola(p.freq_cy_px)).abs();
            assert!(moved < tol, "{} {moved}", p.freq_cy_px);
        }
        let rippled = |f: f64| {
            gauss(f)
                + if f > 0.2 {
                    0.015 * (std::f64::consts::TAU * f / 0.02).sin()
                } else {
                    0.0
                }
        };
        let mut pts = curve(rippled, 0.003);
        smooth(&mut pts, RIPPLE_RMS_MTF);
        for p in pts.iter().filter(|p| (0.23..0.48).contains(&p.freq_cy_px)) {
            assert!(
                (p.mtf - gauss(p.freq_cy_px)).abs() < 0.004,
                "{} {}",
                p.freq_cy_px,
                p.mtf
            );
        }
        let mut pts = curve(gauss, 0.003);
        smooth(&mut pts, RIPPLE_RMS_MTF);
        for p in &pts {
            let moved = (p.mtf - gauss(p.freq_cy_px)).abs();
            if p.aliased {
                assert_eq!(moved, 0.0);
            } else {
                assert!(moved < 5e-4, "{} {moved}", p.freq_cy_px);
            }
            assert!((p.mtf_err - 0.003).abs() < 1e-12);
        }
    }

    /// A blurred lens through a q75 file: a Gaussian MTF (MTF50 0.14 cy/px)
    /// whose tail the quantiser left flat, 0 ± 10⁻⁹ wherever it is below
    /// 0.02 (from 0.27 cy/px), the rest ± 0.003. Smoothed, the curve stays
    /// within 0.005 of the closed form up to 0.25 cy/px (weighed by 1/σ²
    /// alone, they pulled it 0.0056 off already at 0.125 cy/px).
    #[test]
    fn a_flattened_tail_does_not_pin_the_smoothing() {
        let soft = |f: f64| (-(f / 0.14).powi(2) * std::f64::consts::LN_2).exp();
        let mut pts = curve(soft, 0.003);
        for p in pts.iter_mut().filter(|p| soft(p.freq_cy_px) < 0.02) {
            (p.mtf, p.modulation, p.mtf_err) = (0.0, 0.0, 1e-9);
        }
        smooth(&mut pts, RIPPLE_RMS_MTF);
        for p in pts.iter().filter(|p| p.freq_cy_px <= 0.25) {
            let off = (p.mtf - soft(p.freq_cy_px)).abs();
            assert!(off < 0.005, "{} {} {off}", p.freq_cy_px, p.mtf);
        }
    }

    /// A soft lens's curve (Gaussian σ = 0.7 px × the pixel's sinc, MTF50
    /// ≈ 0.25 cy/px) bends enough for a single local quadratic to raise it
    /// by 1.0·10⁻³ near 0.3 cy/px (its fourth derivative); twiced, it moves
    /// by less than 2.5·10⁻⁴ wherever the kernel is whole (up to 0.32 cy/px
    /// here, the points ending at 0.5); nearer the end, not twiced, within
    /// the single pass's 1.1·10⁻³.
    #[test]
    fn twicing_takes_out_the_local_quadratics_bias() {
        let soft = |f: f64| {
            let x = std::f64::consts::PI * f;
            (-2.0 * (x * 0.7).powi(2)).exp() * if x > 0.0 { x.sin() / x } else { 1.0 }
        };
        let mut pts = curve(soft, 0.003);
        smooth(&mut pts, RIPPLE_RMS_MTF);
        for p in pts.iter().filter(|p| !p.aliased) {
            let moved = (p.mtf - soft(p.freq_cy_px)).abs();
            let tol = if p.freq_cy_px <= 0.32 { 2.5e-4 } else { 1.1e-3 };
            assert!(moved < tol, "{} {moved}", p.freq_cy_px);
        }
    }
}
