//! Issue 15's bars on shots that carry what real lenses, lights and cameras do
//! (reference renderer `sweepmtf::measure::synth`, exact truth): strip corners
//! only, no target, default CLI settings (refinement on); RMS |MTF − truth| over
//! 0.01–0.45 cy/px, MTF50 within 1 % and the chart modulation within 0.5 % of
//! the printed 0.8. The geometry variants here are not the ones the estimator
//! was tuned on (the report, `examples/accuracy.rs`, uses variant 0).

use std::path::Path;

use assert_cmd::Command;
use sweepmtf::measure::synth::{SynthShot, nuisance_cases};
use sweepmtf::measure::{MeasureOptions, Measurement, measure_bytes, measure_decoded};
use sweepmtf::photo::decode::decode_bytes;

/// The reference renderer's nuisance shot `name` in geometry `variant`.
fn case(name: &str, variant: u64) -> SynthShot {
    nuisance_cases(variant)
        .into_iter()
        .find(|s| s.name == name)
        .unwrap_or_else(|| panic!("no nuisance case {name}"))
}

/// (RMS over 0.01–0.45 cy/px, MTF50 relative error, chart modulation found, its claimed σ).
/// Measured from the file's bytes as `sweepmtf measure` reads them (a JPEG's
/// luminance from its Y′ plane alone).
fn run(shot: &SynthShot, seed: u64) -> (f64, f64, f64, f64) {
    run_with(shot, seed, MeasureOptions::default()).0
}

/// The shot measured from its file's bytes, with its strip corners given.
fn measured(shot: &SynthShot, seed: u64, base: MeasureOptions) -> Measurement {
    let opts = MeasureOptions {
        roi: Some(shot.quad),
        refine_roi: true,
        ..base
    };
    measure_bytes(&shot.encode(seed), &shot.name, None, &opts)
        .unwrap_or_else(|e| panic!("{}: {e}", shot.name))
}

/// The fraction of unaliased points over 0.01–0.45 cy/px within `k` of
/// their claimed σ of the truth.
fn covered(shot: &SynthShot, m: &Measurement, k: f64) -> f64 {
    let pts: Vec<_> = m.curves[0]
        .points
        .iter()
        .filter(|p| !p.aliased && (0.01..=0.45).contains(&p.freq_cy_px))
        .collect();
    let within = pts
        .iter()
        .filter(|p| (p.mtf - shot.truth(p.freq_cy_px)).abs() <= k * p.mtf_err)
        .count();
    within as f64 / pts.len().max(1) as f64
}

/// [`run`] with other options; also gives the measurement's notes.
fn run_with(
    shot: &SynthShot,
    seed: u64,
    base: MeasureOptions,
) -> ((f64, f64, f64, f64), Vec<String>) {
    let m = measured(shot, seed, base);
    (scores(shot, &m), m.notes.clone())
}

/// [`run`]'s figures of a measurement already made.
fn scores(shot: &SynthShot, m: &Measurement) -> (f64, f64, f64, f64) {
    let c = &m.curves[0];
    let (mut se, mut n) = (0.0, 0);
    for p in c.points.iter().filter(|p| !p.aliased) {
        if (0.01..=0.45).contains(&p.freq_cy_px) {
            se += (p.mtf - shot.truth(p.freq_cy_px)).powi(2);
            n += 1;
        }
    }
    assert!(n > 60, "{}: {n} points", shot.name);
    // True MTF50: the first fall through 0.5 (past a sharpening peak), by bisection.
    let mut lo = 0.0;
    while shot.truth(lo + 0.001) >= 0.5 {
        lo += 0.001;
    }
    let mut hi = lo + 0.001;
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if shot.truth(mid) >= 0.5 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let f50 = c.figures.mtf50_cy_px.expect("MTF50 measured");
    (
        (se / n as f64).sqrt(),
        f50 / lo - 1.0,
        c.chart_modulation,
        c.chart_modulation_err,
    )
}

