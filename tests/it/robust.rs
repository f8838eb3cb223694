//! Regression tests named after the four problems of issue 19 (hostile and
//! careless input): a model run that never ended and left a partial CSV, two
//! batch runs racing in one folder, a JPEG with damaged scan data measured
//! silently, and notes printed as warnings on every run of the README sample.

use assert_cmd::Command;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

fn sweepmtf() -> Command {
    let mut c = Command::cargo_bin("sweepmtf").unwrap();
    c.current_dir(ROOT).timeout(Duration::from_secs(120));
    c
}

fn stderr(a: &assert_cmd::assert::Assert) -> String {
    String::from_utf8_lossy(&a.get_output().stderr).into_owned()
}

/// The README sample shot with 2 KB of pseudo-random bytes over the middle
/// of its scan data (fixed seed; what a bad card or transfer leaves).
fn damaged_sample(dir: &Path, at: f64) -> PathBuf {
    let mut b = std::fs::read(Path::new(ROOT).join("testdata/a4_log_shot.jpg")).unwrap();
    let mid = (b.len() as f64 * at) as usize;
    let mut x = 0x9E37_79B9u32;
    for v in &mut b[mid..mid + 2048] {
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        *v = (x >> 24) as u8;
    }
    let p = dir.join("damaged.jpg");
    std::fs::write(&p, b).unwrap();
    p
}

#[test]
fn model_f_max_1e308_is_refused_at_once_and_leaves_no_partial_csv() {
    let d = tempfile::tempdir().unwrap();
    let csv = d.path().join("m.csv");
    let t = Instant::now();
    let a = sweepmtf()
        .args([
            "model",
            "--aperture",
            "rect:A=5um,B=5um",
            "--cut",
            "u",
            "--f-max",
            "1e308",
            "-o",
        ])
        .arg(&csv)
        .assert()
        .code(2);
    assert!(t.elapsed() < Duration::from_secs(10));
    let err = stderr(&a);
    assert!(err.contains("--f-max") && err.contains("1e6"), "{err}");
    assert!(std::fs::read_dir(d.path()).unwrap().next().is_none());
    // The largest allowed value works and writes both files.
    sweepmtf()
        .args(["model", "--aperture", "rect:A=5um,B=5um", "--cut", "u"])
        .args(["--f-max", "1e6", "--points", "2001", "-o"])
        .arg(&csv)
        .assert()
        .success();
    assert!(csv.is_file() && d.path().join("m.png").is_file());
    for (flag, value) in [
        ("--points", "1000001"),
        ("--f-max", "-3"),
        ("--f-max", "inf"),
    ] {
        let a = sweepmtf()
            .args(["model", "--aperture", "rect:A=5um,B=5um", "--cut", "v"])
            .args(["--f-max", "100", &format!("{flag}={value}"), "-o"])
            .arg(d.path().join("n.csv"))
            .assert()
            .code(2);
        assert!(stderr(&a).contains(flag), "{}", stderr(&a));
    }
    assert!(!d.path().join("n.csv").exists());
}

