//! `measure --model`: the model beside the measurement, checked against the
//! simulator's truth (the presampling MTF the simulator computes along the
//! sweep, STEM.truth.csv, independently of the overlay code), plus bad input.

use assert_cmd::Command;
use std::path::{Path, PathBuf};

use crate::patch_shot;
use patch_shot::SYSTEM;

fn cmd() -> Command {
    Command::cargo_bin("sweepmtf").unwrap()
}

/// Simulates a demo shot with `SYSTEM`; returns (photo, ROI argument, truth rows (freq_cy_px, mtf)).
fn shot(dir: &Path, extra: &[&str]) -> (PathBuf, String, Vec<(f64, f64)>) {
    let photo = dir.join("shot.png");
    cmd()
        .args(["simulate", "--target", "demo:linear", "--system", SYSTEM])
        .args(["--size", "1200x800"])
        .args(extra)
        .arg("-o")
        .arg(&photo)
        .assert()
        .success();
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("shot.json")).unwrap()).unwrap();
    let roi: Vec<String> = meta["sweeps"][0]["roi"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| format!("{}", v.as_f64().unwrap()))
        .collect();
    let mut r = csv::Reader::from_path(dir.join("shot.truth.csv")).unwrap();
    let truth = r
        .deserialize::<(f64, f64, f64, f64, f64, f64, f64)>()
        .map(|row| {
            let row = row.unwrap();
            (row.0, row.1)
        })
        .collect();
    (photo, roi.join(","), truth)
}

/// The ROI argument back as four corners.
fn corners(roi: &str) -> [[f64; 2]; 4] {
    let v: Vec<f64> = roi.split(',').map(|t| t.parse().unwrap()).collect();
    [[v[0], v[1]], [v[2], v[3]], [v[4], v[5]], [v[6], v[7]]]
}

/// Truth interpolated linearly at `f` (rows sorted by frequency).
fn truth_at(truth: &[(f64, f64)], f: f64) -> Option<f64> {
    let i = truth.partition_point(|r| r.0 < f);
    if i == 0 || i >= truth.len() {
        return None;
    }
    let (a, b) = (truth[i - 1], truth[i]);
    Some(a.1 + (b.1 - a.1) * (f - a.0) / (b.0 - a.0))
}

fn check(extra: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let (photo, roi, truth) = shot(dir.path(), extra);
    assert!(truth.len() > 100);

    // Library: the model at the truth's own frequencies, along the measured strip's direction.
    let opts = sweepmtf::measure::MeasureOptions {
        roi: Some(corners(&roi)),
        pixel_pitch_mm: Some(0.0043),
        ..Default::default()
    };
    let m = sweepmtf::measure::measure_file(&photo, &opts).unwrap();
    use sweepmtf::measure::model_overlay::{ModelOverlay, ModelSource, sweep_direction};
    let src = ModelSource::from_file(Path::new(SYSTEM)).unwrap();
    let o = ModelOverlay::build(src, &Default::default(), Some(0.0043), 550e-6).unwrap();
    let d = sweep_direction(&m.curves[0]);
    let worst = truth
        .iter()
        .map(|&(f, t)| (o.mtf_cy_px(d, f) - t).abs())
        .fold(0.0, f64::max);
    assert!(
        worst <= 1e-6,
        "model vs truth at truth frequencies: {worst:e}"
    );

    // CLI: the mtf_model column against the truth, and the MTF50 ratio.
    let out = dir.path().join("out");
    let a = cmd()
        .arg("measure")
        .arg(&photo)
        .args(["--roi", &roi, "--pixel-pitch", "4.3um", "--model", SYSTEM])
        .arg("-o")
        .arg(&out)
        .assert()
        .success();
    let line = String::from_utf8_lossy(&a.get_output().stdout).into_owned();
    assert!(line.contains("measured/model"), "{line}");
    let mut r = csv::Reader::from_path(out.join("shot.mtf.csv")).unwrap();
    let head = r.headers().unwrap().clone();
    let col = |n: &str| head.iter().position(|h| h == n).unwrap();
    let (fc, mc) = (col("freq_cy_px"), col("mtf_model"));
    let mut n = 0;
    let mut worst = 0.0f64;
    for rec in r.records() {
        let rec = rec.unwrap();
        let f: f64 = rec[fc].parse().unwrap();
        let v: f64 = rec[mc].parse().unwrap();
        if let Some(t) = truth_at(&truth, f) {
            worst = worst.max((v - t).abs());
            n += 1;
        }
    }
    assert!(n > 50, "{n}");
    // The CSV carries 6 decimals in both frequency and MTF (≤ 5e-7 each) plus
    // linear interpolation of the dense truth: 3e-6.
    assert!(worst <= 3e-6, "CSV mtf_model vs truth: {worst:e}");
    let s: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("shot.summary.json")).unwrap()).unwrap();
    let ratio = s["curves"][0]["mtf50_measured_over_model"]
        .as_f64()
        .unwrap();
    assert!((ratio - 1.0).abs() < 0.03, "measured/model MTF50 {ratio}");
    let model50 = s["curves"][0]["mtf50_model"]["cy_px"].as_f64().unwrap();
    // The truth's own MTF50 crossing, from the simulator's rows.
    let i = truth.iter().position(|r| r.1 <= 0.5).unwrap();
    let (a, b) = (truth[i - 1], truth[i]);
    let truth50 = a.0 + (b.0 - a.0) * (a.1 - 0.5) / (a.1 - b.1);
    assert!((model50 - truth50).abs() < 1e-5, "{model50} vs {truth50}");
    assert_eq!(s["model"]["factors_left_out"][0], "sampling_rect");
    assert!(s["exif"].is_object());
}

