//! `sweepmtf measure`: arguments, the call into the library, and the outputs
//! (`STEM.mtf.csv`, `STEM.summary.json`, `STEM.mtf.png|svg`, `STEM.roi.png`,
//! written atomically) plus one summary line on stdout; with several charts
//! found automatically, one such set per chart as `STEM.chartN.*`.

use super::{CliError, Code};
use std::path::{Path, PathBuf};
use std::time::Instant;
use sweepmtf::measure::{Failure, MeasureError, MeasureOptions, Measurement};
use sweepmtf::report::atomic::{ReportError, stage};
use sweepmtf::report::json::{Timings, summary};
use sweepmtf::report::mtf_plot::{PlotFormat, mtf_plot_with};
use sweepmtf::report::{csv, roi_plot};

/// Arguments of `sweepmtf measure`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The photo (JPEG, PNG or TIFF; 8 or 16 bits, grey or RGB).
    pub photo: PathBuf,
    /// Measurement flags (shared with `batch`).
    #[command(flatten)]
    pub flags: super::measure_flags::MeasureFlags,
    /// Print the JSON summary on stdout instead of the summary line.
    #[arg(long)]
    pub json: bool,
    /// Model beside the measurement (`--model`, `--wavelength`).
    #[command(flatten)]
    pub model: super::measure_model::ModelArgs,
    /// Output folder.
    #[arg(short = 'o', long = "out", default_value = ".", value_name = "DIR")]
    pub out: PathBuf,
}

/// The exit code for a failed measurement.
pub fn code_of(f: &Failure) -> Code {
    match f {
        Failure::Decode(_) | Failure::Raw(_) | Failure::Target(_) => Code::Input,
        Failure::Options(_) => Code::Usage,
        Failure::NoRoi | Failure::Region(_) | Failure::TooSmall(_) => Code::Locate,
        Failure::Clipped { .. }
        | Failure::NoOscillation(_)
        | Failure::ModulationUnknown(_)
        | Failure::Unreliable(_) => Code::Measure,
        Failure::Damaged { .. } => Code::Input,
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
        // MTF50 with its one-sigma uncertainty (4 decimals: it is often < 0.001 cy/px).
        let f50 = match (c.figures.mtf50_cy_px, c.figures.mtf50_err_cy_px) {
            (Some(f), e) => {
                let v = match e {
                    Some(e) => format!("MTF50 {f:.4} ± {e:.4} cy/px"),
                    None => format!("MTF50 {f:.3} cy/px"),
                };
                match m.pixel_pitch_mm {
                    Some(p) => format!("{v} ({:.1} lp/mm)", f / p),
                    None => v,
                }
            }
            (None, _) => not_reached(c),
        };
        // With a sharpening peak, MTF50P (half the peak) beside MTF50.
        let f50p = match (c.figures.sharpening_peak, c.figures.peak_mtf) {
            (true, Some(pk)) => {
                let at = c.figures.peak_cy_px.unwrap_or(0.0);
                match c.figures.mtf50p_cy_px {
                    Some(f) => format!(", MTF50P {f:.3} cy/px (peak {pk:.3} at {at:.3} cy/px)"),
                    None => format!(", MTF50P not reached (peak {pk:.3} at {at:.3} cy/px)"),
                }
            }
            _ => String::new(),
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
            "{tag}{f50}{f50p}{nyq}, chart modulation {:.3} ({src})",
            c.chart_modulation
        ));
    }
    if !m.patches.is_empty() {
        parts.push(format!("{} sine patches", m.patches.len()));
    }
    if let Some(cm) = m.colour_moire.first() {
        parts.push(moire_phrase(cm));
    }
    format!(
        "{name}: {} [{}] -> {}",
        parts.join("; "),
        m.method.name(),
        csv_path.display()
    )
}

/// "MTF50 not reached", with where the curve ends when it ends above 0.5
/// (the print's reach, or a region cut short, rather than a blur too weak to read).
fn not_reached(c: &sweepmtf::measure::Curve) -> String {
    match c.points.iter().rev().find(|p| !p.aliased) {
        Some(p) if p.mtf > 0.5 => format!(
            "MTF50 not reached (MTF {:.3} at the curve's end, {:.3} cy/px)",
            p.mtf, p.freq_cy_px
        ),
        _ => "MTF50 not reached".to_string(),
    }
}

