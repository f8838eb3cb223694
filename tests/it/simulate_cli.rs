//! `sweepmtf simulate` from the command line: it writes the photo, truth and
//! settings; bad input gives one clear line and the documented exit code
//! (2 bad settings or impossible placement, 3 unreadable target or system file)
//! and writes nothing.

use assert_cmd::Command;

fn cmd() -> Command {
    Command::cargo_bin("sweepmtf").unwrap()
}

#[test]
fn writes_photo_truth_and_settings() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("shot.jpg");
    let a = cmd()
        .args([
            "simulate", "--target", "demo:log", "--size", "480x320", "--rotate", "-10",
        ])
        .args([
            "--tilt",
            "20,x",
            "--full-well",
            "8000",
            "--read-noise",
            "5",
            "--jpeg",
            "85",
        ])
        .arg("-o")
        .arg(&out)
        .assert()
        .success();
    let stdout = String::from_utf8_lossy(&a.get_output().stdout).to_string();
    assert!(stdout.contains("shot.truth.csv"), "{stdout}");
    assert!(out.exists());
    assert!(dir.path().join("shot.truth.csv").exists());
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("shot.json")).unwrap()).unwrap();
    assert_eq!(j["camera"]["tilt_deg"], 20.0);
    assert_eq!(j["camera"]["tilt_axis_deg"], 0.0);
    assert_eq!(j["camera"]["jpeg_quality"], 85);
    let img = image::open(&out).unwrap();
    assert_eq!((img.width(), img.height()), (480, 320));
}

fn fails(args: &[&str], code: i32, needle: &str) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let a = cmd()
        .arg("simulate")
        .args(args)
        .arg("-o")
        .arg(&out)
        .assert()
        .code(code);
    let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(err.contains(needle), "{args:?}: {err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        std::fs::read_dir(dir.path()).unwrap().next().is_none(),
        "wrote something"
    );
}

#[test]
fn bad_input_gives_one_line_and_the_documented_code() {
    fails(
        &["--target", "demo:log", "--chart-px", "5000"],
        2,
        "does not fit",
    );
    fails(&["--target", "demo:log", "--tilt", "90"], 2, "tilt");
    fails(
        &[
            "--target",
            "demo:log",
            "--full-well",
            "1000",
            "--read-noise",
            "-3",
        ],
        2,
        "read noise",
    );
    fails(
        &["--target", "demo:log", "--fpn", "-0.1"],
        2,
        "fixed-pattern",
    );
    fails(&["--target", "demo:log", "--size", "12x"], 2, "--size");
    fails(
        &["--target", "demo:log", "--encoding", "gamma"],
        2,
        "encoding",
    );
    fails(&["--target", "demo:log", "--bayer", "RGBG"], 2, "Bayer");
    fails(
        &["--target", "/nonexistent/t.toml"],
        3,
        "/nonexistent/t.toml",
    );
}

#[test]
fn a_corrupt_target_file_is_an_input_error() {
    let dir = tempfile::tempdir().unwrap();
    let t = dir.path().join("t.toml");
    std::fs::write(&t, "name = 3\nwidth_mm = [").unwrap();
    fails(&["--target", t.to_str().unwrap()], 3, "t.toml");
}
