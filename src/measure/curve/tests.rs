//! Tests of the curve: the sampling lattices' bands, the chart modulation's
//! extrapolation on model curves, and the summary crossings.

use super::chart_modulation::{near_estimate, without_diffraction_tail};
use super::*;

#[test]
fn the_two_greens_form_a_quincunx_whose_band_is_a_diamond() {
    use crate::photo::Plane;
    let plane = |offset, step| Plane {
        width: 1,
        height: 1,
        step,
        offset,
        data: vec![0.0],
    };
    let (gr, gb) = (plane((1, 0), (2, 2)), plane((0, 1), (2, 2)));
    let (r, b) = (plane((0, 0), (2, 2)), plane((1, 1), (2, 2)));
    assert_eq!(
        Lattice::of(&[(&gr).into(), (&gb).into()]),
        Lattice::Quincunx
    );
    assert_eq!(Lattice::of(&[(&r).into(), (&b).into()]), Lattice::Quincunx);
    assert_eq!(
        Lattice::of(&[(&r).into(), (&gr).into()]),
        Lattice::Rect(2, 2)
    );
    assert_eq!(Lattice::of(&[(&r).into()]), Lattice::Rect(2, 2));
    let full = plane((0, 0), (1, 1));
    assert_eq!(Lattice::of(&[(&full).into()]), Lattice::Rect(1, 1));
    // Band edges: along the axes 0.5 cy/px, on the diagonal |f| = 0.5/√2.
    let q = Lattice::Quincunx;
    let d = std::f64::consts::FRAC_PI_4;
    assert!((q.band_limit(0.0) - 0.5).abs() < 1e-12);
    assert!((q.band_limit(d) - 0.5 / 2f64.sqrt()).abs() < 1e-12);
    assert!(!q.outside(0.49, 0.0) && q.outside(0.51, 0.0));
    assert!(!q.outside(0.35, d) && q.outside(0.36, d));
    // 30°: |fx| + |fy| = f·(cos 30° + sin 30°).
    let a = 30f64.to_radians();
    let lim = 0.5 / (a.cos() + a.sin());
    assert!(!q.outside(lim - 1e-6, a) && q.outside(lim + 1e-6, a));
    // A step-2 lattice: 0.25 cy/px along x, and the per-axis test agrees with the limit.
    let rect = Lattice::Rect(2, 2);
    assert!((rect.band_limit(0.0) - 0.25).abs() < 1e-12);
    for f in [0.1, 0.24, 0.26, 0.4] {
        for a in [0.0, 0.3, d, 1.2] {
            assert_eq!(rect.outside(f, a), f > rect.band_limit(a) + 1e-9);
        }
    }
}

/// `n` points from `f0` cy/px, `df` apart: modulation m0·mtf(f), each
/// `mtf_err` uncertain, aliased beyond 0.5 cy/px.
fn grid(
    m0: f64,
    (f0, df, n): (f64, f64, usize),
    mtf_err: f64,
    mtf: impl Fn(f64) -> f64,
) -> Vec<MtfPoint> {
    (0..n)
        .map(|i| {
            let fr = f0 + i as f64 * df;
            MtfPoint {
                s: i as f64,
                freq_cy_px: fr,
                freq_chart: fr,
                modulation: m0 * mtf(fr),
                mtf: mtf(fr),
                mtf_err,
                aliased: fr > 0.5,
                jpeg_limited: false,
            }
        })
        .collect()
}

fn curve(m0: f64, f: impl Fn(f64) -> f64) -> Vec<MtfPoint> {
    grid(m0, (0.005, 0.0025, 200), 0.001, f)
}

/// A circular pupil's diffraction MTF, cut-off `fc` cy/px, from the closed
/// form (0 beyond the cut-off).
fn circular_pupil(fc: f64) -> impl Fn(f64) -> f64 {
    move |f| {
        let x = (f / fc).min(1.0);
        2.0 / std::f64::consts::PI * (x.acos() - x * (1.0 - x * x).sqrt())
    }
}

