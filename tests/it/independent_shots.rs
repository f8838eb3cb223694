//! Shots of the independent camera (`docs/studies/independent_shots.py`, a
//! renderer that shares no code with sweepmtf; testdata/independent) measured
//! from corners clicked up to ±4 px off, as a user gives them, against the
//! renderer's exact truth, on issue 15's bars.

use sweepmtf::measure::tone_black::BlackLevel;
use sweepmtf::measure::{MeasureOptions, Measurement, measure_decoded};
use sweepmtf::photo::decode::decode_bytes;

use crate::csv_support::{read_csv, truth_at};

const DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/testdata/independent");

/// The truth table of shot `stem` (frequency cycles/px, MTF), ascending.
fn truth(stem: &str) -> Vec<(f64, f64)> {
    read_csv(std::path::Path::new(&format!("{DIR}/{stem}.truth.csv")))
        .iter()
        .map(|r| {
            (
                r["freq_cy_px"].parse().unwrap(),
                r["truth"].parse().unwrap(),
            )
        })
        .collect()
}

/// Where the truth first falls to 0.5 (cycles/px).
fn truth_mtf50(t: &[(f64, f64)]) -> f64 {
    let i = t.iter().position(|r| r.1 < 0.5).unwrap();
    let ((f0, m0), (f1, m1)) = (t[i - 1], t[i]);
    f0 + (f1 - f0) * (m0 - 0.5) / (m0 - m1)
}

/// Shot `stem` measured from the corners in `stem.corners.txt`, default settings.
fn measure_shot(stem: &str, corners: &str) -> Measurement {
    let text = std::fs::read_to_string(format!("{DIR}/{stem}.{corners}.txt")).unwrap();
    let v: Vec<f64> = text.trim().split(',').map(|x| x.parse().unwrap()).collect();
    let roi = [[v[0], v[1]], [v[2], v[3]], [v[4], v[5]], [v[6], v[7]]];
    let bytes = std::fs::read(format!("{DIR}/{stem}.jpg")).unwrap();
    let dec = decode_bytes(&bytes, stem).unwrap();
    let opts = MeasureOptions {
        roi: Some(roi),
        // The CLI's default (the library's is off).
        refine_roi: true,
        ..MeasureOptions::default()
    };
    measure_decoded(&dec, stem, None, &opts).unwrap()
}

/// A shot measured and scored against its truth.
struct Scored {
    /// RMS |MTF − truth| over 0.01–0.45 cy/px.
    rms: f64,
    /// MTF50's relative error.
    e50: f64,
    /// MTF50's claimed standard error, relative (NaN where none is given).
    e50_claim: f64,
    /// The measurement.
    m: Measurement,
}

/// Shot `stem` from the corners in `stem.corners.txt`, default settings, scored.
fn scored(stem: &str, corners: &str) -> Scored {
    let m = measure_shot(stem, corners);
    let t = truth(stem);
    let c = &m.curves[0];
    let (mut se, mut n) = (0.0, 0);
    for p in c.points.iter().filter(|p| !p.aliased) {
        if (0.01..=0.45).contains(&p.freq_cy_px) {
            se += (p.mtf - truth_at(&t, p.freq_cy_px)).powi(2);
            n += 1;
        }
    }
    let f50 = c.figures.mtf50_cy_px.expect("an MTF50");
    let (rms, e50) = ((se / n as f64).sqrt(), f50 / truth_mtf50(&t) - 1.0);
    let e50_claim = c.figures.mtf50_err_cy_px.map_or(f64::NAN, |e| e / f50);
    eprintln!(
        "{stem} ({corners}): RMS {rms:.4} MTF50 {:+.2} %",
        100.0 * e50
    );
    Scored {
        rms,
        e50,
        e50_claim,
        m,
    }
}

impl Scored {
    /// The black level of its tone correction, where the paper was read for one.
    fn black(&self) -> Option<&BlackLevel> {
        let c = &self.m.curves[0];
        c.tone_fix.as_ref().and_then(|f| f.black.as_ref())
    }

