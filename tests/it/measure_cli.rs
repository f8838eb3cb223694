//! `sweepmtf measure` end to end: outputs on a rendered shot, and one clear
//! line with a documented exit code (never a panic, never partial output) for
//! every kind of bad input listed in issue 5.

use assert_cmd::Command;
use std::path::Path;
use sweepmtf::measure::law::{LawKind, PhaseLaw};
use sweepmtf::measure::synth::{SynthShot, strip_quad};

fn shot(mean: f64, contrast: f64) -> SynthShot {
    let len = 560.0;
    SynthShot {
        name: "small".into(),
        width: 600,
        height: 100,
        quad: strip_quad(300.0, 50.0, len, 60.0, 0.0, 0.0),
        length: len,
        strip_width: 60.0,
        law: PhaseLaw {
            kind: LawKind::Log,
            c0: 0.0,
            c1: 0.006,
            c2: (0.6f64 / 0.006).ln() / len,
            persp: 0.0,
        },
        mean,
        contrast,
        sigma_px: 0.7,
        noise: None,
        jpeg_quality: None,
        nuisance: Default::default(),
    }
}

fn roi_arg(q: [[f64; 2]; 4]) -> String {
    q.iter()
        .flatten()
        .map(|v| format!("{v}"))
        .collect::<Vec<_>>()
        .join(",")
}

fn measure(photo: &Path, out: &Path, extra: &[&str]) -> assert_cmd::assert::Assert {
    let mut cmd = Command::cargo_bin("sweepmtf").unwrap();
    cmd.arg("measure").arg(photo).arg("-o").arg(out).args(extra);
    cmd.assert()
}

fn files_in(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .map(|r| {
            r.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default()
}

#[test]
fn writes_csv_json_and_both_pictures() {
    let dir = tempfile::tempdir().unwrap();
    let s = shot(0.45, 0.8);
    let photo = dir.path().join("sweep.png");
    std::fs::write(&photo, s.encode(3)).unwrap();
    let out = dir.path().join("out");
    let roi = roi_arg(s.quad);
    let a = measure(&photo, &out, &["--roi", &roi, "--pixel-pitch", "4.3um"]).success();
    let stdout = String::from_utf8_lossy(&a.get_output().stdout).into_owned();
    assert_eq!(stdout.lines().count(), 1, "{stdout}");
    assert!(stdout.contains("MTF50"), "{stdout}");
    let mut names = files_in(&out);
    names.sort();
    assert_eq!(
        names,
        [
            "sweep.mtf.csv",
            "sweep.mtf.png",
            "sweep.roi.png",
            "sweep.summary.json"
        ]
    );
    let csv = std::fs::read_to_string(out.join("sweep.mtf.csv")).unwrap();
    assert!(csv.starts_with(
        "freq_cy_px,mtf,freq_cy_mm,freq_lw_ph,modulation,mtf_err,aliased,jpeg_limited\n"
    ));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("sweep.summary.json")).unwrap())
            .unwrap();
    let f50 = json["curves"][0]["mtf50"]["cy_px"].as_f64().unwrap();
    let truth = (0.5f64.ln() / (-2.0 * std::f64::consts::PI.powi(2) * 0.49)).sqrt();
    assert!((f50 / truth - 1.0).abs() < 0.02, "{f50} vs {truth}");
    let mm = json["curves"][0]["mtf50"]["cy_mm"].as_f64().unwrap();
    assert!((mm - f50 / 0.0043).abs() < 1e-6);
    // MTF50's one-sigma uncertainty beside it, in every unit; it covers the
    // truth within 3 σ and is not absurdly wide.
    let e50 = json["curves"][0]["mtf50"]["err_cy_px"].as_f64().unwrap();
    assert!(e50 > 0.0 && e50 < 0.02 * f50, "{e50}");
    assert!((f50 - truth).abs() < 3.0 * e50, "{f50} ± {e50} vs {truth}");
    let e50_mm = json["curves"][0]["mtf50"]["err_cy_mm"].as_f64().unwrap();
    assert!((e50_mm - e50 / 0.0043).abs() < 1e-6);
    assert!(
        stdout.contains(&format!("MTF50 {f50:.4} ± {e50:.4} cy/px")),
        "{stdout}"
    );
    // --json prints the summary instead of the line; --plot svg writes an SVG.
    let a = measure(&photo, &out, &["--roi", &roi, "--json", "--plot", "svg"]).success();
    let v: serde_json::Value = serde_json::from_slice(&a.get_output().stdout).unwrap();
    assert_eq!(v["method"], "fit");
    assert!(out.join("sweep.mtf.svg").exists());
    // The printed ends: none inside exact corners; --keep-ends looks for none.
    assert_eq!(
        v["curves"][0]["print_ends_inside_px"],
        serde_json::json!([null, null])
    );
    let a = measure(&photo, &out, &["--roi", &roi, "--json", "--keep-ends"]).success();
    let k: serde_json::Value = serde_json::from_slice(&a.get_output().stdout).unwrap();
    assert_eq!(
        k["curves"][0]["print_ends_inside_px"],
        v["curves"][0]["print_ends_inside_px"]
    );
}

