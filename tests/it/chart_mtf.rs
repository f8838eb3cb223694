//! Issue 20, item 2: the print's own MTF divided out (`measure --chart-mtf`).
//! A small chart (one log sweep, 0.3–12 cy/mm over 30 mm) is printed with a
//! Gaussian blur of σ = 0.05 mm (`Camera::print_blur`: its sines lose
//! exp(−2π²σ²f²) at chart frequency f; the print MTF falls to 0.3 at
//! 4.9 cy/mm). A scan-like shot (60 px per chart mm, no optics, measured with
//! `--lens-mtf` so that its pixel aperture is divided out) measures the print;
//! a camera shot (20 px/mm, Gaussian optics σ 0.6 px) of the same print is
//! then compensated, and its camera MTF compared with the simulator's truth
//! (which is the camera's MTF alone) wherever the print's MTF (closed form)
//! is ≥ 0.3. Points below it must be flagged, never given.

use assert_cmd::Command;
use std::f64::consts::PI;
use std::path::Path;
use sweepmtf::measure::chart_mtf::{ChartFlag, ChartMtf, chart_curve, chart_curve_scaled};
use sweepmtf::measure::{MeasureOptions, Measurement, measure_decoded};
use sweepmtf::model::System;
use sweepmtf::photo::decode::decode_bytes;
use sweepmtf::print_mtf::PrintMtf;
use sweepmtf::simulate::demo::GaussianPsf;
use sweepmtf::simulate::{Camera, Encoding, PhotoFormat, Shot, render};
use sweepmtf::target::{Direction, Rect, Sweep, SweepLaw, Target};

/// σ of the print's blur, mm.
const PRINT_SIGMA_MM: f64 = 0.05;

fn print_mtf(f_cy_mm: f64) -> f64 {
    (-2.0 * PI * PI * (PRINT_SIGMA_MM * f_cy_mm).powi(2)).exp()
}

/// A 34×10 mm chart: one log sweep 0.3–12 cy/mm over 30 mm.
pub(crate) fn target() -> Target {
    Target {
        name: "print-test".into(),
        width_mm: 34.0,
        height_mm: 10.0,
        background: 1.0,
        sweeps: vec![Sweep {
            id: "main".into(),
            rect: Rect {
                x_mm: 2.0,
                y_mm: 2.0,
                width_mm: 30.0,
                height_mm: 6.0,
            },
            direction: Direction::X,
            law: SweepLaw::Log,
            f_min_cy_mm: 0.3,
            f_max_cy_mm: 12.0,
            mean: 0.45,
            contrast: 0.8,
        }],
        patches: vec![],
        greys: vec![],
        fiducials: vec![],
    }
}

fn print() -> Option<PrintMtf> {
    Some(PrintMtf::Gaussian {
        sigma_mm: PRINT_SIGMA_MM,
    })
}

/// The scan: 60 px per chart mm (0.005–0.2 cy/px), no optics, 16-bit linear, noiseless.
fn scanner() -> Camera {
    scanner_of(print())
}

/// The scan of a print with `print_blur`.
fn scanner_of(print_blur: Option<PrintMtf>) -> Camera {
    Camera {
        width_px: 2140,
        height_px: 680,
        chart_px: Some(34.0 * 60.0),
        encoding: Encoding::Linear,
        bits: 16,
        print_blur,
        ..Camera::default()
    }
}

/// The camera: 20 px per chart mm (0.015–0.6 cy/px), sRGB 8-bit.
pub(crate) fn camera() -> Camera {
    Camera {
        width_px: 760,
        height_px: 260,
        chart_px: Some(34.0 * 20.0),
        print_blur: print(),
        ..Camera::default()
    }
}

fn noisy(c: Camera) -> Camera {
    Camera {
        full_well_e: Some(6000.0),
        read_noise_e: 5.0,
        seed: 7,
        jpeg_quality: Some(90),
        ..c
    }
}

pub(crate) fn optics(sigma_px: f64) -> System {
    let mut factors: Vec<Box<dyn sweepmtf::model::Factor>> = Vec::new();
    if sigma_px > 0.0 {
        factors.push(Box::new(GaussianPsf {
            sigma_mm: sigma_px * 0.0043,
        }));
    }
    System { factors }
}

