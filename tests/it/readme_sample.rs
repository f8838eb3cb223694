//! The README's main command, end to end: the shipped sample shot of the A4 log
//! chart (simulated with rotation, tilt, fall-off, noise and JPEG q90) is
//! located from its fiducials and measured with no corners given; every sweep
//! row is checked against the simulator's own truth curve (written by
//! `simulate`, not by the code under test).

use assert_cmd::Command;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

use crate::csv_support;
use csv_support::{read_csv, truth_at};

#[test]
fn main_command_measures_the_sample_without_corners() {
    let out = tempfile::tempdir().unwrap();
    Command::cargo_bin("sweepmtf")
        .unwrap()
        .current_dir(ROOT)
        .args([
            "measure",
            "testdata/a4_log_shot.jpg",
            "--target",
            "targets/a4_log.toml",
            "-o",
        ])
        .arg(out.path())
        .assert()
        .success();
    for f in ["mtf.csv", "summary.json", "mtf.png", "roi.png"] {
        assert!(
            out.path().join(format!("a4_log_shot.{f}")).is_file(),
            "{f} missing"
        );
    }
    // Bars: issue 5 (noise + JPEG q90, rotation, tilt) for the 0.8 row; the
    // 0.2-contrast row is the low-modulation case (≤ 0.04).
    let csv_path = out.path().join("a4_log_shot.mtf.csv");
    for (sweep, bar) in [("main", 0.015), ("c0.4", 0.015), ("c0.2", 0.04)] {
        let rms = rms_vs_truth(&csv_path, sweep);
        assert!(rms <= bar, "{sweep}: RMS {rms:.4} > {bar}");
    }
}

/// The real photo of another chart design, in testdata/real.
fn real_chart_photo() -> std::path::PathBuf {
    std::path::Path::new(ROOT)
        .join("testdata/real/chart_photo/mtfmapper_perspective_chart_photo.jpg")
}

/// Issue 7: a real photo of another chart design gives "no chart found" (exit 4),
/// the picture of what was seen, and no measurement files.
#[test]
fn no_chart_found_writes_what_was_seen_and_nothing_else() {
    let photo = real_chart_photo();
    let out = tempfile::tempdir().unwrap();
    let assert = Command::cargo_bin("sweepmtf")
        .unwrap()
        .current_dir(ROOT)
        .arg("measure")
        .arg(&photo)
        .args(["--target", "targets/a4_log.toml", "-o"])
        .arg(out.path())
        .assert()
        .code(4);
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).to_string();
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("no chart found"), "{stderr}");
    let names: Vec<String> = std::fs::read_dir(out.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(
        names,
        vec!["mtfmapper_perspective_chart_photo.roi.png".to_string()]
    );
}

/// RMS |MTF − truth| over 0.01–0.45 cy/px of one sweep row of a measured CSV.
fn rms_vs_truth(csv_path: &std::path::Path, sweep: &str) -> f64 {
    let truth: Vec<(f64, f64)> =
        read_csv(&std::path::Path::new(ROOT).join("testdata/a4_log_shot.truth.csv"))
            .iter()
            .map(|r| (r["freq_cy_px"].parse().unwrap(), r["mtf"].parse().unwrap()))
            .collect();
    let errs: Vec<f64> = read_csv(csv_path)
        .iter()
        .filter(|r| r["sweep"] == sweep && r["aliased"] == "false")
        .filter_map(|r| {
            let f: f64 = r["freq_cy_px"].parse().unwrap();
            (0.01..=0.45)
                .contains(&f)
                .then(|| r["mtf"].parse::<f64>().unwrap() - truth_at(&truth, f))
        })
        .collect();
    assert!(errs.len() > 50, "{sweep}: only {} points", errs.len());
    (errs.iter().map(|e| e * e).sum::<f64>() / errs.len() as f64).sqrt()
}

/// Issue 7: target corners given ±5 px off are refined to the chart's edges, so
/// the result stays within the bar of the exactly placed shot.
#[test]
fn refine_roi_absorbs_five_pixel_corner_errors() {
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(std::path::Path::new(ROOT).join("testdata/a4_log_shot.json"))
            .unwrap(),
    )
    .unwrap();
    let exact: Vec<f64> = json["target_corners"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|p| match p.as_array() {
            Some(xy) => xy.iter().map(|v| v.as_f64().unwrap()).collect::<Vec<_>>(),
            None => vec![p.as_f64().unwrap()],
        })
        .collect();
    assert_eq!(exact.len(), 8);
    let offsets = [5.0, -4.0, -5.0, 3.0, 4.0, 5.0, -3.0, -5.0];
    let roi: Vec<String> = exact
        .iter()
        .zip(offsets)
        .map(|(v, d)| format!("{}", v + d))
        .collect();
    let out = tempfile::tempdir().unwrap();
    let assert = Command::cargo_bin("sweepmtf")
        .unwrap()
        .current_dir(ROOT)
        .args([
            "measure",
            "testdata/a4_log_shot.jpg",
            "--target",
            "targets/a4_log.toml",
            "--refine-roi",
            "-v",
            "--roi",
        ])
        .arg(roi.join(","))
        .arg("-o")
        .arg(out.path())
        .assert()
        .success();
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).to_string();
    assert!(stderr.contains("refined"), "{stderr}");
    let rms = rms_vs_truth(&out.path().join("a4_log_shot.mtf.csv"), "main");
    assert!(rms <= 0.005, "main row RMS {rms:.4} after refinement");
}

/// A failed location never clobbers the picture of an earlier result in the same folder.
#[test]
fn no_chart_found_keeps_an_earlier_region_picture() {
    let photo = real_chart_photo();
    let out = tempfile::tempdir().unwrap();
    let stem = "mtfmapper_perspective_chart_photo";
    std::fs::write(out.path().join(format!("{stem}.mtf.csv")), "earlier").unwrap();
    std::fs::write(out.path().join(format!("{stem}.roi.png")), "earlier").unwrap();
    Command::cargo_bin("sweepmtf")
        .unwrap()
        .current_dir(ROOT)
        .arg("measure")
        .arg(&photo)
        .args(["--target", "targets/a4_log.toml", "-o"])
        .arg(out.path())
        .assert()
        .code(4);
    for f in ["mtf.csv", "roi.png"] {
        let kept = std::fs::read_to_string(out.path().join(format!("{stem}.{f}"))).unwrap();
        assert_eq!(kept, "earlier", "{f} was overwritten");
    }
    assert!(out.path().join(format!("{stem}.seen.png")).is_file());
}
