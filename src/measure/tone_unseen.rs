//! What a camera tone curve's black level, where it stays unseen, leaves
//! uncertain: stated in the chart modulation's and each point's uncertainty
//! instead of a confident number.
//!
//! [`super::sine_tone`] makes a strip's values affine in light,
//! `v' = α + β·ℓ`; where [`super::tone_black`] cannot find α from the paper,
//! every modulation read is `m/(1 + ε)` with `ε = α/(μ − α)` (μ the strip's
//! local mean value). The chart modulation is then off by `ε` at the strip's
//! low end, and the MTF (a ratio) by `ε_ref·(1 − μ_ref/μ(s))`: nothing under
//! even light, up to ±7 % at MTF50 where the light changes 2:1.
//!
//! The sine's shape does not show α, but the curve's strength does bound it:
//! a curve that bends a sine's shape more leaves a larger offset when its
//! shape alone is taken out (a curve through black, `g(0) = 0`, with
//! curvature `g''` leaves `α ≈ −g''·μ²/2`, and its effect on a sine's
//! modulation grows with `g''·μ` too). On the independent camera's picture
//! styles (tanh S-curves of strength 1–2.5 on the sRGB code, light 1.5–2.1:1,
//! 20 shots) |ε| was 2.4–4.3 × the correction's effect on an MTF
//! of 0.5 ([`super::sine_tone::ToneFix::effect`]); the scale stated here is
//! [`PER_EFFECT`] × that effect, taken as a one-sigma uncertainty of ε.

use super::PhaseLaw;
use super::curve::MtfPoint;
use super::profile::Profile;
use super::sine_tone::{MIN_SIGNIFICANCE, MIN_USE_SIGNIFICANCE, ToneFix};

/// The unseen black level's relative scale (of the strip's mean value less
/// black) per unit of the correction's effect on an MTF of 0.5.
pub const PER_EFFECT: f64 = 4.0;

/// The relative scale an unseen black level of a used correction is claimed
/// at, `PER_EFFECT·|effect|` (dimensionless).
pub fn full_scale(fix: &ToneFix) -> f64 {
    PER_EFFECT * fix.effect.abs()
}

/// The relative scale of an unseen black level, [`full_scale`]
/// (dimensionless): where a correction is used and its black level was not
/// found, or, times its [`evidence`], where a curve was seen
/// ([`seen_weakly`]) but not taken out; None otherwise.
pub fn scale(fix: &ToneFix) -> Option<f64> {
    let weight = if fix.used && !fix.black.as_ref().is_some_and(|b| b.claims()) {
        1.0
    } else if seen_weakly(fix) {
        evidence(fix.significance)
    } else {
        0.0
    };
    Some(weight * full_scale(fix)).filter(|e| e.is_finite() && *e > 0.0)
}

/// How far a curve seen at `significance` σ (Wald) is taken as real, 0–1:
/// 0 at [`MIN_SIGNIFICANCE`], rising linearly to 1 at [`MIN_USE_SIGNIFICANCE`].
/// Shots with no curve beyond sRGB read up to 6.2 σ, and there the "effect"
/// is the fit's noise (up to 0.82 %, where the chart modulation was within
/// 0.36 %; issue 15's kinds, seed 51, 60 shots), so a curve just past 5 σ
/// widens the claim only a little.
pub fn evidence(significance: f64) -> f64 {
    ((significance - MIN_SIGNIFICANCE) / (MIN_USE_SIGNIFICANCE - MIN_SIGNIFICANCE)).clamp(0.0, 1.0)
}

/// Whether a camera's tone curve was seen in the periods' shapes (beyond
/// [`MIN_SIGNIFICANCE`] σ) but too weakly, or with too small an effect on the
/// MTF, to be taken out: the modulations are then read through it, and the
/// chart modulation (a ratio of the curve's local slope to its mean, first
/// order in the curve) moves by about what an unseen black level moves it
/// by. (Independent camera, `jpegcam` seed 51 #5: seen at 8.8 σ, effect
/// +0.82 %, chart modulation +3.65 % off claiming ±0.13 %; `camera` seed 47
/// #1: 7.8 σ, +6.1 % off claiming ±0.5 %.)
pub fn seen_weakly(fix: &ToneFix) -> bool {
    !fix.used && !fix.needed() && fix.significance > MIN_SIGNIFICANCE
}