#[test]
fn two_batch_runs_into_one_folder_the_second_names_the_holder() {
    let d = tempfile::tempdir().unwrap();
    let shots = d.path().join("shots");
    std::fs::create_dir(&shots).unwrap();
    std::fs::copy(
        Path::new(ROOT).join("testdata/sweep_log_srgb_q90.jpg"),
        shots.join("a.jpg"),
    )
    .unwrap();
    let out = d.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let batch = |out: &Path| {
        let mut c = sweepmtf();
        c.arg("batch")
            .arg(&shots)
            .arg("-o")
            .arg(out)
            .args(["--roi", "200,200,1000,200,1000,400,200,400"]);
        c
    };
    // A run holds the folder (here: this test process, through the library).
    let lock = sweepmtf::batch::lock::FolderLock::acquire(&out).unwrap();
    let a = batch(&out).assert().code(8);
    let err = stderr(&a);
    assert!(
        err.contains(&format!("process {}", std::process::id())) && err.contains("in use"),
        "{err}"
    );
    assert!(!out.join("summary.csv").exists());
    let m = Command::cargo_bin("sweepmtf")
        .unwrap()
        .arg("merge")
        .arg(&out)
        .arg("-o")
        .arg(&out)
        .assert()
        .code(8);
    assert!(stderr(&m).contains("in use"), "{}", stderr(&m));
    drop(lock);
    // A stale lock file (a killed run's pid, no OS lock) is taken over.
    std::fs::write(out.join(".sweepmtf.lock"), "999999999\n").unwrap();
    batch(&out).assert().success();
    assert!(out.join("summary.csv").is_file());
    // Two real runs at once into a fresh folder: each either finishes or
    // stops with code 8; never the old "cannot write" race.
    let out2 = d.path().join("out2");
    let spawn = || {
        std::process::Command::new(assert_cmd::cargo::cargo_bin("sweepmtf"))
            .arg("batch")
            .arg(&shots)
            .arg("-o")
            .arg(&out2)
            .args([
                "--roi",
                "200,200,1000,200,1000,400,200,400",
                "--force",
                "-q",
            ])
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (p1, p2) = (spawn(), spawn());
    let codes: Vec<(Option<i32>, String)> = [p1, p2]
        .into_iter()
        .map(|p| {
            let o = p.wait_with_output().unwrap();
            (
                o.status.code(),
                String::from_utf8_lossy(&o.stderr).into_owned(),
            )
        })
        .collect();
    for (code, err) in &codes {
        assert!(matches!(code, Some(0) | Some(8)), "{codes:?}");
        if *code == Some(8) {
            assert!(err.contains("in use by process"), "{err}");
        }
    }
    assert!(codes.iter().any(|(c, _)| *c == Some(0)), "{codes:?}");
    assert!(out2.join("summary.csv").is_file());
}

#[test]
fn jpeg_with_damaged_scan_data_is_not_measured_silently() {
    let d = tempfile::tempdir().unwrap();
    // Damage in the middle of the scan: the chart's lower fiducials are lost,
    // so location fails, and the failure names the damage as its cause (exit 3).
    let photo = damaged_sample(d.path(), 0.5);
    let a = sweepmtf()
        .arg("measure")
        .arg(&photo)
        .args(["--target", "targets/a4_log.toml", "-o"])
        .arg(d.path().join("m"))
        .assert()
        .code(3);
    let err = stderr(&a);
    assert!(
        err.contains("damaged.jpg")
            && err.contains("the photo itself is damaged")
            && err.contains("scan data"),
        "{err}"
    );
    // Damage near the end (below the chart): measured, exit 0, with a warning.
    let photo = damaged_sample(d.path(), 0.95);
    let a = sweepmtf()
        .arg("measure")
        .arg(&photo)
        .args(["--target", "targets/a4_log.toml", "-o"])
        .arg(d.path().join("m"))
        .assert()
        .success();
    let err = stderr(&a);
    assert!(
        err.contains("warning") && err.contains("damaged.jpg") && err.contains("scan data"),
        "{err}"
    );
    // The warning reaches the batch summary's row.
    let shots = d.path().join("in");
    std::fs::create_dir(&shots).unwrap();
    std::fs::rename(&photo, shots.join("damaged.jpg")).unwrap();
    let out = d.path().join("out");
    let _ = sweepmtf()
        .arg("batch")
        .arg(&shots)
        .arg("-o")
        .arg(&out)
        .args(["--target", "targets/a4_log.toml", "-q"])
        .output()
        .unwrap();
    let summary = std::fs::read_to_string(out.join("summary.csv")).unwrap();
    let row = summary.lines().find(|l| l.contains("damaged.jpg")).unwrap();
    assert!(row.contains("scan data"), "{summary}");
}

#[test]
fn readme_sample_prints_its_summary_line_and_no_warning() {
    let d = tempfile::tempdir().unwrap();
    let run = |extra: &[&str]| {
        sweepmtf()
            .args([
                "measure",
                "testdata/a4_log_shot.jpg",
                "--target",
                "targets/a4_log.toml",
            ])
            .args(extra)
            .arg("-o")
            .arg(d.path())
            .assert()
            .success()
    };
    let a = run(&[]);
    let out = String::from_utf8_lossy(&a.get_output().stdout).into_owned();
    assert!(
        out.starts_with("testdata/a4_log_shot.jpg: ") && out.contains("MTF50"),
        "{out}"
    );
    assert_eq!(out.lines().count(), 1, "{out}");
    assert_eq!(stderr(&a), "", "nothing on stderr without -v");
    // -v shows the notes; -q stays silent; the JSON keeps them, labelled.
    let v = stderr(&run(&["-v"]));
    for n in [
        "note: testdata/a4_log_shot.jpg: region found automatically",
        "pixel pitch unknown",
    ] {
        assert!(v.contains(n), "{v}");
    }
    assert!(!v.contains("warning"), "{v}");
    assert_eq!(stderr(&run(&["-q"])), "");
    let json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(d.path().join("a4_log_shot.summary.json")).unwrap(),
    )
    .unwrap();
    let notes = json["notes"].as_array().expect("notes in the JSON");
    assert!(
        notes
            .iter()
            .any(|n| n.as_str().unwrap().contains("found automatically"))
    );
    assert!(
        json["warnings"]
            .as_array()
            .expect("warnings in the JSON")
            .is_empty()
    );
}

/// `merge` of inputs that are not batch folders fails with one line and
/// leaves no output folder behind (it used to leave an empty one with a lock file).
#[test]
fn merge_of_bad_inputs_leaves_no_output_folder() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("merged");
    let merge = || {
        sweepmtf()
            .arg("merge")
            .arg(d.path().join("no-such-run"))
            .arg("-o")
            .arg(&out)
            .assert()
            .failure()
    };
    let err = stderr(&merge());
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(!out.exists(), "merge left {}", out.display());
    // An existing output folder is kept as it was.
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("keep.txt"), "mine").unwrap();
    merge();
    assert_eq!(
        std::fs::read_to_string(out.join("keep.txt")).unwrap(),
        "mine"
    );
}
