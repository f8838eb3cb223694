//! The parallel runner: measures planned shots on `jobs` worker threads that
//! take the next shot from a shared counter. Each worker holds one shot at a
//! time and the job decodes its own file, so at most `jobs` decoded images
//! are alive at once (no queue of decoded images).
//!
//! The run uses `jobs` threads in all. Each worker measures inside its own
//! rayon pool of [`in_shot_threads`] threads, itself included: one thread
//! when there are at least `jobs` shots, so two shots never compete for a
//! core with each other's inner work, and a decoder that parallelises inside
//! (rawler does, with rayon) runs on its worker's pool, never on a pool
//! shared with another worker (a worker waiting there could not start a
//! further shot). A panic inside a job is caught and becomes that shot's
//! error row; every other shot is still measured. Complete shots from an
//! earlier run are skipped (see [`super::resume`]).

use super::progress::Progress;
use super::record::{FailKind, ShotFailure, ShotRecord, ShotResult, Status};
use super::resume::{self, InputStamp, Marker};
use super::{BatchError, atomic};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

/// Prefix of the worker threads' names (the CLI's panic hook stays quiet on them).
pub const WORKER_THREAD_PREFIX: &str = "sweepmtf-batch-";

/// One shot to measure, with its place in the full file list and its output stem.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlannedShot {
    /// Position in the full (unsharded) sorted file list.
    pub index: usize,
    /// Path to open.
    pub source: PathBuf,
    /// Path shown to the user (see [`super::discover::FoundShot::display`]).
    pub file: String,
    /// Stem of the per-shot outputs.
    pub stem: String,
}

/// The per-shot work: measure one photo and write its outputs.
pub trait ShotJob: Sync {
    /// Text that changes whenever a setting that affects this shot's result
    /// changes (options, its region, the program version); hashed into the marker.
    fn fingerprint(&self, shot: &PlannedShot) -> String;
    /// Measures `shot`, writing its outputs into `shots_dir` named
    /// `{shot.stem}.*` (atomically) and listing them in the result.
    fn run(&self, shot: &PlannedShot, shots_dir: &Path) -> Result<ShotResult, ShotFailure>;
}

/// A [`ShotJob`] from a closure `(input file, shots folder, stem)` and a fixed
/// settings fingerprint.
pub struct FnJob<F> {
    /// Settings fingerprint shared by every shot.
    pub fingerprint: String,
    /// The per-shot function.
    pub f: F,
}

impl<F> ShotJob for FnJob<F>
where
    F: Fn(&Path, &Path, &str) -> Result<ShotResult, ShotFailure> + Sync,
{
    fn fingerprint(&self, _shot: &PlannedShot) -> String {
        self.fingerprint.clone()
    }
    fn run(&self, shot: &PlannedShot, shots_dir: &Path) -> Result<ShotResult, ShotFailure> {
        (self.f)(&shot.source, shots_dir, &shot.stem)
    }
}

/// How to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunOptions {
    /// Threads in all (≥ 1): worker threads, and the threads they share inside shots.
    pub jobs: usize,
    /// Redo every shot, complete or not.
    pub force: bool,
    /// Redo shots whose stored result is an error.
    pub retry_failed: bool,
}

impl Default for RunOptions {
    fn default() -> Self {
        RunOptions {
            jobs: std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1),
            force: false,
            retry_failed: false,
        }
    }
}

/// What a run did.
#[derive(Debug, Clone, PartialEq)]
pub struct RunOutcome {
    /// One record per planned shot, in file-list order.
    pub records: Vec<ShotRecord>,
    /// Shots measured in this run.
    pub measured: usize,
    /// Shots skipped because they were complete.
    pub skipped: usize,
}

impl RunOutcome {
    /// Number of shots whose record is an error.
    pub fn failed(&self) -> usize {
        self.records.iter().filter(|r| !r.is_ok()).count()
    }
}