#[test]
fn extrapolates_gaussian_and_diffraction_like_curves() {
    let sigma: f64 = 0.9;
    let gauss = |f: f64| (-2.0 * std::f64::consts::PI.powi(2) * sigma * sigma * f * f).exp();
    let a = extrapolate_chart_modulation(&curve(0.8, gauss), 0.0)
        .unwrap()
        .value;
    assert!((a - 0.8).abs() < 0.8 * 1e-3, "{a}");
    // Diffraction (circular pupil), cutoff 0.9 cy/px: non-zero slope at 0.
    let a = extrapolate_chart_modulation(&curve(0.6, circular_pupil(0.9)), 0.0)
        .unwrap()
        .value;
    assert!((a - 0.6).abs() < 0.6 * 1e-3, "{a}");
}

#[test]
fn a_steeply_falling_curve_is_extrapolated_from_its_first_points_only() {
    // A blurry lens, Gaussian σ = 2 px: 17 % lost by 0.06 cy/px. A quadratic
    // in M through 0.01–0.06 cy/px lands 1.2 % high at 0; through the points
    // within 10 % of the first ones (the near estimate), 0.3 %. The wide
    // estimate's three-term log form is exact for a Gaussian, and its
    // smaller uncertainty makes it the one kept.
    let sigma: f64 = 2.0;
    let gauss = |f: f64| (-2.0 * std::f64::consts::PI.powi(2) * sigma * sigma * f * f).exp();
    let pts: Vec<MtfPoint> = curve(0.7, gauss)
        .into_iter()
        .filter(|p| p.freq_cy_px >= 0.01)
        .collect();
    let refs: Vec<&MtfPoint> = pts.iter().collect();
    let near = near_estimate(&refs, 0.01).unwrap();
    assert!(near.f_hi < 0.04, "fitted up to {}", near.f_hi);
    assert!((near.value / 0.7 - 1.0).abs() < 0.004, "{}", near.value);
    let a = extrapolate_chart_modulation(&pts, 0.0).unwrap();
    assert!(a.err < near.err && a.f_hi > 0.04, "{a:?} vs {near:?}");
    assert!((a.value / 0.7 - 1.0).abs() < 1e-4, "{}", a.value);
}

#[test]
fn a_linear_sweep_start_keeps_three_terms_through_a_shared_ripple() {
    // A linear sweep's points: the first at 0.045 cy/px, 0.0035 apart;
    // diffraction at f/5 on 4 µm pixels (cut-off 1.45 cy/px) × Gaussian
    // σ 0.5 px, with the slow ±0.15 % ripple that overlapping windows
    // share (period 0.08 cy/px). The fourth term is not significant: the
    // three terms read 0.8 at −0.2 %; a free cubic carries the ripple to
    // 0 at −1.3 % (both −0.02 % and 0.00 % without the ripple).
    let diff = circular_pupil(1.45);
    let k = 2.0 * std::f64::consts::PI.powi(2);
    let m = |f: f64| {
        diff(f)
            * (-k * 0.25 * f * f).exp()
            * (1.0 + 0.0015 * (2.0 * std::f64::consts::PI * f / 0.08).sin())
    };
    let pts = grid(0.8, (0.045, 0.0035, 75), 0.002, m);
    let a = extrapolate_chart_modulation(&pts, 0.0).unwrap();
    assert!((a.value / 0.8 - 1.0).abs() < 3e-3, "{a:?}");
    assert!(a.linear_start, "{a:?}");
}

#[test]
fn diffractions_terms_beyond_the_quadratic_start_as_its_cubic() {
    // ln D's series from the closed form's own: acos x − x√(1 − x²) =
    // π/2 − 2x + x³/3 + …, so D = 1 − (4/π)x + (2/(3π))x³ + … and
    // ln D = −(4/π)x − (8/π²)x² + (2/(3π) − 64/(3π³))x³ + ….
    use std::f64::consts::PI;
    let k3 = 2.0 / (3.0 * PI) - 64.0 / (3.0 * PI.powi(3));
    for x in [1e-3, 3e-3] {
        let r = diffraction_beyond_quadratic(x) / (k3 * x.powi(3));
        assert!((r - 1.0).abs() < 5e-3, "{x}: {r}");
    }
    assert_eq!(diffraction_beyond_quadratic(0.0), 0.0);
}