    /// Asserts RMS ≤ `rms`, |MTF50 error| ≤ `e50` and |MTF50 error| ≤
    /// `claims` times its claimed standard error.
    fn assert_within(&self, rms: f64, e50: f64, claims: f64) {
        let e50_claim = self.e50_claim;
        assert!(
            self.rms <= rms && self.e50.abs() <= e50 && self.e50.abs() <= claims * e50_claim,
            "RMS {} MTF50 {} ± {e50_claim}",
            self.rms,
            self.e50
        );
    }
}

/// (RMS |MTF − truth| over 0.01–0.45 cy/px, MTF50's relative error) of shot
/// `stem` from the corners in `stem.corners.txt`, default settings.
fn measured(stem: &str, corners: &str) -> (f64, f64) {
    let s = scored(stem, corners);
    (s.rms, s.e50)
}

/// A keystoned linear sweep 1116 × 108 px turned −1.55°, q85 (seed 37 shot 0).
///
/// The first search along the printed bars left the high end slanted by
/// 0.48 px across the strip. Searched again, that slant read 2.0 σ of its
/// uncertainty and the significance gate (which keeps the user's ends where
/// the bars do not clearly say otherwise) kept it: the bins' iso-phase lines
/// stayed tilted against the bars, RMS 0.0078 and MTF50 −1.6 %. An end the
/// first search already turned is now corrected without that gate: RMS 0.0011,
/// MTF50 −0.2 %, as from the exact corners.
#[test]
fn clicked_corners_on_a_keystoned_linear_sweep_read_like_exact_ones() {
    let (rms_c, e50_c) = measured("keylin_s37_0", "clicked");
    let (rms_e, e50_e) = measured("keylin_s37_0", "exact");
    // Issue 15's keystone bar.
    assert!(
        rms_c <= 0.006 && e50_c.abs() <= 0.01,
        "clicked: {rms_c} {e50_c}"
    );
    assert!(
        rms_e <= 0.006 && e50_e.abs() <= 0.01,
        "exact: {rms_e} {e50_e}"
    );
    // Clicked corners cost at most 0.001 of RMS against exact ones.
    assert!(
        rms_c <= rms_e + 0.001,
        "clicked {rms_c} against exact {rms_e}"
    );
}

/// A log sweep printed up to 0.4 cy/px on a grey of its mean reflectance,
/// q75, along the pixel rows (−0.03°) under defocus, its high end clicked
/// 40 px beyond the print (seed 41 shot 9). Its bins at the high end fill one
/// in four, and the print ends on a modulation of 0.13: the grey was kept
/// (RMS 0.042). Now found (session 38: the change-point search reaches as
/// many filled bins inside, a stretch's few bins are judged quiet by their
/// own degrees of freedom, and the sweep counts as whole at a gain of 200).
#[test]
fn a_grey_beyond_a_q75_strip_along_the_rows_is_cut() {
    let (rms, e50) = measured("grey_jpeg75_s41_9", "clicked");
    // Issue 15's bar for RGB JPEG q75 with 4:2:0 chroma and noise.
    assert!(rms <= 0.012 && e50.abs() <= 0.01, "{rms} {e50}");
}

/// A linear sweep turned 9.4° on a grey of its mean (seed 40 `varied` shot 4),
/// corners clicked ±4 px off. The grey shows the long edges no step, so their
/// refinement fails ("ambiguous"), and until session 38 the corners were then
/// used as given, ends and all: the bins ran across the bars slanted by the
/// clicks, RMS 0.241 and MTF50 −22 % (claimed ± 0.5 %). The ends are now
/// turned along the bars even where the long edges are kept as given.
#[test]
fn a_strip_on_grey_whose_long_edges_are_unseen_still_has_its_ends_turned() {
    let (rms, e50) = measured("grey_varied_s40_4", "clicked");
    assert!(rms <= 0.006 && e50.abs() <= 0.01, "{rms} {e50}");
}

