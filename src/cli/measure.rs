//! `sweepmtf measure`: arguments, the call into the library, and the outputs
//! (`STEM.mtf.csv`, `STEM.summary.json`, `STEM.mtf.png|svg`, `STEM.roi.png`,
//! written atomically) plus one summary line on stdout.

use super::{CliError, Code};
use std::path::{Path, PathBuf};
use std::time::Instant;
use sweepmtf::measure::{Failure, MeasureError, MeasureOptions, Measurement, Method, SweepChoice};
use sweepmtf::photo::linearise::Channel;
use sweepmtf::report::atomic::write_all_atomic;
use sweepmtf::report::json::{Timings, summary};
use sweepmtf::report::mtf_plot::{PlotFormat, mtf_plot_with};
use sweepmtf::report::{csv, roi_plot};

/// Arguments of `sweepmtf measure`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The photo (JPEG, PNG or TIFF; 8 or 16 bits, grey or RGB).
    pub photo: PathBuf,
    /// Region corners in image pixels, x1,y1,x2,y2,x3,y3,x4,y4 (origin top-left, y down).
    /// Without --target: one sweep strip, going round it, corners 1 and 4 on the
    /// low-frequency edge. With --target: the target frame's corners (0,0),(w,0),(w,h),(0,h).
    #[arg(long, value_name = "CORNERS", allow_hyphen_values = true)]
    pub roi: Option<String>,
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
    /// With several charts in the frame (found automatically): which one, 0 = leftmost.
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
    /// Tone curve: `chart` measures it from the target's grey/density patches.
    #[arg(long, value_name = "chart", value_parser = parse_tone)]
    pub tone: Option<bool>,
    /// Channel: luma | r | g | b | all.
    #[arg(long, default_value = "luma", value_name = "CH", value_parser = parse_channel)]
    pub channel: Channel,
    /// Pixel pitch with a unit (e.g. 4.3um), for cycles/mm on the sensor.
    #[arg(long, value_name = "LENGTH")]
    pub pixel_pitch: Option<String>,
    /// Plot format: png | svg.
    #[arg(long, default_value = "png", value_name = "FMT", value_parser = parse_plot)]
    pub plot: PlotFormat,
    /// Print the JSON summary on stdout instead of the summary line.
    #[arg(long)]
    pub json: bool,
    /// Model beside the measurement (`--model`, `--wavelength`).
    #[command(flatten)]
    pub model: super::measure_model::ModelArgs,
    /// Output folder.
    #[arg(short = 'o', long = "out", default_value = ".", value_name = "DIR")]
    pub out: PathBuf,
    /// Bin width along the sweep in pixels (advanced).
    #[arg(long, default_value_t = 0.25, value_name = "PX")]
    pub bin_px: f64,
    /// Fraction of the strip width left out along each long edge (advanced).
    #[arg(long, default_value_t = 0.15, value_name = "FRACTION")]
    pub margin: f64,
    /// Estimator window in cycles (advanced).
    #[arg(long, default_value_t = 4.0, value_name = "CYCLES")]
    pub window: f64,
}

/// Parses `x1,y1,…,x4,y4` into four corners.
pub fn parse_roi(text: &str) -> Result<[[f64; 2]; 4], String> {
    let v: Result<Vec<f64>, _> = text.split(',').map(|t| t.trim().parse::<f64>()).collect();
    match v {
        Ok(v) if v.len() == 8 && v.iter().all(|x| x.is_finite()) => {
            Ok([[v[0], v[1]], [v[2], v[3]], [v[4], v[5]], [v[6], v[7]]])
        }
        _ => Err(format!(
            "--roi '{text}': expected eight numbers x1,y1,x2,y2,x3,y3,x4,y4 (image pixels)"
        )),
    }
}

fn parse_method(s: &str) -> Result<Method, String> {
    Method::parse(s).ok_or_else(|| format!("'{s}': use extrema, fit or envelope"))
}

