//! Lens distortion estimated where it was not before (issue 15 item 3): with
//! a target (its sweep strips are straight on the card, so their long edges
//! give the distortion as a hand strip's do) and in camera raws (from one
//! green lattice). Shots from the camera simulator (A4 log target, three sweeps of
//! contrast 0.8 / 0.4 / 0.2, region found from the fiducials), measured with
//! `--target` and default settings; truth: the simulator's MTF50 per sweep.

use assert_cmd::Command;
use serde_json::Value;
use std::path::Path;

/// The simulator's true MTF50 (cy/px) in a truth CSV: the first fall through 0.5.
fn true_mtf50(csv: &Path) -> f64 {
    let rows = crate::csv_support::read_csv(csv);
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .map(|r| (r["freq_cy_px"].parse().unwrap(), r["mtf"].parse().unwrap()))
        .collect();
    let k = pts
        .windows(2)
        .position(|w| w[0].1 >= 0.5 && w[1].1 < 0.5)
        .expect("truth falls through 0.5");
    let ((f0, m0), (f1, m1)) = (pts[k], pts[k + 1]);
    f0 + (0.5 - m0) * (f1 - f0) / (m1 - m0)
}

/// Simulates `name` with `extra` flags, measures it with the target (plus
/// `measure_extra`), and returns the summary and each sweep's MTF50 error.
fn shoot_and_measure(
    dir: &Path,
    name: &str,
    extra: &[&str],
    measure_extra: &[&str],
) -> (Value, Vec<(String, f64)>) {
    let target = Path::new(env!("CARGO_MANIFEST_DIR")).join("targets/a4_log.toml");
    let photo = dir.join(name);
    if !photo.exists() {
        Command::cargo_bin("sweepmtf")
            .unwrap()
            .args(["simulate", "--size", "2400x1600", "--full-well", "9000"])
            .args(["--read-noise", "4", "-q", "--target"])
            .arg(&target)
            .args(extra)
            .arg("-o")
            .arg(&photo)
            .assert()
            .success();
    }
    let out = dir.join(format!("out_{name}_{}", measure_extra.len()));
    Command::cargo_bin("sweepmtf")
        .unwrap()
        .arg("measure")
        .arg(&photo)
        .arg("--target")
        .arg(&target)
        .args(measure_extra)
        .args(["-q", "-o"])
        .arg(&out)
        .assert()
        .success();
    let stem = name.rsplit_once('.').unwrap().0;
    let summary: Value = serde_json::from_str(
        &std::fs::read_to_string(out.join(format!("{stem}.summary.json"))).unwrap(),
    )
    .unwrap();
    let errs = summary["curves"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            let id = c["sweep"].as_str().unwrap().to_string();
            let suffix = if id == "main" {
                String::new()
            } else {
                format!(".{id}")
            };
            let truth = true_mtf50(&dir.join(format!("{stem}.truth{suffix}.csv")));
            let got = c["mtf50"]["cy_px"].as_f64().unwrap();
            (id, got / truth - 1.0)
        })
        .collect();
    (summary, errs)
}

#[test]
fn a_targets_strips_give_the_distortion_and_every_sweep_holds_mtf50() {
    let dir = tempfile::tempdir().unwrap();
    // Pincushion 3.6 % at the corner, PNG; barrel −2.9 % on a turned and
    // tilted card, JPEG q90. Before, a target was binned as if undistorted.
    for (name, b, extra, bar) in [
        (
            "pin.png",
            0.016,
            &["--distortion", "ptlens:a=0,b=0.016,c=0", "--seed", "3"][..],
            0.01,
        ),
        (
            "barrel.jpg",
            -0.013,
            &[
                "--distortion",
                "ptlens:a=0,b=-0.013,c=0",
                "--seed",
                "4",
                "--rotate",
                "3",
                "--tilt",
                "15",
                "--jpeg",
                "90",
            ][..],
            0.02,
        ),
    ] {
        let mut flags = vec!["--optics", "diffraction:lambda=0.55um,fnum=5.6"];
        flags.extend_from_slice(extra);
        let (summary, errs) = shoot_and_measure(dir.path(), name, &flags, &[]);
        let d = &summary["distortion"];
        assert_eq!(d["source"], "estimated", "{name}: {d}");
        let found = d["b"].as_f64().unwrap();
        assert!((found / b - 1.0).abs() < 0.03, "{name}: b {found} for {b}");
        eprintln!("{name}: b {found:.5}, MTF50 errors {errs:?}");
        assert_eq!(errs.len(), 3);
        for (id, e) in &errs {
            assert!(e.abs() <= bar, "{name} {id}: MTF50 off by {e:+.4}");
        }
        // Without the estimate the same shot is far off on some sweep.
        let (_, off) = shoot_and_measure(dir.path(), name, &flags, &["--no-estimate-distortion"]);
        let worst = off.iter().map(|(_, e)| e.abs()).fold(0.0, f64::max);
        assert!(worst > 0.05, "{name}: undistorted worst {worst:.4}");
    }
}