pub(crate) fn shoot(cam: &Camera, sys: &System, format: PhotoFormat) -> (Shot, Vec<u8>) {
    let shot = render(&target(), sys, cam).unwrap();
    let bytes = shot.encode(format).unwrap();
    (shot, bytes)
}

fn corners(shot: &Shot) -> [[f64; 2]; 4] {
    let c = shot.target_corners;
    [[c[0], c[1]], [c[2], c[3]], [c[4], c[5]], [c[6], c[7]]]
}

pub(crate) fn measure(shot: &Shot, bytes: &[u8]) -> Measurement {
    let dec = decode_bytes(bytes, "print").unwrap();
    let opts = MeasureOptions {
        roi: Some(corners(shot)),
        pixel_pitch_mm: Some(shot.camera.pitch_mm()),
        ..MeasureOptions::default()
    };
    measure_decoded(&dec, "print", Some(&target()), &opts).unwrap()
}

/// (RMS |camera MTF − truth| over given points with print MTF ≥ 0.3, points,
/// points wrongly given below 0.29, RMS of the uncompensated MTF there).
fn score(shot: &Shot, m: &Measurement, chart: &ChartMtf) -> (f64, usize, usize, f64) {
    let c = &m.curves[0];
    let cc = chart_curve(c, chart).unwrap();
    let truth = &shot.truth().unwrap().rows;
    let (mut se, mut se_raw, mut n, mut wrong) = (0.0, 0.0, 0, 0);
    for (i, p) in c.points.iter().enumerate() {
        let pm = print_mtf(p.freq_chart);
        let t = sweepmtf::simulate::mtf_at(truth, p.freq_cy_px);
        if pm < 0.29 && cc.flag[i] == ChartFlag::Ok {
            wrong += 1;
        }
        if cc.flag[i] != ChartFlag::Ok {
            assert!(cc.camera_mtf[i].is_nan() && cc.camera_mtf_err[i].is_nan());
            continue;
        }
        if pm >= 0.3 {
            se += (cc.camera_mtf[i] - t).powi(2);
            se_raw += (p.mtf - t).powi(2);
            n += 1;
        }
    }
    let k = n.max(1) as f64;
    ((se / k).sqrt(), n, wrong, (se_raw / k).sqrt())
}

/// The scan's measured print MTF as a chart table (through the CSV that `measure --lens-mtf` writes).
fn scan_table(dir: &Path) -> ChartMtf {
    scan_table_of(dir, print().unwrap())
}

/// [`scan_table`] of a print `p`, checked against its closed form within 0.02.
pub(crate) fn scan_table_of(dir: &Path, p: PrintMtf) -> ChartMtf {
    let (shot, bytes) = shoot(&scanner_of(Some(p)), &optics(0.0), PhotoFormat::Png);
    let m = measure(&shot, &bytes);
    let lcs: Vec<_> = m
        .curves
        .iter()
        .map(|c| {
            sweepmtf::measure::lens_mtf::lens_curve(
                c,
                &sweepmtf::measure::lens_mtf::SensorPart::SquarePixel,
            )
        })
        .collect();
    let csv =
        sweepmtf::report::lens_mtf::add_lens_columns(&sweepmtf::report::csv::curves_csv(&m), &lcs);
    let path = dir.join("scan.mtf.csv");
    std::fs::write(&path, csv).unwrap();
    let t = ChartMtf::from_arg(path.to_str().unwrap()).unwrap();
    // The scan's print MTF against the closed form, over the range it covers.
    if let ChartMtf::Table(tab) = &t {
        assert_eq!(tab.column, "lens_mtf");
        let (mut worst, mut at) = (0.0f64, 0.0);
        for (f, v) in tab.f_cy_mm.iter().zip(&tab.mtf) {
            let d = (v - p.mtf(*f)).abs();
            if d > worst {
                (worst, at) = (d, *f);
            }
        }
        eprintln!(
            "scan: {} rows {:.2}–{:.2} cy/mm, worst |print MTF − closed form| {worst:.4} at {at:.2} cy/mm",
            tab.f_cy_mm.len(),
            tab.f_cy_mm[0],
            tab.f_cy_mm[tab.f_cy_mm.len() - 1]
        );
        assert!(worst < 0.02, "{worst} at {at}");
    }
    t
}