fn parse_sweep(s: &str) -> Result<SweepChoice, String> {
    match s {
        "auto" => Ok(SweepChoice::Auto),
        "linear" => Ok(SweepChoice::Linear),
        "log" => Ok(SweepChoice::Log),
        other => Err(format!("'{other}': use auto, linear or log")),
    }
}

fn parse_channel(s: &str) -> Result<Channel, String> {
    Channel::parse(s).ok_or_else(|| format!("'{s}': use luma, r, g, b or all"))
}

fn parse_tone(s: &str) -> Result<bool, String> {
    match s {
        "chart" => Ok(true),
        other => Err(format!("'{other}': the only tone is 'chart'")),
    }
}

fn parse_plot(s: &str) -> Result<PlotFormat, String> {
    match s {
        "png" => Ok(PlotFormat::Png),
        "svg" => Ok(PlotFormat::Svg),
        other => Err(format!("'{other}': use png or svg")),
    }
}

fn options(a: &Args) -> Result<MeasureOptions, CliError> {
    let usage = CliError::usage;
    let (method, sweep, channel) = (a.method, a.sweep, a.channel);
    let tone_chart = a.tone.unwrap_or(false);
    if tone_chart && a.gamma.is_some() {
        return Err(usage("--tone chart and --gamma exclude each other".into()));
    }
    let pixel_pitch_mm = match &a.pixel_pitch {
        None => None,
        Some(t) => Some(
            sweepmtf::units::parse_length_mm(t)
                .map_err(|e| usage(format!("--pixel-pitch: {e}")))?,
        ),
    };
    let roi = match &a.roi {
        None => None,
        Some(t) => Some(parse_roi(t).map_err(usage)?),
    };
    Ok(MeasureOptions {
        roi,
        target: a.target.clone(),
        method,
        sweep,
        gamma: a.gamma,
        tone_chart,
        channel,
        pixel_pitch_mm,
        bin_px: a.bin_px,
        margin: a.margin,
        window_cycles: a.window,
        chart_index: a.chart_index,
        refine_roi: !a.no_refine_roi,
    })
}

/// The exit code for a failed measurement.
pub fn code_of(f: &Failure) -> Code {
    match f {
        Failure::Decode(_) | Failure::Raw(_) | Failure::Target(_) => Code::Input,
        Failure::Options(_) => Code::Usage,
        Failure::NoRoi | Failure::Region(_) | Failure::TooSmall(_) => Code::Locate,
        Failure::Clipped { .. } | Failure::NoOscillation(_) | Failure::ModulationUnknown(_) => {
            Code::Measure
        }
    }
}

fn fail(e: MeasureError) -> CliError {
    CliError::new(code_of(&e.failure), e.to_string())
}

/// The one-line summary printed on stdout.
pub fn summary_line(m: &Measurement, csv_path: &Path) -> String {
    let name = &m.source;
    let mut parts = Vec::new();
    for c in &m.curves {
        let tag = if m.curves.len() > 1 {
            format!("{}/{} ", c.channel, c.sweep_id)
        } else {
            String::new()
        };
        let f50 = match c.figures.mtf50_cy_px {
            Some(f) => match m.pixel_pitch_mm {
                Some(p) => format!("MTF50 {f:.3} cy/px ({:.1} lp/mm)", f / p),
                None => format!("MTF50 {f:.3} cy/px"),
            },
            None => "MTF50 not reached".to_string(),
        };
        let nyq = c
            .figures
            .mtf_nyquist
            .map(|v| format!(", MTF at Nyquist {v:.3}"))
            .unwrap_or_default();
        let src = if c.chart_modulation_source.starts_with("extrapolated") {
            "extrapolated"
        } else {
            "from target"
        };
        parts.push(format!(
            "{tag}{f50}{nyq}, chart modulation {:.3} ({src})",
            c.chart_modulation
        ));
    }
    if !m.patches.is_empty() {
        parts.push(format!("{} sine patches", m.patches.len()));
    }
    format!(
        "{name}: {} [{}] -> {}",
        parts.join("; "),
        m.method.name(),
        csv_path.display()
    )
}

