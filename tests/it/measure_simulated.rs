//! Accuracy bars of issue 5 against the real simulator (`sweepmtf::simulate`):
//! each shot is rendered through a Gaussian lens × square pixel with the
//! exposure, noise, rotation, perspective and encoding of the case, and the
//! measured MTF is compared with the simulator's own truth curve (its analytic
//! OTF along the strip), RMS over 0.01–0.45 cy/px, non-aliased points.
//! Frequencies are checked against the truth rows' image frequencies.

use sweepmtf::geometry::Point;
use sweepmtf::measure::{MeasureOptions, Method, measure_decoded};
use sweepmtf::model::System;
use sweepmtf::photo::decode::decode_bytes;
use sweepmtf::simulate::demo::{GaussianPsf, demo_target_for};
use sweepmtf::simulate::{Camera, Shot, encode::PhotoFormat, render};
use sweepmtf::target::{SweepLaw, Target};

/// A case: its camera, the sweep's printed contrast, and the photo format.
struct Case {
    name: &'static str,
    camera: Camera,
    contrast: f64,
    format: PhotoFormat,
}

/// 1000×600 frame, 4.3 µm pixels, chart 840 px wide (sweep 700 px), sRGB 8-bit.
fn camera() -> Camera {
    Camera {
        width_px: 1000,
        height_px: 600,
        chart_px: Some(840.0),
        ..Camera::default()
    }
}

/// SNR ≈ 50 at the sweep's mean level (shot noise of 6000 e⁻ full well, 5 e⁻ read noise).
fn noisy(c: Camera) -> Camera {
    Camera {
        full_well_e: Some(6000.0),
        read_noise_e: 5.0,
        seed: 11,
        jpeg_quality: Some(90),
        ..c
    }
}

fn shoot(case: &Case) -> (Shot, Target, Vec<u8>) {
    let mut t = demo_target_for(&case.camera, SweepLaw::Log, 0.006, 0.6).unwrap();
    t.sweeps[0].contrast = case.contrast;
    let sigma_mm = 0.6 * case.camera.pitch_mm();
    let system = System {
        factors: vec![Box::new(GaussianPsf { sigma_mm })],
    };
    let shot = render(&t, &system, &case.camera).unwrap();
    let bytes = shot.encode(case.format).unwrap();
    (shot, t, bytes)
}

/// (RMS |MTF − truth|, largest relative frequency error, points used).
fn score(shot: &Shot, m: &sweepmtf::measure::Measurement) -> (f64, f64, usize) {
    let truth = &shot.truth().unwrap().rows;
    let at = |f: f64| sweepmtf::simulate::mtf_at(truth, f);
    let c = &m.curves[0];
    let (mut se, mut n) = (0.0, 0);
    for p in c.points.iter().filter(|p| !p.aliased) {
        if (0.01..=0.45).contains(&p.freq_cy_px) {
            se += (p.mtf - at(p.freq_cy_px)).powi(2);
            n += 1;
        }
    }
    ((se / n.max(1) as f64).sqrt(), frequency_error(shot, m), n)
}

/// Largest relative error of the measured image frequency against the truth
/// at the same place on the sweep, over 0.01–0.4 cy/px. The strip frame of a
/// measurement and the sweep's chart frame map the same rectangle onto the
/// same image quad, so strip position s (px units without a target, mm with
/// one) is the chart position scaled by the ratio of their lengths.
fn frequency_error(shot: &Shot, m: &sweepmtf::measure::Measurement) -> f64 {
    let rows = &shot.truth().unwrap().rows;
    let len_mm = rows.last().unwrap().s_mm;
    let c = &m.curves[0];
    let len_strip = if c.strip_unit == "mm" {
        len_mm
    } else {
        let q = shot.roi().unwrap();
        let d = |i: usize, j: usize| (q[2 * i] - q[2 * j]).hypot(q[2 * i + 1] - q[2 * j + 1]);
        0.5 * (d(0, 1) + d(3, 2))
    };
    let mut worst = 0.0f64;
    for p in c.points.iter().filter(|p| !p.aliased) {
        if !(0.01..=0.4).contains(&p.freq_cy_px) {
            continue;
        }
        let s_mm = p.s * len_mm / len_strip;
        let i = rows
            .partition_point(|r| r.s_mm < s_mm)
            .clamp(1, rows.len() - 1);
        let (a, b) = (&rows[i - 1], &rows[i]);
        let f = a.freq_cy_px + (b.freq_cy_px - a.freq_cy_px) * (s_mm - a.s_mm) / (b.s_mm - a.s_mm);
        worst = worst.max((p.freq_cy_px / f - 1.0).abs());
    }
    worst
}

fn strip_roi(shot: &Shot) -> [Point; 4] {
    let r = shot.roi().unwrap();
    [[r[0], r[1]], [r[2], r[3]], [r[4], r[5]], [r[6], r[7]]]
}