/// The bar: through the scan's CSV and through the closed form, noiseless
/// PNG and SNR-50 JPEG camera shots give the camera's truth within 0.01 RMS
/// wherever the print's MTF is ≥ 0.3, and nothing below it.
#[test]
fn scan_and_closed_form_compensation_give_the_camera_within_0_01_rms() {
    let dir = tempfile::tempdir().unwrap();
    let scan = scan_table(dir.path());
    let model = ChartMtf::Model(print().unwrap());
    let sys = optics(0.6);
    for (name, cam, fmt) in [
        ("noiseless_png", camera(), PhotoFormat::Png),
        ("snr50_jpeg90", noisy(camera()), PhotoFormat::Jpeg),
    ] {
        let (shot, bytes) = shoot(&cam, &sys, fmt);
        assert!(shot.truth().unwrap().rows.iter().all(|r| {
            r.print_mtf
                .is_some_and(|p| (p - print_mtf(r.chart_freq_cy_mm)).abs() < 1e-12)
        }));
        let m = measure(&shot, &bytes);
        for (src, chart) in [("scan", &scan), ("gaussian", &model)] {
            let (rms, n, wrong, raw) = score(&shot, &m, chart);
            eprintln!(
                "{name} / {src}: camera RMS {rms:.4} over {n} points (uncompensated {raw:.4}); {wrong} given below 0.29"
            );
            assert!(n >= 30, "{name}/{src}: {n} points");
            assert_eq!(wrong, 0, "{name}/{src}");
            assert!(rms <= 0.01, "{name}/{src}: RMS {rms:.4}");
            assert!(
                raw > 0.05,
                "{name}/{src}: the print's loss must show: {raw}"
            );
        }
    }
}

/// Without a target: the sweep strip's corners alone (as `simulate` gives
/// them in `roi`) and its printed length (30 mm) give the chart frequency;
/// through the closed form and the scan, the camera within 0.01 RMS.
#[test]
fn without_a_target_the_printed_strip_length_gives_the_scale() {
    let dir = tempfile::tempdir().unwrap();
    let scan = scan_table(dir.path());
    let (shot, bytes) = shoot(&camera(), &optics(0.6), PhotoFormat::Png);
    let r = shot.roi().unwrap();
    let dec = decode_bytes(&bytes, "strip").unwrap();
    let opts = MeasureOptions {
        roi: Some([[r[0], r[1]], [r[2], r[3]], [r[4], r[5]], [r[6], r[7]]]),
        sweep: sweepmtf::measure::SweepChoice::Log,
        ..MeasureOptions::default()
    };
    let m = measure_decoded(&dec, "strip", None, &opts).unwrap();
    let c = &m.curves[0];
    assert_eq!(c.strip_unit, "px");
    assert!(
        chart_curve(c, &scan).is_err(),
        "no scale without the length"
    );
    let truth = &shot.truth().unwrap().rows;
    for (src, chart) in [
        ("scan", &scan),
        ("gaussian", &ChartMtf::Model(print().unwrap())),
    ] {
        let cc = chart_curve_scaled(c, chart, Some(30.0)).unwrap();
        let (mut se, mut n) = (0.0, 0);
        for (i, p) in c.points.iter().enumerate() {
            // The chart frequency from the shot's scale (20 px per chart mm, straight).
            let fc = p.freq_cy_px * 20.0;
            if cc.flag[i] == ChartFlag::Ok {
                assert!(print_mtf(fc) > 0.29, "{src}: {fc} cy/mm given");
                if print_mtf(fc) >= 0.3 {
                    let t = sweepmtf::simulate::mtf_at(truth, p.freq_cy_px);
                    se += (cc.camera_mtf[i] - t).powi(2);
                    n += 1;
                }
            }
        }
        let rms = (se / n.max(1) as f64).sqrt();
        eprintln!("no target / {src}: camera RMS {rms:.4} over {n} points");
        assert!(n >= 30 && rms <= 0.01, "{src}: {rms} over {n}");
    }
}

