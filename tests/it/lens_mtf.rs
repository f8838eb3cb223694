//! Issue 20, item 4: lens MTF = measured system MTF / sensor part. Shots from
//! the camera simulator (`sweepmtf::simulate`) whose truth is optics × sensor;
//! the optics part is known here analytically (a Gaussian PSF of σ px:
//! exp(−2π²σ²f²) along any direction), so the lens MTF is compared with it,
//! RMS over the given points in 0.01–0.4 cy/px (0.8 × Nyquist).

use assert_cmd::Command;
use std::f64::consts::PI;
use std::sync::Arc;
use sweepmtf::measure::lens_mtf::{LensFlag, SensorPart, lens_curve};
use sweepmtf::measure::{MeasureOptions, Measurement, measure_decoded};
use sweepmtf::model::System;
use sweepmtf::model::spec::parse_factor;
use sweepmtf::photo::decode::decode_bytes;
use sweepmtf::simulate::demo::demo_target_for;
use sweepmtf::simulate::{Camera, Shot, encode::PhotoFormat, render};
use sweepmtf::target::SweepLaw;

/// Gaussian blur of the optics, in pixels (4.3 µm pitch: σ = 2.58 µm).
const SIGMA_PX: f64 = 0.6;

fn optics_truth(f: f64) -> f64 {
    (-2.0 * PI * PI * SIGMA_PX * SIGMA_PX * f * f).exp()
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

fn noisy(c: Camera) -> Camera {
    Camera {
        full_well_e: Some(6000.0),
        read_noise_e: 5.0,
        seed: 11,
        jpeg_quality: Some(90),
        ..c
    }
}

/// The optics (Gaussian, as a model factor) and the sensor factors, as a system.
fn system(sensor: &[(&str, &str)]) -> System {
    let mut factors =
        vec![parse_factor("gaussian", &format!("sigma={}um", SIGMA_PX * 4.3)).unwrap()];
    for (k, s) in sensor {
        factors.push(parse_factor(k, s).unwrap());
    }
    System { factors }
}

fn shoot(cam: &Camera, sys: &System, format: PhotoFormat) -> (Shot, Vec<u8>) {
    let t = demo_target_for(cam, SweepLaw::Log, 0.006, 0.6).unwrap();
    let shot = render(&t, sys, cam).unwrap();
    let bytes = shot.encode(format).unwrap();
    (shot, bytes)
}

fn measure(shot: &Shot, bytes: &[u8]) -> Measurement {
    let r = shot.roi().unwrap();
    let dec = decode_bytes(bytes, "lens").unwrap();
    let opts = MeasureOptions {
        roi: Some([[r[0], r[1]], [r[2], r[3]], [r[4], r[5]], [r[6], r[7]]]),
        pixel_pitch_mm: Some(cam_pitch(shot)),
        ..MeasureOptions::default()
    };
    measure_decoded(&dec, "lens", None, &opts).unwrap()
}

fn cam_pitch(shot: &Shot) -> f64 {
    shot.camera.pitch_mm()
}

/// (RMS |lens MTF − optics truth| over the given points in 0.01–0.4 cy/px, points, flagged in band).
fn score(m: &Measurement, sensor: &SensorPart) -> (f64, usize, usize) {
    let c = &m.curves[0];
    let l = lens_curve(c, sensor);
    let (mut se, mut n, mut flagged) = (0.0, 0, 0);
    for (i, p) in c.points.iter().enumerate() {
        if !(0.01..=0.4).contains(&p.freq_cy_px) {
            continue;
        }
        match l.flag[i] {
            LensFlag::Ok => {
                se += (l.lens_mtf[i] - optics_truth(p.freq_cy_px)).powi(2);
                n += 1;
            }
            LensFlag::SmallDivisor => flagged += 1,
            LensFlag::Aliased => {}
        }
    }
    ((se / n.max(1) as f64).sqrt(), n, flagged)
}

/// Default divisor (square pixel of 100 % fill): noiseless straight, and SNR 50 JPEG turned 20°.
#[test]
fn square_pixel_divisor_gives_the_optics_within_0_01_rms() {
    let sys = system(&[]);
    let cases = [
        ("straight_noiseless", camera(), PhotoFormat::Png),
        (
            "rot20_snr50_jpeg90",
            noisy(Camera {
                rotate_deg: 20.0,
                chart_px: Some(560.0),
                ..camera()
            }),
            PhotoFormat::Jpeg,
        ),
    ];
    for (name, cam, fmt) in cases {
        let (shot, bytes) = shoot(&cam, &sys, fmt);
        let m = measure(&shot, &bytes);
        let (rms, n, flagged) = score(&m, &SensorPart::SquarePixel);
        // The system MTF against the system truth, for comparison.
        let (sys_rms, _, _) = {
            let c = &m.curves[0];
            let truth = &shot.truth().unwrap().rows;
            let at = |f: f64| sweepmtf::simulate::mtf_at(truth, f);
            let v: Vec<f64> = c
                .points
                .iter()
                .filter(|p| !p.aliased && (0.01..=0.4).contains(&p.freq_cy_px))
                .map(|p| (p.mtf - at(p.freq_cy_px)).powi(2))
                .collect();
            ((v.iter().sum::<f64>() / v.len() as f64).sqrt(), 0, 0)
        };
        eprintln!(
            "{name}: lens RMS {rms:.4} over {n} points ({flagged} flagged); system RMS {sys_rms:.4}"
        );
        assert!(n >= 30, "{name}: {n} points");
        assert_eq!(
            flagged, 0,
            "{name}: a square pixel stays above 0.2 below Nyquist"
        );
        assert!(rms <= 0.01, "{name}: lens RMS {rms:.4}");
    }
}

/// A system file's sensor part: an 85 % wide aperture and a 2-spot OLPF of
/// 0.7 pitch, rendered by the simulator and divided out again.
#[test]
fn model_aperture_and_olpf_divisor_gives_the_optics_within_0_01_rms() {
    let sensor = [
        ("aperture", "rect:A=3.655um,B=3.655um"),
        ("olpf", "2spot:d=3.01um"),
    ];
    let sys = system(&sensor);
    let (shot, bytes) = shoot(&camera(), &sys, PhotoFormat::Png);
    assert!(
        shot.factors_applied
            .iter()
            .any(|f| f.contains("aperture_rect")),
        "{:?}",
        shot.factors_applied
    );
    let m = measure(&shot, &bytes);
    let part = SensorPart::from_system(Arc::new(system(&sensor)), Some(cam_pitch(&shot))).unwrap();
    assert_eq!(part.describe(), "aperture_rect × olpf");
    let (rms, n, flagged) = score(&m, &part);
    eprintln!("aperture 85 % + OLPF 0.7 px: lens RMS {rms:.4} over {n} points ({flagged} flagged)");
    assert!(n > 40 && rms <= 0.01, "RMS {rms:.4} over {n}");
}

/// The CLI: `--lens-mtf` with a model whose OLPF (split = pitch) reaches 0 at
/// Nyquist adds the columns, leaves the flagged rows' lens MTF empty, and a
/// model without sensor factors is refused with exit 2 and no output.
#[test]
fn cli_columns_flags_and_refusal() {
    let sys_text = "name = \"olpf test\"\n\
        [[factor]]\nkind = \"gaussian\"\nspec = \"sigma=2.58um\"\n\
        [[factor]]\nkind = \"aperture\"\nspec = \"rect:A=4.3um,B=4.3um\"\n\
        [[factor]]\nkind = \"olpf\"\nspec = \"2spot:d=4.3um\"\n";
    let dir = tempfile::tempdir().unwrap();
    let toml = dir.path().join("sys.toml");
    std::fs::write(&toml, sys_text).unwrap();
    let sys = sweepmtf::model::System::from_file(&toml).unwrap();
    let (shot, bytes) = shoot(&camera(), &sys, PhotoFormat::Png);
    let photo = dir.path().join("lens.png");
    std::fs::write(&photo, bytes).unwrap();
    let roi = shot
        .roi()
        .unwrap()
        .iter()
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(",");
    let run = |model: &std::path::Path, out: &std::path::Path| {
        Command::cargo_bin("sweepmtf")
            .unwrap()
            .arg("measure")
            .arg(&photo)
            .args([
                "--roi",
                &roi,
                "--pixel-pitch",
                "4.3um",
                "--lens-mtf",
                "--model",
            ])
            .arg(model)
            .arg("-o")
            .arg(out)
            .assert()
    };
    let out = dir.path().join("out");
    let a = run(&toml, &out).success();
    let line = String::from_utf8_lossy(&a.get_output().stdout).into_owned();
    assert!(line.contains("lens MTF50"), "{line}");
    let rows = crate::csv_support::read_csv(&out.join("lens.mtf.csv"));
    let (mut ok, mut small) = (0, 0);
    for r in &rows {
        let f: f64 = r["freq_cy_px"].parse().unwrap();
        match r["lens_flag"].as_str() {
            "ok" => {
                let v: f64 = r["lens_mtf"].parse().unwrap();
                let d: f64 = r["sensor_mtf"].parse().unwrap();
                assert!(d >= 0.2 && v.is_finite(), "{r:?}");
                if (0.01..=0.4).contains(&f) {
                    assert!((v - optics_truth(f)).abs() < 0.05, "{f}: {v}");
                }
                ok += 1;
            }
            "small_divisor" => {
                assert!(
                    r["lens_mtf"].is_empty() && r["lens_mtf_err"].is_empty(),
                    "{r:?}"
                );
                assert!(r["sensor_mtf"].parse::<f64>().unwrap() < 0.2);
                small += 1;
            }
            "aliased" => assert_eq!(r["aliased"], "true"),
            other => panic!("flag {other}"),
        }
    }
    assert!(ok > 40 && small > 0, "{ok} given, {small} flagged");
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("lens.summary.json")).unwrap()).unwrap();
    assert_eq!(v["lens_mtf"]["sensor_part"], "aperture_rect × olpf");
    assert!(v["curves"][0]["lens_mtf50_cy_px"].as_f64().is_some());
    assert!(out.join("lens.mtf.png").exists());
    // Optics only: nothing to divide by.
    let bad = dir.path().join("optics.toml");
    std::fs::write(
        &bad,
        "[[factor]]\nkind = \"gaussian\"\nspec = \"sigma=2.58um\"\n",
    )
    .unwrap();
    let out2 = dir.path().join("out2");
    let a = run(&bad, &out2).code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr).into_owned();
    assert!(
        err.contains("--lens-mtf") && err.lines().count() == 1,
        "{err}"
    );
    assert!(!out2.join("lens.mtf.csv").exists());
}