fn measure_strip(case: &Case) -> (f64, f64, usize) {
    let (shot, _, bytes) = shoot(case);
    let dec = decode_bytes(&bytes, case.name).unwrap();
    let opts = MeasureOptions {
        roi: Some(strip_roi(&shot)),
        method: Method::Fit,
        ..MeasureOptions::default()
    };
    let m = measure_decoded(&dec, case.name, None, &opts).unwrap();
    score(&shot, &m)
}

fn case(name: &'static str, camera: Camera, contrast: f64, format: PhotoFormat) -> Case {
    Case {
        name,
        camera,
        contrast,
        format,
    }
}

#[test]
fn noiseless_8bit_srgb_within_0_005() {
    let c = case("noiseless", camera(), 0.8, PhotoFormat::Png);
    let (rms, ferr, n) = measure_strip(&c);
    eprintln!("noiseless: RMS {rms:.4}, frequency error {ferr:.5}, {n} points");
    assert!(n > 60, "{n} points");
    assert!(rms <= 0.005, "RMS {rms:.4}");
    assert!(ferr <= 0.005, "frequency error {ferr:.5}");
}

#[test]
fn snr50_jpeg90_within_0_015_straight_rotated_and_tilted() {
    let cams = [
        ("straight", noisy(camera())),
        (
            "rot45",
            noisy(Camera {
                rotate_deg: 45.0,
                chart_px: Some(480.0),
                ..camera()
            }),
        ),
        (
            "tilt30_rot10",
            noisy(Camera {
                rotate_deg: 10.0,
                tilt_deg: 30.0,
                chart_px: Some(640.0),
                ..camera()
            }),
        ),
    ];
    for (name, cam) in cams {
        let (rms, ferr, n) = measure_strip(&case(name, cam, 0.8, PhotoFormat::Jpeg));
        eprintln!("{name}: RMS {rms:.4}, frequency error {ferr:.5}, {n} points");
        assert!(n > 30, "{name}: {n} points");
        assert!(rms <= 0.015, "{name}: RMS {rms:.4}");
        assert!(ferr <= 0.005, "{name}: frequency error {ferr:.5}");
    }
}

#[test]
fn dark_low_contrast_within_0_04() {
    let cam = Camera {
        exposure: 0.3,
        ..noisy(camera())
    };
    let (rms, _, n) = measure_strip(&case("dark_c0.2", cam, 0.2, PhotoFormat::Jpeg));
    eprintln!("dark c0.2: RMS {rms:.4}, {n} points");
    assert!(n > 40, "{n} points");
    assert!(rms <= 0.04, "RMS {rms:.4}");
}

/// With the target description: the sweep is placed from the target corners
/// and normalised by its printed contrast (no extrapolation).
#[test]
fn with_the_target_the_printed_contrast_normalises() {
    let c = case("target", noisy(camera()), 0.8, PhotoFormat::Jpeg);
    let (shot, t, bytes) = shoot(&c);
    let dec = decode_bytes(&bytes, c.name).unwrap();
    let q = shot.target_corners;
    let opts = MeasureOptions {
        roi: Some([[q[0], q[1]], [q[2], q[3]], [q[4], q[5]], [q[6], q[7]]]),
        ..MeasureOptions::default()
    };
    let m = measure_decoded(&dec, c.name, Some(&t), &opts).unwrap();
    assert!(m.curves[0].chart_modulation_source.starts_with("target"));
    let (rms, _, n) = score(&shot, &m);
    eprintln!("target: RMS {rms:.4}, {n} points");
    assert!(n > 40, "{n} points");
    assert!(rms <= 0.015, "RMS {rms:.4}");
}

/// The plane converted for corner refinement is reused for the measurement:
/// the result must equal a fresh conversion at the same (refined) corners.
#[test]
fn refinement_plane_reuse_changes_nothing() {
    let c = case("reuse", noisy(camera()), 0.8, PhotoFormat::Jpeg);
    let (shot, t, bytes) = shoot(&c);
    let dec = decode_bytes(&bytes, c.name).unwrap();
    let q = shot.target_corners;
    let given = [
        [q[0] + 2.0, q[1] - 1.5],
        [q[2] - 1.0, q[3] + 2.0],
        [q[4] + 1.5, q[5] + 1.0],
        [q[6] - 2.0, q[7] - 1.0],
    ];
    let refined = measure_decoded(
        &dec,
        c.name,
        Some(&t),
        &MeasureOptions {
            roi: Some(given),
            refine_roi: true,
            ..MeasureOptions::default()
        },
    )
    .unwrap();
    let fresh = measure_decoded(
        &dec,
        c.name,
        Some(&t),
        &MeasureOptions {
            roi: Some(refined.roi),
            refine_roi: false,
            ..MeasureOptions::default()
        },
    )
    .unwrap();
    let (a, b) = (&refined.curves[0].points, &fresh.curves[0].points);
    assert_eq!(a.len(), b.len());
    for (p, q) in a.iter().zip(b) {
        assert_eq!(p.mtf.to_bits(), q.mtf.to_bits(), "{} cy/px", p.freq_cy_px);
    }
}