/// A print of square 150 dpi dots (sinc(f·25.4/150): 0.3 at 4.5 cy/mm, zero
/// at 5.9 cy/mm, then reversed contrast): through the scan and through
/// `dots:dpi=150`, the camera within 0.01 RMS where the print's MTF ≥ 0.3,
/// and the points past its zero (where a scan's MTF rises again) flagged.
#[test]
fn dot_print_compensation() {
    let dir = tempfile::tempdir().unwrap();
    let dots = PrintMtf::Dots { dpi: 150.0 };
    let scan = scan_table_of(dir.path(), dots);
    let cam = Camera {
        print_blur: Some(dots),
        ..camera()
    };
    let (shot, bytes) = shoot(&cam, &optics(0.6), PhotoFormat::Png);
    let m = measure(&shot, &bytes);
    let c = &m.curves[0];
    let truth = &shot.truth().unwrap().rows;
    for (src, chart) in [("scan", &scan), ("dots", &ChartMtf::Model(dots))] {
        let cc = chart_curve(c, chart).unwrap();
        let (mut se, mut n) = (0.0, 0);
        for (i, p) in c.points.iter().enumerate() {
            let pm = dots.mtf(p.freq_chart);
            let beyond_zero = p.freq_chart > 150.0 / 25.4;
            if (pm < 0.29 || beyond_zero) && !p.aliased {
                assert_ne!(cc.flag[i], ChartFlag::Ok, "{src}: {} cy/mm", p.freq_chart);
            }
            if cc.flag[i] == ChartFlag::Ok && pm >= 0.3 {
                let t = sweepmtf::simulate::mtf_at(truth, p.freq_cy_px);
                se += (cc.camera_mtf[i] - t).powi(2);
                n += 1;
            }
        }
        let rms = (se / n.max(1) as f64).sqrt();
        eprintln!("dots 150 dpi / {src}: camera RMS {rms:.4} over {n} points");
        assert!(n >= 30 && rms <= 0.01, "{src}: {rms} over {n}");
    }
}

/// A perfect print compensated by a perfect model changes nothing; a print
/// MTF of 0 everywhere (σ huge) flags every point.
#[test]
fn extreme_prints() {
    let (shot, bytes) = shoot(
        &Camera {
            print_blur: None,
            ..camera()
        },
        &optics(0.6),
        PhotoFormat::Png,
    );
    let m = measure(&shot, &bytes);
    let c = &m.curves[0];
    let same = chart_curve(c, &ChartMtf::Model(PrintMtf::Gaussian { sigma_mm: 0.0 })).unwrap();
    for (p, (v, f)) in c.points.iter().zip(same.camera_mtf.iter().zip(&same.flag)) {
        if p.aliased {
            assert_eq!(*f, ChartFlag::Aliased);
        } else {
            assert_eq!(*f, ChartFlag::Ok);
            assert_eq!(*v, p.mtf);
        }
    }
    let gone = chart_curve(c, &ChartMtf::Model(PrintMtf::Gaussian { sigma_mm: 5.0 })).unwrap();
    assert!(
        gone.flag
            .iter()
            .all(|f| matches!(f, ChartFlag::BelowFloor | ChartFlag::Aliased))
    );
    assert!(gone.camera_mtf.iter().all(|v| v.is_nan()));
}

fn roi_arg(shot: &Shot) -> String {
    shot.target_corners
        .iter()
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(",")
}

