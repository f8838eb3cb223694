//! Batch processing of shot folders: find every photo ([`discover`]), give
//! each a unique output name ([`names`]), keep this shard's share
//! ([`shard`]), measure them in parallel with failure isolation and resume
//! ([`runner`], [`resume`]), and write the summary table, the summary
//! pictures and a self-contained HTML report ([`summary`], [`plots`],
//! [`html`]); [`merge`] joins the output folders of several shards.
//!
//! The per-shot work is a [`runner::ShotJob`]; [`measure_job`] holds the glue
//! to the single-shot measurement. Output folder layout:
//! `OUT/batch.json` (the plan), `OUT/shots/STEM.*` (per-shot files and the
//! `STEM.done.json` completion markers), `OUT/summary.csv`, `OUT/curves.png`,
//! `OUT/mtf50_vs_f_number.png`, `OUT/report.html`.

use std::path::{Path, PathBuf};
use thiserror::Error;

pub mod atomic;
pub mod base64;
pub mod curve;
pub mod discover;
pub mod html;
pub mod lock;
pub mod manifest;
pub mod measure_job;
pub mod merge;
pub mod names;
pub mod plots;
pub mod progress;
pub mod record;
pub mod resume;
pub mod roi_file;
pub mod runner;
pub mod shard;
pub mod summary;

pub use progress::{NoProgress, Progress};
pub use record::{FailKind, ShotFailure, ShotRecord, ShotResult, Status};
pub use runner::{PlannedShot, RunOptions, RunOutcome, ShotJob};
pub use shard::Shard;

/// Per-shot folder inside the output folder.
pub const SHOTS_DIR: &str = "shots";
/// Summary table file name.
pub const SUMMARY_CSV: &str = "summary.csv";
/// Overlay of all curves.
pub const CURVES_PNG: &str = "curves.png";
/// MTF50 against f-number.
pub const F_NUMBER_PNG: &str = "mtf50_vs_f_number.png";
/// The HTML report.
pub const REPORT_HTML: &str = "report.html";

/// Why a batch could not run (per-shot failures are rows, not errors).
#[derive(Debug, Error)]
pub enum BatchError {
    /// An input folder or file cannot be read.
    #[error("{path}: {cause}")]
    Input {
        /// The path.
        path: String,
        /// The cause.
        cause: String,
    },
    /// No photo was found in the inputs.
    #[error(
        "no photos found in {0} (extensions: jpg jpeg png tif tiff dng cr2 cr3 nef arw orf rw2 raf pef srw)"
    )]
    NoShots(String),
    /// A batch output cannot be written.
    #[error("{path}: cannot write: {source}")]
    Output {
        /// The path.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// A bad option value.
    #[error("{0}")]
    Usage(String),
    /// Another run holds the output folder's lock.
    #[error(
        "{dir}: output folder in use by {holder} (lock file {dir}/.sweepmtf.lock); wait for it to finish or choose another folder"
    )]
    Locked {
        /// The output folder.
        dir: String,
        /// Who holds it ("process 1234").
        holder: String,
    },
}

impl BatchError {
    /// An input error for `path`.
    pub fn input(path: &Path, e: impl std::fmt::Display) -> Self {
        BatchError::Input {
            path: path.display().to_string(),
            cause: e.to_string(),
        }
    }
    /// An output error for `path`.
    pub fn output(path: &Path, e: std::io::Error) -> Self {
        BatchError::Output {
            path: path.display().to_string(),
            source: e,
        }
    }
}

/// The shots of a run: the full sorted list and this shard's share.
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// Number of shots in the full list.
    pub total: usize,
    /// The shard.
    pub shard: Shard,
    /// This shard's shots, in file-list order.
    pub shots: Vec<PlannedShot>,
}

/// Finds the photos in `inputs`, names their outputs and keeps `shard`'s share;
/// `out` (the output folder) is never searched.
pub fn plan(
    inputs: &[PathBuf],
    recursive: bool,
    out: &Path,
    shard: Shard,
) -> Result<Plan, BatchError> {
    let found = discover::discover(inputs, recursive, Some(out))?;
    if found.is_empty() {
        let list = inputs
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ");
        return Err(BatchError::NoShots(list));
    }
    let displays: Vec<String> = found.iter().map(|f| f.display.clone()).collect();
    let stems = names::unique_stems(&displays);
    let total = found.len();
    let shots = found
        .into_iter()
        .zip(stems)
        .enumerate()
        .filter(|(i, _)| shard.contains(*i))
        .map(|(index, (f, stem))| PlannedShot {
            index,
            source: f.source,
            file: f.display,
            stem,
        })
        .collect();
    Ok(Plan {
        total,
        shard,
        shots,
    })
}

