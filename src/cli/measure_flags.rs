//! The measurement flags `sweepmtf measure` and `sweepmtf batch` share, and
//! their check into [`MeasureOptions`].

use super::CliError;
use std::path::PathBuf;
use sweepmtf::measure::{MeasureOptions, Method, SweepChoice};
use sweepmtf::photo::linearise::Channel;
use sweepmtf::report::mtf_plot::PlotFormat;

/// Measurement flags (flattened into `measure` and `batch`).
#[derive(Debug, clap::Args)]
pub struct MeasureFlags {
    /// Region corners in image pixels, x1,y1,x2,y2,x3,y3,x4,y4 (origin top-left, y down).
    /// Without --target: one sweep strip, going round it, corners 1 and 4 on the
    /// low-frequency edge. With --target: the target frame's corners (0,0),(w,0),(w,h),(0,h).
    /// In `batch`: for every shot not listed in --roi-file (e.g. a tripod series).
    #[arg(long, value_name = "CORNERS", allow_hyphen_values = true, value_parser = parse_roi)]
    pub roi: Option<[[f64; 2]; 4]>,
    /// Target description (chart TOML or sineMTF tgt.txt).
    #[arg(long, value_name = "FILE")]
    pub target: Option<PathBuf>,
    /// Use the --roi corners exactly as given (by default they are refined to the
    /// strip's or target's edges; with --target, errors of ±5 px are absorbed).
    #[arg(long)]
    pub no_refine_roi: bool,
    /// Accepted for compatibility: refining the --roi corners is the default.
    #[arg(long, hide = true, conflicts_with = "no_refine_roi")]
    pub refine_roi: bool,
    /// Raw Bayer files: leave the two green sites' gains as recorded (by default
    /// the second green lattice is scaled to the first's level before the greens
    /// are binned together; the summary gives the gain as green_gain).
    #[arg(long)]
    pub no_green_balance: bool,
    /// With several charts in the frame (found automatically): measure only this one, 0 = leftmost. Without it, `measure` measures each (outputs STEM.chartN.*) and `batch` the leftmost.
    #[arg(long, value_name = "N")]
    pub chart_index: Option<usize>,
    /// Modulation estimator: extrema | fit | envelope.
    #[arg(long, default_value = "fit", value_name = "METHOD", value_parser = parse_method)]
    pub method: Method,
    /// Sweep law without a target: auto | linear | log.
    #[arg(long, default_value = "auto", value_name = "LAW", value_parser = parse_sweep)]
    pub sweep: SweepChoice,
    /// Power-law tone instead of the default (1 = data already linear).
    #[arg(long, value_name = "G")]
    pub gamma: Option<f64>,
    /// Tone curve: `strip` (default) takes a camera's own curve out from the
    /// strip's low-frequency periods; `file` keeps the file's (or --gamma's);
    /// `chart` measures it from the target's grey/density patches.
    #[arg(long, value_name = "strip|file|chart", value_parser = parse_tone)]
    pub tone: Option<ToneFlag>,
    /// Channel: luma | r | g | b | all (luma, r, g, b together, with the R−B colour moiré;
    /// raws: the green sites unless r, b or all).
    #[arg(long, default_value = "luma", value_name = "CH", value_parser = parse_channel)]
    pub channel: Channel,
    /// Pixel pitch with a unit (e.g. 4.3um), for cycles/mm on the sensor; default: from the EXIF.
    #[arg(long, value_name = "LENGTH")]
    pub pixel_pitch: Option<String>,
    /// Plot format: png | svg.
    #[arg(long, default_value = "png", value_name = "FMT", value_parser = parse_plot)]
    pub plot: PlotFormat,
    /// Bin width along the sweep in pixels (advanced).
    #[arg(long, default_value_t = 0.25, value_name = "PX")]
    pub bin_px: f64,
    /// Fraction of the strip width left out along each long edge (advanced).
    #[arg(long, default_value_t = 0.15, value_name = "FRACTION")]
    pub margin: f64,
    /// The lens's radial distortion in Lensfun's PTLens form, ptlens:a=A,b=B,c=C (radius 1 =
    /// half the image's smaller side, centre = image centre), or none. Default: estimated
    /// from the strip's straight long edges and used when clearly there.
    #[arg(long, value_name = "ptlens:a=A,b=B,c=C|none", allow_hyphen_values = true, value_parser = parse_distortion)]
    pub distortion: Option<sweepmtf::distortion::Ptlens>,
    /// Estimate lens distortion from the strip's straight printed long edges
    /// (the default; kept so that older command lines still run).
    #[arg(long, conflicts_with_all = ["distortion", "no_estimate_distortion"])]
    pub estimate_distortion: bool,
    /// Do not estimate lens distortion: measure as without it (like --distortion none).
    #[arg(long, conflicts_with = "distortion")]
    pub no_estimate_distortion: bool,
    /// Keep every bin up to the region's ends: do not look for where the
    /// printed sweep stops inside them (ends clicked beyond the print).
    #[arg(long)]
    pub keep_ends: bool,
    /// Estimator window in cycles (advanced).
    #[arg(long, default_value_t = 4.0, value_name = "CYCLES")]
    pub window: f64,
    /// Most sample lines binned across a strip: a strip taller across is
    /// binned from evenly spaced rows (or columns), faster and a little
    /// noisier; 0 = every line (advanced).
    #[arg(long, default_value_t = sweepmtf::measure::MAX_ACROSS, value_name = "LINES")]
    pub max_across: usize,
}