/// Adds an unseen black level of relative scale `eps` (of the strip's mean
/// value) to each point's uncertainty and returns the chart modulation's
/// share (a one-sigma share either way): the modulations are re-read as
/// they would be were an offset `±eps·μ̄` taken out, each exactly scaled by
/// `μ(s)/(μ(s) ∓ eps·μ̄)` (μ the strip's local mean value over a period, at
/// least [`MEAN_SPAN`] of the strip, μ̄ its mean; the divisor kept above
/// [`MIN_LEFT`] of μ), the chart modulation taken again from them and the
/// `low` end's points, scaled alike, by `chart_modulation` (the
/// extrapolation follows how the offset changes along the low end), and
/// each MTF's change, the larger of the two signs', is its share. Both
/// signs, exactly: where the light rises steeply at the strip's low end the
/// extrapolation turns with the offset far more one way than the other
/// (independent camera, `camera` seed 83 #12, a vignette at the low end,
/// light 1.5:1, eps 0.30: at 0.15 cy/px the MTF moves −3.4 % for +eps and
/// +16 % for −eps; it read 7.5 % low, claiming ±2.4 % from +eps to first
/// order, MTF50 |z| 2.3, points up to 13.9). Nothing is widened where the
/// chart modulation cannot be taken again for either sign.
pub(super) fn widen(
    points: &mut [MtfPoint],
    low: &[MtfPoint],
    prof: &Profile,
    law: &PhaseLaw,
    eps: f64,
    m_chart: f64,
    chart_modulation: impl Fn(&[MtfPoint], &[MtfPoint]) -> Option<f64>,
) -> f64 {
    let n = prof.y.len();
    if n == 0 || !(m_chart > 0.0) {
        return 0.0;
    }
    let (s0, s1) = (prof.s[0], prof.s[n - 1]);
    let mean = prof.y.iter().sum::<f64>() / n as f64;
    let mean_at = |s: f64| -> Option<f64> {
        let f = law.freq(s);
        let w = if f > 0.0 { 1.0 / f } else { 0.0 }.max(MEAN_SPAN * (s1 - s0));
        prof.mean_within(s - 0.5 * w, s + 0.5 * w, |y| y)
            .filter(|m| m.is_finite() && *m > 0.0)
    };
    if !(mean > 0.0) {
        return 0.0;
    }
    let times = |p: &MtfPoint, k: f64| MtfPoint {
        modulation: p.modulation * k,
        ..*p
    };
    let mut widest = vec![0.0f64; points.len()];
    let mut share = 0.0f64;
    for sign in [1.0, -1.0] {
        let scale_at = |p: &MtfPoint| {
            let r = eps * mean / mean_at(p.s).unwrap_or(mean);
            1.0 / (1.0 - sign * r).max(MIN_LEFT)
        };
        // The points' scales are the ones their errors are widened by below (read once).
        let scale: Vec<f64> = points.iter().map(scale_at).collect();
        let alt: Vec<MtfPoint> = points
            .iter()
            .zip(&scale)
            .map(|(p, &k)| times(p, k))
            .collect();
        let alt_low: Vec<MtfPoint> = low.iter().map(|p| times(p, scale_at(p))).collect();
        let Some(m_alt) = chart_modulation(&alt, &alt_low).filter(|m| m.is_finite() && *m > 0.0)
        else {
            continue;
        };
        for ((w, p), k) in widest.iter_mut().zip(points.iter()).zip(&scale) {
            let d = p.mtf * (k * m_chart / m_alt - 1.0);
            if d.is_finite() {
                *w = w.max(d.abs());
            }
        }
        share = share.max((m_alt - m_chart).abs());
    }
    for (p, w) in points.iter_mut().zip(widest) {
        p.mtf_err = p.mtf_err.hypot(w);
    }
    share
}

/// The least a local mean value is left at, as a fraction of itself, by an
/// offset taken out in [`widen`] (an offset as large as the mean would leave
/// no light: the scale is capped at 1/MIN_LEFT).
pub const MIN_LEFT: f64 = 0.25;

/// The shortest stretch a local mean is taken over, as a fraction of the strip.
pub const MEAN_SPAN: f64 = 0.02;