/// "colour moiré: R−B spread max 0.214 at 0.262 cy/px, onset 0.231 cy/px" (the first sweep's).
fn moire_phrase(cm: &sweepmtf::measure::moire::ColourMoire) -> String {
    let max = match (cm.max_spread, cm.max_at_cy_px) {
        (Some(v), Some(f)) => format!("R−B spread max {v:.3} at {f:.3} cy/px"),
        _ => "R−B spread not measured".to_string(),
    };
    let onset = match (cm.onset_cy_px, cm.measured_to_cy_px) {
        (Some(f), _) => format!("onset {f:.3} cy/px"),
        (None, Some(to)) => format!("no onset up to {to:.3} cy/px"),
        (None, None) => "no onset".to_string(),
    };
    format!("colour moiré: {max}, {onset}")
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
    let opts = a.flags.options()?;
    if a.model.chart_mtf.is_some() && opts.target.is_none() && a.model.chart_length.is_none() {
        return Err(CliError::usage(
            sweepmtf::measure::chart_mtf::ChartMtfError::NoScale.to_string(),
        ));
    }
    let prepared = super::measure_model::prepare(&a.model, &a.photo)?;
    let t1 = Instant::now();
    // Every chart found (one set of outputs each), or the one region asked for.
    let all = match sweepmtf::measure::measure_file_each(&a.photo, &opts) {
        Ok(all) => all,
        Err(e) => return Err(located_failure(a, &opts, e)),
    };
    let t2 = Instant::now();
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
    let several = all.len() > 1;
    for (i, m) in all.iter().enumerate() {
        // Several charts: STEM.chartN.* for the chart --chart-index N would pick.
        let stem = if several {
            format!("{stem}.chart{i}")
        } else {
            stem.clone()
        };
        let timings = Timings {
            measure_ms: (t2 - t1).as_secs_f64() * 1e3,
            total_ms: (Instant::now() - t_start).as_secs_f64() * 1e3,
        };
        write_outputs(a, m, &stem, &prepared, timings)?;
    }
    Ok(())
}

/// The files `measure` wrote for one measurement (in writing order), its
/// JSON summary and the summary line's suffix.
pub struct Outputs {
    /// The files written.
    pub paths: Vec<PathBuf>,
    /// The path of `STEM.mtf.csv`.
    pub csv_path: PathBuf,
    /// The JSON summary (as written to `STEM.summary.json`).
    pub summary: serde_json::Value,
    /// Appended to the summary line (the model comparison, when a model is drawn).
    pub line_suffix: String,
    /// Warnings the extras add (e.g. a print that is not sharp enough), printed after the measurement's own.
    pub warnings: Vec<String>,
}

/// Makes and writes one measurement's outputs as `out/STEM.*`, all or none
/// (each to a synced temporary, then every one renamed into place);
/// `sweepmtf gui` saves through this too, so its files are `measure`'s.
pub fn save_outputs(
    m: &Measurement,
    out_dir: &Path,
    stem: &str,
    plot: PlotFormat,
    prepared: &super::measure_model::Prepared,
    timings: Timings,
) -> Result<Outputs, CliError> {
    let extras = prepared.finish(m)?;
    let out = |suffix: &str| out_dir.join(format!("{stem}.{suffix}"));
    let out_err = |e: ReportError| CliError::new(Code::Output, e.to_string());
    let csv_path = out("mtf.csv");
    let plot_ext = match plot {
        PlotFormat::Png => "mtf.png",
        PlotFormat::Svg => "mtf.svg",
    };
    // The region picture (the longest: a large PNG to encode) is drawn and
    // encoded beside everything else, which meanwhile is written to disk.
    let roi_path = out("roi.png");
    let (roi, rest) = rayon::join(
        || roi_plot::roi_plot(m).and_then(|png| stage(&[(roi_path.clone(), png)])),
        || -> Result<_, ReportError> {
            let mut files: Vec<(PathBuf, Vec<u8>)> = Vec::new();
            if m.curves.is_empty() {
                files.push((csv_path.clone(), extras.patches_csv(csv::patches_csv(m))));
            } else {
                files.push((csv_path.clone(), extras.csv(csv::curves_csv(m))));
                if !m.patches.is_empty() {
                    files.push((out("patches.csv"), extras.patches_csv(csv::patches_csv(m))));
                }
            }
            files.push((out(plot_ext), mtf_plot_with(m, plot, &extras.plot)?));
            let summary_value = extras.json(summary(m, Some(timings)), m);
            let mut summary_text = serde_json::to_string_pretty(&summary_value).unwrap_or_default();
            summary_text.push('\n');
            let summary_file = (out("summary.json"), summary_text.into_bytes());
            let paths: Vec<PathBuf> = files.iter().map(|f| f.0.clone()).collect();
            let n = files.len();
            files.push(summary_file);
            let mut body = stage(&files)?;
            let last = body.split_off(n);
            Ok((body, last, paths, summary_value))
        },
    );
    let (body, last, mut paths, summary_value) = rest.map_err(out_err)?;
    let roi = roi.map_err(out_err)?;
    // The summary last, as before.
    body.then(roi).then(last).commit().map_err(out_err)?;
    paths.push(roi_path);
    paths.push(out("summary.json"));
    Ok(Outputs {
        paths,
        csv_path,
        summary: summary_value,
        line_suffix: extras.line_suffix(m),
        warnings: extras.warnings(m),
    })
}

/// Writes one measurement's outputs as `STEM.*` in the output folder and
/// prints its warnings and its summary line (or JSON).
fn write_outputs(
    a: &Args,
    m: &Measurement,
    stem: &str,
    prepared: &super::measure_model::Prepared,
    timings: Timings,
) -> Result<(), CliError> {
    let name = a.photo.display().to_string();
    let o = save_outputs(m, &a.out, stem, a.flags.plot, prepared, timings)?;
    for w in m.warnings.iter().chain(&o.warnings) {
        super::messages::warning(&format!("{name}: {w}"));
    }
    for n in &m.notes {
        super::messages::note(&format!("{name}: {n}"));
    }
    if a.json {
        println!("{}", o.summary);
    } else {
        println!("{}{}", summary_line(m, &o.csv_path), o.line_suffix);
    }
    Ok(())
}
