//! `sweepmtf batch` and `sweepmtf merge`: arguments, the progress display
//! (a bar with ETA on a terminal, plain lines otherwise) and exit codes
//! (0 all shots measured, 7 some failed).

use super::{CliError, Code};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::Mutex;
use sweepmtf::batch::{
    self, BatchError, Progress, RunOptions, Shard, ShotRecord, measure_job::MeasureJob,
    progress::progress_line, roi_file::RoiTable,
};

/// Arguments of `sweepmtf batch`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Folders (or single photos) to measure.
    #[arg(required = true, value_name = "DIR")]
    pub inputs: Vec<PathBuf>,
    /// Output folder (summary.csv, report.html, pictures, shots/).
    #[arg(short = 'o', long = "out", value_name = "OUT")]
    pub out: PathBuf,
    /// Search sub-folders too.
    #[arg(short = 'r', long)]
    pub recursive: bool,
    /// Threads in all (default: number of cores): up to N shots at once, each on
    /// ⌊N / shots at once⌋ threads.
    #[arg(short = 'j', long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub jobs: Option<u32>,
    /// Measure only share K of N of the sorted file list (1 ≤ K ≤ N), for job arrays.
    #[arg(long, value_name = "K/N", value_parser = parse_shard)]
    pub shard: Option<Shard>,
    /// Redo every shot, even complete ones.
    #[arg(long)]
    pub force: bool,
    /// Redo shots whose earlier result is an error.
    #[arg(long)]
    pub retry_failed: bool,
    /// Per-shot regions: CSV with columns file,x1,y1,x2,y2,x3,y3,x4,y4.
    #[arg(long, value_name = "ROIS.csv")]
    pub roi_file: Option<PathBuf>,
    /// Measurement options (as `sweepmtf measure` takes them).
    #[command(flatten)]
    pub measure: super::measure_flags::MeasureFlags,
}

fn parse_shard(s: &str) -> Result<Shard, String> {
    s.parse::<Shard>().map_err(|e| e.to_string())
}

/// Arguments of `sweepmtf merge`.
#[derive(Debug, clap::Args)]
pub struct MergeArgs {
    /// Output folders of `sweepmtf batch` runs (e.g. one per shard).
    #[arg(required = true, value_name = "OUT_K")]
    pub inputs: Vec<PathBuf>,
    /// Merged output folder.
    #[arg(short = 'o', long = "out", value_name = "OUT")]
    pub out: PathBuf,
}

fn cli_error(e: BatchError) -> CliError {
    let code = match &e {
        BatchError::Input { .. } | BatchError::NoShots(_) => Code::Input,
        BatchError::Output { .. } => Code::Output,
        BatchError::Usage(_) => Code::Usage,
        BatchError::Locked { .. } => Code::Busy,
    };
    CliError::new(code, e.to_string())
}

/// Progress on stderr: an indicatif bar on a terminal, plain lines otherwise.
enum Display {
    Quiet,
    Lines(Mutex<()>),
    Bar(indicatif::ProgressBar),
}

impl Progress for Display {
    fn start(&self, total: usize, skipped: usize) {
        let line = format!(
            "{total} shot{}: {skipped} already complete, {} to measure",
            if total == 1 { "" } else { "s" },
            total - skipped
        );
        match self {
            Display::Quiet => {}
            Display::Lines(_) => eprintln!("{line}"),
            Display::Bar(b) => {
                b.set_length((total - skipped) as u64);
                b.println(line);
            }
        }
    }
    fn shot_done(&self, rec: &ShotRecord, done: usize, to_run: usize) {
        match self {
            Display::Quiet => {}
            Display::Lines(lock) => {
                let _g = lock.lock();
                eprintln!("{}", progress_line(rec, done, to_run));
            }
            Display::Bar(b) => {
                if !rec.is_ok() {
                    b.println(format!(
                        "{}: {}",
                        rec.file,
                        rec.error.as_deref().unwrap_or("error")
                    ));
                }
                b.set_message(rec.file.clone());
                b.inc(1);
            }
        }
    }
    fn finish(&self) {
        if let Display::Bar(b) = self {
            b.finish_and_clear();
        }
    }
}

