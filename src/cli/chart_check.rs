//! `sweepmtf chart-check`: whether a print is sharp enough for a camera
//! set-up — up to which image frequency (cycles/pixel, against Nyquist) the
//! print's MTF stays ≥ 0.99 (sharp enough: dividing it out would change the
//! MTF by ≤ 0.01), ≥ 0.9, ≥ 0.5, and ≥ 0.3 (where `measure --chart-mtf`
//! stops compensating). See the library's `chart::suitability`.

use super::{CliError, Code};
use serde_json::json;
use std::path::PathBuf;
use sweepmtf::chart::Setup;
use sweepmtf::chart::suitability::{LevelReach, SHARP_ENOUGH, check};
use sweepmtf::measure::chart_mtf::{ChartMtf, ChartMtfError, MIN_CHART_MTF};

/// Arguments of `sweepmtf chart-check`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The print's MTF: the `.mtf.csv` measured from a scan or close capture of the
    /// print, gaussian:sigma=LENGTH, or dots:dpi=N (a square printer dot of 1/N inch).
    #[arg(long, value_name = "FILE|gaussian:sigma=LENGTH|dots:dpi=N")]
    pub print: String,
    /// Camera pixel pitch (e.g. 4.3um); with --focal-length and --distance.
    #[arg(long, value_name = "LENGTH")]
    pub pixel_pitch: Option<String>,
    /// Lens focal length (e.g. 50mm).
    #[arg(long, value_name = "LENGTH")]
    pub focal_length: Option<String>,
    /// Distance from the lens to the chart (e.g. 2m).
    #[arg(long, value_name = "LENGTH")]
    pub distance: Option<String>,
    /// Or: the chart's width in the frame, pixels; with --chart-width or --target.
    #[arg(long, value_name = "PX")]
    pub chart_px: Option<f64>,
    /// The chart's printed width (e.g. 297mm).
    #[arg(long, value_name = "LENGTH", conflicts_with = "target")]
    pub chart_width: Option<String>,
    /// The chart's description (its width_mm is the printed width).
    #[arg(long, value_name = "FILE")]
    pub target: Option<PathBuf>,
    /// Print the result as JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Also draw the print's MTF against image frequency with the levels (PNG).
    #[arg(long, value_name = "FILE.png")]
    pub plot: Option<PathBuf>,
}

fn usage(m: impl Into<String>) -> CliError {
    CliError::new(Code::Usage, m)
}

fn length(flag: &str, v: &Option<String>) -> Result<Option<f64>, CliError> {
    v.as_deref()
        .map(|t| sweepmtf::units::parse_length_mm(t).map_err(|e| usage(format!("--{flag}: {e}"))))
        .transpose()
}

/// Image pixels per chart millimetre from the set-up or the chart's size in the frame.
fn px_per_chart_mm(a: &Args) -> Result<f64, CliError> {
    let pitch = length("pixel-pitch", &a.pixel_pitch)?;
    let focal = length("focal-length", &a.focal_length)?;
    let dist = length("distance", &a.distance)?;
    let setup_given = pitch.is_some() || focal.is_some() || dist.is_some();
    if setup_given && a.chart_px.is_some() {
        return Err(usage(
            "give either the set-up (--pixel-pitch, --focal-length, --distance) or the chart's size in the frame (--chart-px), not both",
        ));
    }
    if setup_given {
        let (Some(p), Some(f), Some(d)) = (pitch, focal, dist) else {
            return Err(usage(
                "--pixel-pitch, --focal-length and --distance must be given together",
            ));
        };
        let s = Setup::new(p, f, d).map_err(|e| usage(e.to_string()))?;
        return Ok(1.0 / s.pixel_on_chart_mm());
    }
    let Some(n) = a.chart_px else {
        return Err(usage(
            "chart-check needs the image scale: the set-up (--pixel-pitch, --focal-length, --distance) \
             or the chart's width in the frame (--chart-px with --chart-width or --target)",
        ));
    };
    if !(n.is_finite() && n > 0.0 && n <= 1e6) {
        return Err(usage(format!("--chart-px {n}: must be in (0, 1e6] pixels")));
    }
    let width = match (length("chart-width", &a.chart_width)?, &a.target) {
        (Some(w), _) => w,
        (None, Some(t)) => {
            sweepmtf::target::Target::load(t)
                .map_err(|e| CliError::new(Code::Input, e.to_string()))?
                .width_mm
        }
        (None, None) => {
            return Err(usage(
                "--chart-px needs the printed width: --chart-width LENGTH or --target FILE",
            ));
        }
    };
    if !(width.is_finite() && width > 0.0) {
        return Err(usage("--chart-width must be positive"));
    }
    Ok(n / width)
}