#[test]
fn a_linear_sweep_far_from_zero_keeps_diffractions_cubic() {
    // Keystoned linear sweeps start late: points from 0.057 cy/px, the
    // lens at f/7.6 on 4 µm pixels (cut-off 0.957 cy/px, 9 % lost by the
    // first point) × Gaussian σ 0.46 px × the pixel's sinc. Three free log
    // terms miss diffraction's own cubic (−0.476 (f/f_c)³) and read the
    // chart modulation 0.12 % low; with diffraction's terms beyond f²
    // tied to the slope found, 0.03 % low (as measured).
    use std::f64::consts::PI;
    let fc = 0.957;
    let diff = circular_pupil(fc);
    let sinc = |f: f64| (PI * f).sin() / (PI * f);
    let m = |f: f64| diff(f) * (-2.0 * PI * PI * 0.46f64.powi(2) * f * f).exp() * sinc(f);
    let pts = grid(0.8, (0.057, 0.0035, 60), 0.002, m);
    let a = extrapolate_chart_modulation(&pts, 0.0).unwrap();
    assert!((a.value / 0.8 - 1.0).abs() < 4e-4, "{a:?}");
    assert!(a.linear_start, "{a:?}");
    // The slope found is diffraction's, −(4/π)/f_c.
    assert!((a.slope_rel / (-4.0 / PI / fc) - 1.0).abs() < 0.05, "{a:?}");
}

#[test]
fn a_cut_off_near_the_points_leaves_them_uncorrected_and_finite() {
    // f/22 on 1.5 µm pixels: cut-off 0.124 cy/px, inside the points'
    // span, where ln D runs to −∞. The correction is not applied there
    // (f/f_c > 0.8) and the estimate stays finite; a slope of −1e6 per
    // cy/px (a cut-off at 1e-6 cy/px) is refused the same way.
    let pts = curve(0.8, circular_pupil(0.124));
    let a = extrapolate_chart_modulation(&pts, 0.0).unwrap();
    assert!(a.value.is_finite() && a.err.is_finite(), "{a:?}");
    assert!((a.value / 0.8 - 1.0).abs() < 0.01, "{a:?}");
    let refs: Vec<&MtfPoint> = pts.iter().collect();
    assert!(without_diffraction_tail(&refs, -1e6).is_none());
    assert!(without_diffraction_tail(&refs, 0.0).is_none());
    assert!(without_diffraction_tail(&refs, f64::NAN).is_none());
}

#[test]
fn a_sharpened_start_is_followed_over_its_rise() {
    // Unsharp mask amount 0.8, σ 1.3 px on a Gaussian lens σ = 0.8 px: the
    // curve rises 14 % by 0.1 cy/px. The wide estimate follows the rise
    // (a sum of smooth logarithms); a quadratic in M through the first
    // 0.05 cy/px misses its f⁴ term.
    let k = 2.0 * std::f64::consts::PI.powi(2);
    let usm = |f: f64| (-k * 0.64 * f * f).exp() * (1.0 + 0.8 * (1.0 - (-k * 1.69 * f * f).exp()));
    let a = extrapolate_chart_modulation(&curve(0.8, usm), 0.0).unwrap();
    assert!((a.value / 0.8 - 1.0).abs() < 1e-3, "{a:?}");
    assert!(!a.linear_start, "{a:?}");
}

#[test]
fn crossings_and_nyquist() {
    let lin = curve(1.0, |f| 1.0 - 1.2 * f);
    let f = figures(&lin);
    assert!((f.mtf50_cy_px.unwrap() - 0.5 / 1.2).abs() < 0.003);
    assert!(f.mtf10_cy_px.is_none()); // would be at 0.75 cy/px, beyond the non-aliased range
    assert!((f.mtf_nyquist.unwrap() - 0.4).abs() < 1e-9);
    assert!(Lattice::Rect(1, 1).outside(0.6, 0.0));
    assert!(!Lattice::Rect(1, 1).outside(0.6, std::f64::consts::FRAC_PI_4));
    assert!(Lattice::Rect(2, 2).outside(0.3, 0.0));
}