/// Everything at once (keystone, distortion, light 2:1 with vignetting,
/// sharpening, q75) under a picture style (seed 45 `camera` shot 5). Until
/// session 44 a sharpening of the code was fitted beside its tone at 5 σ
/// (its sharpening is in linear light: the lens's MTF, which keeps a sine a
/// sine); the tone then took three passes, the third degenerate (codes moved
/// by 382/255: until session 39 that refused the whole correction, the
/// chart modulation 1.03 and MTF50 −4.9 %; since then that pass is left out
/// and the two before it kept), the paper's line bent, and MTF50 read −3.9 %
/// (claimed ±26 %), RMS 0.060. The nuisance now needs 10 σ
/// (`sine_tone::MIN_SHARPENING_SIGNIFICANCE`), which this shot's windows do
/// not give: the tone is one pass at 175 σ, the black level from the paper
/// is significant and claimed on, and the shot reads RMS 0.026 (its ends
/// under uneven light) with MTF50 and the chart modulation within their
/// claims. The disordering pass is no longer reached here; the rule stays.
#[test]
fn everything_at_once_under_a_picture_style_takes_the_tone_and_its_black_level_out() {
    let s = scored("camera_s45_5", "exact");
    let c = &s.m.curves[0];
    let fix = c.tone_fix.as_ref().expect("a tone fit");
    assert!(fix.used && !fix.sharpening_seen, "{fix:?}");
    let black = fix.black.as_ref().expect("read");
    assert!(black.used && black.claims(), "{black:?}");
    let e50_claim = s.e50_claim;
    assert!(
        s.rms <= 0.03 && s.e50.abs() <= 0.02 && s.e50.abs() <= 2.0 * e50_claim,
        "RMS {} MTF50 {} ± {e50_claim}",
        s.rms,
        s.e50
    );
    let (got, err) = (c.chart_modulation, c.chart_modulation_err);
    eprintln!("chart modulation {got:.4} ± {err:.4} (printed 0.8)");
    assert!(
        (got - 0.8).abs() <= 2.0 * err && err <= 0.05,
        "{got} ± {err}"
    );
}

/// Everything at once under a picture style, the light rising along the
/// strip from its low-frequency end (seed 48 `camera` shot 3). Only the
/// paper beside the low end lies within the codes the tone's shape was read
/// over, and a 32nd of the strip there holds under a cycle: until session 39
/// those stretches were skipped, the black level was not found and the MTF
/// read RMS 0.0385, MTF50 −3.0 % (claimed ± 3.9 %). Stretches of a whole
/// cycle read it: RMS ≤ 0.006 and MTF50 within 1 % and its claim.
#[test]
fn a_picture_styles_black_level_is_read_beside_a_dim_low_end() {
    let s = scored("camera_s48_3", "exact");
    let black = s.black();
    assert!(black.is_some_and(|b| b.used), "{black:?}");
    s.assert_within(0.006, 0.01, 2.0);
}

/// Everything at once under a picture style, light 1.5:1 rising steeply at
/// the strip's low end (a vignette there), the black level unseen: no
/// stretch of paper lies within the codes the tone's shape was read over
/// (seed 83 `camera` shot 12). The curve reads ≈ 7.5 % low from 0.05 cy/px
/// on, since the chart modulation's extrapolation follows the bend the
/// unseen offset gives the low end. Until session 45 the offset was re-read
/// with one sign, to first order, and the points claimed ±2.4 % there
/// (MTF50 −5.2 % ± 2.3 %, points up to |z| 13.9); re-read with either sign,
/// exactly, every point's error lies within 2.5 of its claim and MTF50's
/// within 1.5.
#[test]
fn an_unseen_black_level_under_a_low_end_vignette_is_claimed_either_way() {
    let s = scored("camera_s83_12", "exact");
    let black = s.black();
    assert!(black.is_none_or(|b| !b.used), "{black:?}");
    let t = truth("camera_s83_12");
    let c = &s.m.curves[0];
    let mut worst = 0.0f64;
    for p in c.points.iter().filter(|p| !p.aliased) {
        if (0.01..=0.45).contains(&p.freq_cy_px) {
            worst = worst.max(((p.mtf - truth_at(&t, p.freq_cy_px)) / p.mtf_err).abs());
        }
    }
    eprintln!(
        "worst |z| {worst:.2}, MTF50 {:+.2} % ± {:.2} %",
        100.0 * s.e50,
        100.0 * s.e50_claim
    );
    assert!(worst <= 2.5, "worst |z| {worst}");
    assert!(
        s.e50.abs() <= 1.5 * s.e50_claim,
        "{} ± {}",
        s.e50,
        s.e50_claim
    );
}

