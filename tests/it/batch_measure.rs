//! `sweepmtf batch` with the real measurement on simulated shots with known
//! truth: a series at several f-numbers (camera EXIF written into each JPEG)
//! plus broken files gives the right MTF50 per shot, the f-numbers from the
//! EXIF, one error row per bad file and exit code 7; a run killed with
//! SIGKILL leaves only complete shots and the rerun finishes the rest.

use crate::batch_stub;

use batch_stub::exif_jpeg::{Facts, with_exif};
use batch_stub::read_summary;
use std::fmt::Write as _;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use sweepmtf::model::System;
use sweepmtf::simulate::demo::{GaussianPsf, demo_target};
use sweepmtf::simulate::{self, Camera, PhotoFormat};
use sweepmtf::target::SweepLaw;

const STOPS: [(f64, u32); 4] = [(2.8, 28), (5.6, 56), (11.0, 110), (22.0, 220)];

/// Writes the series and `rois.csv`; returns (file, f-number, true MTF50 cy/px).
fn series(dir: &Path) -> Vec<(String, f64, f64)> {
    std::fs::create_dir_all(dir).unwrap();
    let target = demo_target(SweepLaw::Log);
    let mut rois = String::from("file,x1,y1,x2,y2,x3,y3,x4,y4\n");
    let mut out = Vec::new();
    for (k, &(n, n10)) in STOPS.iter().enumerate() {
        let camera = Camera {
            width_px: 600,
            height_px: 400,
            jpeg_quality: Some(95),
            seed: k as u64,
            ..Camera::default()
        };
        let sigma_px = 0.6 + 0.1 * k as f64;
        let system = System {
            factors: vec![Box::new(GaussianPsf {
                sigma_mm: sigma_px * camera.pitch_mm(),
            })],
        };
        let shot = simulate::render(&target, &system, &camera).unwrap();
        let jpeg = shot.encode(PhotoFormat::Jpeg).unwrap();
        let facts = Facts {
            make: "SimCam".into(),
            model: "SimCam One".into(),
            lens: "Toy".into(),
            f_number: (n10, 10),
            focal_length: (50, 1),
            exposure_time: (1, 125),
            iso: 100,
            pitch_um_and_size: None,
        };
        let name = format!("f{}.jpg", sweepmtf::batch::plots::fmt_fnumber(n));
        std::fs::write(dir.join(&name), with_exif(&jpeg, &facts)).unwrap();
        let r = shot.roi().unwrap();
        let cs: Vec<String> = r.iter().map(|v| v.to_string()).collect();
        writeln!(rois, "{name},{}", cs.join(",")).unwrap();
        // True MTF50: where the simulator's truth curve crosses 0.5.
        let rows = &shot.truth().unwrap().rows;
        let m50 = rows
            .windows(2)
            .find_map(|w| {
                (w[0].mtf >= 0.5 && w[1].mtf < 0.5).then(|| {
                    w[0].freq_cy_px
                        + (w[1].freq_cy_px - w[0].freq_cy_px) * (w[0].mtf - 0.5)
                            / (w[0].mtf - w[1].mtf)
                })
            })
            .unwrap();
        out.push((name, n, m50));
    }
    std::fs::write(dir.join("rois.csv"), rois).unwrap();
    out
}

fn sweepmtf() -> Command {
    Command::new(env!("CARGO_BIN_EXE_sweepmtf"))
}

#[test]
fn series_with_bad_files_gives_truth_rows_error_rows_and_exit_7() {
    let d = tempfile::tempdir().unwrap();
    let shots = d.path().join("shots");
    let truth = series(&shots);
    let good = std::fs::read(shots.join(&truth[0].0)).unwrap();
    std::fs::write(shots.join("truncated.jpg"), &good[..good.len() / 3]).unwrap();
    std::fs::write(shots.join("empty.jpg"), b"").unwrap();
    std::fs::write(shots.join("notes.png"), b"not a photo").unwrap();
    let out = d.path().join("out");
    let st = sweepmtf()
        .args([
            "batch",
            shots.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--jobs",
            "2",
        ])
        .args(["--roi-file", shots.join("rois.csv").to_str().unwrap()])
        .stderr(Stdio::null())
        .status()
        .unwrap();
    assert_eq!(st.code(), Some(7));
    let rows = read_summary(&out.join("summary.csv"));
    assert_eq!(rows.len(), 7);
    for (name, n, m50) in &truth {
        let r = rows.iter().find(|r| &r["file"] == name).unwrap();
        assert_eq!(r["status"], "ok", "{name}: {}", r["error"]);
        let got: f64 = r["mtf50_cy_px"].parse().unwrap();
        assert!(
            (got - m50).abs() < 0.01,
            "{name}: MTF50 {got} against truth {m50}"
        );
        // Its one-sigma uncertainty beside it.
        let err: f64 = r["mtf50_err_cy_px"].parse().unwrap();
        assert!(err > 0.0 && err < 0.05 * got, "{name}: ± {err}");
        assert_eq!(r["f_number"].parse::<f64>().unwrap(), *n);
        assert_eq!(r["make"], "SimCam");
        for suffix in ["mtf.csv", "summary.json", "mtf.png", "roi.png", "done.json"] {
            assert!(
                out.join("shots")
                    .join(format!("{}.{suffix}", r["stem"]))
                    .is_file()
            );
        }
    }
    for bad in ["truncated.jpg", "empty.jpg", "notes.png"] {
        let r = rows.iter().find(|r| r["file"] == bad).unwrap();
        assert_eq!(r["status"], "error");
        assert!(!r["error"].is_empty());
    }
    assert!(out.join("mtf50_vs_f_number.png").is_file());
    assert!(out.join("report.html").is_file());
}

#[test]
fn killed_binary_leaves_complete_shots_and_rerun_finishes() {
    let d = tempfile::tempdir().unwrap();
    let shots = d.path().join("shots");
    series(&shots);
    let out = d.path().join("out");
    let args = |c: &mut Command| {
        c.args([
            "batch",
            shots.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--jobs",
            "1",
        ])
        .args(["--roi-file", shots.join("rois.csv").to_str().unwrap()])
        .stderr(Stdio::null());
    };
    let mut c = sweepmtf();
    args(&mut c);
    let mut child = c.spawn().unwrap();
    let t0 = Instant::now();
    let count = || {
        std::fs::read_dir(out.join("shots"))
            .map(|rd| {
                rd.filter(|e| {
                    let n = e
                        .as_ref()
                        .unwrap()
                        .file_name()
                        .to_string_lossy()
                        .into_owned();
                    n.ends_with(".done.json") && !n.starts_with('.')
                })
                .count()
            })
            .unwrap_or(0)
    };
    while count() < 1 && child.try_wait().unwrap().is_none() {
        assert!(t0.elapsed() < Duration::from_secs(60));
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let done = count();
    // Every marker's outputs exist.
    for e in std::fs::read_dir(out.join("shots")).unwrap() {
        let n = e.unwrap().file_name().to_string_lossy().into_owned();
        if let Some(stem) = n.strip_suffix(".done.json").filter(|_| !n.starts_with('.')) {
            let m = sweepmtf::batch::resume::read_marker(&out.join("shots"), stem).unwrap();
            assert!(sweepmtf::batch::resume::outputs_present(
                &out.join("shots"),
                &m
            ));
        }
    }
    let mut c = sweepmtf();
    args(&mut c);
    let o = c.stderr(Stdio::piped()).output().unwrap();
    assert_eq!(o.status.code(), Some(0));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains(&format!("{done} already complete")), "{err}");
    assert_eq!(read_summary(&out.join("summary.csv")).len(), STOPS.len());
}