fn display(quiet: bool) -> Display {
    if quiet {
        Display::Quiet
    } else if std::io::stderr().is_terminal() {
        let bar = indicatif::ProgressBar::new(0);
        bar.set_style(
            indicatif::ProgressStyle::with_template(
                "{bar:40.cyan/blue} {pos}/{len} shots  {elapsed_precise} elapsed, ETA {eta}  {wide_msg}",
            )
            .expect("valid template"),
        );
        Display::Bar(bar)
    } else {
        Display::Lines(Mutex::new(()))
    }
}

/// Keeps the default panic message off the terminal for batch worker
/// threads (their panics become error rows) and for nothing else.
fn quiet_worker_panics() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let worker = std::thread::current()
            .name()
            .is_some_and(|n| n.starts_with(batch::runner::WORKER_THREAD_PREFIX));
        if !worker {
            default(info);
        }
    }));
}

/// Runs `sweepmtf batch`.
pub fn run(args: &Args) -> Result<(), CliError> {
    let shard = args.shard.unwrap_or(Shard::ALL);
    let rois = match &args.roi_file {
        Some(p) => RoiTable::read(p).map_err(cli_error)?,
        None => RoiTable::default(),
    };
    let plan = batch::plan(&args.inputs, args.recursive, &args.out, shard).map_err(cli_error)?;
    let options = args.measure.options()?;
    // A target description that cannot be read fails every shot the same
    // way: say so once, before measuring anything.
    sweepmtf::measure::load_target(&options)
        .map_err(|f| CliError::new(Code::Input, f.to_string()))?;
    let job = MeasureJob {
        options,
        plot: args.measure.plot,
        rois,
    };
    let opts = RunOptions {
        jobs: args
            .jobs
            .map(|j| j as usize)
            .unwrap_or_else(|| RunOptions::default().jobs),
        force: args.force,
        retry_failed: args.retry_failed,
    };
    let quiet = super::messages::level() == super::messages::Level::Quiet;
    quiet_worker_panics();
    let progress = display(quiet);
    let outcome = batch::run_batch(&plan, &args.out, &job, &opts, &progress).map_err(cli_error)?;
    let failed = outcome.run.failed();
    let total = outcome.run.records.len();
    if !quiet {
        eprintln!(
            "{} of {total} shots measured ({} this run, {} skipped as complete), {failed} failed; summary: {}",
            total - failed,
            outcome.run.measured,
            outcome.run.skipped,
            args.out.join(batch::SUMMARY_CSV).display()
        );
    }
    if failed > 0 {
        return Err(CliError::new(
            Code::Partial,
            format!(
                "{failed} of {total} shots failed (error rows in {})",
                args.out.join(batch::SUMMARY_CSV).display()
            ),
        ));
    }
    Ok(())
}

/// Runs `sweepmtf merge`.
pub fn run_merge(args: &MergeArgs) -> Result<(), CliError> {
    let m = batch::merge::merge(&args.inputs, &args.out).map_err(cli_error)?;
    let failed = m.records.iter().filter(|r| !r.is_ok()).count();
    if super::messages::level() > super::messages::Level::Quiet {
        eprintln!(
            "merged {} shots from {} folders ({} missing), {failed} failed; summary: {}",
            m.records.len(),
            args.inputs.len(),
            m.missing,
            args.out.join(batch::SUMMARY_CSV).display()
        );
    }
    if failed > 0 {
        return Err(CliError::new(
            Code::Partial,
            format!(
                "{failed} of {} shots failed or are missing",
                m.records.len()
            ),
        ));
    }
    Ok(())
}