/// Runs a failing measurement and checks: exit code, one line naming `needle`, no output files.
fn refuses(photo: &Path, extra: &[&str], code: i32, needle: &str) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    let a = measure(photo, &out, extra).code(code);
    let stderr = String::from_utf8_lossy(&a.get_output().stderr).into_owned();
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains(needle), "{needle:?} not in: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(files_in(&out).is_empty(), "{:?}", files_in(&out));
}

#[test]
fn bad_files_exit_3_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let s = shot(0.45, 0.8);
    let roi = roi_arg(s.quad);
    let args = ["--roi", roi.as_str()];
    refuses(&dir.path().join("missing.jpg"), &args, 3, "missing.jpg");
    let mut jpg = std::io::Cursor::new(Vec::new());
    image::GrayImage::from_pixel(600, 100, image::Luma([128u8]))
        .write_to(&mut jpg, image::ImageFormat::Jpeg)
        .unwrap();
    let jpg = jpg.into_inner();
    let cut = dir.path().join("cut.jpg");
    std::fs::write(&cut, &jpg[..jpg.len() / 2]).unwrap();
    refuses(&cut, &args, 3, "cut.jpg");
    let txt = dir.path().join("notes.png");
    std::fs::write(&txt, "not an image at all").unwrap();
    refuses(&txt, &args, 3, "unsupported format");
    let png = s.encode(1);
    let corrupt = dir.path().join("corrupt.png");
    let mut bad = png.clone();
    for b in bad[60..400].iter_mut() {
        *b ^= 0x5a;
    }
    std::fs::write(&corrupt, &bad).unwrap();
    refuses(&corrupt, &args, 3, "corrupt.png");
}

#[test]
fn bad_regions_exit_4_or_2() {
    let dir = tempfile::tempdir().unwrap();
    let s = shot(0.45, 0.8);
    let photo = dir.path().join("sweep.png");
    std::fs::write(&photo, s.encode(1)).unwrap();
    refuses(
        &photo,
        &[],
        4,
        "no --roi given and automatic location is not available",
    );
    refuses(
        &photo,
        &["--roi", "10,10,700,10,700,90,10,90"],
        4,
        "outside",
    );
    refuses(&photo, &["--roi", "10,10,500,90,500,10,10,90"], 4, "cross");
    refuses(
        &photo,
        &["--roi", "10,10,200,10,400,10,10,90"],
        4,
        "degenerate",
    );
    refuses(
        &photo,
        &["--roi", "100,40,108,40,108,43,100,43"],
        4,
        "too small",
    );
    refuses(&photo, &["--roi", "1,2,3"], 2, "--roi");
    // Argument errors are clap's (usage text follows), still exit 2 and no output.
    let out = dir.path().join("out2");
    let a = measure(
        &photo,
        &out,
        &["--roi", &roi_arg(s.quad), "--method", "magic"],
    )
    .code(2);
    assert!(String::from_utf8_lossy(&a.get_output().stderr).contains("magic"));
    assert!(files_in(&out).is_empty());
}

