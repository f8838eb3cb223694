//! `sweepmtf model`: evaluates the theoretical OTF of the named factors at
//! given points (`--at`), along a 1-D cut (`--cut`, CSV + plot) or as a 2-D
//! map (`--map`, PNG).

use super::factors::FactorArgs;
use super::{CliError, Code};
use std::path::{Path, PathBuf};
use sweepmtf::report::atomic::write_all_atomic;
use sweepmtf::report::model_cut::{
    CutDirection, F_MAX_LIMIT_CY_MM, POINTS_LIMIT, compute_cut, cut_csv, plot_cut_bytes,
};
use sweepmtf::report::model_io::OutputError;
use sweepmtf::report::model_map::{compute_map, write_map_png};
use sweepmtf::report::model_points::{read_points, write_points};

/// Arguments of `sweepmtf model`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The model factors.
    #[command(flatten)]
    pub factors: FactorArgs,
    /// Evaluate at the points of this CSV (header u_cy_mm,v_cy_mm).
    #[arg(long, value_name = "POINTS.csv", conflicts_with_all = ["cut", "map"])]
    pub at: Option<PathBuf>,
    /// 1-D cut along u, v or deg=θ (degrees from the u axis).
    #[arg(long, value_name = "u|v|deg=θ", conflicts_with = "map")]
    pub cut: Option<String>,
    /// 2-D map of the MTF over ±f-max in u and v (PNG).
    #[arg(long)]
    pub map: bool,
    /// Highest frequency of a cut, or half-width of a map, cycles/mm.
    #[arg(long, value_name = "CY_PER_MM")]
    pub f_max: Option<f64>,
    /// Number of samples of a cut.
    #[arg(long, default_value_t = 1001)]
    pub points: usize,
    /// Samples per side of a map.
    #[arg(long, default_value_t = 1024)]
    pub size: usize,
    /// Plot file of a cut (PNG, or SVG by extension); default: OUT with .png.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Output file: CSV for --at and --cut, PNG for --map.
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
}

fn output_error(e: OutputError) -> CliError {
    CliError::new(Code::Output, e.to_string())
}

fn f_max(args: &Args) -> Result<f64, CliError> {
    match args.f_max {
        Some(f) if f.is_finite() && f > 0.0 && f <= F_MAX_LIMIT_CY_MM => Ok(f),
        Some(f) => Err(CliError::usage(format!(
            "--f-max must be a number of cycles/mm in (0, {F_MAX_LIMIT_CY_MM:e}], got {f}"
        ))),
        None => Err(CliError::usage(
            "--f-max <cycles/mm> is required with --cut and --map",
        )),
    }
}

/// The plot path beside a cut's CSV: OUT.csv → OUT.png.
fn plot_beside(csv: &Path) -> PathBuf {
    csv.with_extension("png")
}

/// Runs `sweepmtf model`.
pub fn run(args: &Args) -> Result<(), CliError> {
    let modes = args.at.is_some() as u8 + args.cut.is_some() as u8 + args.map as u8;
    if modes != 1 {
        return Err(CliError::usage(
            "give one output mode: --at POINTS.csv, --cut u|v|deg=θ, or --map",
        ));
    }
    let output = args
        .output
        .as_ref()
        .ok_or_else(|| CliError::usage("-o/--output FILE is required"))?;
    // Validate the cheap arguments before building the model.
    let direction = args
        .cut
        .as_deref()
        .map(CutDirection::parse)
        .transpose()
        .map_err(|e| CliError::usage(format!("--cut: {e}")))?;
    if args.cut.is_some() || args.map {
        f_max(args)?;
    }
    if args.cut.is_some() && !(2..=POINTS_LIMIT).contains(&args.points) {
        return Err(CliError::usage(format!(
            "--points must be between 2 and {POINTS_LIMIT}, got {}",
            args.points
        )));
    }
    if args.map && !(2..=4096).contains(&args.size) {
        return Err(CliError::usage(format!(
            "--size must be between 2 and 4096, got {}",
            args.size
        )));
    }
    if args.map
        && output
            .extension()
            .is_some_and(|x| !x.eq_ignore_ascii_case("png"))
    {
        return Err(CliError::usage(format!(
            "--map writes a PNG image; {} does not end in .png",
            output.display()
        )));
    }
    let (name, system) = args.factors.build_named()?;
    let title = name.unwrap_or_else(|| {
        system
            .factors
            .iter()
            .map(|f| f.name())
            .collect::<Vec<_>>()
            .join(" × ")
    });

    if let Some(points_path) = &args.at {
        let pts = read_points(points_path).map_err(|e| CliError::new(Code::Input, e))?;
        write_points(&system, &pts, output).map_err(output_error)?;
    } else if let Some(dir) = direction {
        let cut = compute_cut(&system, dir, f_max(args)?, args.points);
        let plot = args.plot.clone().unwrap_or_else(|| plot_beside(output));
        if plot == *output {
            return Err(CliError::usage(format!(
                "the plot would overwrite the CSV {}; give --plot FILE",
                output.display()
            )));
        }
        // Both files or neither: the plot is drawn before anything is written.
        let png = plot_cut_bytes(&cut, &format!("MTF: {title}"), &plot).map_err(output_error)?;
        let files = [
            (output.clone(), cut_csv(&cut).into_bytes()),
            (plot.clone(), png),
        ];
        for (path, _) in &files {
            if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
                std::fs::create_dir_all(dir).map_err(|e| {
                    CliError::new(
                        Code::Output,
                        format!("{}: cannot write: {e}", path.display()),
                    )
                })?;
            }
        }
        write_all_atomic(&files).map_err(|e| CliError::new(Code::Output, e.to_string()))?;
    } else {
        let map = compute_map(&system, f_max(args)?, args.size);
        write_map_png(&map, &format!("MTF: {title}"), output).map_err(output_error)?;
    }
    Ok(())
}
