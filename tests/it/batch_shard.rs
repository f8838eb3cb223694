//! Sharding and merging: the shards of a job array split the folder without
//! overlap, and `merge` rebuilds the same summary as one unsharded run;
//! a shard stopped early shows up as error rows, not as silence.

use crate::batch_stub;

use batch_stub::*;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use sweepmtf::batch::{self, NoProgress, RunOptions, Shard, merge::merge};

fn run(shots: &Path, out: &Path, shard: Shard) -> batch::BatchOutcome {
    let plan = batch::plan(&[shots.to_path_buf()], true, out, shard).unwrap();
    let job = StubJob::new("s", 0);
    batch::run_batch(&plan, out, &job, &RunOptions::default(), &NoProgress).unwrap()
}

/// Summary rows without the run-time column (which differs between runs).
fn rows_without_time(path: &Path) -> Vec<HashMap<String, String>> {
    let mut rows = read_summary(path);
    for r in &mut rows {
        r.remove("run_time_s");
    }
    rows
}

#[test]
fn shards_partition_and_merge_equals_one_run() {
    let d = tempfile::tempdir().unwrap();
    let shots = d.path().join("shots");
    good_folder(&shots, 11);
    write_shot(&shots.join("sub/f4_00.png"), 77); // same name as a top-level shot
    std::fs::write(shots.join("broken.jpg"), b"nope").unwrap();

    let all = d.path().join("all");
    let whole = run(&shots, &all, Shard::ALL);
    let mut outs: Vec<PathBuf> = Vec::new();
    let mut seen = Vec::new();
    for k in 1..=3 {
        let out = d.path().join(format!("shard{k}"));
        let o = run(&shots, &out, Shard { k, n: 3 });
        seen.extend(o.run.records.iter().map(|r| r.file.clone()));
        outs.push(out);
    }
    seen.sort();
    let mut expected: Vec<String> = whole.run.records.iter().map(|r| r.file.clone()).collect();
    expected.sort();
    assert_eq!(seen, expected, "shards must cover every shot exactly once");

    let merged = d.path().join("merged");
    let m = merge(&outs, &merged).unwrap();
    assert_eq!(m.missing, 0);
    assert_eq!(
        rows_without_time(&merged.join("summary.csv")),
        rows_without_time(&all.join("summary.csv"))
    );
    assert!(merged.join("report.html").is_file());
    assert!(merged.join("curves.png").is_file());
    // Per-shot files came along.
    for r in &m.records {
        if r.is_ok() {
            assert!(
                merged
                    .join("shots")
                    .join(format!("{}.mtf.csv", r.stem))
                    .is_file()
            );
        }
    }
    // Merging twice (or into one of the inputs) gives the same table.
    let again = merge(&outs, &merged).unwrap();
    assert_eq!(again.records.len(), m.records.len());
}

#[test]
fn merge_reports_shots_of_an_unfinished_shard() {
    let d = tempfile::tempdir().unwrap();
    let shots = d.path().join("shots");
    good_folder(&shots, 6);
    let a = d.path().join("a");
    let b = d.path().join("b");
    run(&shots, &a, Shard { k: 1, n: 2 });
    let ob = run(&shots, &b, Shard { k: 2, n: 2 });
    // Shard 2 "was stopped" before its first shot finished.
    let stem = &ob.run.records[0].stem;
    std::fs::remove_file(b.join("shots").join(format!("{stem}.done.json"))).unwrap();
    let m = merge(&[a, b], &d.path().join("m")).unwrap();
    assert_eq!(m.missing, 1);
    let bad: Vec<_> = m.records.iter().filter(|r| !r.is_ok()).collect();
    assert_eq!(bad.len(), 1);
    assert_eq!(&bad[0].stem, stem);
    assert!(
        bad[0]
            .error
            .as_ref()
            .unwrap()
            .contains("no complete result")
    );
}

#[test]
fn merge_refuses_a_folder_that_is_not_a_batch_output() {
    let d = tempfile::tempdir().unwrap();
    let e = merge(&[d.path().to_path_buf()], &d.path().join("m")).unwrap_err();
    assert!(e.to_string().contains("not a batch output folder"), "{e}");
}
