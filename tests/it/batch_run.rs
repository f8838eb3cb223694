//! Batch runner end to end with a stub per-shot job: summary, pictures and
//! report; failure isolation on a folder with bad files; resume, force and
//! settings changes; bounded parallelism; unique names across folders.

use crate::batch_stub;

use batch_stub::*;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::atomic::Ordering;
use sweepmtf::batch::{self, NoProgress, RunOptions, Shard};

fn opts(jobs: usize) -> RunOptions {
    RunOptions {
        jobs,
        force: false,
        retry_failed: false,
    }
}

fn run(inputs: &[PathBuf], out: &Path, job: &StubJob, o: &RunOptions) -> batch::BatchOutcome {
    let plan = batch::plan(inputs, true, out, Shard::ALL).unwrap();
    batch::run_batch(&plan, out, job, o, &NoProgress).unwrap()
}

#[test]
fn good_folder_gives_summary_pictures_and_report() {
    let d = tempfile::tempdir().unwrap();
    let shots = d.path().join("shots");
    let truth = good_folder(&shots, 16);
    // Kept after the test so a person can look at the pictures and the page.
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("batch_report");
    let _ = fs::remove_dir_all(&out);
    let job = StubJob::new("a", 0);
    let o = run(std::slice::from_ref(&shots), &out, &job, &opts(2));
    assert_eq!(o.run.failed(), 0);
    let rows = read_summary(&out.join("summary.csv"));
    assert_eq!(rows.len(), 16);
    for (name, m50) in &truth {
        let row = rows.iter().find(|r| &r["file"] == name).unwrap();
        assert_eq!(row["status"], "ok");
        let got: f64 = row["mtf50_cy_px"].parse().unwrap();
        assert!((got - m50).abs() < 1e-12, "{name}: {got} vs {m50}");
        assert!(row["f_number"].parse::<f64>().unwrap() > 2.0);
    }
    for pic in ["curves.png", "mtf50_vs_f_number.png"] {
        let img = image::open(out.join(pic)).unwrap();
        assert_eq!((img.width(), img.height()), (960, 600));
    }
    let html = fs::read_to_string(out.join("report.html")).unwrap();
    assert_eq!(html.matches("data:image/png;base64,").count(), 2);
    assert!(!html.contains("http://") && !html.contains("https://"));
    assert_eq!(html.matches("<tr>").count(), 16 + 1);
    // Every shot has its outputs and its marker; no temporary file is left.
    for row in &rows {
        for suffix in [".mtf.csv", ".stub.txt", ".done.json"] {
            assert!(
                out.join("shots")
                    .join(format!("{}{suffix}", row["stem"]))
                    .is_file()
            );
        }
    }
    assert!(
        snapshot(&out)
            .iter()
            .all(|(p, _)| !p.to_string_lossy().contains(".sweepmtf-tmp-"))
    );
}

#[test]
fn bad_files_become_error_rows_and_good_shots_are_measured() {
    let d = tempfile::tempdir().unwrap();
    let shots = d.path().join("shots");
    let truth = good_folder(&shots, 24);
    // A truncated PNG, an empty JPEG, a text file named .jpg, an unsupported
    // raw, a shot without a chart (grey 0) and a decoder panic.
    let good = fs::read(shots.join(&truth[0].0)).unwrap();
    fs::write(shots.join("truncated.png"), &good[..good.len() / 2]).unwrap();
    fs::write(shots.join("empty.jpg"), b"").unwrap();
    fs::write(shots.join("notes.jpg"), b"this is not a photo\n").unwrap();
    fs::write(shots.join("raw.cr2"), b"II*\0garbage").unwrap();
    write_shot(&shots.join("nochart.png"), 0);
    write_shot(&shots.join("panic.png"), 100);
    fs::write(shots.join("readme.txt"), b"ignored").unwrap();
    let before = snapshot(&shots);

    let out = d.path().join("out");
    let job = StubJob::new("a", 0);
    let o = run(std::slice::from_ref(&shots), &out, &job, &opts(2));
    let rows = read_summary(&out.join("summary.csv"));
    assert_eq!(rows.len(), 30);
    let errors: Vec<_> = rows.iter().filter(|r| r["status"] == "error").collect();
    let mut bad: Vec<&str> = errors.iter().map(|r| r["file"].as_str()).collect();
    bad.sort();
    assert_eq!(
        bad,
        [
            "empty.jpg",
            "nochart.png",
            "notes.jpg",
            "panic.png",
            "raw.cr2",
            "truncated.png"
        ]
    );
    assert!(errors.iter().all(|r| !r["error"].is_empty()));
    let panic_row = errors.iter().find(|r| r["file"] == "panic.png").unwrap();
    assert!(
        panic_row["error"].contains("decoder exploded"),
        "{}",
        panic_row["error"]
    );
    for (name, m50) in &truth {
        let row = rows.iter().find(|r| &r["file"] == name).unwrap();
        assert_eq!(row["status"], "ok");
        assert!((row["mtf50_cy_px"].parse::<f64>().unwrap() - m50).abs() < 1e-12);
    }
    assert_eq!(o.run.failed(), 6);
    // The inputs are untouched.
    assert_eq!(snapshot(&shots), before);
}