/// Runs `job` over `shots`, writing per-shot outputs into `shots_dir`.
pub fn run_shots(
    shots: &[PlannedShot],
    shots_dir: &Path,
    job: &dyn ShotJob,
    opts: &RunOptions,
    progress: &dyn Progress,
) -> Result<RunOutcome, BatchError> {
    std::fs::create_dir_all(shots_dir).map_err(|e| BatchError::output(shots_dir, e))?;
    atomic::remove_stale_temps(shots_dir, true).map_err(|e| BatchError::output(shots_dir, e))?;

    let mut records: Vec<Option<ShotRecord>> = vec![None; shots.len()];
    let mut todo = Vec::new();
    for (i, shot) in shots.iter().enumerate() {
        let hash = resume::fingerprint_hash(&job.fingerprint(shot));
        let stamp = InputStamp::of(&shot.source).ok();
        let done = match (&stamp, opts.force) {
            (Some(st), false) => {
                resume::complete_record(shots_dir, &shot.stem, &shot.file, st, &hash)
                    .filter(|r| r.is_ok() || !opts.retry_failed)
            }
            _ => None,
        };
        match done {
            Some(mut rec) => {
                rec.index = shot.index;
                records[i] = Some(rec);
            }
            None => todo.push((i, hash)),
        }
    }
    let skipped = shots.len() - todo.len();
    progress.start(shots.len(), skipped);

    let next = AtomicUsize::new(0);
    let finished = AtomicUsize::new(0);
    let to_run = todo.len();
    let workers = opts.jobs.max(1).min(to_run.max(1));
    let threads = in_shot_threads(opts.jobs, workers);
    let done: Vec<(usize, ShotRecord)> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..workers)
            .map(|w| {
                let (next, finished, todo) = (&next, &finished, &todo);
                std::thread::Builder::new()
                    .name(format!("{WORKER_THREAD_PREFIX}{w}"))
                    .spawn_scoped(scope, move || {
                        let mut mine = Vec::new();
                        let mut work = || loop {
                            let t = next.fetch_add(1, Ordering::SeqCst);
                            let Some((i, hash)) = todo.get(t) else { break };
                            let rec = run_one(&shots[*i], shots_dir, job, hash);
                            let n = finished.fetch_add(1, Ordering::SeqCst) + 1;
                            progress.shot_done(&rec, n, to_run);
                            mine.push((*i, rec));
                        };
                        // The worker's own pool: a measurement's inner
                        // parallelism stays on this worker's share of the
                        // `jobs` threads. Without it the pool cannot be made,
                        // and the shots use the global pool as before.
                        match worker_pool(threads) {
                            Some(pool) => pool.install(work),
                            None => work(),
                        }
                        mine
                    })
            })
            .collect::<Result<_, _>>()
            .map_err(|e| {
                BatchError::Usage(format!("cannot start {workers} worker threads: {e}"))
            })?;
        // A worker never panics (jobs run under catch_unwind); if one did, its
        // shots are reported below as missing records, not lost silently.
        Ok::<_, BatchError>(
            handles
                .into_iter()
                .flat_map(|h| h.join().unwrap_or_default())
                .collect(),
        )
    })?;
    for (i, rec) in done {
        records[i] = Some(rec);
    }
    progress.finish();
    Ok(RunOutcome {
        records: records
            .into_iter()
            .map(|r| r.expect("every shot has a record"))
            .collect(),
        measured: to_run,
        skipped,
    })
}

/// Threads each of `workers` workers may use inside one shot so that the
/// run uses `jobs` threads in all: with as many shots at once as cores, each
/// shot is measured on one thread (no two shots' inner work competing for a
/// core); with fewer shots than `jobs`, the spare threads help inside them.
pub fn in_shot_threads(jobs: usize, workers: usize) -> usize {
    (jobs.max(1) / workers.max(1)).max(1)
}

/// A pool of `threads` threads that includes the calling worker thread
/// (so a one-thread pool runs everything on the worker itself); `None` if
/// the system refuses the threads.
fn worker_pool(threads: usize) -> Option<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .use_current_thread()
        .thread_name(|i| format!("{WORKER_THREAD_PREFIX}inner-{i}"))
        .build()
        .ok()
}

fn panic_message(payload: &(dyn std::any::Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "unknown panic".to_string()
    }
}

