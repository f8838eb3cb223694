//! The chart's own modulation, extrapolated to zero frequency from the
//! curve's low-frequency end: the near and wide (log) estimates, the
//! correction for diffraction's higher terms, and the robust fit they use.

use super::MtfPoint;

/// The chart's modulation estimated from the low-frequency end of the curve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChartModulation {
    /// Modulation at 0 cy/px (0–1].
    pub value: f64,
    /// One-sigma uncertainty of `value` (noise and scatter of the points used).
    pub err: f64,
    /// Lowest frequency used (cycles/pixel).
    pub f_lo: f64,
    /// Highest frequency used (cycles/pixel).
    pub f_hi: f64,
    /// Whether the curve was taken to start with a slope (a lens's diffraction):
    /// true for the model M0·(1 + b f + c f²) with b < 0, false for the even
    /// M0·(1 + b f² + c f⁴) used where the data show no falling start.
    pub linear_start: bool,
    /// The curve's relative slope at 0, M′(0)/M0 (per cy/px; ≤ 0, and 0 for an even start).
    pub slope_rel: f64,
}

/// Estimates the chart's modulation by extrapolating the low-frequency end of
/// the (non-aliased) modulation curve to zero frequency.
///
/// Only points at `s ≥ s_min` are used (the caller leaves out the periods
/// next to the strip's end). The models follow the physics of a camera's MTF
/// near 0: every lens has a finite aperture, so its diffraction gives the
/// curve a falling linear start, 1 − (4/π)·f/f_c for a circular pupil,
/// whatever its aberrations (they, the pixel aperture, diffusion, defocus and
/// sharpening are all even in f and start quadratically). Two estimates are
/// made, each by iteratively reweighted least squares (Tukey biweight on
/// residuals scaled by the points' own uncertainty and a robust scale, so one
/// bad point cannot drag the fit), and the one with the smaller uncertainty
/// is kept:
/// - near: M0·(1 + b f + c f²) through the points up to max(2 f_lo, f_lo + 0.05)
///   cy/px that stay within 10 % of the first ones;
/// - wide: ln M = ln M0 + b f + c f² (+ d f³ where the points need it)
///   through those up to max(2 f_lo, f_lo + 0.15) cy/px within 30 %: the MTF
///   is a product of factors, so its logarithm is a sum of smooth terms, and
///   the cubic follows the strong fall of blur and diffusion and the rise of
///   sharpening that bend a low-order polynomial in M itself.
///
/// A rising start (b > 0) is not physical (|OTF| ≤ OTF(0) for any PSF whose
/// rise is even): the even form (in f², f⁴, …) is used then.
///
/// Diffraction brings more than its slope: ln D = −(4/π)x − (8/π²)x² −
/// 0.476x³ − … (x = f/f_c), and three free log terms cannot follow its
/// cubic. Where the start is linear, the points are divided by those terms
/// beyond f² for the cut-off the slope gives, f_c = (4/π)/(−M′(0)/M0), and
/// the estimate made again until the slope settles (session 30): on a
/// linear sweep whose first point lies at 0.057 cy/px (f/7.6 on 4 µm
/// pixels) the chart modulation read 0.12 % low, now 0.03 %. Assuming an even
/// start for a real lens (as before session 10) put the chart modulation
/// 1–4 % low (f/4–f/11 on 4.3 µm pixels).
pub fn extrapolate_chart_modulation(
    points: &[MtfPoint],
    s_min: f64,
) -> Result<ChartModulation, String> {
    let mut pts: Vec<&MtfPoint> = points
        .iter()
        .filter(|p| !p.aliased && p.modulation.is_finite() && p.freq_cy_px > 0.0)
        .collect();
    pts.sort_by(|a, b| a.freq_cy_px.total_cmp(&b.freq_cy_px));
    if pts.is_empty() {
        return Err("no modulation measured".into());
    }
    let inner: Vec<&MtfPoint> = pts.iter().copied().filter(|p| p.s >= s_min).collect();
    // A strip too short, or starting too high, to leave its ends out: use what there is.
    let pts = if inner.len() >= 6 && inner[0].freq_cy_px <= 0.08 {
        inner
    } else {
        pts
    };
    let f_lo = pts[0].freq_cy_px;
    if f_lo > 0.08 {
        return Err(format!(
            "the sweep starts at {f_lo:.3} cy/px, too high to extrapolate to zero frequency; \
             give --target with the printed contrast or a region that starts below 0.08 cy/px"
        ));
    }
    let plain = near_or_wide(&pts, f_lo)?;
    // Diffraction's own terms beyond f², tied to the slope found (see
    // `diffraction_beyond_quadratic`): the points are divided by them and the
    // estimate made again, until the slope settles.
    let mut est = plain;
    for _ in 0..DIFFRACTION_PASSES {
        if !est.linear_start {
            return Ok(plain);
        }
        let Some(adjusted) = without_diffraction_tail(&pts, est.slope_rel) else {
            return Ok(plain);
        };
        let refs: Vec<&MtfPoint> = adjusted.iter().collect();
        let Ok(next) = near_or_wide(&refs, f_lo) else {
            return Ok(plain);
        };
        let settled = (next.slope_rel - est.slope_rel).abs() <= 1e-3 * est.slope_rel.abs();
        est = next;
        if settled {
            break;
        }
    }
    Ok(if est.linear_start { est } else { plain })
}