#[test]
fn model_column_matches_simulator_truth_straight() {
    check(&[]);
}

#[test]
fn model_column_matches_simulator_truth_rotated() {
    check(&["--rotate", "12", "--oversample", "4"]);
}

#[test]
fn auto_without_f_number_is_a_usage_error() {
    let dir = tempfile::tempdir().unwrap();
    let (photo, roi, _) = shot(dir.path(), &[]);
    let a = cmd()
        .arg("measure")
        .arg(&photo)
        .args(["--roi", &roi, "--pixel-pitch", "4.3um", "--model", "auto"])
        .arg("-o")
        .arg(dir.path())
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr).into_owned();
    assert!(err.contains("f-number"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}

#[test]
fn model_without_pitch_is_a_usage_error_and_missing_file_an_input_error() {
    let dir = tempfile::tempdir().unwrap();
    let (photo, roi, _) = shot(dir.path(), &[]);
    let a = cmd()
        .arg("measure")
        .arg(&photo)
        .args(["--roi", &roi, "--model", SYSTEM])
        .arg("-o")
        .arg(dir.path())
        .assert()
        .code(2);
    let err = String::from_utf8_lossy(&a.get_output().stderr).into_owned();
    assert!(err.contains("pixel pitch"), "{err}");
    let missing = dir.path().join("no_such_system.toml");
    let a = cmd()
        .arg("measure")
        .arg(&photo)
        .args(["--roi", &roi, "--pixel-pitch", "4.3um", "--model"])
        .arg(&missing)
        .arg("-o")
        .arg(dir.path())
        .assert()
        .code(3);
    let err = String::from_utf8_lossy(&a.get_output().stderr).into_owned();
    assert!(err.contains("no_such_system.toml"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}

/// `auto` with a real camera's EXIF (the Canon PowerShot S40 file's APP1 segment
/// put into a simulated shot): diffraction at its f/4.9, the caption facts in
/// the summary, and the model column against the closed form
/// (2/π)(acos s − s√(1−s²))·|sinc f|, s = (f/p)·λ·N.
#[test]
fn auto_uses_the_exif_f_number() {
    let canon = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/testdata/real/exif_jpeg/canon_powershot_s40_downscaled.jpg"
    );
    let src = std::fs::read(canon).expect("testdata/real is part of the repository");
    let dir = tempfile::tempdir().unwrap();
    let jpg = dir.path().join("shot.jpg");
    cmd()
        .args(["simulate", "--target", "demo:linear", "--system", SYSTEM])
        .args(["--size", "1200x800", "--jpeg", "95", "-o"])
        .arg(&jpg)
        .assert()
        .success();
    let dst = std::fs::read(&jpg).unwrap();
    let mut i = 2;
    let app1 = loop {
        let len = u16::from_be_bytes([src[i + 2], src[i + 3]]) as usize;
        if src[i + 1] == 0xE1 && &src[i + 4..i + 8] == b"Exif" {
            break &src[i..i + 2 + len];
        }
        i += 2 + len;
    };
    let photo = dir.path().join("canon.jpg");
    std::fs::write(&photo, [&dst[..2], app1, &dst[2..]].concat()).unwrap();
    let out = dir.path().join("out");
    cmd()
        .arg("measure")
        .arg(&photo)
        .args(["--roi", "200,200,1000,200,1000,400,200,400"])
        .args(["--pixel-pitch", "4.3um", "--model", "auto", "-o"])
        .arg(&out)
        .assert()
        .success();
    let s: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("canon.summary.json")).unwrap()).unwrap();
    assert_eq!(s["exif"]["f_number"].as_f64(), Some(4.9));
    let desc = s["exif"]["description"].as_str().unwrap();
    assert!(
        desc.contains("Canon PowerShot S40") && desc.contains("f/4.9"),
        "{desc}"
    );
    let mut r = csv::Reader::from_path(out.join("canon.mtf.csv")).unwrap();
    let head = r.headers().unwrap().clone();
    let col = |n: &str| head.iter().position(|h| h == n).unwrap();
    let (fc, mc) = (col("freq_cy_px"), col("mtf_model"));
    let pi = std::f64::consts::PI;
    let mut n = 0;
    for rec in r.records() {
        let rec = rec.unwrap();
        let f: f64 = rec[fc].parse().unwrap();
        let v: f64 = rec[mc].parse().unwrap();
        let s = f / 0.0043 * 550e-6 * 4.9;
        let want =
            2.0 / pi * (s.acos() - s * (1.0 - s * s).sqrt()) * ((pi * f).sin() / (pi * f)).abs();
        assert!((v - want).abs() < 2e-6, "{f}: {v} vs {want}");
        n += 1;
    }
    assert!(n > 50, "{n}");
}