#[test]
fn unmeasurable_regions_exit_5() {
    let dir = tempfile::tempdir().unwrap();
    let s = shot(0.45, 0.8);
    let roi = roi_arg(s.quad);
    let blank = dir.path().join("blank.png");
    std::fs::write(&blank, shot(0.45, 1e-9).encode(1)).unwrap();
    refuses(&blank, &["--roi", &roi], 5, "no oscillation");
    // Over-exposed: the sweep's peaks clip at white.
    let hot = dir.path().join("hot.png");
    std::fs::write(&hot, shot(0.9, 0.8).encode(1)).unwrap();
    refuses(&hot, &["--roi", &roi], 5, "clipped");
    // Pure noise: no oscillation.
    let noise = dir.path().join("noise.png");
    let mut st = 12345u64;
    let img = image::GrayImage::from_fn(600, 100, |_, _| {
        st = st
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        image::Luma([100 + (st >> 59) as u8])
    });
    img.save(&noise).unwrap();
    refuses(&noise, &["--roi", &roi], 5, "noise.png");
}

#[test]
fn a_failed_run_keeps_earlier_results() {
    let dir = tempfile::tempdir().unwrap();
    let s = shot(0.45, 0.8);
    let photo = dir.path().join("sweep.png");
    std::fs::write(&photo, s.encode(1)).unwrap();
    let out = dir.path().join("out");
    measure(&photo, &out, &["--roi", &roi_arg(s.quad)]).success();
    let before = std::fs::read(out.join("sweep.mtf.csv")).unwrap();
    std::fs::write(&photo, b"garbage").unwrap();
    measure(&photo, &out, &["--roi", &roi_arg(s.quad)]).code(3);
    assert_eq!(std::fs::read(out.join("sweep.mtf.csv")).unwrap(), before);
    assert_eq!(files_in(&out).len(), 4);
}

/// A print that stops above MTF 0.5 has no MTF50; the line says where the
/// curve ends and how high, so that a user can tell the print's reach from a
/// failure (the shot's Gaussian blur, σ 0.7 px, reads 0.68 at 0.2 cy/px).
#[test]
fn a_print_that_ends_above_half_says_where_the_curve_ends() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = shot(0.45, 0.8);
    s.law.c2 = (0.2f64 / 0.006).ln() / s.length;
    let photo = dir.path().join("short.png");
    std::fs::write(&photo, s.encode(3)).unwrap();
    let out = dir.path().join("out");
    let a = measure(&photo, &out, &["--roi", &roi_arg(s.quad)]).success();
    let stdout = String::from_utf8_lossy(&a.get_output().stdout).into_owned();
    let csv = std::fs::read_to_string(out.join("short.mtf.csv")).unwrap();
    let last: Vec<f64> = csv
        .lines()
        .rfind(|l| l.ends_with("false"))
        .unwrap()
        .split(',')
        .take(2)
        .map(|v| v.parse().unwrap())
        .collect();
    let (f, mtf) = (last[0], last[1]);
    let truth = (-2.0 * std::f64::consts::PI.powi(2) * 0.49 * f * f).exp();
    assert!(
        f > 0.15 && f <= 0.2 && (mtf - truth).abs() < 0.02,
        "{f} {mtf} vs {truth}"
    );
    assert!(
        stdout.contains(&format!(
            "MTF50 not reached (MTF {mtf:.3} at the curve's end, {f:.3} cy/px)"
        )),
        "{stdout}"
    );
}