/// Passes of the diffraction-tail correction at most (the slope settles in two or three).
const DIFFRACTION_PASSES: usize = 5;

/// Highest f/f_c at which the points are divided by diffraction's higher terms;
/// beyond it the points are left as they are (nothing is corrected).
const DIFFRACTION_X_MAX: f64 = 0.8;

/// Two estimates; the one with the smaller uncertainty is kept.
fn near_or_wide(pts: &[&MtfPoint], f_lo: f64) -> Result<ChartModulation, String> {
    let near = near_estimate(pts, f_lo)?;
    Ok(match log_estimate(pts, f_lo) {
        Some(w) if w.err < near.err => w,
        _ => near,
    })
}

/// ln D(x) of a circular pupil's diffraction MTF, D = (2/π)(acos x − x√(1 − x²)),
/// less its linear and quadratic terms −(4/π)x − (8/π²)x²: what a model
/// with a free slope and a free f² term cannot follow (−0.476 x³ − …;
/// 1.3e-3 at x = 0.14). x = f/f_c in [0, 1).
pub fn diffraction_beyond_quadratic(x: f64) -> f64 {
    use std::f64::consts::PI;
    let d = crate::model::optics::diffraction_otf_t(1.0 - x);
    d.ln() + 4.0 / PI * x + 8.0 / (PI * PI) * x * x
}

/// The points at `f_lo + 0.2` cy/px and below with their modulation divided
/// by exp([`diffraction_beyond_quadratic`]) for the cut-off the relative
/// slope `slope_rel` (per cy/px, < 0) gives, f_c = (4/π)/(−slope_rel); `None`
/// where the slope is not negative or those points reach beyond
/// [`DIFFRACTION_X_MAX`] of the cut-off.
pub(super) fn without_diffraction_tail(pts: &[&MtfPoint], slope_rel: f64) -> Option<Vec<MtfPoint>> {
    let inv_fc = -slope_rel * std::f64::consts::FRAC_PI_4;
    let f_lo = pts.first()?.freq_cy_px;
    let used: Vec<&MtfPoint> = pts
        .iter()
        .copied()
        .filter(|p| p.freq_cy_px <= f_lo + 0.2)
        .collect();
    let x_max = used.last()?.freq_cy_px * inv_fc;
    if !(inv_fc > 0.0 && x_max <= DIFFRACTION_X_MAX) {
        return None;
    }
    Some(
        used.into_iter()
            .map(|p| MtfPoint {
                modulation: p.modulation
                    * (-diffraction_beyond_quadratic(p.freq_cy_px * inv_fc)).exp(),
                ..*p
            })
            .collect(),
    )
}

/// The lowest points, at most `move_max` (relative) from the first ones' modulation,
/// up to max(2 f_lo, f_lo + `span`) cy/px (at least `least` points when there are).
fn start_points<'a>(
    pts: &[&'a MtfPoint],
    f_lo: f64,
    span: f64,
    move_max: f64,
    least: usize,
) -> Vec<&'a MtfPoint> {
    let f_hi = (f_lo + span).max(2.0 * f_lo);
    let mut sel: Vec<&MtfPoint> = pts
        .iter()
        .copied()
        .filter(|p| p.freq_cy_px <= f_hi)
        .collect();
    if sel.len() < 8 {
        sel = pts.iter().copied().take(8).collect();
    }
    let mut first: Vec<f64> = sel.iter().take(3).map(|p| p.modulation).collect();
    first.sort_by(f64::total_cmp);
    let reference = first[first.len() / 2];
    let within = sel
        .iter()
        .position(|p| (p.modulation / reference - 1.0).abs() > move_max)
        .unwrap_or(sel.len());
    sel.truncate(within.max(least));
    sel
}

/// A point's modulation uncertainty, with a floor so that noiseless points
/// do not claim infinite weight.
fn modulation_err(p: &MtfPoint) -> f64 {
    let e = (p.mtf_err * p.modulation / p.mtf.max(1e-12)).abs();
    e.hypot(2e-4 * p.modulation.abs())
}