fn chart_err(e: ChartMtfError) -> CliError {
    match e {
        ChartMtfError::File { .. } => CliError::new(Code::Input, e.to_string()),
        _ => usage(e.to_string().replace("--chart-mtf", "--print")),
    }
}

/// "0.073 cy/px (1.46 cy/mm on the print, 0.15 × Nyquist)", or where it is not reached.
fn reach_text(r: &LevelReach, px_per_mm: f64) -> String {
    match (r.chart_cy_mm, r.cy_px) {
        (Some(f), Some(p)) if p.is_finite() => {
            let nyq = if p >= 0.5 { ", beyond Nyquist" } else { "" };
            format!(
                "{p:.3} cy/px ({f:.2} cy/mm on the print, {:.2} × Nyquist{nyq})",
                p / 0.5
            )
        }
        (Some(_), _) => "never falls below (a perfect print)".into(),
        _ => format!(
            "at least {:.3} cy/px ({:.2} cy/mm on the print: the file's last row)",
            r.known_to_cy_mm / px_per_mm,
            r.known_to_cy_mm
        ),
    }
}

/// The verdict line against Nyquist.
fn verdict(levels: &[LevelReach]) -> String {
    let sharp = &levels[0];
    let floor = &levels[levels.len() - 1];
    let at = |r: &LevelReach| r.cy_px.map_or("?".to_string(), |f| format!("{f:.3} cy/px"));
    if sharp.covers_nyquist() {
        "sharp enough up to Nyquist: no compensation needed".into()
    } else if floor.covers_nyquist() {
        format!(
            "sharp enough up to {}; beyond it, measure with --chart-mtf (the print's MTF stays ≥ {MIN_CHART_MTF} up to Nyquist)",
            at(sharp)
        )
    } else if floor.cy_px.is_some() {
        format!(
            "sharp enough up to {}; measure --chart-mtf compensates up to {}; beyond, the print limits the measurement (print sharper or larger, or shoot from further)",
            at(sharp),
            at(floor)
        )
    } else {
        format!(
            "sharp enough up to {}; beyond, compensate with measure --chart-mtf (the file does not say how far)",
            at(sharp)
        )
    }
}

/// Runs `sweepmtf chart-check`.
pub fn run(a: &Args) -> Result<(), CliError> {
    let px_per_mm = px_per_chart_mm(a)?;
    let chart = ChartMtf::from_arg(&a.print).map_err(chart_err)?;
    let levels = check(&chart, px_per_mm);
    if let Some(p) = &a.plot {
        let png = sweepmtf::report::chart_check_plot::chart_check_png(&chart, px_per_mm, &levels)
            .map_err(|e| CliError::new(Code::Internal, e.to_string()))?;
        sweepmtf::report::atomic::write_atomic(p, &png)
            .map_err(|e| CliError::new(Code::Output, e.to_string()))?;
    }
    if a.json {
        let lv: Vec<_> = levels
            .iter()
            .map(|r| {
                json!({
                    "level": r.level,
                    "chart_cy_mm": r.chart_cy_mm.filter(|f| f.is_finite()),
                    "cy_px": r.cy_px.filter(|f| f.is_finite()),
                    "fraction_of_nyquist": r.cy_px.filter(|f| f.is_finite()).map(|f| f / 0.5),
                    "known_to_cy_mm": r.known_to_cy_mm.is_finite().then_some(r.known_to_cy_mm),
                })
            })
            .collect();
        let v = json!({
            "print": chart.describe(),
            "px_per_chart_mm": px_per_mm,
            "nyquist_chart_cy_mm": 0.5 * px_per_mm,
            "sharp_enough_level": SHARP_ENOUGH,
            "compensation_floor": MIN_CHART_MTF,
            "levels": lv,
            "verdict": verdict(&levels),
        });
        println!("{}", serde_json::to_string_pretty(&v).unwrap_or_default());
        return Ok(());
    }
    println!(
        "print {} seen at {px_per_mm:.3} px per chart mm (Nyquist 0.5 cy/px = {:.2} cy/mm on the print):",
        chart.describe(),
        0.5 * px_per_mm
    );
    for r in &levels {
        let what = if r.level == SHARP_ENOUGH {
            " (sharp enough: dividing it out changes the MTF by ≤ 0.01)"
        } else if r.level == MIN_CHART_MTF {
            " (measure --chart-mtf compensates up to here)"
        } else {
            ""
        };
        println!(
            "  print MTF ≥ {:.2}{what} up to {}",
            r.level,
            reach_text(r, px_per_mm)
        );
    }
    println!("{}", verdict(&levels));
    Ok(())
}