#[test]
fn an_undistorted_target_shot_gets_no_model() {
    let dir = tempfile::tempdir().unwrap();
    let (summary, errs) = shoot_and_measure(
        dir.path(),
        "plain.png",
        &[
            "--optics",
            "diffraction:lambda=0.55um,fnum=4",
            "--seed",
            "5",
        ],
        &[],
    );
    assert_eq!(summary["distortion"]["source"], "negligible");
    for (id, e) in &errs {
        assert!(e.abs() <= 0.01, "{id}: MTF50 off by {e:+.4}");
    }
}

/// A camera-raw DNG (RGGB, simulated) of a strip bent by a 3.9 % pincushion,
/// strip corners only: the distortion is found in the green sites and MTF50
/// matches the undistorted shot's. Without it MTF50 read 2.3 % high (4 %
/// before session 27 placed each point where its window reads it), beyond
/// the 1 % bar; since session 34 the phase law's foreshortening, read from
/// the phase, follows most of the pincushion's stretch along the strip
/// (−0.2 %), so ignoring it now stays within the bar too.
#[test]
fn a_raw_strip_gives_the_distortion_from_its_green_sites() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, extra: &[&str], measure_extra: &[&str]| -> Value {
        let photo = dir.path().join(name);
        if !photo.exists() {
            Command::cargo_bin("sweepmtf")
                .unwrap()
                .args(["simulate", "--target", "demo:log", "--size", "1100x700"])
                .args([
                    "--chart-px",
                    "900",
                    "--rotate",
                    "1.5",
                    "--full-well",
                    "9000",
                ])
                .args(["--read-noise", "4", "--seed", "1", "--bayer", "RGGB", "-q"])
                .args(["--optics", "diffraction:lambda=0.55um,fnum=4"])
                .args(extra)
                .arg("-o")
                .arg(&photo)
                .assert()
                .success();
        }
        let stem = name.rsplit_once('.').unwrap().0;
        let sim: Value = serde_json::from_str(
            &std::fs::read_to_string(dir.path().join(format!("{stem}.json"))).unwrap(),
        )
        .unwrap();
        let roi: Vec<String> = sim["sweeps"][0]["roi"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.to_string())
            .collect();
        let out = dir
            .path()
            .join(format!("out_{stem}_{}", measure_extra.len()));
        Command::cargo_bin("sweepmtf")
            .unwrap()
            .arg("measure")
            .arg(&photo)
            .args(["--roi", &roi.join(",")])
            .args(measure_extra)
            .args(["-q", "-o"])
            .arg(&out)
            .assert()
            .success();
        serde_json::from_str(
            &std::fs::read_to_string(out.join(format!("{stem}.summary.json"))).unwrap(),
        )
        .unwrap()
    };
    let mtf50 = |s: &Value| s["curves"][0]["mtf50"]["cy_px"].as_f64().unwrap();
    let plain = run("plain.dng", &[], &[]);
    assert_eq!(plain["distortion"]["source"], "negligible");
    let bent = &["--distortion", "ptlens:a=0,b=0.016,c=0"][..];
    let found = run("bent.dng", bent, &[]);
    let d = &found["distortion"];
    assert_eq!(d["source"], "estimated", "{d}");
    let b = d["b"].as_f64().unwrap();
    assert!((b / 0.016 - 1.0).abs() < 0.06, "b {b}");
    let (m_plain, m_found) = (mtf50(&plain), mtf50(&found));
    let m_off = mtf50(&run("bent.dng", bent, &["--no-estimate-distortion"]));
    eprintln!("raw MTF50: plain {m_plain:.4}, estimated {m_found:.4}, ignored {m_off:.4}");
    assert!(
        (m_found / m_plain - 1.0).abs() < 0.01,
        "{m_found} vs {m_plain}"
    );
    assert!((m_off / m_plain - 1.0).abs() < 0.01, "{m_off} vs {m_plain}");
}