/// The error for a failed measurement; when automatic location found no chart,
/// also writes `STEM.roi.png` (`STEM.seen.png` when an earlier result is there),
/// the picture of what was seen, and names it.
fn located_failure(a: &Args, opts: &MeasureOptions, e: MeasureError) -> CliError {
    let searched = opts.roi.is_none() && opts.target.is_some();
    if !(searched && matches!(e.failure, Failure::Region(_))) {
        return fail(e);
    }
    let mut err = fail(e);
    let stem = a
        .photo
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "photo".into());
    // Never clobber the picture of an earlier, complete result in the same folder.
    let earlier = a.out.join(format!("{stem}.mtf.csv")).exists();
    let path = a.out.join(format!(
        "{stem}.{}",
        if earlier { "seen.png" } else { "roi.png" }
    ));
    let picture = sweepmtf::measure::location_picture(&a.photo, opts).and_then(|img| {
        let mut bytes = Vec::new();
        img.write_to(
            &mut std::io::Cursor::new(&mut bytes),
            image::ImageFormat::Png,
        )
        .ok()?;
        std::fs::create_dir_all(&a.out).ok()?;
        sweepmtf::report::atomic::write_atomic(&path, &bytes).ok()
    });
    if picture.is_some() {
        err.message
            .push_str(&format!(" (what was seen: {})", path.display()));
    }
    err
}

/// Runs `sweepmtf measure`.
pub fn run(a: &Args) -> Result<(), CliError> {
    let t_start = Instant::now();
    let opts = options(a)?;
    let plot_format = a.plot;
    let name = a.photo.display().to_string();
    let prepared = super::measure_model::prepare(&a.model, &a.photo)?;
    let t1 = Instant::now();
    let m = match sweepmtf::measure::measure_file(&a.photo, &opts) {
        Ok(m) => m,
        Err(e) => return Err(located_failure(a, &opts, e)),
    };
    let t2 = Instant::now();
    let extras = prepared.finish(&m)?;

    let stem = a
        .photo
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "photo".into());
    std::fs::create_dir_all(&a.out).map_err(|e| {
        CliError::new(
            Code::Output,
            format!("{}: cannot create output folder: {e}", a.out.display()),
        )
    })?;
    let out = |suffix: &str| a.out.join(format!("{stem}.{suffix}"));
    let out_err =
        |e: sweepmtf::report::atomic::ReportError| CliError::new(Code::Output, e.to_string());
    let csv_path = out("mtf.csv");
    let mut files: Vec<(PathBuf, Vec<u8>)> = Vec::new();
    if m.curves.is_empty() {
        files.push((csv_path.clone(), csv::patches_csv(&m)));
    } else {
        files.push((csv_path.clone(), extras.csv(csv::curves_csv(&m))));
        if !m.patches.is_empty() {
            files.push((out("patches.csv"), csv::patches_csv(&m)));
        }
    }
    let plot_ext = match plot_format {
        PlotFormat::Png => "mtf.png",
        PlotFormat::Svg => "mtf.svg",
    };
    files.push((
        out(plot_ext),
        mtf_plot_with(&m, plot_format, &extras.plot).map_err(out_err)?,
    ));
    files.push((out("roi.png"), roi_plot::roi_plot(&m).map_err(out_err)?));
    let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
    let timings = Timings {
        measure_ms: ms(t1, t2),
        total_ms: ms(t_start, Instant::now()),
    };
    let summary_value = extras.json(summary(&m, Some(timings)));
    let mut summary_text = serde_json::to_string_pretty(&summary_value).unwrap_or_default();
    summary_text.push('\n');
    files.push((out("summary.json"), summary_text.into_bytes()));
    write_all_atomic(&files).map_err(out_err)?;
    for w in &m.warnings {
        eprintln!("sweepmtf: warning: {name}: {w}");
    }
    if a.json {
        println!("{summary_value}");
    } else {
        println!("{}{}", summary_line(&m, &csv_path), extras.line_suffix());
    }
    Ok(())
}