/// The near estimate: M0·(1 + b f + c f²) (or the even form) through the
/// points within [`MAX_MOVE`] of the first ones, up to max(2 f_lo, f_lo + 0.05).
pub(super) fn near_estimate(pts: &[&MtfPoint], f_lo: f64) -> Result<ChartModulation, String> {
    let sel = start_points(pts, f_lo, 0.05, MAX_MOVE, 5);
    if sel.len() < 5 {
        return Err("too few low-frequency points to extrapolate to zero frequency".into());
    }
    let f_top = sel.last().map(|p| p.freq_cy_px).unwrap_or(f_lo);
    let data: Vec<(f64, f64, f64)> = sel
        .iter()
        .map(|p| (p.freq_cy_px / f_top, p.modulation, modulation_err(p)))
        .collect();
    let linear = robust_fit(&data, |x| [1.0, x, x * x]).filter(|l| l.slope <= 0.0);
    let (fit, linear_start) = match linear {
        Some(l) => (l, true),
        None => (
            robust_fit(&data, |x| [1.0, x * x, x.powi(4)])
                .ok_or("the low-frequency points do not determine a curve")?,
            false,
        ),
    };
    // Neighbouring points share data, so the scatter rather than the claimed
    // uncertainty sets the variance where it is the larger.
    let disp = fit.dispersion();
    let value = fit.m0;
    if !(value > 0.0 && value.is_finite()) {
        return Err("the extrapolated chart modulation is not positive".into());
    }
    Ok(ChartModulation {
        value,
        err: (fit.var * disp).sqrt(),
        f_lo,
        f_hi: f_top,
        linear_start,
        slope_rel: if linear_start {
            fit.slope / (f_top * value)
        } else {
            0.0
        },
    })
}

/// The wide estimate: ln M = ln M0 + b f + c f² (+ d f³) (or the even forms
/// in f², f⁴ (, f⁶)) through the points within [`WIDE_MOVE`] of the first
/// ones, up to max(2 f_lo, f_lo + 0.15) cy/px. A product of factors (lens,
/// pixel, diffusion, sharpening) is a sum of logarithms, each smooth in f.
/// Near 0 the physics has diffraction's linear start and the even factors'
/// f²; the three terms are kept unless the fourth is significant beyond
/// [`MIN_TERM_SIGNIFICANCE`] of its own uncertainty (nested fits). The cubic
/// follows what a low-order form cannot over this range, the strong fall of
/// blur and diffusion and the rise of sharpening (whose series in f² has not
/// converged by 0.15 cy/px: there it extrapolated within 0.22 % where an f⁴
/// term read up to −0.7 %). Fitted always, the free cubic followed the
/// points' slow, shared ripple (JPEG, noise through overlapping windows) and
/// carried it to 0 several times over: on linear sweeps, whose lowest point
/// lies near 0.045 cy/px, the chart modulation read −1.3…+0.6 %. `None`
/// with fewer than 7 points.
fn log_estimate(pts: &[&MtfPoint], f_lo: f64) -> Option<ChartModulation> {
    let pos: Vec<&MtfPoint> = pts.iter().copied().filter(|p| p.modulation > 0.0).collect();
    if pos.first()?.freq_cy_px > f_lo {
        return None;
    }
    let sel = start_points(&pos, f_lo, 0.15, WIDE_MOVE, 7);
    if sel.len() < 7 {
        return None;
    }
    let f_top = sel.last()?.freq_cy_px;
    let data: Vec<(f64, f64, f64)> = sel
        .iter()
        .map(|p| {
            (
                p.freq_cy_px / f_top,
                p.modulation.ln(),
                modulation_err(p) / p.modulation,
            )
        })
        .collect();
    let three = match robust_fit(&data, |x| [1.0, x, x * x]).filter(|l| l.slope <= 0.0) {
        Some(l) => Some((l, true)),
        None => robust_fit(&data, |x| [1.0, x * x, x.powi(4)]).map(|l| (l, false)),
    };
    let four = match robust_fit(&data, |x| [1.0, x, x * x, x * x * x]).filter(|l| l.slope <= 0.0) {
        Some(l) => Some((l, true)),
        None => robust_fit(&data, |x| {
            let x2 = x * x;
            [1.0, x2, x2 * x2, x2 * x2 * x2]
        })
        .map(|l| (l, false)),
    };
    let estimate = |(fit, linear_start): (RobustFit, bool)| -> Option<ChartModulation> {
        let disp = fit.dispersion();
        let value = fit.m0.exp();
        let err = value * (fit.var * disp).sqrt();
        (value > 0.0 && value.is_finite() && err.is_finite()).then_some(ChartModulation {
            value,
            err,
            f_lo,
            f_hi: f_top,
            linear_start,
            slope_rel: if linear_start { fit.slope / f_top } else { 0.0 },
        })
    };
    // Nested: the fourth term (f³, or f⁶ in the even form) is kept where the
    // points need it, beyond MIN_TERM_SIGNIFICANCE of its own uncertainty
    // (widened by the fit's dispersion); else the three terms.
    let needs_four = four.is_some_and(|(f, _)| {
        f.last.abs() > MIN_TERM_SIGNIFICANCE * (f.last_var * f.dispersion()).sqrt()
    });
    if needs_four || three.is_none() {
        four.and_then(estimate)
    } else {
        three.and_then(estimate)
    }
}

