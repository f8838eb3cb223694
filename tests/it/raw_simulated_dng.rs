//! The whole raw path from the command line: `simulate --bayer RGGB -o X.dng`
//! writes a camera-raw DNG of a shot with known truth, and
//! `measure X.dng --target T --channel g` finds the chart from its fiducials
//! on the green sites and measures the green-site MTF without demosaicing.
//! The result is held to `measure`'s bars against the simulator's truth CSV
//! (RMS ≤ 0.005 noiseless, ≤ 0.015 with shot and read noise), over the
//! greens' unaliased band up to 0.45 cy/px (both green lattices together
//! are a quincunx, whose band reaches 0.5 cy/px along x).

use assert_cmd::Command;
use std::path::Path;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

use crate::csv_support;
use csv_support::{read_csv, truth_at};

/// Simulates `extra` settings into a DNG, measures its green sites with
/// automatic location; returns (RMS |MTF − truth| of sweep `main`, points, summary JSON).
fn simulate_and_measure(extra: &[&str]) -> (f64, usize, serde_json::Value) {
    let dir = tempfile::tempdir().unwrap();
    let dng = dir.path().join("shot.dng");
    let target = Path::new(ROOT).join("targets/a4_log.toml");
    Command::cargo_bin("sweepmtf")
        .unwrap()
        .args(["simulate", "--target"])
        .arg(&target)
        .args(["--size", "1200x800", "--bayer", "RGGB", "-o"])
        .arg(&dng)
        .args(extra)
        .assert()
        .success();
    let out = dir.path().join("out");
    Command::cargo_bin("sweepmtf")
        .unwrap()
        .arg("measure")
        .arg(&dng)
        .arg("--target")
        .arg(&target)
        .args(["--channel", "g", "--json", "-o"])
        .arg(&out)
        .assert()
        .success();
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("shot.summary.json")).unwrap()).unwrap();
    let truth: Vec<(f64, f64)> = read_csv(&dir.path().join("shot.truth.csv"))
        .iter()
        .map(|r| (r["freq_cy_px"].parse().unwrap(), r["mtf"].parse().unwrap()))
        .collect();
    let rows = read_csv(&out.join("shot.mtf.csv"));
    let errs: Vec<f64> = rows
        .iter()
        .filter(|r| r.get("sweep").is_none_or(|s| s == "main") && r["aliased"] == "false")
        .filter_map(|r| {
            let f: f64 = r["freq_cy_px"].parse().unwrap();
            let mtf = r.get("mtf").or_else(|| r.get("mtf_g")).unwrap();
            // The grey images' band: 0.01–0.45 cy/px (the two greens reach 0.5 along x).
            (0.01..=0.45)
                .contains(&f)
                .then(|| mtf.parse::<f64>().unwrap() - truth_at(&truth, f))
        })
        .collect();
    let rms = (errs.iter().map(|e| e * e).sum::<f64>() / errs.len().max(1) as f64).sqrt();
    (rms, errs.len(), summary)
}

#[test]
fn green_sites_of_a_noiseless_simulated_dng_meet_the_bar() {
    let (rms, n, summary) = simulate_and_measure(&[]);
    eprintln!("noiseless: RMS {rms:.5} over {n} points");
    assert!(n > 30, "only {n} unaliased points");
    assert!(rms <= 0.005, "RMS {rms} over {n} points");
    // The pitch comes from the DNG's EXIF focal-plane resolution (4.3 µm by default).
    let pitch = summary["pixel_pitch_um"].as_f64().unwrap();
    assert!((pitch - 4.3).abs() < 1e-3, "{summary}");
}

#[test]
fn green_sites_of_a_noisy_simulated_dng_meet_the_bar() {
    let (rms, n, _) = simulate_and_measure(&["--full-well", "20000", "--read-noise", "5"]);
    eprintln!("noisy: RMS {rms:.5} over {n} points");
    assert!(n > 30, "only {n} unaliased points");
    assert!(rms <= 0.015, "RMS {rms} over {n} points");
}