impl MeasureFlags {
    /// The measurement options, with the checks the library leaves to the command line.
    pub fn options(&self) -> Result<MeasureOptions, CliError> {
        let tone_chart = self.tone == Some(ToneFlag::Chart);
        if tone_chart && self.gamma.is_some() {
            return Err(CliError::usage(
                "--tone chart and --gamma exclude each other",
            ));
        }
        let pixel_pitch_mm = match &self.pixel_pitch {
            None => None,
            Some(t) => Some(
                sweepmtf::units::parse_length_mm(t)
                    .map_err(|e| CliError::usage(format!("--pixel-pitch: {e}")))?,
            ),
        };
        Ok(MeasureOptions {
            roi: self.roi,
            target: self.target.clone(),
            method: self.method,
            sweep: self.sweep,
            gamma: self.gamma,
            tone_chart,
            tone_from_strip: self.tone != Some(ToneFlag::File),
            channel: self.channel,
            pixel_pitch_mm,
            bin_px: self.bin_px,
            margin: self.margin,
            window_cycles: self.window,
            chart_index: self.chart_index,
            refine_roi: !self.no_refine_roi,
            green_balance: !self.no_green_balance,
            distortion: self.distortion,
            estimate_distortion: !self.no_estimate_distortion,
            find_print_ends: !self.keep_ends,
            max_across: self.max_across,
        })
    }
}

/// Parses `x1,y1,…,x4,y4` into four corners.
pub fn parse_roi(text: &str) -> Result<[[f64; 2]; 4], String> {
    let v: Result<Vec<f64>, _> = text.split(',').map(|t| t.trim().parse::<f64>()).collect();
    match v {
        Ok(v) if v.len() == 8 && v.iter().all(|x| x.is_finite()) => {
            Ok([[v[0], v[1]], [v[2], v[3]], [v[4], v[5]], [v[6], v[7]]])
        }
        _ => Err(format!(
            "'{text}': expected eight numbers x1,y1,x2,y2,x3,y3,x4,y4 (image pixels)"
        )),
    }
}

/// `ptlens:a=A,b=B,c=C`, or `none` (the zero model: no distortion, none estimated).
fn parse_distortion(s: &str) -> Result<sweepmtf::distortion::Ptlens, String> {
    if s.trim().eq_ignore_ascii_case("none") {
        return Ok(sweepmtf::distortion::Ptlens {
            a: 0.0,
            b: 0.0,
            c: 0.0,
        });
    }
    s.parse()
}

pub fn parse_method(s: &str) -> Result<Method, String> {
    Method::parse(s).ok_or_else(|| format!("'{s}': use extrema, fit or envelope"))
}

pub fn parse_sweep(s: &str) -> Result<SweepChoice, String> {
    match s {
        "auto" => Ok(SweepChoice::Auto),
        "linear" => Ok(SweepChoice::Linear),
        "log" => Ok(SweepChoice::Log),
        other => Err(format!("'{other}': use auto, linear or log")),
    }
}

pub fn parse_channel(s: &str) -> Result<Channel, String> {
    Channel::parse(s).ok_or_else(|| format!("'{s}': use luma, r, g, b or all"))
}

/// Where `measure` takes the tone from (`--tone`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ToneFlag {
    /// The file's tone, corrected from the strip's shape (the default).
    Strip,
    /// The file's tone (or `--gamma`) only.
    File,
    /// The target's grey or density patches.
    Chart,
}

fn parse_tone(s: &str) -> Result<ToneFlag, String> {
    match s {
        "strip" => Ok(ToneFlag::Strip),
        "file" => Ok(ToneFlag::File),
        "chart" => Ok(ToneFlag::Chart),
        other => Err(format!("'{other}': use strip, file or chart")),
    }
}

fn parse_plot(s: &str) -> Result<PlotFormat, String> {
    match s {
        "png" => Ok(PlotFormat::Png),
        "svg" => Ok(PlotFormat::Svg),
        other => Err(format!("'{other}': use png or svg")),
    }
}