/// Everything at once under a picture style, light 1.7:1 (seed 55 `camera`
/// shot 3). Until session 41 a line needed five stretches of paper within the
/// codes the tone's shape was read over, and only four were read: the black
/// level was not found, RMS 0.0361, MTF50 −1.6 % and the chart modulation
/// +18 % (claimed ±42 %). Session 41 took four; since session 42 a stretch's
/// paper is tested by its mean code, not by its noisiest bin, and seven are
/// read. α lies well beyond what their scatter and the bands' disagreement
/// move it by, and the claims rest on its error (the line's bend carried to
/// zero light): RMS ≤ 0.01, MTF50 within 1 % and both within their claims.
#[test]
fn the_paper_within_the_codes_read_gives_a_picture_styles_black_level() {
    let s = scored("camera_s55_3", "exact");
    let c = &s.m.curves[0];
    let black = s.black();
    assert!(
        black.is_some_and(|b| b.claims() && b.stretches >= 4),
        "{black:?}"
    );
    s.assert_within(0.01, 0.01, 2.0);
    let (got, err) = (c.chart_modulation, c.chart_modulation_err);
    assert!(
        (got - 0.8).abs() <= 2.0 * err && err < 0.04,
        "{got} ± {err}"
    );
}

/// A picture style under light 1.8:1 (seed 55 `tonelight` shot 7). Until
/// session 41 its black level was not found: RMS 0.0316, MTF50 −5.0 %.
/// Session 41 read four stretches of paper, α −9 % of the mean but within
/// 3 times what their scatter moves it by: taken out, the claims those of an
/// unseen one. Since session 42 the stretches' mean codes are tested and
/// five are read: α −9 % is significant and the claims rest on it. RMS
/// ≤ 0.012, MTF50 within 2 % and its claim, the chart modulation (+4.5 %,
/// claimed ±3.8 %) within twice its.
#[test]
fn a_picture_styles_black_level_from_five_stretches_is_claimed_on() {
    let s = scored("tonelight_s55_7", "exact");
    let c = &s.m.curves[0];
    let black = s.black();
    assert!(
        black.is_some_and(|b| b.claims() && b.stretches == 5),
        "{black:?}"
    );
    s.assert_within(0.012, 0.02, 1.0);
    let (got, err) = (c.chart_modulation, c.chart_modulation_err);
    assert!((got - 0.8).abs() <= 2.0 * err, "{got} ± {err}");
}

/// A picture style under light 1.5:1 (seed 55 `tonelight` shot 6). Until
/// session 42 the noisiest bins of its bands left three stretches of paper,
/// too few for a line: the black level was not found, RMS 0.0139, MTF50
/// −2.3 %. Tested by their mean codes, four give α = −4.3 % of the mean,
/// within 3 times what their scatter and the bands' disagreement move it by.
/// It is taken out (its error is under the claim an unseen black level
/// gives) while the claims stay those of an unseen one: RMS ≤ 0.006, MTF50
/// within 1 % and its claim, the chart modulation within its.
#[test]
fn a_black_level_too_near_zero_to_vouch_for_is_still_taken_out() {
    let s = scored("tonelight_s55_6", "exact");
    let c = &s.m.curves[0];
    let black = s.black();
    assert!(black.is_some_and(|b| b.used && !b.claims()), "{black:?}");
    s.assert_within(0.006, 0.01, 1.0);
    let (got, err) = (c.chart_modulation, c.chart_modulation_err);
    assert!((got - 0.8).abs() <= err, "{got} ± {err}");
}