fn check(name: &str, bar: f64) {
    for variant in [7u64, 12] {
        let shot = case(name, variant);
        let (rms, e50, cm, cm_err) = run(&shot, 100 + variant);
        eprintln!("{name} v{variant}: RMS {rms:.4} MTF50 {e50:+.4} chart {cm:.4} ± {cm_err:.4}");
        assert_bars(&format!("{name} v{variant}"), rms, e50, cm, bar);
        // The claimed uncertainty is honest: positive, and covers the error within 4σ.
        assert!(
            cm_err > 0.0 && (cm - 0.8).abs() <= 4.0 * cm_err + 1e-3,
            "{cm} ± {cm_err}"
        );
    }
}

/// Issue 15's bars: RMS within `bar`, MTF50 within 1 % and the chart
/// modulation within 0.5 % of the printed 0.8.
fn assert_bars(what: &str, rms: f64, e50: f64, cm: f64, bar: f64) {
    assert!(rms <= bar, "{what}: RMS {rms:.4} > {bar}");
    assert!(e50.abs() <= 0.01, "{what}: MTF50 off by {e50:+.4}");
    assert!(
        (cm / 0.8 - 1.0).abs() <= 0.005,
        "{what}: chart modulation {cm:.4} (printed 0.8)"
    );
}

#[test]
fn illumination_3_to_1_with_50_percent_vignetting_within_0_008() {
    check("light3_vignette50", 0.008);
}

/// A camera's picture style (an S-curve of strength 2 on top of the sRGB the
/// file declares) bends every period; read through sRGB alone the curve is
/// off, and the strip's own shape gives the curve back. The chart modulation
/// is not held: an offset of the light leaves a sine a sine, so it stays as
/// the file's tone reads it (and the note says so).
#[test]
fn a_camera_picture_style_is_found_from_the_strip_and_taken_out() {
    for variant in [7u64, 12] {
        let shot = case("picture_style2", variant);
        let file_only = MeasureOptions {
            tone_from_strip: false,
            ..MeasureOptions::default()
        };
        let ((rms0, e0, _, _), _) = run_with(&shot, 100 + variant, file_only);
        let ((rms, e50, cm, cm_err), notes) =
            run_with(&shot, 100 + variant, MeasureOptions::default());
        eprintln!(
            "picture style v{variant}: file's tone RMS {rms0:.4} MTF50 {e0:+.4}; \
             from the strip RMS {rms:.4} MTF50 {e50:+.4} chart {cm:.4} ± {cm_err:.4}"
        );
        // Under even light the curve's black level stays unseen: the chart
        // modulation read through the file's tone is off the printed 0.8,
        // and its uncertainty says so instead of claiming the fit's alone.
        assert!(
            (cm - 0.8).abs() > 0.02 && (cm - 0.8).abs() <= 2.0 * cm_err,
            "v{variant}: chart modulation {cm:.4} ± {cm_err:.4}"
        );
        assert!(rms0 > 0.012 && e0 > 0.025, "{rms0} {e0}");
        assert!(rms <= 0.006, "v{variant}: RMS {rms:.4}");
        assert!(e50.abs() <= 0.01, "v{variant}: MTF50 off by {e50:+.4}");
        assert!(
            notes
                .iter()
                .any(|n| n.contains("not sine-shaped") && n.contains("taken out")),
            "{notes:?}"
        );
    }
}