/// The CLI end to end: the scan measured with `--lens-mtf`, its CSV given to
/// `--chart-mtf` for the camera shot: columns, flags, summary, plot; refusals
/// (no target: exit 2; bad model: 2; missing file: 3) write nothing.
#[test]
fn cli_scan_then_camera() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let toml = d.join("print.toml");
    std::fs::write(&toml, target().to_toml()).unwrap();
    let (scan, scan_bytes) = shoot(&scanner(), &optics(0.0), PhotoFormat::Png);
    std::fs::write(d.join("scan.png"), scan_bytes).unwrap();
    // Softer optics (σ 0.8 px) than the bar's, so that the camera's MTF50 (≈ 0.21 cy/px) lies where the print allows.
    let (cam, cam_bytes) = shoot(&camera(), &optics(0.8), PhotoFormat::Png);
    std::fs::write(d.join("cam.png"), cam_bytes).unwrap();
    let run = |photo: &str, roi: &str, extra: &[&str], out: &str| {
        Command::cargo_bin("sweepmtf")
            .unwrap()
            .arg("measure")
            .arg(d.join(photo))
            .arg("--target")
            .arg(&toml)
            .args(["--roi", roi, "--no-refine-roi", "--pixel-pitch", "4.3um"])
            .args(extra)
            .arg("-o")
            .arg(d.join(out))
            .assert()
    };
    run("scan.png", &roi_arg(&scan), &["--lens-mtf"], "scan_out").success();
    let table = d.join("scan_out/scan.mtf.csv");
    let a = run(
        "cam.png",
        &roi_arg(&cam),
        &["--chart-mtf", table.to_str().unwrap()],
        "cam_out",
    )
    .success();
    let line = String::from_utf8_lossy(&a.get_output().stdout).into_owned();
    assert!(line.contains("camera MTF50"), "{line}");
    let rows = crate::csv_support::read_csv(&d.join("cam_out/cam.mtf.csv"));
    // The warning: where the print stops being sharp enough (its MTF < 0.99),
    // within one point of where the closed-form print falls below 0.99.
    let err = String::from_utf8_lossy(&a.get_output().stderr).into_owned();
    let said: f64 = err
        .split("the print's MTF is below 0.99 from ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .unwrap_or_else(|| panic!("no sharpness warning: {err}"))
        .parse()
        .unwrap();
    let fs: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r["aliased"] == "false")
        .map(|r| {
            (
                r["freq_cy_px"].parse().unwrap(),
                r["freq_chart_cy_mm"].parse().unwrap(),
            )
        })
        .collect();
    let k = fs.iter().position(|&(_, fc)| print_mtf(fc) < 0.99).unwrap();
    let step = fs[k.max(1)].0 - fs[k.max(1) - 1].0;
    assert!(
        (said - fs[k].0).abs() <= 1.5 * step,
        "warned from {said}, closed form {}",
        fs[k].0
    );
    // A print sharp enough everywhere: no such warning.
    let sharp = run(
        "cam.png",
        &roi_arg(&cam),
        &["--chart-mtf", "gaussian:sigma=0.0001mm"],
        "cam_sharp",
    )
    .success();
    let err = String::from_utf8_lossy(&sharp.get_output().stderr).into_owned();
    assert!(!err.contains("print's MTF is below"), "{err}");
    let truth = &cam.truth().unwrap().rows;
    let (mut ok, mut below, mut se) = (0, 0, 0.0);
    for r in &rows {
        let fc: f64 = r["freq_chart_cy_mm"].parse().unwrap();
        let f: f64 = r["freq_cy_px"].parse().unwrap();
        match r["chart_flag"].as_str() {
            "ok" => {
                let v: f64 = r["camera_mtf"].parse().unwrap();
                let ch: f64 = r["chart_mtf"].parse().unwrap();
                assert!(ch >= 0.3 && r["camera_mtf_err"].parse::<f64>().unwrap() > 0.0);
                assert!(print_mtf(fc) > 0.29, "{r:?}");
                se += (v - sweepmtf::simulate::mtf_at(truth, f)).powi(2);
                ok += 1;
            }
            "chart_below_floor" | "outside_chart_file" => {
                assert!(
                    r["camera_mtf"].is_empty() && r["camera_mtf_err"].is_empty(),
                    "{r:?}"
                );
                below += 1;
            }
            "aliased" => assert_eq!(r["aliased"], "true"),
            other => panic!("flag {other}"),
        }
    }
    let rms = (se / ok as f64).sqrt();
    eprintln!("CLI: {ok} given (RMS {rms:.4}), {below} refused");
    assert!(ok > 30 && below > 20 && rms <= 0.01, "{ok} {below} {rms}");
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("cam_out/cam.summary.json")).unwrap())
            .unwrap();
    assert_eq!(v["chart_mtf"]["floor"], 0.3);
    assert!(
        v["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w.as_str().unwrap().contains("print's MTF is below 0.99")),
        "{}",
        v["warnings"]
    );
    assert!(
        v["chart_mtf"]["source"]
            .as_str()
            .unwrap()
            .ends_with("(lens_mtf)")
    );
    let c0 = &v["curves"][0];
    let (cam50, raw50) = (
        c0["camera_mtf50_cy_px"].as_f64().unwrap(),
        c0["mtf50"]["cy_px"].as_f64().unwrap(),
    );
    // The truth's MTF50: exp(−2π²σ²f²)·sinc(f) = 0.5, σ = 0.8 px.
    let truth50 = {
        let g = |f: f64| (-2.0 * PI * PI * 0.64 * f * f).exp() * (PI * f).sin() / (PI * f) - 0.5;
        let (mut a, mut b) = (0.01, 0.4);
        for _ in 0..60 {
            let m = 0.5 * (a + b);
            if g(m) > 0.0 { a = m } else { b = m }
        }
        a
    };
    eprintln!("CLI: MTF50 measured {raw50:.4}, camera {cam50:.4}, truth {truth50:.4} cy/px");
    assert!((cam50 / truth50 - 1.0).abs() < 0.01 && raw50 < 0.95 * truth50);
    assert!(c0["chart_points_below_floor"].as_u64().unwrap() > 0);
    assert!(d.join("cam_out/cam.mtf.png").exists());
    if let Ok(keep) = std::env::var("SWEEPMTF_PREVIEW") {
        std::fs::create_dir_all(&keep).unwrap();
        std::fs::copy(
            d.join("cam_out/cam.mtf.png"),
            Path::new(&keep).join("chart_mtf.png"),
        )
        .unwrap();
    }
    // Without a target: the strip's corners and its printed length (30 mm).
    let strip_roi = cam
        .roi()
        .unwrap()
        .iter()
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(",");
    let out = d.join("strip_out");
    Command::cargo_bin("sweepmtf")
        .unwrap()
        .arg("measure")
        .arg(d.join("cam.png"))
        .args(["--roi", &strip_roi, "--no-refine-roi", "--sweep", "log"])
        .args([
            "--chart-mtf",
            "gaussian:sigma=0.05mm",
            "--chart-length",
            "30mm",
        ])
        .arg("-o")
        .arg(&out)
        .assert()
        .success();
    let rows = crate::csv_support::read_csv(&out.join("cam.mtf.csv"));
    let (mut n, mut se) = (0, 0.0);
    for r in rows.iter().filter(|r| r["chart_flag"] == "ok") {
        let f: f64 = r["freq_cy_px"].parse().unwrap();
        let v: f64 = r["camera_mtf"].parse().unwrap();
        se += (v - sweepmtf::simulate::mtf_at(truth, f)).powi(2);
        n += 1;
    }
    let rms = (se / n as f64).sqrt();
    eprintln!("CLI without target, --chart-length 30mm: {n} given, RMS {rms:.4}");
    assert!(n > 30 && rms <= 0.01);
    // Refusals: one line on stderr, the documented code, nothing written.
    let cases: [(&[&str], i32, &str, bool); 4] = [
        (
            &["--chart-mtf", "gaussian:sigma=0.05mm"],
            2,
            "--target",
            false,
        ),
        (
            &[
                "--chart-mtf",
                "gaussian:sigma=0.05mm",
                "--chart-length",
                "0mm",
            ],
            2,
            "--chart-length",
            false,
        ),
        (
            &["--chart-mtf", "gaussian:sigma=0.05"],
            2,
            "--chart-mtf",
            true,
        ),
        (
            &["--chart-mtf", "/nonexistent/p.mtf.csv"],
            3,
            "p.mtf.csv",
            true,
        ),
    ];
    for (i, (extra, code, word, with_target)) in cases.iter().enumerate() {
        let out = d.join(format!("bad{i}"));
        let mut cmd = Command::cargo_bin("sweepmtf").unwrap();
        cmd.arg("measure").arg(d.join("cam.png"));
        if *with_target {
            cmd.arg("--target").arg(&toml);
        }
        let a = cmd
            .args(["--roi", &roi_arg(&cam)])
            .args(*extra)
            .arg("-o")
            .arg(&out)
            .assert()
            .code(*code);
        let err = String::from_utf8_lossy(&a.get_output().stderr).into_owned();
        assert!(err.contains(word) && err.lines().count() == 1, "{err}");
        assert!(!out.join("cam.mtf.csv").exists());
    }
}
