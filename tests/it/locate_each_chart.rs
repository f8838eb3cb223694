//! Several charts in one frame (issue 7): two simulated shots of the A4 log
//! chart side by side in one photo. `measure` without corners or a chart
//! index measures each chart (library: `measure_file_each`; CLI: outputs
//! `STEM.chart0.*` and `STEM.chart1.*`, left to right), each against its own
//! shot's truth from the simulator; `--chart-index 1` measures only the right one.

use crate::locate_support::sweep;

use assert_cmd::Command;
use std::path::{Path, PathBuf};
use sweep::Pose;
use sweepmtf::measure::{MeasureOptions, measure_file_each};

fn pose(rot: f64, tilt: f64, axis: f64, seed: u64) -> Pose {
    Pose {
        size: (700, 560),
        rotate_deg: rot,
        tilt_deg: tilt,
        tilt_axis_deg: axis,
        cover: 0.75,
        shift: [0.0, 0.0],
        falloff: 0.2,
        gradient: [0.1, -0.1],
        exposure: 0.7,
        full_well_e: 9000.0,
        w020: 0.25,
        seed,
    }
}

/// The two shots and the photo holding them side by side (left, right).
pub(crate) fn two_charts(dir: &Path) -> (PathBuf, [sweepmtf::simulate::Shot; 2]) {
    let target = sweep::a4_log();
    let (left, lj) = sweep::shoot(&target, &pose(6.0, 20.0, 90.0, 21)).unwrap();
    let (right, rj) = sweep::shoot(&target, &pose(-12.0, 30.0, 20.0, 22)).unwrap();
    let l = image::load_from_memory(&lj).unwrap().to_rgb8();
    let r = image::load_from_memory(&rj).unwrap().to_rgb8();
    let mut both = image::RgbImage::new(l.width() + r.width(), l.height());
    for (x, y, p) in l.enumerate_pixels() {
        both.put_pixel(x, y, *p);
    }
    for (x, y, p) in r.enumerate_pixels() {
        both.put_pixel(l.width() + x, y, *p);
    }
    let path = dir.join("two.png");
    both.save(&path).unwrap();
    (path, [left, right])
}

fn target_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("targets/a4_log.toml")
}

#[test]
fn each_chart_of_a_frame_is_measured_against_its_own_truth() {
    let dir = tempfile::tempdir().unwrap();
    let (path, shots) = two_charts(dir.path());
    let opts = MeasureOptions {
        target: Some(target_path()),
        ..MeasureOptions::default()
    };
    let all = measure_file_each(&path, &opts).unwrap();
    assert_eq!(all.len(), 2);
    for (k, (m, shot)) in all.iter().zip(&shots).enumerate() {
        let dx = 700.0 * k as f64;
        let c = shot.target_corners;
        let err = (0..4)
            .map(|i| (m.roi[i][0] - c[2 * i] - dx).hypot(m.roi[i][1] - c[2 * i + 1]))
            .fold(0.0, f64::max);
        assert!(err < 0.5, "chart {k}: corner error {err:.3} px");
        let rms = sweep::curve_rms(m, &shot.sweeps[0], "main");
        eprintln!("chart {k}: corner error {err:.3} px, main sweep RMS {rms:.4}");
        assert!(
            rms <= sweep::bar(shot.sweeps[0].chart_contrast),
            "chart {k}: RMS {rms:.4}"
        );
        assert!(
            m.notes
                .iter()
                .any(|w| w.contains(&format!("chart index {k} of the 2"))),
            "{:?}",
            m.notes
        );
    }
}

/// Runs `sweepmtf measure PHOTO EXTRA --target a4_log -o OUT`, which must succeed; its stdout.
fn measure(photo: &Path, extra: &[&str], out: &Path) -> String {
    let run = Command::cargo_bin("sweepmtf")
        .unwrap()
        .arg("measure")
        .arg(photo)
        .args(extra)
        .arg("--target")
        .arg(target_path())
        .arg("-o")
        .arg(out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    String::from_utf8_lossy(&run.stdout).into_owned()
}

#[test]
fn the_cli_writes_one_set_of_outputs_per_chart_or_the_one_asked_for() {
    // Kept under the target folder to be looked at.
    let kept = Path::new(env!("CARGO_TARGET_TMPDIR")).join("each_chart");
    let _ = std::fs::remove_dir_all(&kept);
    std::fs::create_dir_all(&kept).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let (path, _) = two_charts(dir.path());
    std::fs::copy(&path, kept.join("two.png")).unwrap();
    let out = kept.join("out");
    let stdout = measure(&path, &[], &out);
    assert_eq!(stdout.lines().count(), 2, "{stdout}");
    for k in 0..2 {
        for suffix in ["mtf.csv", "mtf.png", "roi.png", "summary.json"] {
            let f = out.join(format!("two.chart{k}.{suffix}"));
            assert!(f.exists(), "{} missing", f.display());
        }
    }
    assert!(!out.join("two.mtf.csv").exists());
    // --chart-index 1: only the right chart, under the plain stem.
    let one = dir.path().join("one");
    measure(&path, &["--chart-index", "1"], &one);
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(one.join("two.summary.json")).unwrap()).unwrap();
    let xs: Vec<f64> = summary["roi_px"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p[0].as_f64().unwrap())
        .collect();
    assert!(
        xs.iter().all(|&x| x > 700.0),
        "the right chart's corners: {xs:?}"
    );
    assert!(!one.join("two.chart0.mtf.csv").exists());
}