#[test]
fn rerun_skips_complete_shots_and_redoes_changed_ones() {
    let d = tempfile::tempdir().unwrap();
    let shots = d.path().join("shots");
    good_folder(&shots, 8);
    write_shot(&shots.join("nochart.png"), 0);
    let out = d.path().join("out");

    let job = StubJob::new("a", 0);
    let first = run(std::slice::from_ref(&shots), &out, &job, &opts(2));
    assert_eq!((first.run.measured, first.run.skipped), (9, 0));
    let summary1 = fs::read(out.join("summary.csv")).unwrap();
    let shots_before = snapshot(&out.join("shots"));

    // Unchanged: nothing is measured, nothing rewritten, same table.
    let job = StubJob::new("a", 0);
    let again = run(std::slice::from_ref(&shots), &out, &job, &opts(2));
    assert_eq!((again.run.measured, again.run.skipped), (0, 9));
    assert_eq!(job.started.load(Ordering::SeqCst), 0);
    assert_eq!(fs::read(out.join("summary.csv")).unwrap(), summary1);
    assert_eq!(snapshot(&out.join("shots")), shots_before);

    // Retry failed: only the error shot.
    let job = StubJob::new("a", 0);
    let o = batch::run_batch(
        &batch::plan(std::slice::from_ref(&shots), true, &out, Shard::ALL).unwrap(),
        &out,
        &job,
        &RunOptions {
            retry_failed: true,
            ..opts(2)
        },
        &NoProgress,
    )
    .unwrap();
    assert_eq!((o.run.measured, o.run.skipped), (1, 8));

    // A changed file, a lost output: only those two are redone.
    write_shot(&shots.join("f4_01.png"), 99);
    let first_stem = &first.run.records[0].stem;
    fs::remove_file(out.join("shots").join(format!("{first_stem}.stub.txt"))).unwrap();
    let job = StubJob::new("a", 0);
    let o = run(std::slice::from_ref(&shots), &out, &job, &opts(2));
    assert_eq!((o.run.measured, o.run.skipped), (2, 7));
    let row = o
        .run
        .records
        .iter()
        .find(|r| r.file == "f4_01.png")
        .unwrap();
    assert!((row.result.mtf50_cy_px.unwrap() - mtf50_of_sigma(0.99)).abs() < 1e-12);

    // Changed settings redo everything; so does --force.
    let job = StubJob::new("b", 0);
    let o = run(std::slice::from_ref(&shots), &out, &job, &opts(2));
    assert_eq!((o.run.measured, o.run.skipped), (9, 0));
    let job = StubJob::new("b", 0);
    let o = run(
        std::slice::from_ref(&shots),
        &out,
        &job,
        &RunOptions {
            force: true,
            ..opts(2)
        },
    );
    assert_eq!((o.run.measured, o.run.skipped), (9, 0));
}

#[test]
fn workers_are_bounded_by_jobs() {
    let d = tempfile::tempdir().unwrap();
    let shots = d.path().join("shots");
    good_folder(&shots, 12);
    for jobs in [1, 3] {
        let out = d.path().join(format!("out{jobs}"));
        let job = StubJob::new("a", 40);
        run(std::slice::from_ref(&shots), &out, &job, &opts(jobs));
        assert_eq!(job.max_running.load(Ordering::SeqCst), jobs);
        assert_eq!(job.started.load(Ordering::SeqCst), 12);
    }
}

#[test]
fn nested_parallel_decoding_does_not_start_extra_shots() {
    // A decoder that parallelises inside (rawler does) must not let a waiting
    // worker pick up another shot: at most `jobs` shots (decoded images) at once.
    let d = tempfile::tempdir().unwrap();
    let shots = d.path().join("shots");
    good_folder(&shots, 12);
    let out = d.path().join("out");
    let mut job = StubJob::new("a", 16);
    job.nested_rayon = true;
    run(std::slice::from_ref(&shots), &out, &job, &opts(2));
    assert_eq!(job.max_running.load(Ordering::SeqCst), 2);
}

#[test]
fn same_file_name_in_two_folders_keeps_both() {
    let d = tempfile::tempdir().unwrap();
    let a = d.path().join("a");
    let b = d.path().join("b");
    write_shot(&a.join("shot.png"), 50);
    write_shot(&b.join("shot.png"), 150);
    write_shot(&b.join("sub/shot.png"), 120);
    let out = d.path().join("out");
    let job = StubJob::new("a", 0);
    let o = run(&[a, b], &out, &job, &opts(2));
    let files: Vec<_> = o.run.records.iter().map(|r| r.file.as_str()).collect();
    assert_eq!(files, ["a/shot.png", "b/shot.png", "b/sub/shot.png"]);
    let stems: Vec<_> = o.run.records.iter().map(|r| r.stem.as_str()).collect();
    assert_eq!(stems, ["a__shot", "b__shot", "b__sub__shot"]);
    let m: Vec<f64> = o
        .run
        .records
        .iter()
        .map(|r| r.result.mtf50_cy_px.unwrap())
        .collect();
    assert!((m[0] - mtf50_of_sigma(0.5)).abs() < 1e-12);
    assert!((m[1] - mtf50_of_sigma(1.5)).abs() < 1e-12);
}

#[test]
fn output_folder_inside_the_input_is_not_measured() {
    let d = tempfile::tempdir().unwrap();
    good_folder(d.path(), 3);
    let out = d.path().join("out");
    let job = StubJob::new("a", 0);
    run(&[d.path().to_path_buf()], &out, &job, &opts(1));
    // Second run: the pictures written in out/ must not become shots.
    let o = run(&[d.path().to_path_buf()], &out, &job, &opts(1));
    assert_eq!(o.run.records.len(), 3);
}