/// Sine patches get `mtf_model` too: the model along each patch's sine at its
/// measured frequency, against the simulator's own patch truth (STEM.patches.csv).
#[test]
fn patch_model_matches_simulator_patch_truth() {
    let dir = tempfile::tempdir().unwrap();
    let (photo, roi) = patch_shot::shot(dir.path());
    let out = dir.path().join("out");
    cmd()
        .arg("measure")
        .arg(&photo)
        .args([
            "--target",
            patch_shot::TARGET,
            "--roi",
            &roi,
            "--no-refine-roi",
        ])
        .args(["--pixel-pitch", "4.3um", "--model", SYSTEM, "-o"])
        .arg(&out)
        .assert()
        .success();
    let truth: std::collections::HashMap<String, f64> =
        csv::Reader::from_path(dir.path().join("shot.patches.csv"))
            .unwrap()
            .records()
            .map(|r| {
                let r = r.unwrap();
                (r[0].to_string(), r[2].parse().unwrap())
            })
            .collect();
    let mut r = csv::Reader::from_path(out.join("shot.mtf.csv")).unwrap();
    let head = r.headers().unwrap().clone();
    let col = |name: &str| head.iter().position(|h| h == name).unwrap();
    let (id, model) = (col("patch"), col("mtf_model"));
    let mut n = 0;
    for rec in r.records() {
        let rec = rec.unwrap();
        let want = truth[&rec[id]];
        let got: f64 = rec[model].parse().unwrap();
        assert!((got - want).abs() < 1e-3, "{}: {got} vs {want}", &rec[id]);
        n += 1;
    }
    assert_eq!(n, truth.len());
}
