//! Progress reporting without printing: the runner calls a [`Progress`]
//! implementation supplied by the caller (the CLI draws a bar on a terminal
//! or prints plain lines); [`progress_line`] formats one plain line.

use super::record::ShotRecord;

/// Receives the runner's progress events (called from worker threads).
pub trait Progress: Sync {
    /// The run starts: `total` shots, of which `skipped` are already complete.
    fn start(&self, _total: usize, _skipped: usize) {}
    /// Shot `rec` finished; `done` shots of `to_run` are finished so far.
    fn shot_done(&self, _rec: &ShotRecord, _done: usize, _to_run: usize) {}
    /// All shots are finished.
    fn finish(&self) {}
}

/// A progress sink that ignores every event.
#[derive(Debug, Default, Clone, Copy)]
pub struct NoProgress;

impl Progress for NoProgress {}

/// One plain progress line for a finished shot, e.g.
/// `[3/16] sub/f4.jpg: ok, MTF50 0.2134 cy/px (1.24 s)`.
pub fn progress_line(rec: &ShotRecord, done: usize, to_run: usize) -> String {
    let what = if rec.is_ok() {
        match rec.result.mtf50_cy_px {
            Some(v) => format!("ok, MTF50 {v:.4} cy/px"),
            None => "ok".to_string(),
        }
    } else {
        format!("error: {}", rec.error.as_deref().unwrap_or("unknown"))
    };
    format!(
        "[{done}/{to_run}] {}: {what} ({:.2} s)",
        rec.file, rec.run_time_s
    )
}