/// Significance (in its own standard deviations) beyond which the wide
/// estimate's fourth term is kept.
const MIN_TERM_SIGNIFICANCE: f64 = 3.0;

/// Largest relative move of the modulation over the points the wide estimate fits.
const WIDE_MOVE: f64 = 0.3;

/// Largest relative move of the modulation over the points the extrapolation fits.
const MAX_MOVE: f64 = 0.1;

/// One robust fit: intercept, its variance, and the robust χ² with its degrees of freedom.
#[derive(Debug, Clone, Copy)]
struct RobustFit {
    m0: f64,
    slope: f64,
    var: f64,
    /// The last basis function's coefficient and its variance.
    last: f64,
    last_var: f64,
    chi2: f64,
    dof: f64,
}

impl RobustFit {
    /// The robust χ² per degree of freedom, at least 1: neighbouring points
    /// share data, so the scatter rather than the claimed uncertainty sets the
    /// variance where it is the larger.
    fn dispersion(&self) -> f64 {
        (self.chi2 / self.dof.max(1.0)).max(1.0)
    }
}

/// Iteratively reweighted least squares of y on the three basis functions of x,
/// weights 1/e² times a Tukey biweight (c = 4.685) of the residuals over their
/// robust scale.
fn robust_fit<const N: usize>(
    data: &[(f64, f64, f64)],
    basis: impl Fn(f64) -> [f64; N],
) -> Option<RobustFit> {
    let mut tukey = vec![1.0f64; data.len()];
    let mut coef = [0.0f64; N];
    let mut cov00 = 0.0;
    let mut cov_last = 0.0;
    let unit: [f64; N] = std::array::from_fn(|i| if i == 0 { 1.0 } else { 0.0 });
    let unit_last: [f64; N] = std::array::from_fn(|i| if i == N - 1 { 1.0 } else { 0.0 });
    let model =
        |coef: &[f64; N], x: f64| -> f64 { basis(x).iter().zip(coef).map(|(b, c)| b * c).sum() };
    for iter in 0..20 {
        let mut m = [[0.0f64; N]; N];
        let mut r = [0.0f64; N];
        for (k, &(x, y, e)) in data.iter().enumerate() {
            let w = tukey[k] / (e * e);
            let b = basis(x);
            for i in 0..N {
                r[i] += w * b[i] * y;
                for j in 0..N {
                    m[i][j] += w * b[i] * b[j];
                }
            }
        }
        let new = crate::linalg::solve(m, r, 1e-300)?;
        // Variance of the intercept: first column of the inverse.
        cov00 = crate::linalg::solve(m, unit, 1e-300)?[0];
        cov_last = crate::linalg::solve(m, unit_last, 1e-300)?[N - 1];
        let moved = (new[0] - coef[0]).abs();
        coef = new;
        let z: Vec<f64> = data
            .iter()
            .map(|&(x, y, e)| (y - model(&coef, x)) / e)
            .collect();
        let mut abs: Vec<f64> = z.iter().map(|v| v.abs()).collect();
        abs.sort_by(f64::total_cmp);
        let mad = 1.4826 * abs[abs.len() / 2];
        // The scale never falls below the claimed uncertainty (z of 1).
        let scale = mad.max(1.0);
        for (t, v) in tukey.iter_mut().zip(&z) {
            let u = v / (4.685 * scale);
            *t = if u.abs() < 1.0 {
                (1.0 - u * u).powi(2)
            } else {
                0.0
            };
        }
        if iter > 2 && moved < 1e-9 * coef[0].abs() {
            break;
        }
    }
    let mut chi2 = 0.0;
    let mut wsum = 0.0;
    for (k, &(x, y, e)) in data.iter().enumerate() {
        let res = (y - model(&coef, x)) / e;
        chi2 += tukey[k] * res * res;
        wsum += tukey[k];
    }
    (coef[0].is_finite() && cov00.is_finite()).then_some(RobustFit {
        m0: coef[0],
        slope: coef[1],
        var: cov00.max(0.0),
        last: coef[N - 1],
        last_var: cov_last.max(0.0),
        chi2,
        dof: (wsum - N as f64).max(1.0),
    })
}
