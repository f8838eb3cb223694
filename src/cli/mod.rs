//! Command-line front end: argument definitions per subcommand, and the
//! mapping of library errors to one clear line and a documented exit code.

use clap::{Parser, Subcommand};

mod batch;
mod chart;
mod chart_check;
mod exit;
pub(crate) mod factors;
mod gui;
pub(crate) mod measure;
pub(crate) mod measure_flags;
pub(crate) mod measure_model;
mod messages;
mod model;
mod simulate;

pub use exit::{CliError, Code};

/// Measure and model camera MTF with sine-sweep charts.
#[derive(Debug, Parser)]
#[command(name = "sweepmtf", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Also print notes (what was done or assumed) on stderr.
    #[arg(short, long, global = true, conflicts_with = "quiet")]
    verbose: bool,
    /// Print only errors on stderr (no warnings, notes or progress).
    #[arg(short, long, global = true)]
    quiet: bool,
}

#[derive(Debug, Subcommand)]
#[allow(clippy::large_enum_variant)] // parsed once; boxing buys nothing
enum Command {
    /// Measure the MTF from a photograph of a sine chart.
    Measure(measure::Args),
    /// Generate a printable sweep or sine-patch chart and its description.
    Chart(chart::Args),
    /// Say up to which image frequency a print is sharp enough for a camera set-up.
    ChartCheck(chart_check::Args),
    /// Measure every photo in one or more folders.
    Batch(batch::Args),
    /// Join the summaries of several batch output folders.
    Merge(batch::MergeArgs),
    /// Evaluate the theoretical MTF of optics and sensor.
    Model(model::Args),
    /// Render a target through a modelled camera, with the exact truth.
    Simulate(simulate::Args),
    /// Open a local page to measure by hand and explore the model.
    Gui(gui::Args),
}

/// Parses the command line, runs the subcommand and returns the exit code.
pub fn main() -> std::process::ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            return match e.kind() {
                clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion => {
                    let _ = e.print();
                    std::process::ExitCode::SUCCESS
                }
                _ => {
                    eprintln!("sweepmtf: {}", one_line(&e.render().to_string()));
                    Code::Usage.into()
                }
            };
        }
    };
    messages::set_level(cli.quiet, cli.verbose);
    let result = match &cli.command {
        Command::Measure(a) => measure::run(a),
        Command::Chart(a) => chart::run(a),
        Command::ChartCheck(a) => chart_check::run(a),
        Command::Batch(a) => batch::run(a),
        Command::Merge(a) => batch::run_merge(a),
        Command::Model(a) => model::run(a),
        Command::Simulate(a) => simulate::run(a),
        Command::Gui(a) => gui::run(a),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("sweepmtf: {}", e.message);
            e.code.into()
        }
    }
}

/// A clap error as one line: its text up to the usage hint, without the "error:" prefix.
fn one_line(text: &str) -> String {
    let parts: Vec<&str> = text
        .lines()
        .map(str::trim)
        .take_while(|l| !l.starts_with("Usage:") && !l.starts_with("For more information"))
        .filter(|l| !l.is_empty())
        .collect();
    let joined = parts.join(" ");
    let line = joined
        .strip_prefix("error: ")
        .unwrap_or(&joined)
        .to_string();
    format!("{line} (see --help)")
}
