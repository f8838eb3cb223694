//! `sweepmtf batch` and `sweepmtf merge` through the binary: usage errors,
//! exit codes, and error rows for files that are not photos.

use assert_cmd::Command;
use std::fs;

fn sweepmtf() -> Command {
    Command::cargo_bin("sweepmtf").unwrap()
}

#[test]
fn usage_errors_exit_2() {
    let d = tempfile::tempdir().unwrap();
    sweepmtf().arg("batch").assert().code(2);
    for shard in ["0/3", "4/3", "x"] {
        let a = sweepmtf()
            .args(["batch", d.path().to_str().unwrap(), "-o"])
            .arg(d.path().join("out"))
            .args(["--shard", shard])
            .assert()
            .code(2);
        let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
        assert!(err.contains("--shard"), "{err}");
    }
    sweepmtf()
        .args([
            "batch",
            d.path().to_str().unwrap(),
            "-o",
            "x",
            "--jobs",
            "0",
        ])
        .assert()
        .code(2);
}

#[test]
fn missing_or_empty_input_exits_3_naming_it() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("out");
    let a = sweepmtf()
        .args(["batch", "/no/such/dir", "-o"])
        .arg(&out)
        .assert()
        .code(3);
    assert!(String::from_utf8_lossy(&a.get_output().stderr).contains("/no/such/dir"));
    fs::write(d.path().join("notes.txt"), b"x").unwrap();
    let a = sweepmtf()
        .args(["batch", d.path().to_str().unwrap(), "-o"])
        .arg(&out)
        .assert()
        .code(3);
    assert!(String::from_utf8_lossy(&a.get_output().stderr).contains("no photos found"));
}

#[test]
fn bad_roi_file_exits_3_naming_the_line() {
    let d = tempfile::tempdir().unwrap();
    let rois = d.path().join("rois.csv");
    fs::write(&rois, "file,x1,y1,x2,y2,x3,y3,x4,y4\na.jpg,1,2,3\n").unwrap();
    let a = sweepmtf()
        .args(["batch", d.path().to_str().unwrap(), "-o", "x", "--roi-file"])
        .arg(&rois)
        .assert()
        .code(3);
    let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(err.contains("rois.csv") && err.contains("line 2"), "{err}");
}

#[test]
fn broken_files_give_error_rows_exit_7_and_plain_progress_lines() {
    let d = tempfile::tempdir().unwrap();
    let shots = d.path().join("shots");
    fs::create_dir_all(&shots).unwrap();
    fs::write(shots.join("empty.jpg"), b"").unwrap();
    fs::write(shots.join("text.png"), b"not a png").unwrap();
    fs::write(shots.join("raw.nef"), b"MM\0*garbage").unwrap();
    let out = d.path().join("out");
    let a = sweepmtf()
        .args(["batch", shots.to_str().unwrap(), "-o"])
        .arg(&out)
        .assert()
        .code(7);
    let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(
        err.contains("[3/3]"),
        "plain progress lines expected: {err}"
    );
    let mut r = csv::Reader::from_path(out.join("summary.csv")).unwrap();
    let rows: Vec<csv::StringRecord> = r.records().map(|x| x.unwrap()).collect();
    assert_eq!(rows.len(), 3);
    for row in &rows {
        assert_eq!(&row[1], "error");
        assert!(!row[2].is_empty());
    }
    assert!(out.join("report.html").is_file());
    // A rerun skips them (their failure is final for unchanged files) and still exits 7.
    let a = sweepmtf()
        .args(["batch", shots.to_str().unwrap(), "-o"])
        .arg(&out)
        .assert()
        .code(7);
    let err = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(err.contains("3 already complete"), "{err}");
}

#[test]
fn merge_of_a_plain_folder_exits_3() {
    let d = tempfile::tempdir().unwrap();
    let a = sweepmtf()
        .args(["merge", d.path().to_str().unwrap(), "-o"])
        .arg(d.path().join("m"))
        .assert()
        .code(3);
    assert!(String::from_utf8_lossy(&a.get_output().stderr).contains("not a batch output folder"));
}