/// A picture style (tanh S-curve on the code) with the camera's sharpening
/// after it, even light, q75 (`jpegcam` seed 51 #5). Until session 44 its
/// tone fit set a sharpening of the code beside the curve (at 5 σ) and read
/// the curve at 8.8 σ with it profiled out, under the 10 σ a correction is
/// taken out at: the modulations were read through it (RMS 0.0030) and the
/// chart modulation landed 3.6 % high, claimed ±0.13 % until session 40 and
/// since then widened by the curve's effect weighed by its evidence
/// (`tone_unseen::evidence`). The nuisance now needs 10 σ, which this
/// strip's shapes do not give: the curve reads 22 σ and is taken out (RMS
/// 0.0010). The chart modulation stays 3.7 % high (under even light a tone
/// curve's black level is unseen), and its claim says so.
#[test]
fn a_picture_style_under_a_sharpened_code_is_taken_out_and_the_chart_modulation_claimed() {
    let s = scored("jpegcam_s51_5", "exact");
    let c = &s.m.curves[0];
    let f = c.tone_fix.as_ref().expect("a tone fit");
    assert!(f.used && f.significance > 10.0, "{f:?}");
    let off = (c.chart_modulation - 0.8).abs();
    assert!(
        off <= 2.0 * c.chart_modulation_err,
        "chart modulation {} ± {} against 0.8",
        c.chart_modulation,
        c.chart_modulation_err
    );
    assert!(
        c.chart_modulation_source.contains("black level, unseen"),
        "{}",
        c.chart_modulation_source
    );
    // The MTF itself: a ratio, under even light the curve divides out.
    assert!(
        s.rms <= 0.006 && s.e50.abs() <= 0.01,
        "RMS {} MTF50 {}",
        s.rms,
        s.e50
    );
}

/// f/16 on q75 without sensor noise (`jpeg75` seed 57 #9, turned 2.9°):
/// from ≈ 0.38 cy/px the sine is ≈ 2 codes, and q75's luma steps (20–31
/// there) round its DCT coefficients away in every block; the curve reads
/// 0 where the lens passes up to 0.02. Until session 43 each point there
/// claimed ±0.0004–0.002 (|z| up to 23); the quantiser's dead zone now
/// joins each point's uncertainty (`jpeg_deadzone`): every point's error
/// within 2.5 of its claims, and the claims grow only where the sine nears
/// it; a warning says from where to the curve's end the sine is rounded away,
/// and each point lost there is flagged `jpeg_limited` (none where the MTF
/// is above 0.3).
#[test]
fn a_sine_the_jpeg_quantiser_rounds_away_is_claimed_as_unknown() {
    let s = scored("jpeg75f16_s57_9", "exact");
    let t = truth("jpeg75f16_s57_9");
    let c = &s.m.curves[0];
    let (mut worst, mut lost) = (0.0f64, 0);
    for p in c.points.iter().filter(|p| !p.aliased) {
        if !(0.01..=0.45).contains(&p.freq_cy_px) {
            continue;
        }
        let truth = truth_at(&t, p.freq_cy_px);
        let z = (p.mtf - truth) / p.mtf_err;
        worst = worst.max(z.abs());
        if p.freq_cy_px > 0.39 && p.mtf < 0.5 * truth {
            lost += 1;
            assert!(p.mtf_err > 0.005, "{} ± {}", p.mtf, p.mtf_err);
            assert!(p.jpeg_limited, "{}: lost, not flagged", p.freq_cy_px);
        }
        // Well clear of the dead zone (MTF > 0.3, ≥ 30 codes), claims as
        // the noise gives them, and the point is the lens's.
        if truth > 0.3 {
            assert!(p.mtf_err < 0.004, "{}: ± {}", p.freq_cy_px, p.mtf_err);
            assert!(!p.jpeg_limited, "{}: flagged", p.freq_cy_px);
        }
    }
    assert!(lost >= 5, "{lost} points read under half the lens's MTF");
    assert!(worst <= 2.5, "worst |z| {worst}");
    // Said where: from where the sine is rounded away to the curve's end.
    let from = c
        .rounded_away_from_cy_px
        .expect("the rounded-away sine said");
    assert!((0.36..=0.43).contains(&from), "{from}");
    // Every point from there on is flagged as the file's.
    assert!(
        c.points
            .iter()
            .filter(|p| !p.aliased && p.freq_cy_px >= from)
            .all(|p| p.jpeg_limited)
    );
    assert!(
        s.m.warnings.iter().any(|w| w.contains(&format!(
            "from {from:.3} cy/px to the curve's end the JPEG's quantiser rounds"
        ))),
        "{:?}",
        s.m.warnings
    );
    s.assert_within(0.012, 0.01, 2.5);
}