/// Measures one shot: clears its marker, runs the job (catching panics),
/// checks the listed outputs, and writes the marker last.
fn run_one(shot: &PlannedShot, shots_dir: &Path, job: &dyn ShotJob, hash: &str) -> ShotRecord {
    let t0 = Instant::now();
    let mut rec = ShotRecord {
        index: shot.index,
        file: shot.file.clone(),
        stem: shot.stem.clone(),
        status: Status::Ok,
        error_kind: None,
        error: None,
        result: ShotResult::default(),
        run_time_s: 0.0,
    };
    let fail = |rec: &mut ShotRecord, f: ShotFailure| {
        rec.status = Status::Error;
        rec.error_kind = Some(f.kind);
        rec.error = Some(f.message);
        rec.result = ShotResult::default();
    };
    if let Err(e) = resume::clear_marker(shots_dir, &shot.stem) {
        fail(
            &mut rec,
            ShotFailure::new(FailKind::Output, format!("cannot remove old marker: {e}")),
        );
        return rec;
    }
    let stamp = match InputStamp::of(&shot.source) {
        Ok(s) => s,
        Err(e) => {
            fail(
                &mut rec,
                ShotFailure::new(FailKind::Input, format!("cannot read: {e}")),
            );
            rec.run_time_s = t0.elapsed().as_secs_f64();
            return rec;
        }
    };
    let outcome = catch_unwind(AssertUnwindSafe(|| job.run(shot, shots_dir))).unwrap_or_else(|p| {
        Err(ShotFailure::new(
            FailKind::Panic,
            format!(
                "internal error (panic) while measuring: {}",
                panic_message(&*p)
            ),
        ))
    });
    match outcome {
        Ok(result) => {
            rec.result = result;
            if let Some(missing) = rec
                .result
                .outputs
                .iter()
                .find(|o| !shots_dir.join(o).is_file())
            {
                let msg = format!("output {missing} was not written");
                fail(&mut rec, ShotFailure::new(FailKind::Output, msg));
            }
        }
        Err(f) => fail(&mut rec, f),
    }
    rec.run_time_s = t0.elapsed().as_secs_f64();
    let keep = rec.error_kind.is_none_or(|k| k.is_deterministic());
    if keep
        && let Err(e) = resume::write_marker(
            shots_dir,
            &Marker::new(hash.to_string(), stamp, rec.clone()),
        )
    {
        fail(
            &mut rec,
            ShotFailure::new(FailKind::Output, format!("cannot write marker: {e}")),
        );
    }
    rec
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::batch::progress::NoProgress;

    #[test]
    fn jobs_are_shared_between_workers_and_their_shots() {
        assert_eq!(in_shot_threads(1, 1), 1);
        assert_eq!(in_shot_threads(2, 2), 1);
        assert_eq!(in_shot_threads(2, 1), 2);
        assert_eq!(in_shot_threads(8, 3), 2);
        assert_eq!(in_shot_threads(0, 0), 1);
    }

    /// Each shot records how many threads its inner parallel work may use
    /// (as its MTF50, which nothing reads here).
    fn threads_seen(n_shots: usize, jobs: usize) -> Vec<usize> {
        let dir = tempfile::tempdir().unwrap();
        let shots: Vec<PlannedShot> = (0..n_shots)
            .map(|i| {
                let source = dir.path().join(format!("s{i}.jpg"));
                std::fs::write(&source, b"x").unwrap();
                PlannedShot {
                    index: i,
                    source,
                    file: format!("s{i}.jpg"),
                    stem: format!("s{i}"),
                }
            })
            .collect();
        let job = FnJob {
            fingerprint: "t".into(),
            f: |_: &Path, _: &Path, _: &str| {
                let n = rayon::join(rayon::current_num_threads, || 0).0;
                Ok(ShotResult {
                    mtf50_cy_px: Some(n as f64),
                    ..ShotResult::default()
                })
            },
        };
        let opts = RunOptions {
            jobs,
            force: true,
            retry_failed: false,
        };
        let out = run_shots(&shots, &dir.path().join("shots"), &job, &opts, &NoProgress).unwrap();
        out.records
            .iter()
            .map(|r| r.result.mtf50_cy_px.unwrap_or_else(|| panic!("{r:?}")) as usize)
            .collect()
    }

    #[test]
    fn a_full_run_measures_each_shot_on_one_thread_and_a_short_one_shares_the_spare() {
        assert_eq!(threads_seen(5, 2), vec![1; 5]);
        assert_eq!(threads_seen(3, 1), vec![1; 3]);
        assert_eq!(threads_seen(1, 2), vec![2]);
    }
}