/// The same picture style under light falling 2:1 along the strip (and a
/// vignette), on white paper: the curve's black level, which a sine's shape
/// cannot show, bends the MTF where the light changes; the paper beside the
/// strip sees the same light through the same curve and gives it.
#[test]
fn a_picture_style_under_uneven_light_takes_its_black_level_from_the_paper() {
    for variant in [7u64, 12] {
        let shot = case("picture_style2_light2", variant);
        let ((rms, e50, cm, cm_err), notes) =
            run_with(&shot, 200 + variant, MeasureOptions::default());
        // The same shot with the surround at the strip's mean (no paper to read).
        let grey = SynthShot {
            nuisance: sweepmtf::measure::synth::Nuisances {
                paper_surround: false,
                ..shot.nuisance
            },
            ..shot.clone()
        };
        let m0 = measured(&grey, 200 + variant, MeasureOptions::default());
        let (rms0, e0, cm0, _) = scores(&grey, &m0);
        let notes0 = &m0.notes;
        eprintln!(
            "picture style + light v{variant}: no paper RMS {rms0:.4} MTF50 {e0:+.4} chart {cm0:.4}; \
             paper RMS {rms:.4} MTF50 {e50:+.4} chart {cm:.4} ± {cm_err:.4}"
        );
        assert!(rms0 > 0.008 && e0.abs() > 0.015, "{rms0} {e0}");
        // Where it is not found the MTF's uncertainty carries the unseen
        // black level: the claimed σ covers the bend.
        let cover = covered(&grey, &m0, 2.0);
        eprintln!("  no paper: within 2 σ of the truth {cover:.2}");
        assert!(cover >= 0.9, "v{variant}: {cover:.2} within 2 σ");
        // And MTF50's claimed σ (from the widened points) covers its error.
        let f50 = m0.curves[0].figures.mtf50_cy_px.unwrap();
        let s50 = m0.curves[0].figures.mtf50_err_cy_px.unwrap();
        let miss = f50 - f50 / (1.0 + e0);
        eprintln!("  no paper: MTF50 {f50:.4} ± {s50:.4}, off by {miss:+.4}");
        assert!(
            miss.abs() <= 2.0 * s50,
            "v{variant}: MTF50 off by {miss:+.4}, ± {s50:.4}"
        );
        // The region picture's paper bands: two, one beside each long edge,
        // outside the binned region.
        let c = &m0.curves[0];
        assert_eq!(c.paper_bands_px.len(), 2);
        let q = c.region_px;
        // Signed distance (× length) from the strip's centre line.
        let mid = |u: [f64; 2], v: [f64; 2]| [0.5 * (u[0] + v[0]), 0.5 * (u[1] + v[1])];
        let side = |p: [f64; 2]| {
            let (a, b) = (mid(q[0], q[3]), mid(q[1], q[2]));
            (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
        };
        let centre = |v: &[[f64; 2]]| {
            let n = v.len() as f64;
            [
                v.iter().map(|p| p[0]).sum::<f64>() / n,
                v.iter().map(|p| p[1]).sum::<f64>() / n,
            ]
        };
        let (s0, s1) = (
            side(centre(&c.paper_bands_px[0])),
            side(centre(&c.paper_bands_px[1])),
        );
        let (e0, e1) = (side(q[0]), side(q[3]));
        assert!(
            s0 * s1 < 0.0 && s0.abs().min(s1.abs()) > e0.abs().max(e1.abs()),
            "bands at {s0:.0}, {s1:.0}; the region's far edge at {e0:.0}, {e1:.0}"
        );
        assert!(
            !notes0
                .iter()
                .any(|n| n.contains("black level") && n.contains("; taken out")),
            "{notes0:?}"
        );
        // Unlike under even light, the chart modulation is found too.
        assert_bars(&format!("v{variant}"), rms, e50, cm, 0.006);
        // Its uncertainty carries the black level's, and covers the error
        // (since session 41 α's error is the line's departure carried to
        // zero light, not that over √stretches: 1.2 % here, from 0.4 %).
        assert!(
            (cm - 0.8).abs() <= 3.0 * cm_err && cm_err < 0.015,
            "v{variant}: chart modulation {cm:.4} ± {cm_err:.4}"
        );
        assert!(
            notes
                .iter()
                .any(|n| n.contains("black level") && n.contains("; taken out")),
            "{notes:?}"
        );
    }
}

#[test]
fn keystoned_linear_sweep_within_0_006() {
    check("keystone1.5_linear", 0.006);
}

#[test]
fn unsharp_mask_peaking_near_1_15_within_0_01_and_never_clipped() {
    check("usm_peak1.15", 0.01);
    // Sharpening is measured, not clipped or normalised away: the curve peaks above 1
    // where the truth does.
    let shot = case("usm_peak1.15", 7);
    let peak_truth = (1..500)
        .map(|i| shot.truth(i as f64 * 0.001))
        .fold(0.0, f64::max);
    assert!(peak_truth > 1.12, "{peak_truth}");
    let dec = decode_bytes(&shot.encode(3), "usm").unwrap();
    let opts = MeasureOptions {
        roi: Some(shot.quad),
        refine_roi: true,
        ..MeasureOptions::default()
    };
    let m = measure_decoded(&dec, "usm", None, &opts).unwrap();
    let peak = m.curves[0]
        .points
        .iter()
        .filter(|p| !p.aliased)
        .map(|p| p.mtf)
        .fold(0.0, f64::max);
    assert!(
        (peak - peak_truth).abs() < 0.02,
        "peak {peak} vs {peak_truth}"
    );
}

/// A camera sharpens its code after its tone curve (an unsharp mask on the
/// sRGB code, amount 0.8, radius 1.2 px, as JPEG engines do; the truth is the
/// modulation a sine of the chart's contrast reads through it: see
/// `synth_code_sharpen`). The bend it gives the periods' shapes is not a tone
/// curve: nothing is taken out, and the sharpening bars hold.
#[test]
fn a_sharpened_code_is_not_a_tone_curve_and_within_0_01() {
    for variant in [7u64, 12] {
        let shot = case("code_usm0.8", variant);
        let m = measured(&shot, 100 + variant, MeasureOptions::default());
        let (rms, e50, cm, cm_err) = scores(&shot, &m);
        let fix = m.curves[0].tone_fix.as_ref();
        eprintln!(
            "code_usm v{variant}: RMS {rms:.4} MTF50 {e50:+.4} chart {cm:.4} ± {cm_err:.4}; tone used {:?} sharpening seen {:?}",
            fix.map(|f| f.used),
            fix.map(|f| f.sharpening_seen)
        );
        assert!(fix.is_none_or(|f| !f.used), "v{variant}: {fix:?}");
        assert_bars(&format!("v{variant}"), rms, e50, cm, 0.01);
    }
}

#[test]
fn rgb_jpeg_q75_420_with_noise_within_0_012() {
    check("rgb_jpeg75_420", 0.012);
    // The coarse table is read from the file and said: its quantisation is part of this MTF.
    let shot = case("rgb_jpeg75_420", 7);
    let dec = decode_bytes(&shot.encode(1), "q75.jpg").unwrap();
    let opts = MeasureOptions {
        roi: Some(shot.quad),
        ..MeasureOptions::default()
    };
    let m = measure_decoded(&dec, "q75.jpg", None, &opts).unwrap();
    assert!(
        m.warnings
            .iter()
            .any(|w| w.starts_with("JPEG quality ≈ 75 ")),
        "{:?}",
        m.warnings
    );
    // At q92 (a camera's usual "fine") nothing is said.
    let fine = SynthShot {
        jpeg_quality: Some(92),
        ..shot
    };
    let dec = decode_bytes(&fine.encode(1), "q92.jpg").unwrap();
    let m = measure_decoded(&dec, "q92.jpg", None, &opts).unwrap();
    assert!(
        !m.warnings.iter().any(|w| w.starts_with("JPEG")),
        "{:?}",
        m.warnings
    );
}

/// Exact corners stay exact: the default refinement fits the long edges and turns
/// the ends along the bars, but no longer pulls the ends inward.
#[test]
fn refinement_keeps_exact_strip_corners() {
    let shot = &nuisance_cases(7)[0];
    let dec = decode_bytes(&shot.encode(5), "exact").unwrap();
    let opts = MeasureOptions {
        roi: Some(shot.quad),
        refine_roi: true,
        ..MeasureOptions::default()
    };
    let m = measure_decoded(&dec, "exact", None, &opts).unwrap();
    let moved = m
        .roi
        .iter()
        .zip(&shot.quad)
        .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
        .fold(0.0, f64::max);
    assert!(
        moved <= 1.0,
        "exact corners moved {moved:.2} px: {:?}",
        m.notes
    );
    assert!(
        m.notes
            .iter()
            .any(|w| w.contains("long edges moved") && w.contains("ends kept")),
        "{:?}",
        m.notes
    );
}

fn roi_arg(q: [[f64; 2]; 4]) -> String {
    q.iter()
        .flatten()
        .map(|v| format!("{v}"))
        .collect::<Vec<_>>()
        .join(",")
}

fn files_in(dir: &Path) -> usize {
    std::fs::read_dir(dir).map(|r| r.count()).unwrap_or(0)
}

/// A strip 3 px tall holds too few samples per bin for a confident curve: exit 5,
/// one line naming the file and the cause, and no output files.
#[test]
fn a_three_pixel_strip_is_refused() {
    let mut shot = nuisance_cases(7).remove(2);
    let q = shot.quad;
    // Same strip, 3 px tall about its centre line.
    let mid = |a: [f64; 2], b: [f64; 2]| [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
    let (m0, m1) = (mid(q[0], q[3]), mid(q[1], q[2]));
    let h = |a: [f64; 2], b: [f64; 2], t: f64| {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let l = dx.hypot(dy);
        [a[0] + t * dx / l, a[1] + t * dy / l]
    };
    shot.quad = [
        h(m0, q[0], 1.5),
        h(m1, q[1], 1.5),
        h(m1, q[2], 1.5),
        h(m0, q[3], 1.5),
    ];
    shot.strip_width = 3.0;
    let dir = tempfile::tempdir().unwrap();
    let photo = dir.path().join("thin.png");
    std::fs::write(&photo, shot.encode(9)).unwrap();
    let out = dir.path().join("out");
    let assert = Command::cargo_bin("sweepmtf")
        .unwrap()
        .arg("measure")
        .arg(&photo)
        .arg("--roi")
        .arg(roi_arg(shot.quad))
        .arg("-o")
        .arg(&out)
        .assert()
        .code(5);
    let err = String::from_utf8_lossy(&assert.get_output().stderr).to_string();
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("thin.png"), "{err}");
    assert_eq!(files_in(&out), 0, "{err}");
}

/// Plain sRGB (no tone beyond it) under light falling 2:1 along the strip
/// with 50 % vignetting, an unsharp mask peaking near 1.15 and JPEG q92: the
/// strip-tone fit's Wald distance reaches 5–6 σ on such shots (their
/// residuals share the JPEG blocks and the light), and at the 5 σ use
/// threshold of sessions 22–26 a "tone" was taken out of 4 of 12 variants
/// (RMS 0.0073–0.0092 against 0.0020–0.0037 on the others). Since session 27
/// a correction is used only beyond 10 σ: nothing is taken out and the bars
/// hold.
#[test]
fn plain_srgb_under_uneven_light_and_sharpening_is_not_given_a_tone() {
    use sweepmtf::measure::synth::Nuisances;
    for variant in [3u64, 4] {
        let base = case("usm_peak1.15", variant);
        let shot = SynthShot {
            mean: 0.3,
            jpeg_quality: Some(92),
            nuisance: Nuisances {
                light_ratio: 2.0,
                vignette_corner: 0.5,
                ..base.nuisance
            },
            ..base
        };
        let m = measured(&shot, 100 + variant, MeasureOptions::default());
        let (rms, e50, cm, cm_err) = scores(&shot, &m);
        let fix = m.curves[0].tone_fix.as_ref();
        eprintln!(
            "plain sRGB, light 2:1, USM, q92 v{variant}: RMS {rms:.4} MTF50 {e50:+.4} chart {cm:.4} ± {cm_err:.4}; tone {:?}",
            fix.map(|f| (f.used, f.significance))
        );
        assert!(fix.is_none_or(|f| !f.used), "v{variant}: {fix:?}");
        assert_bars(&format!("v{variant}"), rms, e50, cm, 0.006);
    }
}
