//! Interruption: a batch process killed (SIGKILL) at several moments leaves
//! only complete per-shot results (every marker's outputs exist and are
//! whole), and the next run skips those and finishes the rest.
//!
//! The killed process is this test binary itself, re-run with an environment
//! variable that makes the test body run a slow batch instead.

use crate::batch_stub;

use batch_stub::*;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use sweepmtf::batch::atomic::TEMP_PREFIX;
use sweepmtf::batch::{self, NoProgress, RunOptions, Shard, resume};

const CHILD_ENV: &str = "SWEEPMTF_BATCH_KILL_CHILD";
const SHOTS: usize = 24;

fn run_batch(shots: &Path, out: &Path, sleep_ms: u64) -> batch::BatchOutcome {
    let plan = batch::plan(&[shots.to_path_buf()], false, out, Shard::ALL).unwrap();
    let job = StubJob::new("kill-test", sleep_ms);
    let opts = RunOptions {
        jobs: 2,
        force: false,
        retry_failed: false,
    };
    batch::run_batch(&plan, out, &job, &opts, &NoProgress).unwrap()
}

fn markers(shots_dir: &Path) -> Vec<String> {
    let Ok(rd) = std::fs::read_dir(shots_dir) else {
        return vec![];
    };
    let mut v: Vec<String> = rd
        .filter_map(|e| {
            let n = e.ok()?.file_name().to_string_lossy().into_owned();
            if n.starts_with(TEMP_PREFIX) {
                return None; // a killed write, not a marker
            }
            n.strip_suffix(resume::MARKER_SUFFIX).map(str::to_string)
        })
        .collect();
    v.sort();
    v
}

/// Every marker is whole and every output it lists exists and is whole.
fn check_only_complete_results(out: &Path) -> usize {
    let shots_dir = out.join("shots");
    let stems = markers(&shots_dir);
    for stem in &stems {
        let m = resume::read_marker(&shots_dir, stem)
            .unwrap_or_else(|| panic!("marker of {stem} is unreadable"));
        assert!(m.record.is_ok(), "{stem}: {:?}", m.record.error);
        assert!(
            resume::outputs_present(&shots_dir, &m),
            "{stem}: outputs missing"
        );
        let curve =
            batch::curve::read_curve(&shots_dir.join(m.record.result.curve_file.unwrap())).unwrap();
        assert_eq!(curve.len(), 51, "{stem}: curve file incomplete");
    }
    // The summary, when present, is a whole table.
    let summary = out.join("summary.csv");
    if summary.exists() {
        let rows = read_summary(&summary);
        assert!(rows.iter().all(|r| r.contains_key("warnings")));
    }
    stems.len()
}

#[test]
fn killed_run_leaves_only_complete_shots_and_rerun_finishes() {
    if let Ok(dir) = std::env::var(CHILD_ENV) {
        let dir = Path::new(&dir);
        run_batch(&dir.join("shots"), &dir.join("out"), 120);
        return;
    }
    let d = tempfile::tempdir().unwrap();
    let shots = d.path().join("shots");
    good_folder(&shots, SHOTS);
    let out = d.path().join("out");
    let mut last = 0;
    for kill_after in [2, 5, 8] {
        let mut child = Command::new(std::env::current_exe().unwrap())
            .args([
                "--exact",
                "batch_resume::killed_run_leaves_only_complete_shots_and_rerun_finishes",
                "--test-threads=1",
            ])
            .env(CHILD_ENV, d.path())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let t0 = Instant::now();
        while markers(&out.join("shots")).len() < kill_after {
            assert!(
                t0.elapsed() < Duration::from_secs(60),
                "child made no progress"
            );
            assert!(
                child.try_wait().unwrap().is_none(),
                "child ended before the kill"
            );
            std::thread::sleep(Duration::from_millis(5));
        }
        child.kill().unwrap(); // SIGKILL on Unix
        child.wait().unwrap();
        let n = check_only_complete_results(&out);
        assert!(
            n >= last && n < SHOTS,
            "{n} complete after kill (before: {last})"
        );
        last = n;
    }
    // The rerun skips every complete shot and measures the rest.
    let o = run_batch(&shots, &out, 0);
    assert_eq!(o.run.skipped, last);
    assert_eq!(o.run.measured, SHOTS - last);
    assert_eq!(o.run.failed(), 0);
    assert_eq!(check_only_complete_results(&out), SHOTS);
    let rows = read_summary(&out.join("summary.csv"));
    assert_eq!(rows.len(), SHOTS);
    // No temporary file of the killed runs is left.
    for (p, _) in snapshot(&out) {
        assert!(
            !p.to_string_lossy().contains(".sweepmtf-tmp-"),
            "{}",
            p.display()
        );
    }
}