/// What a whole batch did.
#[derive(Debug, Clone, PartialEq)]
pub struct BatchOutcome {
    /// The runner's outcome (records in file-list order).
    pub run: RunOutcome,
    /// Files written in the output folder (summary, pictures, report).
    pub reports: Vec<PathBuf>,
}

/// Runs a planned batch into output folder `out`: writes the manifest,
/// measures (or skips) every shot, then rebuilds summary, pictures and report.
pub fn run_batch(
    plan: &Plan,
    out: &Path,
    job: &dyn ShotJob,
    opts: &RunOptions,
    progress: &dyn Progress,
) -> Result<BatchOutcome, BatchError> {
    std::fs::create_dir_all(out).map_err(|e| BatchError::output(out, e))?;
    // Before anything is touched: a second run must not remove this run's temporaries.
    let _lock = lock::FolderLock::acquire(out)?;
    atomic::remove_stale_temps(out, false).map_err(|e| BatchError::output(out, e))?;
    manifest::Manifest::of_run(plan.shard.to_string(), plan.total, &plan.shots).write(out)?;
    let run = runner::run_shots(&plan.shots, &out.join(SHOTS_DIR), job, opts, progress)?;
    let title = if plan.shard.n > 1 {
        format!("sweepmtf batch, shard {}", plan.shard)
    } else {
        "sweepmtf batch".to_string()
    };
    let reports = write_reports(out, &run.records, &title)?;
    Ok(BatchOutcome { run, reports })
}

/// Writes `summary.csv`, the pictures and `report.html` into `out` from
/// `records` (curves are read from the per-shot files in `out/shots`).
pub fn write_reports(
    out: &Path,
    records: &[ShotRecord],
    title: &str,
) -> Result<Vec<PathBuf>, BatchError> {
    let shots_dir = out.join(SHOTS_DIR);
    let mut written = Vec::new();
    let summary_path = out.join(SUMMARY_CSV);
    summary::write_summary(&summary_path, records)?;
    written.push(summary_path);

    let curves: Vec<(&ShotRecord, Vec<(f64, f64)>)> = records
        .iter()
        .filter(|r| r.is_ok())
        .filter_map(|r| {
            let f = r.result.curve_file.as_ref()?;
            let pts = curve::read_curve(&shots_dir.join(f)).ok()?;
            (!pts.is_empty()).then_some((r, pts))
        })
        .collect();
    let png_err = |p: &Path, e: String| BatchError::output(p, std::io::Error::other(e));
    let mut pictures: Vec<(&str, Vec<u8>)> = Vec::new();
    let curves_path = out.join(CURVES_PNG);
    if !curves.is_empty() {
        let png = plots::curves_png(&curves).map_err(|e| png_err(&curves_path, e))?;
        atomic::write_atomic(&curves_path, &png)
            .map_err(|e| BatchError::output(&curves_path, e))?;
        written.push(curves_path);
        pictures.push((
            "MTF curves of all measured shots (aliased points left out)",
            png,
        ));
    } else {
        let _ = std::fs::remove_file(&curves_path);
    }
    let fnum_path = out.join(F_NUMBER_PNG);
    match plots::mtf50_f_number_png(records).map_err(|e| png_err(&fnum_path, e))? {
        Some(png) => {
            atomic::write_atomic(&fnum_path, &png)
                .map_err(|e| BatchError::output(&fnum_path, e))?;
            written.push(fnum_path);
            pictures.push(("MTF50 against f-number (line: median per aperture)", png));
        }
        None => {
            let _ = std::fs::remove_file(&fnum_path);
        }
    }
    let pics: Vec<html::Picture<'_>> = pictures
        .iter()
        .map(|(c, p)| html::Picture { caption: c, png: p })
        .collect();
    let page = html::report_html(title, records, &pics, SHOTS_DIR);
    let html_path = out.join(REPORT_HTML);
    atomic::write_atomic(&html_path, page.as_bytes())
        .map_err(|e| BatchError::output(&html_path, e))?;
    written.push(html_path);
    Ok(written)
}