/// The chart modulation source's clause for the share `err` an unseen black
/// level of relative scale `eps` leaves it.
pub fn source_note(err: f64, eps: f64, fix: &ToneFix) -> String {
    if seen_weakly(fix) {
        let why = if fix.significance > MIN_USE_SIGNIFICANCE {
            format!(
                "its effect on an MTF of 0.5 ({:+.2} %) too small to take out",
                -100.0 * fix.effect
            )
        } else {
            format!("under the {MIN_USE_SIGNIFICANCE:.0} σ it is taken out at")
        };
        return format!(
            "; ± {err:.4} from a camera tone curve seen at {:.1} σ, {why} (± {:.1} % of the \
             strip's mean: {PER_EFFECT:.0} × its effect on an MTF of 0.5, × {:.2} for its evidence)",
            fix.significance,
            100.0 * eps,
            evidence(fix.significance)
        );
    }
    format!(
        "; ± {err:.4} from the tone curve's black level, unseen (± {:.1} % of the strip's mean: \
         {PER_EFFECT:.0} × the curve's effect on an MTF of 0.5)",
        100.0 * eps
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn profile(s: Vec<f64>, y: Vec<f64>) -> Profile {
        let n = s.len();
        Profile {
            count: vec![60.0; n],
            var_s: vec![0.0; n],
            length: s.last().copied().unwrap_or(0.0),
            s,
            y,
            bin: 1.0,
            samples: 60 * n,
            clipped_high: 0,
            clipped_low: 0,
            clipped: Vec::new(),
            parity: Vec::new(),
        }
    }

    fn linear_law(f0: f64, slope: f64) -> PhaseLaw {
        PhaseLaw {
            kind: super::super::law::LawKind::Linear,
            c0: 0.0,
            c1: f0,
            c2: 0.5 * slope,
            persp: 0.0,
        }
    }

    fn point(s: f64, mtf: f64) -> MtfPoint {
        MtfPoint {
            s,
            freq_cy_px: 0.01 + s / 1000.0,
            freq_chart: 0.01 + s / 1000.0,
            modulation: 0.8 * mtf,
            mtf,
            mtf_err: 0.001,
            aliased: false,
            jpeg_limited: false,
        }
    }

    /// The chart modulation "extrapolated" by a line through the two lowest points.
    fn two_point(pts: &[MtfPoint]) -> Option<f64> {
        let (a, b) = (pts.first()?, pts.get(1)?);
        Some(a.modulation - a.s * (b.modulation - a.modulation) / (b.s - a.s))
    }

    /// The stated widening matches the bias an offset α really leaves, worked
    /// out by hand: the modulation read is `m·(μ − α)/μ`.
    #[test]
    fn the_widening_is_the_bias_an_offset_leaves_under_changing_light() {
        // Light rising 1 → 2 along a 1000 px strip; the values' local mean is the light.
        let s: Vec<f64> = (0..1000).map(|i| i as f64 + 0.5).collect();
        let light = |s: f64| 1.0 + s / 1000.0;
        let prof = profile(s.clone(), s.iter().map(|&s| light(s)).collect());
        let law = linear_law(0.01, 0.3 / 1000.0);
        let mean = 1.5;
        let eps = 0.04;
        let alpha = eps * mean;
        let mtf = |s: f64| 1.0 - (s / 1200.0).powi(2);
        let mut pts: Vec<MtfPoint> = (1..20)
            .map(|i| {
                let s = 50.0 * i as f64;
                let mut p = point(s, 0.0);
                p.modulation = 0.8 * mtf(s) * (light(s) - alpha) / light(s);
                p
            })
            .collect();
        let m_chart = two_point(&pts).unwrap();
        pts.iter_mut().for_each(|p| p.mtf = p.modulation / m_chart);
        // Without α: the same extrapolation of the true modulations.
        let truth: Vec<MtfPoint> = pts
            .iter()
            .map(|p| MtfPoint {
                modulation: 0.8 * mtf(p.s),
                ..*p
            })
            .collect();
        let m_true = two_point(&truth).unwrap();
        let before: Vec<f64> = pts.iter().map(|p| p.mtf_err).collect();
        let cm_share = widen(&mut pts, &[], &prof, &law, eps, m_chart, |p, _| {
            two_point(p)
        });
        let cm_bias = (m_true - m_chart).abs();
        assert!(
            (cm_share - cm_bias).abs() < 0.1 * cm_bias,
            "{cm_share} against {cm_bias}"
        );
        for ((p, t), e0) in pts.iter().zip(&truth).zip(before) {
            let bias = (p.mtf - t.modulation / m_true).abs();
            let share = (p.mtf_err.powi(2) - e0 * e0).max(0.0).sqrt();
            assert!(
                (share - bias).abs() < 0.1 * bias + 1e-4,
                "at s {}: widened by {share:.5} against the bias {bias:.5}",
                p.s
            );
        }
        // The light doubles, so the high end's bias is real, not rounding.
        assert!((pts[18].mtf - truth[18].modulation / m_true).abs() > 0.005);
    }

    /// Under light rising steeply at the low end, an offset of either sign
    /// is claimed: the widening is the larger of the biases an offset
    /// `+eps·μ̄` and one `−eps·μ̄` really leave, worked out by hand (the
    /// modulation read `m·(μ − α)/μ`), at a scale (0.3) where the two differ
    /// by far more than the claims' tolerance.
    #[test]
    fn the_widening_covers_an_offset_of_either_sign() {
        let s: Vec<f64> = (0..1000).map(|i| i as f64 + 0.5).collect();
        // Light from 0.5 to 1.2, most of the rise in the first fifth.
        let light = |s: f64| 1.2 - 0.7 * (-s / 200.0).exp();
        let prof = profile(s.clone(), s.iter().map(|&s| light(s)).collect());
        let law = linear_law(0.01, 0.3 / 1000.0);
        let mean = prof.y.iter().sum::<f64>() / prof.y.len() as f64;
        let eps = 0.3;
        let mtf = |s: f64| 1.0 - (s / 1200.0).powi(2);
        let read = |alpha: f64| -> Vec<MtfPoint> {
            (1..20)
                .map(|i| {
                    let s = 50.0 * i as f64;
                    let mut p = point(s, 0.0);
                    p.modulation = 0.8 * mtf(s) * (light(s) - alpha) / light(s);
                    p
                })
                .collect()
        };
        let truth: Vec<MtfPoint> = read(0.0);
        let m_true = two_point(&truth).unwrap();
        // The file as read carries no offset; the truth is an offset of
        // ±eps·μ̄ away: the bias of each is the MTF read minus the MTF it hides.
        let mut pts = truth.clone();
        let m_chart = two_point(&pts).unwrap();
        pts.iter_mut().for_each(|p| p.mtf = p.modulation / m_chart);
        let hidden: Vec<Vec<f64>> = [1.0, -1.0]
            .iter()
            .map(|sign| {
                // Modulations with the offset sign·eps·μ̄ taken out of the values read.
                let alpha = sign * eps * mean;
                let alt: Vec<MtfPoint> = pts
                    .iter()
                    .map(|p| MtfPoint {
                        modulation: p.modulation * light(p.s) / (light(p.s) - alpha),
                        ..*p
                    })
                    .collect();
                let m_alt = two_point(&alt).unwrap();
                alt.iter().map(|p| p.modulation / m_alt).collect()
            })
            .collect();
        let share = widen(&mut pts, &[], &prof, &law, eps, m_chart, |p, _| {
            two_point(p)
        });
        assert!(share > 0.0 && (m_true - m_chart).abs() < 1e-12);
        let mut apart = 0.0f64;
        for (k, p) in pts.iter().enumerate() {
            let (up, down) = ((hidden[0][k] - p.mtf).abs(), (hidden[1][k] - p.mtf).abs());
            apart = apart.max((up - down).abs() / up.max(down).max(1e-12));
            let want = up.max(down);
            let got = (p.mtf_err.powi(2) - 1e-6).max(0.0).sqrt();
            assert!(
                (got - want).abs() < 0.02 * want + 1e-6,
                "at s {}: widened by {got:.5}, the larger bias {want:.5} (+ {up:.5}, − {down:.5})",
                p.s
            );
        }
        assert!(apart > 0.2, "the signs' biases differ by {apart}");
    }

    /// A fix of `significance` σ and `effect` (no passes: only its figures matter here).
    fn fix(significance: f64, effect: f64, used: bool) -> ToneFix {
        ToneFix {
            base: crate::photo::linearise::Tone::Srgb,
            passes: Vec::new(),
            significance,
            effect,
            max_shift_255: 0.0,
            code_range: (0.2, 0.8),
            windows: 12,
            light_ratio: 1.0,
            used,
            sharpening_seen: false,
            black: None,
        }
    }

    /// A curve too weak to take out still widens the claim, in proportion to
    /// its evidence: nothing at 5 σ (where shots without one read), all of
    /// an unseen black level's scale at 10 σ; a used one without its black
    /// level, the whole scale; one under 5 σ, nothing.
    #[test]
    fn a_curve_seen_too_weakly_to_take_out_widens_by_its_evidence() {
        let eff = -0.01;
        assert_eq!(scale(&fix(4.9, eff, false)), None);
        assert_eq!(scale(&fix(5.0, eff, false)), None);
        let at = |sig: f64| scale(&fix(sig, eff, false)).unwrap();
        assert!((at(7.5) - 0.5 * PER_EFFECT * 0.01).abs() < 1e-12);
        assert!((at(9.99) - 0.998 * PER_EFFECT * 0.01).abs() < 1e-12);
        // Significant but of too small an effect to take out: the whole scale.
        let tiny = fix(40.0, 0.0005, false);
        assert!(!tiny.needed());
        assert!((scale(&tiny).unwrap() - PER_EFFECT * 0.0005).abs() < 1e-15);
        // Used, its black level unseen: the whole scale, whatever the evidence.
        assert!((scale(&fix(12.0, eff, true)).unwrap() - PER_EFFECT * 0.01).abs() < 1e-12);
        // Needed but not used (it would put the values out of order): not this scale.
        assert_eq!(scale(&fix(12.0, eff, false)), None);
        assert_eq!(scale(&fix(f64::NAN, eff, false)), None);
        let note = source_note(0.01, 0.02, &fix(8.8, eff, false));
        assert!(note.contains("8.8 σ, under the 10 σ"), "{note}");
        let note = source_note(0.002, 0.002, &tiny);
        assert!(
            note.contains("40.0 σ, its effect") && note.contains("too small"),
            "{note}"
        );
    }

    #[test]
    fn even_light_widens_only_the_chart_modulation_and_degenerate_input_is_safe() {
        let s: Vec<f64> = (0..200).map(|i| i as f64).collect();
        let prof = profile(s, vec![0.5; 200]);
        let law = linear_law(0.02, 0.001);
        let mut pts = vec![point(10.0, 1.0), point(150.0, 0.3)];
        let m_chart = two_point(&pts).unwrap();
        let share = widen(&mut pts, &[], &prof, &law, 0.2, m_chart, |p, _| {
            two_point(p)
        });
        // Even light: every modulation scaled by 1/(1 − 0.2) or 1/(1 + 0.2),
        // the chart modulation with them; the larger change is its share.
        assert!((share - m_chart * 0.25).abs() < 1e-9, "{share}");
        assert!(pts.iter().all(|p| (p.mtf_err - 0.001).abs() < 1e-9));
        // An offset as large as the mean or larger (no light left) is capped
        // at a scale of 1/MIN_LEFT, not divided by zero or turned negative.
        for eps in [1.0, 3.0, 1e6] {
            let mut big = pts.clone();
            let share = widen(&mut big, &[], &prof, &law, eps, m_chart, |p, _| {
                two_point(p)
            });
            assert!(
                (share - m_chart * (1.0 / MIN_LEFT - 1.0)).abs() < 1e-9,
                "{eps}: {share}"
            );
            assert!(big.iter().all(|p| p.mtf_err.is_finite()), "{big:?}");
        }
        // No profile, no chart modulation, a dark profile: left as they are.
        let dark = profile((0..10).map(f64::from).collect(), vec![0.0; 10]);
        assert_eq!(
            widen(&mut pts, &[], &dark, &law, 0.2, 0.8, |p, _| two_point(p)),
            0.0
        );
        assert_eq!(
            widen(
                &mut pts,
                &[],
                &profile(vec![], vec![]),
                &law,
                0.2,
                0.8,
                |p, _| two_point(p)
            ),
            0.0
        );
        assert_eq!(
            widen(&mut pts, &[], &prof, &law, 0.2, 0.8, |_, _| None),
            0.0
        );
        assert_eq!(
            widen(&mut pts, &[], &prof, &law, 0.2, f64::NAN, |p, _| two_point(
                p
            )),
            0.0
        );
        assert!(pts.iter().all(|p| (p.mtf_err - 0.001).abs() < 1e-9));
    }
}
